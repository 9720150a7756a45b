// The node: parameters from the private namespace, subscribers feeding an EkfSlamProcessor,
// publishers for its outputs (odometry, TF, path, landmarks, debug tracks, status, events),
// diagnostics, dynamic_reconfigure and the reset service. The nodelet and the standalone
// executable are thin wrappers around this class; the logic is in EkfSlamProcessor.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <memory>
#include <mutex>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "vi_ekf_slam/EkfSlamReconfigureConfig.h"
#include "vi_ekf_slam/ros/ekf_slam_processor.h"
#include "vi_ekf_slam/ros/input_watch.h"

namespace vi_ekf_slam::glue {

class EkfSlamRos : public OutputSink {
 public:
  /// Throws std::invalid_argument listing every impossible parameter value.
  EkfSlamRos(ros::NodeHandle nh, ros::NodeHandle pnh);

  // OutputSink: publish.
  void odometry(const nav_msgs::Odometry& odom) override;
  bool wantsLandmarks() const override { return landmarks_pub_.getNumSubscribers() > 0; }
  bool wantsImuOdometry() const override { return odom_imu_pub_.getNumSubscribers() > 0; }
  void imuOdometry(const nav_msgs::Odometry& odom) override { odom_imu_pub_.publish(odom); }
  void landmarks(const std::vector<LandmarkOutput>& landmarks, const ros::Time& stamp) override;
  bool wantsTracksImage() const override { return tracks_pub_.getNumSubscribers() > 0; }
  void tracksImage(const std_msgs::Header& header, const cv::Mat& bgr) override;
  void status(const vi_ekf_slam::FilterStatus& status) override;
  void event(const std::string& text, double t_s) override;

 private:
  void diagnosticsTimer(const ros::TimerEvent&);
  /// "" or which input the node waits on, by its resolved topic (logged, and in the diagnostics).
  std::string waitingOn();
  /// ~image_transport (raw | compressed | any installed transport), with "compressed" served by
  /// this package's own plugin (src/ros/compressed_subscriber.cc).
  image_transport::TransportHints imageTransportHints() const;
  void diagnoseInputs(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void diagnoseTf(diagnostic_updater::DiagnosticStatusWrapper& stat);
  /// "" or why parent -> child is not broadcast: before the node's first broadcast, `child`
  /// already had another parent on TF (a driver's or URDF's tree; a frame has one parent).
  const std::string& tfConflict(const std::string& parent, const std::string& child);

  std::mutex mutex_;  ///< serializes callbacks (a nodelet manager may run them on several threads)
  // The input rates' diagnostics (WARN below min_imu_rate_hz / min_image_rate_hz); the bounds
  // are read by FrequencyStatus through these pointers. Declared before the subscribers and the
  // updater that use them, so they are destroyed after those.
  double imu_rate_min_hz_ = 0.0, image_rate_min_hz_ = 0.0, no_max_hz_ = 1e9;
  std::unique_ptr<diagnostic_updater::FrequencyStatus> imu_rate_, image_rate_;
  ros::NodeHandle nh_, pnh_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  bool tf_sent_ = false;     ///< the node has broadcast its transform (its child's parent is then its own)
  std::string tf_conflict_;  ///< see tfConflict()
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;  ///< map_frame -> odom_frame
  std::unique_ptr<EkfSlamProcessor> processor_;
  enum WatchedInput : size_t { kImuInput, kImageInput, kCameraInfoInput };
  std::unique_ptr<InputWatch> input_watch_;  ///< on the wall clock: a paused replay waits on nothing
  image_transport::ImageTransport it_;
  image_transport::Subscriber image_sub_;
  image_transport::Publisher tracks_pub_;
  ros::Subscriber imu_sub_, info_sub_;
  ros::Publisher odom_pub_, odom_imu_pub_, path_pub_, landmarks_pub_, status_pub_, events_pub_;
  ros::ServiceServer reset_srv_;
  ros::ServiceServer save_map_srv_;  ///< ~save_map: the kept map to map_file
  ros::Timer diag_timer_;
  ros::WallTimer watch_timer_;        ///< logs what the node waits on (waitingOn)
  double last_waiting_log_s_ = -1e9;  ///< wall time of that log [s]
  nav_msgs::Path path_;
  diagnostic_updater::Updater updater_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<EkfSlamReconfigureConfig>> reconfigure_;
};

}  // namespace vi_ekf_slam::glue
