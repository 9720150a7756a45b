// The processor on the simulated rig's stream (synthetic_rig.h) in simulated time: each bad input
// and fault, a reset while walking and a calibration file, fed message by message as fast as the
// CPU allows. They were rostests streaming in real time; the node's wiring (nodelet, topics, TF,
// transport, reconfigure server, reset service) keeps its rostests (test/ros/*.test).
#include <gtest/gtest.h>
#include <tf2/buffer_core.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <functional>
#include <map>

#include "synthetic_rig.h"
#include "msg_eigen.h"
#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/ros/conversions.h"
#include "vi_ekf_slam/ros/ekf_slam_processor.h"

namespace vi_ekf_slam::glue {
namespace {

using test::pos;
using test::quat;
using test::RigOptions;

struct Recorder : OutputSink {
  std::vector<nav_msgs::Odometry> odom;
  std::vector<vi_ekf_slam::FilterStatus> statuses;
  std::vector<std::string> events;
  int clouds = 0;
  void odometry(const nav_msgs::Odometry& o) override { odom.push_back(o); }
  void landmarks(const std::vector<LandmarkOutput>&, const ros::Time&) override { ++clouds; }
  void status(const vi_ekf_slam::FilterStatus& s) override { statuses.push_back(s); }
  void event(const std::string& e, double) override { events.push_back(e); }
};

/// What a run must show (the former rostest parameters).
struct Expect {
  bool odom = true;
  double min_odom_hz = 15.0;       ///< odometry messages per second of stream time
  double max_final_error_m = 0.0;  ///< after registering the first pose (0: not checked)
  int min_inputs_level = 0;        ///< the inputs' health must reach it once (1 WARN, 2 ERROR)
  std::string event = "";          ///< a substring some event must contain
  long min_resets = 0;
};

struct StreamRun {
  Recorder out;
  InputCounters counters;
  int max_level = 0;
  std::map<double, geometry_msgs::Pose> truth;
  double reset_stamp = 0.0;
};

/// Feeds the stream; `at` is called before each message with the processor and the stream time
/// since the first odometry (negative before it).
StreamRun runStream(const RigOptions& rig, NodeParams params,
                    const std::function<void(EkfSlamProcessor&, double since_first_odom, StreamRun&)>& at = {}) {
  ros::Time::init();
  const test::RigStream stream = test::makeRigStream(rig, 1000.0);
  tf2::BufferCore tf;
  tf.setTransform(stream.imu_camera, "rig", true);
  params.node.tune_allocator = false;
  StreamRun run;
  EkfSlamProcessor p(params, run.out, &tf);
  for (const auto& m : stream.messages) {
    if (at) {
      const double since = run.out.odom.empty() ? -1.0 : m.play_t + 1000.0 - run.out.odom.front().header.stamp.toSec();
      at(p, since, run);
    }
    std::visit(
        [&](const auto& msg) {
          using T = std::decay_t<decltype(msg)>;
          if constexpr (std::is_same_v<T, sensor_msgs::Imu>) p.imu(msg);
          if constexpr (std::is_same_v<T, sensor_msgs::Image>) p.image(msg);
          if constexpr (std::is_same_v<T, sensor_msgs::CameraInfo>) p.cameraInfo(msg);
          if constexpr (std::is_same_v<T, geometry_msgs::PoseStamped>) run.truth[msg.header.stamp.toSec()] = msg.pose;
        },
        m.msg);
    run.max_level = std::max(run.max_level, p.inputsHealth().first);
  }
  run.counters = p.counters();
  return run;
}

NodeParams testParams() {
  const std::string dir = VI_EKF_SLAM_SOURCE_DIR;
  YamlParams yaml(dir + "/config/vi_ekf_slam.yaml");
  yaml.overlay(YamlParams(dir + "/test/ros/test_config.yaml"));  // the simulated IMU, a 2-core tracker load
  NodeParams p;
  EXPECT_EQ(loadParams(yaml, &p), "");
  return p;
}

/// The checks every run gets: nothing non-finite, odometry at the camera rate with landmarks and
/// a status per image, the final error after registering the first pose (after the last restart
/// of the stamps), the health level, the events and the resets.
void check(const StreamRun& r, const Expect& e) {
  for (const auto& o : r.out.odom) ASSERT_TRUE(allFinite(o)) << "non-finite odometry";
  if (!e.odom) {
    EXPECT_TRUE(r.out.odom.empty()) << "odometry published although it should not";
  } else {
    ASSERT_GT(r.out.odom.size(), 20u);
    const double span = r.out.odom.back().header.stamp.toSec() - r.out.odom.front().header.stamp.toSec();
    EXPECT_GE((r.out.odom.size() - 1) / std::max(1e-6, span), e.min_odom_hz) << "odometry rate";
    EXPECT_GT(r.out.clouds, 5) << "landmark clouds";
    ASSERT_GT(r.out.statuses.size(), 20u) << "status messages";
    EXPECT_GT(r.out.statuses.back().landmarks_in_state, 0);
    for (const auto& st : r.out.statuses) EXPECT_LE(st.tracker_time_ms, st.update_time_ms);
  }
  if (e.max_final_error_m > 0.0 && !r.out.odom.empty()) {
    size_t first = 0;
    for (size_t i = 1; i < r.out.odom.size(); ++i) {
      if (r.out.odom[i].header.stamp < r.out.odom[i - 1].header.stamp) first = i;
    }
    auto truthAt = [&](double t) {
      auto b = r.truth.lower_bound(t - 1e-6);
      if (b == r.truth.end()) b = std::prev(b);
      return b->second;  // the image stamps are the truth's; the offset estimate moves them by ms
    };
    const auto& o0 = r.out.odom[first];
    const auto& o1 = r.out.odom.back();
    const geometry_msgs::Pose g0 = truthAt(o0.header.stamp.toSec()), g1 = truthAt(o1.header.stamp.toSec());
    const Eigen::Isometry3d T_true_est = registrationAtFirstPose(
        pos(o0.pose.pose.position), quat(o0.pose.pose.orientation), pos(g0.position), quat(g0.orientation));
    const Eigen::Vector3d err = T_true_est * pos(o1.pose.pose.position) - pos(g1.position);
    std::printf("final position error %.3f m over %.1f m walked\n", err.norm(),
                (pos(g1.position) - pos(g0.position)).norm());
    EXPECT_LT(err.norm(), e.max_final_error_m);
  }
  EXPECT_GE(r.max_level, e.min_inputs_level) << "the inputs' health never reached " << e.min_inputs_level;
  if (!e.event.empty()) {
    bool seen = false;
    for (const auto& ev : r.out.events) seen = seen || ev.find(e.event) != std::string::npos;
    EXPECT_TRUE(seen) << "no event containing '" << e.event << "'";
  }
  EXPECT_GE(r.counters.resets, e.min_resets);
}

RigOptions rig(const std::string& fault, double duration_s = 6.0, double standing_s = 2.0) {
  RigOptions o;
  o.fault = fault;
  o.duration_s = duration_s;
  o.standing_s = standing_s;
  return o;
}

}  // namespace

TEST(ProcessorStream, NaNImuSamplesAreDroppedAndCounted) {
  const StreamRun r = runStream(rig("nan_imu"), testParams());
  check(r, {.min_odom_hz = 20, .min_inputs_level = 1});
  EXPECT_GT(r.counters.imu_nonfinite, 0);
}

TEST(ProcessorStream, RepeatedAndBackwardImuStampsAreDropped) {
  const StreamRun r = runStream(rig("imu_repeat"), testParams());
  check(r, {.min_odom_hz = 20, .min_inputs_level = 1});
  EXPECT_GT(r.counters.imu_stale, 0);
}

TEST(ProcessorStream, RepeatedImagesAreDropped) {
  const StreamRun r = runStream(rig("image_repeat"), testParams());
  check(r, {.min_odom_hz = 20, .min_inputs_level = 1});
  EXPECT_GT(r.counters.images_stale, 0);
}

TEST(ProcessorStream, AnImuGapIsReportedAndBridged) {
  const StreamRun r = runStream(rig("imu_gap", 7.0), testParams());
  check(r, {.max_final_error_m = 1.0, .min_inputs_level = 1});
  EXPECT_GT(r.counters.imu_gaps, 0);
}

TEST(ProcessorStream, ABagRestartResetsTheFilter) {
  const StreamRun r = runStream(rig("time_jump", 6.0), testParams());
  check(r, {.max_final_error_m = 0.5, .event = "time jumped back", .min_resets = 1});
}

TEST(ProcessorStream, ImagesBeforeAnyImuWait) {
  const StreamRun r = runStream(rig("image_before_imu", 7.0, 4.0), testParams());
  check(r, {});
  EXPECT_GT(r.counters.images_before_init, 0);
}

TEST(ProcessorStream, AnUnsupportedEncodingIsAnErrorAndNothingIsPublished) {
  const StreamRun r = runStream(rig("encoding:32FC1"), testParams());
  check(r, {.odom = false, .min_inputs_level = 2});
  EXPECT_GT(r.counters.images_bad_encoding, 0);
}

TEST(ProcessorStream, EverySupportedEncodingWorks) {
  const StreamRun r = runStream(rig("encoding_cycle"), testParams());
  check(r, {.min_odom_hz = 20});
  EXPECT_EQ(r.counters.images_bad_encoding, 0);
}

TEST(ProcessorStream, WithoutCameraInfoImagesWaitAndItSaysSo) {
  const StreamRun r = runStream(rig("camera_info_missing"), testParams());
  check(r, {.odom = false, .min_inputs_level = 2});
  EXPECT_GT(r.counters.images_no_camera, 0);
}

TEST(ProcessorStream, AnAllZeroCameraInfoIsRefused) {
  const StreamRun r = runStream(rig("camera_info_zero"), testParams());
  check(r, {.odom = false, .min_inputs_level = 2});
  EXPECT_GT(r.counters.camera_info_invalid, 0);
}

TEST(ProcessorStream, ACalibrationFileStandsInForCameraInfo) {
  NodeParams p = testParams();
  p.node.camera_calibration_file = std::string(VI_EKF_SLAM_SOURCE_DIR) + "/test/ros/paper_camera.yaml";
  const StreamRun r = runStream(rig("camera_info_missing"), p);
  check(r, {.min_odom_hz = 20});
}

TEST(ProcessorStream, TwoSecondsWithoutImagesAreRiddenThrough) {
  const StreamRun r = runStream(rig("image_dropout", 8.0), testParams());
  check(r, {.max_final_error_m = 0.2});
  EXPECT_GT(r.counters.image_gaps, 0);
}

TEST(ProcessorStream, ACoveredCameraIsRiddenThrough) {
  const StreamRun r = runStream(rig("camera_covered", 10.0), testParams());
  check(r, {.max_final_error_m = 0.15});
  EXPECT_GT(r.counters.images_without_features, 0);
  // It says it is blind (status, events) for no longer than the lens was covered (5 s), and that
  // it sees again.
  double max_blind_s = 0.0;
  for (const auto& st : r.out.statuses) max_blind_s = std::max(max_blind_s, st.blind_s);
  EXPECT_GT(max_blind_s, 1.0);
  EXPECT_LE(max_blind_s, 5.0);
  ASSERT_FALSE(r.out.statuses.empty());
  EXPECT_EQ(r.out.statuses.back().blind_s, 0.0);
  auto said = [&](const std::string& what) {
    return std::count_if(r.out.events.begin(), r.out.events.end(),
                         [&](const std::string& e) { return e.find(what) != std::string::npos; });
  };
  EXPECT_EQ(said("blind since"), 1);
  EXPECT_EQ(said("sight back after"), 1);
  // No landmark was left to find again: the first images after it re-anchored the velocity.
  EXPECT_EQ(std::count_if(r.out.events.begin(), r.out.events.end(),
                          [](const std::string& e) { return e.rfind("re-anchored", 0) == 0; }),
            1);
  // The tracks that start while it walks (after the stand, after the cover) wait for their
  // baseline, and status says how many.
  int max_waiting = 0;
  for (const auto& st : r.out.statuses) max_waiting = std::max(max_waiting, st.waiting_features);
  EXPECT_GT(max_waiting, 0);
}

// Darkness at a high gain: images of noise over a faint scene. The corners ranked against the best
// of each image would be measurements of nothing; the ones that stand above the image's own noise
// are few (min_corner_snr 5), so the filter knows it is blind as under a covered lens, and comes
// back. Without the test (the default) every dark image is full of corners and the filter never
// says it is blind.
TEST(ProcessorStream, DarknessIsBlindAsACoveredLensWithTheNoiseTest) {
  NodeParams checked = testParams();
  checked.tracker.min_corner_snr = 5.0;
  const StreamRun r = runStream(rig("camera_dark", 10.0), checked);
  check(r, {.max_final_error_m = 0.15});
  EXPECT_EQ(r.counters.resets, 0);
  EXPECT_GT(r.counters.images_without_features, 28);  // of the 140 dark images
  double max_blind_s = 0.0;
  for (const auto& st : r.out.statuses) max_blind_s = std::max(max_blind_s, st.blind_s);
  EXPECT_GT(max_blind_s, 1.0);
  EXPECT_LE(max_blind_s, 5.0);
  EXPECT_GE(std::count_if(r.out.events.begin(), r.out.events.end(),
                          [](const std::string& e) { return e.rfind("re-anchored", 0) == 0; }),
            1);

  const StreamRun all = runStream(rig("camera_dark", 10.0), testParams());
  EXPECT_EQ(all.counters.images_without_features, 0);
}

TEST(ProcessorStream, ABurstOfOutlierTracksIsGatedOut) {
  const StreamRun r = runStream(rig("outlier_burst", 7.0), testParams());
  check(r, {.max_final_error_m = 0.1});
  EXPECT_GT(r.counters.outlier_bursts, 0);
}

TEST(ProcessorStream, AResetWhileWalkingComesBackMovingAndOdomStaysContinuous) {
  bool done = false;
  const StreamRun r =
      runStream(rig("none", 10.0), testParams(), [&](EkfSlamProcessor& p, double since, StreamRun& run) {
        if (done || since < 4.0) return;
        run.reset_stamp = run.out.odom.back().header.stamp.toSec();
        p.reset("reset service called");
        done = true;
      });
  ASSERT_TRUE(done);
  check(r, {.min_odom_hz = 10, .event = "initialized: dynamic", .min_resets = 1});
  // Odometry back within 2 s of stream time, and no jump in odom across the reset.
  double gap = 0.0, step = 0.0, prev = r.reset_stamp - 0.5;
  for (size_t i = 0; i < r.out.odom.size(); ++i) {
    const double t = r.out.odom[i].header.stamp.toSec();
    if (t < prev) continue;
    gap = std::max(gap, t - prev);
    prev = t;
    if (i > 0)
      step = std::max(step, (pos(r.out.odom[i].pose.pose.position) - pos(r.out.odom[i - 1].pose.pose.position)).norm());
  }
  std::printf("odometry back %.2f s after the reset; largest step %.3f m\n", gap, step);
  EXPECT_LT(gap, 2.0);
  EXPECT_LT(step, 0.2);  // one image while walking is ~5 cm; a world restarting at the origin jumps metres
}

}  // namespace vi_ekf_slam::glue
