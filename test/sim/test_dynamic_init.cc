// Dynamic initialization (visual-inertial alignment) on simulated windows whose truth is known:
// noise-free windows give the exact gravity direction, velocity and feature depths; motions that
// leave them unobservable (rotation in place, constant velocity) are refused with the reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <fstream>
#include <random>
#include <string>

#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/sim/camera_simulator.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam {
namespace {

/// Constant velocity and constant angular rate: neither acceleration nor (for v = 0) parallax.
class UniformMotion : public sim::Trajectory {
 public:
  UniformMotion(const Vec3& v, const Vec3& w_b) : v_(v), w_(w_b) {}
  double startTime() const override { return 0.0; }
  double endTime() const override { return 100.0; }
  sim::TrajectorySample sample(double t) const override {
    sim::TrajectorySample s;
    s.t = t;
    s.p_n_b = v_ * t;
    s.v_n_b = v_;
    s.q_n_b = expQuat(w_ * t);
    s.w_b = w_;
    return s;
  }

 private:
  Vec3 v_, w_;
};

struct Window {
  std::optional<DynamicInitResult> result;
  std::string why;
  sim::TrajectorySample truth;                ///< at the last frame
  std::map<std::int64_t, double> true_depth;  ///< of the features in the last frame
  int tracked = 0;                            ///< features seen in min_observations frames or more
};

/// IMU at 1 kHz (exact) and noise-free frames at 20 Hz over [t0, t1] into the initializer.
/// clock_error_s: the frames are stamped this much early on the IMU clock (an unknown time offset).
/// pixel_noise_px > 0: the frames get that noise, drawn from rng.
Window runWindow(const sim::Trajectory& traj, const sim::LandmarkWorld& world, const CameraModel& cam,
                 const CameraExtrinsics& T_b_c, double t0, double t1, double clock_error_s = 0.0,
                 double pixel_noise_px = 0.0, std::mt19937_64* rng = nullptr, double time_offset_sigma_s = 0.05,
                 const Vec3& gyro_bias = Vec3::Zero(), double gyro_bias_sigma_radps = 1e-5,
                 const std::function<void(DynamicInitParams&)>& tweak = {}) {
  DynamicInitParams p;
  p.time_offset_sigma_s = time_offset_sigma_s;
  p.window_s = t1 - t0;
  p.accel_bias_sigma_mps2 = 0.0;  // exact IMU (but for the gyro bias, if given)
  p.gyro_bias_sigma_radps = gyro_bias_sigma_radps;
  if (tweak) tweak(p);
  DynamicInitializer init(p, cam, T_b_c);
  sim::CameraSimParams cp;
  cp.pixel_noise_px = pixel_noise_px;
  cp.max_features = 60;
  sim::TrackingCamera camera(world, cam, T_b_c, cp);
  Window w;
  const int n_imu = static_cast<int>(std::round((t1 - t0) * 1000.0));
  for (int i = -200; i <= n_imu + 200; ++i) {  // IMU beyond the frames: the time offset is searched
    const double t = t0 + 1e-3 * i;
    const sim::TrajectorySample s = traj.sample(t);
    init.addImu({t, s.w_b + gyro_bias, s.q_n_b.conjugate() * (s.a_n_b - gravityInNav(9.81))});
  }
  const int n_frames = static_cast<int>(std::round((t1 - t0) * 20.0));
  CameraFrame last;
  std::map<std::int64_t, int> seen;
  for (int k = 0; k <= n_frames; ++k) {
    const double t = t0 + 0.05 * k;
    CameraFrame f = camera.observe(traj.sample(t), rng);
    f.timestamp = t - clock_error_s;
    init.addFrame(f);
    for (const auto& o : f.features) ++seen[o.id];
    last = f;
  }
  for (const auto& [id, count] : seen) w.tracked += count >= p.min_observations;
  w.truth = traj.sample(last.timestamp + clock_error_s);
  for (const auto& o : last.features) {
    const Vec3 p_b = w.truth.q_n_b.conjugate() * (sim::landmarkOfTrack(o.id, world).p_n - w.truth.p_n_b);
    w.true_depth[o.id] = (T_b_c.R_b_c.transpose() * (p_b - T_b_c.p_b_c)).z();
  }
  w.result = init.tryInitialize(&w.why);
  return w;
}

/// A window's errors (truth - estimate) of the first k entries of [v_n (3), roll, pitch] and of
/// every aligned inverse depth, in the estimate's {n} (the yaw is not the alignment's to know),
/// with their joint covariance as the alignment reports it.
struct JointError {
  Eigen::VectorXd e;
  Eigen::MatrixXd P;
};
JointError jointError(const Window& w, int k) {
  const DynamicInitResult& r = *w.result;
  const auto m = static_cast<Eigen::Index>(r.landmarks.size());
  const Quat unyaw(Eigen::AngleAxisd(yawBetween(w.truth.q_n_b, r.state.q_n_b), Vec3::UnitZ()));
  Eigen::Matrix<double, 5, 1> x;
  x.head<3>() = unyaw * w.truth.v_n_b - r.state.v_n_b;
  x.tail<2>() = logSO3(((unyaw * w.truth.q_n_b) * r.state.q_n_b.conjugate()).toRotationMatrix()).head<2>();
  JointError j;
  j.e.resize(k + m);
  j.e.head(k) = x.head(k);
  for (Eigen::Index i = 0; i < m; ++i) {
    const DynamicInitLandmark& l = r.landmarks[static_cast<size_t>(i)];
    j.e(k + i) = 1.0 / w.true_depth.at(l.id) - 1.0 / l.depth_m;
  }
  j.P.resize(k + m, k + m);
  j.P.topLeftCorner(k, k) = r.covariance.topLeftCorner(k, k);
  j.P.bottomLeftCorner(m, k) = r.landmark_state_covariance.leftCols(k);
  j.P.topRightCorner(k, m) = r.landmark_state_covariance.leftCols(k).transpose();
  j.P.bottomRightCorner(m, m) = r.landmark_covariance;
  return j;
}

}  // namespace

