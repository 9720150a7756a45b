#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

#include "test_helpers.h"
#include "vi_ekf_slam/core/zero_velocity.h"

using namespace vi_ekf_slam;

TEST(ZeroVelocity, UpdateEqualsTextbookJosephForm) {
  std::mt19937_64 rng(4);
  // Standing while swaying uses velocity_sigma_mps; with the IMU at rest too, rest_velocity_sigma_mps.
  for (const bool at_rest : {false, true})
    for (Mechanization m : {Mechanization::kWorldCentric, Mechanization::kSensorCentricComposition}) {
      FilterState s = test::randomState(m, 4, rng);
      s.x.v_s_b = Vec3(0.03, -0.02, 0.01);  // near zero: passes the gate
      const FilterState before = s;
      const Eigen::MatrixXd P = s.covariance();
      ZeroVelocityParams params;
      params.velocity_sigma_mps = 0.05;
      params.rest_velocity_sigma_mps = 0.02;
      const double sigma = at_rest ? 0.02 : 0.05;
      const ZeroVelocityResult r = zeroVelocityUpdate(s, params, at_rest);
      ASSERT_TRUE(r.applied);
      Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, s.dim());
      H.middleCols<3>(idx::kV).setIdentity();
      const Mat3 R = sigma * sigma * Mat3::Identity();
      const Mat3 S = H * P * H.transpose() + R;
      const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
      const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(s.dim(), s.dim()) - K * H;
      const Eigen::MatrixXd P_joseph = IKH * P * IKH.transpose() + K * R * K.transpose();
      EXPECT_LT((s.covariance() - P_joseph).cwiseAbs().maxCoeff(), 1e-12);
      const Vec3 r_v = -before.x.v_s_b;
      EXPECT_NEAR(r.nis, r_v.dot(S.inverse() * r_v), 1e-9);
      const Eigen::VectorXd dx = s.boxminus(before);
      EXPECT_LT((dx - K * r_v).cwiseAbs().maxCoeff(), 1e-12);
      // The velocity moved towards zero and its uncertainty is below the pseudo-measurement's.
      EXPECT_LT(s.x.v_s_b.norm(), before.x.v_s_b.norm());
      EXPECT_LT((s.covariance().block<3, 3>(idx::kV, idx::kV).trace()), 3 * sigma * sigma);
    }
}

TEST(ZeroVelocity, GateRefusesAMovingFilter) {
  std::mt19937_64 rng(5);
  FilterState s = test::randomState(Mechanization::kSensorCentric, 2, rng);
  s.x.v_s_b = Vec3(1.3, 0.0, 0.0);  // walking, far outside sqrt(P_vv + R)
  const FilterState before = s;
  EXPECT_FALSE(zeroVelocityUpdate(s, ZeroVelocityParams(), false).applied);
  EXPECT_EQ(s.x.v_s_b, before.x.v_s_b);
  EXPECT_EQ(s.covariance(), before.covariance());
}

namespace {
/// Features of a world of points seen from camera pose (R_n_c, p_n_c), 0.5 px noise.
CameraFrame see(double t, const std::vector<Vec3>& world, const Mat3& R_n_c, const Vec3& p_n_c, const CameraModel& cam,
                std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 0.5);
  CameraFrame f;
  f.timestamp = t;
  for (size_t i = 0; i < world.size(); ++i) {
    const Vec3 p_c = R_n_c.transpose() * (world[i] - p_n_c);
    Eigen::Vector2d uv;
    if (p_c.z() > 0.5 && cam.project(p_c, &uv) && cam.inImage(uv)) {
      f.features.push_back({static_cast<std::int64_t>(i), uv + Eigen::Vector2d(n(rng), n(rng))});
    }
  }
  return f;
}
}  // namespace

