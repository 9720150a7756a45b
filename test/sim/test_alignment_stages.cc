// The dynamic initializer's stages one by one (core/dynamic_init/): track selection, preintegration,
// the linear alignment, the refinement, the time-offset search and the uncertainty, each on a
// simulated window whose truth is known. The initializer as a whole: test_dynamic_init.cc.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <deque>
#include <random>

#include "vi_ekf_slam/core/dynamic_init/alignment_problem.h"
#include "vi_ekf_slam/core/dynamic_init/alignment_uncertainty.h"
#include "vi_ekf_slam/core/dynamic_init/preintegration.h"
#include "vi_ekf_slam/core/dynamic_init/time_offset_search.h"
#include "vi_ekf_slam/core/dynamic_init/track_selection.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/sim/camera_simulator.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam::alignment {
namespace {

constexpr double kG = 9.81;

/// One second of the built-in walk: an exact IMU at 1 kHz (with the search's margins) and 21
/// frames at 20 Hz, stamped clock_error_s early.
struct Window {
  sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5);
  std::deque<ImuData> imu;
  std::vector<CameraFrame> frames;
  double t0 = 5.0;

  Window(double pixel_noise_px, std::uint64_t seed, double clock_error_s = 0.0) {
    sim::CameraSimParams cp;
    cp.pixel_noise_px = pixel_noise_px;
    cp.max_features = 80;
    sim::TrackingCamera camera(sc.world, sc.camera, sc.T_b_c, cp);
    std::mt19937_64 rng(seed);
    for (int i = -200; i <= 1200; ++i) {
      const double t = t0 + 0.001 * i;
      const sim::TrajectorySample s = sc.trajectory->sample(t);
      imu.push_back({t, s.w_b, s.q_n_b.conjugate() * (s.a_n_b - gravityInNav(kG))});
    }
    for (int k = 0; k <= 20; ++k) {
      const double t = t0 + 0.05 * k;
      CameraFrame f = camera.observe(sc.trajectory->sample(t), &rng);
      f.timestamp = t - clock_error_s;
      frames.push_back(f);
    }
  }
  std::vector<const CameraFrame*> window() const {
    std::vector<const CameraFrame*> w;
    for (const auto& f : frames) w.push_back(&f);
    return w;
  }
  AlignmentProblem problem(const ProblemSettings& s = ProblemSettings()) const {
    std::vector<double> stamps;
    for (const auto& f : frames) stamps.push_back(f.timestamp);
    return AlignmentProblem(imu, stamps, selectTracks(window(), sc.camera, 4, 80), sc.camera, sc.T_b_c, s);
  }
  /// The true y = [v_0, g, b_a] in the first body frame {I0}.
  VecY trueY() const {
    const sim::TrajectorySample s = sc.trajectory->sample(t0);
    VecY y;
    y << s.q_n_b.conjugate() * s.v_n_b, s.q_n_b.conjugate() * gravityInNav(kG), Vec3::Zero();
    return y;
  }
};

bool positiveSemidefinite(const Eigen::MatrixXd& P, double tol) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (P + P.transpose())).eigenvalues().minCoeff() > -tol;
}

TEST(AlignmentStages, SelectionKeepsTracksSeenOftenEnoughLongestFirstAndBounded) {
  const CameraModel cam = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5).camera;
  std::vector<CameraFrame> frames(6);
  for (int k = 0; k < 6; ++k) {
    for (int id = 1; id <= 8; ++id) {
      if (k >= id) continue;  // feature id is seen in frames 0 .. id - 1
      frames[static_cast<size_t>(k)].features.push_back({id, Eigen::Vector2d(100.0 + 10 * id, 200.0)});
    }
  }
  frames[1].features.push_back({99, Eigen::Vector2d(std::nan(""), 1.0)});  // not finite: never used
  std::vector<const CameraFrame*> w;
  for (const auto& f : frames) w.push_back(&f);
  const std::vector<Track> all = selectTracks(w, cam, 3, 100);
  ASSERT_EQ(all.size(), 6u);     // ids 3..8 are seen 3..6 times
  EXPECT_EQ(all.front().id, 6);  // 6, 7 and 8 are seen in all 6 frames: smaller id first
  EXPECT_EQ(all[1].id, 7);
  EXPECT_EQ(all.back().id, 3);
  for (size_t i = 1; i < all.size(); ++i) {
    EXPECT_GE(all[i - 1].observations.size(), all[i].observations.size());
  }
  EXPECT_EQ(all.front().observations.front().frame, 0);
  EXPECT_EQ(selectTracks(w, cam, 3, 2).size(), 2u);
  EXPECT_TRUE(selectTracks(w, cam, 7, 100).empty());
}

