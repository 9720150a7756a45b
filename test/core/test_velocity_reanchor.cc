#include <gtest/gtest.h>

#include <random>

#include "test_helpers.h"
#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/velocity_reanchor.h"

using namespace vi_ekf_slam;

namespace {
Eigen::MatrixXd randomSpd(int n, std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  return scale * scale * (A * A.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n));
}
}  // namespace

TEST(VelocityReanchor, TheAlignmentsBodyVelocityCarriesItsTiltErrorAsANumericalDerivativeSays) {
  std::mt19937_64 rng(3);
  DynamicInitResult a;
  a.state.q_n_b = Quat(Eigen::AngleAxisd(0.4, Vec3(0.3, -0.5, 0.8).normalized()));
  a.state.v_n_b = Vec3(0.6, -0.3, 0.1);
  a.covariance = randomSpd(9, rng, 0.05);
  const BodyVelocity m = bodyVelocityOf(a);
  const Mat3 R = a.state.q_n_b.toRotationMatrix();
  EXPECT_LT((m.v_b - R.transpose() * a.state.v_n_b).norm(), 1e-12);
  // d v_b / d [v_n, psi] numerically, with R_true = Exp(psi) R.
  Eigen::Matrix<double, 3, 6> J;
  const double eps = 1e-6;
  for (int j = 0; j < 6; ++j) {
    Vec3 v = a.state.v_n_b, psi = Vec3::Zero();
    (j < 3 ? v : psi)(j % 3) += eps;
    J.col(j) = ((expSO3(psi) * R).transpose() * v - m.v_b) / eps;
  }
  const Mat3 expected = J * a.covariance.topLeftCorner<6, 6>() * J.transpose();
  EXPECT_LT((m.cov - expected).cwiseAbs().maxCoeff(), 1e-6 * expected.cwiseAbs().maxCoeff());
}

TEST(VelocityReanchor, TheUpdateIsTheTextbookOneWithANumericalJacobian) {
  std::mt19937_64 rng(5);
  for (Mechanization mech : {Mechanization::kWorldCentric, Mechanization::kSensorCentricComposition}) {
    FilterState s = test::randomState(mech, 3, rng);
    s.x.v_s_b = Vec3(0.4, -0.2, 0.3);
    const FilterState before = s;
    const Eigen::MatrixXd P = s.covariance();
    auto h = [](const FilterState& x) -> Vec3 { return x.x.q_s_b.conjugate() * x.x.v_s_b; };
    Eigen::MatrixXd H(3, s.dim());
    const double eps = 1e-7;
    for (int j = 0; j < s.dim(); ++j) {
      FilterState x = before;
      Eigen::VectorXd dx = Eigen::VectorXd::Zero(s.dim());
      dx(j) = eps;
      x.boxplus(dx);
      H.col(j) = (h(x) - h(before)) / eps;
    }
    BodyVelocity m;
    m.v_b = h(before) + Vec3(0.05, -0.03, 0.02);
    m.cov = randomSpd(3, rng, 0.05);
    const KalmanUpdateResult r = bodyVelocityUpdate(s, m, 0.0);
    ASSERT_TRUE(r.applied);
    const Mat3 S = H * P * H.transpose() + m.cov;
    const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
    const Vec3 res = m.v_b - h(before);
    EXPECT_NEAR(r.nis, res.dot(S.inverse() * res), 1e-6 * r.nis);
    EXPECT_LT((s.boxminus(before) - K * res).cwiseAbs().maxCoeff(), 1e-6);
    const Eigen::MatrixXd P_expected = P - K * H * P;
    EXPECT_LT((s.covariance() - P_expected).cwiseAbs().maxCoeff(), 1e-6 * P.cwiseAbs().maxCoeff());
  }
}

TEST(VelocityReanchor, AVelocityFarOutsideBothUncertaintiesIsRefused) {
  std::mt19937_64 rng(8);
  FilterState s = test::randomState(Mechanization::kSensorCentric, 2, rng);
  const FilterState before = s;
  BodyVelocity m;
  m.v_b = s.x.q_s_b.conjugate() * s.x.v_s_b + Vec3(5.0, 0.0, 0.0);
  m.cov = 0.01 * Mat3::Identity();
  const KalmanUpdateResult r = bodyVelocityUpdate(s, m, 0.999);
  EXPECT_FALSE(r.applied);
  EXPECT_GT(r.nis, 100.0);
  EXPECT_EQ(s.x.v_s_b, before.x.v_s_b);
  EXPECT_EQ(s.covariance(), before.covariance());
}
