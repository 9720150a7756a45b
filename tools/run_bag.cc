// Offline mode: runs the node's own EkfSlamProcessor over a bag through the rosbag API, as fast
// as the CPU allows and deterministically (messages in bag order, no threads, no master), and
// evaluates the result: against the bag's ground truth (summary.json / summary.md /
// <run>_timeseries.csv: ATE, NEES, ...), against reference trajectories (--reference, evo-style
// alignment), and what needs no ground truth (health.json / health.md / <run>_trace.csv). The
// second form (--recorded) evaluates recordings of live replays of the same bag with the same
// metrics. vi_ekf_slam_run_bag --help lists the options; docs/evaluation.md explains them.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <ros/package.h>
#include <sstream>

#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/eval/progress.h"
#include "vi_ekf_slam/eval/reference_comparison.h"
#include "vi_ekf_slam/eval/run_evaluation.h"
#include "vi_ekf_slam/eval/run_health.h"
#include "vi_ekf_slam/io/tum_io.h"
#include "vi_ekf_slam/ros/bag_io.h"
#include "vi_ekf_slam/ros/bag_replay.h"
#include "vi_ekf_slam/ros/console_progress.h"
#include "cli.h"

using namespace vi_ekf_slam;
namespace fs = std::filesystem;
namespace po = cli::po;

