// Initialization while moving (visual-inertial alignment): from a short window of IMU samples
// and feature tracks, the velocity, the gravity vector, the accelerometer bias and every
// feature's position in the first body frame {I0} (as OpenVINS's dynamic initializer and
// Martinelli's closed-form solution). With the attitude from the gyro and the IMU's position
// increments alpha_k (A_k = d alpha_k / d b_a), the camera at frame k sees feature f at
//   p_c = R_c_k (p_f - v_0 t_k - g t_k^2 / 2 - alpha_k - A_k b_a) - R_b_c^T p_b_c.
// The stages, each in core/dynamic_init/: track selection, IMU preintegration, the alignment problem
// (linear solution, then refinement on the reprojection error), the camera-IMU time-offset
// search, and the uncertainty.
// The covariance of the solution (features eliminated) gives the initial uncertainty of velocity,
// roll/pitch and accelerometer bias with their correlations; when the velocity or the tilt is
// known too poorly (the rig rotates in place, moves at constant velocity, or sees too little
// parallax) it waits and says why.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/dynamic_init/preintegration.h"
#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/navigation_output.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct DynamicInitParams {
  double window_s = 1.0;  ///< span of the frames used [s]
  /// When that window's motion is too little (degenerate), the frames of up to this span are
  /// aligned once they span 10% more [s] (no longer window when <= window_s)
  double max_window_s = 2.0;
  int min_frames = 6;        ///< frames in the window [count]
  int min_features = 12;     ///< features seen in >= min_observations frames [count]
  int min_observations = 4;  ///< frames a feature must be seen in to be used [count]
  /// Refuse when the velocity is known worse than this [m/s]: the near-degenerate windows (turning
  /// in place, constant velocity) whose linearized covariance is not to be trusted. A start with
  /// an honest 0.2-0.3 m/s is consistent and the filter sharpens it within seconds.
  double max_velocity_sigma_mps = 0.3;
  double max_tilt_sigma_rad = 0.035;  ///< refuse when roll/pitch is known worse than this [rad]
  /// Refuse when the scene's scale (the mean inverse depth of the last frame's features, with the
  /// error they share) is known worse than this fraction of itself [ratio]: a slow motion (a hand
  /// at 0.1 m/s) whose velocity sigma passes the absolute bound but leaves the depths unknown.
  double max_scale_sigma = 0.5;
  double gyro_bias_sigma_radps = 0.01;  ///< initial std-dev of the (unknown) gyro bias [rad/s]
  /// std-dev of the (unknown) accelerometer bias [m/s^2]; set from the filter's prior
  double accel_bias_sigma_mps2 = 0.05;
  double time_offset_sigma_s = 0.05;  ///< std-dev of the camera-IMU time offset it assumes [s]
  /// The frames' clock is searched for the best alignment within +- this [s] (0: taken as given).
  double time_offset_search_s = 0.1;
  double pixel_noise_px = 1.0;  ///< std-dev of a feature position [px]
  double gravity_mps2 = 9.81;   ///< local gravity [m/s^2]
  std::string validate() const;
};

/// `p` told what the filter's configuration already says: pixel noise, the priors of the time
/// offset and of the accelerometer bias, and gravity (one source for each).
DynamicInitParams withFilterSettings(DynamicInitParams p, const EkfSlamConfig& filter);

/// A feature of the last frame as the alignment placed it: the filter starts with it as a landmark.
struct DynamicInitLandmark {
  std::int64_t id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< its pixel in the last frame
  double depth_m = 0.0;                          ///< its depth in the last camera frame [m]
  double inverse_depth_sigma = 0.0;              ///< std-dev of 1 / depth (its marginal) [1/m]
};

