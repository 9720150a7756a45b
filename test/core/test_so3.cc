#include <gtest/gtest.h>

#include "test_helpers.h"
#include "vi_ekf_slam/core/so3.h"

using namespace vi_ekf_slam;

TEST(So3, ExpLogRoundTrip) {
  std::mt19937_64 rng(1);
  for (int i = 0; i < 100; ++i) {
    const Vec3 phi = test::randomVec(rng, 1.7);
    EXPECT_LT((logSO3(expSO3(phi)) - phi).norm(), 1e-12);
    EXPECT_LT((logQuat(expQuat(phi)) - phi).norm(), 1e-12);
  }
  EXPECT_LT(logQuat(expQuat(Vec3(1e-12, 0, 0))).norm(), 1e-11);
}

TEST(So3, SkewIsCrossProduct) {
  const Vec3 a(1, -2, 3), b(0.5, 4, -1);
  EXPECT_LT((skew(a) * b - a.cross(b)).norm(), 1e-15);
}

TEST(So3, RightJacobianMatchesNumeric) {
  std::mt19937_64 rng(2);
  for (int i = 0; i < 20; ++i) {
    const Vec3 phi = test::randomVec(rng, 1.2);
    // Exp(phi + d) = Exp(phi) Exp(Jr d)  ->  Log(Exp(phi)^T Exp(phi + d)) = Jr d
    const Eigen::MatrixXd Jn = test::numericJacobian(
        [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
          return logSO3(expSO3(phi).transpose() * expSO3(phi + Vec3(d)));
        },
        3);
    EXPECT_LT(test::maxAbs(Jn - rightJacobianSO3(phi)), 1e-8);
  }
}

// The yaw between two attitudes is the z rotation that turns one into the other, for any body
// axes: an IMU mounted x up (EuRoC's) has no usable heading of its x axis, and a 10 mrad tilt
// difference moved that heading by up to 0.5 rad.
TEST(So3, YawBetweenAttitudesHoldsForABodyWithItsXAxisUp) {
  std::mt19937_64 rng(4);
  const Quat x_up(Eigen::AngleAxisd(-0.5 * M_PI, Vec3::UnitY()));  // body x along {n}'s -z
  for (int i = 0; i < 20; ++i) {
    const Quat q = (expQuat(test::randomVec(rng, 0.05)) * x_up).normalized();  // x within 3 deg of vertical
    const double yaw = std::uniform_real_distribution<double>(-3.0, 3.0)(rng);
    const Vec3 tilt = test::randomVec(rng, 0.01).cwiseProduct(Vec3(1.0, 1.0, 0.0));
    const Quat turned = (expQuat(tilt) * Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ())) * q).normalized();
    EXPECT_NEAR(yawBetween(q, turned), yaw, 1e-3);
    EXPECT_NEAR(yawBetween(turned, q), -yaw, 1e-3);
  }
  EXPECT_NEAR(yawBetween(x_up, x_up), 0.0, 1e-12);
}

// The first-pose registration every evaluation uses: a trajectory turned about z and shifted is
// put back exactly, its first pose onto the other's and every later pose with it.
TEST(So3, RegistrationAtTheFirstPoseUndoesAYawAndATranslation) {
  std::mt19937_64 rng(5);
  for (int i = 0; i < 20; ++i) {
    const double yaw = std::uniform_real_distribution<double>(-3.0, 3.0)(rng);
    Eigen::Isometry3d T_to_from(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
    T_to_from.translation() = test::randomVec(rng, 10.0);
    const Vec3 p0 = test::randomVec(rng, 5.0), p1 = test::randomVec(rng, 5.0);
    const Quat q0 = expQuat(test::randomVec(rng, 1.0));
    const Quat q0_to(T_to_from.linear() * q0);
    const Eigen::Isometry3d T = registrationAtFirstPose(p0, q0, T_to_from * p0, q0_to);
    EXPECT_LT((T * p0 - T_to_from * p0).norm(), 1e-9);
    EXPECT_LT((T * p1 - T_to_from * p1).norm(), 1e-9);
    EXPECT_LT((T.linear() - T_to_from.linear()).norm(), 1e-9);
  }
}
