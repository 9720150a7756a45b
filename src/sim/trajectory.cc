#include "vi_ekf_slam/sim/trajectory.h"

#include <cmath>

namespace vi_ekf_slam::sim {

CircleTrajectory::CircleTrajectory(double radius_m, double yaw_rate_radps, double bounce_m, double duration_s)
    : r_(radius_m), w_(yaw_rate_radps), h_(bounce_m), duration_(duration_s) {}

TrajectorySample CircleTrajectory::sample(double t) const {
  TrajectorySample s;
  s.t = t;
  const double c = std::cos(w_ * t), sn = std::sin(w_ * t);
  const double c2 = std::cos(2.0 * w_ * t), s2 = std::sin(2.0 * w_ * t);
  s.p_n_b = Vec3(r_ * sn, r_ * (1.0 - c), h_ * s2);
  s.v_n_b = Vec3(r_ * w_ * c, r_ * w_ * sn, 2.0 * h_ * w_ * c2);
  s.a_n_b = Vec3(-r_ * w_ * w_ * sn, r_ * w_ * w_ * c, -4.0 * h_ * w_ * w_ * s2);
  s.q_n_b = Quat(Eigen::AngleAxisd(w_ * t, Vec3::UnitZ()));
  s.w_b = Vec3(0.0, 0.0, w_);
  return s;
}

LissajousTrajectory::LissajousTrajectory(const Vec3& p0, const Vec3& amplitude_m, const Vec3& freq_radps,
                                         const Vec3& angle_amp_rad, const Vec3& angle_freq_radps, double duration_s)
    : p0_(p0), A_(amplitude_m), w_(freq_radps), B_(angle_amp_rad), u_(angle_freq_radps), duration_(duration_s) {}

TrajectorySample LissajousTrajectory::sample(double t) const {
  TrajectorySample s;
  s.t = t;
  const Vec3 wt = w_ * t;
  const Vec3 sin_wt = wt.array().sin(), cos_wt = wt.array().cos();
  s.p_n_b = p0_ + A_.cwiseProduct(sin_wt);
  s.v_n_b = A_.cwiseProduct(w_).cwiseProduct(cos_wt);
  s.a_n_b = -A_.cwiseProduct(w_).cwiseProduct(w_).cwiseProduct(sin_wt);
  const Vec3 ut = u_ * t;
  const Vec3 phi = B_.cwiseProduct(Vec3(ut.array().sin()));
  const Vec3 phi_dot = B_.cwiseProduct(u_).cwiseProduct(Vec3(ut.array().cos()));
  s.q_n_b = expQuat(phi);
  s.w_b = rightJacobianSO3(phi) * phi_dot;  // R = Exp(phi(t)) -> R^T dR/dt = [Jr(phi) phi']x
  return s;
}

}  // namespace vi_ekf_slam::sim
