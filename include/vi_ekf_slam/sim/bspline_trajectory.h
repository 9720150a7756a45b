// A C2 trajectory through a sequence of poses: cumulative cubic B-splines (Kim et al. 1995,
// as used for visual-inertial simulation by Mueggler/Sommer and OpenVINS), uniform knots, one
// for the position in R^3 and one on SO(3) for the attitude. The poses are resampled at the
// knot spacing and used as control points, so the curve approximates them (smoothing jitter of
// estimated trajectories) and its acceleration and angular rate are analytic and consistent
// with its poses.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "vi_ekf_slam/io/tum_io.h"
#include "vi_ekf_slam/sim/trajectory.h"

namespace vi_ekf_slam::sim {

class BsplineTrajectory : public Trajectory {
 public:
  /// poses: body in {n}, strictly increasing time. Throws std::invalid_argument if fewer than
  /// 4 knots result or the span is shorter than 4 knot spacings.
  BsplineTrajectory(const std::vector<io::StampedPose>& poses, double knot_spacing_s);

  double startTime() const override;
  double endTime() const override;
  TrajectorySample sample(double t) const override;
  double knotSpacing() const { return dt_; }

 private:
  double t0_ = 0.0, dt_ = 0.05;
  std::vector<Vec3> p_;
  std::vector<Quat> q_;
};

/// Converts a TUM pose (z-up world {w}, e.g. ENU) to the navigation frame {n} of the filter
/// (z down): a rotation by pi about x. The body frame is unchanged.
io::StampedPose worldZUpToNav(const io::StampedPose& pose_w);

/// Loads a TUM file as a C2 trajectory in {n}. Clear errors for unreadable, malformed or too
/// short files (fewer than 4 poses or less than 1 s).
std::shared_ptr<BsplineTrajectory> loadTumTrajectory(const std::string& path, double knot_spacing_s = 0.05);

}  // namespace vi_ekf_slam::sim
