// The nodelet: all the work is in vi_ekf_slam::glue::EkfSlamRos.
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "vi_ekf_slam/ros/ekf_slam_ros.h"

namespace vi_ekf_slam {

class EkfSlamNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      node_ = std::make_unique<glue::EkfSlamRos>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL("%s", e.what());
      throw;
    }
  }
  std::unique_ptr<glue::EkfSlamRos> node_;
};

}  // namespace vi_ekf_slam

PLUGINLIB_EXPORT_CLASS(vi_ekf_slam::EkfSlamNodelet, nodelet::Nodelet)
