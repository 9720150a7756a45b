// Every tool answers --help with its usage (exit 0) and refuses a bad value with one error line
// (exit 2), instead of starting a long run or ending in an uncaught std::stod.
#include <cv_bridge/cv_bridge.h>
#include <gtest/gtest.h>

#include "../evo_tum_rules.h"
#include "../scratch_dir.h"
#include "vi_ekf_slam/io/tum_io.h"
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include <Eigen/Core>
#include <opencv2/imgcodecs.hpp>

#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/imu_sample_check.h"
#include "vi_ekf_slam/ros/bag_faults.h"

#include <algorithm>
#include <numeric>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

struct Outcome {
  int code = -1;
  std::string output;  ///< stdout and stderr
};

Outcome run(const std::string& command) {
  Outcome o;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return o;
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), p)) o.output += buf.data();
  const int status = pclose(p);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

struct Tool {
  const char* path;
  const char* bad_value;  ///< arguments with a value that is not a number
};

const Tool kTools[] = {
    {VI_TOOL_MAKE_BAG, "--out /tmp/x.bag --duration abc"},
    {VI_TOOL_ASL_TO_BAG, "--asl /tmp --out /tmp/x.bag --imu-margin 1s"},
    {VI_TOOL_SIMULATE_SHORT, "thirty"},
    {VI_TOOL_RUN_FEATURES, "--gate high"},
    {VI_TOOL_STUDY, "--runs many"},
    {VI_TOOL_SOAK, "--minutes half"},
    {VI_TOOL_RUN_BAG, "--bag /tmp/x.bag --reference-from-s"},
    {VI_TOOL_MAKE_WALKS, "--out /tmp/walks --bogus"},
    {VI_TOOL_PERTURB_BAG, "--bag /tmp/x.bag --out /tmp/y.bag --fault clipped_imu --size big"},
};

}  // namespace

TEST(ToolsCli, HelpPrintsUsageAndBadNumbersAreRefused) {
  for (const Tool& t : kTools) {
    const Outcome help = run(std::string(t.path) + " --help");
    EXPECT_EQ(help.code, 0) << t.path << "\n" << help.output;
    EXPECT_NE(help.output.find("usage:"), std::string::npos) << t.path;
    const Outcome bad = run(std::string(t.path) + " " + t.bad_value);
    EXPECT_EQ(bad.code, 2) << t.path << " " << t.bad_value << "\n" << bad.output;
    EXPECT_NE(bad.output.find("error:"), std::string::npos) << t.path;
  }
  const Outcome unknown = run(std::string(VI_TOOL_SOAK) + " --minute 1");  // not taken for --minutes
  EXPECT_EQ(unknown.code, 2) << unknown.output;
}

