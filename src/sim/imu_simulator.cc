#include "vi_ekf_slam/sim/imu_simulator.h"

#include <cmath>

namespace vi_ekf_slam::sim {

namespace {
Vec3 gaussian3(std::mt19937_64& rng, double sigma) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double x = n(rng), y = n(rng), z = n(rng);
  return sigma * Vec3(x, y, z);
}
}  // namespace

ImuSequence simulateImu(const Trajectory& traj, const ImuSimParams& p, std::mt19937_64& rng) {
  ImuSequence out;
  const double dt = 1.0 / p.rate_hz;
  const Vec3 g_n = gravityInNav(p.gravity_mps2);
  Vec3 b_a = gaussian3(rng, p.initial_accel_bias_sigma_mps2);
  Vec3 b_g = gaussian3(rng, p.initial_gyro_bias_sigma_radps);
  const double noise_scale = p.noise_enabled ? 1.0 : 0.0;
  const int n = static_cast<int>(std::floor((traj.endTime() - traj.startTime()) / dt + 1e-9)) + 1;
  out.samples.reserve(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    const double t = traj.startTime() + k * dt;
    const TrajectorySample s = traj.sample(t);
    ImuData d;
    d.timestamp = t;
    // Discrete white noise with density sigma has std-dev sigma / sqrt(dt) per sample.
    d.am = s.q_n_b.conjugate() * (s.a_n_b - g_n) + b_a +
           noise_scale * gaussian3(rng, p.noise.accel_noise_density / std::sqrt(dt));
    d.wm = s.w_b + b_g + noise_scale * gaussian3(rng, p.noise.gyro_noise_density / std::sqrt(dt));
    out.samples.push_back(d);
    out.true_accel_bias.push_back(b_a);
    out.true_gyro_bias.push_back(b_g);
    b_a += noise_scale * gaussian3(rng, p.noise.accel_random_walk * std::sqrt(dt));
    b_g += noise_scale * gaussian3(rng, p.noise.gyro_random_walk * std::sqrt(dt));
  }
  return out;
}

}  // namespace vi_ekf_slam::sim
