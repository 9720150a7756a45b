#include "vi_ekf_slam/ros/bag_io.h"

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Imu.h>
#include <std_msgs/String.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>
#include <rosbag/view.h>
#include <algorithm>
#include <boost/make_shared.hpp>

#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/ros/conversions.h"

namespace vi_ekf_slam::glue {

RigBagWriter::RigBagWriter(const std::string& path, const RigTopics& topics, const CameraModel& camera,
                           const CameraExtrinsics& T_b_c, const ImuNoiseParams& noise, double imu_rate_hz,
                           const ros::Time& start)
    : topics_(topics), camera_(camera) {
  bag_.open(path, rosbag::bagmode::Write);
  // Uncompressed, as `rosbag record` writes by default: LZ4 hardly shrinks the rendered images
  // (textured noise) but reading them back (checksum and decompression) cost a large share of
  // the offline pipeline's time per image (bench/README.md).
  bag_.setCompression(rosbag::compression::Uncompressed);
  // Per-sample variance of white noise of density sigma sampled at rate f: sigma^2 * f.
  gyro_var_ = noise.gyro_noise_density * noise.gyro_noise_density * imu_rate_hz;
  accel_var_ = noise.accel_noise_density * noise.accel_noise_density * imu_rate_hz;
  tf2_msgs::TFMessage tf;
  geometry_msgs::TransformStamped T;
  T.header.stamp = start;
  T.header.frame_id = topics.imu_frame;
  T.child_frame_id = topics.camera_frame;
  tf2::toMsg(T_b_c.p_b_c, T.transform.translation);
  T.transform.rotation = tf2::toMsg(Quat(T_b_c.R_b_c));
  tf.transforms.push_back(T);
  // Marked latched, as `rosbag record` stores /tf_static from tf2's latched publishers, so that
  // `rosbag play` re-publishes it latched: the bag has this one message, and a TF listener that
  // connects after it went out (rosbag play waits only 0.2 s after advertising) would otherwise
  // never learn the camera-IMU extrinsic.
  // A given connection header replaces rosbag's own, so it carries the type fields too.
  auto connection = boost::make_shared<ros::M_string>();
  (*connection)["type"] = ros::message_traits::datatype(tf);
  (*connection)["md5sum"] = ros::message_traits::md5sum(tf);
  (*connection)["message_definition"] = ros::message_traits::definition(tf);
  (*connection)["callerid"] = "/vi_ekf_slam_bag_writer";
  (*connection)["latching"] = "1";
  bag_.write("/tf_static", start, tf, connection);
}

void RigBagWriter::imu(const ImuData& d) {
  sensor_msgs::Imu m;
  m.header.stamp = ros::Time(d.timestamp);
  m.header.frame_id = topics_.imu_frame;
  m.orientation_covariance[0] = -1.0;  // REP-145: no orientation estimate
  m.angular_velocity.x = d.wm.x();
  m.angular_velocity.y = d.wm.y();
  m.angular_velocity.z = d.wm.z();
  m.linear_acceleration.x = d.am.x();
  m.linear_acceleration.y = d.am.y();
  m.linear_acceleration.z = d.am.z();
  for (int i = 0; i < 3; ++i) {
    m.angular_velocity_covariance[static_cast<size_t>(4 * i)] = gyro_var_;
    m.linear_acceleration_covariance[static_cast<size_t>(4 * i)] = accel_var_;
  }
  bag_.write(topics_.imu, m.header.stamp, m);
}

void RigBagWriter::image(double t, const cv::Mat& mono8) {
  std_msgs::Header h;
  h.stamp = ros::Time(t);
  h.frame_id = topics_.camera_frame;
  bag_.write(topics_.image, h.stamp, cv_bridge::CvImage(h, "mono8", mono8).toImageMsg());
  bag_.write(topics_.camera_info, h.stamp, toCameraInfo(camera_.intrinsics(), h));
}

void RigBagWriter::groundTruth(double t, const Vec3& p, const Quat& q) {
  geometry_msgs::PoseStamped g;
  g.header.stamp = ros::Time(t);
  g.header.frame_id = topics_.world_frame;
  g.pose.position = tf2::toMsg(p);
  g.pose.orientation = tf2::toMsg(q);
  bag_.write(topics_.ground_truth, g.header.stamp, g);
}

void RigBagWriter::text(const std::string& topic, double t, const std::string& s) {
  std_msgs::String m;
  m.data = s;
  bag_.write(topic, ros::Time(t), m);
}

InputBagInfo readInputBag(const std::string& path, const RigTopics& topics) {
  InputBagInfo info;
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error("cannot read bag '" + path + "': " + e.what());
  }
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{topics.ground_truth, "/sim/world",
                                                                     topics.camera_info, "/tf_static"}));
  rosbag::View all(bag);
  info.start = all.getBeginTime().toSec();
  info.end = all.getEndTime().toSec();
  for (const rosbag::MessageInstance& m : view) {
    if (auto g = m.instantiate<geometry_msgs::PoseStamped>()) {
      io::StampedPose p;
      p.t = g->header.stamp.toSec();
      tf2::fromMsg(g->pose.position, p.p);
      tf2::fromMsg(g->pose.orientation, p.q);
      p.q.normalize();
      info.truth.push_back(p);
    } else if (auto w = m.instantiate<std_msgs::String>()) {
      if (m.getTopic() == "/sim/world") info.world = sim::parseQuads(w->data);
    } else if (auto ci = m.instantiate<sensor_msgs::CameraInfo>()) {
      CameraIntrinsics in;
      if (!info.camera && intrinsicsFromCameraInfo(*ci, &in).empty()) info.camera = in;
    } else if (auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
      for (const auto& t : tf->transforms) {
        if (t.header.frame_id == topics.imu_frame && t.child_frame_id == topics.camera_frame) {
          info.T_b_c = extrinsicsFromTransform(t.transform);
        }
      }
    }
  }
  std::sort(info.truth.begin(), info.truth.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  return info;
}

eval::LandmarkTruth landmarkTruthFromWorld(const InputBagInfo& info) {
  if (info.world.empty() || !info.camera || !info.T_b_c) return {};
  const CameraModel camera(*info.camera);
  const CameraExtrinsics T = *info.T_b_c;
  const std::vector<io::StampedPose>& truth = info.truth;
  const std::vector<sim::Quad>& world = info.world;
  return [camera, T, &truth, &world](const eval::EstimatedLandmark& l) -> std::optional<Vec3> {
    auto it = std::lower_bound(truth.begin(), truth.end(), l.birth_time - 1e-3,
                               [](const io::StampedPose& p, double x) { return p.t < x; });
    if (it == truth.end() || std::abs(it->t - l.birth_time) > 1e-3) return std::nullopt;
    Eigen::Vector2d xn;
    if (!camera.pixelToNormalized(l.birth_uv, &xn)) return std::nullopt;
    Vec3 p_n;
    Quat q_n_b;
    navToZUpWorld(it->p, it->q, &p_n, &q_n_b);  // the map is its own inverse
    const Vec3 o = p_n + q_n_b * T.p_b_c;
    const Vec3 d = q_n_b * (T.R_b_c * Vec3(xn.x(), xn.y(), 1.0));
    const auto hit = sim::raycast(world, o, d);
    if (!hit) return std::nullopt;
    return zUpWorldFromNav() * *hit;
  };
}

}  // namespace vi_ekf_slam::glue
