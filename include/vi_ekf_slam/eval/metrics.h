// Evaluation metrics, defined once for the study, the tools and the tests (DESIGN.md):
// errors as true minus estimate with orientation error Log(R_true R_est^T) (global, like the
// filter's psi), NEES e^T P^-1 e, its chi-square band for M Monte-Carlo runs, ATE/RPE, posyaw
// alignment, and the paper's scale ratio gamma (eq. 34).
#pragma once

#include <Eigen/Core>
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

/// Path length of a sequence of positions.
double pathLength(const std::vector<Vec3>& p);

/// Relative pose error of position over windows of `delta` samples: RMS of
/// || (p_true[k+d] - p_true[k]) - R_true[k] R_est[k]^T (p_est[k+d] - p_est[k]) ||.
double rpePosition(const std::vector<Vec3>& p_true, const std::vector<Quat>& q_true, const std::vector<Vec3>& p_est,
                   const std::vector<Quat>& q_est, int delta);

}  // namespace vi_ekf_slam::eval