// run_bag on a user's bag: two IMU topics and JPEG images (sensor_msgs/CompressedImage). Without
// imu_topic:= it refuses and lists both; with it, it runs on the compressed images as on raw ones.
TEST(ToolsCli, RunBagPicksTopicsAndReadsCompressedImages) {
  const vi_ekf_slam::test::ScratchDir scratch("vi_ekf_slam_run_bag_topics");
  const std::string dir = scratch.path();
  ASSERT_EQ(run("rm -rf " + dir + " && mkdir -p " + dir).code, 0);
  const Outcome made = run(std::string(VI_TOOL_MAKE_BAG) + " --out " + dir + "/raw.bag --duration 6 --standing 2");
  ASSERT_EQ(made.code, 0) << made.output;
  {
    rosbag::Bag in(dir + "/raw.bag", rosbag::bagmode::Read), out(dir + "/user.bag", rosbag::bagmode::Write);
    for (const rosbag::MessageInstance& m : rosbag::View(in)) {
      if (auto img = m.instantiate<sensor_msgs::Image>()) {
        sensor_msgs::CompressedImage c;
        c.header = img->header;
        c.format = "mono8; jpeg compressed mono8";
        std::vector<uchar> jpg;
        cv::imencode(".jpg", cv_bridge::toCvShare(img)->image, jpg, {cv::IMWRITE_JPEG_QUALITY, 95});
        c.data = jpg;
        out.write("/cam/image/compressed", m.getTime(), c);
      } else if (auto imu = m.instantiate<sensor_msgs::Imu>()) {
        out.write("/imu/data", m.getTime(), *imu);
        out.write("/imu/data_raw", m.getTime(), *imu);
      } else if (m.getTopic() != "/ground_truth/pose") {  // a user's recording has none
        out.write(m.getTopic(), m.getTime(), m);
      }
    }
  }
  const Outcome help = run(std::string(VI_TOOL_RUN_BAG) + " --help");
  EXPECT_EQ(help.code, 0) << help.output;
  EXPECT_NE(help.output.find("--image-topic"), std::string::npos) << help.output;
  const std::string base =
      std::string(VI_TOOL_RUN_BAG) + " --bag " + dir + "/user.bag --out " + dir + "/out --no-plots";
  const Outcome ambiguous = run(base);
  EXPECT_EQ(ambiguous.code, 2) << ambiguous.output;
  EXPECT_NE(ambiguous.output.find("/imu/data_raw"), std::string::npos) << ambiguous.output;
  EXPECT_NE(ambiguous.output.find("--imu-topic"), std::string::npos) << ambiguous.output;
  const Outcome ok = run(base + " --imu-topic /imu/data");
  EXPECT_EQ(ok.code, 0) << ok.output;
  // It says which topics it read and why.
  EXPECT_NE(ok.output.find("reading imu /imu/data (given with --imu-topic), image /cam/image/compressed (the bag's "
                           "only sensor_msgs/Image topic)"),
            std::string::npos)
      << ok.output;
  EXPECT_NE(ok.output.find("the bag has no ground truth"), std::string::npos) << ok.output;
  // In a pipe, the log lines come in the order they were written, before the run's summary.
  EXPECT_LT(ok.output.find("initialized: static"), ok.output.find("sensor_centric_composition: ")) << ok.output;
  EXPECT_LT(ok.output.find("initialized: static"), ok.output.find("# Run health")) << ok.output;
  // The start's time is in the events file (on the bag's IMU clock).
  {
    std::ifstream events(dir + "/out/sensor_centric_composition_events.csv");
    std::string header, first;
    std::getline(events, header);
    std::getline(events, first);
    EXPECT_NE(first.find("\"initialized"), std::string::npos) << first;
    EXPECT_GT(std::stod(first.substr(0, first.find(','))), 1.0) << first;
  }
  // The compressed images reached the filter: it initialized and tracked (no "0 images").
  EXPECT_NE(ok.output.find("sensor_centric_composition: "), std::string::npos) << ok.output;
  EXPECT_EQ(ok.output.find(": 0 images"), std::string::npos) << ok.output;
  EXPECT_EQ(ok.output.find("not decoded"), std::string::npos) << ok.output;
  // A rig file on top of the defaults (make realdata's --rig), and a parameter on the command line.
  std::ofstream(dir + "/rig.yaml") << "max_landmarks: 120\n";
  const Outcome rig = run(base + " --imu-topic /imu/data --rig " + dir + "/rig.yaml --mechanization world_centric");
  EXPECT_EQ(rig.code, 0) << rig.output;
  EXPECT_NE(rig.output.find("world_centric: "), std::string::npos) << rig.output;
  const Outcome typo = run(base + " --imu-topic /imu/data --param max_landmark=120");
  EXPECT_EQ(typo.code, 2) << typo.output;  // the command line does not fit
  EXPECT_NE(typo.output.find("max_landmarks"), std::string::npos) << typo.output;
  // A reference trusted only from some seconds on (--reference-from-s): the run's own trajectory
  // as the reference, whole and from 4 s of the 8 s bag on (poses from 1 s, after the static start):
  // fewer poses compared, each matching itself.
  const std::string own = dir + "/own.tum";
  ASSERT_EQ(run("cp " + dir + "/out/world_centric.tum " + own).code, 0);
  const Outcome refs =
      run(base + " --imu-topic /imu/data --rig " + dir + "/rig.yaml --mechanization world_centric --reference " + own +
          " --reference " + own + " --reference-from-s 0 --reference-from-s 4");
  EXPECT_EQ(refs.code, 0) << refs.output;
  // What run_bag wrote for the two comparisons (health.json: one entry per reference).
  const nlohmann::json refs_json =
      nlohmann::json::parse(std::ifstream(dir + "/out/health.json"))["runs"]["world_centric"]["references"];
  ASSERT_EQ(refs_json.size(), 2u) << refs_json.dump();
  const int whole = refs_json[0]["matched"], from_4 = refs_json[1]["matched"];
  EXPECT_EQ(refs_json[1]["from_s"], 4.0) << refs_json.dump();
  EXPECT_GT(from_4, whole / 3) << refs_json.dump();  // 4 s of the 7 s with poses
  EXPECT_LT(from_4, 2 * whole / 3) << refs_json.dump();
  EXPECT_LT(refs_json[1]["position_rmse_m"].get<double>(), 1e-6) << refs_json.dump();
  EXPECT_NE(refs.output.find("imu clock, from 4 s): " + std::to_string(from_4) + " matched"), std::string::npos)
      << refs.output;
  // The comparisons it made end the output; no remark about a missing ground truth then.
  EXPECT_NE(refs.output.find("Against the references"), std::string::npos) << refs.output;
  EXPECT_NE(refs.output.find("world_centric vs " + own + ": sim3, " + std::to_string(from_4) + " poses, from 4 s"),
            std::string::npos)
      << refs.output;
  EXPECT_EQ(refs.output.find("the bag has no ground truth"), std::string::npos) << refs.output;
  // A preset's topic the bag lacks is said, not passed over in silence.
  const Outcome other_rig = run(std::string(VI_TOOL_RUN_BAG) + " --bag " + dir + "/user.bag --out " + dir +
                                "/d435i --no-plots --imu-topic /imu/data --rig d435i --mechanization world_centric");
  EXPECT_NE(other_rig.output.find("the bag's only sensor_msgs/Image topic; image_topic /camera/infra1/image_rect_raw "
                                  "is not in the bag"),
            std::string::npos)
      << other_rig.output;
  // A camera that does not fit the images (tum_vi's 512x512 on these): an error, not "ATE 0".
  const Outcome unfit = run(std::string(VI_TOOL_RUN_BAG) + " --bag " + dir + "/user.bag --out " + dir +
                            "/unfit --no-plots --imu-topic /imu/data --rig tum_vi --mechanization world_centric");
  EXPECT_EQ(unfit.code, 1) << unfit.output;
  EXPECT_NE(unfit.output.find("error: none of the"), std::string::npos) << unfit.output;
  EXPECT_NE(unfit.output.find("differs from the calibration 512x512"), std::string::npos) << unfit.output;
  EXPECT_FALSE(std::ifstream(dir + "/unfit/world_centric.tum").good()) << "an empty trajectory written";
  // The trajectory is a TUM file evo reads, its covariances beside it, one per pose.
  EXPECT_EQ(vi_ekf_slam::test::evoStrictTumProblem(dir + "/out/world_centric.tum"), "");
  std::vector<vi_ekf_slam::io::StampedPose> written = vi_ekf_slam::io::readTum(dir + "/out/world_centric.tum");
  EXPECT_EQ(vi_ekf_slam::io::readPoseCovariances(dir + "/out/world_centric_covariance.txt", &written),
            static_cast<int>(written.size()));
  // EuRoC's ground-truth CSV is a reference too: the run's own trajectory written that way.
  {
    std::ofstream csv(dir + "/own.csv");
    csv << "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z "
           "[],v,v,v,b,b,b,b,b,b\n";
    for (const auto& p : written) {
      csv << std::llround(p.t * 1e9) << std::setprecision(12) << "," << p.p.x() << "," << p.p.y() << "," << p.p.z()
          << "," << p.q.w() << "," << p.q.x() << "," << p.q.y() << "," << p.q.z() << ",0,0,0,0,0,0,0,0,0\n";
    }
  }
  const Outcome euroc = run(base + " --imu-topic /imu/data --rig " + dir +
                            "/rig.yaml --mechanization world_centric --reference " + dir + "/own.csv");
  EXPECT_EQ(euroc.code, 0) << euroc.output;
  const nlohmann::json euroc_json =
      nlohmann::json::parse(std::ifstream(dir + "/out/health.json"))["runs"]["world_centric"]["references"][0];
  EXPECT_EQ(euroc_json["matched"], whole) << euroc_json.dump();
  EXPECT_LT(euroc_json["position_rmse_m"].get<double>(), 1e-6) << euroc_json.dump();
  const Outcome negative = run(base + " --imu-topic /imu/data --reference " + own + " --reference-from-s -1");
  EXPECT_EQ(negative.code, 2) << negative.output;
  EXPECT_NE(negative.output.find("--reference-from-s"), std::string::npos) << negative.output;
}

