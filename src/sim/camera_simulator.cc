#include "vi_ekf_slam/sim/camera_simulator.h"

#include <algorithm>
#include <unordered_map>

namespace vi_ekf_slam::sim {

std::vector<FeatureObservation> visibleLandmarks(const TrajectorySample& s, const LandmarkWorld& world,
                                                 const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                                 const CameraSimParams& p) {
  MotionState x;  // the true body pose, as a world-centric state
  x.p_s_b = s.p_n_b;
  x.q_s_b = s.q_n_b;
  std::vector<FeatureObservation> out;
  for (const auto& l : world) {
    const Vec3 p_c = landmarkInCamera(x, l.p_n, T_b_c);
    if (p_c.z() < p.min_depth_m || p_c.norm() > p.max_range_m) continue;
    Eigen::Vector2d uv;
    if (!camera.project(p_c, &uv) || !camera.inImage(uv, p.border_px)) continue;
    out.push_back({l.id, uv});
  }
  return out;
}

TrackingCamera::TrackingCamera(const LandmarkWorld& world, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                               const CameraSimParams& params)
    : world_(world), camera_(camera), T_b_c_(T_b_c), params_(params) {}

CameraFrame TrackingCamera::observe(const TrajectorySample& s, std::mt19937_64* rng) {
  const std::vector<FeatureObservation> visible = visibleLandmarks(s, world_, camera_, T_b_c_, params_);
  std::unordered_map<std::int64_t, Eigen::Vector2d> uv_of;
  for (const auto& v : visible) uv_of[v.id] = v.uv;
  const int cols = std::max(1, params_.grid_cols), rows = std::max(1, params_.grid_rows);
  auto cellOf = [&](const Eigen::Vector2d& uv) {
    const int c = std::clamp(static_cast<int>(uv.x() * cols / camera_.width()), 0, cols - 1);
    const int r = std::clamp(static_cast<int>(uv.y() * rows / camera_.height()), 0, rows - 1);
    return r * cols + c;
  };
  // Continue the tracks that are still visible.
  std::vector<std::int64_t> kept;
  std::vector<int> occupancy(static_cast<size_t>(cols * rows), 0);
  for (auto id : tracked_) {
    auto it = uv_of.find(id);
    if (it == uv_of.end()) continue;
    kept.push_back(id);
    ++occupancy[static_cast<size_t>(cellOf(it->second))];
  }
  // Start new tracks, always in the currently emptiest cell (ties: a random candidate).
  std::vector<std::int64_t> candidates;
  for (const auto& v : visible) {
    if (std::find(kept.begin(), kept.end(), v.id) == kept.end()) candidates.push_back(v.id);
  }
  if (rng) std::shuffle(candidates.begin(), candidates.end(), *rng);
  std::vector<bool> used(candidates.size(), false);
  while (static_cast<int>(kept.size()) < params_.max_features) {
    int best = -1, best_occ = 1 << 30;
    for (size_t i = 0; i < candidates.size(); ++i) {
      if (used[i]) continue;
      const int occ = occupancy[static_cast<size_t>(cellOf(uv_of[candidates[i]]))];
      if (occ < best_occ) {
        best_occ = occ;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) break;
    used[static_cast<size_t>(best)] = true;
    kept.push_back(candidates[static_cast<size_t>(best)]);
    ++occupancy[static_cast<size_t>(cellOf(uv_of[candidates[static_cast<size_t>(best)]]))];
  }
  tracked_ = kept;
  CameraFrame f;
  f.timestamp = s.t;
  std::normal_distribution<double> n(0.0, 1.0);
  for (auto id : kept) {
    Eigen::Vector2d uv = uv_of[id];
    if (rng && params_.pixel_noise_px > 0.0) {
      const double du = n(*rng), dv = n(*rng);
      uv += params_.pixel_noise_px * Eigen::Vector2d(du, dv);
    }
    f.features.push_back({id, uv});
  }
  return f;
}

}  // namespace vi_ekf_slam::sim
