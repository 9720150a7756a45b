// Monte-Carlo consistency study of the paper's Sec. IV-A: M runs of each filter configuration on
// the built-in hallway walk or a TUM trajectory. Writes summary.json, summary.md and per
// configuration CSV time series for tools/plot_study.py.
//
//   vi_ekf_slam_study --trajectory builtin|FILE --runs 50 --seed 1 --out results/study
//                     [--configs paper|all|name,name,...] [--threads N] [--density 1.0]
//                     ("default": the node's default configuration, whatever it is at the time)
//                     [--per-metre 15] [--start-offset S] [--max-duration S] [--max-landmarks N]
//                     [--imu ASL_IMU_CSV] [--imu-noise datasheet|euroc_mav] [--preset openvins_sim]
//                     [--inverse-depth INITIAL_DEPTH_M,SIGMA_PER_M] [--update-iterations N]
//                     [--landmark-entry triangulated|prior] [--imu-biases drawn|none]
//
// --preset openvins_sim: OpenVINS's simulator setup on a TUM file (sim/openvins_preset.h).
// --start-offset / --max-duration: a time window of the trajectory (e.g. start while walking).
//
// With --imu the recorded IMU of the same recording replaces the synthesized one (real IMU,
// simulated camera; see sim/recorded_imu.h). The filter is told the densities of the IMU's
// sensor.yaml (datasheet) or those tuned for the EuRoC MAV in flight (euroc_mav).
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "cli.h"
#include "vi_ekf_slam/eval/report.h"
#include "vi_ekf_slam/eval/report_columns.h"
#include "vi_ekf_slam/eval/monte_carlo.h"
#include "vi_ekf_slam/platform/allocator_tuning.h"
#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/sim/openvins_preset.h"
#include "vi_ekf_slam/sim/recorded_imu.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;
namespace fs = std::filesystem;

