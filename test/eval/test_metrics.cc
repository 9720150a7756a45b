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

// Coming back to places: a walk 40 m out and back along x whose estimate drifts sideways by
// 1 cm per second. Registered on the way out, the error at a place on return is the drift then,
// against the drift when the place was first passed; a yaw and offset of the whole estimate (the
// start's registration, which nothing observes) change nothing.
TEST(Metrics, RevisitErrorsCompareTheReturnWithTheFirstVisit) {
  std::vector<double> t;
  std::vector<Vec3> truth, est;
  for (int k = 0; k <= 800; ++k) {  // 1 m/s, 10 Hz: out for 40 s, back for 40 s
    const double s = 0.1 * k;
    t.push_back(s);
    truth.emplace_back(s <= 40.0 ? s : 80.0 - s, 0.0, 0.0);
    est.push_back(truth.back() + Vec3(0.0, 0.01 * s, 0.0));
  }
  const eval::RevisitErrors r = eval::revisitErrors(t, truth, est);
  // The first return 20 s after a place (x = 30 m at 30 s and 50 s) on: places x <= 30 m again.
  EXPECT_GE(r.pairs, 300);
  EXPECT_LE(r.pairs, 305);
  std::printf("revisits: %d pairs, %.3f m then, %.3f m again\n", r.pairs, r.first_m, r.again_m);
  // Registered on the way out (yaw + offset fitted to the linear drift), the remaining errors at
  // x on the way out and back differ by the drift accumulated in between: 0.01 (80 - 2x) m.
  EXPECT_GT(r.ratio(), 1.5);
  const Quat yaw(Eigen::AngleAxisd(0.3, Vec3::UnitZ()));
  std::vector<Vec3> moved;
  for (const Vec3& p : est) moved.push_back(yaw * p + Vec3(5.0, -3.0, 0.0));
  const eval::RevisitErrors m = eval::revisitErrors(t, truth, moved);
  EXPECT_NEAR(m.ratio(), r.ratio(), 1e-9);
  EXPECT_NEAR(m.again_m, r.again_m, 1e-9);
  // No drift: no error on return either; a walk that never comes back has no pairs.
  EXPECT_NEAR(eval::revisitErrors(t, truth, truth).again_m, 0.0, 1e-12);
  const std::vector<double> t_out(t.begin(), t.begin() + 401);
  const std::vector<Vec3> out(truth.begin(), truth.begin() + 401);
  EXPECT_EQ(eval::revisitErrors(t_out, out, out).pairs, 0);
  EXPECT_TRUE(std::isnan(eval::revisitErrors(t_out, out, out).ratio()));
  EXPECT_THROW(eval::revisitErrors(t_out, truth, truth), std::invalid_argument);
}