namespace {

struct Reference {
  std::string path, frame, clock;
  eval::Alignment alignment = eval::Alignment::kSim3;
  double from_s = 0.0;  ///< compare from this long after the bag's start [s]
  std::vector<io::StampedPose> poses;
};

/// The estimate as the reference sees it: the camera's poses (through the bag's extrinsic) or the
/// body's, stamped on the IMU clock or on the camera clock (minus the estimated time offset).
std::vector<io::StampedPose> referenceView(const glue::RecordingSink& sink, const glue::InputBagInfo& info,
                                           const std::string& frame, const std::string& clock) {
  if (frame == "camera" && !info.T_b_c) throw std::runtime_error("the bag has no camera-IMU extrinsic");
  std::map<double, double> offset_at;
  for (const auto& r : sink.trace) offset_at[r.t] = r.time_offset_s;
  std::vector<io::StampedPose> poses;
  std::vector<double> offsets;
  for (const auto& p : sink.poses) {
    poses.push_back({p.t, p.p, p.q, std::nullopt});
    const auto it = offset_at.find(p.t);
    offsets.push_back(it != offset_at.end() ? it->second : 0.0);
  }
  return eval::referenceView(poses, frame == "camera" ? info.T_b_c : std::nullopt,
                             clock == "camera" ? &offsets : nullptr);
}

/// A calibration given wrong on purpose: the parameters' T_b_c turned by deg about `turn` (in the
/// body frame, R_b_c' = Exp(deg turn) R_b_c) and moved by m along `move`.
struct ExtrinsicError {
  double deg = 0.0, m = 0.0;
  Vec3 turn = Vec3::UnitX(), move = Vec3::UnitY();
};

/// The command line.
struct Options {
  std::string bag, out, config, rig, mechanization;
  std::optional<std::string> imu_topic, image_topic, camera_info_topic;
  bool plots = true;
  bool segments = false;  ///< also each segment in the filter's own world
  std::vector<std::string> references, reference_alignment, reference_frame, reference_clock, reference_from_s;
  double reference_window_s = 10.0;   ///< each reference also per window of this long, aligned on its own
  std::vector<std::string> recorded;  ///< NAME=BAG
  std::vector<std::string> params;    ///< name=value
  std::vector<double> reset_at_s;     ///< forced resets (the ~reset service), seconds after the bag's start
  bool save_map = false;              ///< write the kept map to map_file at the end (~save_map)
  std::optional<ExtrinsicError> extrinsic_error;
};

/// Parses argv into *o (--help and usage errors exit, as every tool's).
void parseArguments(int argc, char** argv, Options* o) {
  const std::string usage =
      "vi_ekf_slam_run_bag --bag FILE [--out DIR] [--config YAML] [--rig NAME|YAML] [--param NAME=VALUE ...] "
      "[--mechanization NAME|all] [--reference FILE.tum ...]\n"
      "       vi_ekf_slam_run_bag --bag FILE --recorded NAME=REC.bag [--recorded ...] [--out DIR]";
  po::options_description d("options");
  std::string imu, image, info, extrinsic_error;
  bool no_plots = false;
  d.add_options()("bag", po::value(&o->bag)->required(), "the input bag")(
      "out", po::value(&o->out), "output directory (default results/run_bag/<bag name>)")(
      "config", po::value(&o->config), "node parameters, YAML (default: the package's config/vi_ekf_slam.yaml)")(
      "rig", po::value(&o->rig),
      "a rig preset (NAME of config/rigs/NAME.yaml) or the path of a rig file, on top of "
      "--config")("param", po::value(&o->params)->composing(), "NAME=VALUE: one node parameter (repeatable)")(
      "mechanization", po::value(&o->mechanization),
      "world_centric | sensor_centric | sensor_centric_composition | all")(
      "imu-topic", po::value(&imu), "sensor_msgs/Imu topic (default: the bag's one)")(
      "image-topic", po::value(&image), "sensor_msgs/Image or CompressedImage topic (default: the bag's one)")(
      "camera-info-topic", po::value(&info), "sensor_msgs/CameraInfo topic (default: the bag's one, if any)")(
      "no-plots", po::bool_switch(&no_plots), "skip the plots of plot_run.py")(
      "segments", po::bool_switch(&o->segments),
      "also <run>_segment_<k>.tum: the poses after the k-th reset in the filter's own world")(
      "reference", po::value(&o->references)->composing(),
      "a trajectory to compare with: TUM, or EuRoC's state_groundtruth_estimate0/data.csv (repeatable)")(
      "reference-alignment", po::value(&o->reference_alignment)->composing(),
      "sim3 | se3 | posyaw: once for all references or once per reference (default sim3)")(
      "reference-frame", po::value(&o->reference_frame)->composing(),
      "body | camera: whose poses the reference holds (default body)")(
      "reference-clock", po::value(&o->reference_clock)->composing(),
      "imu | camera: the clock of the reference's stamps (default imu)")(
      "reference-from-s", po::value(&o->reference_from_s)->composing(),
      "compare only from this many seconds after the bag's start (default 0)")(
      "reference-window-s", po::value(&o->reference_window_s)->default_value(10.0),
      "also compare in consecutive windows of this many seconds, each aligned on its own: the scale per "
      "window, and the first's over the later ones' median (0: not)")(
      "recorded", po::value(&o->recorded)->composing(), "NAME=REC.bag: a recording of a live replay (repeatable)")(
      "reset-at", po::value(&o->reset_at_s)->composing(),
      "reset the filter (as the ~reset service does) this many seconds after the bag's start (repeatable)")(
      "save-map", po::bool_switch(&o->save_map),
      "at the end, write the kept map to the map_file parameter (as ~save_map does; needs keep_map)")(
      "extrinsic-error", po::value(&extrinsic_error),
      "DEG,M[,TX,TY,TZ,MX,MY,MZ]: the filter is given the parameters' T_b_c turned by DEG degrees about T (body "
      "frame; default x) and moved by M metres along M (default y); health.json says how far its estimate ends from "
      "the parameters' (needs extrinsic_source parameters)");
  const po::variables_map vm = cli::parse(
      argc, argv, usage,
      "Runs the node's processor over a bag offline (deterministic, as fast as the CPU allows) and evaluates it.", d);
  if (vm.count("imu-topic")) o->imu_topic = imu;
  if (vm.count("image-topic")) o->image_topic = image;
  if (vm.count("camera-info-topic")) o->camera_info_topic = info;
  if (vm.count("extrinsic-error")) {
    std::vector<double> v;
    std::stringstream ss(extrinsic_error);
    for (std::string item; std::getline(ss, item, ',');) {
      char* end = nullptr;
      v.push_back(std::strtod(item.c_str(), &end));
      if (item.empty() || *end != '\0' || !std::isfinite(v.back())) v.back() = std::nan("");
    }
    const bool finite = std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
    if (!finite || (v.size() != 2 && v.size() != 8))
      cli::fail(usage, "--extrinsic-error takes DEG,M or DEG,M,TX,TY,TZ,MX,MY,MZ");
    ExtrinsicError e;
    e.deg = v[0];
    e.m = v[1];
    if (v.size() == 8) {
      e.turn = Vec3(v[2], v[3], v[4]);
      e.move = Vec3(v[5], v[6], v[7]);
    }
    if (!(e.turn.norm() > 0.0) || !(e.move.norm() > 0.0)) cli::fail(usage, "--extrinsic-error: axes must not be zero");
    o->extrinsic_error = e;
  }
  o->plots = !no_plots;
  if (o->out.empty()) o->out = "results/run_bag/" + fs::path(o->bag).stem().string();
}

/// The references with their options (one value for all or one per reference).
std::vector<Reference> readReferences(const Options& o) {
  auto pick = [&](const std::vector<std::string>& v, const std::string& option, const std::string& fallback, size_t i) {
    if (v.empty()) return fallback;
    if (v.size() != 1 && v.size() != o.references.size())
      throw std::runtime_error(option + " needs one value or one per --reference");
    return v.size() == 1 ? v[0] : v[i];
  };
  std::vector<Reference> refs;
  for (size_t i = 0; i < o.references.size(); ++i) {
    Reference r;
    r.path = o.references[i];
    r.frame = pick(o.reference_frame, "--reference-frame", "body", i);
    r.clock = pick(o.reference_clock, "--reference-clock", "imu", i);
    const auto a = eval::alignmentFromString(pick(o.reference_alignment, "--reference-alignment", "sim3", i));
    if (!a || (r.frame != "body" && r.frame != "camera") || (r.clock != "imu" && r.clock != "camera")) {
      throw std::runtime_error(
          "--reference-alignment sim3|se3|posyaw, --reference-frame body|camera, --reference-clock imu|camera");
    }
    r.alignment = *a;
    const std::string from = pick(o.reference_from_s, "--reference-from-s", "0", i);
    char* end = nullptr;
    r.from_s = std::strtod(from.c_str(), &end);
    if (from.empty() || *end != '\0' || !std::isfinite(r.from_s) || r.from_s < 0.0)
      throw std::runtime_error("--reference-from-s takes seconds >= 0");
    r.poses = io::readTrajectoryFile(r.path);  // TUM, or EuRoC's ground-truth CSV
    refs.push_back(std::move(r));
  }
  return refs;
}

/// The package's files, found as any ROS tool finds a package (devel space or installed), never in
/// the source tree the binary was built from.
std::string packageShare() {
  const std::string share = ros::package::getPath("vi_ekf_slam");
  if (share.empty()) {
    throw std::runtime_error(
        "the package vi_ekf_slam is not on ROS_PACKAGE_PATH (source setup.bash) for its config and rig presets");
  }
  return share;
}

/// T_b_c (x y z qx qy qz qw) as the parameters hold it.
CameraExtrinsics extrinsicOf(const std::vector<double>& v) {
  CameraExtrinsics T;
  T.p_b_c = Vec3(v[0], v[1], v[2]);
  T.R_b_c = Quat(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
  return T;
}

/// How far apart two extrinsics are: rotation [deg] and translation [m].
nlohmann::ordered_json extrinsicDistance(const CameraExtrinsics& a, const CameraExtrinsics& b) {
  return {{"deg", rotationError(Quat(a.R_b_c), Quat(b.R_b_c)).norm() * 180.0 / M_PI},
          {"m", (a.p_b_c - b.p_b_c).norm()}};
}

/// The node's parameters: --config, --rig over it, each --param, the mechanization (and, with
/// --extrinsic-error, the wrong calibration the filter is given).
glue::NodeParams nodeParams(const Options& o, const std::string& mechanization) {
  glue::YamlParams yaml(o.config);
  if (!o.rig.empty()) yaml.overlay(glue::YamlParams(glue::rigFile(o.rig, ros::package::getPath("vi_ekf_slam"))));
  for (const std::string& p : o.params) {
    const auto eq = p.find('=');
    if (eq == std::string::npos || eq == 0) throw std::runtime_error("--param takes name=value (got '" + p + "')");
    yaml.set(p.substr(0, eq), p.substr(eq + 1));  // an unknown name is refused with the closest one
  }
  if (!mechanization.empty()) yaml.set("mechanization", mechanization);
  glue::NodeParams params;
  const std::string err = glue::loadParams(yaml, &params);
  if (!err.empty()) throw std::runtime_error("impossible parameter values:\n" + err);
  // The whole run in the node's continuous odom frame (of the IMU): a reset continues from the last
  // pose, and is marked in <run>_events.csv.
  params.node.publish_tf = glue::TfMode::kOdom;
  params.node.base_frame.clear();
  if (o.extrinsic_error) {
    if (params.node.extrinsic_source != "parameters")
      throw std::runtime_error("--extrinsic-error needs extrinsic_source parameters (T_b_c in the rig file)");
    const ExtrinsicError& e = *o.extrinsic_error;
    CameraExtrinsics T = extrinsicOf(params.node.T_b_c);
    T.R_b_c = expSO3(e.deg * M_PI / 180.0 * e.turn.normalized()) * T.R_b_c;
    T.p_b_c += e.m * e.move.normalized();
    const Quat q(T.R_b_c);
    params.node.T_b_c = {T.p_b_c.x(), T.p_b_c.y(), T.p_b_c.z(), q.x(), q.y(), q.z(), q.w()};
  }
  return params;
}

/// One reference comparison of the run, printed, with its matched positions as CSV.
nlohmann::ordered_json compareRun(const glue::RecordingSink& sink, const glue::InputBagInfo& info, const Reference& ref,
                                  double window_s, const std::string& csv) {
  nlohmann::ordered_json j = {
      {"file", ref.path}, {"frame", ref.frame}, {"clock", ref.clock}, {"alignment", eval::toString(ref.alignment)}};
  if (sink.poses.empty()) {
    std::printf("  against %s: no pose (never initialized)\n", ref.path.c_str());
    j["error"] = "no pose";
    return j;
  }
  try {
    std::vector<io::StampedPose> view = referenceView(sink, info, ref.frame, ref.clock);
    if (ref.from_s > 0.0) {
      j["from_s"] = ref.from_s;
      const double from = info.start + ref.from_s;
      view.erase(std::remove_if(view.begin(), view.end(), [&](const io::StampedPose& p) { return p.t < from; }),
                 view.end());
    }
    const eval::ReferenceComparison c = eval::compareWithReference(view, ref.poses, ref.alignment);
    j.update({{"matched", c.matched},
              {"position_rmse_m", c.position_rmse_m},
              {"position_rmse_reference_units", c.position_rmse_reference_units},
              {"rotation_rmse_deg", c.rotation_rmse_deg},
              {"scale_reference_units_per_m", c.scale},
              {"estimate_path_m", c.estimate_path_m},
              {"reference_path_m", c.reference_path_m}});
    char from_text[48] = "";
    if (ref.from_s > 0.0) std::snprintf(from_text, sizeof(from_text), ", from %g s", ref.from_s);
    std::printf(
        "  against %s (%s, %s poses, %s clock%s): %d matched, position RMSE %.3f m (%.3f reference units, as "
        "evo_ape), rotation RMSE %.2f deg, scale %.3f reference units per metre, path %.2f m (reference %.2f m)\n",
        ref.path.c_str(), eval::toString(c.alignment).c_str(), ref.frame.c_str(), ref.clock.c_str(), from_text,
        c.matched, c.position_rmse_m, c.position_rmse_reference_units, c.rotation_rmse_deg, c.scale, c.estimate_path_m,
        c.reference_path_m);
    // A scale that changes along the run (a start mapped at the wrong scale) shows per window.
    const std::vector<eval::WindowComparison> windows =
        eval::compareInWindows(view, ref.poses, ref.alignment, window_s);
    if (windows.size() >= 2) {
      nlohmann::ordered_json w = nlohmann::ordered_json::array();
      std::string scales;
      for (const auto& x : windows) {
        w.push_back({{"from_s", x.from_t - info.start},
                     {"to_s", x.to_t - info.start},
                     {"matched", x.comparison.matched},
                     {"scale_reference_units_per_m", x.comparison.scale},
                     {"position_rmse_m", x.comparison.position_rmse_m}});
        char one[32];
        std::snprintf(one, sizeof(one), "%s%.2f", scales.empty() ? "" : " ", x.comparison.scale);
        scales += one;
      }
      j["window_s"] = window_s;
      j["windows"] = w;
      const double first_ratio = eval::firstWindowScaleRatio(windows);
      j["first_window_scale_ratio"] = first_ratio;
      std::printf(
          "    in windows of %g s, each aligned on its own: scale %s; the first over the later ones' median %.2f\n",
          window_s, scales.c_str(), first_ratio);
    }
    std::ofstream rc(csv);
    rc << "t,ex,ey,ez,rx,ry,rz\n" << std::setprecision(12);
    for (size_t i = 0; i < c.t.size(); ++i) {
      rc << c.t[i] << "," << c.estimate[i].x() << "," << c.estimate[i].y() << "," << c.estimate[i].z() << ","
         << c.reference[i].x() << "," << c.reference[i].y() << "," << c.reference[i].z() << "\n";
    }
  } catch (const std::exception& e) {
    std::printf("  against %s: not comparable: %s\n", ref.path.c_str(), e.what());
    j["error"] = e.what();
  }
  return j;
}

/// The run's events (starts, resets and why), with the time of the pose before each.
void writeEvents(const std::string& path, const glue::RecordingSink& sink) {
  std::ofstream f(path);
  f << "t,event\n" << std::setprecision(12);
  for (const auto& e : sink.events) f << e.t << ",\"" << e.text << "\"\n";
}

/// The faults the processor met and rode through (or not), for the health report.
nlohmann::ordered_json inputCounters(const glue::InputCounters& c) {
  return {{"imu_nonfinite", c.imu_nonfinite},
          {"imu_clipped", c.imu_clipped},
          {"imu_implausible", c.imu_implausible},
          {"imu_gaps", c.imu_gaps},
          {"imu_stale", c.imu_stale},
          {"images_stale", c.images_stale},
          {"images_late", c.images_late},
          {"images_queue_dropped", c.images_queue_dropped},
          {"image_gaps", c.image_gaps},
          {"images_without_features", c.images_without_features},
          {"outlier_bursts", c.outlier_bursts},
          {"divergences", c.divergences}};
}

/// The extrinsic the filter estimated, and how far it moved from the one it was given.
nlohmann::ordered_json extrinsicReport(const EkfSlam& f) {
  const CameraExtrinsics& T = f.extrinsics();
  const CameraExtrinsics& T0 = f.calibratedExtrinsics();
  const Quat q(T.R_b_c);
  return {{"T_b_c", {T.p_b_c.x(), T.p_b_c.y(), T.p_b_c.z(), q.x(), q.y(), q.z(), q.w()}},
          {"moved_deg", rotationError(q, Quat(T0.R_b_c)).norm() * 180.0 / M_PI},
          {"moved_m", (T.p_b_c - T0.p_b_c).norm()}};
}

/// Throws when no image could be used: a camera that does not fit the bag's images (size,
/// encoding) or no image on the topic read must not end as an empty trajectory and exit 0.
void checkImagesUsed(const glue::EkfSlamProcessor& processor, const glue::InputTopics& topics) {
  const glue::InputCounters& c = processor.counters();
  if (c.images_received == 0) throw std::runtime_error("no image on " + topics.image + " (" + topics.image_why + ")");
  const long unusable = c.images_bad_encoding + c.images_no_camera;
  if (unusable < c.images_received) return;
  std::ostringstream m;
  m << "none of the " << c.images_received << " images on " << topics.image << " could be used ("
    << c.images_bad_encoding << " of an encoding the node does not read, " << c.images_no_camera
    << " without a camera calibration that fits them): " << processor.lastProblem()
    << ". Check the rig's camera (camera_resolution, intrinsics) against the bag's images.";
  throw std::runtime_error(m.str());
}

/// One mechanization over the bag: its trajectory, trace, health (into *health) and, with ground
/// truth, its metrics (into *results).
void runOne(const Options& o, const std::string& mechanization, const glue::InputBagInfo& info,
            const glue::InputTopics& topics, const std::vector<Reference>& refs, glue::ConsoleBesideProgress& console,
            eval::Report* health, std::vector<std::pair<std::string, eval::RunMetrics>>* results) {
  const glue::NodeParams params = nodeParams(o, mechanization);
  const std::string name = toString(params.filter.mechanization);
  glue::RecordingSink sink;
  tf2::BufferCore tf;
  glue::EkfSlamProcessor processor(params, sink, &tf);
  if (o.segments) sink.processor = &processor;
  const double bag_s = info.end - info.start;
  eval::Progress progress(name, bag_s);  // on a terminal only
  console.follow(&progress);
  std::vector<double> resets = o.reset_at_s;
  std::sort(resets.begin(), resets.end(), std::greater<>());  // the next one last
  const double wall = glue::replayBag(o.bag, topics, processor, tf, [&](double done, double) {
    progress.update(done);
    if (!resets.empty() && done >= resets.back()) {
      processor.reset("forced at " + std::to_string(resets.back()) + " s (--reset-at)");
      resets.pop_back();
    }
  });
  progress.finish();
  console.follow(nullptr);
  checkImagesUsed(processor, topics);
  if (o.save_map) {
    std::string message;
    const bool saved = processor.saveMap(&message);
    std::printf("  %s%s\n", saved ? "" : "map not saved: ", message.c_str());
    if (!saved) throw std::runtime_error("--save-map: " + message);
  }
  fs::create_directories(o.out);
  std::vector<io::StampedPose> traj;
  for (const auto& p : sink.poses) traj.push_back({p.t, p.p, p.q, p.cov});
  io::writeTum(o.out + "/" + name + ".tum", traj,
               "t x y z qx qy qz qw (body in the continuous odom frame, IMU clock; resets in " + name +
                   "_events.csv, covariances in " + name + "_covariance.txt)");
  io::writePoseCovariances(o.out + "/" + name + "_covariance.txt", traj);
  writeEvents(o.out + "/" + name + "_events.csv", sink);
  for (size_t k = 0; k < sink.segments.size(); ++k) {
    io::writeTum(o.out + "/" + name + "_segment_" + std::to_string(k) + ".tum", sink.segments[k],
                 "t x y z qx qy qz qw (body in the filter's world after reset " + std::to_string(k) + ", IMU clock)");
  }
  nlohmann::ordered_json& h = health->runs.rows[name] = eval::runHealth(sink.trace, sink.resets, bag_s, wall);
  h["output_s"] = sink.poses.size() > 1 ? sink.poses.back().t - sink.poses.front().t : 0.0;
  h["input_s"] = bag_s;
  h["inputs"] = inputCounters(processor.counters());
  if (params.filter.map.within_run && params.filter.map.across_runs) {
    h["relocalizations"] = processor.pipeline().relocalizations();
    h["map_points"] = processor.pipeline().map().size();
    std::printf("  kept map: %d points across resets, %d relocalizations\n", processor.pipeline().map().size(),
                processor.pipeline().relocalizations());
  }
  if (const EkfSlam* f = processor.filter(); f && params.filter.estimate_extrinsic) {
    h["extrinsic"] = extrinsicReport(*f);
    std::printf("  camera-IMU extrinsic estimated: %s\n", h["extrinsic"].dump().c_str());
  }
  if (o.extrinsic_error) {
    // Against the parameters' own T_b_c (the calibration before the error): what was given, and
    // where the estimate ended.
    Options right = o;
    right.extrinsic_error.reset();
    const CameraExtrinsics calibration = extrinsicOf(nodeParams(right, mechanization).node.T_b_c);
    h["extrinsic_error"] = {{"given", extrinsicDistance(extrinsicOf(params.node.T_b_c), calibration)}};
    if (const EkfSlam* f = processor.filter(); f && params.filter.estimate_extrinsic)
      h["extrinsic_error"]["final"] = extrinsicDistance(f->extrinsics(), calibration);
  }
  eval::writeTrace(o.out + "/" + name + "_trace.csv", sink.trace);
  std::cout << eval::healthLine(name, h);
  for (size_t k = 0; k < refs.size(); ++k) {
    const std::string csv = o.out + "/" + name + "_reference" + (k ? std::to_string(k + 1) : "") + ".csv";
    h["references"].push_back(compareRun(sink, info, refs[k], o.reference_window_s, csv));
  }
  if (info.truth.empty()) return;
  std::vector<eval::EstimatedLandmark> lms;
  for (const auto& [id, l] : sink.map) lms.push_back(l);
  eval::RunMetrics metrics = eval::evaluateRun(sink.poses, info.truth, lms, glue::landmarkTruthFromWorld(info));
  std::printf("  against the bag's ground truth: ATE %.3f m, final %.3f m (%.2f%%)\n", metrics.ate_position_m,
              metrics.final_position_error_m, metrics.final_position_error_pct);
  metrics.real_time_factor = bag_s / wall;  // offline: the whole pipeline, bag reading included
  results->emplace_back(name, metrics);
}

/// The recordings of live replays, evaluated against the bag's ground truth.
std::vector<std::pair<std::string, eval::RunMetrics>> evaluateRecordings(const Options& o,
                                                                         const glue::InputBagInfo& info) {
  std::vector<std::pair<std::string, eval::RunMetrics>> results;
  for (const std::string& item : o.recorded) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) throw std::runtime_error("--recorded takes NAME=BAG (got '" + item + "')");
    double tracks = 0.0;
    results.emplace_back(item.substr(0, eq), glue::evaluateRecording(item.substr(eq + 1), info, &tracks));
    std::printf("%s: %d poses, %.1f tracks per frame\n", item.substr(0, eq).c_str(), results.back().second.frames,
                tracks);
  }
  return results;
}

