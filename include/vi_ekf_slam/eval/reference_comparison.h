// Comparison of an estimated trajectory with a reference trajectory of unknown frame (and, for
// vision-only references, unknown scale), as `evo_ape --align [--correct_scale]` does: the
// reference is interpolated at the estimate's stamps, the estimate is aligned onto the reference by
// Umeyama (Eigen::umeyama) with SE(3), Sim(3) or position + yaw, and the residuals are measured in
// the reference's units (evo's number) and in the estimate's metres.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/io/tum_io.h"

namespace vi_ekf_slam::eval {

enum class Alignment { kSE3, kPosYaw, kSim3 };
std::optional<Alignment> alignmentFromString(const std::string& s);
std::string toString(Alignment a);

struct ReferenceComparison {
  Alignment alignment = Alignment::kSim3;
  int matched = 0;                             ///< estimates with a reference pose interpolated at their stamp
  double position_rmse_m = 0.0;                ///< after alignment, in the estimate's metres
  double position_rmse_reference_units = 0.0;  ///< the same in the reference's units (evo_ape's APE)
  double rotation_rmse_deg = 0.0;              ///< of the aligned orientations
  double scale = 1.0;                          ///< reference units per metre of the estimate (1 unless Sim(3))
  double estimate_path_m = 0.0;                ///< path length of the matched estimates [m]
  double reference_path_m = 0.0;               ///< of the matched reference poses, in the estimate's metres
  std::vector<double> t;                       ///< stamps of the matched estimates
  std::vector<Vec3> estimate;                  ///< matched estimated positions
  std::vector<Vec3> reference;                 ///< the reference positions in the estimate's frame and metres
};

/// The estimate as a reference of another frame or clock sees it: body poses moved to the camera
/// through T_b_c (if given), and stamps moved from the IMU clock to the camera clock by each pose's
/// time offset estimate t_d (t_image = t_imu - t_d; if given, one per pose).
std::vector<io::StampedPose> referenceView(const std::vector<io::StampedPose>& body_poses,
                                           const std::optional<CameraExtrinsics>& T_b_c,
                                           const std::vector<double>* time_offsets_s = nullptr);

/// Interpolates `reference` (sorted by time) at each estimate stamp (linear position, slerp),
/// where the two reference poses around it are at most max_gap_s apart, aligns the estimate onto
/// it and measures.
/// Throws std::invalid_argument with fewer than three matches.
ReferenceComparison compareWithReference(const std::vector<io::StampedPose>& estimate,
                                         const std::vector<io::StampedPose>& reference, Alignment alignment,
                                         double max_gap_s = 0.5);

/// One window of compareInWindows: its span on the estimate's clock and its own alignment.
struct WindowComparison {
  double from_t = 0.0, to_t = 0.0;  ///< [from_t, to_t) [s]
  ReferenceComparison comparison;
};

/// The estimate cut into consecutive windows of window_s from its first stamp, each compared with
/// the reference and aligned on its own. The whole run's alignment averages a scale that changes
/// along the run (a start mapped at the wrong scale); each window's scale shows it. Windows with
/// fewer than three matches are left out.
std::vector<WindowComparison> compareInWindows(const std::vector<io::StampedPose>& estimate,
                                               const std::vector<io::StampedPose>& reference, Alignment alignment,
                                               double window_s, double max_gap_s = 0.5);

/// The first window's scale over the median of the later windows' (1: the start's scale is the
/// rest's; NaN with fewer than two windows).
double firstWindowScaleRatio(const std::vector<WindowComparison>& windows);

}  // namespace vi_ekf_slam::eval