// The suite runs on whatever trajectories a user drops into DATA_DIR/trajectories: a file the
// study refuses is a row of the table that says why, the other cases still run, and the suite
// ends non-zero. (A stand-in study answers at once; the real one would take minutes per case.)
TEST(ToolsCli, SuiteReportsACaseTheStudyCannotRunAndGoesOn) {
  const vi_ekf_slam::test::ScratchDir scratch("vi_ekf_slam_suite_failure");
  const std::string dir = scratch.path();
  ASSERT_EQ(run("rm -rf " + dir + " && mkdir -p " + dir + "/data/trajectories").code, 0);
  std::ofstream(dir + "/data/trajectories/broken.txt") << "10.0 1 2 3 0 0 0 1\n9.0 1 2 3 0 0 0 1\n";
  std::ofstream(dir + "/data/trajectories/walk.txt") << "10.0 1 2 3 0 0 0 1\n";
  std::ofstream(dir + "/study.sh") << R"(#!/bin/sh
while [ $# -gt 0 ]; do
  case "$1" in --trajectory) traj="$2"; shift;; --out) out="$2"; shift;; esac; shift
done
case "$traj" in *broken*) echo "error: $traj:2: time does not increase" >&2; exit 1;; esac
mkdir -p "$out"
echo '{"schema": "vi_ekf_slam.report/1", "tool": "study", "title": "stand-in", "config": {"pose_nees_band": [3.84, 8.63]},
 "runs": {"default": {"ate_position_m": 0.2, "ate_posyaw_m": 0.1, "nees_pose": 6.1, "consistent_fraction": 0.97,
  "revisit_error_ratio": 1.5, "revisits_per_run": 12.0, "false_revisits": 0, "filter_ms_mean": 2.0}}}' > "$out/summary.json"
)";
  ASSERT_EQ(run("chmod +x " + dir + "/study.sh").code, 0);
  const std::string suite = "python3 " + std::string(VI_EKF_SLAM_SOURCE_DIR) + "/tools/suite.py --study " + dir +
                            "/study.sh --make-walks " + VI_TOOL_MAKE_WALKS + " --data " + dir + "/data --out " + dir +
                            "/out --runs 2 --configs default";
  const Outcome o = run(suite);
  EXPECT_EQ(o.code, 1) << o.output;
  EXPECT_NE(o.output.find("| broken@0 / default | - | - | - | no | - | - | error: " + dir +
                          "/data/trajectories/broken.txt:2: time does not increase |"),
            std::string::npos)
      << o.output;
  EXPECT_NE(o.output.find("| walk@0 / default | 0.200 | 0.100 | 6.10 | yes | 0.97 |"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("| walk_stairs / default | 0.200 |"), std::string::npos) << o.output;
  // The worst case counts it as failed, not as a NEES.
  EXPECT_NE(o.output.find("| default | 6.10 | 0 | 0.97 | - | 1 |"), std::string::npos) << o.output;
  EXPECT_TRUE(std::ifstream(dir + "/out/suite.md").good());
  // The map's walks, each kept and forgotten (the stand-in gives both the same).
  EXPECT_NE(o.output.find("| laps, tiled | 0.100 | 0.100 | 1.00 | 1.50 | 1.50 | 12.0 | 0 | 6.10 | yes | 0.97 |"),
            std::string::npos)
      << o.output;
  EXPECT_TRUE(std::ifstream(dir + "/out/map/suite_map.md").good());
  // The suite's report in the tools' one schema, its cases and worst case as tables.
  const nlohmann::json suite_json = nlohmann::json::parse(std::ifstream(dir + "/out/suite.json"));
  EXPECT_EQ(suite_json["schema"], "vi_ekf_slam.report/1");
  EXPECT_EQ(suite_json["tool"], "suite");
  EXPECT_EQ(suite_json["runs"]["walk@0 / default"]["nees_pose"], 6.1);
  EXPECT_EQ(suite_json["tables"]["worst"]["default"]["failed"], 1);

  // --walks: the named generated walks and no others, also in a folder that held the
  // default ones; an unknown kind ends the suite before any case runs.
  const Outcome w = run(suite + " --walks slow_walk,stairs");
  EXPECT_NE(w.output.find("| walk_slow_walk / default | 0.200 |"), std::string::npos) << w.output;
  EXPECT_NE(w.output.find("| walk_stairs / default | 0.200 |"), std::string::npos) << w.output;
  EXPECT_EQ(w.output.find("walk_crawl"), std::string::npos) << w.output;
  const Outcome unknown = run(suite + " --walks nope");
  EXPECT_NE(unknown.code, 0);
  EXPECT_NE(unknown.output.find("unknown walk 'nope'"), std::string::npos) << unknown.output;
  EXPECT_EQ(unknown.output.find("| builtin |"), std::string::npos) << unknown.output;
}