/// The comparisons with --reference of every run, one line each, after the tables.
void printReferenceComparisons(const eval::Report& health) {
  bool first = true;
  for (const auto& item : health.runs.rows.items()) {
    const std::string& run = item.key();
    const nlohmann::ordered_json& row = item.value();
    if (!row.contains("references")) continue;
    if (first) std::cout << "\nAgainst the references (position and rotation RMSE after alignment):\n";
    first = false;
    for (const auto& r : row["references"]) {
      std::cout << "  " << run << " vs " << r.value("file", std::string()) << ": ";
      if (r.contains("error")) {
        std::cout << "not compared: " << r["error"].template get<std::string>() << "\n";
        continue;
      }
      char from[48] = "";
      if (r.contains("from_s")) std::snprintf(from, sizeof(from), ", from %g s", r["from_s"].template get<double>());
      char line[200];
      std::snprintf(line, sizeof(line), "%s, %d poses%s, %.3f m, %.2f deg", r.value("alignment", std::string()).c_str(),
                    r.value("matched", 0), from, r.value("position_rmse_m", 0.0), r.value("rotation_rmse_deg", 0.0));
      std::cout << line;
      if (r.contains("first_window_scale_ratio") && r["first_window_scale_ratio"].is_number()) {
        std::snprintf(line, sizeof(line), ", its first %g s window at %.2fx the later ones' scale",
                      r["window_s"].template get<double>(), r["first_window_scale_ratio"].template get<double>());
        std::cout << line;
      }
      std::cout << "\n";
    }
  }
}