TEST(AlignmentStages, PreintegrationIsExactForConstantRatesAndLinearInTheAccelerometerBias) {
  const Vec3 w(0.3, -0.2, 0.5), am(0.4, 9.6, -1.2);
  std::deque<ImuData> imu;
  for (int i = 0; i <= 200; ++i) imu.push_back({0.005 * i, w, am});
  const std::vector<double> times = {0.0, 0.3, 0.55, 1.0};
  const std::vector<Preintegrated> pre = preintegrate(imu, times);
  ASSERT_EQ(pre.size(), times.size());
  for (size_t k = 0; k < times.size(); ++k) {
    EXPECT_LT((pre[k].R - expSO3(w * times[k])).norm(), 1e-12);
  }
  // alpha and beta are linear in the bias: A and B are their exact derivatives.
  const Vec3 db(0.05, -0.03, 0.02);
  std::deque<ImuData> biased = imu;
  for (auto& d : biased) d.am -= db;
  const std::vector<Preintegrated> pb = preintegrate(biased, times);
  for (size_t k = 0; k < times.size(); ++k) {
    EXPECT_LT((pb[k].alpha - (pre[k].alpha + pre[k].A * db)).norm(), 1e-12);
    EXPECT_LT((pb[k].beta - (pre[k].beta + pre[k].B * db)).norm(), 1e-12);
  }
  // Without rotation: the closed forms.
  std::deque<ImuData> still = imu;
  for (auto& d : still) d.wm.setZero();
  const Preintegrated last = preintegrate(still, times).back();
  EXPECT_LT((last.alpha - 0.5 * am).norm(), 1e-12);
  EXPECT_LT((last.beta - am).norm(), 1e-12);
  EXPECT_LT((last.A + 0.5 * Mat3::Identity()).norm(), 1e-12);
  EXPECT_LT((last.B + Mat3::Identity()).norm(), 1e-12);
  // A gyro bias taken off the rates is the same as rates without it.
  std::deque<ImuData> drifting = imu;
  const Vec3 bg(0.01, 0.02, -0.01);
  for (auto& d : drifting) d.wm += bg;
  const Preintegrated corrected = preintegrate(drifting, times, bg).back();
  EXPECT_LT((corrected.R - pre.back().R).norm(), 1e-12);
  EXPECT_LT((corrected.alpha - pre.back().alpha).norm(), 1e-12);
}

TEST(AlignmentStages, TheLinearAlignmentIsExactOnANoiseFreeWindow) {
  const Window w(0.0, 1);
  AlignmentProblem p = w.problem();
  ASSERT_GE(p.size(), 40);
  const double chi2 = p.solveLinear(0.0);
  const VecY truth = w.trueY();
  EXPECT_LT(chi2, 1e-4);  // [px^2] over ~1000 observations: the IMU's discretization alone
  EXPECT_NEAR(p.y().segment<3>(3).norm(), kG, 1e-9);
  EXPECT_LT((p.y().head<6>() - truth.head<6>()).norm(), 1e-4) << p.y().transpose() << "\n" << truth.transpose();
}

TEST(AlignmentStages, TheRefinementRemovesTheLinearSolutionsScaleBias) {
  // With pixel noise the linear equations (noise times the unknown depth) shrink the scale; the
  // refinement on the reprojection error does not. Over 8 windows of 1 px noise.
  double linear_err = 0.0, refined_err = 0.0, linear_scale = 0.0, refined_scale = 0.0;
  constexpr int kWindows = 8;
  for (int seed = 1; seed <= kWindows; ++seed) {
    const Window w(1.0, static_cast<std::uint64_t>(seed));
    AlignmentProblem p = w.problem();
    const Vec3 v_true = w.trueY().head<3>();
    ASSERT_TRUE(std::isfinite(p.solveLinear(0.0)));
    linear_err += (p.y().head<3>() - v_true).norm() / kWindows;
    linear_scale += p.y().head<3>().norm() / v_true.norm() / kWindows;
    ASSERT_TRUE(std::isfinite(p.refine(0.0, true)));
    refined_err += (p.y().head<3>() - v_true).norm() / kWindows;
    refined_scale += p.y().head<3>().norm() / v_true.norm() / kWindows;
  }
  std::printf("velocity error: linear %.3f m/s (scale %.3f), refined %.3f m/s (scale %.3f)\n", linear_err, linear_scale,
              refined_err, refined_scale);
  EXPECT_LT(refined_err, 0.5 * linear_err);
  EXPECT_LT(std::abs(refined_scale - 1.0), std::abs(linear_scale - 1.0));
  EXPECT_NEAR(refined_scale, 1.0, 0.05);
}

