#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>

#include "vi_ekf_slam/core/body_velocity.h"
#include "vi_ekf_slam/sim/hallway.h"
#include "vi_ekf_slam/eval/monte_carlo.h"
#include "vi_ekf_slam/sim/scenarios.h"
#include "vi_ekf_slam/sim/sim_runner.h"

using namespace vi_ekf_slam;

namespace {

struct FaultRun {
  double final_error = 0.0;
  bool finite = true;
  int frames = 0, imu_gaps = 0;
  int frames_in_dropout = 0, covered_frames_with_updates = 0, burst_frames_with_rejections = 0;
  int walking_frames = 0, walking_frames_wide_gate = 0;  ///< 12-15 s: walking, the last outlier-free stretch
  int burst_frames = 0, burst_frames_narrow_gate = 0;    ///< after the burst's first frame
};

FaultRun runWithFaults(const std::vector<sim::SensorFault>& faults) {
  sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 1);
  sc.faults = faults;
  EkfSlamConfig c;  // the node's defaults
  c.imu_noise = sc.imu.noise;
  std::mt19937_64 rng(3);
  FaultRun r;
  auto in = [&](sim::SensorFault::Kind kind, double t) { return sim::activeFault(faults, kind, t) != nullptr; };
  sim::runSimulation(sc, c, sim::trueNavState(*sc.trajectory, sc.trajectory->startTime()), rng,
                     [&](EkfSlam& f, sim::FrameRecord& rec) {
                       ++r.frames;
                       r.finite = r.finite && rec.estimate.p_n_b.allFinite() && rec.estimate.cov.allFinite();
                       r.final_error = (rec.truth.p_n_b - rec.estimate.p_n_b).norm();
                       r.imu_gaps = f.imuGaps();
                       if (in(sim::SensorFault::Kind::kImageDropout, rec.t)) ++r.frames_in_dropout;
                       if (in(sim::SensorFault::Kind::kCameraCovered, rec.t) && rec.result.update.accepted > 0)
                         ++r.covered_frames_with_updates;
                       if (in(sim::SensorFault::Kind::kOutlierBurst, rec.t) && !rec.result.update.rejected_ids.empty())
                         ++r.burst_frames_with_rejections;
                       const bool wide = rec.result.gate_probability == c.update.clean_gate_probability;
                       if (rec.t >= 12.0 && rec.t < 15.0) {
                         ++r.walking_frames;
                         r.walking_frames_wide_gate += wide ? 1 : 0;
                       }
                       if (rec.t >= 15.1 && rec.t < 16.0) {
                         ++r.burst_frames;
                         r.burst_frames_narrow_gate += rec.result.gate_probability == c.update.gate_probability ? 1 : 0;
                       }
                     });
  return r;
}

}  // namespace

// The sensor faults the core can see, injected into the 35 s hallway walk (the fifth, a bag
// restart, is a ROS clock jump: node_time_jump.test). Each fault must take effect (frames
// missing, an IMU gap counted, no update while covered, outliers rejected by the gate) and the
// filter must ride through them: finite throughout and a final error close to the fault-free
// run's. The covered lens ends every track (the map is rebuilt from new tracks after it).
// Measured: fault-free 0.119 m, with the four faults 0.016 m (one run's final error, a draw;
// 0.119 m when the simulated tracker went on through the covered lens; 2.1 m before the IMU-gap
// uncertainty stopped tying velocity to position).
TEST(SensorFaults, FilterRidesThroughDropoutGapOutliersAndCoveredCamera) {
  using K = sim::SensorFault::Kind;
  const FaultRun clean = runWithFaults({});
  const FaultRun hit = runWithFaults({{K::kImageDropout, 6.0, 2.0},
                                      {K::kImuGap, 11.0, 0.5},
                                      {K::kOutlierBurst, 15.0, 1.0},
                                      {K::kImuClipped, 20.0, 3.0},
                                      {K::kCameraCovered, 27.0, 5.0}});
  std::printf("final error: fault-free %.3f m, with faults %.3f m\n", clean.final_error, hit.final_error);
  EXPECT_TRUE(clean.finite);
  EXPECT_TRUE(hit.finite);
  EXPECT_EQ(hit.frames_in_dropout, 0);
  EXPECT_LT(hit.frames, clean.frames - 2 * 28 + 2);  // 2 s of images never arrived
  EXPECT_GE(hit.imu_gaps, 1);
  EXPECT_EQ(hit.covered_frames_with_updates, 0);
  EXPECT_GE(hit.burst_frames_with_rejections, 20);  // nearly every one of the 28 burst frames
  // The simulated tracks have no outliers until the burst: walking, the gate is the clean one;
  // from the burst's first frame on it is narrow again (core/outlier_watch.h).
  std::printf(
      "wide gate walking (12-15 s): %d of %d frames (with the faults %d of %d); narrow in the burst: %d of %d\n",
      clean.walking_frames_wide_gate, clean.walking_frames, hit.walking_frames_wide_gate, hit.walking_frames,
      hit.burst_frames_narrow_gate, hit.burst_frames);
  EXPECT_GT(clean.walking_frames, 70);
  // (A tail of the noise beyond 99.99% narrows it for 1 s: ~0.3 of those in 3 s of 40 tracks.)
  EXPECT_GE(clean.walking_frames_wide_gate, clean.walking_frames - 30);
  EXPECT_GE(hit.walking_frames_wide_gate, hit.walking_frames - 30);
  EXPECT_GT(hit.burst_frames, 20);
  EXPECT_EQ(hit.burst_frames_narrow_gate, hit.burst_frames);
  EXPECT_LT(hit.final_error, 0.3);
  EXPECT_LT(hit.final_error, clean.final_error + 0.15);
}