struct DynamicInitResult {
  NavState state;  ///< at the last frame of the window (p = 0, yaw = 0), on the IMU clock
  /// What the frames' stamps were off on the IMU clock [s]: add it to the time offset they used.
  double time_offset_correction_s = 0.0;
  double velocity_sigma_mps = 0.0;     ///< std-dev of the velocity (largest axis) [m/s]
  double tilt_sigma_rad = 0.0;         ///< std-dev of roll and pitch (largest) [rad]
  double gyro_bias_sigma_radps = 0.0;  ///< the gyro bias is not estimated: its prior std-dev [rad/s]
  double accel_bias_sigma_mps2 = 0.0;  ///< std-dev of the accelerometer bias (largest axis) [m/s^2]
  /// Covariance of [v_n_b (3), psi (3, R_true = Exp(psi) R_est in {n}; yaw row and column zero:
  /// the heading is not known), b_a (3)], with their correlations (a tilt and a bias across
  /// gravity explain the same specific force).
  Eigen::Matrix<double, 9, 9> covariance = Eigen::Matrix<double, 9, 9>::Zero();
  /// `base` with this result's uncertainty: the covariance above and the gyro bias's prior; the
  /// position, yaw and time offset keep base's.
  InitialUncertainty uncertainty(InitialUncertainty base) const {
    base.velocity_mps = velocity_sigma_mps;
    base.roll_pitch_rad = tilt_sigma_rad;
    base.accel_bias_mps2 = accel_bias_sigma_mps2;
    base.gyro_bias_radps = gyro_bias_sigma_radps;
    base.velocity_relative_to_heading = true;
    base.velocity_attitude_accel_bias = covariance;
    return base;
  }
  int frames = 0;    ///< frames used
  int features = 0;  ///< features used
  /// of the features in the last frame whose depth it knows to 50%; 0 (unknown) with fewer than 3
  double median_depth_m = 0.0;
  double residual_rms_px = 0.0;  ///< of the alignment
  /// relative std-dev of the mean inverse depth of `landmarks` (the scene's scale) [ratio]
  double scale_sigma = 0.0;
  std::vector<DynamicInitLandmark> landmarks;
  /// The landmarks' inverse depths are not known independently: one error of the window's
  /// velocity, gravity and bias (its scale) moves every depth and the velocity together. Their
  /// joint covariance [1/m^2] (order of `landmarks`; the diagonal is their inverse_depth_sigma^2)
  /// and their cross-covariance with [v_n_b, psi, b_a] of `covariance` (one row per landmark).
  Eigen::MatrixXd landmark_covariance;
  Eigen::Matrix<double, Eigen::Dynamic, 9> landmark_state_covariance;
  /// The gyro bias is not estimated, only considered (its prior gyro_bias_sigma_radps): the
  /// cross-covariance of [v_n_b, psi, b_a] (rows) and of the landmarks' inverse depths (one row
  /// per landmark) with it [., rad/s].
  Eigen::Matrix<double, 9, 3> gyro_bias_covariance = Eigen::Matrix<double, 9, 3>::Zero();
  Eigen::Matrix<double, Eigen::Dynamic, 3> landmark_gyro_bias_covariance;
};

class DynamicInitializer {
 public:
  DynamicInitializer(const DynamicInitParams& params, const CameraModel& camera, const CameraExtrinsics& T_b_c);

  /// IMU samples in time order (others are ignored).
  void addImu(const ImuData& imu);
  /// A frame of tracks on the IMU clock (its stamp + the camera-IMU time offset).
  void addFrame(const CameraFrame& frame);
  /// Tries the alignment on the frames of the last window_s that the IMU covers, and if their
  /// motion is degenerate, on those of up to max_window_s. On failure returns nothing and sets
  /// *why (what is missing or degenerate).
  std::optional<DynamicInitResult> tryInitialize(std::string* why);
  /// The IMU from t0 to t1, preintegrated in the body frame at t0 with the gyro bias b_g taken off
  /// (alignment::preintegrate); none unless the samples cover [t0, t1].
  std::optional<alignment::Preintegrated> imuBetween(double t0, double t1, const Vec3& b_g) const;
  void reset();
  const DynamicInitParams& params() const { return params_; }

 private:
  /// The frames the IMU covers (with the time offset search's margin at both ends), the last
  /// span_s of them, oldest first.
  std::vector<const CameraFrame*> coveredFrames(double span_s) const;
  /// *degenerate (if given) is set when it fails because the motion leaves the state unobservable.
  std::optional<DynamicInitResult> alignSpan(double span_s, std::string* why, bool* degenerate);

  DynamicInitParams params_;
  CameraModel camera_;
  CameraExtrinsics T_b_c_;
  std::deque<ImuData> imu_;
  std::deque<CameraFrame> frames_;
};

}  // namespace vi_ekf_slam
