// Where the camera's calibration comes from: the intrinsics from camera_info or from a file (a
// ROS camera YAML, the parameters camera_intrinsics..., Kalibr's camchain through them), with
// calibration_source choosing which wins; the camera-IMU extrinsic from TF (IMU frame <- the
// images' frame) or from the parameters. One job: know the calibration, or say what is missing.
#pragma once

#include <optional>
#include <sensor_msgs/CameraInfo.h>
#include <string>
#include <tf2/buffer_core.h>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/ros/params.h"

namespace vi_ekf_slam::glue {

/// The intrinsics of camera_intrinsics, camera_resolution, camera_distortion_model and
/// camera_distortion_coeffs: "" and *out, or what is wrong (nothing is set: "" and out untouched).
std::string intrinsicsFromOptions(const NodeOptions& o, std::optional<CameraIntrinsics>* out);

/// What a camera_info did.
struct CameraInfoUse {
  std::string error;     ///< not a usable calibration (the message is ignored)
  bool changed = false;  ///< taken, and it differs from the calibration in use (the map no longer fits)
  /// calibration_source file: the message differs from the file and is ignored; said once (then "").
  std::string ignored_once;
  bool ignored = false;  ///< it differs from the file and was ignored (every time)
};

class CalibrationSource {
 public:
  /// Reads the file intrinsics (camera_calibration_file or camera_intrinsics) and T_b_c
  /// (extrinsic_source "parameters"). Throws std::invalid_argument if they cannot be used.
  explicit CalibrationSource(const NodeOptions& o);

  /// Takes a camera_info (calibration_source camera_info) or compares it with the file (file).
  CameraInfoUse cameraInfo(const sensor_msgs::CameraInfo& msg);
  /// "" once intrinsics and extrinsic are known (the extrinsic looked up on TF once), else what is
  /// missing. tf may be null when the extrinsic comes from the parameters.
  std::string ready(const std::string& image_frame, const std::string& imu_frame, const tf2::BufferCore* tf);

  /// Intrinsics are known (from a file, or from a camera_info taken): camera_info is then optional.
  bool hasIntrinsics() const { return intrinsics_.has_value(); }
  /// Valid once ready() returned "".
  const CameraIntrinsics& intrinsics() const { return *intrinsics_; }
  const CameraExtrinsics& extrinsics() const { return *extrinsics_; }
  /// Where the intrinsics in use came from, and whether a camera_info was ignored (diagnostics).
  std::string summary() const;

 private:
  bool file_wins_ = false;
  std::string intrinsics_from_ = "none yet";
  bool said_ignored_ = false;
  std::optional<CameraIntrinsics> intrinsics_;
  std::optional<CameraExtrinsics> extrinsics_;
};

}  // namespace vi_ekf_slam::glue
