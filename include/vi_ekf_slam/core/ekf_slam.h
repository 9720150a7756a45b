// The estimator facade: an IMU buffer, the filter state, and the per-image sequence of the
// paper (propagate -> update -> new landmarks -> composition), for any mechanization.
// ROS-free; the ROS node, the simulator study and the tools all drive this class.
#pragma once

#include <optional>

#include <deque>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/dynamic_initializer.h"
#include "vi_ekf_slam/core/map_archive.h"
#include "vi_ekf_slam/core/map_memory.h"
#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/navigation_output.h"
#include "vi_ekf_slam/core/outlier_watch.h"
#include "vi_ekf_slam/core/types.h"

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
  int deferred_features = 0;                ///< new tracks kept out of the map: rig neither seen moving nor at rest
  int waiting_features = 0;                 ///< new tracks waiting for the baseline that triangulates them
  std::string lost;  ///< non-empty: the filter is lost (DivergenceMonitor) and should be reset; why
};

class EkfSlam {
 public:
  /// Throws std::invalid_argument with every problem if the configuration is impossible.
  EkfSlam(const EkfSlamConfig& config, const CameraModel& camera, const CameraExtrinsics& T_b_c);

  const EkfSlamConfig& config() const { return config_; }
  const CameraModel& camera() const { return camera_; }
  /// The camera-IMU extrinsic in use: the calibration, or its online estimate (estimate_extrinsic).
  const CameraExtrinsics& extrinsics() const { return state_.x.T_b_c; }
  /// The calibration the filter was given.
  const CameraExtrinsics& calibratedExtrinsics() const { return T_b_c_; }

  /// Starts the filter at a known pose, velocity and biases in {n} at initial.timestamp; the
  /// covariance comes from config().initial. IMU samples buffered so far are kept.
  void initialize(const NavState& initial);
  /// The same with another initial uncertainty (a dynamic initialization's) and, if > 0, the
  /// depth the scene was seen at [m]: new landmarks start there until the map knows its own.
  /// time_offset_s, if given, replaces camera_time_offset_s as the time offset's initial value.
  void initialize(const NavState& initial, const InitialUncertainty& uncertainty, double scene_depth_m = 0.0,
                  std::optional<double> time_offset_s = std::nullopt);
  /// Starts from a dynamic initialization: its state (or `registered`, the same moved to a known
  /// position and yaw), its uncertainty over config().initial, its time offset, and the features
  /// it aligned as landmarks at their depth, with their joint uncertainty (one scale error for
  /// all and the velocity). Returns the number of landmarks added.
  int initialize(const DynamicInitResult& aligned, const NavState& registered);
  bool initialized() const { return initialized_; }
  /// Forgets state, map and IMU buffer.
  void reset();

  /// Buffers one IMU sample. Returns false (and ignores it) if it is non-finite or not newer
  /// than the previous one.
  bool addImu(const ImuData& imu);
  /// Integrates the buffered IMU up to time t. False if the buffer does not reach t.
  bool propagateTo(double t);
  /// Latest buffered IMU time (or -inf).
  double latestImuTime() const;

  /// Propagates to the image time on the IMU clock (stamp + time offset estimate), updates with
  /// known landmarks, adds new ones and composes. frame.timestamp is on the camera clock.
  FrameResult processFrame(const CameraFrame& frame);
  /// A camera stamp on the IMU clock, with the current time offset estimate [s].
  double imuTime(double camera_stamp) const {
    return camera_stamp + (initialized_ ? state_.x.t_d : config_.camera_time_offset_s);
  }

  /// Applies a new configuration to the running filter: validates it (false and the problems in
  /// *error otherwise), converts the mechanization if it changed, and uses every other value
  /// from now on (new landmarks, next IMU samples, next update).
  bool setConfig(const EkfSlamConfig& config, std::string* error = nullptr);

  /// Converts the running filter to another mechanization, keeping the map.
  void setMechanization(Mechanization m);
  Mechanization mechanization() const { return state_.mechanization(); }

  NavState navState() const { return vi_ekf_slam::navState(state_); }
  /// The state propagated through the IMU samples buffered past it, to the latest one (an
  /// IMU-rate pose between images, with its covariance; the filter is not changed), and the
  /// bias-corrected angular rate there [rad/s]. Nothing before initialization.
  std::optional<NavState> predictedNavState(Vec3* angular_rate = nullptr) const;
  std::vector<NavLandmark> landmarks() const { return navLandmarks(state_); }
  const FilterState& state() const { return state_; }