// The study writes run 0's errors and sigmas (run0.csv) and, with --all-runs, every run's: the file
// that shows which runs carry a run-averaged NEES. Each row ends with the time offset's error and
// sigma, which start at the prior's (the simulator's offset is 0, the filter starts at 0).
TEST(ToolsCli, StudyWritesEveryRunsErrorsWithAllRuns) {
  const vi_ekf_slam::test::ScratchDir scratch("vi_ekf_slam_study_all_runs");
  const std::string dir = scratch.path();
  ASSERT_EQ(run("rm -rf " + dir).code, 0);
  const std::string study =
      std::string(VI_TOOL_STUDY) + " --trajectory builtin --runs 2 --max-duration 2 --configs default";
  const Outcome one = run(study + " --out " + dir + "/one");
  ASSERT_EQ(one.code, 0) << one.output;
  EXPECT_TRUE(std::ifstream(dir + "/one/default/run0.csv").good());
  EXPECT_FALSE(std::ifstream(dir + "/one/default/run1.csv").good());
  const Outcome all = run(study + " --all-runs --out " + dir + "/all");
  ASSERT_EQ(all.code, 0) << all.output;
  for (const char* name : {"run0.csv", "run1.csv", "landmarks_run1.csv"})
    EXPECT_TRUE(std::ifstream(dir + "/all/default/" + name).good()) << name;
  std::ifstream f(dir + "/all/default/run1.csv");
  std::string header, first;
  ASSERT_TRUE(std::getline(f, header) && std::getline(f, first));
  EXPECT_EQ(header.substr(header.size() - 10), ",e_td,s_td");
  const double s_td = std::stod(first.substr(first.rfind(',') + 1));
  const std::string without_s = first.substr(0, first.rfind(','));
  const double e_td = std::stod(without_s.substr(without_s.rfind(',') + 1));
  const double prior = vi_ekf_slam::InitialUncertainty{}.time_offset_s;
  EXPECT_NEAR(s_td, prior, 0.1 * prior);  // one image after the start: hardly observed yet
  EXPECT_LT(std::abs(e_td), 3.0 * s_td);
}

