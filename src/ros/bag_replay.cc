#include "vi_ekf_slam/ros/bag_replay.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <tuple>

#include <cv_bridge/cv_bridge.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/eval/run_evaluation.h"

namespace vi_ekf_slam::glue {

void RecordingSink::odometry(const nav_msgs::Odometry& o) {
  eval::EstimatedPose p;
  p.t = o.header.stamp.toSec();
  tf2::fromMsg(o.pose.pose.position, p.p);
  tf2::fromMsg(o.pose.pose.orientation, p.q);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) p.cov(i, j) = o.pose.covariance[static_cast<size_t>(6 * i + j)];
  poses.push_back(p);
  Vec3 v_b;
  tf2::fromMsg(o.twist.twist.linear, v_b);
  speed_mps = v_b.norm();
  velocity_sigma_mps = std::sqrt((o.twist.covariance[0] + o.twist.covariance[7] + o.twist.covariance[14]) / 3.0);
  if (processor) {
    const Eigen::Isometry3d T_w_o = processor->outputFrames().fixedFromWorld().inverse();
    if (static_cast<int>(segments.size()) <= resets) segments.resize(static_cast<size_t>(resets) + 1);
    segments[static_cast<size_t>(resets)].push_back(
        {p.t, T_w_o * p.p, Quat(T_w_o.rotation() * p.q.toRotationMatrix()).normalized(), std::nullopt});
  }
}

void RecordingSink::landmarks(const std::vector<LandmarkOutput>& lms, const ros::Time&) {
  for (const auto& l : lms) {
    eval::EstimatedLandmark e;
    e.id = l.landmark.id;
    e.p = zUpWorldFromNav() * l.landmark.p_n_l;
    e.birth_time = l.birth_time;
    e.birth_uv = l.birth_uv;
    map[e.id] = e;
  }
}

void RecordingSink::status(const vi_ekf_slam::FilterStatus& s) {
  if (poses.empty()) return;
  poses.back().processing_ms = s.update_time_ms;
  poses.back().tracker_ms = s.tracker_time_ms;
  eval::StatusSample x;
  x.t = poses.back().t;
  x.p = poses.back().p;
  x.tracks = s.tracks;
  x.accepted = s.accepted_observations;
  x.rejected = s.rejected_observations;
  x.nis_per_dof = s.nis_per_dof;
  x.time_offset_s = s.time_offset_s;
  x.time_offset_sigma_s = s.time_offset_sigma_s;
  x.resets = s.resets;
  x.processing_ms = s.update_time_ms;
  x.tracker_ms = s.tracker_time_ms;
  x.landmarks = s.landmarks_in_state;
  x.new_landmarks = s.new_landmarks;
  x.deferred = s.deferred_features;
  x.removed = s.removed_landmarks;
  x.dormant = s.dormant_landmarks;
  x.revisits = s.revisits;
  x.stationary = s.stationary;
  x.speed_mps = speed_mps;
  x.velocity_sigma_mps = velocity_sigma_mps;
  x.blind_s = s.blind_s;
  trace.push_back(x);
}

void RecordingSink::event(const std::string& text, double t_s) {
  events.push_back({t_s, text});
  if (text.rfind("reset", 0) == 0) {
    ++resets;
    map.clear();  // the new filter maps anew
  }
}

InputTopics chooseInputTopics(const std::string& bag_path, const std::optional<std::string>& imu,
                              const std::optional<std::string>& image, const std::optional<std::string>& camera_info,
                              const InputTopics* preferred) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  std::map<std::string, std::string> types;  // topic -> datatype
  for (const rosbag::ConnectionInfo* c : view.getConnections()) types[c->topic] = c->datatype;
  // The topic and why it was chosen.
  auto choose = [&](const std::string& option, const std::optional<std::string>& requested,
                    const std::vector<std::string>& accepted, const std::string& parameter,
                    std::string preferred_topic) -> std::pair<std::string, std::string> {
    std::vector<std::string> found;
    for (const auto& [topic, type] : types) {
      if (std::find(accepted.begin(), accepted.end(), type) != accepted.end()) found.push_back(topic);
    }
    std::string list;
    for (const auto& t : found) list += " " + t + " (" + types[t] + ")";
    if (requested) {
      if (std::find(found.begin(), found.end(), *requested) == found.end()) {
        throw std::runtime_error(option + " " + *requested + " is not a topic of type " + accepted.front() +
                                 " in the bag; it has:" + (list.empty() ? std::string(" none") : list));
      }
      return {*requested, "given with " + option};
    }
    // The node's default names are relative: as a node at the root resolves them.
    const bool relative = !preferred_topic.empty() && preferred_topic.front() != '/';
    if (relative) preferred_topic = "/" + preferred_topic;
    const bool listed = std::find(found.begin(), found.end(), preferred_topic) != found.end();
    if (listed) return {preferred_topic, "the parameters' " + parameter};
    // A topic the parameters name (a rig file's) that the bag lacks is said, not passed over.
    const std::string missing =
        !preferred_topic.empty() && !relative ? parameter + " " + preferred_topic + " is not in the bag" : "";
    const std::string prefix = missing.empty() ? std::string() : missing + ", and ";
    if (found.empty()) throw std::runtime_error(prefix + "the bag has no " + accepted.front() + " topic");
    if (found.size() > 1) {
      throw std::runtime_error(prefix + "the bag has " + std::to_string(found.size()) + " topics of type " +
                               accepted.front() + ":" + list + "; choose one with " + option);
    }
    return {found.front(),
            "the bag's only " + accepted.front() + " topic" + (missing.empty() ? std::string() : "; " + missing)};
  };
  InputTopics t;
  const InputTopics none;
  const InputTopics& pref = preferred ? *preferred : none;
  std::tie(t.imu, t.imu_why) = choose("--imu-topic", imu, {"sensor_msgs/Imu"}, "imu_topic", pref.imu);
  std::tie(t.image, t.image_why) =
      choose("--image-topic", image, {"sensor_msgs/Image", "sensor_msgs/CompressedImage"}, "image_topic", pref.image);
  // camera_info is optional (camera_calibration_file may give the intrinsics instead).
  try {
    std::tie(t.camera_info, t.camera_info_why) =
        choose("--camera-info-topic", camera_info, {"sensor_msgs/CameraInfo"}, "camera_info_topic", pref.camera_info);
  } catch (const std::exception& e) {
    if (camera_info) throw;
    t.camera_info_why = std::string("none read (") + e.what() + "): the intrinsics come from the parameters";
  }
  return t;
}

