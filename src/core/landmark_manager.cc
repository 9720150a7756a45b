#include "vi_ekf_slam/core/landmark_manager.h"

#include <algorithm>
#include <cmath>

#include "vi_ekf_slam/core/landmark_initialization.h"

namespace vi_ekf_slam {

void LandmarkManager::clear(FilterState* state) {
  delayed_.clear(state);
  last_seen_.clear();
}

void LandmarkManager::started(const FilterState& state, double scene_depth_m) {
  scene_depth_hint_m_ = scene_depth_m > 0.0 && std::isfinite(scene_depth_m) ? scene_depth_m : 0.0;
  delayed_.clear(nullptr);
  last_seen_.clear();
  for (int i = 0; i < state.numLandmarks(); ++i)
    last_seen_[state.landmarkIds()[static_cast<size_t>(i)]] = state.timestamp;
}

bool LandmarkManager::triangulationActive(const FilterState& state, const EkfSlamConfig& config) {
  return config.triangulation.enabled && config.landmark_init == LandmarkInitMethod::kInverseDepth &&
         state.mechanization() == Mechanization::kSensorCentricComposition &&
         config.composition_trigger == CompositionTrigger::kEveryUpdate;
}

LandmarkManager::SceneDepth LandmarkManager::sceneDepth(const FilterState& state, const EkfSlamConfig& config) const {
  SceneDepth out;
  out.depth_m = config.inverse_depth_initial_m;
  if (!config.inverse_depth_scene_prior) return out;
  if (scene_depth_hint_m_ > 0.0) out.depth_m = scene_depth_hint_m_;
  const double max_var = 0.25 * config.inverse_depth_sigma * config.inverse_depth_sigma;
  std::vector<std::pair<double, int>> depths;
  for (int i = 0; i < state.numLandmarks(); ++i) {
    if (state.landmark(i).kind != LandmarkKind::kInverseDepth) continue;
    const int c = state.landmarkIndex(i);
    if (!(state.covariance()(c + 2, c + 2) < max_var)) continue;
    // The depth the new points are then tied to (initializeLandmarksAtMapDepth), as it reads it.
    const double rho = inverseDepthInCamera(state, i, state.x.T_b_c);
    if (rho > 0.0 && std::isfinite(1.0 / rho)) depths.emplace_back(1.0 / rho, i);
  }
  if (depths.size() < 10) return out;
  auto mid = depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2);
  std::nth_element(depths.begin(), mid, depths.end());
  out.depth_m = mid->first;
  out.landmark = mid->second;
  return out;
}

bool LandmarkManager::initializeLandmark(const FilterView& f, const FeatureObservation& obs,
                                         double inverse_depth_initial_m) {
  const EkfSlamConfig& config = f.config;
  switch (config.landmark_init) {
    case LandmarkInitMethod::kFixedDepth: {
      FixedDepthParams p;
      p.depth_m = config.landmark_depth_m;
      p.depth_sigma_m = config.landmark_depth_sigma_m;
      p.pixel_noise_px = config.update.pixel_noise_px;
      return initializeLandmarkFixedDepth(f.state, obs, f.camera, f.state.x.T_b_c, p);
    }
    case LandmarkInitMethod::kInverseDepth: {
      InverseDepthParams p;
      p.initial_depth_m = inverse_depth_initial_m;
      p.inverse_depth_sigma = config.inverse_depth_sigma;
      p.pixel_noise_px = config.update.pixel_noise_px;
      return initializeLandmarkInverseDepth(f.state, obs, f.camera, f.state.x.T_b_c, p);
    }
  }
  return false;
}

void LandmarkManager::remove(const FilterView& f, WithinRunMap& map, const std::vector<std::int64_t>& ids) {
  map.removing(f, ids);
  std::vector<int> indices;
  for (auto id : ids) {
    if (auto i = f.state.findLandmark(id)) indices.push_back(*i);
    last_seen_.erase(id);
  }
  f.state.removeLandmarks(indices);
}

std::vector<std::int64_t> LandmarkManager::makeRoom(const FilterView& f, WithinRunMap& map, double t, int wanted) {
  const EkfSlamConfig& config = f.config;
  // Tracked landmarks not seen for landmark_timeout_s leave the tracked map, then those seen
  // longest ago make room for the new ones (never one observed in this frame).
  std::vector<std::pair<double, std::int64_t>> by_age;
  for (const auto& [id, seen] : last_seen_)
    if (!map.dormant(id)) by_age.emplace_back(seen, id);
  std::sort(by_age.begin(), by_age.end());
  std::vector<std::int64_t> leaving;
  size_t k = 0;
  if (config.landmark_timeout_s >= 0.0) {
    for (; k < by_age.size() && by_age[k].first < t - config.landmark_timeout_s; ++k)
      leaving.push_back(by_age[k].second);
  }
  const int tracked = f.state.numLandmarks() - map.dormantCount();
  while (tracked - static_cast<int>(leaving.size()) + wanted > config.max_landmarks && k < by_age.size() &&
         by_age[k].first < t) {
    leaving.push_back(by_age[k++].second);
  }
  std::vector<std::int64_t> drop;
  map.retire(f, leaving, wanted, &drop);
  remove(f, map, drop);
  return drop;
}

