// Standalone executable running the same class as the nodelet.
#include <cstdio>
#include <ros/ros.h>

#include "vi_ekf_slam/ros/ekf_slam_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "vi_ekf_slam");
  try {
    vi_ekf_slam::glue::EkfSlamRos node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::exception& e) {
    // Also on stderr: rosconsole may not be set up when the parameters are rejected.
    std::fprintf(stderr, "%s\n", e.what());
    ROS_FATAL("%s", e.what());
    return 1;
  }
  return 0;
}
