// The simulated pedestrian rig as its drivers would publish it: the hallway walk's IMU (200 Hz),
// rendered images (28 Hz) with camera_info, the camera-IMU transform and the truth, as a list of
// messages in publication order, with one kind of bad input injected (`fault`):
//   none | nan_imu | imu_repeat | image_repeat | time_jump | imu_gap | image_before_imu |
//   encoding_cycle | encoding:<enc> | camera_info_missing | camera_info_zero |
//   compressed (PNG CompressedImage instead of raw images) | image_dropout (no images for 2 s
//   from t = 4 s) | camera_covered (uniform dark images for 5 s from t = 3 s) | camera_dark (the
//   same 5 s at a twentieth of the light with noise of 8 grey levels) | outlier_burst (for
//   0.5 s from t = 4 s the images are those of 1.5 s earlier: every track is wrong, consistently)
// The rostest node (synthetic_stream.cc) publishes them in real time; processor gtests feed them
// straight to EkfSlamProcessor in simulated time.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace vi_ekf_slam::test {

struct RigOptions {
  double duration_s = 8.0;  ///< stream length from the start [s]
  double standing_s = 2.0;  ///< standing before the walk [s]
  std::string fault = "none";
  int seed = 1;
  std::string imu_frame = "imu", camera_frame = "camera";
  /// The rendered camera and its pose in the IMU frame (default: the hallway scenario's).
  std::optional<CameraIntrinsics> camera;
  std::optional<CameraExtrinsics> T_b_c;
};

struct RigMessage {
  /// When to publish it: seconds since the stream's start (a restart replays old stamps later).
  double play_t = 0.0;
  std::variant<sensor_msgs::Imu, sensor_msgs::Image, sensor_msgs::CompressedImage, sensor_msgs::CameraInfo,
               geometry_msgs::PoseStamped>
      msg;
};

struct RigStream {
  geometry_msgs::TransformStamped imu_camera;  ///< imu_frame -> camera_frame (for /tf_static)
  std::vector<RigMessage> messages;            ///< stamps relative to t0 = 0 (shift them to publish)
};

/// The stream; every stamp is t0 + the simulation time (which starts slightly below 0 for the IMU:
/// t0 must keep the stamps positive).
RigStream makeRigStream(const RigOptions& o, double t0);

}  // namespace vi_ekf_slam::test