  /// The landmarks worth keeping across a reset (map_archive.h): the well-mapped ones with an
  /// appearance, in {n} with their covariance.
  std::vector<MapPoint> mapPoints() const;
  /// Moves the filter's world: every {n} quantity x becomes T_new_old x (a rotation about z and a
  /// translation, so gravity stays along z), the covariance with it. A relocalization places the
  /// running filter in the kept map this way.
  void moveWorld(const Eigen::Isometry3d& T_new_old);

  int compositions() const { return compositions_; }
  /// The probability of the next update's chi^2 gate (OutlierWatch).
  double gateProbability() const { return outlier_watch_.gateProbability(config_.update); }
  int imuGaps() const { return imu_gaps_; }
  /// A sample not to be integrated as it is (clipped at the range or implausible, ImuSampleCheck):
  /// the propagation interpolates its neighbours over it and the covariance grows by what it could
  /// have hidden, its departure from the last good sample over its period. Later samples than the
  /// last buffered one only.
  void bridgeImu(const ImuData& imu);
  /// Zero-velocity updates applied since the start or the last reset (standing detected).
  int zeroVelocityUpdates() const { return zero_velocity_updates_; }

 private:
  // The steps of processFrame, in order.
  /// Whether the IMU showed the rig at rest over the still window before t (and drops the samples
  /// before that window).
  bool imuAtRestBefore(double t);
  /// Standing (no translation parallax): the zero-velocity update.
  void detectStanding(const CameraFrame& frame, bool at_rest, FrameResult* r);
  /// The latched "seen moving" that lets new tracks become landmarks.
  void updateSeenMoving(const FrameResult& r);
  /// Removes timed-out landmarks and, for `wanted` new ones, the longest unseen; returns their ids.
  std::vector<std::int64_t> makeRoomInTheMap(double t, int wanted);
  /// New landmarks from the fresh tracks (up to max_landmarks); returns their ids.
  std::vector<std::int64_t> addLandmarks(const std::vector<FeatureObservation>& fresh, double t);
  /// The same through the delayed entry: triangulated tracks, then the expired ones (not waiting,
  /// or taken by a short map) at the prior depth (unless `defer`). Fills new_ids, removed_ids and
  /// the counts of r.
  void addLandmarksDelayed(const std::vector<FeatureObservation>& fresh, double t, bool defer, FrameResult* r);
  /// A state of the configured layout with the calibrated extrinsic and nothing else.
  FilterState emptyState(Mechanization m) const;
  /// The world-centric starting state (its covariance the registration's and u's).
  FilterState startingState(const NavState& init, const InitialUncertainty& u,
                            std::optional<double> time_offset_s) const;
  /// Starts from s (world-centric, switched to the configured mechanization).
  void start(FilterState s, double scene_depth_m);
  /// New tracks wait for a baseline (config().triangulation, for inverse depth composed after every update).
  bool triangulationActive() const;

  void removeLandmarksById(const std::vector<std::int64_t>& ids);
  bool initializeLandmark(const FeatureObservation& obs, double inverse_depth_initial_m);
  /// Prior depth of new inverse-depth landmarks [m] (see inverse_depth_scene_prior).
  double newLandmarkDepth() const;
  /// The depth new landmarks' prior is centred on [m] and, where it is the map's median, that
  /// landmark's index (else -1).
  struct SceneDepth {
    double depth_m = 0.0;
    int landmark = -1;
  };
  SceneDepth sceneDepth() const;
  bool shouldCompose(int new_landmarks) const;
  /// The estimated speed exceeds zero_velocity.moving_speed_mps by two standard deviations.
  bool confidentlyMoving() const;
  void addGapUncertainty(FilterState& s, double dt) const;
  /// Propagates s to t through the buffered IMU samples (they must reach t).
  void integrateImu(FilterState& s, double t, Vec3* last_gyro) const;