std::vector<std::int64_t> LandmarkManager::addNow(const FilterView& f, WithinRunMap& map,
                                                  const std::vector<FeatureObservation>& fresh, double t,
                                                  std::vector<std::int64_t>* removed) {
  *removed = makeRoom(f, map, t, static_cast<int>(fresh.size()));
  return add(f, fresh, t);
}

std::vector<std::int64_t> LandmarkManager::add(const FilterView& f, const std::vector<FeatureObservation>& fresh,
                                               double t) {
  FilterState& state = f.state;
  const EkfSlamConfig& config = f.config;
  std::vector<std::int64_t> added;
  if (fresh.empty()) return added;
  const SceneDepth scene = sceneDepth(state, config);
  if (scene.landmark >= 0 && config.landmark_init == LandmarkInitMethod::kInverseDepth) {
    // At the map's depth, tied to the map's median point (initializeLandmarksAtMapDepth).
    const auto room = static_cast<size_t>(std::max(0, config.max_landmarks - state.numLandmarks()));
    const std::vector<FeatureObservation> obs(fresh.begin(), fresh.begin() + std::min(room, fresh.size()));
    for (int k : initializeLandmarksAtMapDepth(state, obs, scene.landmark, config.inverse_depth_sigma, f.camera,
                                               state.x.T_b_c, config.update.pixel_noise_px)) {
      added.push_back(obs[static_cast<size_t>(k)].id);
      last_seen_[added.back()] = t;
    }
    return added;
  }
  const double new_depth_m = scene.depth_m;
  for (const auto& o : fresh) {
    if (state.numLandmarks() >= config.max_landmarks) break;
    if (initializeLandmark(f, o, new_depth_m)) {
      added.push_back(o.id);
      last_seen_[o.id] = t;
    }
  }
  return added;
}

void LandmarkManager::addDelayed(const FilterView& f, WithinRunMap& map, const std::vector<FeatureObservation>& fresh,
                                 double t, bool wait, bool defer, FrameResult* r) {
  FilterState& state = f.state;
  const EkfSlamConfig& config = f.config;
  const double pixel_var = config.update.pixel_noise_px * config.update.pixel_noise_px;
  // Tracks wait for their baseline while the rig is seen moving (the baseline then comes within
  // max_wait_s; a point entering at the prior depth would be linearized at a depth that may be
  // off by a factor of five while the camera moves under it) and while the zero-velocity rules
  // hold new tracks back (standing, swaying, a start the detector cannot tell yet): a track then
  // enters only with the full baseline and depth gate, never at the prior depth, and a short map
  // does not take the waiting ones early (a sway's two views are what the rules keep out). At
  // rest by the IMU they enter at the prior depth, as without the delay.
  const int tracked = state.numLandmarks() - map.dormantCount();
  const int fill = defer ? 0 : config.triangulation.min_map_landmarks - (tracked - delayed_.clones());
  const DelayedLandmarks::Selection sel = delayed_.select(
      state, fresh, f.camera, state.x.T_b_c, config.triangulation, pixel_var, config.update.gate_probability, wait,
      1.0 / newLandmarkDepth(state, config), fill, config.inverse_depth_sigma);
  // The expired (not waiting, or taken by a map short of landmarks) enter at the prior depth.
  const std::vector<FeatureObservation>& at_prior = sel.expired;
  // Room for both and for a clone.
  r->removed_ids = makeRoom(f, map, t, static_cast<int>(sel.triangulated.size() + at_prior.size()) + 1);
  const int capacity = config.max_landmarks - state.numLandmarks();
  r->new_ids = delayed_.commit(state, sel, fresh, capacity, state.x.T_b_c, config.triangulation);
  r->new_triangulated = static_cast<int>(r->new_ids.size());
  for (auto id : r->new_ids) last_seen_[id] = t;
  for (auto id : add(f, at_prior, t)) r->new_ids.push_back(id);
  if (defer) r->deferred_features = static_cast<int>(fresh.size()) - r->new_triangulated;
  r->waiting_features = delayed_.waitingTracks();
}

}  // namespace vi_ekf_slam
