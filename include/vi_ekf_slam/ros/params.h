// Parameters of the node: read from the private namespace, validated (every impossible value is
// reported at once), echoed at startup, and updated from dynamic_reconfigure.
#pragma once

#include <ros/node_handle.h>
#include <string>
#include <vector>

#include "vi_ekf_slam/EkfSlamReconfigureConfig.h"
#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/feature_tracker.h"
#include "vi_ekf_slam/core/static_initializer.h"

namespace vi_ekf_slam::glue {

struct NodeOptions {
  std::string world_frame = "world";  ///< fixed frame of the outputs (z up)
  std::string body_frame = "imu";     ///< the IMU/body frame, child of world_frame
  bool publish_tf = true;
  double camera_time_offset_s = 0.0;  ///< t_imu = t_image + offset [s]
  std::string camera_calibration_file;  ///< ROS camera YAML used while no camera_info arrives
  std::string extrinsic_source = "tf";  ///< "tf" (body_frame <- image frame_id) or "parameters"
  std::vector<double> T_b_c = {0, 0, 0, 0, 0, 0, 1};  ///< x y z qx qy qz qw of the camera in the body [m]
  int max_image_queue = 20;           ///< images waiting for IMU beyond this are dropped
  double time_jump_reset_s = 1.0;     ///< a stamp this far backwards resets the filter [s]
  int path_max_length = 2000;         ///< poses kept in the published path
};

struct NodeParams {
  EkfSlamConfig filter;
  TrackerParams tracker;
  StaticInitParams static_init;
  NodeOptions node;
};

/// Reads every parameter from pnh (defaults where unset). Returns the problems, one per line,
/// or an empty string.
std::string loadParams(const ros::NodeHandle& pnh, NodeParams* out);
/// Human-readable list of every effective value with its unit.
std::string describeParams(const NodeParams& p);
/// Applies a dynamic_reconfigure update; returns the problems or an empty string.
std::string applyReconfigure(const EkfSlamReconfigureConfig& c, NodeParams* p);
/// The dynamic_reconfigure view of the current parameters.
EkfSlamReconfigureConfig toReconfigure(const NodeParams& p);

}  // namespace vi_ekf_slam::glue
