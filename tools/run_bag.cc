// Offline mode: runs the node's own EkfSlamProcessor over a bag through the rosbag API, as fast
// as the CPU allows and deterministically (messages in bag order, no threads, no master), and
// evaluates the result against the bag's ground truth.
//
//   vi_ekf_slam_run_bag bag:=FILE [out:=DIR] [config:=YAML] [rig:=YAML] [mechanization:=NAME|all] [plots:=false]
//                       [reference:=FILE.tum[,FILE2.tum] [reference_alignment:=sim3|se3|posyaw]
//                        [reference_frame:=body|camera] [reference_clock:=imu|camera] [reference_from_s:=S]]
//                       [NAME:=VALUE ...]
// (the reference_* options take one value for every file or one per file, comma-separated;
// reference_from_s:= compares only the poses from S seconds after the bag's start, for a reference
// whose first seconds are less trustworthy)
//   vi_ekf_slam_run_bag bag:=FILE recorded:=NAME=REC.bag[,NAME=REC.bag...] [out:=DIR]
// The second form evaluates recordings of live replays (odom, status, landmarks of the node)
// against the same input bag, with the same metrics.
//
// What needs no ground truth is always reported (health.json, health.md, <run>_trace.csv): path
// length, speed, tracks, accepted/rejected observations, NIS per dof, time offset, resets, time
// per image. reference:= compares with any TUM trajectory (evo-style alignment; the reference's
// poses are of the IMU (body) or of the camera, stamped on the IMU or on the camera clock).
// With ground truth in the bag: <run>_timeseries.csv, summary.json, summary.md (ATE, NEES, ...).
// rig:= loads a rig file (calibration values) on top of config:= (default config/vi_ekf_slam.yaml).
// Writes to out (default results/run_bag/<bag name>) with <run>.tum and the plots of
// tools/plot_run.py (plots:=false to skip them).
// Inputs: imu_topic:=, image_topic:= (sensor_msgs/Image or CompressedImage) and
// camera_info_topic:= pick the topics; by default the one topic of each type the bag has (with
// several, the tool says which and asks to choose).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <optional>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <ros/package.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2/buffer_core.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>
#include <nlohmann/json.hpp>
#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <set>
#include <sstream>

#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/eval/reference_comparison.h"
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
    if (!poses.empty()) trace.push_back({poses.back().t, poses.back().p, s});
  }
  std::vector<int> tracks;
  struct TraceRow {
    double t;  ///< [s] IMU clock
    Vec3 p;    ///< [m] body position in the output frame
    vi_ekf_slam::FilterStatus status;
  };
  std::vector<TraceRow> trace;  ///< every processed image, across resets
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

/// What a run says about itself without ground truth.
nlohmann::json healthOf(const RecordingSink& sink, double bag_s, double wall_s) {
  nlohmann::json h;
  const auto& tr = sink.trace;
  double path = 0.0, tracks = 0.0, accepted = 0.0, rejected = 0.0, nis = 0.0, ms = 0.0, tracker_ms = 0.0;
  int nis_n = 0, min_tracks = tr.empty() ? 0 : 1 << 30;
  std::vector<double> speeds;
  for (size_t i = 0; i < tr.size(); ++i) {
    const auto& s = tr[i].status;
    tracks += s.tracks;
    min_tracks = std::min(min_tracks, s.tracks);
    accepted += s.accepted_observations;
    rejected += s.rejected_observations;
    ms += s.update_time_ms;
    tracker_ms += s.tracker_time_ms;
    if (s.accepted_observations > 0) {
      nis += s.nis_per_dof;
      ++nis_n;
    }
    if (i > 0 && tr[i - 1].status.resets == s.resets && tr[i].t > tr[i - 1].t) {
      const double d = (tr[i].p - tr[i - 1].p).norm();
      path += d;
      speeds.push_back(d / (tr[i].t - tr[i - 1].t));
    }
  }
  const double n = std::max<double>(1.0, static_cast<double>(tr.size()));
  std::sort(speeds.begin(), speeds.end());
  h["images"] = tr.size();
  h["resets"] = sink.resets;
  h["path_length_m"] = path;
  h["speed_p99_mps"] = speeds.empty() ? 0.0 : speeds[static_cast<size_t>(0.99 * (speeds.size() - 1))];
  h["tracks_mean"] = tracks / n;
  h["tracks_min"] = min_tracks;
  h["accepted_per_image"] = accepted / n;
  h["rejected_per_image"] = rejected / n;
  h["rejected_fraction"] = accepted + rejected > 0 ? rejected / (accepted + rejected) : 0.0;
  h["nis_per_dof_mean"] = nis_n ? nis / nis_n : 0.0;
  h["time_offset_s"] = tr.empty() ? 0.0 : tr.back().status.time_offset_s;
  h["time_offset_sigma_s"] = tr.empty() ? 0.0 : tr.back().status.time_offset_sigma_s;
  h["processing_ms_mean"] = ms / n;
  h["tracker_ms_mean"] = tracker_ms / n;
  h["reading_ms_mean"] = tr.empty() ? 0.0 : std::max(0.0, 1000.0 * wall_s / n - ms / n);
  h["real_time_factor"] = wall_s > 0.0 ? bag_s / wall_s : 0.0;  // offline: bag reading included
  return h;
}