TEST(ZeroVelocity, DetectorTellsStandingAndTurningFromWalking) {
  std::mt19937_64 rng(6);
  const CameraModel cam = test::paperCamera();
  std::vector<Vec3> world;  // camera looks along z; points 2-12 m ahead
  std::uniform_real_distribution<double> lat(-4.0, 4.0), depth(2.0, 12.0);
  for (int i = 0; i < 200; ++i) world.emplace_back(lat(rng), 0.5 * lat(rng), depth(rng));
  const ZeroVelocityParams params;
  // motion(t) -> camera pose; 28 Hz for 2 s; the decision at the end.
  auto decide = [&](const std::function<std::pair<Mat3, Vec3>(double)>& motion) {
    StationaryDetector det;
    StationaryDetector::Decision d;
    for (int k = 0; k <= 56; ++k) {
      const double t = k / 28.0;
      const auto [R, p] = motion(t);
      d = det.update(see(t, world, R, p, cam, rng), R, cam, params);
    }
    return d;
  };
  const auto standing = decide([](double) { return std::make_pair(Mat3::Identity(), Vec3::Zero()); });
  EXPECT_TRUE(standing.decided);
  EXPECT_TRUE(standing.stationary) << standing.parallax_px;
  // Turning on the spot at 30 deg/s: the filter's rotation removes it.
  const auto turning = decide([](double t) { return std::make_pair(expSO3(Vec3(0, 0.52 * t, 0)), Vec3::Zero()); });
  EXPECT_TRUE(turning.stationary) << turning.parallax_px;
  // Swaying 1 cm at 2 Hz while standing is still standing.
  const auto swaying =
      decide([](double t) { return std::make_pair(Mat3::Identity(), Vec3(0.01 * std::sin(4 * M_PI * t), 0, 0)); });
  EXPECT_TRUE(swaying.stationary) << swaying.parallax_px;
  // Walking forward at 1.3 m/s and sideways at 0.3 m/s: not standing.
  const auto walking = decide([](double t) { return std::make_pair(Mat3::Identity(), Vec3(0, 0, 1.3 * t)); });
  EXPECT_TRUE(walking.decided);
  EXPECT_FALSE(walking.stationary) << walking.parallax_px;
  const auto sidestep = decide([](double t) { return std::make_pair(Mat3::Identity(), Vec3(0.3 * t, 0, 0)); });
  EXPECT_FALSE(sidestep.stationary) << sidestep.parallax_px;
  // Too few features: no decision, although a window of history exists (has_history: new
  // landmarks need not wait for a decision that a sparse scene never gives).
  StationaryDetector det;
  CameraFrame empty;
  for (int k = 0; k <= 28; ++k) {
    empty.timestamp = k / 28.0;
    const auto d = det.update(empty, Mat3::Identity(), cam, params);
    EXPECT_FALSE(d.decided);
    EXPECT_EQ(d.has_history, empty.timestamp >= params.window_s - 1e-9) << empty.timestamp;
  }
}

