// What the filter did with one image (EkfSlam::processFrame): the update, the landmarks that
// entered and left, the revisits, the standing test, the composition, and whether it is lost.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/ekf_update.h"
#include "vi_ekf_slam/core/map_reuse/kept_map.h"
#include "vi_ekf_slam/core/map_reuse/revisit_matching.h"
#include "vi_ekf_slam/core/zero_velocity.h"

namespace vi_ekf_slam {

struct FrameResult {
  bool processed = false;
  std::string error;  ///< why the frame was not processed
  UpdateResult update;
  double gate_probability = 0.0;  ///< of the update's chi^2 gate (OutlierWatch: narrow while the tracks show outliers)
  std::vector<std::int64_t> new_ids;
  int new_triangulated = 0;  ///< of new_ids, those triangulated (the others entered at the prior depth)
  std::vector<std::int64_t> removed_ids;
  /// Keeping the map: landmarks whose tracks had ended, observed again through a new track (the
  /// update accepted them) and those the update's gate refused (a false match).
  std::vector<RevisitMatch> revisits;
  int revisits_rejected = 0;
  int dormant_landmarks = 0;  ///< after this frame
  /// Well-mapped landmarks with an appearance that left the state with this frame (room for new
  /// ones), in {n}: the map kept across resets takes them (map_relocalize).
  std::vector<MapPoint> left_the_state;
  bool composed = false;
  StationaryDetector::Decision stationary;  ///< the standing test of this frame
  bool zero_velocity_applied = false;       ///< stationary and the zero-velocity update passed its gate
  bool imu_at_rest = false;                 ///< the IMU's rest test over the still window before the frame
  /// New tracks kept out of the map: the rig neither seen moving nor at rest, or held (holdNewLandmarks).
  int deferred_features = 0;
  int waiting_features = 0;  ///< new tracks waiting for the baseline that triangulates them
  std::string lost;          ///< non-empty: the filter is lost (DivergenceMonitor) and should be reset; why
  /// A blind stretch (no usable feature in the image: a covered lens, darkness, smoke): the time
  /// of its first image [s, IMU clock]. The filter propagates on the IMU.
  std::optional<double> blind_since;
  double blind_s = 0.0;        ///< how long the stretch has lasted at this image [s] (0 at its first and while seeing)
  bool blind_started = false;  ///< this image is the stretch's first
  /// The first image with features after a blind stretch: how long it lasted [s] (0: none ended).
  double blind_ended_after_s = 0.0;
  /// No observation constrained the velocity at this image and the motion prior of the seconds of
  /// sight before (blind_motion_prior.h) was applied.
  bool motion_prior_applied = false;
};

}  // namespace vi_ekf_slam