TEST(AlignmentStages, TheTimeOffsetSearchFindsTheFramesShiftOnTheImuClock) {
  const Window w(0.5, 2, 0.03);  // the frames are stamped 30 ms early
  AlignmentProblem p = w.problem();
  const TimeOffsetFit fit = searchTimeOffset(p, 0.1);
  EXPECT_NEAR(fit.dt_s, 0.03, 0.003);
  EXPECT_GT(fit.curvature, 0.0);
  AlignmentProblem q = w.problem();
  const TimeOffsetFit none = searchTimeOffset(q, 0.0);
  EXPECT_EQ(none.dt_s, 0.0);
  EXPECT_EQ(none.curvature, 0.0);
}

TEST(AlignmentStages, TheUncertaintyGrowsWithThePixelNoiseAndTheGyroBiasItConsiders) {
  const Window w(1.0, 3);
  AlignmentProblem p = w.problem();
  const TimeOffsetFit fit = searchTimeOffset(p, 0.1);
  ASSERT_TRUE(std::isfinite(p.refine(fit.dt_s)));
  ASSERT_TRUE(p.dropUndeterminedFeatures(fit.dt_s));
  ASSERT_TRUE(p.eliminateAtSolution());
  UncertaintySettings none, some;
  none.gyro_bias_sigma_radps = 0.0;
  some.gyro_bias_sigma_radps = 0.01;
  const AlignmentUncertainty u0(p, w.imu, fit, none), u1(p, w.imu, fit, some);
  const StateCovariance c1 = u0.covariance(1.0), c2 = u0.covariance(2.0), cb = u1.covariance(1.0);
  EXPECT_TRUE(positiveSemidefinite(c1.covariance, 1e-15));
  EXPECT_TRUE(positiveSemidefinite(c2.covariance - c1.covariance, 1e-15));
  EXPECT_TRUE(positiveSemidefinite(cb.covariance - c1.covariance, 1e-15));
  EXPECT_GT(c2.velocity_sigma_mps, c1.velocity_sigma_mps);
  EXPECT_GT(cb.tilt_sigma_rad, c1.tilt_sigma_rad);
  EXPECT_LE(c1.velocity_sigma_ls_mps, c1.velocity_sigma_mps);
  // The yaw is not the alignment's to know: its row and column are zero.
  EXPECT_EQ(c1.covariance.row(5).norm(), 0.0);
  // The state it gives is the truth's at the last frame (roll, pitch and velocity; yaw aside).
  const sim::TrajectorySample last = w.sc.trajectory->sample(w.t0 + 1.0);
  const Quat unyaw(Eigen::AngleAxisd(yawBetween(last.q_n_b, u1.state().q_n_b), Vec3::UnitZ()));
  EXPECT_LT((unyaw * last.v_n_b - u1.state().v_n).norm(), 5.0 * cb.velocity_sigma_mps);
  // The landmarks: their joint covariance, its diagonal the reported sigmas.
  DynamicInitResult r;
  u1.addLandmarks(p, 1.0, cb, &r);
  ASSERT_GE(r.landmarks.size(), 10u);
  EXPECT_TRUE(positiveSemidefinite(r.landmark_covariance, 1e-15));
  for (size_t i = 0; i < r.landmarks.size(); ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    EXPECT_DOUBLE_EQ(r.landmarks[i].inverse_depth_sigma, std::sqrt(r.landmark_covariance(ii, ii)));
    EXPECT_GT(r.landmarks[i].depth_m, 0.0);
  }
}

}  // namespace
}  // namespace vi_ekf_slam::alignment