// --imu-biases none: the simulated IMU has no turn-on biases while the filter keeps its prior (the
// diagnostic of docs/initialization.md). The first image's accelerometer-bias error is then what
// one image's update moved the estimate by (< 1 mm/s^2 measured), against the drawn 0.05 m/s^2
// sigma otherwise; the summary says which it was; another word is refused.
TEST(ToolsCli, StudyRunsAnImuWithoutBiasesWhenAsked) {
  const vi_ekf_slam::test::ScratchDir scratch("vi_ekf_slam_study_imu_biases");
  const std::string dir = scratch.path();
  ASSERT_EQ(run("rm -rf " + dir).code, 0);
  const std::string study = std::string(VI_TOOL_STUDY) +
                            " --trajectory builtin --runs 2 --max-duration 2 --configs default --all-runs --out " + dir;
  auto largest_accel_bias_error = [&](const std::string& sub) {
    double largest = 0.0;
    for (const char* name : {"run0.csv", "run1.csv"}) {
      std::ifstream f(dir + "/" + sub + "/default/" + name);
      std::string header, first;
      EXPECT_TRUE(std::getline(f, header) && std::getline(f, first)) << name;
      std::vector<std::string> keys, values;
      for (auto [line, out] : {std::pair{&header, &keys}, std::pair{&first, &values}}) {
        std::stringstream ss(*line);
        for (std::string item; std::getline(ss, item, ',');) out->push_back(item);
      }
      for (size_t i = 0; i < keys.size() && i < values.size(); ++i)
        if (keys[i].rfind("e_ba_", 0) == 0) largest = std::max(largest, std::abs(std::stod(values[i])));
    }
    return largest;
  };
  ASSERT_EQ(run(study + "/none --imu-biases none").code, 0);
  ASSERT_EQ(run(study + "/drawn").code, 0);
  EXPECT_LT(largest_accel_bias_error("none"), 0.005);
  EXPECT_GT(largest_accel_bias_error("drawn"), 0.02);  // six draws of a 0.05 m/s^2 sigma
  std::ifstream summary(dir + "/none/summary.json");
  const nlohmann::json s = nlohmann::json::parse(summary);
  EXPECT_EQ(s["schema"], "vi_ekf_slam.report/1");
  EXPECT_EQ(s["tool"], "study");
  EXPECT_EQ(s["config"]["imu_biases"], "none");
  EXPECT_EQ(s["runs"]["default"]["runs"], 2);
  const Outcome bad = run(std::string(VI_TOOL_STUDY) + " --imu-biases zero");
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--imu-biases must be drawn or none"), std::string::npos) << bad.output;
}

// Every current number lives in docs/results.md (generated by make results); the README quotes its
// first section, and the quote must be the page's, not an older copy. A README edited by hand, or a
// page regenerated without the README, fails here.
TEST(ToolsCli, TheReadmeQuotesTheResultsPage) {
  const std::string dir = VI_EKF_SLAM_SOURCE_DIR;
  const Outcome ok = run("/usr/bin/python3 " + dir + "/tools/results_page.py --check --out " + dir +
                         "/docs/results.md --readme " + dir + "/README.md");
  EXPECT_EQ(ok.code, 0) << ok.output;
  // A README whose quote differs by one digit is refused.
  std::ifstream in(dir + "/README.md");
  std::stringstream readme;
  readme << in.rdbuf();
  std::string changed = readme.str();
  const size_t quote = changed.find("<!-- results:");
  ASSERT_NE(quote, std::string::npos);
  const size_t digit = changed.find_first_of("0123456789", changed.find("|", quote));
  ASSERT_NE(digit, std::string::npos);
  changed[digit] = changed[digit] == '9' ? '8' : static_cast<char>(changed[digit] + 1);
  const vi_ekf_slam::test::ScratchDir scratch("vi_ekf_slam_readme");
  const std::string tmp = scratch / "README_changed.md";
  std::ofstream(tmp) << changed;
  const Outcome bad = run("/usr/bin/python3 " + dir + "/tools/results_page.py --check --out " + dir +
                          "/docs/results.md --readme " + tmp);
  EXPECT_NE(bad.code, 0) << bad.output;
}

