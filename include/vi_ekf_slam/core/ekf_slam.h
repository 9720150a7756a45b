// The estimator: the filter state and the per-image sequence of the paper (propagate -> update ->
// new landmarks -> composition), for any mechanization, as OpenVINS's VioManager is its own. The
// parts it sequences have their own files: the IMU between images (imu_buffer.h), the start
// (filter_start.h), the map's membership (landmark_manager.h), finding landmarks again within a
// run (map_reuse/within_run_map.h), the update (ekf_update.h), the frame changes (frame_change.h).
// ROS-free; the ROS node, the simulator study and the tools all drive this class.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/blind_motion_prior.h"
#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"
#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/frame_result.h"
#include "vi_ekf_slam/core/imu_buffer.h"
#include "vi_ekf_slam/core/landmark_manager.h"
#include "vi_ekf_slam/core/map_reuse/within_run_map.h"
#include "vi_ekf_slam/core/navigation_output.h"
#include "vi_ekf_slam/core/outlier_watch.h"
#include "vi_ekf_slam/core/types.h"
#include "vi_ekf_slam/core/velocity_reanchor.h"

namespace vi_ekf_slam {

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
  double latestImuTime() const { return imu_.latestTime(); }

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

  /// The landmarks worth keeping across a reset (map_reuse/kept_map.h): the well-mapped ones with an
  /// appearance, in {n} with their covariance.
  std::vector<MapPoint> mapPoints() const;
  /// Moves the filter's world: every {n} quantity x becomes T_new_old x (a rotation about z and a
  /// translation, so gravity stays along z), the covariance with it. A relocalization places the
  /// running filter in the kept map this way.
  void moveWorld(const Eigen::Isometry3d& T_new_old);

  int compositions() const { return compositions_; }
  /// The probability of the next update's chi^2 gate (OutlierWatch).
  double gateProbability() const { return outlier_watch_.gateProbability(config_.update); }
  int imuGaps() const { return imu_.gaps(); }
  /// A sample not to be integrated as it is (clipped at the range or implausible, ImuSampleCheck):
  /// the propagation interpolates its neighbours over it and the covariance grows by what it could
  /// have hidden, its departure from the last good sample over its period. Later samples than the
  /// last buffered one only.
  void bridgeImu(const ImuData& imu) { imu_.bridge(imu); }
  /// Zero-velocity updates applied since the start or the last reset (standing detected).
  int zeroVelocityUpdates() const { return zero_velocity_updates_; }

  /// The first image of the current blind stretch (no usable feature) [s, IMU clock]; none while the camera sees.
  std::optional<double> blindSince() const { return blind_since_; }
  /// How long the current blind stretch has lasted at the state's time [s]; 0 while the camera sees.
  double blindFor() const { return blind_since_ ? std::max(0.0, state_.timestamp - *blind_since_) : 0.0; }
  /// While held, new tracks do not become landmarks (their tracks go on and enter once released):
  /// after a blind stretch, until the velocity is re-anchored (VioPipeline, velocity_reanchor.h).
  void holdNewLandmarks(bool hold) { hold_new_landmarks_ = hold; }
  /// Corrects the state by the body's velocity as an alignment of the last frames measured it
  /// (bodyVelocityUpdate), gated at the update's gate probability.
  KalmanUpdateResult updateBodyVelocity(const BodyVelocity& m) {
    return bodyVelocityUpdate(state_, m, gateProbability());
  }

 private:
  // The steps of processFrame besides its parts' (imu_, landmarks_, map_), in order.
  /// Standing (no translation parallax): the zero-velocity update.
  void detectStanding(const CameraFrame& frame, bool at_rest, FrameResult* r);
  /// A blind stretch begins: the accelerometer bias's variance is raised to at least its prior's.
  void knowAccelBiasAsAtStart();
  /// The motion prior: learned where the images constrained the velocity, applied where none did.
  void boundBlindVelocity(FrameResult* r);
  /// The latched "seen moving" that lets new tracks become landmarks.
  void updateSeenMoving(const FrameResult& r);
  bool shouldCompose(int new_landmarks) const;
  /// The estimated speed exceeds zero_velocity.moving_speed_mps by two standard deviations.
  bool confidentlyMoving() const;
  /// Starts from s (world-centric, switched to the configured mechanization).
  void start(FilterState s, double scene_depth_m);
  /// Forgets what a run of the filter knows besides its state and the IMU: the one path of a
  /// start and a reset.
  void forgetRun();
  /// The state, camera and configuration its parts work on at this image.
  FilterView view();

  EkfSlamConfig config_;
  CameraModel camera_;
  CameraExtrinsics T_b_c_;
  FilterState state_;
  ImuBuffer imu_;              ///< the IMU between images and the propagation through it
  LandmarkManager landmarks_;  ///< which tracks enter the map and which leave
  WithinRunMap map_;           ///< keep_map: dormant landmarks found again
  bool initialized_ = false;
  int compositions_ = 0;
  int zero_velocity_updates_ = 0;
  StationaryDetector stationary_;
  DivergenceMonitor divergence_;
  OutlierWatch outlier_watch_;
  bool seen_moving_ = false;           ///< parallax reached moving_parallax_px since the last stand (or start)
  std::optional<double> blind_since_;  ///< the first image of the current blind stretch [s]
  bool hold_new_landmarks_ = false;
  BlindMotionPrior motion_prior_;  ///< the body-frame velocity of the seconds of sight, for the blind ones
};

}  // namespace vi_ekf_slam
