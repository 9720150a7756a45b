// Offline mode: runs the node's own EkfSlamProcessor over a bag through the rosbag API, as fast
// as the CPU allows and deterministically (messages in bag order, no threads, no master), and
// evaluates the result against the bag's ground truth.
//
//   vi_ekf_slam_run_bag bag:=FILE [out:=DIR] [config:=YAML] [mechanization:=NAME|all] [plots:=false] [NAME:=VALUE ...]
//   vi_ekf_slam_run_bag bag:=FILE recorded:=NAME=REC.bag[,NAME=REC.bag...] [out:=DIR]
// The second form evaluates recordings of live replays (odom, status, landmarks of the node)
// against the same input bag, with the same metrics.
//
// Writes to out (default results/run_bag/<bag name>): <run>.tum (trajectory with the 6x6 pose
// covariance), summary.json, summary.md, <run>_timeseries.csv, and the plots of tools/plot_run.py
// (topview.png, errors.png, nees.png; plots:=false to skip them).
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2/buffer_core.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <sstream>

#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/eval/run_evaluation.h"
#include "vi_ekf_slam/eval/tum_io.h"
#include "vi_ekf_slam/ros/bag_io.h"
#include "vi_ekf_slam/ros/ekf_slam_processor.h"

using namespace vi_ekf_slam;
namespace fs = std::filesystem;

namespace {

/// Keeps what the processor outputs.
class RecordingSink : public glue::OutputSink {
 public:
  std::vector<eval::EstimatedPose> poses;
  std::map<std::int64_t, eval::EstimatedLandmark> map;
  std::vector<std::string> events;
  int resets = 0;

  void odometry(const nav_msgs::Odometry& o) override {
    eval::EstimatedPose p;
    p.t = o.header.stamp.toSec();
    tf2::fromMsg(o.pose.pose.position, p.p);
    tf2::fromMsg(o.pose.pose.orientation, p.q);
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) p.cov(i, j) = o.pose.covariance[static_cast<size_t>(6 * i + j)];
    poses.push_back(p);
  }
  void landmarks(const std::vector<glue::LandmarkOutput>& lms, const ros::Time&) override {
    for (const auto& l : lms) {
      eval::EstimatedLandmark e;
      e.id = l.landmark.id;
      e.p = zUpWorldFromNav() * l.landmark.p_n_l;
      e.birth_time = l.birth_time;
      e.birth_uv = l.birth_uv;
      map[e.id] = e;
    }
  }
  void status(const vi_ekf_slam::FilterStatus& s) override {
    if (!poses.empty()) {
      poses.back().processing_ms = s.update_time_ms;
      poses.back().tracker_ms = s.tracker_time_ms;
    }
    tracks.push_back(s.tracks);
  }
  std::vector<int> tracks;
  void event(const std::string& text) override {
    events.push_back(text);
    if (text.rfind("reset", 0) == 0) {
      ++resets;
      poses.clear();  // a reset starts a new estimate frame: evaluate the last one
      map.clear();
    }
  }
};

}  // namespace

/// Evaluates a recording of the node's outputs (/vi_ekf_slam/odom, status, landmarks).
eval::RunMetrics evaluateRecording(const std::string& path, const glue::InputBagInfo& info, double* mean_tracks) {
  RecordingSink sink;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<std::int64_t, eval::EstimatedLandmark> last_cloud;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto o = m.instantiate<nav_msgs::Odometry>())
      sink.odometry(*o);
    else if (auto s = m.instantiate<vi_ekf_slam::FilterStatus>())
      sink.status(*s);
    else if (auto c = m.instantiate<sensor_msgs::PointCloud2>()) {
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
  for (int t : sink.tracks) *mean_tracks += static_cast<double>(t) / sink.tracks.size();
  return eval::evaluateRun(sink.poses, info.truth, lms, glue::landmarkTruthFromWorld(info));
}