// The gate widens on moving images without outliers (core/outlier_watch.h), and images at rest do
// not count. A crawl (0.3 m/s, the gait's bounce and sway a quarter of a walk's) is as quiet to
// the IMU's rest test as a stand; its images are not, and their standing test decides: the gate
// widens during the crawl as during a walk (before: 95% for the whole crawl, 5% of its good
// observations cut; docs/evaluation.md).
TEST(SensorFaults, TheGateWidensDuringACrawlWhoseImuLooksAtRest) {
  sim::HallwayParams h;
  h.speed_mps = 0.3;
  h.duration_s = 12.0;
  const double quarter = 0.23;
  h.gait.step_frequency_hz *= 0.48;
  h.gait.bounce_m *= quarter;
  h.gait.sway_m *= quarter;
  h.gait.yaw_sway_rad *= quarter;
  h.gait.roll_sway_rad *= quarter;
  h.gait.pitch_bob_rad *= quarter;
  sim::Scenario sc = sim::hallwayScenario(h, 1.0, 1);
  EkfSlamConfig c;  // the node's defaults
  c.imu_noise = sc.imu.noise;
  c.update.pixel_noise_px = sc.cam.pixel_noise_px;
  std::mt19937_64 rng(5);
  int frames = 0, wide = 0, quiet_imu = 0;
  sim::runSimulation(sc, c, sim::trueNavState(*sc.trajectory, sc.trajectory->startTime()), rng,
                     [&](EkfSlam&, sim::FrameRecord& rec) {
                       if (rec.t < 4.0) return;
                       ++frames;
                       wide += rec.result.gate_probability == c.update.clean_gate_probability ? 1 : 0;
                       quiet_imu += rec.result.imu_at_rest ? 1 : 0;
                     });
  ASSERT_GT(frames, 100);
  EXPECT_GT(quiet_imu, frames / 2);  // the IMU's rest test is fooled most of the time
  EXPECT_GT(wide, frames / 2);       // the images' is not
}

// Consistency across each outage: a clipped IMU sample a second for 4 s (bridged), a 0.5 s IMU
// gap, 2 s of images lost and a lens covered for 3 s, on the 35 s walk. Over 12 runs the
// run-averaged pose NEES, averaged over the 2 s after each outage (over the clipped stretch and
// 1 s after it), stays below the upper end of the band a consistent filter's run average keeps
// 95% of the time: the covariance grew by at least what the outage hid.
TEST(SensorFaults, TheFilterIsConsistentRightAfterEachOutage) {
  using K = sim::SensorFault::Kind;
  sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 1);
  sc.faults = {{K::kImuClipped, 5.0, 4.0},
               {K::kImuGap, 12.0, 0.5},
               {K::kImageDropout, 17.0, 2.0},
               {K::kCameraCovered, 24.0, 3.0}};
  EkfSlamConfig c;  // the node's defaults
  c.imu_noise = sc.imu.noise;
  std::vector<eval::RunResult> runs;
  for (int r = 0; r < 12; ++r) runs.push_back(eval::runMonteCarloRun(sc, c, 1000 + r));
  const eval::ConsistencySummary sum = eval::summarize("faults", runs);
  std::map<long, std::pair<double, int>> by_time;  // frame time [ms] -> (sum of NEES, runs)
  for (const auto& run : runs) {
    for (const auto& f : run.frames) {
      auto& [total, n] = by_time[std::lround(1000.0 * f.t)];
      total += f.nees_pose;
      ++n;
    }
  }
  struct Window {
    const char* what;
    double from, to;
  };
  for (const Window& w : {Window{"clipped samples", 5.0, 10.0}, Window{"IMU gap", 12.5, 14.5},
                          Window{"images lost", 19.0, 21.0}, Window{"lens covered", 27.0, 29.0}}) {
    double total = 0.0;
    int frames = 0;
    for (const auto& [ms, v] : by_time) {
      if (ms < 1000.0 * w.from || ms >= 1000.0 * w.to || v.second != static_cast<int>(runs.size())) continue;
      total += v.first / v.second;
      ++frames;
    }
    ASSERT_GT(frames, 20) << w.what;
    std::printf("%s: run-averaged pose NEES %.2f over %d frames (band [%.2f, %.2f])\n", w.what, total / frames, frames,
                sum.pose_band.lo, sum.pose_band.hi);
    EXPECT_LT(total / frames, sum.pose_band.hi) << w.what;
  }
  EXPECT_EQ(sum.runs, 12);
}