TEST(DynamicInit, NoiseFreeWindowGivesExactGravityVelocityAndDepths) {
  // The wall scenario: a rig swaying a few decimetres on every axis in front of a wall 5-8 m away.
  const sim::Scenario sc = sim::wallScenario(10.0, false, 3);
  int initialized = 0;
  for (const double t0 : {1.0, 2.5, 4.0, 5.5, 7.5}) {
    const Window w = runWindow(*sc.trajectory, sc.world, sc.camera, sc.T_b_c, t0, t0 + 1.0);
    std::printf("window at %.1f s: %s\n", t0, w.result ? "initialized" : w.why.c_str());
    if (!w.result) continue;
    ++initialized;
    const DynamicInitResult& r = *w.result;
    // Gravity in the body frame (roll and pitch), and the velocity in the body frame (yaw-free).
    const Vec3 down_true = w.truth.q_n_b.conjugate() * Vec3::UnitZ();
    const Vec3 down_est = r.state.q_n_b.conjugate() * Vec3::UnitZ();
    EXPECT_LT(std::acos(std::min(1.0, down_true.dot(down_est))), 1e-4) << t0;
    const Vec3 v_true_b = w.truth.q_n_b.conjugate() * w.truth.v_n_b;
    const Vec3 v_est_b = r.state.q_n_b.conjugate() * r.state.v_n_b;
    EXPECT_LT((v_est_b - v_true_b).norm(), 1e-3) << t0 << ": " << v_est_b.transpose() << " vs " << v_true_b.transpose();
    EXPECT_NEAR(r.state.timestamp, t0 + 1.0, 1e-3);
    EXPECT_NEAR(r.time_offset_correction_s, 0.0, 1e-3);
    EXPECT_LT(r.residual_rms_px, 0.01);
    // Every aligned feature at its true depth; the scene depth is their median when the window
    // determines them (for the 1 px it assumes), 0 (unknown) when the sway is too slow for that.
    ASSERT_FALSE(r.landmarks.empty());
    for (const DynamicInitLandmark& l : r.landmarks) EXPECT_NEAR(l.depth_m, w.true_depth.at(l.id), 0.01) << t0;
    std::vector<double> depths;
    for (const auto& [id, z] : w.true_depth) depths.push_back(z);
    std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
    if (r.median_depth_m > 0.0) {
      EXPECT_NEAR(r.median_depth_m, depths[depths.size() / 2], 0.05) << t0;
    }
    // Its uncertainty is small but not zero (the pixel noise it assumes).
    EXPECT_GT(r.velocity_sigma_mps, 0.0);
    EXPECT_LE(r.velocity_sigma_mps, DynamicInitParams().max_velocity_sigma_mps);
  }
  // The sway is slow: the velocity is known to 0.16-0.27 m/s for 1 px (below its bound); four of
  // the five windows answer, exactly; the one at 4 s knows the scene's scale to 67% only and waits.
  EXPECT_GE(initialized, 4);
}