// run_bag finds its default configuration as a ROS tool finds a package (devel or install space),
// never in the source tree it was built from: without the package on ROS_PACKAGE_PATH and without
// --config it says so and stops.
TEST(ToolsCli, RunBagFindsItsDefaultsThroughThePackageNotTheSourceTree) {
  const vi_ekf_slam::test::ScratchDir empty("vi_ekf_slam_no_packages");
  const Outcome o = run("env ROS_PACKAGE_PATH=" + empty.path() + " " + VI_TOOL_RUN_BAG + " --bag /nonexistent.bag");
  EXPECT_EQ(o.code, 2) << o.output;
  EXPECT_NE(o.output.find("ROS_PACKAGE_PATH"), std::string::npos) << o.output;
}

namespace {
/// Per topic: messages, IMU samples with a NaN, IMU samples at the default range, black images.
struct BagCounts {
  int imu = 0, images = 0, imu_nan = 0, imu_at_range = 0, black = 0;
};
BagCounts countBag(const std::string& path) {
  BagCounts c;
  const vi_ekf_slam::ImuCheckParams range;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto imu = m.instantiate<sensor_msgs::Imu>()) {
      ++c.imu;
      const double a[] = {imu->linear_acceleration.x, imu->linear_acceleration.y, imu->linear_acceleration.z};
      bool nan = false, at_range = false;
      for (double v : a) {
        nan = nan || std::isnan(v);
        at_range = at_range || std::abs(v) >= range.accel_range_mps2;
      }
      c.imu_nan += nan;
      c.imu_at_range += at_range;
    } else if (auto img = m.instantiate<sensor_msgs::Image>()) {
      ++c.images;
      c.black += std::all_of(img->data.begin(), img->data.end(), [](uint8_t v) { return v == 0; });
    }
  }
  return c;
}
}  // namespace

