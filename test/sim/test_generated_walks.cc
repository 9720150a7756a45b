// The simulator's one gait model (sim/gait.h) and the generated walks of the suite
// (sim/generated_walks.h): each walk is continuous, at the speeds its description says, with the
// gait's cadence and amplitudes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "vi_ekf_slam/eval/metrics.h"
#include "vi_ekf_slam/sim/gait.h"
#include "vi_ekf_slam/sim/generated_walks.h"

namespace vi_ekf_slam::sim {
namespace {

/// Mean horizontal speed over [t0, t1) [m/s] (the centreline's, up to the gait's sway).
double meanSpeed(const std::vector<io::StampedPose>& w, double t0, double t1) {
  double d = 0.0, t_first = -1.0, t_last = 0.0;
  for (size_t i = 1; i < w.size(); ++i) {
    if (w[i - 1].t < t0 || w[i].t >= t1) continue;
    d += (w[i].p - w[i - 1].p).head<2>().norm();
    if (t_first < 0.0) t_first = w[i - 1].t;
    t_last = w[i].t;
  }
  return d / (t_last - t_first);
}

double heightAt(const std::vector<io::StampedPose>& w, double t) {
  return w[static_cast<size_t>(std::lround(t * 100.0))].p.z();
}

TEST(GeneratedWalks, EveryKindIsAContinuousTrajectoryAt100Hz) {
  for (const std::string& kind : generatedWalkKinds(false)) {
    const std::vector<io::StampedPose> w = generatedWalk(kind);
    ASSERT_GE(w.size(), 6000u) << kind;
    for (size_t i = 1; i < w.size(); ++i) {
      ASSERT_NEAR(w[i].t - w[i - 1].t, 0.01, 1e-9) << kind;
      // Below 6 m/s and 4 rad/s between samples (the run is 3.5 m/s): no jump, no heading wrap.
      ASSERT_LT((w[i].p - w[i - 1].p).norm(), 0.06) << kind << " at " << w[i].t;
      ASSERT_LT(w[i].q.angularDistance(w[i - 1].q), 0.04) << kind << " at " << w[i].t;
      ASSERT_NEAR(w[i].q.norm(), 1.0, 1e-12);
    }
  }
  EXPECT_EQ(generatedWalkKinds(true).size(), 6u);
  EXPECT_THROW(generatedWalk("nope"), std::invalid_argument);
}

TEST(GeneratedWalks, SpeedsStandsAndClimbsAreAsDescribed) {
  const auto crawl = generatedWalk("crawl");
  EXPECT_NEAR(meanSpeed(crawl, 1.0, 10.0), 0.3, 0.03);
  EXPECT_NEAR(meanSpeed(crawl, 20.0, 80.0), 1.3, 0.1);
  const auto fast = generatedWalk("fast");
  EXPECT_NEAR(meanSpeed(fast, 1.0, 59.0), 2.4, 0.15);
  const auto stops = generatedWalk("stops");
  EXPECT_LT(meanSpeed(stops, 16.0, 18.5), 0.01);  // standing: postural sway only
  EXPECT_NEAR(meanSpeed(stops, 22.0, 38.0), 1.3, 0.1);
  const auto stairs = generatedWalk("stairs");
  EXPECT_NEAR(heightAt(stairs, 40.0) - heightAt(stairs, 0.0), 2.8, 0.1);  // up the flight
  EXPECT_NEAR(heightAt(stairs, 89.0) - heightAt(stairs, 0.0), 0.0, 0.1);  // and back down
  const auto stairwell = generatedWalk("stairwell");
  EXPECT_NEAR((heightAt(stairwell, 21.0) - heightAt(stairwell, 11.0)) / 10.0, 0.24, 0.03);
  // The steady probe does not accelerate at all (its torso turns as a walker's does).
  const auto steady = generatedWalk("steady");
  EXPECT_NEAR(meanSpeed(steady, 1.0, 59.0), 0.3, 1e-9);
  for (size_t i = 1; i + 1 < steady.size(); ++i) {
    ASSERT_LT((steady[i + 1].p - 2.0 * steady[i].p + steady[i - 1].p).norm(), 1e-9) << steady[i].t;
  }
}

TEST(Gait, TheCadenceFollowsTheSpeedAndStandingLeavesOnlyThePosturalSway) {
  GaitParams p;
  p.cadence_speed_exponent = 0.5;
  p.postural_sway_m = 0.004;
  Gait g(p, 1);
  for (int i = 0; i < 100; ++i) g.advance(0.5, 0.01);                       // 1 s at 0.5 m/s
  EXPECT_NEAR(g.phase() / (2.0 * M_PI), 1.9 * std::sqrt(0.5 / 1.3), 1e-9);  // steps in that second
  // Standing: the rig within the postural sway of its centreline point, upright.
  for (double t = 0.0; t < 10.0; t += 0.1) {
    const io::StampedPose s = g.pose(t, Vec3(1.0, 2.0, 1.3), 0.3, 0.0);
    EXPECT_LE((s.p - Vec3(1.0, 2.0, 1.3)).norm(), 0.004 + 1e-12);
    EXPECT_LT(s.q.angularDistance(Quat(Eigen::AngleAxisd(0.3, Vec3::UnitZ()))), 1e-12);
  }
  // Walking at cruise: the bounce, sway and torso angles at their amplitudes.
  Gait walk(GaitParams{}, 1);
  double max_up = 0.0, max_side = 0.0;
  for (int i = 0; i < 400; ++i) {
    walk.advance(1.3, 0.01);
    const io::StampedPose s = walk.pose(0.01 * i, Vec3::Zero(), 0.0, 1.3);
    max_up = std::max(max_up, std::abs(s.p.z()));
    max_side = std::max(max_side, std::abs(s.p.y()));
  }
  EXPECT_NEAR(max_up, 0.025, 0.001);
  EXPECT_NEAR(max_side, 0.03, 0.001);
}

}  // namespace
}  // namespace vi_ekf_slam::sim

namespace vi_ekf_slam::sim {
namespace {

// The walks that come back: there_and_back returns along its way out (within 0.5 m of where it
// was more than 20 s before, for most of the way back), laps passes every place of its first lap
// again.
TEST(GeneratedWalks, TheReturningWalksComeBackToWhereTheyWere) {
  for (const char* kind : {"there_and_back", "laps"}) {
    SCOPED_TRACE(kind);
    const std::vector<io::StampedPose> w = generatedWalk(kind);
    std::vector<double> t;
    std::vector<Vec3> p;
    for (size_t i = 0; i < w.size(); i += 10) {  // 10 Hz
      t.push_back(w[i].t);
      p.push_back(w[i].p);
    }
    const eval::RevisitErrors r = eval::revisitErrors(t, p, p);
    const double later = static_cast<double>(std::count_if(t.begin(), t.end(), [&](double x) { return x > 30.0; }));
    EXPECT_GT(r.pairs, 0.5 * later);
  }
}

}  // namespace
}  // namespace vi_ekf_slam::sim