TEST(DynamicInit, NoisyWindowsAreUnbiasedAndAsUncertainAsItSays) {
  // 1 px pixel noise, exact IMU, windows along the built-in walk: the velocity errors average
  // out, and their spread is the one reported.
  const sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5);
  std::mt19937_64 rng(11);
  Vec3 sum = Vec3::Zero();
  double nees = 0.0, sigma_sum = 0.0;
  int n = 0;
  for (int i = 0; i < 24; ++i) {
    const double t0 = 1.0 + 1.3 * i;
    const Window w = runWindow(*sc.trajectory, sc.world, sc.camera, sc.T_b_c, t0, t0 + 1.0, 0.0, 1.0, &rng);
    if (!w.result) continue;
    const Vec3 v_true_b = w.truth.q_n_b.conjugate() * w.truth.v_n_b;
    const Vec3 v_est_b = w.result->state.q_n_b.conjugate() * w.result->state.v_n_b;
    const Vec3 e = v_est_b - v_true_b;
    std::printf("window at %.1f s: v error %+.3f %+.3f %+.3f m/s (sigma %.3f), t_d %+.4f s\n", t0, e.x(), e.y(), e.z(),
                w.result->velocity_sigma_mps, w.result->time_offset_correction_s);
    sum += e;
    nees += e.squaredNorm() / std::pow(w.result->velocity_sigma_mps, 2);
    sigma_sum += w.result->velocity_sigma_mps;
    ++n;
  }
  ASSERT_GE(n, 12);
  std::printf("mean v error %+.3f %+.3f %+.3f m/s, mean (e / sigma)^2 %.2f over %d windows\n", sum.x() / n, sum.y() / n,
              sum.z() / n, nees / n, n);
  // Unbiased: the mean within 3 standard errors (the linear solution alone was -0.04 m/s along
  // the walk, 25% of the speed with an IMU of realistic noise).
  EXPECT_LT((sum / n).cwiseAbs().maxCoeff(), 3.0 * sigma_sum / n / std::sqrt(n));
  // Not over-confident: sigma is the largest axis's, so sum (e_i / sigma)^2 over the 3 axes is at
  // most chi^2(3 n) / n (95%: 3.98 for 19 windows); and not needlessly cautious either.
  EXPECT_LT(nees / n, 4.0);
  EXPECT_GT(nees / n, 0.3);
}

TEST(DynamicInit, TheDepthsShareTheVelocitysScaleErrorAsTheJointCovarianceSays) {
  // The same windows: the errors of the velocity and of every aligned feature's inverse depth
  // against their joint covariance. One error of the window's scale moves them all; taken as
  // independent (the marginals alone), the depths' common error would be several times what the
  // covariance allows, and tens of landmarks would "know" the scale the window does not.
  const sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5);
  std::mt19937_64 rng(11);
  double nees = 0.0, common = 0.0, common_marginal = 0.0;
  int dims = 0, n = 0;
  for (int i = 0; i < 24; ++i) {
    const double t0 = 1.0 + 1.3 * i;
    const Window w = runWindow(*sc.trajectory, sc.world, sc.camera, sc.T_b_c, t0, t0 + 1.0, 0.0, 1.0, &rng);
    if (!w.result) continue;
    const DynamicInitResult& r = *w.result;
    const auto m = static_cast<Eigen::Index>(r.landmarks.size());
    ASSERT_EQ(r.landmark_covariance.rows(), m);
    ASSERT_EQ(r.landmark_state_covariance.rows(), m);
    const JointError j = jointError(w, 3);
    nees += j.e.dot(j.P.ldlt().solve(j.e));
    dims += static_cast<int>(j.e.size());
    // The depths' common error: their mean, against its variance with and without the correlations.
    const double mean = j.e.tail(m).mean();
    common += mean * mean / (r.landmark_covariance.sum() / static_cast<double>(m * m));
    common_marginal += mean * mean / (r.landmark_covariance.diagonal().sum() / static_cast<double>(m * m));
    ++n;
  }
  ASSERT_GE(n, 12);
  std::printf(
      "joint NEES of velocity and inverse depths %.2f per dimension (%d windows, %d dimensions); the depths' "
      "mean error: (e / sigma)^2 %.2f with the correlations, %.2f with the marginals alone\n",
      nees / dims, n, dims, common / n, common_marginal / n);
  // chi^2(dims) / dims is about 1 (+-0.1 for this many dimensions); the alignment's covariance is
  // a linearization, so within 1.5. The mean error: chi^2(n) / n < 1.8 (95%) for 12 or more windows.
  EXPECT_LT(nees / dims, 1.5);
  EXPECT_LT(common / n, 1.8);
}

