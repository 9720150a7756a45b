// Evaluation metrics, defined once for the study, the tools and the tests (DESIGN.md):
// errors as true minus estimate with orientation error Log(R_true R_est^T) (global, like the
// filter's psi), NEES e^T P^-1 e, its chi-square band for M Monte-Carlo runs, ATE/RPE, posyaw
// alignment, and the paper's scale ratio gamma (eq. 34).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam::eval {

/// Log(R_true R_est^T) as a rotation vector (global frame of the two rotations).
inline Vec3 orientationError(const Quat& q_true, const Quat& q_est) { return rotationError(q_true, q_est); }

/// e^T P^-1 e; NaN if P is not positive definite.
double nees(const Eigen::VectorXd& e, const Eigen::MatrixXd& P);

/// Two-sided interval that the average of M NEES values of `dof` degrees of freedom falls into
/// with probability `prob` if the filter is consistent: chi2(dof*M) quantiles divided by M.
struct NeesBand {
  double lo = 0.0;
  double hi = 0.0;
  bool contains(double v) const { return v >= lo && v <= hi; }
};
NeesBand neesBand(int dof, int runs, double prob = 0.95);

/// Root mean square of the norms.
double rms(const std::vector<Vec3>& errors);
double rms(const std::vector<double>& values);
/// The mean of the finite values (NaN when there is none).
double meanOfFinite(const std::vector<double>& values);

/// Scale ratio gamma (paper eq. 34): sum of pairwise distances of the estimated landmarks over
/// the same sum for their true positions. NaN with fewer than two landmarks.
double scaleRatio(const std::vector<Vec3>& estimated, const std::vector<Vec3>& truth);

/// 4-DoF alignment (yaw about the gravity axis z, and translation) of `est` onto `truth` in the
/// least-squares sense; returns the aligned copy of `est` (Umeyama without scale, yaw only).
struct YawTranslation {
  double yaw = 0.0;
  Vec3 t = Vec3::Zero();
  Vec3 apply(const Vec3& p) const;
  Quat apply(const Quat& q) const;
};
YawTranslation alignPosYaw(const std::vector<Vec3>& est, const std::vector<Vec3>& truth);

/// Coming back to a place: every pose that is within radius_m of an earlier pose at least
/// min_gap_s before (the first such one) pairs with it; their position errors then and again,
/// with the estimate registered (yaw and position, alignPosYaw) on the poses before the first
/// return, those that mapped the places.
struct RevisitErrors {
  int pairs = 0;
  double first_m = std::nan("");  ///< RMS position error at the earlier poses [m]
  double again_m = std::nan("");  ///< RMS position error at the later poses [m]
  /// again_m / first_m: below 1 when a map that is kept corrects the pose on return (NaN: none).
  double ratio() const { return pairs > 0 && first_m > 0.0 ? again_m / first_m : std::nan(""); }
};
RevisitErrors revisitErrors(const std::vector<double>& t, const std::vector<Vec3>& p_true,
                            const std::vector<Vec3>& p_est, double radius_m = 0.5, double min_gap_s = 20.0);

/// Path length of a sequence of positions.
double pathLength(const std::vector<Vec3>& p);

/// Relative pose error of position over windows of `delta` samples: RMS of
/// || (p_true[k+d] - p_true[k]) - R_true[k] R_est[k]^T (p_est[k+d] - p_est[k]) ||.
double rpePosition(const std::vector<Vec3>& p_true, const std::vector<Quat>& q_true, const std::vector<Vec3>& p_est,
                   const std::vector<Quat>& q_est, int delta);

}  // namespace vi_ekf_slam::eval