namespace {

struct Options {
  std::vector<std::string> faults;  // KIND:START_S:DURATION_S
  std::string trajectory = "builtin";
  int runs = 50;
  std::uint64_t seed = 1;
  std::string out = "results/study";
  std::string configs = "all";
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  double density = 1.0;     // landmarks per m^2 of wall (built-in walk)
  double per_metre = 15.0;  // landmarks per metre of path (TUM trajectories)
  double max_duration = 0;  // truncate TUM trajectories [s], 0 = whole file
  // Start this long after the file's first pose [s]; several (comma-separated): run r starts at
  // the (r mod n)-th, so that each start is run runs / n times.
  std::string start_offset = "0";
  std::vector<double> start_offsets;
  int random_starts = 0;  // > 0: that many start offsets drawn from the seed instead
  int max_landmarks = 0;  // map size bound of every configuration; 0: 300, or 100 with the preset
  std::string imu;        // recorded IMU (ASL imu0/data.csv) instead of a synthesized one
  std::string imu_noise = "datasheet";
  std::string preset;  // "" or openvins_sim
  // "truth": every run starts at the true state (the preset's default, like OpenVINS);
  // "prior": the start error is drawn from the filter's initial covariance (default otherwise);
  // "dynamic": the filter waits for the dynamic initializer, as the node does on a moving rig.
  std::string init;
  // --inverse-depth M,S: prior depth 1/rho0 [m] and sigma of rho [1/m] of new inverse-depth
  // landmarks in every configuration (default: the core's).
  std::string inverse_depth;
  double inverse_depth_initial_m = 0.0, inverse_depth_sigma = 0.0;
  std::string depth_prior;     // "fixed" | "scene": the inverse-depth prior's centre; "": the core's default
  std::string landmark_entry;  // "triangulated" | "prior": new tracks wait for a baseline or not; "": the core's
  double gate = 0.0;           // chi^2 gate probability of every configuration; 0: the core's default
  int update_iterations = 0;   // linearizations per update of every configuration; 0: the core's default
  // +zero_velocity: "wait" (the core's default): new landmarks wait until the standing detector
  // sees the rig move, unless the IMU shows rest; "immediate": whenever a track is new.
  std::string new_landmarks = "wait";
  bool new_landmarks_given = false;  // "default" keeps the core's choice unless told
  bool all_runs = false;             // every run's runN.csv and landmarks_runN.csv (else run 0's)
  bool list_configs = false;         // print the configurations and exit
  std::string imu_biases = "drawn";  // drawn | none: the simulated IMU's turn-on biases
  bool estimate_extrinsic = false;   // every configuration estimates the camera-IMU extrinsic
  bool second_order = false;         // every composition keeps the second-order term (frame_change.h)
  std::string extrinsic_error;       // DEG,M: the filter is given an extrinsic this far off the true one
  std::string map;                 // "keep" | "forget": landmarks whose tracks ended stay dormant or go; "": the core's
  std::string dormant_consider;    // "yes" | "no": dormant landmarks are consider states; "": the core's
  std::string blind_motion_prior;  // "on" | "off": the motion prior while blind (blind_motion_prior.h); "": the core's
  // After a blind stretch, new tracks wait for the re-anchor at most this long [s]; < 0: the pipeline's.
  double reanchor_max_wait_s = -1.0;
  int texture_patterns = 0;  // > 0: the world's appearance repeats N patterns (repeated texture)
};

const char* const kUsage =
    "vi_ekf_slam_study --trajectory builtin|FILE [--runs N] [--seed S] [--out DIR] [--configs paper|all|NAME,...] "
    "[more options: --help]";

[[noreturn]] void usage(const std::string& err) { cli::fail(kUsage, err); }

Options parse(int argc, char** argv) {
  Options o;
  namespace po = cli::po;
  po::options_description d("options");
  d.add_options()("trajectory", po::value(&o.trajectory)->default_value(o.trajectory), "builtin, or a TUM file (z up)")(
      "runs", po::value(&o.runs)->default_value(o.runs), "Monte-Carlo runs per configuration")(
      "seed", po::value(&o.seed)->default_value(o.seed), "run r uses seed * 1000003 + r")(
      "out", po::value(&o.out)->default_value(o.out), "output folder")(
      "configs", po::value(&o.configs)->default_value(o.configs),
      "paper | all | names, comma-separated (\"default\": the node's default configuration)")(
      "threads", po::value(&o.threads)->default_value(o.threads), "worker threads")(
      "density", po::value(&o.density)->default_value(o.density), "built-in walk: landmarks per m^2 of wall")(
      "per-metre", po::value(&o.per_metre)->default_value(o.per_metre), "TUM files: landmarks per metre of path")(
      "start-offset", po::value(&o.start_offset)->default_value(o.start_offset),
      "start this long into the file [s]; S1,S2,...: run r starts at the (r mod n)-th")(
      "random-starts", po::value(&o.random_starts)->default_value(o.random_starts),
      "N > 0: N start offsets drawn uniformly (from the seed) where a --max-duration window fits")(
      "max-duration", po::value(&o.max_duration)->default_value(o.max_duration), "window length, 0: to the end [s]")(
      "max-landmarks", po::value(&o.max_landmarks)->default_value(o.max_landmarks),
      "map bound of every configuration (0: 300, or 100 with the preset)")(
      "imu", po::value(&o.imu), "a recorded ASL IMU (imu0/data.csv) of the same recording as --trajectory")(
      "imu-noise", po::value(&o.imu_noise)->default_value(o.imu_noise), "datasheet | euroc_mav (with --imu)")(
      "preset", po::value(&o.preset), "openvins_sim: OpenVINS's simulator setup on a TUM file")(
      "init", po::value(&o.init),
      "truth | prior | dynamic: start at the true state, from an error drawn from the prior (default; truth with "
      "the preset), or from the dynamic initializer (registered to the truth's position and yaw)")(
      "start", po::value(&o.init), "the same as --init")("gate", po::value(&o.gate)->default_value(o.gate),
                                                         "chi^2 gate probability of every configuration (0: default)")(
      "new-landmarks", po::value(&o.new_landmarks)->default_value(o.new_landmarks),
      "wait | immediate: +zero_velocity configurations hold new tracks until the rig is seen moving, or not")(
      "update-iterations", po::value(&o.update_iterations)->default_value(o.update_iterations),
      "1: EKF update, more: iterated update, every configuration (0: default)")(
      "inverse-depth", po::value(&o.inverse_depth), "INITIAL_DEPTH_M,SIGMA_PER_M of new inverse-depth landmarks")(
      "depth-prior", po::value(&o.depth_prior),
      "fixed | scene: new inverse-depth landmarks start at INITIAL_DEPTH_M, or at the median depth of the landmarks "
      "seen (default: the core's)")(
      "list-configs", po::bool_switch(&o.list_configs),
      "print every configuration's name and its sets (paper: the paper's three; suite: the suite's "
      "default list) and exit; the scripts read the names from here")(
      "all-runs", po::bool_switch(&o.all_runs),
      "write every run's errors and sigmas (runN.csv, landmarks_runN.csv), not only run 0's")(
      "landmark-entry", po::value(&o.landmark_entry),
      "triangulated | prior: new inverse-depth tracks wait for the baseline that triangulates them, or enter at the "
      "prior depth at once (default: the core's)")("composition-second-order", po::bool_switch(&o.second_order),
                                                   "every composition keeps the second-order term of an inverse-depth "
                                                   "landmark's depth error times the pose error")(
      "estimate-extrinsic", po::bool_switch(&o.estimate_extrinsic),
      "every configuration estimates the camera-IMU extrinsic online")(
      "extrinsic-error", po::value(&o.extrinsic_error),
      "DEG,M: the filter is given the camera-IMU extrinsic turned by DEG degrees and moved by M metres (fixed "
      "directions) from the true one")(
      "map", po::value(&o.map),
      "keep | forget: landmarks whose tracks ended stay in the state as dormant and are found again by their "
      "appearance, or are marginalized (every configuration; default: the core's)")(
      "dormant-consider", po::value(&o.dormant_consider),
      "yes | no: dormant landmarks are consider states (Schmidt-Kalman: no update sharpens them) or ordinary "
      "ones (every configuration; default: the core's)")(
      "blind-motion-prior", po::value(&o.blind_motion_prior),
      "on | off: while no image constrains the velocity, the body-frame velocity of the seconds of sight before "
      "bounds it (every configuration; default: the core's)")(
      "reanchor-max-wait-s", po::value(&o.reanchor_max_wait_s)->default_value(o.reanchor_max_wait_s),
      "after a blind stretch new tracks wait at most this long for the first images to re-anchor the velocity "
      "(0: not; < 0: the pipeline's default) [s]")(
      "texture-patterns", po::value(&o.texture_patterns)->default_value(o.texture_patterns),
      "N > 0: repeated texture, the landmarks' appearance repeats N patterns over the world (0: all differ)")(
      "fault", po::value(&o.faults)->composing(),
      "KIND:START_S:DURATION_S, repeatable: a sensor fault in every run, START_S from the window's start "
      "(image_dropout, imu_gap, outlier_burst, "
      "camera_covered, imu_clipped)")(
      "imu-biases", po::value(&o.imu_biases)->default_value(o.imu_biases),
      "drawn | none: the simulated IMU's biases are drawn from the filter's prior, or zero (a diagnostic: what "
      "not knowing them costs; the filter keeps its prior)");
  const po::variables_map vm = cli::parse(argc, argv, kUsage,
                                          "Monte-Carlo consistency study (paper Sec. IV-A): M runs of each filter "
                                          "configuration on the built-in hallway walk or a TUM trajectory.",
                                          d);
  o.new_landmarks_given = !vm["new-landmarks"].defaulted();
  if (o.update_iterations < 0 || o.update_iterations > 20) usage("--update-iterations must be in [1, 20]");
  if (o.runs < 2) usage("--runs must be >= 2 (NEES bands need several runs)");
  if (o.threads < 1) usage("--threads must be >= 1");
  if (o.max_landmarks < 0) usage("--max-landmarks must be >= 1 (0: the default)");
  {
    std::stringstream ss(o.start_offset);
    std::string item;
    while (std::getline(ss, item, ',')) {
      try {
        size_t used = 0;
        o.start_offsets.push_back(std::stod(item, &used));
        if (used != item.size()) throw std::invalid_argument(item);
      } catch (const std::exception&) {
        usage("--start-offset needs numbers [s], comma-separated (got '" + o.start_offset + "')");
      }
    }
  }
  if (o.start_offsets.empty()) o.start_offsets.push_back(0.0);
  if (o.random_starts < 0) usage("--random-starts must be >= 0");
  if (o.random_starts > 0 && !(o.max_duration > 0.0)) usage("--random-starts needs --max-duration");
  const bool offset_given = o.random_starts > 0 || o.start_offsets.size() > 1 || o.start_offsets[0] != 0.0;
  for (double s : o.start_offsets) {
    if (!(s >= 0.0)) usage("--start-offset must be >= 0");
  }
  if (o.max_duration < 0.0) usage("--max-duration must be >= 0");
  if (offset_given && !o.imu.empty()) usage("--start-offset is for synthesized IMU only");
  if (o.imu_noise != "datasheet" && o.imu_noise != "euroc_mav") usage("--imu-noise must be datasheet or euroc_mav");
  if (o.gate != 0.0 && !(o.gate > 0.0 && o.gate < 1.0)) usage("--gate must be in (0, 1)");
  if (!o.init.empty() && o.init != "truth" && o.init != "prior" && o.init != "dynamic") {
    usage("--init must be truth, prior or dynamic");
  }
  if (o.init == "dynamic" && !o.imu.empty()) usage("--init dynamic is for synthesized IMU only");
  if (o.new_landmarks != "wait" && o.new_landmarks != "immediate") usage("--new-landmarks must be wait or immediate");
  if (o.imu_biases != "drawn" && o.imu_biases != "none") usage("--imu-biases must be drawn or none");
  if (o.imu_biases == "none" && !o.imu.empty()) usage("--imu-biases none is for synthesized IMU only");
  if (!o.inverse_depth.empty() &&
      (std::sscanf(o.inverse_depth.c_str(), "%lf,%lf", &o.inverse_depth_initial_m, &o.inverse_depth_sigma) != 2 ||
       !(o.inverse_depth_initial_m > 0.0) || !(o.inverse_depth_sigma > 0.0))) {
    usage("--inverse-depth needs INITIAL_DEPTH_M,SIGMA_PER_M (both > 0)");
  }
  if (!o.landmark_entry.empty() && o.landmark_entry != "triangulated" && o.landmark_entry != "prior") {
    usage("--landmark-entry must be triangulated or prior");
  }
  if (!o.map.empty() && o.map != "keep" && o.map != "forget") usage("--map must be keep or forget");
  if (!o.blind_motion_prior.empty() && o.blind_motion_prior != "on" && o.blind_motion_prior != "off")
    usage("--blind-motion-prior must be on or off");
  if (!o.dormant_consider.empty() && o.dormant_consider != "yes" && o.dormant_consider != "no") {
    usage("--dormant-consider must be yes or no");
  }
  if (o.texture_patterns < 0) usage("--texture-patterns must be >= 0");
  if (!o.depth_prior.empty() && o.depth_prior != "fixed" && o.depth_prior != "scene") {
    usage("--depth-prior must be fixed or scene");
  }
  if (!o.preset.empty() && o.preset != "openvins_sim") usage("unknown --preset '" + o.preset + "'");
  if (!o.preset.empty() && (o.trajectory == "builtin" || !o.imu.empty())) usage("--preset needs a TUM --trajectory");
  return o;
}

/// The chi^2 gate probability that keeps all but 0.01% of correct observations.
constexpr double kOutlierFreeGate = 0.9999;

std::string formatGate(double p) {
  std::ostringstream s;
  s << p;
  return s.str();
}

/// What every configuration, the default included, is told: the simulated sensors' noise (what a
/// rig's calibration gives) and the options given for all configurations.
EkfSlamConfig withStudyOptions(EkfSlamConfig c, const Options& o, const sim::Scenario& sc) {
  c.imu_noise = sc.imu.noise;
  c.update.pixel_noise_px = sc.cam.pixel_noise_px;
  if (o.preset == "openvins_sim") c.initial = sim::openvinsSimInitialUncertainty();
  if (!o.inverse_depth.empty()) {
    c.inverse_depth_initial_m = o.inverse_depth_initial_m;
    c.inverse_depth_sigma = o.inverse_depth_sigma;
  }
  if (o.update_iterations > 0) c.update.iterations = o.update_iterations;
  if (!o.depth_prior.empty()) c.inverse_depth_scene_prior = o.depth_prior == "scene";
  if (!o.landmark_entry.empty()) c.triangulation.enabled = o.landmark_entry == "triangulated";
  // The recorded IMU is EuRoC's MAV: standing on the ground it does not sway like a pedestrian.
  if (!o.imu.empty()) c.zero_velocity.velocity_sigma_mps = io::kEurocMavStandingVelocitySigma;
  if (o.gate > 0.0) c.update.gate_probability = o.gate;
  if (o.estimate_extrinsic) c.estimate_extrinsic = true;
  if (o.second_order) c.composition_second_order = true;
  if (!o.map.empty()) c.map.within_run = o.map == "keep";
  if (!o.dormant_consider.empty()) c.map.dormant_consider = o.dormant_consider == "yes";
  if (!o.blind_motion_prior.empty()) c.blind_motion.enabled = o.blind_motion_prior == "on";
  return c;
}

/// The configurations of the study. The paper's three (fixed 8 m depth, composition when more
/// than four landmarks were added at once), then beyond the paper: the same with anchored
/// inverse-depth landmarks, and the composition after every update (robocentric) with each
/// landmark initialization; last, the node's default, which adds the zero-velocity update while
/// standing (core/zero_velocity.h).
std::vector<std::pair<std::string, EkfSlamConfig>> makeConfigs(const Options& o, const sim::Scenario& sc) {
  std::vector<std::pair<std::string, EkfSlamConfig>> all;
  auto add = [&](Mechanization m, LandmarkInitMethod init, CompositionTrigger trig, bool zero_velocity = false,
                 double gate = 0.0) {
    EkfSlamConfig c = withStudyOptions(EkfSlamConfig(), o, sc);
    c.mechanization = m;
    c.landmark_init = init;
    c.composition_trigger = trig;
    c.landmark_timeout_s = 1.0;  // marginalize landmarks out of view for 1 s
    // The preset bounds the map like OpenVINS bounds its SLAM + MSCKF features per update; the
    // accuracy is the same as with 300 (README) at 60-80% of the time per frame.
    c.max_landmarks = o.max_landmarks > 0 ? o.max_landmarks : (o.preset.empty() ? 300 : 100);
    c.zero_velocity.enabled = zero_velocity;
    c.zero_velocity.defer_landmarks = o.new_landmarks == "wait";
    if (gate > 0.0) c.update.gate_probability = gate;
    // The paper's three, and a configuration named by its gate, gate at one probability; the
    // others widen it on tracks without outliers as the node does (core/outlier_watch.h).
    if (gate > 0.0 || (init == LandmarkInitMethod::kFixedDepth && trig == CompositionTrigger::kNewLandmarks)) {
      c.update.clean_gate_probability = c.update.gate_probability;
    }
    std::string name = toString(m);
    if (init == LandmarkInitMethod::kInverseDepth) name += "+inverse_depth";
    if (m == Mechanization::kSensorCentricComposition && trig == CompositionTrigger::kEveryUpdate) {
      name += "+every_update";
    }
    if (zero_velocity) name += "+zero_velocity";
    if (gate > 0.0) name += "+gate_" + formatGate(gate);
    all.emplace_back(name, c);
  };
  const auto fixed = LandmarkInitMethod::kFixedDepth, inv = LandmarkInitMethod::kInverseDepth;
  const auto paper = CompositionTrigger::kNewLandmarks, every = CompositionTrigger::kEveryUpdate;
  for (auto m :
       {Mechanization::kWorldCentric, Mechanization::kSensorCentric, Mechanization::kSensorCentricComposition}) {
    add(m, fixed, paper);
  }
  if (o.configs == "paper") return all;
  for (auto m :
       {Mechanization::kWorldCentric, Mechanization::kSensorCentric, Mechanization::kSensorCentricComposition}) {
    add(m, inv, paper);
  }
  add(Mechanization::kSensorCentricComposition, fixed, every);
  add(Mechanization::kSensorCentricComposition, inv, every);
  // The node's default: the best one plus the zero-velocity update while standing.
  add(Mechanization::kSensorCentricComposition, inv, every, true);
  // The same with the chi^2 gate of an outlier-free front end: the simulator has no outliers, so
  // the 95% gate only drops the 5% of correct observations that would correct the largest errors.
  add(Mechanization::kSensorCentricComposition, inv, every, true, kOutlierFreeGate);
  // The node's default as it is (EkfSlamConfig{}, which test/ros/test_params.cc keeps equal to
  // config/vi_ekf_slam.yaml), told only what a rig's calibration would tell it: the sensors'
  // noise, and the options given to every configuration.
  {
    EkfSlamConfig c = withStudyOptions(EkfSlamConfig(), o, sc);
    if (o.max_landmarks > 0) c.max_landmarks = o.max_landmarks;
    if (o.new_landmarks_given) c.zero_velocity.defer_landmarks = o.new_landmarks == "wait";
    all.emplace_back("default", c);
  }
  if (o.configs == "all") return all;
  std::vector<std::pair<std::string, EkfSlamConfig>> chosen;
  std::stringstream ss(o.configs);
  std::string name;
  while (std::getline(ss, name, ',')) {
    auto it = std::find_if(all.begin(), all.end(), [&](const auto& c) { return c.first == name; });
    if (it == all.end()) usage("unknown configuration '" + name + "'");
    chosen.push_back(*it);
  }
  if (chosen.empty()) usage("--configs names no configuration (--list-configs lists them)");
  return chosen;
}

/// The header columns of writeCsvRow: NAME_x,NAME_y,NAME_z for each name.
void writeCsvHeader(std::ofstream& f, std::initializer_list<const char*> names) {
  for (const char* n : names) f << "," << n << "_x," << n << "_y," << n << "_z";
}

void writeCsvRow(std::ofstream& f, std::initializer_list<Vec3> vs) {
  for (const Vec3& v : vs) f << "," << v.x() << "," << v.y() << "," << v.z();
}

/// nees_runs.csv: every run's position, orientation and pose NEES per camera time (run0.csv has
/// run 0's full errors, runN.csv run N's with --all-runs); shows whether a run-averaged NEES is
/// carried by a few runs.
void writeRunNees(const fs::path& dir, const std::vector<eval::RunResult>& runs) {
  std::ofstream f(dir / "nees_runs.csv");
  f << "t";
  for (const char* kind : {"pose", "p", "q"})
    for (size_t r = 0; r < runs.size(); ++r) f << "," << kind << "_" << r;
  f << "\n";
  // Runs of a dynamic start begin at their initialization and differ in length: the frames all have.
  size_t frames = runs.front().frames.size();
  for (const auto& r : runs) frames = std::min(frames, r.frames.size());
  for (size_t k = 0; k < frames; ++k) {
    f << std::setprecision(15) << runs.front().frames[k].t << std::setprecision(5);
    for (const auto& r : runs) f << "," << r.frames[k].nees_pose;
    for (const auto& r : runs) f << "," << r.frames[k].nees_p;
    for (const auto& r : runs) f << "," << r.frames[k].nees_q;
    f << "\n";
  }
}

/// runN.csv: run N's errors (true - estimate) and sigmas per camera time, with the frame's map
/// and update counts; landmarks_runN.csv: its last estimate of every landmark against the truth.
void writeRunFiles(const fs::path& dir, const eval::RunResult& run, size_t index, const sim::Scenario& sc) {
  std::ofstream r(dir / ("run" + std::to_string(index) + ".csv"));
  r << "t,px,py,pz,ex,ey,ez,tx,ty,tz";
  writeCsvHeader(r, {"e_p", "s_p", "e_q", "s_q", "e_v", "s_v", "e_ba", "s_ba", "e_bg", "s_bg", "e_p_sb", "s_p_sb",
                     "e_q_sb", "s_q_sb", "e_p_ns", "s_p_ns", "e_q_ns", "s_q_ns"});
  r << ",has_s,gamma,landmarks,new_landmarks,rejected,composed,nees_pose,update_ms,stationary,parallax_px,e_td,s_td\n"
    << std::setprecision(15);
  for (const auto& m : run.frames) {
    r << m.t;
    writeCsvRow(r, {m.p_true, m.p_est, m.p_true});
    writeCsvRow(r, {m.e_p, m.s_p, m.e_q, m.s_q, m.e_v, m.s_v, m.e_ba, m.s_ba, m.e_bg, m.s_bg});
    const Vec3 z = Vec3::Zero();
    if (m.has_s)
      writeCsvRow(r, {m.e_p_sb, m.s_p_sb, m.e_q_sb, m.s_q_sb, m.e_p_ns, m.s_p_ns, m.e_q_ns, m.s_q_ns});
    else
      writeCsvRow(r, {z, z, z, z, z, z, z, z});
    r << "," << m.has_s << "," << m.gamma << "," << m.landmarks << "," << m.new_landmarks << "," << m.rejected << ","
      << m.composed << "," << m.nees_pose << "," << m.update_ms << "," << m.stationary << "," << m.parallax_px << ","
      << m.e_td << "," << m.s_td << "\n";
  }
  std::ofstream l(dir / ("landmarks_run" + std::to_string(index) + ".csv"));
  l << "id,true_x,true_y,true_z,est_x,est_y,est_z\n" << std::setprecision(8);
  for (const auto& [id, p] : run.landmark_estimates) {
    const Vec3& t = sim::landmarkOfTrack(id, sc.world).p_n;
    l << id << "," << t.x() << "," << t.y() << "," << t.z() << "," << p.x() << "," << p.y() << "," << p.z() << "\n";
  }
}

/// all_runs: runN.csv for every run, else for run 0 only.
void writeConfigFiles(const fs::path& dir, const eval::ConsistencySummary& s, const std::vector<eval::RunResult>& runs,
                      const sim::Scenario& sc, bool all_runs) {
  fs::create_directories(dir);
  writeRunNees(dir, runs);
  const eval::NeesBand b3 = eval::neesBand(3, s.runs);
  std::ofstream ts(dir / "timeseries.csv");
  ts << "t,avg_nees_p,avg_nees_q,avg_nees_pose,median_gamma,rms_p,band6_lo,band6_hi,band3_lo,band3_hi";
  writeCsvHeader(ts, {"axis_p", "axis_v", "axis_q", "axis_ba", "axis_bg"});
  ts << "\n" << std::setprecision(15);
  for (size_t k = 0; k < s.t.size(); ++k) {
    ts << s.t[k] << "," << s.avg_nees_p[k] << "," << s.avg_nees_q[k] << "," << s.avg_nees_pose[k] << ","
       << s.median_gamma[k] << "," << s.rms_p[k] << "," << s.pose_band.lo << "," << s.pose_band.hi << "," << b3.lo
       << "," << b3.hi;
    writeCsvRow(ts, {s.axis_p[k], s.axis_v[k], s.axis_q[k], s.axis_ba[k], s.axis_bg[k]});
    ts << "\n";
  }
  for (size_t i = 0; i < (all_runs ? runs.size() : 1); ++i) writeRunFiles(dir, runs[i], i, sc);
}

}  // namespace