TEST(DynamicInit, AGyroBiasItDoesNotEstimateIsInItsJointCovariance) {
  // The same windows with a gyro bias drawn from a 0.01 rad/s prior that the alignment is told
  // but does not estimate: it turns every integrated attitude and so moves velocity, tilt and
  // every depth together. The joint covariance (its first-order share, a "consider" parameter)
  // covers the errors of the velocity, roll/pitch and inverse depths.
  const sim::Scenario sc = sim::hallwayScenario(sim::HallwayParams(), 1.0, 5);
  std::mt19937_64 rng(17);
  std::normal_distribution<double> bias(0.0, 0.01);
  double nees = 0.0;
  int dims = 0, n = 0;
  for (int i = 0; i < 24; ++i) {
    const double t0 = 1.0 + 1.3 * i;
    const Vec3 b_g(bias(rng), bias(rng), bias(rng));
    const Window w =
        runWindow(*sc.trajectory, sc.world, sc.camera, sc.T_b_c, t0, t0 + 1.0, 0.0, 1.0, &rng, 0.05, b_g, 0.01);
    if (!w.result) continue;
    const JointError j = jointError(w, 5);  // velocity, roll/pitch and inverse depths
    nees += j.e.dot(j.P.ldlt().solve(j.e));
    dims += static_cast<int>(j.e.size());
    ++n;
  }
  ASSERT_GE(n, 12);
  std::printf(
      "gyro bias considered: joint NEES of velocity, roll/pitch and inverse depths %.2f per dimension (%d "
      "windows, %d dimensions)\n",
      nees / dims, n, dims);
  // As above: a linearization's covariance, chi^2(dims) / dims ~ 1. Measured 0.48 (0.31 before
  // the features the linear solution misplaced rejoined): conservative, the former b_g T bound
  // stays on top of the first-order share (docs/initialization.md).
  EXPECT_LT(nees / dims, 1.5);
}

TEST(DynamicInit, FeaturesTheLinearSolutionPutsBehindTheCameraRejoinTheRefinement) {
  // A stretch of the EuRoC V1_01 flight (turning at 0.4-0.6 rad/s, 0.4-0.6 m/s), 1 px noise, a
  // gyro bias drawn from the filter's prior. The linear solution can be far enough off there to put
  // many features, all 1-10 m away, behind the camera (here up to 30 of 67; in the simulated starts
  // of make initsuite, with a noisy accelerometer, 34 of 50), and refined on those it kept the
  // alignment confirmed itself (roll/pitch 5-7 sigma off there). Placed again for the refined
  // window they rejoin it: it uses the features it tracks, and its joint covariance holds.
  const char* dir = std::getenv("DATA_DIR");
  const std::string path = std::string(dir ? dir : "") + "/trajectories/euroc_V1_01_easy.txt";
  if (!dir || !std::ifstream(path)) GTEST_SKIP() << "DATA_DIR/trajectories/euroc_V1_01_easy.txt not found";
  const sim::Scenario sc = sim::tumScenario(path, 15.0, 6);
  std::mt19937_64 rng(23);
  constexpr double kBiasSigma = 0.002;  // the filter's default prior [rad/s], as the simulated starts draw it
  std::normal_distribution<double> bias(0.0, kBiasSigma);
  double nees = 0.0, min_share = 1.0;
  int dims = 0, n = 0;
  for (int i = 0; i < 16; ++i) {
    const double t0 = sc.trajectory->startTime() + 98.0 + 0.25 * i;
    const Vec3 b_g(bias(rng), bias(rng), bias(rng));
    const Window w =
        runWindow(*sc.trajectory, sc.world, sc.camera, sc.T_b_c, t0, t0 + 1.0, 0.0, 1.0, &rng, 0.05, b_g, kBiasSigma);
    if (!w.result) continue;
    const JointError j = jointError(w, 5);
    const double e = j.e.dot(j.P.ldlt().solve(j.e));
    std::printf("window at %.2f s: %d of %d features, %zu landmarks, joint NEES %.2f per dimension\n",
                t0 - sc.trajectory->startTime(), w.result->features, w.tracked, w.result->landmarks.size(),
                e / static_cast<double>(j.e.size()));
    min_share = std::min(min_share, w.result->features / static_cast<double>(std::min(w.tracked, 80)));
    nees += e;
    dims += static_cast<int>(j.e.size());
    ++n;
  }
  ASSERT_GE(n, 12);
  std::printf(
      "joint NEES of velocity, roll/pitch and inverse depths %.2f per dimension (%d windows); the "
      "alignment used at least %.0f%% of the features tracked\n",
      nees / dims, n, 100.0 * min_share);
  // Every feature here is near enough for its depth: measured 95% at least (the linear
  // solution's choice alone: 55%, 37 of 67 features at 99 s).
  EXPECT_GE(min_share, 0.9);
  // As above (chi^2(dims) / dims ~ 1, a linearization's covariance): measured 1.16.
  EXPECT_LT(nees / dims, 1.5);
}

