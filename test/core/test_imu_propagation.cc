#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "test_helpers.h"
#include "vi_ekf_slam/core/imu_propagation.h"

using namespace vi_ekf_slam;

namespace {
const Vec3 kG = gravityInNav(9.81);

FilterState motionOnly(Mechanization m, std::mt19937_64& rng) { return test::randomState(m, 0, rng); }
}  // namespace

class PropagationTest : public ::testing::TestWithParam<Mechanization> {};

// Phi (eq. 12-17, 22-28) against the numerical derivative of the strapdown step (eq. 8-9, 21).
TEST_P(PropagationTest, TransitionMatrixMatchesNumeric) {
  std::mt19937_64 rng(4);
  for (int trial = 0; trial < 10; ++trial) {
    const FilterState s0 = motionOnly(GetParam(), rng);
    const Vec3 wm = test::randomVec(rng, 1.0), am = Vec3(0.3, -0.2, -9.5) + test::randomVec(rng, 2.0);
    const double dt = 0.02;
    const MotionMatrix Phi = transitionMatrix(s0.x, s0.mechanization(), wm, am, dt, kG);
    FilterState ref = s0;
    strapdownStep(ref.x, ref.mechanization(), wm, am, dt, kG);
    const Eigen::MatrixXd Jn = test::numericJacobian(
        [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
          FilterState s = s0;
          s.boxplus(d);
          strapdownStep(s.x, s.mechanization(), wm, am, dt, kG);
          return s.boxminus(ref);
        },
        s0.dim());
    EXPECT_LT(test::maxAbs(Jn - Eigen::MatrixXd(Phi)), 1e-8) << "\n" << Jn - Eigen::MatrixXd(Phi);
  }
}

TEST_P(PropagationTest, StationaryImuWithExactGravityKeepsPose) {
  FilterState s(GetParam());
  s.x.q_s_b = expQuat(Vec3(0.2, -0.1, 0.7));
  if (isSensorCentric(GetParam())) {
    // {s} tilted w.r.t. {n}: gravity in {s} comes from q_n_s (eq. 21).
    s.x.q_n_s = expQuat(Vec3(-0.3, 0.25, 1.0));
  }
  const Quat q_n_b = s.x.q_n_s * s.x.q_s_b;
  const Vec3 am = -(q_n_b.conjugate() * kG);  // specific force at rest
  const FilterState s0 = s;
  ImuNoiseParams noise;
  for (int k = 0; k < 2000; ++k) propagateState(s, Vec3::Zero(), am, 0.005, noise, kG);
  EXPECT_LT(s.x.p_s_b.norm(), 1e-9);
  EXPECT_LT(s.x.v_s_b.norm(), 1e-10);
  EXPECT_LT(rotationError(s.x.q_s_b, s0.x.q_s_b).norm(), 1e-12);
}

TEST_P(PropagationTest, ConstantRotationMatchesClosedForm) {
  // Rotation about a fixed axis at constant rate, body at rest: q(t) = q0 Exp(w t).
  FilterState s(GetParam());
  const Vec3 w(0.3, -0.5, 0.8);
  const double dt = 0.005;
  const int steps = 2000;  // 10 s
  ImuNoiseParams noise;
  for (int k = 0; k < steps; ++k) {
    // At rest the specific force is -R_n_b(t)^T g; the step uses its value at mid-step.
    const Quat q_n_b_mid = s.x.q_n_s * s.x.q_s_b * expQuat(0.5 * dt * w);
    const Vec3 am = -(q_n_b_mid.conjugate() * kG);
    propagateState(s, w, am, dt, noise, kG);
  }
  const Quat expected = expQuat(w * steps * dt);
  EXPECT_LT(rotationError(s.x.q_s_b, expected).norm(), 1e-10);
  EXPECT_LT(s.x.p_s_b.norm(), 1e-9);
  EXPECT_LT(s.x.v_s_b.norm(), 1e-10);
}

