// Kalibr's calibration files (kalibr_calibrate_imu_camera's camchain-imucam.yaml and the imu.yaml
// it was given) as the node's parameters: T_b_c (the inverse of T_cam_imu), the intrinsics, the
// distortion, the resolution, timeshift_cam_imu, the line delay of a rolling-shutter calibration,
// and the IMU's noise densities and random walks. The node reads them through its kalibr_camchain
// and kalibr_imu parameters; vi_ekf_slam_kalibr_to_rig writes them as a rig file.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace vi_ekf_slam::glue {

struct KalibrImport {
  /// Parameter name and its value written as YAML, in the order of a rig file.
  std::vector<std::pair<std::string, std::string>> params;
  std::string image_topic, imu_topic;  ///< Kalibr's rostopic entries ("" when absent)
  double imu_rate_hz = 0.0;            ///< imu.yaml's update_rate (0 when absent)
  std::vector<std::string> notes;      ///< what was read, and what a rig needs besides
};

/// Reads camchain-imucam.yaml (its cam0) and imu.yaml (its imu0); either path may be empty.
/// Throws std::runtime_error naming the file and key for what cannot be used (a missing key, a
/// camera model other than pinhole, a distortion other than radtan/equidistant/none, a T_cam_imu
/// that is not a rigid transform).
KalibrImport importKalibr(const std::string& camchain_path, const std::string& imu_path);

/// A rig file (YAML, loaded on top of config/vi_ekf_slam.yaml) with the imported values.
std::string kalibrRigFile(const KalibrImport& k, const std::string& camchain_path, const std::string& imu_path);

}  // namespace vi_ekf_slam::glue
