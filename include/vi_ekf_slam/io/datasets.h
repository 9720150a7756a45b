// Readers for the real datasets in ../shared/data (ROS-free): the EuRoC/ASL folder layout and
// the EqVIO feature-track CSV. Every reader throws std::runtime_error naming the file and
// line when the data is malformed.
#pragma once

#include <string>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/types.h"
#include "vi_ekf_slam/io/tum_io.h"

namespace vi_ekf_slam::io {

/// An ASL sensor.yaml: intrinsics, radial-tangential distortion, T_BS (sensor in body).
struct AslCamera {
  CameraIntrinsics intrinsics;
  CameraExtrinsics T_b_c;
  double rate_hz = 0.0;
};
AslCamera readAslCamera(const std::string& sensor_yaml);
/// Noise densities of an ASL imu0/sensor.yaml.
ImuNoiseParams readAslImuNoise(const std::string& sensor_yaml);
/// Densities for the EuRoC MAV's VI-sensor in flight: the datasheet values of imu0/sensor.yaml
/// (gyro 1.7e-4, accelerometer 2.0e-3) inflated for the propellers' vibration as VIO systems do
/// (EqVIO's settings use 6x the accelerometer density): gyro 2.5e-4 rad/s/sqrt(Hz),
/// accelerometer 1.0e-2 m/s^2/sqrt(Hz), random walks 2.0e-5 rad/s^2/sqrt(Hz), 3.0e-3 m/s^3/sqrt(Hz).
ImuNoiseParams eurocMavImuNoise();
/// Zero-velocity update noise for the EuRoC MAV [m/s]: standing on the ground it does not sway
/// like a pedestrian (the core default, 0.08), so the tighter value of a still platform.
constexpr double kEurocMavStandingVelocitySigma = 0.03;

struct AslImage {
  double t = 0.0;
  std::string path;
};
std::vector<AslImage> readAslImages(const std::string& cam_folder);  ///< data.csv + data/
std::vector<ImuData> readAslImu(const std::string& imu_csv);         ///< imu0/data.csv

/// Ground truth (state_groundtruth_estimate0/data.csv): body pose in the z-up world, velocity,
/// biases.
struct AslState {
  double t = 0.0;
  Vec3 p = Vec3::Zero(), v = Vec3::Zero();
  Quat q = Quat::Identity();
  Vec3 b_g = Vec3::Zero(), b_a = Vec3::Zero();
};
std::vector<AslState> readAslGroundTruth(const std::string& csv);
std::vector<StampedPose> toStampedPoses(const std::vector<AslState>& states);

/// Trajectory file in either TUM or ASL (EuRoC) ground-truth CSV format (detected from the
/// content: 17 comma-separated columns with nanosecond stamps).
std::vector<StampedPose> readTrajectoryFile(const std::string& path);

/// The EqVIO CSV (see ../shared/data/euroc_v1_01_features/README.md): IMU rows, per-frame
/// feature tracks in normalized image coordinates, and the camera in the meta rows.
struct FeatureTrackData {
  std::vector<ImuData> imu;
  std::vector<CameraFrame> frames;  ///< uv in pixels of `camera` (an undistorted pinhole)
  CameraIntrinsics camera;
  CameraExtrinsics T_b_c;
};
FeatureTrackData readEqvioCsv(const std::string& path, int width = 752, int height = 480);

}  // namespace vi_ekf_slam::io
