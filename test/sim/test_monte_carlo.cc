#include <gtest/gtest.h>

#include "test_helpers.h"
#include "vi_ekf_slam/sim/monte_carlo.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;

namespace {

sim::ConsistencySummary shortStudy(Mechanization m, LandmarkInitMethod init, CompositionTrigger trig, int runs) {
  sim::HallwayParams hp;
  hp.duration_s = 12.0;
  hp.turn_time_s = 8.0;  // the turn happens inside the short walk
  const sim::Scenario sc = sim::hallwayScenario(hp, 1.0, 9);
  EkfSlamConfig c;
  c.mechanization = m;
  c.landmark_init = init;
  c.composition_trigger = trig;
  c.imu_noise = sc.imu.noise;
  c.landmark_timeout_s = 1.0;
  std::vector<sim::RunResult> results;
  for (int r = 0; r < runs; ++r) results.push_back(sim::runMonteCarloRun(sc, c, 500 + r));
  return sim::summarize(toString(m), results);
}

}  // namespace

TEST(MonteCarlo, InitialErrorsAreDrawnFromThePrior) {
  std::mt19937_64 rng(33);
  InitialUncertainty u;
  NavState truth;
  truth.q_n_b = expQuat(Vec3(0.1, 0.2, 0.3));
  Eigen::Matrix<double, 6, 6> P = Eigen::Matrix<double, 6, 6>::Zero();
  P.diagonal() << Vec3::Constant(u.position_m * u.position_m),
      Vec3(u.roll_pitch_rad * u.roll_pitch_rad, u.roll_pitch_rad * u.roll_pitch_rad, u.yaw_rad * u.yaw_rad);
  double sum = 0.0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const NavState est = sim::drawInitialEstimate(truth, u, rng);
    Eigen::Matrix<double, 6, 1> e;
    e << truth.p_n_b - est.p_n_b, eval::orientationError(truth.q_n_b, est.q_n_b);
    sum += eval::nees(e, P);
  }
  EXPECT_NEAR(sum / n, 6.0, 0.25);
}

// A small Monte-Carlo of the best configuration (robocentric composition after every update,
// inverse-depth landmarks) on a 12 s walk with a turn: its run-averaged pose NEES stays in a
// loose band around 6. The paper's world-centric filter fails the same bound by far, which shows
// the test can fail. Measured (10 runs): best 6.46 (inside the band at 100% of camera times);
// world-centric with fixed depth 11216 (1%).
TEST(MonteCarlo, BestConfigurationIsConsistentOnAShortWalk) {
  const int runs = 10;
  const auto best = shortStudy(Mechanization::kSensorCentricComposition, LandmarkInitMethod::kInverseDepth,
                               CompositionTrigger::kEveryUpdate, runs);
  EXPECT_GT(best.nees_pose, 3.0);
  EXPECT_LT(best.nees_pose, 10.0);
  EXPECT_GT(best.consistent_fraction, 0.7);
  std::printf("best: NEES pose %.2f, consistent %.2f\n", best.nees_pose, best.consistent_fraction);
  const auto paper_wc = shortStudy(Mechanization::kWorldCentric, LandmarkInitMethod::kFixedDepth,
                                   CompositionTrigger::kNewLandmarks, runs);
  EXPECT_GT(paper_wc.nees_pose, 20.0);
  EXPECT_LT(paper_wc.consistent_fraction, 0.3);
  std::printf("paper world-centric: NEES pose %.1f, consistent %.2f\n", paper_wc.nees_pose,
              paper_wc.consistent_fraction);
}
