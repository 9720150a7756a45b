// The landmarks in the state: which new tracks enter and how (at once at the prior depth, tied to
// the map's depth, or after waiting for a baseline: delayed_landmarks.h), which leave to make room
// (timed out, then the longest unseen; within_run_map.h keeps some of them dormant), and when each
// was last seen. One job: the map's membership. EkfSlam owns one.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "vi_ekf_slam/core/delayed_landmarks.h"
#include "vi_ekf_slam/core/frame_result.h"
#include "vi_ekf_slam/core/map_reuse/within_run_map.h"

namespace vi_ekf_slam {

class LandmarkManager {
 public:
  /// Forgets the waiting tracks (their clones leave `state` if given) and when landmarks were seen.
  void clear(FilterState* state);
  /// A start: the landmarks it brings were seen at its time; `scene_depth_m` (> 0: a dynamic
  /// initialization's) centres new landmarks' depth prior until the map knows its own.
  void started(const FilterState& state, double scene_depth_m);
  /// The landmark was observed at t.
  void seen(std::int64_t id, double t) { last_seen_[id] = t; }

  /// New tracks wait for a baseline (config.triangulation; inverse depth composed after every update).
  static bool triangulationActive(const FilterState& state, const EkfSlamConfig& config);
  /// The fresh tracks (up to max_landmarks) enter at once, at the prior depth or tied to the map's;
  /// the landmarks leaving to make room are returned in *removed (within_run_map keeps some).
  std::vector<std::int64_t> addNow(const FilterView& f, WithinRunMap& map, const std::vector<FeatureObservation>& fresh,
                                   double t, std::vector<std::int64_t>* removed);
  /// The same through the delayed entry: triangulated tracks, then the expired ones (not waiting,
  /// or taken by a short map) at the prior depth. wait: new tracks wait for their baseline (the rig
  /// is seen moving, or the zero-velocity rules hold them back: defer, then none enters early).
  /// Fills new_ids, removed_ids and the counts of *r.
  void addDelayed(const FilterView& f, WithinRunMap& map, const std::vector<FeatureObservation>& fresh, double t,
                  bool wait, bool defer, FrameResult* r);
  /// Prior depth of new inverse-depth landmarks [m] (see inverse_depth_scene_prior).
  double newLandmarkDepth(const FilterState& state, const EkfSlamConfig& config) const {
    return sceneDepth(state, config).depth_m;
  }
  /// Removes the landmarks from the state (and what is known of them).
  void remove(const FilterView& f, WithinRunMap& map, const std::vector<std::int64_t>& ids);

  /// The clones and waiting tracks of the delayed entry.
  DelayedLandmarks& delayed() { return delayed_; }

 private:
  /// The depth new landmarks' prior is centred on [m] and, where it is the map's median, that
  /// landmark's index (else -1).
  struct SceneDepth {
    double depth_m = 0.0;
    int landmark = -1;
  };
  SceneDepth sceneDepth(const FilterState& state, const EkfSlamConfig& config) const;
  /// Removes timed-out landmarks and, for `wanted` new ones, the longest unseen; returns their ids.
  std::vector<std::int64_t> makeRoom(const FilterView& f, WithinRunMap& map, double t, int wanted);
  /// New landmarks from the fresh tracks (up to max_landmarks) without waiting; returns their ids.
  std::vector<std::int64_t> add(const FilterView& f, const std::vector<FeatureObservation>& fresh, double t);
  bool initializeLandmark(const FilterView& f, const FeatureObservation& obs, double inverse_depth_initial_m);

  std::unordered_map<std::int64_t, double> last_seen_;
  double scene_depth_hint_m_ = 0.0;  ///< see started(); 0: none
  DelayedLandmarks delayed_;
};

}  // namespace vi_ekf_slam
