// Simulated feature observations: projections of the visible landmarks with Gaussian pixel
// noise. Data association is perfect along a track; a landmark tracked again after its track
// ended gets a new track id, as a KLT tracker gives a corner it finds again a new id.
#pragma once

#include <optional>
#include <random>
#include <unordered_map>

#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/types.h"
#include "vi_ekf_slam/sim/landmark_world.h"
#include "vi_ekf_slam/sim/trajectory.h"

namespace vi_ekf_slam::sim {

/// The appearance a simulated tracker gives a new track (an ORB descriptor's 256 bits): its
/// landmark's pattern with bits flipped by the view (a function of the viewing direction and
/// distance, the same for every detection from one view), so that a point seen again from another
/// angle or distance does not always match while two detections from one place do, plus each
/// detection's own noise. The randomness is the landmark's and the track's own (the pixel noise and
/// everything else is unchanged by it).
struct DescriptorSimParams {
  bool enabled = true;
  double same_view_bits = 12.0;      ///< mean bits differing between two detections from the same view [bits]
  double bits_per_rad = 110.0;       ///< more per radian between the viewing directions [bits/rad]
  double bits_per_log_scale = 60.0;  ///< more per unit of |ln(distance_1 / distance_2)| [bits]
  /// A front end that looks again where the filter expects a landmark finds its corner with this
  /// probability (detection is not perfectly repeatable) [probability].
  double redetect_probability = 0.8;
  /// Repeated texture: 0, every landmark looks different; N > 0, landmark i has pattern i mod N
  /// (N patterns repeated over the world, a corridor of identical doors) [count].
  int texture_patterns = 0;
};

/// The pattern of landmark index i (256 random bits, a function of the pattern's number).
Descriptor landmarkPattern(std::int64_t landmark, const DescriptorSimParams& params);

struct CameraSimParams {
  double rate_hz = 28.0;
  double pixel_noise_px = 1.0;  ///< std-dev of the Gaussian pixel noise [px]
  double max_range_m = 20.0;
  double min_depth_m = 0.3;
  double border_px = 2.0;
  int max_features = 40;  ///< tracks kept per image, like a tracker's target count
  int grid_cols = 4;      ///< new tracks are spread over a grid, like a tracker's detector
  int grid_rows = 3;
  /// Camera-IMU clock offset of the simulated rig [s]: a frame taken at true (IMU) time t is
  /// stamped t - time_offset_s, so t_imu = t_image + time_offset_s.
  double time_offset_s = 0.0;
  DescriptorSimParams descriptors;
};

/// Noise-free projections of every landmark of `world` visible from the body pose at `sample`
/// (in front of the camera, inside the image, within range).
std::vector<FeatureObservation> visibleLandmarks(const TrajectorySample& sample, const LandmarkWorld& world,
                                                 const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                                 const CameraSimParams& params);

/// The id of the k-th track (k = 0, 1, ...) of the landmark with index `landmark` in a world of
/// `world_size` landmarks: the landmark's index the first time (its id too, in the worlds built
/// here), landmark + k * world_size after, so a track's landmark is found again without a table
/// (landmarkOfTrack).
std::int64_t trackId(std::int64_t landmark, std::int64_t k, size_t world_size);
/// The world landmark a track id of trackId() belongs to.
const WorldLandmark& landmarkOfTrack(std::int64_t track_id, const LandmarkWorld& world);

/// A simulated front end: keeps following its tracks while they stay visible and starts new ones
/// in the emptiest grid cells up to max_features, then adds pixel noise. A track that ends is
/// never continued: if its landmark is picked again, that is a new track with a new id (trackId),
/// so the estimator cannot re-identify a point that left the view, as with a real KLT front end.
/// Deterministic for a given trajectory and random generator.
class TrackingCamera {
 public:
  TrackingCamera(const LandmarkWorld& world, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                 const CameraSimParams& params);
  /// The features of the frame taken at `sample`; FeatureObservation::id is the track id.
  CameraFrame observe(const TrajectorySample& sample, std::mt19937_64* rng);
  /// Ends every track (an image with nothing to follow, e.g. a covered lens).
  void loseTracks() { tracked_.clear(); }
  /// A landmark's (index into the world) appearance seen from the camera at p_n_c; `salt` makes
  /// the detection's own noise (a track's number, or an image's for a search).
  std::optional<Descriptor> describe(std::int64_t landmark, std::uint64_t salt, const Vec3& p_n_c) const;

 private:
  struct Track {
    std::int64_t landmark;                        ///< index into the world
    std::int64_t id;                              ///< the track id the estimator sees
    std::optional<Descriptor> descriptor;         ///< where it was detected
    std::optional<Descriptor> latest_descriptor;  ///< described again every kDescribeEveryFrames
  };
  /// CameraFrame::search and adopt for the frame just observed: the visible landmarks that are not
  /// tracked (index, noisy pixel), found inside a region with redetect_probability.
  void offerSearch(CameraFrame* frame, std::vector<std::pair<std::int64_t, Eigen::Vector2d>> untracked,
                   const Vec3& p_n_c);
  std::uint64_t frames_ = 0;  ///< images observed (a search's draws depend on it)
  const LandmarkWorld& world_;
  CameraModel camera_;
  CameraExtrinsics T_b_c_;
  CameraSimParams params_;
  std::unordered_map<std::int64_t, size_t> index_of_;  ///< world id -> index in the world
  std::vector<Track> tracked_;
  std::unordered_map<std::int64_t, std::int64_t> tracks_started_;  ///< per landmark index
};

}  // namespace vi_ekf_slam::sim
