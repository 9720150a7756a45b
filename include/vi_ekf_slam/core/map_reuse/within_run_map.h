// Keeping the map within a run (keep_map): a landmark whose track ended stays in the state as
// *dormant* (its correlation with the pose is what corrects the pose when the place is seen again),
// and a new track, or a corner the front end finds where the filter predicts the landmark, that is
// the same point by its appearance observes it again (revisit_matching.h). This class holds what
// that needs besides the state: the landmarks' appearance, which are dormant, which tracks are
// revisits, the matches still to be confirmed, and the well-mapped points leaving the state (the
// map kept across runs takes them: kept_map.h). EkfSlam calls it at the steps of its per-image
// sequence.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/ekf_update.h"
#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/map_reuse/kept_map.h"
#include "vi_ekf_slam/core/map_reuse/revisit_matching.h"
#include "vi_ekf_slam/core/navigation_output.h"

namespace vi_ekf_slam {

/// What the filter's parts work on at one image: the state, the camera and the configuration, and
/// the body's angular rate (bias-corrected, [rad/s]) for the rolling-shutter predictions.
struct FilterView {
  FilterState& state;
  const CameraModel& camera;
  const EkfSlamConfig& config;
  Vec3 omega_b = Vec3::Zero();
};

class WithinRunMap {
 public:
  /// Forgets appearance, dormancy, revisiting and pending tracks (a new start or a reset).
  void clear();

  /// The track is a match waiting for its confirmation (its features observe nothing yet).
  bool pending(std::int64_t track_id) const { return pending_.count(track_id) > 0; }
  /// The landmark a track observes: the one it found again, else the track's own id.
  std::int64_t landmarkOf(std::int64_t track_id) const {
    const auto a = revisiting_.find(track_id);
    return a != revisiting_.end() && a->second != kNotRevisit ? a->second : track_id;
  }

  /// The pending matches' features of this image: each agreeing one counts an image, one that
  /// has agreed long enough moves to *known under its landmark's id (returned), one that does not
  /// agree is a new point (into *fresh, counted in *refused). gate_probability: the update's.
  std::vector<RevisitMatch> confirm(const FilterView& f, const std::vector<FeatureObservation>& pending,
                                    double gate_probability, std::vector<FeatureObservation>* fresh,
                                    std::vector<FeatureObservation>* known, int* refused);
  /// The features of new tracks that found a landmark again, under that landmark's id: they move
  /// from *fresh to *known. With frame.search, the front end also looks again where the other
  /// landmarks are expected and starts tracking the corners that are them (frame.adopt).
  std::vector<RevisitMatch> find(const FilterView& f, const CameraFrame& frame, std::vector<FeatureObservation>* fresh,
                                 std::vector<FeatureObservation>* known);
  /// After the update: a revisit its gate refused was a false match (its track is a new point from
  /// now on, the landmark stays dormant: into *refused_landmarks, counted in *refused_count); the
  /// others are returned as accepted.
  std::vector<RevisitMatch> settle(const std::vector<RevisitMatch>& revisits, const UpdateResult& update,
                                   std::unordered_set<std::int64_t>* refused_landmarks, int* refused_count);
  /// The landmark was observed: it is tracked again, no longer dormant (nor a consider state).
  void observed(FilterState& state, std::int64_t landmark_id);
  /// Keeps the first descriptor of every observed landmark (what revisits match) and its latest
  /// view's (what the map kept across runs holds).
  void rememberAppearance(const FilterState& state, const std::vector<FeatureObservation>& observed);
  /// Forgets the revisiting and pending tracks that no longer appear in the frame (`started`:
  /// adopted in this image, seen from the next on).
  void forgetEndedTracks(const FilterState& state, const CameraFrame& frame, const std::vector<RevisitMatch>& started);

  /// Landmarks leaving the tracked map: dormant (keep_map, an appearance, well mapped) or dropped
  /// (into *drop); then dormant ones are dropped, the most crowded place first, until `wanted` new
  /// ones fit in max_landmarks and at most map.max_dormant are left.
  void retire(const FilterView& f, const std::vector<std::int64_t>& leaving, int wanted,
              std::vector<std::int64_t>* drop);
  /// The landmarks are about to leave the state: their well-mapped points with an appearance go to
  /// leftTheState() (when the map is kept across runs), the rest of what is known of them is
  /// forgotten.
  void removing(const FilterView& f, const std::vector<std::int64_t>& ids);
  /// The points removing() kept since the last call.
  std::vector<MapPoint> takeLeftTheState();

  bool dormant(std::int64_t landmark_id) const { return dormant_.count(landmark_id) > 0; }
  int dormantCount() const { return static_cast<int>(dormant_.size()); }
  /// The landmarks worth keeping across a reset: the well-mapped ones with an appearance, in {n}
  /// with their covariance.
  std::vector<MapPoint> mapPoints(const FilterState& state, const EkfSlamConfig& config) const;

  /// Landmark i (map position) is known well enough to be kept and found again: its position's
  /// std-dev (root of the covariance's trace) within map.max_relative_sigma of its distance.
  static bool wellMapped(const FilterState& state, int i, const MapReuseParams& params);
  /// Landmark i's position (in {s}) and the trace of its covariance [m^2].
  static std::pair<Vec3, double> positionVariance(const FilterState& state, int i);

 private:
  std::unordered_map<std::int64_t, Descriptor> descriptors_;  ///< of landmarks in the state (their tracks' first)
  std::unordered_map<std::int64_t, Descriptor> latest_descriptors_;  ///< their latest views' (what mapPoints keeps)
  std::vector<MapPoint> left_the_state_;                             ///< see removing()
  std::unordered_set<std::int64_t> dormant_;                         ///< landmarks whose tracks ended, kept
  /// A track that found a landmark again -> that landmark; kNotRevisit: its match was refused by the
  /// update's gate, it is a new point (a track is matched once).
  std::unordered_map<std::int64_t, std::int64_t> revisiting_;
  static constexpr std::int64_t kNotRevisit = -1;
  /// A match not yet believed: its track must go on landing where the filter predicts the landmark
  /// for map.revisit_confirm_frames images (a look-alike at another depth drifts off the
  /// prediction as the camera moves: its innovation changes beyond pixel noise, while the true
  /// point's keeps the filter's error of the moment). Until then the track observes nothing.
  struct PendingRevisit {
    std::int64_t landmark_id = 0;
    int distance = 0;                                            ///< of the match [bits]
    int frames = 0;                                              ///< images it has agreed in
    Eigen::Vector2d first_innovation = Eigen::Vector2d::Zero();  ///< in the image it was found in [px]
    double found_t = 0.0;                                        ///< that image's time [s]
  };
  std::unordered_map<std::int64_t, PendingRevisit> pending_;  ///< by track id
};

}  // namespace vi_ekf_slam
