#include "vi_ekf_slam/sim/camera_simulator.h"

#include <algorithm>
#include <cmath>
#include <memory>
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
    : world_(world), camera_(camera), T_b_c_(T_b_c), params_(params) {
  for (size_t i = 0; i < world_.size(); ++i) index_of_[world_[i].id] = i;
}

Descriptor landmarkPattern(std::int64_t landmark, const DescriptorSimParams& params) {
  const std::int64_t pattern = params.texture_patterns > 0 ? landmark % params.texture_patterns : landmark;
  std::minstd_rand g(static_cast<std::uint32_t>(static_cast<std::uint64_t>(pattern) * 2654435761ULL) | 1u);
  Descriptor d;
  for (auto& byte : d) byte = static_cast<std::uint8_t>((g() >> 7) & 0xff);
  return d;
}

std::optional<Descriptor> TrackingCamera::describe(std::int64_t landmark, std::uint64_t salt, const Vec3& p_n_c) const {
  const DescriptorSimParams& p = params_.descriptors;
  if (!p.enabled) return std::nullopt;
  const Vec3 ray = p_n_c - world_.at(static_cast<size_t>(landmark)).p_n;
  const double distance = std::max(1e-6, ray.norm());
  // The appearance is a function of the view (not of the order of the views): each bit of the
  // pattern flips with a stripe function of the viewing direction and log-distance, period 2 along
  // a random direction. Two views differ in a bit with probability |n . (phi_1 - phi_2)|
  // (E = sqrt(2/pi) |dphi|) while that is small, and in about half of their bits when far apart
  // (no resemblance left); the scales give bits_per_rad and bits_per_log_scale on average. The
  // stripes belong to the pattern, so look-alikes (texture_patterns) change alike.
  constexpr double kMeanAbsNormal = 0.7978845608;  // E|n . u| for n ~ N(0, I), |u| = 1
  Eigen::Vector4d phi;
  phi.head<3>() = ray / distance * (p.bits_per_rad / (256.0 * kMeanAbsNormal));
  phi(3) = std::log(distance) * (p.bits_per_log_scale / (256.0 * kMeanAbsNormal));
  const std::int64_t pattern = p.texture_patterns > 0 ? landmark % p.texture_patterns : landmark;
  std::minstd_rand view(static_cast<std::uint32_t>(static_cast<std::uint64_t>(pattern) * 40503ULL + 12345ULL) | 1u);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> phase(0.0, 2.0);
  // Each detection adds its own noise: two from the same view differ in same_view_bits on average.
  // (The track's own randomness, not the frame's generator: descriptors change nothing else.)
  std::minstd_rand g(static_cast<std::uint32_t>(static_cast<std::uint64_t>(landmark) * 2654435761ULL + salt * 97ULL) |
                     1u);
  std::bernoulli_distribution noise(std::clamp(p.same_view_bits / 512.0, 0.0, 0.5));
  Descriptor d = landmarkPattern(landmark, p);
  for (auto& byte : d) {
    for (int bit = 0; bit < 8; ++bit) {
      Eigen::Vector4d n;
      for (int k = 0; k < 4; ++k) n(k) = normal(view);
      const bool stripe = static_cast<long>(std::floor(n.dot(phi) + phase(view))) % 2 != 0;
      if (stripe != noise(g)) byte ^= static_cast<std::uint8_t>(1u << bit);
    }
  }
  return d;
}

std::int64_t trackId(std::int64_t landmark, std::int64_t k, size_t world_size) {
  return landmark + k * static_cast<std::int64_t>(world_size);
}

const WorldLandmark& landmarkOfTrack(std::int64_t track_id, const LandmarkWorld& world) {
  return world.at(static_cast<size_t>(track_id % static_cast<std::int64_t>(world.size())));
}