void printHealth(const std::string& name, const nlohmann::json& h) {
  std::printf(
      "%s: %d images, %d resets, path %.2f m (speed p99 %.2f m/s), tracks per image %.1f (min %d), observations "
      "per image %.1f accepted / %.1f rejected, NIS per dof %.2f, time offset %.4f +- %.4f s\n"
      "  per image: %.2f ms processing, of which %.2f ms tracking; bag reading and the rest %.2f ms (%.1fx real "
      "time)\n",
      name.c_str(), h["images"].get<int>(), h["resets"].get<int>(), h["path_length_m"].get<double>(),
      h["speed_p99_mps"].get<double>(), h["tracks_mean"].get<double>(), h["tracks_min"].get<int>(),
      h["accepted_per_image"].get<double>(), h["rejected_per_image"].get<double>(), h["nis_per_dof_mean"].get<double>(),
      h["time_offset_s"].get<double>(), h["time_offset_sigma_s"].get<double>(), h["processing_ms_mean"].get<double>(),
      h["tracker_ms_mean"].get<double>(), h["reading_ms_mean"].get<double>(), h["real_time_factor"].get<double>());
}

std::string healthTable(const nlohmann::json& health) {
  std::ostringstream md;
  md << "| run | images | resets | path [m] | speed p99 [m/s] | tracks | accepted | rejected | NIS/dof | time "
        "offset [s] | ms/image | real-time factor | ref. RMSE [m] | ref. scale | ref. rot [deg] |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
     << std::fixed;
  for (const auto& [name, h] : health.items()) {
    if (name == "config") continue;
    md << "| " << name << " | " << h["images"].get<int>() << " | " << h["resets"].get<int>() << " | "
       << std::setprecision(2) << h["path_length_m"].get<double>() << " | " << h["speed_p99_mps"].get<double>() << " | "
       << std::setprecision(1) << h["tracks_mean"].get<double>() << " | " << h["accepted_per_image"].get<double>()
       << " | " << h["rejected_per_image"].get<double>() << " | " << std::setprecision(2)
       << h["nis_per_dof_mean"].get<double>() << " | " << std::setprecision(4) << h["time_offset_s"].get<double>()
       << " | " << std::setprecision(1) << h["processing_ms_mean"].get<double>() << " | "
       << h["real_time_factor"].get<double>() << " | ";
    if (h.contains("references") && h["references"][0].contains("position_rmse_m")) {
      const auto& r = h["references"][0];
      md << std::setprecision(3) << r["position_rmse_m"].get<double>() << " | "
         << r["scale_reference_units_per_m"].get<double>() << " | " << std::setprecision(2)
         << r["rotation_rmse_deg"].get<double>() << " |\n";
    } else {
      md << "- | - | - |\n";
    }
  }
  return md.str();
}

