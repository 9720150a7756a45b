// Keeping the map (map_reuse/revisit_matching.h) on the simulator's corridor walked there and back: landmarks
// whose tracks ended are found again on the way back, none of them is another point (the
// simulator knows), also where the texture repeats, and the filter stays consistent. Weakening
// the search (no ratio test, no joint compatibility, regions far wider than the filter's
// uncertainty, a loose descriptor bound, matches believed at once) lets false closures through, which shows the
// repeated-texture test can fail.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <future>

#include "corridor_return.h"
#include "vi_ekf_slam/eval/monte_carlo.h"

namespace vi_ekf_slam::sim {
using namespace eval;  // the Monte-Carlo runs (eval/monte_carlo.h)
namespace {

constexpr int kRuns = 3;

struct Outcome {
  ConsistencySummary sum;
  int revisits = 0;
  int false_revisits = 0;
};

Outcome run(const Scenario& sc, const std::function<void(EkfSlamConfig&)>& configure) {
  EkfSlamConfig c;
  c.imu_noise = sc.imu.noise;
  c.update.pixel_noise_px = sc.cam.pixel_noise_px;
  configure(c);
  std::vector<std::future<RunResult>> futures;
  for (int r = 0; r < kRuns; ++r)
    futures.push_back(std::async(std::launch::async, [&, r] { return runMonteCarloRun(sc, c, 4100 + r); }));
  std::vector<RunResult> runs;
  for (auto& f : futures) runs.push_back(f.get());
  Outcome o;
  o.sum = summarize("map", runs);
  for (const auto& r : runs)
    for (const auto& f : r.frames) {
      o.revisits += f.revisits;
      o.false_revisits += f.false_revisits;
    }
  std::printf(
      "revisits %d (false %d), error on return / first %.2f, pose NEES %.2f (band [%.2f, %.2f]), "
      "posyaw ATE %.3f m\n",
      o.revisits, o.false_revisits, o.sum.revisit_error_ratio, o.sum.nees_pose, o.sum.pose_band.lo, o.sum.pose_band.hi,
      o.sum.ate_posyaw_m);
  return o;
}

}  // namespace

TEST(MapReuse, TheCorridorWalkedBackFindsItsLandmarksAgain) {
  const Scenario sc = corridorReturn(0);
  const Outcome kept = run(sc, [](EkfSlamConfig& c) { c.map.within_run = true; });
  const Outcome forgot = run(sc, [](EkfSlamConfig& c) { c.map.within_run = false; });
  EXPECT_GE(kept.revisits, 4 * kRuns);
  EXPECT_EQ(kept.false_revisits, 0);
  EXPECT_EQ(forgot.revisits, 0);
  EXPECT_LT(kept.sum.revisit_error_ratio, forgot.sum.revisit_error_ratio);
  EXPECT_LT(kept.sum.nees_pose, kept.sum.pose_band.hi);
  // Matches believed only after their tracks stayed on the prediction for 5 images: found again
  // too, later (the revisits are counted when believed), and still none false.
  const Outcome confirmed = run(sc, [](EkfSlamConfig& c) {
    c.map.within_run = true;
    c.map.revisit_confirm_frames = 5;
  });
  EXPECT_GE(confirmed.revisits, 2 * kRuns);
  EXPECT_EQ(confirmed.false_revisits, 0);
  EXPECT_LT(confirmed.sum.revisit_error_ratio, forgot.sum.revisit_error_ratio);
}

TEST(MapReuse, RepeatedTextureClosesNoFalseLoop) {
  // One pattern for the whole world (a tiled floor): every landmark looks like the others seen from
  // the same place; only the view and the geometry tell them apart.
  const Scenario sc = corridorReturn(1);
  const Outcome kept = run(sc, [](EkfSlamConfig& c) { c.map.within_run = true; });
  EXPECT_EQ(kept.false_revisits, 0);
  EXPECT_LT(kept.sum.nees_pose, kept.sum.pose_band.hi);
  const Outcome weak = run(sc, [](EkfSlamConfig& c) {
    c.map.within_run = true;
    c.map.descriptor_ratio = 1.0;
    c.map.distinct_in_view = false;
    c.map.search_gate_probability = 0.999999;
    c.map.max_search_sigma_px = 1000.0;
    c.map.min_joint_revisits = 1;
    c.map.max_descriptor_distance = 128;
    c.map.revisit_confirm_frames = 1;
  });
  EXPECT_GT(weak.false_revisits, 0);
}

}  // namespace vi_ekf_slam::sim
