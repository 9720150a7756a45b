// The live node runs the moving start's attempts on a worker thread (an attempt can cost more than
// a camera period): an attempt that ends before the next frame gives the start and trajectory of
// the inline (offline) pipeline exactly, and one that does not still starts the filter, without
// the callbacks ever waiting for it.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "vi_ekf_slam/core/vio_pipeline.h"
#include "vi_ekf_slam/sim/scenarios.h"
#include "vi_ekf_slam/sim/sensor_stream.h"

namespace vi_ekf_slam {
namespace {

struct Recorder : PipelineListener {
  std::map<double, NavState> estimates;  ///< by filter time, of every processed frame
  int starts = 0, moving_starts = 0;
  double start_t = 0.0;
  void started(StartKind kind, const std::string&, EkfSlam& filter) override {
    ++starts;
    moving_starts += kind == StartKind::kMoving;
    start_t = filter.state().timestamp;
  }
  void processed(const CameraFrame&, const FrameResult& r, EkfSlam& filter) override {
    if (r.processed) estimates[filter.state().timestamp] = filter.navState();
  }
};

enum class Mode {
  kInline,
  kBackgroundWaiting,  ///< each attempt ends before the next frame
  kBackgroundSlow,     ///< each attempt ends before the third frame after it at the latest
};

constexpr double kCameraRateHz = 20.0;

/// The built-in walk from its first step (no rest: the moving start), through a pipeline.
Recorder run(Mode mode) {
  sim::HallwayParams h;
  h.standing_s = 0.0;
  h.duration_s = 8.0;
  sim::Scenario sc = sim::hallwayScenario(h, 1.0, 5);
  sc.cam.rate_hz = kCameraRateHz;
  sc.register_to_truth = false;
  EkfSlamConfig config;
  PipelineParams params = sim::simulatedNodeStart(sc, config);
  params.background_start_attempts = mode != Mode::kInline;
  Recorder rec;
  VioPipeline pipeline(config, params, sc.camera, sc.T_b_c, rec);
  std::mt19937_64 rng(11);
  sim::SensorStream stream(sc, std::max(0.0, sc.trajectory->startTime()), rng);
  sim::SensorStream::Event e;
  int frames = 0;
  while (stream.next(&e)) {
    if (e.imu) {
      pipeline.addImu(*e.imu);
      continue;
    }
    const CameraFrame frame = *e.frame;
    pipeline.addFrame({frame.timestamp, [frame](const std::optional<Mat3>&) { return frame; }});
    // Attempts that end within one or three camera periods, whatever the machine's load.
    ++frames;
    if (mode == Mode::kBackgroundWaiting || (mode == Mode::kBackgroundSlow && frames % 3 == 0)) {
      pipeline.waitForStartAttempt();
    }
  }
  pipeline.waitForStartAttempt();
  pipeline.flush();
  return rec;
}

TEST(BackgroundStart, AnAttemptEndingBeforeTheNextFrameGivesTheInlineStartAndTrajectory) {
  const Recorder in = run(Mode::kInline);
  const Recorder bg = run(Mode::kBackgroundWaiting);
  ASSERT_EQ(in.moving_starts, 1);
  ASSERT_EQ(bg.moving_starts, 1);
  EXPECT_EQ(bg.start_t, in.start_t);
  ASSERT_EQ(bg.estimates.size(), in.estimates.size());
  ASSERT_GT(in.estimates.size(), 80u);
  double max_dp = 0.0;
  for (auto a = in.estimates.begin(), b = bg.estimates.begin(); a != in.estimates.end(); ++a, ++b) {
    ASSERT_EQ(a->first, b->first);
    max_dp = std::max(max_dp, (a->second.p_n_b - b->second.p_n_b).norm());
  }
  EXPECT_EQ(max_dp, 0.0);
  std::printf("start at %.3f s, %zu frames, largest difference %.1e m\n", in.start_t, in.estimates.size(), max_dp);
}

TEST(BackgroundStart, FramesArrivingWhileAnAttemptRunsStillLeadToAStart) {
  // However the worker and this thread interleave, the filter starts while moving, at or after
  // the inline start (an attempt sees what the inline one at its frame saw) and at most a few
  // frames later, and every later frame is processed.
  const Recorder in = run(Mode::kInline);
  const Recorder bg = run(Mode::kBackgroundSlow);
  ASSERT_EQ(bg.moving_starts, 1);
  EXPECT_GE(bg.start_t, in.start_t);
  EXPECT_LE(bg.start_t, in.start_t + 0.5);
  ASSERT_FALSE(bg.estimates.empty());
  const double end_t = in.estimates.rbegin()->first;
  EXPECT_NEAR(bg.estimates.rbegin()->first, end_t, 0.005);  // the same last frame (its time offset estimated)
  // Frames after its start, each processed: the camera's rate over what remains.
  const double expected = (end_t - bg.estimates.begin()->first) * kCameraRateHz;
  EXPECT_GE(static_cast<double>(bg.estimates.size()), expected - 1.0);
  std::printf("inline start %.3f s, background start %.3f s, %zu frames\n", in.start_t, bg.start_t,
              bg.estimates.size());
}

}  // namespace
}  // namespace vi_ekf_slam
