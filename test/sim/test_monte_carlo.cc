#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "test_helpers.h"
#include "vi_ekf_slam/sim/camera_simulator.h"
#include "vi_ekf_slam/sim/imu_simulator.h"
#include "vi_ekf_slam/eval/monte_carlo.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;

namespace {

/// The filter told the simulator's noise; landmarks out of view for 1 s leave the map (the study's).
EkfSlamConfig simConfig(const sim::Scenario& sc, bool zero_velocity = true) {
  EkfSlamConfig c;
  c.imu_noise = sc.imu.noise;
  c.landmark_timeout_s = 1.0;
  c.zero_velocity.enabled = zero_velocity;
  return c;
}

eval::ConsistencySummary shortStudy(Mechanization m, LandmarkInitMethod init, CompositionTrigger trig, int runs) {
  sim::HallwayParams hp;
  hp.duration_s = 12.0;
  hp.turn_time_s = 8.0;  // the turn happens inside the short walk
  const sim::Scenario sc = sim::hallwayScenario(hp, 1.0, 9);
  EkfSlamConfig c = simConfig(sc);
  c.mechanization = m;
  c.landmark_init = init;
  c.composition_trigger = trig;
  std::vector<eval::RunResult> results;
  for (int r = 0; r < runs; ++r) results.push_back(eval::runMonteCarloRun(sc, c, 500 + r));
  return eval::summarize(toString(m), results);
}

/// Runs r = 0..runs-1 of sc, each started 2, 4.5, 7 or 9.5 s into the walk and window_s long.
std::vector<eval::RunResult> startsAlongTheWalk(const sim::Scenario& sc, const EkfSlamConfig& c, int runs,
                                                double window_s) {
  std::vector<eval::RunResult> out;
  for (int r = 0; r < runs; ++r) {
    sim::Scenario s = sc;
    const double start = sc.trajectory->startTime() + 2.0 + 2.5 * (r % 4);
    s.trajectory = std::make_shared<sim::TruncatedTrajectory>(sc.trajectory, start, start + window_s);
    out.push_back(eval::runMonteCarloRun(s, c, 900 + r));
  }
  return out;
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
    const NavState est = eval::drawInitialEstimate(truth, u, rng);
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

namespace {
struct StandingStartResult {
  double velocity_nees = 0.0;  ///< run- and time-averaged NEES of the velocity while standing (3 dof)
  double pose_nees = 0.0;      ///< run- and time-averaged pose NEES over the whole run
  double standing_detected = 0.0;
  int walking_detected = 0;  ///< frames detected as standing while walking (false alarms)
  double ate_m = 0.0;
};

/// The walk after 4 s of standing still, with or without the zero-velocity update.
StandingStartResult standingStart(bool zero_velocity, int runs) {
  sim::HallwayParams hp;
  hp.standing_s = 4.0;
  hp.duration_s = 14.0;
  hp.turn_time_s = 10.0;
  const sim::Scenario sc = sim::hallwayScenario(hp, 1.0, 9);
  const EkfSlamConfig c = simConfig(sc, zero_velocity);
  StandingStartResult out;
  int standing_frames = 0, frames = 0;
  double v_nees = 0.0;
  for (int r = 0; r < runs; ++r) {
    const eval::RunResult run = eval::runMonteCarloRun(sc, c, 700 + r);
    for (const auto& f : run.frames) {
      out.pose_nees += f.nees_pose;
      ++frames;
      if (f.t < hp.standing_s) {
        v_nees += f.e_v.cwiseQuotient(f.s_v).squaredNorm();
        ++standing_frames;
        out.standing_detected += f.stationary;
      } else if (f.t > hp.standing_s + 0.6 && f.stationary) {  // after the parallax window
        ++out.walking_detected;
      }
    }
    out.ate_m += run.ate_position_m / runs;
  }
  out.velocity_nees = v_nees / standing_frames;
  out.pose_nees /= frames;
  out.standing_detected /= standing_frames;
  return out;
}
}  // namespace

// Standing still, the camera constrains only inverse depth times velocity; the zero-velocity
// update (core/zero_velocity.h) detects the missing parallax and pins the velocity. Measured
// (10 runs): see the printout; the detector fires on most standing frames and never while walking.
TEST(MonteCarlo, ZeroVelocityUpdateWhileStandingKeepsTheStartConsistent) {
  const int runs = 10;
  const StandingStartResult on = standingStart(true, runs), off = standingStart(false, runs);
  std::printf(
      "standing start: velocity NEES %.2f (off %.2f), pose NEES %.2f (off %.2f), ATE %.3f (off %.3f) m, "
      "standing detected %.2f, false alarms %d\n",
      on.velocity_nees, off.velocity_nees, on.pose_nees, off.pose_nees, on.ate_m, off.ate_m, on.standing_detected,
      on.walking_detected);
  EXPECT_GT(on.standing_detected, 0.6);
  EXPECT_EQ(on.walking_detected, 0);
  EXPECT_EQ(off.standing_detected, 0.0);
  // A still rig is consistent either way; the update must not break it.
  EXPECT_GT(on.velocity_nees, 1.5);
  EXPECT_LT(on.velocity_nees, 4.5);
  EXPECT_GT(on.pose_nees, 3.0);
  EXPECT_LT(on.pose_nees, 9.0);
  EXPECT_LT(on.ate_m, 1.1 * off.ate_m);
}

// The TUM-VI corridor starts with 5.5 s of a hand-held rig held still (jitter of up to 0.16 m/s),
// then shakes it and walks. Points first seen while it jitters have no parallax; linearized, their
// depth times the jitter gives the filter false confidence in the velocity and the gyro bias, which
// the shake turns into roll/pitch errors and the walk into yaw drift that stay. By default those
// tracks wait until the rig is seen moving, i.e. a parallax of moving_parallax_px (8 px) after the
// last stand (core/zero_velocity.h); the jitter itself shows 2-5 px. Once it walks, new tracks wait
// for their baseline and enter triangulated (core/delayed_landmarks.h). Measured (10 runs, 30 s):
// pose NEES (6 expected) 6.54 waiting, 9.11 when any parallax above the standing threshold counts
// as moving (the rule before), 6.83 at once; gyro bias z NEES (1 expected) 2.36 / 17.1 / 63.0;
// landmarks added at the prior depth on swaying frames 0 / 12.
TEST(MonteCarlo, HandHeldStartOfTheTumCorridorStaysConsistent) {
  const char* dir = std::getenv("DATA_DIR");
  if (!dir) GTEST_SKIP() << "DATA_DIR not set";
  const std::string path = std::string(dir) + "/trajectories/tum_corridor1_512_16_okvis.txt";
  if (!std::ifstream(path)) GTEST_SKIP() << path << " not found";
  sim::Scenario sc = sim::tumScenario(path, 15.0, 1);
  const double t0 = sc.trajectory->startTime();
  sc.trajectory = std::make_shared<sim::TruncatedTrajectory>(sc.trajectory, t0, t0 + 30.0);
  const double standing_px = simConfig(sc).zero_velocity.max_parallax_px;
  const double moving_px = simConfig(sc).zero_velocity.moving_parallax_px;
  ASSERT_EQ(moving_px, 8.0);
  struct Stats {
    double pose_nees = 0.0, bg_z_nees = 0.0, pos_err = 0.0, detected = 0.0;
    int deferred = 0;
    int new_while_swaying = 0;  ///< landmarks added at the prior depth on frames that neither stand nor move enough
  };
  auto run = [&](bool defer, double moving_parallax_px) {
    EkfSlamConfig c = simConfig(sc);
    c.zero_velocity.defer_landmarks = defer;
    c.zero_velocity.moving_parallax_px = moving_parallax_px;
    c.update.gate_probability = 0.9999;  // no outliers in the simulator: keep every inlier (README)
    Stats s;
    int n = 0, standing = 0;
    for (int r = 0; r < 10; ++r) {
      const eval::RunResult run = eval::runMonteCarloRun(sc, c, 1000003ULL + r);
      for (const auto& f : run.frames) {
        if (f.t - t0 > 1.0 && f.t - t0 < 5.5) {  // standing, after the parallax window
          s.detected += f.stationary;
          ++standing;
          if (f.parallax_px >= standing_px && f.parallax_px < moving_px) {
            s.new_while_swaying += f.new_landmarks - f.new_triangulated;
          }
        }
        s.pose_nees += f.nees_pose;
        s.bg_z_nees += std::pow(f.e_bg.z() / f.s_bg.z(), 2);
        s.pos_err += f.e_p.norm();
        ++n;
      }
      s.deferred += run.frames.front().new_landmarks == 0;
    }
    s.pose_nees /= n;
    s.bg_z_nees /= n;
    s.pos_err /= n;
    s.detected /= standing;
    return s;
  };
  const Stats wait = run(true, moving_px), once3 = run(true, standing_px), at_once = run(false, moving_px);
  std::printf(
      "corridor, 30 s: pose NEES %.2f waiting / %.2f moving from %.0f px / %.2f at once; gyro bias z NEES %.2f / "
      "%.2f / %.2f; mean position error %.3f / %.3f / %.3f m; standing detected on %.2f of the frames; landmarks "
      "added while swaying %d / %d\n",
      wait.pose_nees, once3.pose_nees, standing_px, at_once.pose_nees, wait.bg_z_nees, once3.bg_z_nees,
      at_once.bg_z_nees, wait.pos_err, once3.pos_err, at_once.pos_err, wait.detected, wait.new_while_swaying,
      once3.new_while_swaying);
  EXPECT_GT(wait.detected, 0.5);
  EXPECT_EQ(wait.deferred, 10);  // no landmark on the first frame: the rig is not at rest
  EXPECT_EQ(at_once.deferred, 0);
  EXPECT_LT(10 * wait.new_while_swaying, once3.new_while_swaying);  // a few at most, where the IMU shows rest
  EXPECT_LT(wait.pose_nees, once3.pose_nees);
  EXPECT_LT(5.0 * wait.bg_z_nees, at_once.bg_z_nees);  // waiting keeps the gyro bias far more honest
  EXPECT_LT(wait.bg_z_nees, 9.0);
  EXPECT_GT(once3.bg_z_nees, 2.0 * wait.bg_z_nees);
  EXPECT_GT(wait.pose_nees, 4.0);
  EXPECT_LT(wait.pose_nees, 8.5);
}

// The built-in walk starts from rest: the IMU shows it, so the first frame's tracks become
// landmarks at once (their zero parallax pins the velocity exactly), as without the rule.
TEST(MonteCarlo, AStartAtRestGetsItsLandmarksAtOnce) {
  sim::HallwayParams hp;
  hp.duration_s = 3.0;
  const sim::Scenario sc = sim::hallwayScenario(hp, 1.0, 9);
  const EkfSlamConfig c = simConfig(sc);
  ASSERT_TRUE(c.zero_velocity.defer_landmarks);
  const eval::RunResult run = eval::runMonteCarloRun(sc, c, 77);
  ASSERT_FALSE(run.frames.empty());
  EXPECT_GT(run.frames.front().new_landmarks, 20);

  // The same when the caller has already propagated to the frame (the node does, to predict
  // the tracker's rotation): the rest test must not depend on what propagation has consumed.
  std::mt19937_64 rng(78);
  const sim::ImuSequence imu = sim::simulateImu(*sc.trajectory, sc.imu, rng);
  EkfSlam filter(c, sc.camera, sc.T_b_c);
  const double t0 = sc.trajectory->startTime();
  filter.initialize(sim::trueNavState(*sc.trajectory, t0));
  const double t_frame = t0 + 1.0 / sc.cam.rate_hz;
  for (const auto& d : imu.samples) {
    if (d.timestamp > t_frame + 0.01) break;
    filter.addImu(d);
  }
  ASSERT_TRUE(filter.propagateTo(t_frame));
  sim::TrackingCamera camera(sc.world, sc.camera, sc.T_b_c, sc.cam);
  const FrameResult r = filter.processFrame(camera.observe(sc.trajectory->sample(t_frame), &rng));
  ASSERT_TRUE(r.processed) << r.error;
  EXPECT_EQ(r.deferred_features, 0);
  EXPECT_GT(r.new_ids.size(), 20u);
}

// Starting mid-walk from the dynamic initializer (what the node does on a moving rig), position
// and yaw registered to the truth with an error drawn from the prior: every run initializes within
// 1.5 s, and the pose NEES of its first 10 s is inside the 95% band of the run average (an
// over-confident start would sit far above it). Measured: see docs/initialization.md.
TEST(MonteCarlo, ADynamicStartMidWalkIsQuickAndConsistent) {
  sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 9);
  sc.dynamic_init = DynamicInitParams();
  const int kRuns = 12;
  const eval::ConsistencySummary sum = eval::summarize("dynamic", startsAlongTheWalk(sc, simConfig(sc), kRuns, 12.0));
  for (double d : sum.init_delay_s) EXPECT_LE(d, 1.5);
  ASSERT_EQ(sum.runs, kRuns);
  std::printf("dynamic start: NEES pose first 10 s %.2f (band [%.2f, %.2f]), posyaw ATE %.3f m\n", sum.nees_pose_early,
              sum.pose_band.lo, sum.pose_band.hi, sum.ate_posyaw_m);
  EXPECT_GT(sum.nees_pose_early, sum.pose_band.lo);
  EXPECT_LT(sum.nees_pose_early, sum.pose_band.hi);
}

// What a start mid-walk costs over a start from the true state (the target: 10% in posyaw ATE)
// is the accelerometer's turn-on bias: a start from the truth is handed it; a window of a walk
// cannot tell its part across gravity from a tilt (nor can a static start). With an IMU whose
// biases are zero (the filter keeps its prior) the dynamic start tracks as the truth's start does.
// Measured with these runs: see docs/initialization.md.
TEST(MonteCarlo, ADynamicStartLosesToTheTruthOnlyTheImuBiasItCannotSeparateFromTilt) {
  const sim::Scenario base = sim::hallwayScenario(sim::HallwayParams(), 1.0, 9);
  const EkfSlamConfig c = simConfig(base);
  auto posyaw = [&](bool dynamic, bool biases) {
    sim::Scenario s = base;
    if (dynamic) s.dynamic_init = DynamicInitParams();
    s.start_at_truth = !dynamic;
    s.draw_imu_biases = biases;
    return eval::summarize("start", startsAlongTheWalk(s, c, 12, 20.0)).ate_posyaw_m;
  };
  const double truth = posyaw(false, true), drawn = posyaw(true, true), none = posyaw(true, false);
  std::printf("posyaw ATE: from the truth %.4f m, dynamic start %.4f m (%.2fx), without IMU biases %.4f m (%.2fx)\n",
              truth, drawn, drawn / truth, none, none / truth);
  EXPECT_LT(none, 1.1 * truth);
  EXPECT_GT(drawn, 1.1 * none);
}