double replayBag(const std::string& bag_path, const InputTopics& topics, EkfSlamProcessor& processor,
                 tf2::BufferCore& tf, const std::function<void(double done_s, double total_s)>& progress) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  const auto tic = std::chrono::steady_clock::now();
  const double start = view.getBeginTime().toSec(), total = (view.getEndTime() - view.getBeginTime()).toSec();
  for (const rosbag::MessageInstance& msg : view) {
    if (progress) progress(msg.getTime().toSec() - start, total);
    const std::string& topic = msg.getTopic();
    if (topic == topics.imu) {
      if (auto imu = msg.instantiate<sensor_msgs::Imu>()) processor.imu(*imu);
    } else if (topic == topics.image) {
      if (auto img = msg.instantiate<sensor_msgs::Image>()) {
        processor.image(*img);
      } else if (auto c = msg.instantiate<sensor_msgs::CompressedImage>()) {
        try {
          processor.image(*cv_bridge::toCvCopy(*c, "mono8")->toImageMsg());
        } catch (const std::exception& e) {
          std::cerr << "warning: compressed image at " << c->header.stamp << " not decoded: " << e.what() << "\n";
        }
      }
    } else if (topic == topics.camera_info) {
      if (auto ci = msg.instantiate<sensor_msgs::CameraInfo>()) processor.cameraInfo(*ci);
    } else if (topic == "/tf_static" || topic == "/tf") {
      if (auto t = msg.instantiate<tf2_msgs::TFMessage>()) {
        for (const auto& tr : t->transforms) tf.setTransform(tr, "bag", topic == "/tf_static");
      }
    }
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - tic).count();
}

eval::RunMetrics evaluateRecording(const std::string& path, const InputBagInfo& info, double* mean_tracks) {
  RecordingSink sink;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<std::int64_t, eval::EstimatedLandmark> last_cloud;
  std::vector<int> tracks;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto o = m.instantiate<nav_msgs::Odometry>()) {
      sink.odometry(*o);
    } else if (auto s = m.instantiate<vi_ekf_slam::FilterStatus>()) {
      sink.status(*s);
      tracks.push_back(s->tracks);
    } else if (auto c = m.instantiate<sensor_msgs::PointCloud2>()) {
      last_cloud.clear();
      sensor_msgs::PointCloud2ConstIterator<float> x(*c, "x"), y(*c, "y"), z(*c, "z"), u(*c, "birth_u"),
          v(*c, "birth_v");
      sensor_msgs::PointCloud2ConstIterator<uint32_t> id(*c, "id");
      sensor_msgs::PointCloud2ConstIterator<double> bt(*c, "birth_time");
      for (; x != x.end(); ++x, ++y, ++z, ++u, ++v, ++id, ++bt) {
        eval::EstimatedLandmark l;
        l.id = *id;
        l.p = Vec3(*x, *y, *z);
        l.birth_time = *bt;
        l.birth_uv = Eigen::Vector2d(*u, *v);
        last_cloud[l.id] = l;
      }
    }
  }
  std::vector<eval::EstimatedLandmark> lms;
  for (const auto& [id, l] : last_cloud) lms.push_back(l);
  *mean_tracks = 0.0;
  for (int t : tracks) *mean_tracks += static_cast<double>(t) / tracks.size();
  return eval::evaluateRun(sink.poses, info.truth, lms, landmarkTruthFromWorld(info));
}

}  // namespace vi_ekf_slam::glue