/// The sets a configuration belongs to, for --list-configs: the paper's three, and the suite's
/// default list (the paper's, the robocentric filter with inverse depth, with the zero-velocity
/// update, and the node's default).
std::string configSets(const std::string& name, size_t index) {
  std::string sets;
  if (index < 3) sets += "paper,suite";
  if (name == "sensor_centric_composition+inverse_depth+every_update" ||
      name == "sensor_centric_composition+inverse_depth+every_update+zero_velocity" || name == "default") {
    sets += "suite";
  }
  return sets.empty() ? "-" : sets;
}

/// The seconds after a covered camera over which the study averages the pose NEES.
constexpr double kAfterOutageS = 5.0;

/// Per summary: the largest, over the covered-camera faults (of the run's scenario: on its clock),
/// of the run-averaged pose NEES averaged over the kAfterOutageS after the fault ends (NaN where no
/// frame falls there); empty without one.
std::vector<double> neesAfterOutages(const std::vector<sim::SensorFault>& faults,
                                     const std::vector<eval::ConsistencySummary>& sums) {
  std::vector<double> worst;
  for (const auto& f : faults) {
    if (f.kind != sim::SensorFault::Kind::kCameraCovered) continue;
    worst.resize(sums.size(), std::nan(""));
    const double t0 = f.start_s + f.duration_s;
    for (size_t c = 0; c < sums.size(); ++c) {
      double sum = 0.0;
      int n = 0;
      for (size_t k = 0; k < sums[c].t.size(); ++k) {
        const double t = sums[c].t[k];
        if (t < t0 || t >= t0 + kAfterOutageS || !std::isfinite(sums[c].avg_nees_pose[k])) continue;
        sum += sums[c].avg_nees_pose[k];
        ++n;
      }
      if (n > 0 && !(worst[c] >= sum / n)) worst[c] = sum / n;
    }
  }
  return worst;
}