TEST(DynamicInit, FindsAnUnknownCameraImuTimeOffset) {
  // The frames' stamps are 40 ms early on the IMU clock (a camera-IMU time offset nobody
  // configured): the alignment is best at the true offset, which it reports.
  const sim::Scenario sc = sim::wallScenario(10.0, false, 3);
  for (const double err : {0.04, -0.047}) {
    // Told nothing about the offset (a 1 s prior): the images alone find it.
    const Window w = runWindow(*sc.trajectory, sc.world, sc.camera, sc.T_b_c, 1.0, 2.0, err, 0.0, nullptr, 1.0);
    ASSERT_TRUE(w.result.has_value()) << w.why;
    EXPECT_NEAR(w.result->time_offset_correction_s, err, 1e-3);
    const Vec3 v_true_b = w.truth.q_n_b.conjugate() * w.truth.v_n_b;
    const Vec3 v_est_b = w.result->state.q_n_b.conjugate() * w.result->state.v_n_b;
    EXPECT_LT((v_est_b - v_true_b).norm(), 0.01);
  }
}

// A hand's sway (the wall scenario's at a quarter of its amplitude: about 0.08 m/s, 0.06-0.15 m/s^2)
// gives a velocity known to a few cm/s, under the absolute bound, but a scene 5-8 m away whose
// depth it barely knows: the relative bound on the scale refuses it, and says so; the full sway's
// windows know it well enough.
TEST(DynamicInit, ASwayTooSlowForTheSceneScaleIsRefused) {
  const sim::Scenario sc = sim::wallScenario(10.0, false, 3);
  const auto scale_bound_off = [](DynamicInitParams& p) { p.max_scale_sigma = 1e6; };  // what the window knows
  int refused_for_scale = 0;
  for (const double amplitude : {1.0, 0.25}) {
    const sim::LissajousTrajectory sway(Vec3::Zero(), amplitude * Vec3(0.3, 0.4, 0.2), Vec3(1.1, 0.8, 1.7),
                                        Vec3(0.1, 0.08, 0.15), Vec3(0.9, 1.3, 0.7), 10.0);
    for (const double t0 : {1.0, 2.5, 5.5, 7.5}) {
      const Window all = runWindow(sway, sc.world, sc.camera, sc.T_b_c, t0, t0 + 1.0, 0.0, 0.0, nullptr, 0.05,
                                   Vec3::Zero(), 1e-5, scale_bound_off);
      ASSERT_TRUE(all.result.has_value()) << amplitude << " " << t0 << ": " << all.why;
      const Window w = runWindow(sway, sc.world, sc.camera, sc.T_b_c, t0, t0 + 1.0);
      std::printf("sway x%.2f, window at %.1f s: velocity sigma %.3f m/s, scale sigma %.2f: %s\n", amplitude, t0,
                  all.result->velocity_sigma_mps, all.result->scale_sigma, w.result ? "initialized" : w.why.c_str());
      EXPECT_LE(all.result->velocity_sigma_mps, DynamicInitParams().max_velocity_sigma_mps);
      EXPECT_EQ(w.result.has_value(), all.result->scale_sigma <= DynamicInitParams().max_scale_sigma);
      if (amplitude == 1.0) {
        EXPECT_TRUE(w.result.has_value()) << t0;
      }
      if (!w.result) {
        EXPECT_NE(w.why.find("scene's scale known to"), std::string::npos) << w.why;
        ++refused_for_scale;
      }
    }
  }
  EXPECT_GE(refused_for_scale, 3);
}

