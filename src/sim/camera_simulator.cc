#include "vi_ekf_slam/sim/camera_simulator.h"

#include <algorithm>

namespace vi_ekf_slam::sim {

CameraFrame observe(const TrajectorySample& s, const LandmarkWorld& world, const CameraModel& camera,
                    const CameraExtrinsics& T_b_c, const CameraSimParams& p, std::mt19937_64* rng) {
  MotionState x;  // the true body pose, as a world-centric state
  x.p_s_b = s.p_n_b;
  x.q_s_b = s.q_n_b;
  std::vector<std::pair<double, FeatureObservation>> visible;
  for (const auto& l : world) {
    const Vec3 p_c = landmarkInCamera(x, l.p_n, T_b_c);
    const double range = p_c.norm();
    if (p_c.z() < p.min_depth_m || range > p.max_range_m) continue;
    Eigen::Vector2d uv;
    if (!camera.project(p_c, &uv) || !camera.inImage(uv, p.border_px)) continue;
    visible.push_back({range, {l.id, uv}});
  }
  std::sort(visible.begin(), visible.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  if (static_cast<int>(visible.size()) > p.max_features) visible.resize(static_cast<size_t>(p.max_features));
  CameraFrame f;
  f.timestamp = s.t;
  std::normal_distribution<double> n(0.0, p.pixel_noise_px);
  for (auto& v : visible) {
    if (rng && p.pixel_noise_px > 0.0) {
      const double du = n(*rng), dv = n(*rng);
      v.second.uv += Eigen::Vector2d(du, dv);
    }
    f.features.push_back(v.second);
  }
  return f;
}

}  // namespace vi_ekf_slam::sim
