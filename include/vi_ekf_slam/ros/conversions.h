// Conversions between ROS messages and the core's plain types. The only place where the
// filter's navigation frame {n} (z down) meets the ROS world frame (ENU-style, z up, REP-103).
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <opencv2/core.hpp>
#include <optional>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <string>
#include <vector>

#include "vi_ekf_slam/FilterStatus.h"
#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/navigation_output.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam::glue {

/// IMU sample at stamp + nothing; nullopt if any value is NaN/Inf.
std::optional<ImuData> fromImuMsg(const sensor_msgs::Imu& msg);

/// The CameraInfo of a calibration (plumb_bob or equidistant, no rectification).
sensor_msgs::CameraInfo toCameraInfo(const CameraIntrinsics& k, const std_msgs::Header& header);
/// Intrinsics from a CameraInfo (plumb_bob, rational_polynomial with zero rational terms,
/// equidistant); returns an empty string or what is wrong (all-zero K, unknown model, ...).
std::string intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& msg, CameraIntrinsics* out);

/// Any of mono8, mono16, bgr8, rgb8, bgra8, rgba8 as mono8; returns an empty string or why not.
std::string toMono8(const sensor_msgs::Image& msg, cv::Mat* out);

/// Extrinsic from a transform "body <- camera" (the camera frame expressed in the body frame).
CameraExtrinsics extrinsicsFromTransform(const geometry_msgs::Transform& t);

/// Odometry of the body in the ENU-style world frame; twist in the body frame (REP-105).
/// w_b: body angular rate [rad/s] (bias-corrected gyro), w_var: its variance per axis.
nav_msgs::Odometry toOdometry(const NavState& nav, const Eigen::Vector3d& w_b, double w_var, const ros::Time& stamp,
                              const std::string& world_frame, const std::string& body_frame);

/// Landmarks in `frame` (the ENU-style world is T_frame_world in it) as a cloud with fields x y z
/// (float32), id (uint32), sigma (float32, square root of the largest eigenvalue of the 3x3
/// covariance [m]), and where the landmark's track started: birth_time (float64 [s]), birth_u,
/// birth_v (float32 [px]).
struct LandmarkOutput;
sensor_msgs::PointCloud2 toPointCloud(const std::vector<LandmarkOutput>& landmarks, const ros::Time& stamp,
                                      const std::string& frame, const Eigen::Isometry3d& T_frame_world);

/// What the per-image status says besides the filter's own state.
struct StatusExtras {
  LandmarkInitMethod landmark_init = LandmarkInitMethod::kInverseDepth;
  int tracks = 0;
  long resets = 0;
  double update_ms = 0.0, tracker_ms = 0.0;  ///< time for the image, and the tracker's part of it [ms]
  double gravity_mps2 = 9.81;
  bool in_map = false;  ///< the kept map (VioPipeline::inMap, map())
  int map_points = 0;
  int relocalizations = 0;
};
/// The status of one processed image (header left empty for the caller).
vi_ekf_slam::FilterStatus toFilterStatus(const EkfSlam& filter, const NavState& nav, const FrameResult& r,
                                         const StatusExtras& x);

/// True if every number of the pose, twist and covariances is finite.
bool allFinite(const nav_msgs::Odometry& odom);

}  // namespace vi_ekf_slam::glue
