// The ROS processor and the simulator's runner drive one pipeline (core/vio_pipeline.h): the
// same simulated stream through both gives the same trajectory. A difference here means one of
// them starts, queues or maps clocks in a way of its own.
#include <gtest/gtest.h>

#include "../scratch_dir.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>

#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/core/map_reuse/kept_map.h"
#include "vi_ekf_slam/ros/conversions.h"
#include "vi_ekf_slam/ros/ekf_slam_processor.h"
#include "vi_ekf_slam/sim/scenarios.h"
#include "vi_ekf_slam/sim/sensor_stream.h"
#include "msg_eigen.h"

namespace vi_ekf_slam::glue {
namespace {

struct OdomRecorder : OutputSink {
  std::map<double, nav_msgs::Odometry> odom;  ///< by stamp (the IMU clock)
  std::vector<std::string> events;
  void odometry(const nav_msgs::Odometry& o) override { odom[o.header.stamp.toSec()] = o; }
  bool wantsLandmarks() const override { return false; }
  void landmarks(const std::vector<LandmarkOutput>&, const ros::Time&) override {}
  void status(const vi_ekf_slam::FilterStatus&) override {}
  void event(const std::string& e, double) override { events.push_back(e); }
};

/// The built-in walk's first seconds, standing first when standing_s > 0 (the start at rest) or
/// walking from the first image (the start while moving), with a camera-IMU time offset.
sim::Scenario scenario(double standing_s) {
  sim::HallwayParams h;
  h.standing_s = standing_s;
  h.duration_s = standing_s + 9.0;
  sim::Scenario sc = sim::hallwayScenario(h, 1.0, 5);
  sc.cam.time_offset_s = 0.01;
  sc.register_to_truth = false;  // the node keeps the initializer's position and yaw
  sc.stamp_resolution_s = 1e-9;  // stamps as ROS messages carry them
  return sc;
}

NodeParams nodeParams(const sim::Scenario& sc) {
  NodeParams p;
  p.node.extrinsic_source = "parameters";
  const Quat q(sc.T_b_c.R_b_c);
  p.node.T_b_c = {sc.T_b_c.p_b_c.x(), sc.T_b_c.p_b_c.y(), sc.T_b_c.p_b_c.z(), q.x(), q.y(), q.z(), q.w()};
  p.node.tune_allocator = false;
  p.node.publish_tf = TfMode::kWorld;                           // odometry in the filter's own world (ENU of its {n})
  p.tracker.max_image_width_px = sc.camera.intrinsics().width;  // the features are at full resolution
  p.static_init.gravity_mps2 = p.filter.gravity_mps2;
  return p;
}

/// The simulated stream (seeded) as messages through the ROS processor, stamped from 1000 s on
/// (ROS time cannot be negative; the IMU starts just before 0).
constexpr double kStampOffsetS = 1000.0;
void feed(const sim::Scenario& sc, double t0, std::uint64_t seed, EkfSlamProcessor& processor) {
  std_msgs::Header camera_header;
  camera_header.frame_id = "camera";
  std::mt19937_64 rng(seed);
  sim::SensorStream stream(sc, t0, rng);
  sim::SensorStream::Event e;
  processor.cameraInfo(toCameraInfo(sc.camera.intrinsics(), camera_header));
  while (stream.next(&e)) {
    if (e.imu) {
      sensor_msgs::Imu m;
      m.header.stamp.fromSec(e.imu->timestamp + kStampOffsetS);
      m.header.frame_id = "imu";
      m.angular_velocity.x = e.imu->wm.x(), m.angular_velocity.y = e.imu->wm.y(), m.angular_velocity.z = e.imu->wm.z();
      m.linear_acceleration.x = e.imu->am.x(), m.linear_acceleration.y = e.imu->am.y();
      m.linear_acceleration.z = e.imu->am.z();
      processor.imu(m);
      continue;
    }
    camera_header.stamp.fromSec(e.frame->timestamp + kStampOffsetS);
    processor.features(*e.frame, camera_header);
  }
}

void expectSameTrajectory(double standing_s, const std::string& start) {
  ros::Time::init();
  sim::Scenario sc = scenario(standing_s);
  const NodeParams params = nodeParams(sc);
  sc.dynamic_init = withFilterSettings(params.dynamic_init, params.filter);
  ASSERT_TRUE(pipelineParams(params).dynamic_init_enabled);
  const NavState t0 = sim::trueNavState(*sc.trajectory, std::max(0.0, sc.trajectory->startTime()));

  // The simulator's runner.
  std::mt19937_64 rng(7);
  const sim::SimRun run = sim::runSimulation(sc, params.filter, t0, rng);
  ASSERT_GT(run.frames.size(), 100u);

  // The same stream (same seed) through the ROS processor.
  OdomRecorder out;
  EkfSlamProcessor processor(params, out, nullptr);
  feed(sc, t0.timestamp, 7, processor);
  for (const auto& ev : out.events) std::printf("event: %s\n", ev.c_str());
  std::printf("runner: started %.4f, %zu frames %.4f..%.4f; processor: %zu odometry %.4f..%.4f\n", run.initialized_t,
              run.frames.size(), run.frames.front().estimate.timestamp, run.frames.back().estimate.timestamp,
              out.odom.size(), out.odom.empty() ? 0.0 : out.odom.begin()->first - kStampOffsetS,
              out.odom.empty() ? 0.0 : out.odom.rbegin()->first - kStampOffsetS);
  ASSERT_FALSE(out.events.empty());
  EXPECT_NE(out.events.front().find(start), std::string::npos) << out.events.front();

  // Every frame the runner processed, the processor published, at the same time and pose. The
  // runner's estimate is in {n} (z down); the odometry in the ENU world of the same filter.
  int compared = 0;
  double max_dp = 0.0, max_dq = 0.0, max_dt = 0.0;
  for (const auto& f : run.frames) {
    if (!f.result.processed) continue;
    const double t = f.estimate.timestamp + kStampOffsetS;
    const auto it = out.odom.lower_bound(t - 1e-6);
    ASSERT_NE(it, out.odom.end()) << "no odometry at " << t;
    max_dt = std::max(max_dt, std::abs(it->first - t));
    Eigen::Vector3d p_w;
    Eigen::Quaterniond q_w;
    navToZUpWorld(f.estimate.p_n_b, f.estimate.q_n_b, &p_w, &q_w);
    max_dp = std::max(max_dp, (test::pos(it->second.pose.pose.position) - p_w).norm());
    max_dq = std::max(max_dq, q_w.angularDistance(test::quat(it->second.pose.pose.orientation)));
    ++compared;
  }
  EXPECT_EQ(compared, static_cast<int>(out.odom.size()));
  EXPECT_LT(max_dt, 2e-9);  // the odometry's stamp is whole nanoseconds
  EXPECT_LT(max_dp, 1e-9);
  EXPECT_LT(max_dq, 1e-9);
  std::printf("%s start: %d frames, largest difference %.2e m, %.2e rad, %.2e s\n", start.c_str(), compared, max_dp,
              max_dq, max_dt);
}

TEST(OnePipeline, TheProcessorAndTheSimulatorsRunnerGiveTheSameTrajectoryStartingAtRest) {
  expectSameTrajectory(2.0, "initialized: static");
}

TEST(OnePipeline, TheProcessorAndTheSimulatorsRunnerGiveTheSameTrajectoryStartingWhileMoving) {
  expectSameTrajectory(0.0, "initialized: dynamic");
}

TEST(OnePipeline, AMapSavedByOneNodeStartsTheNextInIt) {
  // ~save_map after a walk writes map_file; a node started with that map_file is placed in it.
  ros::Time::init();
  const sim::Scenario sc = scenario(2.0);
  NodeParams params = nodeParams(sc);
  params.filter.map.within_run = true;
  const test::ScratchDir scratch;
  params.node.map_file = scratch / "map.yaml";
  std::remove(params.node.map_file.c_str());
  const double t0 = std::max(0.0, sc.trajectory->startTime());
  OdomRecorder first;
  EkfSlamProcessor mapping(params, first, nullptr);
  feed(sc, t0, 7, mapping);
  std::string message;
  ASSERT_TRUE(mapping.saveMap(&message)) << message;
  std::printf("%s\n", message.c_str());
  KeptMap saved;
  ASSERT_TRUE(saved.load(params.node.map_file, &message)) << message;
  EXPECT_GT(saved.size(), 50);
  OdomRecorder second;
  EkfSlamProcessor localized(params, second, nullptr);
  EXPECT_EQ(localized.pipeline().map().size(), saved.size());
  EXPECT_FALSE(localized.pipeline().inMap());
  feed(sc, t0, 8, localized);
  const bool relocalized = std::any_of(second.events.begin(), second.events.end(), [](const std::string& e) {
    return e.find("relocalized in the kept map") != std::string::npos;
  });
  EXPECT_TRUE(relocalized);
  EXPECT_TRUE(localized.pipeline().inMap());
  // Without keep_map there is nothing to save, and the node says why.
  params.filter.map.within_run = false;
  OdomRecorder third;
  EkfSlamProcessor plain(params, third, nullptr);
  EXPECT_FALSE(plain.saveMap(&message));
  EXPECT_NE(message.find("keep_map"), std::string::npos);
  std::remove(params.node.map_file.c_str());
}

}  // namespace
}  // namespace vi_ekf_slam::glue