  EkfSlamConfig config_;
  CameraModel camera_;
  CameraExtrinsics T_b_c_;
  Vec3 g_n_;
  FilterState state_;
  bool initialized_ = false;
  double scene_depth_hint_m_ = 0.0;  ///< see initialize(); 0: none
  std::deque<ImuData> imu_;
  std::deque<ImuData> recent_imu_;  ///< samples since the last frame's rest window (bounded by imu_buffer_max)
  std::unordered_map<std::int64_t, double> last_seen_;
  Vec3 last_gyro_ = Vec3::Zero();  ///< the angular rate [rad/s] (raw) of the last propagation step
  int compositions_ = 0;
  int imu_gaps_ = 0;
  /// A left-out sample: after the buffered one at t_before, over dt, hiding up to sigma_a / sigma_g.
  struct ImuBridge {
    double t_before, dt;
    Vec3 sigma_a, sigma_g;
  };
  std::deque<ImuBridge> bridges_;
  /// The bridges' uncertainty for the piece of [a, b] integrated (fraction of it).
  void addBridgeUncertainty(FilterState& s, double t_before, double fraction) const;
  /// Motion the IMU did not see: independent variances of position, velocity and attitude.
  static void addUnseenMotion(FilterState& s, const Vec3& var_p, const Vec3& var_v, const Vec3& var_psi);
  int zero_velocity_updates_ = 0;
  // Keeping the map (map_memory.h).
  std::unordered_map<std::int64_t, Descriptor> descriptors_;  ///< of landmarks in the state (their tracks' first)
  std::unordered_map<std::int64_t, Descriptor> latest_descriptors_;  ///< their latest views' (what mapPoints keeps)
  std::vector<MapPoint> left_the_state_;      ///< removed during the current frame (FrameResult::left_the_state)
  std::unordered_set<std::int64_t> dormant_;  ///< landmarks whose tracks ended, kept
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
  /// The pending matches' features of this image: each agreeing one counts an image, one that
  /// has agreed long enough moves to *known under its landmark's id (returned), one that does not
  /// agree is a new point (into *fresh, counted in *refused).
  std::vector<RevisitMatch> confirmRevisits(const std::vector<FeatureObservation>& pending,
                                            std::vector<FeatureObservation>* fresh,
                                            std::vector<FeatureObservation>* known, int* refused);
  /// Landmarks being tracked (clones included, dormant ones not).
  int trackedLandmarks() const { return state_.numLandmarks() - static_cast<int>(dormant_.size()); }
  /// The features of tracks that found a landmark again, under that landmark's id; new matches
  /// of fresh tracks to landmarks not observed in this image move from *fresh to *known.
  /// With frame.search, the front end also looks again where the other landmarks are expected and
  /// starts tracking the corners that are them (frame.adopt).
  std::vector<RevisitMatch> findRevisits(const CameraFrame& frame, std::vector<FeatureObservation>* fresh,
                                         std::vector<FeatureObservation>* known);
  /// Forgets the tracks of revisiting_ that no longer appear in the frame.
  void forgetEndedRevisits(const CameraFrame& frame, const std::vector<RevisitMatch>& started);
  /// Forgets descriptors, dormancy and revisiting tracks (a new start).
  void forgetMap();
  /// Landmark i (map position) is known well enough to be kept and found again: its position's
  /// std-dev (root of the covariance's trace) within map.max_relative_sigma of its distance.
  bool wellMapped(int i) const;
  /// Landmark i's position (in {s}) and the trace of its covariance [m^2].
  std::pair<Vec3, double> landmarkPositionVariance(int i) const;
  /// Keeps the first descriptor of every observed landmark (what revisits match) and its latest
  /// view's (what the map kept across resets holds).
  void rememberAppearance(const std::vector<FeatureObservation>& observed);
  /// Landmarks leaving the tracked map: dormant (keep_map and a descriptor) or dropped (into *drop);
  /// then dormant ones are dropped (retire's rule) until `wanted` new ones fit in max_landmarks and
  /// at most map.max_dormant are left.
  void retire(const std::vector<std::int64_t>& leaving, int wanted, std::vector<std::int64_t>* drop);
  StationaryDetector stationary_;
  DivergenceMonitor divergence_;
  OutlierWatch outlier_watch_;
  DelayedLandmarks delayed_;
  bool seen_moving_ = false;  ///< parallax reached moving_parallax_px since the last stand (or start)
};

}  // namespace vi_ekf_slam