// vi_ekf_slam_perturb_bag: each fault class as its size says, on a short rendered bag; the rest
// of the bag as it was.
TEST(ToolsCli, PerturbBagWritesEachFaultClassAsItsSizeSays) {
  const vi_ekf_slam::test::ScratchDir scratch("vi_ekf_slam_perturb");
  const std::string dir = scratch.path();
  ASSERT_EQ(run("rm -rf " + dir + " && mkdir -p " + dir).code, 0);
  ASSERT_EQ(run(std::string(VI_TOOL_MAKE_BAG) + " --out " + dir + "/in.bag --duration 9 --standing 1").code, 0);
  const BagCounts clean = countBag(dir + "/in.bag");
  ASSERT_GT(clean.images, 200);
  auto perturbed = [&](const std::string& fault, double size) {
    vi_ekf_slam::glue::FaultPlan plan;
    plan.fault = *vi_ekf_slam::glue::faultClassFromString(fault);
    plan.size = size;
    vi_ekf_slam::glue::perturbBag(dir + "/in.bag", dir + "/" + fault + ".bag", plan);
    return countBag(dir + "/" + fault + ".bag");
  };
  // One clipped sample every 2 s of the 8.5 s between 10% and 95% of the 10 s bag: 4 or 5.
  const BagCounts clipped = perturbed("clipped_imu", 2.0);
  EXPECT_GE(clipped.imu_at_range, 4);
  EXPECT_LE(clipped.imu_at_range, 5);
  EXPECT_EQ(clipped.imu, clean.imu);
  const BagCounts gaps = perturbed("sensor_gaps", 0.2);  // 3 x 0.2 s of IMU, 2 x 1.2 s of images
  EXPECT_NEAR(clean.imu - gaps.imu, 3 * 0.2 * 200, 6);
  EXPECT_NEAR(clean.images - gaps.images, 2 * 1.2 * 28, 4);
  const BagCounts covered = perturbed("covered_lens", 1.0);
  EXPECT_NEAR(covered.black, 28, 2);
  EXPECT_EQ(covered.images, clean.images);
  // A fault of one moment placed elsewhere (the fault matrix places it at several): black from
  // 20% of the bag on, for the same length.
  vi_ekf_slam::glue::FaultPlan early;
  early.fault = vi_ekf_slam::glue::FaultClass::kCoveredLens;
  early.size = 1.0;
  early.at_fraction = 0.2;
  const auto early_counts = vi_ekf_slam::glue::perturbBag(dir + "/in.bag", dir + "/early.bag", early);
  const auto middle_counts = vi_ekf_slam::glue::perturbBag(dir + "/in.bag", dir + "/middle.bag", [] {
    vi_ekf_slam::glue::FaultPlan p;
    p.fault = vi_ekf_slam::glue::FaultClass::kCoveredLens;
    p.size = 1.0;
    return p;
  }());
  ASSERT_EQ(early_counts.intervals.size(), 1u);
  ASSERT_EQ(middle_counts.intervals.size(), 1u);
  // The bag spans about 10 s: 0.5 - 0.2 of it is about 3 s earlier.
  EXPECT_NEAR(middle_counts.intervals[0].first - early_counts.intervals[0].first, 3.0, 0.2);
  EXPECT_NEAR(early_counts.images_black, 28, 2);
  const Outcome misplaced = run(std::string(VI_TOOL_PERTURB_BAG) + " --bag " + dir + "/in.bag --out " + dir +
                                "/x.bag --fault nan_imu --at 0.2");
  EXPECT_EQ(misplaced.code, 1) << misplaced.output;
  EXPECT_NE(misplaced.output.find("one moment"), std::string::npos) << misplaced.output;
  // Darkness: a twentieth of the light and the sensor's noise for its length, at its moment.
  vi_ekf_slam::glue::FaultPlan dark;
  dark.fault = vi_ekf_slam::glue::FaultClass::kDarkness;
  dark.size = 1.0;
  const auto dark_counts = vi_ekf_slam::glue::perturbBag(dir + "/in.bag", dir + "/dark.bag", dark);
  EXPECT_NEAR(dark_counts.images_dim, 28, 2);
  ASSERT_EQ(dark_counts.intervals.size(), 1u);
  double dark_mean = 0.0, clean_mean = 0.0;
  {
    rosbag::Bag a(dir + "/in.bag", rosbag::bagmode::Read), b(dir + "/dark.bag", rosbag::bagmode::Read);
    auto meanAt = [&](rosbag::Bag& bag, double t) {
      for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
        auto img = m.instantiate<sensor_msgs::Image>();
        if (img && std::abs(m.getTime().toSec() - t) < 0.02)
          return std::accumulate(img->data.begin(), img->data.end(), 0.0) / img->data.size();
      }
      return -1.0;
    };
    const double mid = 0.5 * (dark_counts.intervals[0].first + dark_counts.intervals[0].second);
    clean_mean = meanAt(a, mid);
    dark_mean = meanAt(b, mid);
  }
  ASSERT_GT(clean_mean, 20.0);
  // 5% of the light plus zero-mean noise (clipped at black: a little above 5%).
  EXPECT_GT(dark_mean, 0.03 * clean_mean);
  EXPECT_LT(dark_mean, 0.05 * clean_mean + 4.0);
  const BagCounts nan = perturbed("nan_imu", 3.0);
  EXPECT_GE(nan.imu_nan, 2);
  const BagCounts lossy = perturbed("lossy_link", 0.2);
  EXPECT_LT(lossy.images, clean.images * 1.0);
  EXPECT_GT(lossy.images, clean.images * 0.7);
  // The tool names its classes (the fault matrix reads them), and refuses what it does not know.
  const Outcome list = run(std::string(VI_TOOL_PERTURB_BAG) + " --list-faults");
  EXPECT_EQ(list.code, 0) << list.output;
  EXPECT_EQ(std::count(list.output.begin(), list.output.end(), '\n'), 7) << list.output;
  EXPECT_NE(list.output.find("lossy_link\n"), std::string::npos) << list.output;
  const Outcome moments = run(std::string(VI_TOOL_PERTURB_BAG) + " --list-moment-faults");
  EXPECT_EQ(moments.output, "covered_lens\ndim_images\ndarkness\n");
  const Outcome unknown =
      run(std::string(VI_TOOL_PERTURB_BAG) + " --bag " + dir + "/in.bag --out " + dir + "/x.bag --fault glove");
  EXPECT_EQ(unknown.code, 2) << unknown.output;
  EXPECT_NE(unknown.output.find("covered_lens"), std::string::npos) << unknown.output;
}

