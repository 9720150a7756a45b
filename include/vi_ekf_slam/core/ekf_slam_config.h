// Every setting of the estimator, with units in the names or comments, and its validation.
#pragma once

#include <optional>
#include <string>

#include "vi_ekf_slam/core/map_reuse/map_reuse_params.h"
#include "vi_ekf_slam/core/imu_sample_check.h"
#include "vi_ekf_slam/core/delayed_landmarks.h"
#include "vi_ekf_slam/core/divergence_monitor.h"
#include "vi_ekf_slam/core/ekf_update.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/landmark_initialization.h"
#include "vi_ekf_slam/core/state_layout.h"
#include "vi_ekf_slam/core/blind_motion_prior.h"
#include "vi_ekf_slam/core/zero_velocity.h"

namespace vi_ekf_slam {

/// When the composition step runs (sensor_centric_composition only).
enum class CompositionTrigger {
  kNewLandmarks,  ///< paper: when more than `composition_new_landmarks` were added in one update
  kEveryUpdate,   ///< after every image
  kNever,
};
std::string toString(CompositionTrigger t);

/// How a new landmark enters the state.
enum class LandmarkInitMethod {
  kFixedDepth,    ///< paper: Cartesian point at a fixed depth along the first ray
  kInverseDepth,  ///< anchored inverse depth with a wide prior on rho (beyond the paper)
};
std::optional<LandmarkInitMethod> landmarkInitFromString(const std::string& s);
std::string toString(LandmarkInitMethod m);

/// Initial standard deviations. World-centric: they describe the registration error of the
/// body pose in {n}. Sensor-centric: the body pose in {s} is exact (zero), the same numbers go
/// to p_n_s and q_n_s.
struct InitialUncertainty {
  double position_m = 0.05;
  double velocity_mps = 0.05;
  double roll_pitch_rad = 0.0175;  ///< ~1 deg
  double yaw_rad = 0.035;          ///< ~2 deg
  double accel_bias_mps2 = 0.05;
  double gyro_bias_radps = 0.002;
  /// Camera-IMU time offset [s]; 0 keeps camera_time_offset_s fixed. A rig whose camera and
  /// IMU share no hardware clock is off by tens of ms (the hand-held RealSense: 47 ms).
  double time_offset_s = 0.05;
  /// Camera-IMU extrinsic (EkfSlamConfig::estimate_extrinsic): a transform measured with a ruler
  /// is off by a few degrees and centimetres.
  double extrinsic_rotation_rad = 0.05;   ///< ~3 deg
  double extrinsic_translation_m = 0.03;  ///< per axis
  /// The velocity is known relative to the heading (a dynamic initialization's, whose yaw is
  /// arbitrary): its error in {n} then includes the yaw error's rotation of it, v x yaw_rad.
  /// Without that correlation vision would "observe" the yaw from the velocity.
  bool velocity_relative_to_heading = false;
  /// If given, the covariance of [v_n_b (3), psi (3), b_a (3)] that replaces the diagonal ones
  /// above (an initializer's, with its correlations); the yaw's variance stays yaw_rad^2.
  std::optional<Eigen::Matrix<double, 9, 9>> velocity_attitude_accel_bias;
};

/// Defaults are the most consistent configuration of the study (README): sensor-centric with
/// the composition after every update and anchored inverse-depth landmarks. The paper's setup is
/// composition_trigger = kNewLandmarks and landmark_init = kFixedDepth.
struct EkfSlamConfig {
  Mechanization mechanization = Mechanization::kSensorCentricComposition;
  CompositionTrigger composition_trigger = CompositionTrigger::kEveryUpdate;
  int composition_new_landmarks = 4;  ///< compose when MORE than this many are new (paper: 4)
  /// The composition keeps the second-order term of an inverse-depth landmark's depth error times
  /// the pose error (compositionSecondOrderTerm in frame_change.h). Off: the paper's first order.
  /// In the simulator it brings the slow start (crawl) into the NEES band and changes nothing
  /// elsewhere; on the real hand-held recording it is worse, so it is off.
  bool composition_second_order = false;
  ImuNoiseParams imu_noise;
  double gravity_mps2 = 9.81;  ///< local gravity magnitude [m/s^2]
  /// Camera-IMU time offset at the start [s]: t_imu = t_image + t_d. Estimated online from here
  /// when initial.time_offset_s > 0.
  double camera_time_offset_s = 0.0;
  /// Estimate the camera-IMU extrinsic online (rotation and translation in the state, OpenVINS's
  /// calib_cam_extrinsics), from the given one with initial.extrinsic_* as its std-devs.
  bool estimate_extrinsic = false;
  UpdateParams update;  ///< pixel noise [px] and chi^2 gate probability
  LandmarkInitMethod landmark_init = LandmarkInitMethod::kInverseDepth;
  double landmark_depth_m = 8.0;         ///< fixed depth of new landmarks [m]
  double landmark_depth_sigma_m = 4.0;   ///< std-dev along the ray [m]
  double inverse_depth_initial_m = 5.0;  ///< inverse depth: prior depth 1/rho0 [m]
  /// inverse depth: prior std-dev of rho [1/m]. 0.5 (with 5 m) puts 95% of the prior between 0.8 m
  /// and infinity: a hand-held rig sees desks and beds at 1 m, and a point outside the prior is
  /// gated out once its parallax shows (0.3 made every mechanization diverge in a bedroom).
  double inverse_depth_sigma = 0.5;
  /// inverse depth: centre the prior of new landmarks at the median depth of the landmarks the
  /// camera sees whose depth the images already determined (inverse-depth sigma below half the
  /// prior's, at least 10 of them), instead of inverse_depth_initial_m (as ROVIO does). Sigma is
  /// unchanged. A bedroom's points at 0.5-2 m are then inside their own prior; a hallway's stay
  /// near its median depth. The new points' inverse depths are tied to the median point's, so they
  /// move with the map's scale instead of repeating it (initializeLandmarksAtMapDepth).
  bool inverse_depth_scene_prior = true;
  /// inverse depth, composition after every update: new tracks wait for the baseline that
  /// triangulates them (delayed_landmarks.h) instead of entering at the prior depth at once.
  TriangulationParams triangulation;
  int max_landmarks = 150;  ///< map size bound, dormant landmarks included (tracked ones take precedence) [count]
  /// Landmarks not observed for this long leave the tracked map [s] (<0: never): dormant while
  /// map.within_run and they have a descriptor, otherwise dropped.
  double landmark_timeout_s = 0.5;
  MapReuseParams map;          ///< map reuse within a run and across runs (map_reuse/)
  double max_imu_gap_s = 0.1;  ///< IMU intervals longer than this are gaps [s]
  /// Over a gap the IMU is interpolated, and the motion it missed enters as uncertainty: an
  /// unknown acceleration and angular rate with these std-devs (a walking torso: ~3 m/s^2, 0.3 rad/s).
  double imu_gap_accel_sigma_mps2 = 3.0;
  double imu_gap_gyro_sigma_radps = 0.3;
  int imu_buffer_max = 4000;         ///< bound on buffered IMU samples
  ImuCheckParams imu_check;          ///< samples clipped at the range or implausible: bridged
  ZeroVelocityParams zero_velocity;  ///< standing detection from parallax + zero-velocity update
  /// While no image constrains the velocity: the body-frame velocity as the seconds of sight showed it
  BlindMotionPriorParams blind_motion;
  InitialUncertainty initial;
  DivergenceParams divergence;  ///< when the filter counts as lost (FrameResult::lost)

  /// Empty if every value is possible, otherwise one line per problem.
  std::string validate() const;
};

}  // namespace vi_ekf_slam
