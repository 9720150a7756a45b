// Test fixture: publishes the simulated pedestrian rig (synthetic_rig.h) in real time, like its
// drivers would: /imu, /camera/image_raw (or /camera/image_raw/compressed), /camera/camera_info,
// /tf_static (IMU <- camera) and /ground_truth/pose (the IMU in the z-up world); /stream/end once
// it is over. Private parameters: duration_s, standing_s, fault, seed, imu_frame, camera_frame.
#include <ros/ros.h>
#include <std_msgs/Time.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "synthetic_rig.h"

using vi_ekf_slam::test::RigOptions;

namespace {

/// Publishes each message type on its topic.
struct Publishers {
  ros::Publisher imu, image, compressed, info, truth;
  void operator()(const sensor_msgs::Imu& m) const { imu.publish(m); }
  void operator()(const sensor_msgs::Image& m) const { image.publish(m); }
  void operator()(const sensor_msgs::CompressedImage& m) const { compressed.publish(m); }
  void operator()(const sensor_msgs::CameraInfo& m) const { info.publish(m); }
  void operator()(const geometry_msgs::PoseStamped& m) const { truth.publish(m); }
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "synthetic_stream");
  ros::NodeHandle nh, pnh("~");
  RigOptions o;
  pnh.param("duration_s", o.duration_s, o.duration_s);
  pnh.param("standing_s", o.standing_s, o.standing_s);
  pnh.param("fault", o.fault, o.fault);
  pnh.param("seed", o.seed, o.seed);
  pnh.param("imu_frame", o.imu_frame, o.imu_frame);
  pnh.param("camera_frame", o.camera_frame, o.camera_frame);

  Publishers pub;
  pub.imu = nh.advertise<sensor_msgs::Imu>("/imu", 400);
  pub.image = nh.advertise<sensor_msgs::Image>("/camera/image_raw", 10);
  pub.compressed = nh.advertise<sensor_msgs::CompressedImage>("/camera/image_raw/compressed", 10);
  pub.info = nh.advertise<sensor_msgs::CameraInfo>("/camera/camera_info", 10);
  pub.truth = nh.advertise<geometry_msgs::PoseStamped>("/ground_truth/pose", 50);
  // Latched once the stream is over: the stamp of its last IMU sample. Checkers listen until then
  // (and until the node has caught up), not for a wall-clock window a loaded machine may cut short.
  ros::Publisher end_pub = nh.advertise<std_msgs::Time>("/stream/end", 1, true);

  // Rendered before the clock starts, stamped from kBase (the IMU may start before the first
  // image, at a negative time); the stamps are shifted to the start below.
  constexpr double kBase = 1000.0;
  const vi_ekf_slam::test::RigStream stream = vi_ekf_slam::test::makeRigStream(o, kBase);
  ROS_INFO("synthetic_stream: %zu messages, fault '%s'", stream.messages.size(), o.fault.c_str());
  tf2_ros::StaticTransformBroadcaster tf_static;
  geometry_msgs::TransformStamped T = stream.imu_camera;
  T.header.stamp = ros::Time::now();
  tf_static.sendTransform(T);
  ros::Duration(1.5).sleep();  // let the filter and the checker connect

  const ros::Time t0 = ros::Time::now();
  const ros::Duration shift = t0 - ros::Time(kBase);
  ros::Time last_imu;
  for (auto m : stream.messages) {
    if (!ros::ok()) break;
    ros::Time::sleepUntil(t0 + ros::Duration(m.play_t));
    std::visit(
        [&](auto& msg) {
          msg.header.stamp += shift;
          using T = std::decay_t<decltype(msg)>;
          if constexpr (std::is_same_v<T, sensor_msgs::Imu>) last_imu = msg.header.stamp;
          pub(msg);
        },
        m.msg);
  }
  std_msgs::Time end;
  end.data = last_imu;
  end_pub.publish(end);
  ROS_INFO("synthetic_stream: done");
  ros::spin();  // stay up until the test ends
  return 0;
}
