// Standing still: a pedestrian stops at doors, waits, looks around. While the rig does not
// translate, the camera sees no parallax and constrains only the product of each landmark's
// inverse depth and the velocity; linearized, that product gives the filter false confidence in
// the forward velocity (README, TUM corridor). Like OpenVINS' zero-velocity updater, we detect
// standing from the images and tell the filter directly that the velocity is (nearly) zero.
#pragma once

#include <cstdint>
#include <deque>
#include <unordered_map>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct ZeroVelocityParams {
  bool enabled = true;
  /// Baseline over which the parallax is measured [s]; walking at 1 m/s moves the rig 0.5 m.
  double window_s = 0.5;
  /// Standing when the median de-rotated feature displacement over the window is below this
  /// [px] (pixel noise alone gives about 1.8 px for 1 px noise; walking gives tens of px).
  double max_parallax_px = 3.0;
  int min_features = 10;  ///< features seen at both ends of the window to decide at all
  /// Std-dev of the true velocity while standing (torso sway) [m/s]: the noise of the
  /// zero-velocity pseudo-measurement.
  double velocity_sigma_mps = 0.03;
  double gate_probability = 0.999;  ///< chi^2 gate (3 dof): a moving filter refuses the update
};

/// Decides from the tracked features whether the rig translated over the last window: each
/// feature's ray from the start of the window is rotated into the current camera with the
/// filter's own relative rotation (gyro-accurate over 0.5 s) and compared with where it is seen
/// now, so turning on the spot is still "standing".
class StationaryDetector {
 public:
  struct Decision {
    bool decided = false;     ///< enough history and features to tell
    bool stationary = false;  ///< decided and the parallax is below the threshold
    double parallax_px = 0.0;
    int features = 0;
  };

  /// R_n_c: the estimated camera orientation at the frame's time.
  Decision update(const CameraFrame& frame, const Mat3& R_n_c, const CameraModel& camera,
                  const ZeroVelocityParams& params);
  void reset() { history_.clear(); }

 private:
  struct Past {
    double t;
    Mat3 R_n_c;
    std::unordered_map<std::int64_t, Eigen::Vector2d> xn;  ///< normalized image coordinates
  };
  std::deque<Past> history_;
};

struct ZeroVelocityResult {
  bool applied = false;
  double nis = 0.0;  ///< normalized innovation squared (3 dof)
};

/// EKF update with the pseudo-measurement v_s_b = 0 (zero velocity is zero in every frame),
/// noise velocity_sigma_mps per axis, gated on its 3-dof innovation; Joseph-equivalent
/// covariance update P - B S^-1 B^T with B = P H^T (exact for the optimal gain).
ZeroVelocityResult zeroVelocityUpdate(FilterState& state, const ZeroVelocityParams& params);

}  // namespace vi_ekf_slam
