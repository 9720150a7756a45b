// Relocalization (map_reuse/kept_map.h) on the simulator's corridor walked there and back: the filter is
// reset on the way back, in a place it has mapped; the new run is placed back in the kept map
// within a second of its start, with the error it had before the reset plus at most 0.1 m, and no
// relocalization pairs a feature with another point (the simulator knows). Without the kept map
// the new run only continues from its last estimate.
#include <gtest/gtest.h>

#include "scratch_dir.h"

#include <cmath>
#include <filesystem>
#include <cstdio>
#include <future>
#include <random>

#include "corridor_return.h"
#include "vi_ekf_slam/eval/monte_carlo.h"
#include "vi_ekf_slam/sim/sim_runner.h"

namespace vi_ekf_slam::sim {
using namespace eval;  // the Monte-Carlo runs (eval/monte_carlo.h)
namespace {

constexpr int kRelocalizationRuns = 3;
/// Into the way back (the U-turn is near 28 s of the walk, 14 s into the cut) [s after its start].
constexpr double kResetAfterS = 24.0;

struct ResetOutcome {
  double error_before_m = NAN;  ///< position error on the last frame before the reset
  double restart_t = NAN;       ///< the new run's start [s]
  double relocalized_t = NAN;   ///< NaN: never
  double error_after_m = NAN;   ///< the largest position error over the second after relocalizing
  int inliers = 0, false_pairs = 0;
  double error_1s_after_restart_m = NAN;  ///< (for the run without the kept map) [m]
};

ResetOutcome resetRun(Scenario sc, bool relocalize, std::uint64_t seed) {
  const double t_reset = sc.trajectory->startTime() + kResetAfterS;
  sc.faults = {{SensorFault::Kind::kReset, t_reset, 0.0}};
  EkfSlamConfig c;
  c.imu_noise = sc.imu.noise;
  c.update.pixel_noise_px = sc.cam.pixel_noise_px;
  c.map.within_run = true;
  c.map.across_runs = relocalize;
  std::mt19937_64 rng(seed);
  const NavState truth0 = trueNavState(*sc.trajectory, sc.trajectory->startTime());
  const NavState init = drawInitialEstimate(truth0, c.initial, rng);
  const SimRun run = runSimulation(sc, c, init, rng);
  ResetOutcome o;
  for (const FrameRecord& f : run.frames) {
    const double e = (f.estimate.p_n_b - f.truth.p_n_b).norm();
    if (f.t < t_reset) o.error_before_m = e;
    if (f.t >= t_reset && std::isnan(o.restart_t) && f.initialized_t >= t_reset) o.restart_t = f.initialized_t;
    if (f.relocalized && std::isnan(o.relocalized_t)) {
      o.relocalized_t = f.t;
      o.inliers = f.relocalization_inliers;
    }
    o.false_pairs += f.relocalization_false_pairs;
    if (!std::isnan(o.relocalized_t) && f.t <= o.relocalized_t + 1.0) {
      o.error_after_m = std::isnan(o.error_after_m) ? e : std::max(o.error_after_m, e);
    }
    if (!std::isnan(o.restart_t) && std::isnan(o.error_1s_after_restart_m) && f.t >= o.restart_t + 1.0) {
      o.error_1s_after_restart_m = e;
    }
  }
  std::printf(
      "seed %llu relocalize %d: error before %.3f m, restart %.2f s after the reset, relocalized %.2f s after "
      "the restart (%d inliers, %d false), error over the next second %.3f m, 1 s after the restart %.3f m\n",
      static_cast<unsigned long long>(seed), relocalize, o.error_before_m, o.restart_t - t_reset,
      o.relocalized_t - o.restart_t, o.inliers, o.false_pairs, o.error_after_m, o.error_1s_after_restart_m);
  return o;
}

}  // namespace

TEST(Relocalization, AResetInAMappedPlaceRejoinsTheOldMap) {
  const Scenario sc = corridorReturn(0);
  std::vector<std::future<ResetOutcome>> kept, forgot;
  for (int r = 0; r < kRelocalizationRuns; ++r) {
    kept.push_back(std::async(std::launch::async, [&sc, r] { return resetRun(sc, true, 5100 + r); }));
    forgot.push_back(std::async(std::launch::async, [&sc, r] { return resetRun(sc, false, 5100 + r); }));
  }
  for (int r = 0; r < kRelocalizationRuns; ++r) {
    const ResetOutcome k = kept[static_cast<size_t>(r)].get();
    const ResetOutcome f = forgot[static_cast<size_t>(r)].get();
    ASSERT_FALSE(std::isnan(k.restart_t));
    ASSERT_FALSE(std::isnan(k.relocalized_t)) << "run " << r << " never relocalized";
    EXPECT_LE(k.relocalized_t - k.restart_t, 1.0);
    EXPECT_EQ(k.false_pairs, 0);
    EXPECT_LE(k.error_after_m, k.error_before_m + 0.1);
    EXPECT_TRUE(std::isnan(f.relocalized_t));  // the kept map is what relocalizes
  }
}

TEST(Relocalization, ASecondWalkStartsInTheMapSavedByTheFirst) {
  // The first walk maps the corridor there and back and saves the map; the second starts later on
  // the same walk in a world of its own (2 m and 40 deg away: a new session knows nothing), and is
  // placed in the saved map as soon as it sees it.
  const test::ScratchDir scratch;
  const std::string file = scratch / "map.yaml";
  std::remove(file.c_str());
  Scenario first = corridorReturn(0);
  first.save_map_file = file;
  EkfSlamConfig c;
  c.imu_noise = first.imu.noise;
  c.update.pixel_noise_px = first.cam.pixel_noise_px;
  c.map.within_run = true;
  std::mt19937_64 rng(61);
  const NavState truth0 = trueNavState(*first.trajectory, first.trajectory->startTime());
  const SimRun one = runSimulation(first, c, drawInitialEstimate(truth0, c.initial, rng), rng);
  const double mapped_error = (one.frames.back().estimate.p_n_b - one.frames.back().truth.p_n_b).norm();
  KeptMap saved;
  std::string error;
  ASSERT_TRUE(saved.load(file, &error)) << error;
  EXPECT_GT(saved.size(), 300);  // what left the state while walking, not only the last view

  Scenario second = corridorReturn(0);
  second.load_map_file = file;
  const double t1 = first.trajectory->startTime() + 8.0;
  second.trajectory = std::make_shared<TruncatedTrajectory>(second.trajectory, t1, t1 + 12.0);
  NavState start = trueNavState(*second.trajectory, t1);
  const Eigen::AngleAxisd yaw(0.7, Vec3::UnitZ());
  start.q_n_b = Quat(yaw) * start.q_n_b;
  start.v_n_b = yaw * start.v_n_b;
  start.p_n_b += Vec3(2.0, -1.0, 0.0);
  const SimRun two = runSimulation(second, c, start, rng);
  double relocalized_t = NAN, worst_after = 0.0;
  int false_pairs = 0;
  for (const FrameRecord& f : two.frames) {
    if (f.relocalized && std::isnan(relocalized_t)) relocalized_t = f.t;
    false_pairs += f.relocalization_false_pairs;
    if (!std::isnan(relocalized_t)) worst_after = std::max(worst_after, (f.estimate.p_n_b - f.truth.p_n_b).norm());
  }
  std::printf(
      "map of %d points (error at its end %.3f m); relocalized %.2f s after the start, worst error after %.3f m\n",
      saved.size(), mapped_error, relocalized_t - t1, worst_after);
  ASSERT_FALSE(std::isnan(relocalized_t));
  EXPECT_LE(relocalized_t - t1, 1.0);
  EXPECT_EQ(false_pairs, 0);
  EXPECT_LT(worst_after, 0.5);  // started 2.2 m off; the map itself is off by its own error
  std::remove(file.c_str());
}

}  // namespace vi_ekf_slam::sim