// run_bag keeps the whole run: a filter told that walking speed is implausible (lost above
// 0.5 m/s over 0.5 s) is lost again and again on the rendered walk; the trajectory file still
// covers the walk from the first start to the end, continuous across each reset (the odom frame),
// the resets are in <run>_events.csv and counted in health.json, and --segments writes each
// stretch in the filter's own world.
TEST(ToolsCli, RunBagWritesTheWholeRunAcrossResets) {
  const vi_ekf_slam::test::ScratchDir scratch("vi_ekf_slam_run_bag_resets");
  const std::string dir = scratch.path();
  ASSERT_EQ(run("rm -rf " + dir + " && mkdir -p " + dir).code, 0);
  ASSERT_EQ(run(std::string(VI_TOOL_MAKE_BAG) + " --out " + dir + "/walk.bag --duration 10 --standing 1").code, 0);
  const Outcome o =
      run(std::string(VI_TOOL_RUN_BAG) + " --bag " + dir + "/walk.bag --out " + dir +
          "/out --no-plots --segments --mechanization sensor_centric_composition --param lost_max_speed_mps=0.5 "
          "--param lost_window_s=0.5");
  ASSERT_EQ(o.code, 0) << o.output;
  const nlohmann::json h =
      nlohmann::json::parse(std::ifstream(dir + "/out/health.json"))["runs"]["sensor_centric_composition"];
  const int resets = h["resets"];
  EXPECT_GE(resets, 2) << h.dump();
  EXPECT_EQ(h["inputs"]["divergences"], resets);
  std::ifstream events(dir + "/out/sensor_centric_composition_events.csv");
  int reset_lines = 0, starts = 0;
  for (std::string line; std::getline(events, line);) {
    reset_lines += line.find("\"reset: lost") != std::string::npos;
    starts += line.find("\"initialized") != std::string::npos;
  }
  EXPECT_EQ(reset_lines, resets);
  EXPECT_GE(starts, 2);
  // The whole walk after the first start (1 s standing), continuous: no jump between poses beyond
  // what 2 m/s would move in the time between them, across every restart.
  std::ifstream tum(dir + "/out/sensor_centric_composition.tum");
  double t_first = -1.0, t_last = 0.0, largest_speed = 0.0;
  Eigen::Vector3d last = Eigen::Vector3d::Zero();
  for (std::string line; std::getline(tum, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    double t;
    Eigen::Vector3d p;
    ss >> t >> p.x() >> p.y() >> p.z();
    if (t_first >= 0.0 && t > t_last) largest_speed = std::max(largest_speed, (p - last).norm() / (t - t_last));
    if (t_first < 0.0) t_first = t;
    t_last = t;
    last = p;
  }
  EXPECT_GT(t_last - t_first, 9.0);
  EXPECT_LT(largest_speed, 2.0);
  EXPECT_NEAR(h["output_s"].get<double>(), t_last - t_first, 1e-6);
  // One stretch per start (in the filter's own world, which starts over at each).
  int segments = 0;
  while (std::ifstream(dir + "/out/sensor_centric_composition_segment_" + std::to_string(segments) + ".tum").good())
    ++segments;
  EXPECT_GE(segments, starts - 1);
  EXPECT_GE(segments, 2);
}

// run_bag --extrinsic-error gives the filter the parameters' extrinsic turned and moved by the
// amounts asked, and says how far that and its estimate are from the parameters' own.
TEST(ToolsCli, RunBagGivesTheFilterTheExtrinsicErrorAsked) {
  const vi_ekf_slam::test::ScratchDir dir("vi_ekf_slam_extrinsic_error");
  ASSERT_EQ(run(std::string(VI_TOOL_MAKE_BAG) + " --out " + dir / "walk.bag" + " --duration 4 --standing 1").code, 0);
  const std::string base = std::string(VI_TOOL_RUN_BAG) + " --bag " + dir / "walk.bag" + " --out " + dir / "out" +
                           " --no-plots --param extrinsic_source=parameters --param T_b_c=[0.1,0,0,-0.5,0.5,-0.5,0.5]"
                           " --param estimate_extrinsic=true";
  const Outcome o = run(base + " --extrinsic-error 3,0.03,0,0,1,1,-1,1");
  ASSERT_EQ(o.code, 0) << o.output;
  const nlohmann::json h =
      nlohmann::json::parse(std::ifstream(dir / "out/health.json"))["runs"]["sensor_centric_composition"];
  EXPECT_NEAR(h["extrinsic_error"]["given"]["deg"].get<double>(), 3.0, 1e-9) << h.dump();
  EXPECT_NEAR(h["extrinsic_error"]["given"]["m"].get<double>(), 0.03, 1e-12) << h.dump();
  EXPECT_TRUE(h["extrinsic_error"]["final"]["deg"].is_number()) << h.dump();
  const Outcome bad = run(base + " --extrinsic-error 3");
  EXPECT_EQ(bad.code, 2) << bad.output;
}

// The scripts' reports go through the C++ writer: a metric key gets the one header of
// eval/report_columns.h, a script's own column its own; JSON and Markdown are written.
TEST(ToolsCli, TheScriptsReportsAreWrittenByTheOneWriter) {
  const vi_ekf_slam::test::ScratchDir dir("vi_ekf_slam_script_report");
  const std::string script =
      "import sys; sys.path.insert(0, '" + std::string(VI_EKF_SLAM_SOURCE_DIR) +
      "/tools'); import report; "
      "r = report.report('t', 'A title', {'seed': 1}, {'a': {'ate_position_m': 0.5, 'x': 2, 'n': float('nan')}}); "
      "print(report.write_report('" +
      dir.path() +
      "', 'r', r, columns=['ate_position_m', ('x', 'my x', 0), "
      "('n', 'n', 1)]))";
  const Outcome o = run("env VI_EKF_SLAM_BIN=" + std::filesystem::path(VI_TOOL_RUN_BAG).parent_path().string() +
                        " /usr/bin/python3 -c \"" + script + "\"");
  ASSERT_EQ(o.code, 0) << o.output;
  EXPECT_NE(o.output.find("| | ATE [m] | my x | n |"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("| a | 0.500 | 2 | - |"), std::string::npos) << o.output;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "r.json"));
  EXPECT_EQ(j["schema"], "vi_ekf_slam.report/1");
  EXPECT_TRUE(j["runs"]["a"]["n"].is_null());
}