TEST_P(PropagationTest, ConstantAccelerationMatchesClosedForm) {
  FilterState s(GetParam());
  s.x.q_s_b = expQuat(Vec3(0.1, 0.2, -0.3));
  s.x.v_s_b = Vec3(1.0, -0.5, 0.2);
  const Vec3 a_s(0.4, 0.3, -0.2);  // kinematic acceleration in {s}
  const Quat q_n_b = s.x.q_n_s * s.x.q_s_b;
  const Vec3 am = s.x.q_s_b.conjugate() * a_s - q_n_b.conjugate() * kG;
  const Vec3 v0 = s.x.v_s_b;
  ImuNoiseParams noise;
  const double dt = 0.005, T = 5.0;
  for (int k = 0; k < 1000; ++k) propagateState(s, Vec3::Zero(), am, dt, noise, kG);
  EXPECT_LT((s.x.p_s_b - (v0 * T + 0.5 * a_s * T * T)).norm(), 1e-9);
  EXPECT_LT((s.x.v_s_b - (v0 + a_s * T)).norm(), 1e-10);
}

TEST_P(PropagationTest, CovarianceStaysSymmetricPsdAndTouchesOnlyMotionBlocks) {
  std::mt19937_64 rng(5);
  FilterState s = test::randomState(GetParam(), 6, rng);
  s.setLazyCrossCovariance(false);
  const Eigen::MatrixXd P0 = s.covariance();
  ImuNoiseParams noise;
  for (int k = 0; k < 400; ++k) {
    propagateState(s, test::randomVec(rng, 1.0), Vec3(0, 0, -9.81) + test::randomVec(rng, 1.0), 0.005, noise, kG);
  }
  const Eigen::MatrixXd& P = s.covariance();
  const int m = s.motionDim();
  EXPECT_LT(test::maxAbs(P - P.transpose()), 1e-12);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(P);
  EXPECT_GT(es.eigenvalues().minCoeff(), -1e-12);
  // P_mm is untouched by propagation (eq. 19).
  EXPECT_EQ(
      test::maxAbs(P.bottomRightCorner(s.dim() - m, s.dim() - m) - P0.bottomRightCorner(s.dim() - m, s.dim() - m)),
      0.0);
}

TEST_P(PropagationTest, LazyCrossCovarianceEqualsPerSamplePropagation) {
  std::mt19937_64 rng(6);
  FilterState eager = test::randomState(GetParam(), 10, rng);
  FilterState lazy = eager;
  eager.setLazyCrossCovariance(false);
  lazy.setLazyCrossCovariance(true);
  ImuNoiseParams noise;
  for (int k = 0; k < 200; ++k) {
    const Vec3 w = test::randomVec(rng, 1.0), a = Vec3(0, 0, -9.81) + test::randomVec(rng, 2.0);
    propagateState(eager, w, a, 0.005, noise, kG);
    propagateState(lazy, w, a, 0.005, noise, kG);
  }
  EXPECT_TRUE(lazy.hasPendingCrossPropagation());
  EXPECT_LT(test::maxAbs(eager.covariance() - lazy.covariance()), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Mechanizations, PropagationTest,
                         ::testing::Values(Mechanization::kWorldCentric, Mechanization::kSensorCentric));

TEST(Propagation, DiscreteNoiseMatchesDensities) {
  // Over one step the velocity variance grows by sigma_a^2 dt and the gyro bias by sigma_bg^2 dt.
  ImuNoiseParams noise;
  noise.accel_noise_density = 0.01;
  noise.gyro_random_walk = 1e-4;
  const MotionMatrix I = MotionMatrix::Identity(idx::kWorldCentricDim, idx::kWorldCentricDim);
  const MotionMatrix Qd = discreteNoise(I, Mechanization::kWorldCentric, noise, 0.01);
  EXPECT_NEAR(Qd(idx::kV, idx::kV), 1e-4 * 0.01, 1e-15);
  EXPECT_NEAR(Qd(idx::kBg, idx::kBg), 1e-8 * 0.01, 1e-20);
  EXPECT_EQ(Qd(idx::kP, idx::kP), 0.0);
}
