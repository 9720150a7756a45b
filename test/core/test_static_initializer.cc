#include <gtest/gtest.h>

#include "test_helpers.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/static_initializer.h"

using namespace vi_ekf_slam;

TEST(StaticInitializer, RecoversRollPitchAndGyroBias) {
  const Quat q_true = expQuat(Vec3(0.3, -0.2, 1.1));  // any heading
  const Vec3 bg(0.01, -0.02, 0.005);
  const Vec3 f = -(q_true.conjugate() * gravityInNav(9.81));
  StaticInitializer init;
  std::mt19937_64 rng(26);
  std::normal_distribution<double> n(0.0, 0.02);
  std::optional<StaticInitResult> r;
  for (int k = 0; k < 400 && !r; ++k) {
    ImuData d;
    d.timestamp = 0.005 * k;
    d.am = f + Vec3(n(rng), n(rng), n(rng));
    d.wm = bg + 0.1 * Vec3(n(rng), n(rng), n(rng));
    r = init.addImu(d);
  }
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(r->timestamp, 1.0, 0.006);
  // Gravity direction (roll, pitch) matches to the noise level; yaw is set to zero.
  const Vec3 down_true = q_true.conjugate() * Vec3::UnitZ();
  const Vec3 down_est = r->q_n_b.conjugate() * Vec3::UnitZ();
  EXPECT_LT(std::acos(std::min(1.0, down_true.dot(down_est))), 2e-3);
  const Vec3 x_n = r->q_n_b * Vec3::UnitX();
  EXPECT_NEAR(std::atan2(x_n.y(), x_n.x()), 0.0, 1e-9);
  EXPECT_LT((r->b_g - bg).norm(), 1e-3);
}

TEST(StaticInitializer, AccelBiasAlongGravityFromTheMagnitude) {
  // An accelerometer that reads 9.93 m/s^2 at rest under 9.81 (as the real hand-held rig does):
  // the bias component along gravity is observable at rest, the horizontal one is not (it tilts
  // roll and pitch instead), so the initializer returns exactly the vertical part.
  const Quat q_true = expQuat(Vec3(0.2, 0.4, -0.7));
  const Vec3 down_b = q_true.conjugate() * Vec3::UnitZ();
  const Vec3 ba_vertical = -0.12 * down_b;  // along the specific force (up), 0.12 m/s^2
  const Vec3 f = -(q_true.conjugate() * gravityInNav(9.81)) + ba_vertical;
  StaticInitializer init;
  std::optional<StaticInitResult> r;
  for (int k = 0; k < 400 && !r; ++k) r = init.addImu({0.005 * k, Vec3::Zero(), f});
  ASSERT_TRUE(r.has_value());
  EXPECT_LT((r->b_a - ba_vertical).norm(), 1e-9);
  // Integrating the bias-corrected specific force with the estimated attitude gives no motion.
  const Vec3 a_n = r->q_n_b * (f - r->b_a) + gravityInNav(9.81);
  EXPECT_LT(a_n.norm(), 1e-9);
}

TEST(StaticInitializer, VibrationIsRestButSlowMotionIsNot) {
  // A MAV on the ground with its rotors running (EuRoC V1_01's first seconds: raw accel-norm std
  // 0.25-0.30 m/s^2, gyro 0.06-0.08 rad/s, far above the thresholds) is at rest: vibration at
  // 80-90 Hz averages out over the 50 ms blocks. The same amplitudes at 2 Hz are motion.
  auto run = [](double f_hz) {
    StaticInitializer init;
    std::optional<StaticInitResult> r;
    for (int k = 0; k < 600 && !r; ++k) {
      const double t = 0.005 * k, s = std::sin(2.0 * M_PI * f_hz * t + 0.3);
      r = init.addImu({t, Vec3(0.11 * s, -0.09 * s, 0.1 * s), Vec3(0.4 * s, 0.0, -9.81 + 0.4 * s)});
    }
    return r;
  };
  const auto vib = run(87.0);
  ASSERT_TRUE(vib.has_value());
  EXPECT_NEAR(vib->timestamp, 1.0, 0.006);  // from its first second
  EXPECT_FALSE(run(2.0).has_value());
}

TEST(StaticInitializer, WaitsWhileMoving) {
  StaticInitializer init;
  for (int k = 0; k < 1000; ++k) {
    ImuData d;
    d.timestamp = 0.005 * k;
    d.am = Vec3(0.0, 0.0, -9.81) + Vec3(2.0 * std::sin(0.05 * k), 0, 0);
    d.wm = Vec3(0.0, 0.5 * std::cos(0.05 * k), 0.0);
    EXPECT_FALSE(init.addImu(d).has_value());
  }
}

TEST(StaticInitializer, IgnoresNonFiniteAndOutOfOrderSamples) {
  StaticInitializer init;
  ImuData d;
  d.timestamp = 1.0;
  d.am = Vec3(std::nan(""), 0, 0);
  EXPECT_FALSE(init.addImu(d).has_value());
  std::optional<StaticInitResult> r;
  for (int k = 0; k < 300 && !r; ++k) {
    d.timestamp = 1.0 + 0.005 * k;
    d.am = Vec3(0, 0, -9.81);
    d.wm.setZero();
    r = init.addImu(d);
    ImuData old = d;
    old.timestamp -= 0.5;  // out of order: ignored
    EXPECT_FALSE(init.addImu(old).has_value());
  }
  ASSERT_TRUE(r.has_value());
  EXPECT_LT(rotationError(r->q_n_b, Quat::Identity()).norm(), 1e-9);
}
