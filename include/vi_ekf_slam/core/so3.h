// SO(3) helpers shared by the whole core: skew matrices, exponential/logarithm maps and the
// right Jacobian. Rotations follow the project convention: R_a_b maps vectors from b to a,
// quaternions are Eigen's Hamilton quaternions, and orientation errors are global (left)
// perturbations as in the paper's eq. (4): R_true = Exp(psi) * R_est.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace vi_ekf_slam {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

/// [v]x, so that skew(a) * b == a.cross(b).
inline Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

/// Rotation vector -> unit quaternion (exact, with a series for tiny angles).
inline Quat expQuat(const Vec3& phi) {
  const double theta = phi.norm();
  if (theta < 1e-10) {
    Quat q(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z());
    return q.normalized();
  }
  return Quat(Eigen::AngleAxisd(theta, phi / theta));
}

/// Rotation vector -> rotation matrix.
inline Mat3 expSO3(const Vec3& phi) { return expQuat(phi).toRotationMatrix(); }

/// Unit quaternion -> rotation vector in (-pi, pi].
inline Vec3 logQuat(const Quat& q_in) {
  Quat q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // shortest rotation
  const double sin_half = q.vec().norm();
  if (sin_half < 1e-10) return 2.0 * q.vec() / q.w();
  const double theta = 2.0 * std::atan2(sin_half, q.w());
  return theta * q.vec() / sin_half;
}

/// Rotation matrix -> rotation vector.
inline Vec3 logSO3(const Mat3& R) { return logQuat(Quat(R)); }

/// The angle [rad] of the rotation about {n}'s z axis that best turns attitude R_n_from into
/// R_n_to: the z rotation nearest (Frobenius) to R_n_to R_n_from^T. Defined whatever the body's
/// axes: the heading of one body axis is not when that axis is near vertical (an IMU mounted x up).
inline double yawBetween(const Quat& q_n_from, const Quat& q_n_to) {
  const Mat3 D = (q_n_to * q_n_from.conjugate()).toRotationMatrix();
  return std::atan2(D(1, 0) - D(0, 1), D(0, 0) + D(1, 1));
}

/// T_to_from: the turn about z by yawBetween(q_from, q_to) and the translation that put the pose
/// (p_from, q_from) of one trajectory on the pose (p_to, q_to) of another: a visual-inertial
/// estimate's unobservable yaw and position, registered at its first pose.
inline Eigen::Isometry3d registrationAtFirstPose(const Vec3& p_from, const Quat& q_from, const Vec3& p_to,
                                                 const Quat& q_to) {
  Eigen::Isometry3d T(Eigen::AngleAxisd(yawBetween(q_from, q_to), Vec3::UnitZ()));
  T.translation() = p_to - T.linear() * p_from;
  return T;
}

/// Right Jacobian of SO(3): Exp(phi + d) ~= Exp(phi) * Exp(Jr(phi) * d).
inline Mat3 rightJacobianSO3(const Vec3& phi) {
  const double theta = phi.norm();
  const Mat3 K = skew(phi);
  if (theta < 1e-6) return Mat3::Identity() - 0.5 * K + K * K / 6.0;
  const double t2 = theta * theta;
  return Mat3::Identity() - (1.0 - std::cos(theta)) / t2 * K + (theta - std::sin(theta)) / (t2 * theta) * K * K;
}

/// Orientation error between two rotations in the global (left) convention:
/// returns psi with R_a = Exp(psi) * R_b.
inline Vec3 rotationError(const Quat& q_a, const Quat& q_b) { return logQuat(q_a * q_b.conjugate()); }

}  // namespace vi_ekf_slam