/// health.json / health.md and, with ground truth, summary.json / summary.md, printed too.
void writeReports(const Options& o, eval::Report health,
                  const std::vector<std::pair<std::string, eval::RunMetrics>>& results) {
  const std::string mode = o.recorded.empty() ? "offline" : "live replay";
  health.config = {{"bag", o.bag}, {"config", o.config}, {"mode", mode}};
  eval::writeReport(o.out, "health", health);
  std::cout << "\n" << eval::reportMarkdown(health);
  if (!results.empty()) {
    eval::writeRunReport(o.out, results, {{"bag", o.bag}, {"config", o.config}, {"mode", mode}});
    std::ifstream md(o.out + "/summary.md");
    std::cout << "\n" << md.rdbuf();
  } else {
    fs::remove(o.out + "/summary.json");  // a stale one from an earlier run with ground truth
  }
  printReferenceComparisons(health);
  if (results.empty() && o.references.empty()) {
    std::cout << "\nthe bag has no ground truth (" << glue::RigTopics().ground_truth
              << "): no ATE or NEES; use --reference FILE.tum to compare with a trajectory\n";
  }
  std::cout << "written to " << o.out << "\n";
}

/// Top view, speed, NIS, time offset and tracks over time (and, with ground truth, errors with
/// 3-sigma and NEES) with Debian's Python (matplotlib): plot_run.py is installed beside this
/// program (devel and install spaces alike).
void plot(const std::string& out) {
  std::error_code ec;
  const fs::path script = fs::read_symlink("/proc/self/exe", ec).parent_path() / "plot_run.py";
  const std::string cmd = "/usr/bin/python3 '" + script.string() + "' '" + out + "'";
  if (ec || !fs::exists(script)) {
    std::cerr << "warning: no plots: " << script << " not found\n";
  } else if (std::system(cmd.c_str()) != 0) {
    std::cerr << "warning: plotting failed: " << cmd << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  ros::Time::init();                    // no master: wall time for the (throttled) log messages only
  glue::ConsoleBesideProgress console;  // log lines off the progress line, in order with stdout
  Options o;
  parseArguments(argc, argv, &o);
  // Exit 2: the command line does not fit (options, references, topics); 1: the run failed.
  std::vector<Reference> refs;
  glue::InputBagInfo info;
  glue::InputTopics topics;
  try {
    if (o.config.empty()) o.config = packageShare() + "/config/vi_ekf_slam.yaml";
    refs = readReferences(o);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  try {
    info = glue::readInputBag(o.bag);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  try {
    if (o.recorded.empty()) {
      // The rig's topics where the bag has them.
      const glue::NodeOptions n = nodeParams(o, "").node;
      glue::InputTopics rig_topics;
      rig_topics.imu = n.imu_topic;
      rig_topics.image = n.image_topic;
      rig_topics.camera_info = n.camera_info_topic;
      topics = glue::chooseInputTopics(o.bag, o.imu_topic, o.image_topic, o.camera_info_topic, &rig_topics);
      std::printf("reading imu %s (%s), image %s (%s), camera_info %s (%s)\n", topics.imu.c_str(),
                  topics.imu_why.c_str(), topics.image.c_str(), topics.image_why.c_str(),
                  topics.camera_info.empty() ? "-" : topics.camera_info.c_str(), topics.camera_info_why.c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  try {
    std::vector<std::pair<std::string, eval::RunMetrics>> results = evaluateRecordings(o, info);
    eval::Report health;
    health.tool = "run_bag";
    health.title = "Run health (no ground truth needed)";
    health.runs.columns = eval::healthColumns();
    std::vector<std::string> mechanizations = {o.mechanization};
    if (o.mechanization == "all") mechanizations = {"world_centric", "sensor_centric", "sensor_centric_composition"};
    if (!o.recorded.empty()) mechanizations.clear();
    for (const std::string& m : mechanizations) runOne(o, m, info, topics, refs, console, &health, &results);
    fs::create_directories(o.out);
    writeReports(o, health, results);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  if (o.plots) plot(o.out);
  return 0;
}