TEST(ZeroVelocity, ASlowWalkTowardsAFarSceneIsNotStandingWhenTheImagesShowTheFiltersMotion) {
  // The camera looks along z at points 8-20 m ahead; walking at 0.3 m/s moves most of them by
  // less than max_parallax_px over the window: the median alone calls it standing.
  std::mt19937_64 rng(7);
  const CameraModel cam = test::paperCamera();
  std::vector<Vec3> world;
  std::uniform_real_distribution<double> lat(-5.0, 5.0), depth(8.0, 20.0);
  for (int i = 0; i < 120; ++i) world.emplace_back(lat(rng), 0.4 * lat(rng), depth(rng));
  const ZeroVelocityParams params;
  // true_speed: along z [m/s]; filter_v: the filter's velocity (nullopt: no ExpectedMotion).
  auto decide = [&](double true_speed, std::optional<Vec3> filter_v) {
    StationaryDetector det;
    StationaryDetector::Decision d;
    for (int k = 0; k <= 28; ++k) {
      const double t = k / 28.0;
      std::optional<ExpectedMotion> expected;
      if (filter_v) {
        expected = ExpectedMotion{};
        expected->v_n_b = *filter_v;
        expected->scene_depth_m = 5.0;  // the prior's depth: the points are 2-4 times as far
        expected->pixel_noise_px = 0.5;
      }
      d = det.update(see(t, world, Mat3::Identity(), Vec3(0, 0, true_speed * t), cam, rng), Mat3::Identity(), cam,
                     params, expected);
    }
    return d;
  };
  const auto median_alone = decide(0.3, std::nullopt);
  ASSERT_TRUE(median_alone.decided);
  EXPECT_LT(median_alone.parallax_px, params.max_parallax_px);  // the ambiguous case
  EXPECT_TRUE(median_alone.stationary);
  EXPECT_TRUE(std::isnan(median_alone.motion_shown));
  // The filter walking at 0.3 m/s: the images show its motion (at a third of the flow the 5 m
  // depth predicts), so no zero-velocity update.
  const auto walking = decide(0.3, Vec3(0, 0, 0.3));
  EXPECT_TRUE(walking.motion_confirmed) << walking.motion_shown << " +- " << walking.motion_shown_sigma;
  EXPECT_FALSE(walking.stationary);
  EXPECT_GT(walking.motion_shown, 0.2);
  EXPECT_LT(walking.motion_shown, 0.7);
  // Standing while the filter's velocity drifted to 0.3 m/s: the images refute it; standing.
  const auto drifted = decide(0.0, Vec3(0, 0, 0.3));
  EXPECT_FALSE(drifted.motion_confirmed);
  EXPECT_LT(std::abs(drifted.motion_shown), 4.0 * drifted.motion_shown_sigma);
  EXPECT_TRUE(drifted.stationary);
  // Standing, the filter at nearly zero velocity: too small to show; the median decides.
  const auto still = decide(0.0, Vec3(0.01, 0, 0.0));
  EXPECT_GT(still.motion_shown_sigma, 5.0 * drifted.motion_shown_sigma);
  EXPECT_FALSE(still.motion_confirmed);
  EXPECT_TRUE(still.stationary);
  // A slipped track (a 40 px jump along the filter's flow) does not make a stand a walk.
  StationaryDetector det;
  StationaryDetector::Decision d;
  ExpectedMotion drifting;
  drifting.v_n_b = Vec3(0, 0, 0.3);
  drifting.pixel_noise_px = 0.5;
  for (int k = 0; k <= 28; ++k) {
    CameraFrame f = see(k / 28.0, world, Mat3::Identity(), Vec3::Zero(), cam, rng);
    if (k >= 14)
      f.features[0].uv +=
          40.0 * (f.features[0].uv - Eigen::Vector2d(cam.intrinsics().cx, cam.intrinsics().cy)).normalized();
    d = det.update(f, Mat3::Identity(), cam, params, drifting);
  }
  EXPECT_FALSE(d.motion_confirmed) << d.motion_shown << " +- " << d.motion_shown_sigma;
  EXPECT_TRUE(d.stationary);
}

TEST(ZeroVelocity, ImuAtRestTellsAStillRigFromAJitteringOne) {
  ZeroVelocityParams p;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  auto samples = [&](double accel_sigma, double gyro) {
    std::deque<ImuData> imu;
    for (int k = 0; k < 40; ++k) {
      ImuData d;
      d.timestamp = 0.005 * k;
      d.am = Vec3(0.1, -0.2, 9.81) + accel_sigma * Vec3(noise(rng), noise(rng), noise(rng));
      d.wm = Vec3(gyro, 0.001, -0.002);
      imu.push_back(d);
    }
    return imu;
  };
  EXPECT_TRUE(imuAtRest(samples(0.05, 0.0), 0.0, 0.2, p));    // sensor noise of 5 mg
  EXPECT_FALSE(imuAtRest(samples(1.0, 0.0), 0.0, 0.2, p));    // a hand-held rig's jitter
  EXPECT_FALSE(imuAtRest(samples(0.05, 0.14), 0.0, 0.2, p));  // turning slowly
  EXPECT_FALSE(imuAtRest(samples(0.05, 0.0), 0.3, 0.5, p));   // no sample in the interval
  std::deque<ImuData> jolt = samples(0.05, 0.0);
  jolt[30].am.x() += 5.0;  // a bump outside the interval does not count
  EXPECT_TRUE(imuAtRest(jolt, 0.0, 0.1, p));
  EXPECT_FALSE(imuAtRest(jolt, 0.0, 0.2, p));
}