/// --fault KIND:START_S:DURATION_S (exits with usage on a malformed one).
std::vector<sim::SensorFault> parseFaults(const std::vector<std::string>& specs) {
  std::vector<sim::SensorFault> faults;
  for (const std::string& f : specs) {
    const auto a = f.find(':'), b = f.rfind(':');
    sim::SensorFault fault;
    const auto kind = sim::sensorFaultKindFromString(f.substr(0, a));
    char* end = nullptr;
    if (a != std::string::npos && b > a) {
      fault.start_s = std::strtod(f.c_str() + a + 1, &end);
      if (end == f.c_str() + b) fault.duration_s = std::strtod(f.c_str() + b + 1, &end);
    }
    if (!kind || a == std::string::npos || b == a || !end || *end != '\0' || !(fault.duration_s > 0.0) ||
        !(fault.start_s >= 0.0)) {
      usage("--fault takes KIND:START_S:DURATION_S (got '" + f + "')");
    }
    fault.kind = *kind;
    faults.push_back(fault);
  }
  return faults;
}

/// The scenario the options describe, with *name for the reports (exits with usage on a bad
/// combination; throws when a file cannot be read).
sim::Scenario loadScenario(const Options& o, std::string* name) {
  *name = "builtin_hallway_walk";
  sim::Scenario sc;
  if (o.preset == "openvins_sim") {
    sc = sim::openvinsSimScenario(o.trajectory, o.seed);
    *name = fs::path(o.trajectory).filename().string() + " (openvins_sim)";
  } else if (!o.imu.empty()) {
    if (o.trajectory == "builtin") usage("--imu needs the ground truth of the same recording as --trajectory");
    sc = sim::recordedImuScenario(o.trajectory, o.imu, o.per_metre, o.seed);
    if (o.imu_noise == "euroc_mav") sc.imu.noise = io::eurocMavImuNoise();
    *name = fs::path(o.trajectory).filename().string() + " + recorded IMU";
  } else if (o.trajectory == "builtin") {
    sc = sim::hallwayScenario(sim::HallwayParams(), o.density, o.seed);
  } else {
    sc = sim::tumScenario(o.trajectory, o.per_metre, o.seed);
    *name = fs::path(o.trajectory).filename().string();
  }
  if (!o.init.empty()) sc.start_at_truth = o.init == "truth";
  if (o.init == "dynamic") sc.dynamic_init = DynamicInitParams();
  sc.draw_imu_biases = o.imu_biases == "drawn";
  sc.faults = parseFaults(o.faults);
  if (o.reanchor_max_wait_s >= 0.0) sc.reanchor_max_wait_s = o.reanchor_max_wait_s;
  sc.cam.descriptors.texture_patterns = o.texture_patterns;
  if (!o.extrinsic_error.empty()) {
    double deg = 0.0, m = 0.0;
    if (std::sscanf(o.extrinsic_error.c_str(), "%lf,%lf", &deg, &m) != 2 || !std::isfinite(deg) || !std::isfinite(m)) {
      usage("--extrinsic-error takes DEG,M");
    }
    CameraExtrinsics given = sc.T_b_c;
    given.R_b_c = expSO3(Vec3(1.0, 1.0, 1.0).normalized() * (deg * M_PI / 180.0)) * given.R_b_c;
    given.p_b_c += Vec3(1.0, -1.0, 1.0).normalized() * m;
    sc.given_T_b_c = given;
  }
  return sc;
}

