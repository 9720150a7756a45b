#include <gtest/gtest.h>

#include "vi_ekf_slam/sim/loop_walk.h"
#include "vi_ekf_slam/sim/monte_carlo.h"

using namespace vi_ekf_slam;

// The lap geometry: a closed path of the block's perimeter walked at the set speed, ending where
// it started after a whole lap.
TEST(LoopWalk, LapsAreClosedAndWalkedAtTheSetSpeed) {
  sim::HallwayParams gait;
  sim::LoopParams loop;
  const double perimeter = 2 * (loop.length_m + loop.width_m) - (8 - 2 * M_PI) * loop.corner_radius_m;
  const double lap_s = perimeter / gait.speed_mps;
  loop.duration_s = 2 * lap_s + 5;
  const auto walk = sim::loopWalk(gait, loop);
  EXPECT_NEAR(walk->sample(20.0).v_n_b.norm(), gait.speed_mps, 0.15);
  const Vec3 a = walk->sample(10.0).p_n_b, b = walk->sample(10.0 + lap_s).p_n_b;
  EXPECT_LT((a - b).norm(), 0.1);  // gait sway and bounce are a few cm
  double max_x = -1e9, max_y = -1e9;
  for (double t = 0; t < lap_s + 1; t += 0.1) {
    max_x = std::max(max_x, walk->sample(t).p_n_b.x());
    max_y = std::max(max_y, walk->sample(t).p_n_b.y());
  }
  EXPECT_NEAR(max_x, loop.length_m / 2, 0.1);
  EXPECT_NEAR(max_y, loop.width_m / 2, 0.1);
}

// A short endurance run (3 laps, 4 minutes) of the default filter: the map stays within its
// bound, nothing becomes non-finite, and the error stays small. Measured: final 0.049 m after
// ~290 m; the bound (0.2 m) leaves room for platform differences in a 4-minute chaotic run while
// failing for a drifting filter (the world-centric one). `make soak` runs 30 minutes.
TEST(LoopWalk, ShortEnduranceRunStaysBoundedAndFinite) {
  sim::HallwayParams gait;
  gait.standing_s = 2.0;
  sim::LoopParams loop;
  loop.duration_s = 240.0;
  const sim::Scenario sc = sim::loopScenario(gait, loop, 1);
  EkfSlamConfig c;
  c.imu_noise = sc.imu.noise;
  std::mt19937_64 rng(1);
  const NavState init = sim::trueNavState(*sc.trajectory, sc.trajectory->startTime());
  int max_lm = 0, frames = 0;
  bool finite = true;
  double err = 0.0;
  sim::runSimulation(sc, c, init, rng, [&](EkfSlam& f, sim::FrameRecord& rec) {
    max_lm = std::max(max_lm, f.state().numLandmarks());
    finite = finite && rec.estimate.p_n_b.allFinite() && rec.estimate.cov.allFinite();
    err = (rec.truth.p_n_b - rec.estimate.p_n_b).norm();
    ++frames;
  });
  std::printf("4 min loop walk: %d frames, final error %.3f m, at most %d landmarks\n", frames, err, max_lm);
  EXPECT_GT(frames, 6500);
  EXPECT_TRUE(finite);
  EXPECT_LE(max_lm, c.max_landmarks);
  EXPECT_LT(err, 0.2);
}
