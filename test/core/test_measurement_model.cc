#include <gtest/gtest.h>

#include "test_helpers.h"
#include "vi_ekf_slam/core/measurement_model.h"

using namespace vi_ekf_slam;

class MeasurementModelTest : public ::testing::TestWithParam<Mechanization> {};

// H = J_pi [J_p 0 J_psi ... J_Y ...] (eq. 30) against numerical differentiation of eq. (29)
// with respect to the full error state.
TEST_P(MeasurementModelTest, JacobianMatchesNumeric) {
  std::mt19937_64 rng(7);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  for (int trial = 0; trial < 5; ++trial) {
    const FilterState s0 = test::randomState(GetParam(), 4, rng);
    for (int i = 0; i < s0.numLandmarks(); ++i) {
      Eigen::Vector2d uv;
      ObservationJacobians J;
      ASSERT_TRUE(predictObservation(s0.x, s0.landmark(i), cam, T, &uv, &J));
      Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, s0.dim());
      H.middleCols<3>(idx::kP) = J.H_p;
      H.middleCols<3>(idx::kPsi) = J.H_psi;
      H.middleCols<3>(s0.landmarkIndex(i)) = J.H_l;
      const Eigen::MatrixXd Hn = test::numericJacobian(
          [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
            FilterState s = s0;
            s.boxplus(d);
            Eigen::Vector2d u;
            predictObservation(s.x, s.landmark(i), cam, T, &u);
            return u;
          },
          s0.dim());
      EXPECT_LT(test::maxAbs(Hn - H), 1e-5 * test::maxAbs(H)) << "\n" << Hn - H;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Mechanizations, MeasurementModelTest,
                         ::testing::Values(Mechanization::kWorldCentric, Mechanization::kSensorCentric));

// The time offset's Jacobian is the pixel's rate of change while the body moves with its
// velocity v_s_b and turns with omega_b: checked against the numerical derivative of the
// projection along that motion (Cartesian and inverse-depth points, camera off the IMU origin).
TEST(MeasurementModel, ImageVelocityIsTheNumericalTimeDerivative) {
  std::mt19937_64 rng(31);
  const CameraModel cam = test::paperCamera();
  CameraExtrinsics T = test::forwardCamera();
  T.p_b_c = Vec3(0.05, -0.03, 0.1);
  for (int trial = 0; trial < 5; ++trial) {
    const FilterState s0 = test::randomState(Mechanization::kSensorCentric, 4, rng);
    const Vec3 omega_b = test::randomVec(rng, 2.0);
    for (int i = 0; i < s0.numLandmarks(); ++i) {
      Eigen::Vector2d velocity;
      ASSERT_TRUE(predictImageVelocity(s0.x, s0.landmark(i), cam, T, omega_b, &velocity));
      auto pixelAt = [&](double tau) {
        MotionState x = s0.x;
        x.p_s_b += x.v_s_b * tau;
        x.q_s_b = x.q_s_b * expQuat(omega_b * tau);
        Eigen::Vector2d uv;
        predictObservation(x, s0.landmark(i), cam, T, &uv);
        return uv;
      };
      const double h = 1e-6;
      const Eigen::Vector2d numeric = (pixelAt(h) - pixelAt(-h)) / (2.0 * h);
      EXPECT_LT((numeric - velocity).norm(), 1e-5 * std::max(1.0, velocity.norm()))
          << numeric.transpose() << " vs " << velocity.transpose();
    }
  }
}

TEST(MeasurementModel, PredictsTheSimulatedPixel) {
  // A landmark straight ahead of the camera projects onto the principal point.
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  MotionState x;
  x.p_s_b = Vec3(1, 2, 3);
  x.q_s_b = expQuat(Vec3(0, 0, 0.5));
  const Vec3 p_c(0, 0, 5);
  const Vec3 p_s = x.q_s_b * (T.R_b_c * p_c + T.p_b_c) + x.p_s_b;
  Eigen::Vector2d uv;
  ASSERT_TRUE(predictObservation(x, Landmark::cartesian(p_s), cam, T, &uv));
  EXPECT_LT((uv - Eigen::Vector2d(349.0, 269.5)).norm(), 1e-9);
  EXPECT_LT((landmarkInCamera(x, p_s, T) - p_c).norm(), 1e-12);
}

TEST(MeasurementModel, InverseDepthPointAtInfinityStaysFinite) {
  // rho = 0: a point at infinity along the anchor ray projects like a direction.
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  MotionState x;
  Landmark lm;
  lm.kind = LandmarkKind::kInverseDepth;
  lm.R_s_a = T.R_b_c;
  lm.p_s_a = T.p_b_c;
  lm.l = Vec3(0.1, -0.05, 0.0);
  x.p_s_b = Vec3(0.5, 0.3, -0.2);  // translation does not move a point at infinity
  Eigen::Vector2d uv;
  ObservationJacobians J;
  ASSERT_TRUE(predictObservation(x, lm, cam, T, &uv, &J));
  EXPECT_LT((uv - cam.normalizedToPixel(Eigen::Vector2d(0.1, -0.05))).norm(), 1e-9);
  EXPECT_TRUE(J.H_p.allFinite() && J.H_psi.allFinite() && J.H_l.allFinite());
  EXPECT_LT(J.H_p.norm(), 1e-12);
}
