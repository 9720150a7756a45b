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