void writeTrace(const std::string& path, const RecordingSink& sink) {
  std::ofstream f(path);
  f << "t,x,y,z,tracks,accepted,rejected,nis_per_dof,time_offset_s,time_offset_sigma_s,resets,processing_ms,"
       "tracker_ms,landmarks,new_landmarks,deferred,removed,stationary\n"
    << std::setprecision(12);
  for (const auto& r : sink.trace) {
    const auto& s = r.status;
    f << r.t << "," << r.p.x() << "," << r.p.y() << "," << r.p.z() << "," << s.tracks << "," << s.accepted_observations
      << "," << s.rejected_observations << "," << s.nis_per_dof << "," << s.time_offset_s << ","
      << s.time_offset_sigma_s << "," << s.resets << "," << s.update_time_ms << "," << s.tracker_time_ms << ","
      << s.landmarks_in_state << "," << s.new_landmarks << "," << s.deferred_features << "," << s.removed_landmarks
      << "," << static_cast<int>(s.stationary) << "\n";
  }
}

struct Reference {
  std::string path, frame, clock;
  eval::Alignment alignment = eval::Alignment::kSim3;
  double from_s = 0.0;  ///< compare from this long after the bag's start [s]
  std::vector<eval::StampedPose> poses;
};

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

/// reference:=A[,B...] with reference_frame/_clock/_alignment:= one value or one per file.
std::vector<Reference> parseReferences(std::map<std::string, std::string>& args) {
  std::vector<Reference> refs;
  if (!args.count("reference")) return refs;
  const auto files = splitList(args["reference"]);
  auto pick = [&](const std::string& key, const std::string& fallback, size_t i) {
    const auto v = args.count(key) ? splitList(args[key]) : std::vector<std::string>{fallback};
    if (v.size() != 1 && v.size() != files.size()) throw std::runtime_error(key + ":= needs one value or one per file");
    return v.size() == 1 ? v[0] : v[i];
  };
  for (size_t i = 0; i < files.size(); ++i) {
    Reference r;
    r.path = files[i];
    r.frame = pick("reference_frame", "body", i);
    r.clock = pick("reference_clock", "imu", i);
    const auto a = eval::alignmentFromString(pick("reference_alignment", "sim3", i));
    if (!a || (r.frame != "body" && r.frame != "camera") || (r.clock != "imu" && r.clock != "camera")) {
      throw std::runtime_error(
          "reference_alignment:= sim3|se3|posyaw, reference_frame:= body|camera, reference_clock:= imu|camera");
    }
    r.alignment = *a;
    const std::string from = pick("reference_from_s", "0", i);
    char* end = nullptr;
    r.from_s = std::strtod(from.c_str(), &end);
    if (from.empty() || *end != '\0' || !std::isfinite(r.from_s) || r.from_s < 0.0)
      throw std::runtime_error("reference_from_s:= takes seconds >= 0");
    r.poses = eval::readTum(r.path);
    refs.push_back(std::move(r));
  }
  return refs;
}

/// The estimate as the reference sees it: the camera's poses (through the bag's extrinsic) or the
/// body's, stamped on the IMU clock or on the camera clock (minus the estimated time offset).
std::vector<eval::StampedPose> referenceView(const RecordingSink& sink, const glue::InputBagInfo& info,
                                             const std::string& frame, const std::string& clock) {
  if (frame == "camera" && !info.T_b_c) throw std::runtime_error("the bag has no camera-IMU extrinsic");
  std::map<double, double> offset_at;
  for (const auto& r : sink.trace) offset_at[r.t] = r.status.time_offset_s;
  std::vector<eval::StampedPose> poses;
  std::vector<double> offsets;
  for (const auto& p : sink.poses) {
    poses.push_back({p.t, p.p, p.q, std::nullopt});
    const auto it = offset_at.find(p.t);
    offsets.push_back(it != offset_at.end() ? it->second : 0.0);
  }
  return eval::referenceView(poses, frame == "camera" ? info.T_b_c : std::nullopt,
                             clock == "camera" ? &offsets : nullptr);
}

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

/// The topics the processor is fed from.
struct InputTopics {
  std::string imu, image, camera_info;
};

