#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "test_helpers.h"
#include "vi_ekf_slam/eval/metrics.h"

using namespace vi_ekf_slam;

TEST(Metrics, NeesOfAKnownGaussianAveragesToItsDof) {
  std::mt19937_64 rng(30);
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::MatrixXd P = test::randomSpd(6, rng, 2.0);
  const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(P).matrixL();
  const int n = 20000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd z(6);
    for (int k = 0; k < 6; ++k) z(k) = g(rng);
    sum += eval::nees(L * z, P);
  }
  // Mean of chi^2(6) is 6, std-dev of the average sqrt(12 / n) = 0.024.
  EXPECT_NEAR(sum / n, 6.0, 0.1);
  // An over-confident covariance (half the true one) doubles the NEES.
  EXPECT_NEAR(eval::nees(L * Eigen::VectorXd::Ones(6), 0.5 * P), 2.0 * eval::nees(L * Eigen::VectorXd::Ones(6), P),
              1e-9);
}

TEST(Metrics, NeesBandMatchesChiSquare) {
  const eval::NeesBand b = eval::neesBand(6, 50);
  EXPECT_NEAR(b.lo, 253.912 / 50, 1e-3);
  EXPECT_NEAR(b.hi, 349.874 / 50, 1e-3);
  EXPECT_TRUE(b.contains(6.0));
  EXPECT_FALSE(b.contains(7.5));
  EXPECT_TRUE(std::isnan(eval::nees(Eigen::Vector3d::Ones(), -Eigen::Matrix3d::Identity())));
}

TEST(Metrics, ScaleRatioOfAScaledMapIsTheScale) {
  std::mt19937_64 rng(31);
  std::vector<Vec3> truth, est;
  for (int i = 0; i < 30; ++i) {
    truth.push_back(test::randomVec(rng, 10.0));
    est.push_back(1.25 * truth.back() + Vec3(3, -1, 2));  // scaled and shifted
  }
  EXPECT_NEAR(eval::scaleRatio(est, truth), 1.25, 1e-12);
  EXPECT_TRUE(std::isnan(eval::scaleRatio({Vec3::Zero()}, {Vec3::Zero()})));
}

TEST(Metrics, PosYawAlignmentRecoversYawAndTranslation) {
  std::mt19937_64 rng(32);
  std::vector<Vec3> truth, est;
  const Eigen::AngleAxisd yaw(0.7, Vec3::UnitZ());
  const Vec3 t(1, -2, 0.5);
  for (int i = 0; i < 50; ++i) {
    truth.push_back(test::randomVec(rng, 5.0));
    est.push_back(yaw.inverse() * (truth.back() - t));
  }
  const eval::YawTranslation T = eval::alignPosYaw(est, truth);
  EXPECT_NEAR(T.yaw, 0.7, 1e-12);
  EXPECT_LT((T.t - t).norm(), 1e-12);
  EXPECT_LT((T.apply(est[3]) - truth[3]).norm(), 1e-12);
}

TEST(Metrics, AteAndRpe) {
  std::vector<Vec3> e = {Vec3(3, 4, 0), Vec3(0, 0, 0)};
  EXPECT_NEAR(eval::rms(e), std::sqrt(12.5), 1e-12);
  std::vector<Vec3> p_true, p_est;
  std::vector<Quat> q;
  for (int k = 0; k < 10; ++k) {
    p_true.push_back(Vec3(k, 0, 0));
    p_est.push_back(Vec3(1.1 * k, 0, 0));  // 10% scale error
    q.push_back(Quat::Identity());
  }
  EXPECT_NEAR(eval::rpePosition(p_true, q, p_est, q, 2), 0.2, 1e-12);
  EXPECT_NEAR(eval::pathLength(p_true), 9.0, 1e-12);
}