/// One scenario per start offset (the same world and sensors, another window of the path); the
/// offsets used into *offsets.
std::vector<sim::Scenario> startScenarios(const Options& o, const sim::Scenario& sc, std::vector<double>* offsets) {
  *offsets = o.start_offsets;
  if (o.random_starts > 0) {
    const double span = sc.trajectory->endTime() - sc.trajectory->startTime() - o.max_duration;
    if (!(span > 0.0)) usage("--random-starts: the trajectory is shorter than --max-duration");
    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<double> u(0.0, span);
    offsets->clear();
    for (int i = 0; i < o.random_starts; ++i) offsets->push_back(std::round(10.0 * u(rng)) / 10.0);
  }
  std::vector<sim::Scenario> scenarios;
  for (double offset : *offsets) {
    sim::Scenario s = sc;
    if (o.max_duration > 0.0 || offset > 0.0) {
      const double start = sc.trajectory->startTime() + offset;
      if (!(start < sc.trajectory->endTime())) usage("--start-offset beyond the end of the trajectory");
      const double end =
          o.max_duration > 0.0 ? std::min(start + o.max_duration, sc.trajectory->endTime()) : sc.trajectory->endTime();
      s.trajectory = std::make_shared<sim::TruncatedTrajectory>(sc.trajectory, start, end);
    }
    // --fault times are from the window's start (a TUM file's clock is the recording's).
    for (auto& f : s.faults) f.start_s += s.trajectory->startTime();
    scenarios.push_back(s);
  }
  return scenarios;
}