/// imu_topic:=, image_topic:=, camera_info_topic:= as given (checked against the bag), or the one
/// topic of each type the bag holds; several, or none, is an error that lists them.
InputTopics chooseInputTopics(const std::string& bag_path, std::map<std::string, std::string>& args) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  std::map<std::string, std::string> types;  // topic -> datatype
  for (const rosbag::ConnectionInfo* c : view.getConnections()) types[c->topic] = c->datatype;
  auto choose = [&](const std::string& arg, const std::vector<std::string>& accepted) {
    std::vector<std::string> found;
    for (const auto& [topic, type] : types) {
      if (std::find(accepted.begin(), accepted.end(), type) != accepted.end()) found.push_back(topic);
    }
    std::string list;
    for (const auto& t : found) list += " " + t + " (" + types[t] + ")";
    if (args.count(arg)) {
      const std::string& t = args[arg];
      if (std::find(found.begin(), found.end(), t) == found.end()) {
        throw std::runtime_error(arg + ":=" + t + " is not a topic of type " + accepted.front() +
                                 " in the bag; it has:" + (list.empty() ? std::string(" none") : list));
      }
      return t;
    }
    if (found.size() != 1) {
      throw std::runtime_error("the bag has " + std::to_string(found.size()) + " topics of type " + accepted.front() +
                               (list.empty() ? std::string("") : ":" + list) + "; choose one with " + arg + ":=");
    }
    return found.front();
  };
  InputTopics t;
  t.imu = choose("imu_topic", {"sensor_msgs/Imu"});
  t.image = choose("image_topic", {"sensor_msgs/Image", "sensor_msgs/CompressedImage"});
  // camera_info is optional (camera_calibration_file:= may give the intrinsics instead).
  try {
    t.camera_info = choose("camera_info_topic", {"sensor_msgs/CameraInfo"});
  } catch (const std::exception&) {
    if (args.count("camera_info_topic")) throw;
  }
  return t;
}