// A lens covered for 15 s of the 35 s walk (blind_motion_prior.h): the velocity's uncertainty is
// the IMU's alone and grows; the walk's own motion before the stretch bounds it. With the prior the
// body-frame velocity's sigmas stay below the unbounded ones, the prior acts only where no image
// constrains the velocity (never before the stretch or once landmarks are seen again), and the
// velocity stays honest (its NEES, 3 dof, below the 99.9% quantile at every blind image: the bound
// is no false certainty). Measured (seed 3): the largest sigmas 0.21, 0.26, 0.39 m/s with the prior,
// 0.36, 0.37, 0.75 without; largest NEES 2.2 either way.
TEST(SensorFaults, ALongBlindStretchIsBoundedByTheWalksOwnMotion) {
  using K = sim::SensorFault::Kind;
  struct Blind {
    Vec3 largest_sigma = Vec3::Zero();  ///< per principal axis of the body-frame velocity's covariance, ascending
    double largest_nees = 0.0;
    int applied = 0, applied_seeing = 0, covered = 0;
  };
  auto run = [](bool prior) {
    sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 1);
    sc.faults = {{K::kCameraCovered, 12.0, 15.0}};
    EkfSlamConfig c;  // the node's defaults
    c.imu_noise = sc.imu.noise;
    c.blind_motion.enabled = prior;
    std::mt19937_64 rng(3);
    Blind b;
    bool seen_again = false;  // after the stretch, an image whose landmarks constrained the velocity
    sim::runSimulation(
        sc, c, sim::trueNavState(*sc.trajectory, sc.trajectory->startTime()), rng,
        [&](EkfSlam& f, sim::FrameRecord& rec) {
          const bool covered = sim::activeFault(sc.faults, K::kCameraCovered, rec.t) != nullptr;
          seen_again = seen_again || (rec.t > 27.0 && rec.result.update.accepted > 0);
          if (rec.result.motion_prior_applied) ++(rec.t < 12.0 || seen_again ? b.applied_seeing : b.applied);
          if (!covered) return;
          ++b.covered;
          const BodyVelocity v = bodyVelocityOfState(f.state());
          const Vec3 v_true = rec.truth.q_n_b.conjugate() * rec.truth.v_n_b;
          const Vec3 v_est = rec.estimate.q_n_b.conjugate() * rec.estimate.v_n_b;
          const Vec3 sigma =
              Eigen::SelfAdjointEigenSolver<Mat3>(v.cov, Eigen::EigenvaluesOnly).eigenvalues().cwiseSqrt();
          b.largest_sigma = b.largest_sigma.cwiseMax(sigma);
          b.largest_nees = std::max(b.largest_nees, (v_est - v_true).dot(v.cov.ldlt().solve(v_est - v_true)));
        });
    return b;
  };
  const Blind with = run(true), without = run(false);
  std::printf(
      "blind 15 s: body-velocity sigmas (ascending, largest over the stretch) %.3f %.3f %.3f m/s with the prior "
      "(%d updates), %.3f %.3f %.3f without; largest NEES %.2f, %.2f\n",
      with.largest_sigma(0), with.largest_sigma(1), with.largest_sigma(2), with.applied, without.largest_sigma(0),
      without.largest_sigma(1), without.largest_sigma(2), with.largest_nees, without.largest_nees);
  ASSERT_GT(with.covered, 200);
  EXPECT_GT(with.applied, 0);
  EXPECT_EQ(with.applied_seeing, 0);
  EXPECT_EQ(without.applied + without.applied_seeing, 0);
  // The IMU's own uncertainty grows without bound (the accelerometer bias, known as at the start from
  // the stretch's first image, and the tilt); the prior bounds it along every axis.
  for (int i = 0; i < 3; ++i) EXPECT_LT(with.largest_sigma(i), 0.75 * without.largest_sigma(i)) << "axis " << i;
  EXPECT_LT(with.largest_nees, 16.27);  // chi^2, 3 dof, 99.9%
}
