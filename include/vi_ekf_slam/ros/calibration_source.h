// Where the camera's calibration comes from: the intrinsics from camera_info (a calibration file
// until one arrives), the camera-IMU extrinsic from TF (IMU frame <- the images' frame) or from
// the parameters. One job: know the calibration, or say what is missing.
#pragma once

#include <optional>
#include <sensor_msgs/CameraInfo.h>
#include <string>
#include <tf2/buffer_core.h>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/ros/params.h"

namespace vi_ekf_slam::glue {

class CalibrationSource {
 public:
  /// Reads o.camera_calibration_file (if set) and o.T_b_c (extrinsic_source "parameters"). Throws
  /// std::invalid_argument if the calibration file cannot be used.
  explicit CalibrationSource(const NodeOptions& o);

  /// Takes a camera_info. Returns "" or why it was ignored; *changed: it differs from the
  /// calibration in use (the map and the tracks no longer fit).
  std::string cameraInfo(const sensor_msgs::CameraInfo& msg, bool* changed);
  /// "" once intrinsics and extrinsic are known (the extrinsic looked up on TF once), else what is
  /// missing. tf may be null when the extrinsic comes from the parameters.
  std::string ready(const std::string& image_frame, const std::string& imu_frame, const tf2::BufferCore* tf);

  /// Valid once ready() returned "".
  const CameraIntrinsics& intrinsics() const { return *intrinsics_; }
  const CameraExtrinsics& extrinsics() const { return *extrinsics_; }

 private:
  std::optional<CameraIntrinsics> intrinsics_;
  std::optional<CameraExtrinsics> extrinsics_;
};

}  // namespace vi_ekf_slam::glue