using Configs = std::vector<std::pair<std::string, EkfSlamConfig>>;

/// All (configuration, run) jobs on a small thread pool. Run r uses seed + r for every
/// configuration (common random numbers: the same noise for each filter).
std::vector<std::vector<eval::RunResult>> runAll(const Options& o, const Configs& configs,
                                                 const std::vector<sim::Scenario>& scenarios) {
  std::vector<std::vector<eval::RunResult>> results(configs.size(),
                                                    std::vector<eval::RunResult>(static_cast<size_t>(o.runs)));
  std::atomic<int> next{0};
  std::mutex print_mutex;
  const int jobs = static_cast<int>(configs.size()) * o.runs;
  auto worker = [&]() {
    for (int j = next++; j < jobs; j = next++) {
      const size_t c = static_cast<size_t>(j / o.runs);
      const size_t r = static_cast<size_t>(j % o.runs);
      results[c][r] =
          eval::runMonteCarloRun(scenarios[r % scenarios.size()], configs[c].second, o.seed * 1000003ULL + r);
      std::lock_guard<std::mutex> lock(print_mutex);
      std::fprintf(stderr, "\r  %d/%d runs done", j + 1, jobs);
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < o.threads; ++i) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  std::fprintf(stderr, "\n");
  return results;
}

/// summary.json / summary.md: each configuration name -> metrics, with the settings used
/// (non-finite: null); for dynamic starts, their delays.
eval::Report summaryReport(const Options& o, const std::string& traj_name, const sim::Scenario& sc,
                           const std::vector<double>& offsets, double duration, const Configs& configs,
                           const std::vector<eval::ConsistencySummary>& sums) {
  eval::Report r;
  r.tool = "study";
  std::ostringstream title;
  title << "Study: " << traj_name << " (" << o.runs << " runs, seed " << o.seed << ", " << std::fixed
        << std::setprecision(1) << duration << " s, " << sums[0].distance_m << " m)";
  r.title = title.str();
  r.config = {{"trajectory", traj_name},
              {"seed", o.seed},
              {"runs", o.runs},
              {"recorded_imu", o.imu},
              {"faults", o.faults},
              {"start", sc.dynamic_init     ? "dynamic"
                        : sc.start_at_truth ? "truth"
                                            : "prior"},
              {"imu_noise", o.imu_noise},
              {"imu_biases", o.imu_biases},
              {"start_offsets_s", offsets},
              {"duration_s", duration},
              {"world_landmarks", sc.world.size()},
              {"imu_rate_hz", sc.imu.rate_hz},
              {"camera_rate_hz", sc.cam.rate_hz},
              {"pixel_noise_px", sc.cam.pixel_noise_px},
              {"accel_noise_density", sc.imu.noise.accel_noise_density},
              {"gyro_noise_density", sc.imu.noise.gyro_noise_density},
              {"accel_random_walk", sc.imu.noise.accel_random_walk},
              {"gyro_random_walk", sc.imu.noise.gyro_random_walk},
              {"pose_nees_band", {sums[0].pose_band.lo, sums[0].pose_band.hi}}};
  for (size_t c = 0; c < sums.size(); ++c) {
    const auto& s = sums[c];
    const auto& cfg = configs[c].second;
    r.runs.rows[s.name] = {{"mechanization", toString(cfg.mechanization)},
                           {"landmark_init", toString(cfg.landmark_init)},
                           {"composition_trigger", toString(cfg.composition_trigger)},
                           {"ate_position_m", s.ate_position_m},
                           {"ate_posyaw_m", s.ate_posyaw_m},
                           {"real_time_factor", s.real_time_factor},
                           {"ate_orientation_deg", s.ate_orientation_deg},
                           {"final_position_error_m", s.final_position_error_m},
                           {"final_position_error_pct", s.final_position_error_pct},
                           {"distance_m", s.distance_m},
                           {"nees_position", s.nees_position},
                           {"nees_orientation", s.nees_orientation},
                           {"nees_pose", s.nees_pose},
                           {"consistent_fraction", s.consistent_fraction},
                           {"final_scale_ratio", s.final_scale_ratio},
                           {"runs", s.runs},
                           {"filter_ms_mean", s.mean_update_ms},
                           {"filter_ms_p95", s.p95_update_ms},
                           {"nees_pose_first_10s", s.nees_pose_early},
                           {"runs_started", s.runs_started},
                           {"init_delay_s", s.init_delay_s},
                           {"ate_posyaw_runs_m", s.ate_posyaw_runs_m},
                           {"revisit_error_ratio", s.revisit_error_ratio},
                           {"revisits_per_run", s.revisits_per_run},
                           {"false_revisits", s.false_revisits}};
  }
  // After each covered camera (sim::SensorFault::kCameraCovered), the run-averaged pose NEES over
  // the seconds that follow it: whether the filter comes back honest. The worst outage's.
  const std::vector<double> after = neesAfterOutages(sc.faults, sums);
  if (!after.empty()) {
    for (size_t c = 0; c < sums.size(); ++c) r.runs.rows[sums[c].name]["nees_pose_after_outage"] = after[c];
    std::ostringstream n;
    n << "NEES pose after an outage: the run average over the " << kAfterOutageS
      << " s after each covered camera, the worst of them.";
    r.notes.push_back(n.str());
  }
  r.runs.columns =
      eval::metricColumns({"ate_position_m", "ate_posyaw_m", "ate_orientation_deg", "final_position_error_m",
                           "final_position_error_pct", "nees_position", "nees_orientation", "nees_pose",
                           "consistent_fraction", "revisit_error_ratio", "revisits_per_run", "false_revisits",
                           "final_scale_ratio", "filter_ms_mean", "filter_ms_p95", "real_time_factor"});
  if (!after.empty()) r.runs.columns.push_back(eval::metricColumns({"nees_pose_after_outage"}).front());
  std::ostringstream band;
  band << "Pose NEES 95% band for the run average: [" << std::fixed << std::setprecision(2) << sums[0].pose_band.lo
       << ", " << sums[0].pose_band.hi << "] (6 dof).";
  r.notes.push_back(band.str());
  if (sc.dynamic_init) {
    eval::ReportTable t;
    t.heading = "Dynamic initialization (--init dynamic)";
    t.columns = {
        {"initialized", "initialized", 0},
        {"within_1_5_s", "within 1.5 s", 0},
        {"delay_mean_s", "delay mean [s]", 2},
        {"delay_max_s", "delay max [s]", 2},
        {"nees_pose_first_10s", "NEES pose, first " + std::to_string(static_cast<int>(eval::kEarlyWindowS)) + " s", 2}};
    for (const auto& s : sums) {
      double sum = 0.0, worst = 0.0;
      int fast = 0;
      for (double d : s.init_delay_s) {
        if (!std::isfinite(d)) continue;
        sum += d;
        worst = std::max(worst, d);
        fast += d <= 1.5;
      }
      t.rows[s.name] = {{"initialized", std::to_string(s.runs) + "/" + std::to_string(s.runs_started)},
                        {"within_1_5_s", std::to_string(fast) + "/" + std::to_string(s.runs_started)},
                        {"delay_mean_s", s.runs ? sum / s.runs : std::nan("")},
                        {"delay_max_s", worst},
                        {"nees_pose_first_10s", s.nees_pose_early}};
    }
    r.tables.emplace_back("dynamic_start", t);
    r.notes.push_back(
        "Dynamic initialization: the delay from the start; the first table is over the runs that initialized, "
        "from their initialization on.");
  }
  return r;
}

/// --list-configs: every configuration's name and the sets it belongs to.
void listConfigs(Options all) {
  all.configs = "all";
  const auto configs = makeConfigs(all, sim::Scenario());
  for (size_t i = 0; i < configs.size(); ++i) {
    std::printf("%s %s\n", configs[i].first.c_str(), configSets(configs[i].first, i).c_str());
  }
}

int main(int argc, char** argv) {
  tuneAllocatorForLargeBuffers();
  const Options o = parse(argc, argv);
  if (o.list_configs) {
    listConfigs(o);
    return 0;
  }
  std::string traj_name;
  sim::Scenario sc;
  try {
    sc = loadScenario(o, &traj_name);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  std::vector<double> offsets;
  const std::vector<sim::Scenario> scenarios = startScenarios(o, sc, &offsets);
  sc = scenarios.front();
  const Configs configs = makeConfigs(o, sc);
  const double duration = sc.trajectory->endTime() - std::max(0.0, sc.trajectory->startTime());
  std::ostringstream starts;
  for (size_t i = 0; i < offsets.size(); ++i) starts << (i ? "," : "") << offsets[i];
  std::printf("study: %s, %.1f s from %s s, %zu landmarks in the world, %d runs x %zu configurations, %d threads\n",
              traj_name.c_str(), duration, starts.str().c_str(), sc.world.size(), o.runs, configs.size(), o.threads);
  const auto results = runAll(o, configs, scenarios);

  const fs::path out(o.out);
  fs::create_directories(out);
  {
    std::ofstream w(out / "world.csv");
    w << "id,x,y,z\n";
    for (const auto& l : sc.world) w << l.id << "," << l.p_n.x() << "," << l.p_n.y() << "," << l.p_n.z() << "\n";
  }
  std::vector<eval::ConsistencySummary> sums;
  for (size_t c = 0; c < configs.size(); ++c) {
    sums.push_back(eval::summarize(configs[c].first, results[c]));
    writeConfigFiles(out / configs[c].first, sums.back(), results[c], sc, o.all_runs);
  }
  const eval::Report report = summaryReport(o, traj_name, sc, offsets, duration, configs, sums);
  eval::writeReport(out.string(), "summary", report);
  std::cout << "\n" << eval::reportMarkdown(report) << "written to " << out << "\n";
  return 0;
}
