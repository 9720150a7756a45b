#include "vi_ekf_slam/core/delayed_landmarks.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "vi_ekf_slam/core/chi_squared.h"

namespace vi_ekf_slam {

const CameraClone* DelayedLandmarks::findClone(std::int64_t id) const {
  for (const auto& c : clones_) {
    if (c.id == id) return &c;
  }
  return nullptr;
}

template <typename Pred>
void DelayedLandmarks::removeClonesIf(FilterState* state, Pred remove) {
  std::vector<int> indices;
  for (const auto& c : clones_) {
    if (!remove(c) || !state) continue;
    if (auto i = state->findLandmark(c.id)) indices.push_back(*i);
  }
  clones_.erase(std::remove_if(clones_.begin(), clones_.end(), remove), clones_.end());
  if (state) state->removeLandmarks(indices);
}

DelayedLandmarks::Selection DelayedLandmarks::select(const FilterState& state,
                                                     const std::vector<FeatureObservation>& fresh,
                                                     const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                                     const TriangulationParams& params, double pixel_var,
                                                     double gate_probability, bool wait, double scene_inverse_depth,
                                                     int fill, double prior_inverse_depth_sigma) {
  Selection out;
  out.wait = wait;
  const double max_rho_sigma = params.max_relative_depth_sigma * scene_inverse_depth;
  std::unordered_map<std::int64_t, Waiting> still;  // the waiting tracks seen in this image
  const double gate = chiSquaredQuantile(gate_probability, 1.0);
  struct Waited {
    double how_long_s;
    FeatureObservation obs;
    std::int64_t clone_id;
    bool triangulated;  ///< the two views give a point that passes the rays' gap test
    TriangulatedLandmark landmark;
  };
  std::vector<Waited> waited;  // those still waiting
  for (const auto& f : fresh) {
    const auto w = waiting_.find(f.id);
    const CameraClone* clone = w == waiting_.end() ? nullptr : findClone(w->second.clone_id);
    if (!clone) {
      if (!wait) out.expired.push_back(f);
      continue;
    }
    TriangulatedLandmark l;
    const bool ok =
        triangulateLandmark(state, *clone, w->second.uv_clone, f.uv, camera, T_b_c, pixel_var, params.min_depth_m, &l);
    // rho ~ 1 / baseline: its first-order covariance holds only where the baseline is known to a
    // fraction of itself (a sway's few centimetres, with the velocity known to 0.05 m/s, are not).
    if (ok && l.P_ll(2, 2) <= max_rho_sigma * max_rho_sigma &&
        l.baseline_relative_sigma <= params.max_relative_depth_sigma) {
      // The rays' gap is tested only now: with little parallax their plane, and the gap's first-order
      // variance, are not defined.
      if (l.ray_gap_nis > gate) continue;  // the two views do not meet: forget (restarts as a new track)
      out.triangulated.push_back({f, clone->id, l});
    } else if (state.timestamp - clone->t > params.max_wait_s) {
      continue;  // a far point, or a rig that hardly moves: forgotten, it starts again on a new clone
    } else {
      still.emplace(f.id, w->second);
      waited.push_back({state.timestamp - clone->t, f, clone->id, ok && l.ray_gap_nis <= gate, l});
    }
  }
  // A map short of landmarks takes the tracks that waited longest, and at least
  // starved_max_wait_s, now: with the inverse depth their two views give where that is known
  // better than the prior's (a slow start's baseline after 0.3 s), else at the prior depth.
  std::sort(waited.begin(), waited.end(), [](const auto& a, const auto& b) { return a.how_long_s > b.how_long_s; });
  const int take = std::min<int>(static_cast<int>(waited.size()), fill - static_cast<int>(out.triangulated.size()));
  for (int i = 0; i < take && waited[static_cast<size_t>(i)].how_long_s >= params.starved_max_wait_s; ++i) {
    const Waited& w = waited[static_cast<size_t>(i)];
    if (w.triangulated && w.landmark.P_ll(2, 2) < prior_inverse_depth_sigma * prior_inverse_depth_sigma) {
      out.triangulated.push_back({w.obs, w.clone_id, w.landmark});
    } else {
      out.expired.push_back(w.obs);
    }
    still.erase(w.obs.id);
  }
  waiting_ = std::move(still);  // without the lost, the selected and the forgotten
  return out;
}

std::vector<std::int64_t> DelayedLandmarks::commit(FilterState& state, const Selection& selection,
                                                   const std::vector<FeatureObservation>& fresh, int capacity,
                                                   const CameraExtrinsics& T_b_c, const TriangulationParams& params) {
  std::vector<std::int64_t> added;
  for (const auto& r : selection.triangulated) {
    const CameraClone* clone = findClone(r.clone_id);
    if (static_cast<int>(added.size()) >= capacity || !clone || state.findLandmark(r.obs.id)) continue;
    appendTriangulatedLandmark(state, r.obs.id, *clone, r.landmark);
    added.push_back(r.obs.id);
  }
  // Fresh tracks that wait on nothing yet (new, or not entered above) start waiting on a clone of
  // now. The expired may enter at the prior depth now; else they start again at the next image.
  std::vector<const FeatureObservation*> unattached;
  if (selection.wait) {
    std::unordered_set<std::int64_t> expired;
    for (const auto& e : selection.expired) expired.insert(e.id);
    for (const auto& f : fresh) {
      if (!waiting_.count(f.id) && !expired.count(f.id) && !state.findLandmark(f.id)) unattached.push_back(&f);
    }
  }
  double newest = -std::numeric_limits<double>::infinity();
  for (const auto& c : clones_) newest = std::max(newest, c.t);
  const bool room = static_cast<int>(added.size()) < capacity;
  if (!unattached.empty() && room && state.timestamp - newest >= params.clone_interval_s) {
    clones_.push_back(appendCameraClone(state, next_clone_id_++, T_b_c));
    for (const auto* f : unattached) waiting_[f->id] = {clones_.back().id, f->uv};
  }
  // Clones no track waits on leave the state.
  removeClonesIf(&state, [&](const CameraClone& c) {
    return std::none_of(waiting_.begin(), waiting_.end(), [&](const auto& w) { return w.second.clone_id == c.id; });
  });
  return added;
}

void DelayedLandmarks::beforeComposition(const FilterState& state) {
  // The composition resets {s} to the body: a clone's orientation in the new {s} is R_b_s R_s_c,
  // and its error relative to the body gains the body's orientation error in {s} (which the
  // composition then removes from the state). A clone taken at this image shares that error.
  const Mat3 R_b_s = state.x.q_s_b.conjugate().toRotationMatrix();
  const Mat3 P_psi = state.covariance().block<3, 3>(idx::kPsi, idx::kPsi);
  for (auto& c : clones_) {
    if (c.t < state.timestamp) c.rotation_cov += P_psi;
    c.R_s_c = R_b_s * c.R_s_c;
    c.rotation_cov = R_b_s * c.rotation_cov * R_b_s.transpose();
  }
}

void DelayedLandmarks::clear(FilterState* state) {
  removeClonesIf(state, [](const CameraClone&) { return true; });
  waiting_.clear();
}

}  // namespace vi_ekf_slam