int main(int argc, char** argv) {
  ros::Time::init();  // no master: wall time for the (throttled) log messages only
  std::map<std::string, std::string> args;
  const char* const usage =
      "usage: vi_ekf_slam_run_bag bag:=FILE [out:=DIR] [config:=YAML] [rig:=YAML] [mechanization:=NAME|all] "
      "[imu_topic:=T] [image_topic:=T] [camera_info_topic:=T] [plots:=false] [reference:=FILE.tum[,...] "
      "[reference_alignment:=sim3|se3|posyaw] [reference_frame:=body|camera] [reference_clock:=imu|camera] "
      "[reference_from_s:=S]] "
      "[PARAM:=VALUE ...]\n"
      "       vi_ekf_slam_run_bag bag:=FILE recorded:=NAME=REC.bag[,...] [out:=DIR]\n"
      "Runs the node's processor over a bag offline (deterministic, as fast as the CPU allows) and evaluates it.\n";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::cout << usage;
      return 0;
    }
    const auto k = a.find(":=");
    if (k == std::string::npos) {
      std::cerr << "arguments are NAME:=VALUE (got '" << a << "')\n";
      return 2;
    }
    args[a.substr(0, k)] = a.substr(k + 2);
  }
  if (!args.count("bag")) {
    std::cerr << "error: bag:= is missing\n" << usage;
    return 2;
  }
  const std::string bag_path = args["bag"];
  const std::string out = args.count("out") ? args["out"] : "results/run_bag/" + fs::path(bag_path).stem().string();
  // The package's default configuration, found as any ROS tool finds a package (devel space or
  // installed), never in the source tree the binary was built from.
  std::string config = args.count("config") ? args["config"] : "";
  if (config.empty()) {
    const std::string share = ros::package::getPath("vi_ekf_slam");
    if (share.empty()) {
      std::cerr << "error: the package vi_ekf_slam is not on ROS_PACKAGE_PATH (source setup.bash) and no config:= "
                   "was given\n";
      return 2;
    }
    config = share + "/config/vi_ekf_slam.yaml";
  }
  std::vector<std::string> mechanizations;
  const std::string mech = args.count("mechanization") ? args["mechanization"] : "";
  if (mech == "all")
    mechanizations = {"world_centric", "sensor_centric", "sensor_centric_composition"};
  else
    mechanizations = {mech};

  // reference:=A.tum[,B.tum...]; reference_frame / reference_clock / reference_alignment give one
  // value for all or one per file.
  std::vector<Reference> references;
  try {
    references = parseReferences(args);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  nlohmann::json health;

  glue::InputBagInfo info;
  try {
    info = glue::readInputBag(bag_path);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  InputTopics inputs;
  try {
    inputs = chooseInputTopics(bag_path, args);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
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
        glue::YamlParams y(config);
        if (args.count("rig")) y.overlay(glue::YamlParams(args["rig"]));
        return y;
      } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        std::exit(1);
      }
    }();
    // Every other name:=value is a node parameter (an unknown one is refused with the closest name).
    static const std::set<std::string> kOwn = {"bag",   "out",      "config",    "rig",         "mechanization",
                                               "plots", "recorded", "imu_topic", "image_topic", "camera_info_topic"};
    for (const auto& [k, v] : args) {
      if (!kOwn.count(k) && k.rfind("reference", 0) != 0) yaml.set(k, v);
    }
    if (!m.empty()) yaml.set("mechanization", m);
    glue::NodeParams params;
    const std::string err = glue::loadParams(yaml, &params);
    if (!err.empty()) {
      std::cerr << "impossible parameter values:\n" << err;
      return 1;
    }
    // The evaluation is of the filter in its own world, which restarts at every reset (and so does
    // the evaluated segment); the node's odom frame would join the segments.
    params.node.publish_tf = glue::TfMode::kWorld;
    const std::string name = toString(params.filter.mechanization);
    RecordingSink sink;
    tf2::BufferCore tf;
    glue::EkfSlamProcessor processor(params, sink, &tf);
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    rosbag::View view(bag);
    const auto tic = std::chrono::steady_clock::now();
    for (const rosbag::MessageInstance& msg : view) {
      const std::string& topic = msg.getTopic();
      if (topic == inputs.imu) {
        if (auto imu = msg.instantiate<sensor_msgs::Imu>()) processor.imu(*imu);
      } else if (topic == inputs.image) {
        if (auto img = msg.instantiate<sensor_msgs::Image>()) {
          processor.image(*img);
        } else if (auto c = msg.instantiate<sensor_msgs::CompressedImage>()) {
          try {
            processor.image(*cv_bridge::toCvCopy(*c, "mono8")->toImageMsg());
          } catch (const std::exception& e) {
            std::cerr << "warning: compressed image at " << c->header.stamp << " not decoded: " << e.what() << "\n";
          }
        }
      } else if (topic == inputs.camera_info) {
        if (auto ci = msg.instantiate<sensor_msgs::CameraInfo>()) processor.cameraInfo(*ci);
      } else if (topic == "/tf_static" || topic == "/tf") {
        if (auto t = msg.instantiate<tf2_msgs::TFMessage>()) {
          for (const auto& tr : t->transforms) tf.setTransform(tr, "bag", topic == "/tf_static");
        }
      }
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - tic).count();
    const double bag_s = info.end - info.start;
    fs::create_directories(out);
    std::vector<eval::StampedPose> traj;
    for (const auto& p : sink.poses) traj.push_back({p.t, p.p, p.q, p.cov});
    eval::writeTum(out + "/" + name + ".tum", traj,
                   "t x y z qx qy qz qw (body in the filter's world frame, IMU clock)");
    health[name] = healthOf(sink, bag_s, wall);
    writeTrace(out + "/" + name + "_trace.csv", sink);
    printHealth(name, health[name]);
    nlohmann::json comparisons = nlohmann::json::array();
    for (size_t k = 0; k < references.size(); ++k) {
      const Reference& ref = references[k];
      nlohmann::json j = {
          {"file", ref.path}, {"frame", ref.frame}, {"clock", ref.clock}, {"alignment", eval::toString(ref.alignment)}};
      if (sink.poses.empty()) {
        std::printf("  against %s: no pose since the last reset (lost, not re-initialized)\n", ref.path.c_str());
        j["error"] = "no pose since the last reset";
        comparisons.push_back(j);
        continue;
      }
      try {
        std::vector<eval::StampedPose> view = referenceView(sink, info, ref.frame, ref.clock);
        if (ref.from_s > 0.0) {
          j["from_s"] = ref.from_s;
          const double from = info.start + ref.from_s;
          view.erase(std::remove_if(view.begin(), view.end(), [&](const eval::StampedPose& p) { return p.t < from; }),
                     view.end());
        }
        const eval::ReferenceComparison c = eval::compareWithReference(view, ref.poses, ref.alignment);
        j.update({{"matched", c.matched},
                  {"position_rmse_m", c.position_rmse_m},
                  {"rotation_rmse_deg", c.rotation_rmse_deg},
                  {"scale_reference_units_per_m", c.scale},
                  {"estimate_path_m", c.estimate_path_m},
                  {"reference_path_m", c.reference_path_m}});
        char from_text[48] = "";
        if (ref.from_s > 0.0) std::snprintf(from_text, sizeof(from_text), ", from %g s", ref.from_s);
        std::printf(
            "  against %s (%s, %s poses, %s clock%s): %d matched, position RMSE %.3f m, rotation RMSE %.2f deg, "
            "scale %.3f reference units per metre, path %.2f m (reference %.2f m)\n",
            ref.path.c_str(), eval::toString(c.alignment).c_str(), ref.frame.c_str(), ref.clock.c_str(), from_text,
            c.matched, c.position_rmse_m, c.rotation_rmse_deg, c.scale, c.estimate_path_m, c.reference_path_m);
        std::ofstream rc(out + "/" + name + "_reference" + (k ? std::to_string(k + 1) : "") + ".csv");
        rc << "t,ex,ey,ez,rx,ry,rz\n" << std::setprecision(12);
        for (size_t i = 0; i < c.t.size(); ++i) {
          rc << c.t[i] << "," << c.estimate[i].x() << "," << c.estimate[i].y() << "," << c.estimate[i].z() << ","
             << c.reference[i].x() << "," << c.reference[i].y() << "," << c.reference[i].z() << "\n";
        }
      } catch (const std::exception& e) {
        std::printf("  against %s: not comparable: %s\n", ref.path.c_str(), e.what());
        j["error"] = e.what();
      }
      comparisons.push_back(j);
    }
    if (!references.empty()) health[name]["references"] = comparisons;
    if (info.truth.empty()) continue;
    std::vector<eval::EstimatedLandmark> lms;
    for (const auto& [id, l] : sink.map) lms.push_back(l);
    eval::RunMetrics metrics = eval::evaluateRun(sink.poses, info.truth, lms, glue::landmarkTruthFromWorld(info));
    std::printf("  against the bag's ground truth: ATE %.3f m, final %.3f m (%.2f%%)\n", metrics.ate_position_m,
                metrics.final_position_error_m, metrics.final_position_error_pct);
    metrics.real_time_factor = bag_s / wall;  // offline: the whole pipeline, bag reading included
    results.emplace_back(name, metrics);
  }
  {
    health["config"] = {
        {"bag", bag_path}, {"config", config}, {"mode", args.count("recorded") ? "live replay" : "offline"}};
    std::ofstream hj(out + "/health.json");
    hj << health.dump(2) << "\n";
    std::ofstream hm(out + "/health.md");
    hm << healthTable(health);
    std::cout << "\n" << healthTable(health);
  }
  if (!results.empty()) {
    eval::writeRunReport(
        out, results,
        {{"bag", bag_path}, {"config", config}, {"mode", args.count("recorded") ? "live replay" : "offline"}});
    std::ifstream md(out + "/summary.md");
    std::cout << "\nagainst the bag's ground truth:\n" << md.rdbuf();
  } else {
    fs::remove(out + "/summary.json");  // a stale one from an earlier run with ground truth
    std::cout << "\nthe bag has no ground truth (" << glue::RigTopics().ground_truth
              << "): no ATE or NEES; use reference:=FILE.tum to compare with a trajectory\n";
  }
  std::cout << "written to " << out << "\n";
  if (!args.count("plots") || args["plots"] != "false") {
    // Top view, speed, NIS, time offset and tracks over time (and, with ground truth, errors with
    // 3-sigma and NEES) with Debian's Python (matplotlib).
    // plot_run.py is installed beside this program (devel and install spaces alike).
    std::error_code ec;
    const fs::path script = fs::read_symlink("/proc/self/exe", ec).parent_path() / "plot_run.py";
    const std::string cmd = "/usr/bin/python3 '" + script.string() + "' '" + out + "'";
    if (ec || !fs::exists(script)) {
      std::cerr << "warning: no plots: " << script << " not found\n";
    } else if (std::system(cmd.c_str()) != 0) {
      std::cerr << "warning: plotting failed: " << cmd << "\n";
    }
  }
  return 0;
}
