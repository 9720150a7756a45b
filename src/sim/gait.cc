#include "vi_ekf_slam/sim/gait.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace vi_ekf_slam::sim {

Gait::Gait(const GaitParams& params, std::uint64_t seed) : p_(params) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.2, 0.5);
  f1_hz_ = u(rng);
  f2_hz_ = u(rng);
}

void Gait::advance(double v, double dt) {
  const double cadence =
      p_.step_frequency_hz * std::pow(std::max(0.0, v) / p_.cruise_speed_mps, p_.cadence_speed_exponent);
  phase_ += 2.0 * M_PI * cadence * dt;
}

io::StampedPose Gait::pose(double t, Vec3 centre, double heading, double v) const {
  const double a = std::min(v / p_.cruise_speed_mps, p_.max_amplitude);
  const double still = 1.0 - std::clamp(v / 0.3, 0.0, 1.0);
  const Vec3 side(-std::sin(heading), std::cos(heading), 0.0);
  const double lateral =
      a * p_.sway_m * std::sin(0.5 * phase_) + still * p_.postural_sway_m * std::sin(2.0 * M_PI * f1_hz_ * t);
  centre += lateral * side;
  centre.z() += -a * p_.bounce_m * std::cos(phase_);
  const double yaw = heading + a * p_.yaw_sway_rad * std::cos(0.5 * phase_);
  const double roll = a * p_.roll_sway_rad * std::sin(0.5 * phase_);
  const double pitch =
      a * p_.pitch_bob_rad * std::sin(phase_) + still * p_.postural_pitch_rad * std::sin(2.0 * M_PI * f2_hz_ * t + 1.0);
  io::StampedPose sp;
  sp.t = t;
  sp.p = centre;
  sp.q = Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
              Eigen::AngleAxisd(roll, Vec3::UnitX()));
  return sp;
}

}  // namespace vi_ekf_slam::sim