/// From rest, 1 m/s^2 forward for accel_s, then on at constant velocity: a walk-off.
class WalkOff : public sim::Trajectory {
 public:
  explicit WalkOff(double accel_s) : T_(accel_s) {}
  double startTime() const override { return 0.0; }
  double endTime() const override { return 100.0; }
  sim::TrajectorySample sample(double t) const override {
    sim::TrajectorySample s;
    s.t = t;
    const Vec3 a(0.0, 1.0, 0.0);
    const double ta = std::min(t, T_);
    s.p_n_b = 0.5 * a * ta * ta + a * T_ * std::max(0.0, t - T_);
    s.v_n_b = a * ta;
    s.a_n_b = t < T_ ? a : Vec3::Zero();
    return s;
  }

 private:
  double T_;
};

// The last window_s at constant velocity is degenerate (no acceleration gives the scale); the
// images before it saw the walk-off, and the longer window (up to max_window_s) answers, exactly.
TEST(DynamicInit, ADegenerateWindowIsRetriedWithTheImagesBeforeIt) {
  const sim::Scenario sc = sim::wallScenario(10.0, false, 3);
  const WalkOff walk_off(1.0);
  const auto window = [](double max_window_s) {
    return [max_window_s](DynamicInitParams& p) {
      p.window_s = 1.0;
      p.max_window_s = max_window_s;
    };
  };
  const Window only_last = runWindow(walk_off, sc.world, sc.camera, sc.T_b_c, 0.2, 2.0, 0.0, 0.0, nullptr, 0.05,
                                     Vec3::Zero(), 1e-5, window(1.0));
  EXPECT_FALSE(only_last.result.has_value());
  EXPECT_EQ(only_last.why.rfind("degenerate motion", 0), 0u) << only_last.why;
  const Window longer = runWindow(walk_off, sc.world, sc.camera, sc.T_b_c, 0.2, 2.0, 0.0, 0.0, nullptr, 0.05,
                                  Vec3::Zero(), 1e-5, window(2.0));
  ASSERT_TRUE(longer.result.has_value()) << longer.why;
  EXPECT_GT(longer.result->frames, 30);  // 1.8 s of images at 20 Hz, not the last 1 s
  EXPECT_LT((longer.result->state.v_n_b - longer.truth.v_n_b).norm(), 1e-3);
  for (const DynamicInitLandmark& l : longer.result->landmarks)
    EXPECT_NEAR(l.depth_m, longer.true_depth.at(l.id), 0.01);
}

TEST(DynamicInit, RotationInPlaceAndConstantVelocityAreRefused) {
  const sim::Scenario sc = sim::wallScenario(10.0, false, 3);
  // Turning in place: no parallax, so neither depths nor velocity.
  const UniformMotion turn(Vec3::Zero(), Vec3(0.0, 0.0, 0.3));
  const Window a = runWindow(turn, sc.world, sc.camera, sc.T_b_c, 1.0, 2.0);
  EXPECT_FALSE(a.result.has_value());
  EXPECT_NE(a.why.find("degenerate"), std::string::npos) << a.why;
  // Walking straight at constant velocity: parallax, but no acceleration to fix the scale.
  const UniformMotion walk(Vec3(0.0, 1.2, 0.0), Vec3::Zero());
  const Window b = runWindow(walk, sc.world, sc.camera, sc.T_b_c, 1.0, 2.0);
  EXPECT_FALSE(b.result.has_value());
  EXPECT_NE(b.why.find("degenerate"), std::string::npos) << b.why;
  // Too few images yet: it says so.
  DynamicInitializer init(DynamicInitParams(), sc.camera, sc.T_b_c);
  std::string why;
  EXPECT_FALSE(init.tryInitialize(&why).has_value());
  EXPECT_FALSE(why.empty());
}

}  // namespace vi_ekf_slam