CameraFrame TrackingCamera::observe(const TrajectorySample& s, std::mt19937_64* rng) {
  // Visible landmarks by their index in the world (visibleLandmarks reports world ids).
  std::unordered_map<std::int64_t, Eigen::Vector2d> uv_of;
  std::vector<std::int64_t> visible;
  for (const auto& v : visibleLandmarks(s, world_, camera_, T_b_c_, params_)) {
    const auto landmark = static_cast<std::int64_t>(index_of_.at(v.id));
    uv_of[landmark] = v.uv;
    visible.push_back(landmark);
  }
  const int cols = std::max(1, params_.grid_cols), rows = std::max(1, params_.grid_rows);
  auto cellOf = [&](const Eigen::Vector2d& uv) {
    const int c = std::clamp(static_cast<int>(uv.x() * cols / camera_.width()), 0, cols - 1);
    const int r = std::clamp(static_cast<int>(uv.y() * rows / camera_.height()), 0, rows - 1);
    return r * cols + c;
  };
  // Continue the tracks that are still visible; the others end for good.
  std::vector<Track> kept;
  std::vector<int> occupancy(static_cast<size_t>(cols * rows), 0);
  for (const auto& track : tracked_) {
    auto it = uv_of.find(track.landmark);
    if (it == uv_of.end()) continue;
    kept.push_back(track);
    ++occupancy[static_cast<size_t>(cellOf(it->second))];
  }
  // Start new tracks, always in the currently emptiest cell (ties: a random candidate).
  auto isKept = [&](std::int64_t landmark) {
    return std::any_of(kept.begin(), kept.end(), [&](const Track& t) { return t.landmark == landmark; });
  };
  std::vector<std::int64_t> candidates;
  for (auto landmark : visible) {
    if (!isKept(landmark)) candidates.push_back(landmark);
  }
  if (rng) std::shuffle(candidates.begin(), candidates.end(), *rng);
  std::vector<bool> used(candidates.size(), false);
  const Vec3 p_n_c = s.p_n_b + s.q_n_b * T_b_c_.p_b_c;
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
    const std::int64_t landmark = candidates[static_cast<size_t>(best)];
    const std::int64_t k = tracks_started_[landmark]++;
    const std::optional<Descriptor> d = describe(landmark, static_cast<std::uint64_t>(k), p_n_c);
    kept.push_back({landmark, trackId(landmark, k, world_.size()), d, d});
    ++occupancy[static_cast<size_t>(cellOf(uv_of[landmark]))];
  }
  // A tracker describes its tracks again every kDescribeEveryFrames images (the appearance the
  // map keeps is the latest view's, which is what a return to the same place sees).
  if (frames_ % kDescribeEveryFrames == 0) {
    for (auto& track : kept) track.latest_descriptor = describe(track.landmark, (frames_ << 20) + 3, p_n_c);
  }
  tracked_ = kept;
  CameraFrame f;
  f.timestamp = s.t;
  std::normal_distribution<double> n(0.0, 1.0);
  for (const auto& track : kept) {
    Eigen::Vector2d uv = uv_of[track.landmark];
    if (rng && params_.pixel_noise_px > 0.0) {
      const double du = n(*rng), dv = n(*rng);
      uv += params_.pixel_noise_px * Eigen::Vector2d(du, dv);
    }
    f.features.push_back({track.id, uv, track.descriptor, track.latest_descriptor});
  }
  ++frames_;
  if (params_.descriptors.enabled) {
    std::vector<std::pair<std::int64_t, Eigen::Vector2d>> untracked;
    for (auto landmark : visible)
      if (!isKept(landmark)) untracked.emplace_back(landmark, uv_of[landmark]);
    offerSearch(&f, std::move(untracked), p_n_c);
  }
  return f;
}

void TrackingCamera::offerSearch(CameraFrame* frame, std::vector<std::pair<std::int64_t, Eigen::Vector2d>> untracked,
                                 const Vec3& p_n_c) {
  const std::uint64_t image = frames_;
  // The corners returned by the last search, by their id (their index): what adopt() takes.
  auto found = std::make_shared<std::vector<std::int64_t>>();
  frame->search = [this, untracked, p_n_c, image, found](const std::vector<SearchRegion>& regions) {
    std::vector<FeatureObservation> corners;
    found->clear();
    for (const auto& [landmark, uv_true] : untracked) {
      const bool inside = std::any_of(regions.begin(), regions.end(), [&](const SearchRegion& r) {
        const Eigen::Vector2d e = uv_true - r.uv;
        return e.dot(r.S.ldlt().solve(e)) <= 16.0;  // a 4-sigma ellipse
      });
      if (!inside) continue;
      // The draws of this landmark in this image: found or not, its pixel noise, its appearance.
      std::minstd_rand g(
          static_cast<std::uint32_t>((static_cast<std::uint64_t>(landmark) * 2654435761ULL) ^ (image * 40503ULL)) | 1u);
      if (!std::bernoulli_distribution(params_.descriptors.redetect_probability)(g)) continue;
      std::normal_distribution<double> n(0.0, 1.0);
      const Eigen::Vector2d uv = uv_true + params_.pixel_noise_px * Eigen::Vector2d(n(g), n(g));
      corners.push_back({static_cast<std::int64_t>(found->size()), uv, describe(landmark, (image << 24) + 7, p_n_c)});
      found->push_back(landmark);
    }
    return corners;
  };
  frame->adopt = [this, found](const FeatureObservation& corner) {
    const std::int64_t landmark = found->at(static_cast<size_t>(corner.id));
    const std::int64_t k = tracks_started_[landmark]++;
    tracked_.push_back({landmark, trackId(landmark, k, world_.size()), corner.descriptor, corner.descriptor});
    return tracked_.back().id;
  };
}

}  // namespace vi_ekf_slam::sim
