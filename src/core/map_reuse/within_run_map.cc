#include "vi_ekf_slam/core/map_reuse/within_run_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "vi_ekf_slam/core/chi_squared.h"

namespace vi_ekf_slam {

void WithinRunMap::clear() {
  descriptors_.clear();
  latest_descriptors_.clear();
  dormant_.clear();
  revisiting_.clear();
  pending_.clear();
}

std::vector<RevisitMatch> WithinRunMap::find(const FilterView& f, const CameraFrame& frame,
                                             std::vector<FeatureObservation>* fresh,
                                             std::vector<FeatureObservation>* known) {
  const FilterState& state = f.state;
  const EkfSlamConfig& config = f.config;
  std::vector<RevisitMatch> matches;
  if (descriptors_.empty()) return matches;
  // The well-mapped landmarks not observed in this image (dormant, or whose track just ended),
  // where the filter predicts them.
  std::unordered_set<std::int64_t> observed;
  for (const auto& o : *known) observed.insert(o.id);
  for (const auto& [track, q] : pending_) observed.insert(q.landmark_id);  // one match at a time
  std::vector<RevisitCandidate> candidates;
  for (int i = 0; i < state.numLandmarks(); ++i) {
    const std::int64_t id = state.landmarkIds()[static_cast<size_t>(i)];
    const auto d = descriptors_.find(id);
    if (d == descriptors_.end() || observed.count(id) || !wellMapped(state, i, config.map)) continue;
    const auto p = predictWithCovariance(state, i, f.camera, state.x.T_b_c, config.update, f.omega_b);
    if (p) candidates.push_back({id, p->uv, p->S, d->second});
  }
  if (candidates.empty()) return matches;
  // Proposals: each a landmark and the observation that would be it.
  struct Proposal {
    RevisitMatch match;
    FeatureObservation obs;  ///< under its own id (a fresh track's, or the search's corner's)
    bool searched = false;
  };
  std::vector<Proposal> proposals;
  // 1) The new tracks of this image (a point the detector found again), told apart from the
  //    image's other tracks too (matchRevisits).
  std::vector<FeatureObservation> searching;
  std::unordered_set<std::int64_t> searching_ids;
  for (const auto& o : *fresh) {
    if (o.descriptor && !revisiting_.count(o.id)) {
      searching.push_back(o);
      searching_ids.insert(o.id);
    }
  }
  std::vector<FeatureObservation> other_tracks, all_tracks;
  for (const auto& o : frame.features) {
    const auto& d = o.latest_descriptor ? o.latest_descriptor : o.descriptor;
    if (!d) continue;
    all_tracks.push_back({o.id, o.uv, d});
    if (!searching_ids.count(o.id)) other_tracks.push_back(all_tracks.back());
  }
  for (const auto& m : matchRevisits(candidates, searching, config.map, other_tracks)) {
    const auto s = std::find_if(searching.begin(), searching.end(), [&](const auto& o) { return o.id == m.track_id; });
    proposals.push_back({m, *s, false});
  }
  // 2) The others: the front end looks again inside their regions.
  std::vector<FeatureObservation> corners;
  if (frame.search && frame.adopt) {
    std::vector<RevisitCandidate> rest;
    std::vector<SearchRegion> regions;
    const double max_var = config.map.max_search_sigma_px * config.map.max_search_sigma_px;
    for (const auto& c : candidates) {
      const bool taken = std::any_of(proposals.begin(), proposals.end(),
                                     [&](const auto& q) { return q.match.landmark_id == c.landmark_id; });
      if (taken || !(c.S.trace() <= 2.0 * max_var)) continue;
      rest.push_back(c);
      regions.push_back({c.landmark_id, c.uv, c.S});
    }
    if (!regions.empty()) corners = frame.search(regions);
    for (const auto& m : matchRevisits(rest, corners, config.map, all_tracks)) {
      const auto c = std::find_if(corners.begin(), corners.end(), [&](const auto& o) { return o.id == m.track_id; });
      proposals.push_back({m, *c, true});
    }
  }
  // 3) Joint compatibility: one look-alike alone in a region passes every test above, but the
  //    matches of one image must agree on the one pose error that moved their landmarks. The
  //    stacked innovation (with the landmarks' cross-covariances) must pass the chi^2 gate of its
  //    dimension; the match that disagrees most leaves until it does, and fewer than
  //    map.min_joint_revisits agreeing matches are none.
  const double joint_gate = config.update.gate_probability;
  while (static_cast<int>(proposals.size()) >= std::max(1, config.map.min_joint_revisits)) {
    std::vector<FeatureObservation> as_landmarks;
    as_landmarks.reserve(proposals.size());
    for (const auto& q : proposals) as_landmarks.push_back({q.match.landmark_id, q.obs.uv, std::nullopt});
    const JointInnovation j = jointInnovation(state, as_landmarks, f.camera, state.x.T_b_c, config.update, f.omega_b);
    if (j.valid && j.nis <= chiSquaredQuantile(joint_gate, 2.0 * static_cast<double>(proposals.size()))) break;
    const size_t worst =
        j.valid ? static_cast<size_t>(std::max_element(j.each.begin(), j.each.end()) - j.each.begin()) : 0;
    proposals.erase(proposals.begin() + static_cast<std::ptrdiff_t>(worst));
  }
  if (static_cast<int>(proposals.size()) < config.map.min_joint_revisits) return matches;
  // The agreeing matches observe their landmarks under their ids (or, with revisit_confirm_frames
  // > 1, are pending until their tracks have agreed that long); a searched corner becomes a track
  // of the front end, which observes the landmark from then on.
  for (const auto& q : proposals) {
    RevisitMatch m = q.match;
    if (q.searched) {
      m.track_id = frame.adopt(q.obs);
    } else {
      fresh->erase(std::find_if(fresh->begin(), fresh->end(), [&](const auto& o) { return o.id == q.obs.id; }));
    }
    if (config.map.revisit_confirm_frames > 1) {
      const auto c = std::find_if(candidates.begin(), candidates.end(),
                                  [&](const auto& x) { return x.landmark_id == m.landmark_id; });
      pending_[m.track_id] = {m.landmark_id, m.distance, 1, q.obs.uv - c->uv, state.timestamp};
      continue;
    }
    known->push_back(q.obs);
    known->back().id = m.landmark_id;
    matches.push_back(m);
  }
  return matches;
}

std::vector<RevisitMatch> WithinRunMap::confirm(const FilterView& f, const std::vector<FeatureObservation>& pending,
                                                double gate_probability, std::vector<FeatureObservation>* fresh,
                                                std::vector<FeatureObservation>* known, int* refused) {
  const FilterState& state = f.state;
  const EkfSlamConfig& config = f.config;
  std::vector<RevisitMatch> confirmed;
  std::unordered_set<std::int64_t> observed;
  for (const auto& o : *known) observed.insert(o.id);
  // (The search's gate at least: a match at the edge of the update's narrow gate is no look-alike.)
  const double gate = std::max(config.map.search_gate_probability, gate_probability);
  for (const auto& o : pending) {
    PendingRevisit& q = pending_.at(o.id);
    const std::optional<int> i = state.findLandmark(q.landmark_id);
    std::optional<PredictedPixel> p;
    if (i && !observed.count(q.landmark_id))
      p = predictWithCovariance(state, *i, f.camera, state.x.T_b_c, config.update, f.omega_b);
    if (!p ||
        !pendingRevisitAgrees(o.uv - p->uv, p->S, q.first_innovation, gate, config.update.pixel_noise_px, config.map)) {
      revisiting_[o.id] = kNotRevisit;  // a new point from now on
      pending_.erase(o.id);
      fresh->push_back(o);
      ++*refused;
      continue;
    }
    if (++q.frames < config.map.revisit_confirm_frames) continue;
    confirmed.push_back({o.id, q.landmark_id, q.distance});
    observed.insert(q.landmark_id);
    known->push_back(o);
    known->back().id = q.landmark_id;
    pending_.erase(o.id);
  }
  return confirmed;
}

std::vector<RevisitMatch> WithinRunMap::settle(const std::vector<RevisitMatch>& revisits, const UpdateResult& update,
                                               std::unordered_set<std::int64_t>* refused_landmarks,
                                               int* refused_count) {
  std::vector<RevisitMatch> accepted;
  for (const auto& m : revisits) {
    const bool gated_out =
        std::find(update.rejected_ids.begin(), update.rejected_ids.end(), m.landmark_id) != update.rejected_ids.end() ||
        std::find(update.invalid_ids.begin(), update.invalid_ids.end(), m.landmark_id) != update.invalid_ids.end();
    if (gated_out) {
      revisiting_[m.track_id] = kNotRevisit;
      refused_landmarks->insert(m.landmark_id);
      ++*refused_count;
    } else {
      revisiting_[m.track_id] = m.landmark_id;
      accepted.push_back(m);
    }
  }
  return accepted;
}

void WithinRunMap::observed(FilterState& state, std::int64_t landmark_id) {
  dormant_.erase(landmark_id);
  if (const auto i = state.findLandmark(landmark_id)) state.landmark(*i).consider = false;
}

std::pair<Vec3, double> WithinRunMap::positionVariance(const FilterState& state, int i) {
  Mat3 M;
  const Vec3 p = state.landmark(i).position(&M);
  const int c = state.landmarkIndex(i);
  return {p, (M * state.covariance().block<3, 3>(c, c) * M.transpose()).trace()};
}

bool WithinRunMap::wellMapped(const FilterState& state, int i, const MapReuseParams& params) {
  const auto [p, var] = positionVariance(state, i);
  const double distance = (p - state.x.p_s_b).norm();
  return std::isfinite(var) && var <= std::pow(params.max_relative_sigma * distance, 2);
}

void WithinRunMap::rememberAppearance(const FilterState& state, const std::vector<FeatureObservation>& observed) {
  for (const auto& o : observed) {
    if (!state.findLandmark(o.id)) continue;
    if (o.descriptor && !descriptors_.count(o.id)) descriptors_[o.id] = *o.descriptor;
    if (const auto& d = o.latest_descriptor ? o.latest_descriptor : o.descriptor) latest_descriptors_[o.id] = *d;
  }
}

void WithinRunMap::forgetEndedTracks(const FilterState& state, const CameraFrame& frame,
                                     const std::vector<RevisitMatch>& started) {
  if (revisiting_.empty() && pending_.empty()) return;
  std::unordered_set<std::int64_t> live;
  for (const auto& o : frame.features) live.insert(o.id);
  for (const auto& m : started) live.insert(m.track_id);  // adopted in this image: seen from the next on
  for (auto it = revisiting_.begin(); it != revisiting_.end();)
    it = live.count(it->first) ? std::next(it) : revisiting_.erase(it);
  for (auto it = pending_.begin(); it != pending_.end();) {
    // (A corner adopted in this image is tracked from the next.)
    it = live.count(it->first) || it->second.found_t == state.timestamp ? std::next(it) : pending_.erase(it);
  }
}

void WithinRunMap::retire(const FilterView& f, const std::vector<std::int64_t>& leaving, int wanted,
                          std::vector<std::int64_t>* drop) {
  const FilterState& state = f.state;
  const EkfSlamConfig& config = f.config;
  for (auto id : leaving) {
    const auto i = state.findLandmark(id);
    if (config.map.within_run && descriptors_.count(id) && i && wellMapped(state, *i, config.map)) {
      dormant_.insert(id);
      f.state.landmark(*i).consider = config.map.dormant_consider;
    } else {
      drop->push_back(id);
    }
  }
  // Dormant points use the room the tracked ones leave in the map (max_landmarks bounds them all,
  // so the cost at the bound is the same), up to map.max_dormant.
  const int tracked = state.numLandmarks() - static_cast<int>(dormant_.size()) - static_cast<int>(drop->size());
  const int allowed = std::clamp(config.max_landmarks - wanted - tracked, 0, config.map.max_dormant);
  int excess = static_cast<int>(dormant_.size()) - allowed;
  if (excess <= 0) return;
  // What a kept point is worth is the place it lets the filter recognize: the map should cover
  // every place walked, not the last few metres. So the dormant points are binned in cells of
  // map.dormant_spacing_m and the most crowded cell gives up a point first, the least certain of
  // its points (the trace of its covariance): a point the filter knows well corrects the pose
  // most when it is seen again.
  std::map<std::array<long, 3>, std::vector<std::pair<double, std::int64_t>>> cells;
  for (auto id : dormant_) {
    const auto i = state.findLandmark(id);
    if (!i) continue;
    const auto [position, variance] = positionVariance(state, *i);
    const Vec3 p = position / config.map.dormant_spacing_m;
    const std::array<long, 3> key{std::lround(std::floor(p.x())), std::lround(std::floor(p.y())),
                                  std::lround(std::floor(p.z()))};
    cells[key].emplace_back(variance, id);
  }
  for (auto& [key, points] : cells) std::sort(points.begin(), points.end());  // most certain first
  for (; excess > 0; --excess) {
    auto crowded = cells.begin();
    for (auto it = cells.begin(); it != cells.end(); ++it)
      if (it->second.size() > crowded->second.size()) crowded = it;
    if (crowded == cells.end() || crowded->second.empty()) break;
    const std::int64_t id = crowded->second.back().second;
    crowded->second.pop_back();
    dormant_.erase(id);
    drop->push_back(id);
  }
}

void WithinRunMap::removing(const FilterView& f, const std::vector<std::int64_t>& ids) {
  // The well-mapped ones leave for the map kept across runs (VioPipeline's kept map).
  if (f.config.map.within_run && f.config.map.across_runs) {
    const std::unordered_set<std::int64_t> leaving(ids.begin(), ids.end());
    for (const MapPoint& p : mapPoints(f.state, f.config))
      if (leaving.count(p.id)) left_the_state_.push_back(p);
  }
  for (auto id : ids) {
    descriptors_.erase(id);
    latest_descriptors_.erase(id);
    dormant_.erase(id);
  }
}

std::vector<MapPoint> WithinRunMap::takeLeftTheState() {
  std::vector<MapPoint> out = std::move(left_the_state_);
  left_the_state_.clear();
  return out;
}

std::vector<MapPoint> WithinRunMap::mapPoints(const FilterState& state, const EkfSlamConfig& config) const {
  std::vector<MapPoint> out;
  for (const NavLandmark& l : navLandmarks(state)) {
    const auto d = latest_descriptors_.find(l.id);
    const std::optional<int> i = state.findLandmark(l.id);
    if (d == latest_descriptors_.end() || !i || !wellMapped(state, *i, config.map)) continue;
    out.push_back({l.id, l.p_n_l, l.cov, d->second});
  }
  return out;
}

}  // namespace vi_ekf_slam
