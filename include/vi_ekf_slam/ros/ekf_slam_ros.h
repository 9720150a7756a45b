// The ROS glue: subscribes to IMU, images (image_transport) and camera_info, synchronizes them,
// runs the front end and the filter of the ROS-free core, and publishes odometry, path,
// landmarks, the debug track image, filter status, diagnostics and TF. The nodelet and the
// standalone node are thin wrappers around this class.
#pragma once

#include <deque>
#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <memory>
#include <mutex>
#include <nav_msgs/Path.h>
#include <optional>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "vi_ekf_slam/EkfSlamReconfigureConfig.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/feature_tracker.h"
#include "vi_ekf_slam/core/static_initializer.h"
#include "vi_ekf_slam/ros/params.h"

namespace vi_ekf_slam::glue {

/// Counters shown in the diagnostics (and used by the tests).
struct InputCounters {
  long imu_received = 0, imu_nonfinite = 0, imu_stale = 0, imu_gaps = 0;
  long images_received = 0, images_processed = 0, images_bad_encoding = 0, images_stale = 0;
  long images_late = 0, images_before_init = 0, images_no_camera = 0, images_queue_dropped = 0;
  long camera_info_invalid = 0, rejected_observations = 0, resets = 0;
};

class EkfSlamRos {
 public:
  /// Throws std::invalid_argument listing every impossible parameter value.
  EkfSlamRos(ros::NodeHandle nh, ros::NodeHandle pnh);

 private:
  struct PendingImage {
    double t;
    ros::Time stamp;
    cv::Mat mono;
  };

  void imuCallback(const sensor_msgs::ImuConstPtr& msg);
  void imageCallback(const sensor_msgs::ImageConstPtr& msg);
  void cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& msg);
  bool resetCallback(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  void reconfigureCallback(EkfSlamReconfigureConfig& config, uint32_t level);
  void diagnosticsTimer(const ros::TimerEvent&);

  bool cameraReady(const std::string& image_frame);
  void tryInitialize(double t_now);
  void processQueue();
  void processImage(const PendingImage& img);
  void resetFilter(const std::string& reason);
  void reportProblem(const std::string& what);
  void publish(const PendingImage& img, const FrameResult& r, double update_ms);

  void diagnoseInputs(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& stat);

  std::mutex mutex_;
  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  std::optional<CameraIntrinsics> intrinsics_;
  bool intrinsics_from_topic_ = false;
  std::optional<CameraExtrinsics> extrinsics_;
  std::unique_ptr<EkfSlam> filter_;
  std::unique_ptr<FeatureTracker> tracker_;
  StaticInitializer static_init_;
  std::optional<StaticInitResult> static_result_;
  std::deque<PendingImage> queue_;
  double last_imu_t_ = -1e300, last_image_t_ = -1e300;
  Vec3 last_gyro_ = Vec3::Zero();
  std::optional<Quat> prev_q_n_b_;
  InputCounters counters_;
  int last_tracks_ = 0;
  double last_update_ms_ = 0.0;
  std::string last_problem_;
  double rate_window_start_ = 0.0;
  long rate_imu_count_ = 0, rate_image_count_ = 0;
  double imu_rate_hz_ = 0.0, image_rate_hz_ = 0.0;

  image_transport::ImageTransport it_;
  image_transport::Subscriber image_sub_;
  image_transport::Publisher tracks_pub_;
  ros::Subscriber imu_sub_, info_sub_;
  ros::Publisher odom_pub_, path_pub_, landmarks_pub_, status_pub_, events_pub_;
  ros::ServiceServer reset_srv_;
  ros::Timer diag_timer_;
  nav_msgs::Path path_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  diagnostic_updater::Updater updater_;
  std::unique_ptr<dynamic_reconfigure::Server<EkfSlamReconfigureConfig>> reconfigure_;
  boost::recursive_mutex reconfigure_mutex_;
};

}  // namespace vi_ekf_slam::glue
