// Message fields as Eigen values for the ROS tests' checks (tf2_eigen's fromMsg, returned by value).
#pragma once

#include <geometry_msgs/Point.h>
#include <geometry_msgs/Quaternion.h>
#include <tf2_eigen/tf2_eigen.h>

#include <Eigen/Geometry>

namespace vi_ekf_slam::test {

inline Eigen::Quaterniond quat(const geometry_msgs::Quaternion& q) {
  Eigen::Quaterniond out;
  tf2::fromMsg(q, out);
  return out;
}

inline Eigen::Vector3d pos(const geometry_msgs::Point& p) {
  Eigen::Vector3d out;
  tf2::fromMsg(p, out);
  return out;
}

}  // namespace vi_ekf_slam::test