int main(int argc, char** argv) {
  ros::Time::init();  // no master: wall time for the (throttled) log messages only
  std::map<std::string, std::string> args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto k = a.find(":=");
    if (k == std::string::npos) {
      std::cerr << "arguments are NAME:=VALUE (got '" << a << "')\n";
      return 2;
    }
    args[a.substr(0, k)] = a.substr(k + 2);
  }
  if (!args.count("bag")) {
    std::cerr << "usage: vi_ekf_slam_run_bag bag:=FILE [out:=DIR] [config:=YAML] [mechanization:=NAME|all] "
                 "[PARAM:=VALUE ...]\n";
    return 2;
  }
  const std::string bag_path = args["bag"];
  const std::string out = args.count("out") ? args["out"] : "results/run_bag/" + fs::path(bag_path).stem().string();
  const std::string config =
      args.count("config") ? args["config"] : std::string(VI_EKF_SLAM_SOURCE_DIR) + "/config/vi_ekf_slam.yaml";
  std::vector<std::string> mechanizations;
  const std::string mech = args.count("mechanization") ? args["mechanization"] : "";
  if (mech == "all")
    mechanizations = {"world_centric", "sensor_centric", "sensor_centric_composition"};
  else
    mechanizations = {mech};

  glue::InputBagInfo info;
  try {
    info = glue::readInputBag(bag_path);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  std::vector<std::pair<std::string, eval::RunMetrics>> results;
  if (args.count("recorded")) {
    std::stringstream list(args["recorded"]);
    std::string item;
    while (std::getline(list, item, ',')) {
      const auto eq = item.find('=');
      if (eq == std::string::npos) {
        std::cerr << "recorded:= expects NAME=BAG[,NAME=BAG...]\n";
        return 2;
      }
      double tracks = 0.0;
      try {
        results.emplace_back(item.substr(0, eq), evaluateRecording(item.substr(eq + 1), info, &tracks));
      } catch (const std::exception& e) {
        std::cerr << "error: " << item.substr(eq + 1) << ": " << e.what() << "\n";
        return 1;
      }
      std::printf("%s: %d poses, %.1f tracks per frame\n", item.substr(0, eq).c_str(), results.back().second.frames,
                  tracks);
    }
    mechanizations.clear();
  }
  for (const std::string& m : mechanizations) {
    glue::YamlParams yaml = [&] {
      try {
        return glue::YamlParams(config);
      } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        std::exit(1);
      }
    }();
    for (const auto& [k, v] : args) {
      if (k != "bag" && k != "out" && k != "config" && k != "mechanization" && k != "plots") yaml.set(k, v);
    }
    if (!m.empty()) yaml.set("mechanization", m);
    glue::NodeParams params;
    const std::string err = glue::loadParams(yaml, &params);
    if (!err.empty()) {
      std::cerr << "impossible parameter values:\n" << err;
      return 1;
    }
    const std::string name = toString(params.filter.mechanization);
    RecordingSink sink;
    tf2::BufferCore tf;
    glue::EkfSlamProcessor processor(params, sink, &tf);
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    rosbag::View view(bag);
    const auto tic = std::chrono::steady_clock::now();
    for (const rosbag::MessageInstance& msg : view) {
      const std::string& topic = msg.getTopic();
      if (auto imu = msg.instantiate<sensor_msgs::Imu>())
        processor.imu(*imu);
      else if (auto img = msg.instantiate<sensor_msgs::Image>())
        processor.image(*img);
      else if (auto ci = msg.instantiate<sensor_msgs::CameraInfo>())
        processor.cameraInfo(*ci);
      else if (topic == "/tf_static" || topic == "/tf") {
        if (auto t = msg.instantiate<tf2_msgs::TFMessage>()) {
          for (const auto& tr : t->transforms) tf.setTransform(tr, "bag", topic == "/tf_static");
        }
      }
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - tic).count();
    std::vector<eval::EstimatedLandmark> lms;
    for (const auto& [id, l] : sink.map) lms.push_back(l);
    eval::RunMetrics metrics = eval::evaluateRun(sink.poses, info.truth, lms, glue::landmarkTruthFromWorld(info));
    fs::create_directories(out);
    std::vector<eval::StampedPose> traj;
    for (const auto& p : sink.poses) traj.push_back({p.t, p.p, p.q, p.cov});
    eval::writeTum(out + "/" + name + ".tum", traj, "t x y z qx qy qz qw (body in the filter's world frame)");
    const double bag_s = info.end - info.start;
    double mean_tracks = 0.0;
    int min_tracks = sink.tracks.empty() ? 0 : 1 << 30;
    for (int t : sink.tracks) {
      mean_tracks += static_cast<double>(t) / sink.tracks.size();
      min_tracks = std::min(min_tracks, t);
    }
    std::printf(
        "%s: %zu poses, %d resets, tracks per frame %.1f (min %d), %.1f s of data in %.1f s (%.1fx real time), "
        "ATE %.3f m, final %.3f m (%.2f%%)\n"
        "  per image: %.2f ms processing, of which %.2f ms tracking; bag reading and the rest %.2f ms\n",
        name.c_str(), sink.poses.size(), sink.resets, mean_tracks, min_tracks, bag_s, wall, bag_s / wall,
        metrics.ate_position_m, metrics.final_position_error_m, metrics.final_position_error_pct,
        metrics.processing_ms_mean, metrics.tracker_ms_mean,
        sink.poses.empty() ? 0.0 : 1000.0 * wall / sink.poses.size() - metrics.processing_ms_mean);
    metrics.real_time_factor = bag_s / wall;  // offline: the whole pipeline, bag reading included
    results.emplace_back(name, metrics);
  }
  std::ostringstream cfg;
  cfg << "{\"bag\": \"" << bag_path << "\", \"config\": \"" << config << "\", \"mode\": \""
      << (args.count("recorded") ? "live replay" : "offline") << "\"}";
  eval::writeRunReport(out, results, cfg.str());
  std::ifstream md(out + "/summary.md");
  std::cout << "\n" << md.rdbuf() << "\nwritten to " << out << "\n";
  if (!args.count("plots") || args["plots"] != "false") {
    // The study's plots (top view, errors with 3-sigma, NEES) with Debian's Python (matplotlib).
    const std::string cmd =
        "/usr/bin/python3 '" + std::string(VI_EKF_SLAM_SOURCE_DIR) + "/tools/plot_run.py' '" + out + "'";
    if (std::system(cmd.c_str()) != 0) std::cerr << "warning: plotting failed: " << cmd << "\n";
  }
  return 0;
}
