// New tracks wait for a baseline before they become landmarks (landmark_triangulation.h).
//
// A track not in the map is attached to a clone of the camera position taken at an image where it
// is seen (one clone serves every track that starts within clone_interval_s). At each image, each
// waiting track is triangulated from its clone's view and the current one; it enters the map once
// its inverse depth is known to max_relative_depth_sigma of the scene's inverse depth, the baseline
// that makes it to max_relative_depth_sigma of itself, and its two rays meet (chi^2 gate). The
// scene's, not its own: a track is tried at every image, and a gate on
// its own noisy estimate lets each track in at the first image whose noise puts it near (small
// sigma(rho) / rho), so the map's points entered too near on average (half their distance on a slow
// start, with the velocity following them). sigma(rho) depends on the baseline and
// the rays' geometry, not on the pixel noise's draw, so that gate selects nothing. A track that
// has not got there after max_wait_s (a far point, a rotation in place) is forgotten and starts
// again on a newer clone. Waiting costs the filter those tracks' information: a map with fewer
// than min_map_landmarks (a start, a reset, a new scene) takes the longest waiting once they have
// waited starved_max_wait_s, with their two-view depth if it beats the prior, else at the prior
// depth (not while the zero-velocity rules hold new tracks back: fill 0). When the caller does not
// wait (a rig at rest), new tracks are handed back for the prior depth. Clones no track waits on
// leave the state.
#pragma once

#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

#include "vi_ekf_slam/core/landmark_triangulation.h"

namespace vi_ekf_slam {

struct TriangulationParams {
  bool enabled = true;  ///< new tracks wait for a baseline (else enter at the prior depth)
  /// A track enters once sigma(rho) is below this fraction of the scene's inverse depth (select())
  /// and the baseline's share of it below this fraction of rho.
  double max_relative_depth_sigma = 0.3;
  double clone_interval_s = 0.1;  ///< at most one clone of the camera position per this interval [s]
  double max_wait_s = 1.0;        ///< a track still waiting after this starts again on a newer clone [s]
  double min_depth_m = 0.1;       ///< a track triangulated nearer than this to a camera is a mismatch [m]
  /// Waiting leaves the filter without those tracks' information: a map with fewer landmarks than
  /// this (a start, a reset, a new scene) takes the longest waiting at the prior depth once they
  /// have waited starved_max_wait_s [s].
  int min_map_landmarks = 10;
  double starved_max_wait_s = 0.3;
};

/// Ids of clones in the state: far below any track's id (features with such ids are refused).
constexpr std::int64_t kFirstCloneId = std::numeric_limits<std::int64_t>::min();
inline bool isCloneId(std::int64_t id) { return id < kFirstCloneId + (std::int64_t{1} << 40); }

class DelayedLandmarks {
 public:
  struct Ready {
    FeatureObservation obs;
    std::int64_t clone_id;
    TriangulatedLandmark landmark;
  };
  struct Selection {
    std::vector<Ready> triangulated;          ///< can enter now
    std::vector<FeatureObservation> expired;  ///< not waiting, or taken by a short map: for the prior depth
    bool wait = true;                         ///< new tracks start waiting
  };

  /// Step 1, after the image's update: forgets the tracks not seen in `fresh` (the observations
  /// of tracks not in the map), triangulates the others, and says which can enter. pixel_var
  /// [px^2], gate_probability: the rays' gap test. wait = false: new tracks do not start waiting
  /// (they are expired at once); those already waiting go on. fill: a map short of this many
  /// landmarks: up to that many (less those triangulated) of those waiting longest, at least
  /// starved_max_wait_s, enter now: triangulated if their two views know the inverse depth better
  /// than prior_inverse_depth_sigma [1/m] (the prior of a new track), else expired (for the prior).
  /// scene_inverse_depth [1/m]: the scene's typical inverse depth (the filter's scene-depth prior),
  /// which max_relative_depth_sigma is relative to.
  Selection select(const FilterState& state, const std::vector<FeatureObservation>& fresh, const CameraModel& camera,
                   const CameraExtrinsics& T_b_c, const TriangulationParams& params, double pixel_var,
                   double gate_probability, bool wait, double scene_inverse_depth, int fill = 0,
                   double prior_inverse_depth_sigma = 0.0);
  /// Step 2: appends up to `capacity` of the selected landmarks (returns their ids), stops waiting
  /// for the expired ones, attaches the fresh tracks not yet waiting to a clone taken now (if the
  /// selection waits, the last clone is older than clone_interval_s and there is room), and
  /// removes unused clones.
  std::vector<std::int64_t> commit(FilterState& state, const Selection& selection,
                                   const std::vector<FeatureObservation>& fresh, int capacity,
                                   const CameraExtrinsics& T_b_c, const TriangulationParams& params);
  /// Before a composition: carries the clones' orientations into the new {s} and adds the
  /// relative rotation's variance they are carried through.
  void beforeComposition(const FilterState& state);
  /// Forgets every waiting track and clone, and removes the clones from `state` if given (not
  /// needed when the state is replaced).
  void clear(FilterState* state);

  int waitingTracks() const { return static_cast<int>(waiting_.size()); }
  int clones() const { return static_cast<int>(clones_.size()); }

 private:
  struct Waiting {
    std::int64_t clone_id;
    Eigen::Vector2d uv_clone;
  };
  const CameraClone* findClone(std::int64_t id) const;
  /// Forgets the clones `remove` picks, and takes them out of `state` if given.
  template <typename Pred>
  void removeClonesIf(FilterState* state, Pred remove);

  std::unordered_map<std::int64_t, Waiting> waiting_;
  std::vector<CameraClone> clones_;
  std::int64_t next_clone_id_ = kFirstCloneId;
};

}  // namespace vi_ekf_slam
