// The one update step (kalman_update.h) against the textbook EKF with a dense H.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "test_helpers.h"
#include "vi_ekf_slam/core/chi_squared.h"
#include "vi_ekf_slam/core/kalman_update.h"

using namespace vi_ekf_slam;

namespace {

/// Two measurements on a state with landmarks: a 2-row one on the position, the attitude, the
/// time offset and a landmark (a feature's shape) and a 3-row one on the velocity.
std::vector<MeasurementRows> randomRows(const FilterState& s, std::mt19937_64& rng, double residual_scale) {
  std::normal_distribution<double> g(0.0, 1.0);
  auto block = [&](int col, int rows, int width) {
    JacobianBlock b;
    b.col = col;
    b.H.resize(rows, width);
    for (int i = 0; i < rows; ++i)
      for (int j = 0; j < width; ++j) b.H(i, j) = g(rng);
    return b;
  };
  MeasurementRows feature;
  feature.blocks = {block(idx::kP, 2, 3), block(idx::kPsi, 2, 3), block(s.landmarkIndex(1), 2, 3),
                    block(idx::kTd, 2, 1)};
  feature.residual = residual_scale * Eigen::Vector2d(g(rng), g(rng));
  feature.noise_var = 0.7;
  MeasurementRows velocity;
  velocity.blocks = {block(idx::kV, 3, 3)};
  velocity.residual = residual_scale * Vec3(g(rng), g(rng), g(rng));
  velocity.noise_var = 0.05;
  return {feature, velocity};
}

Eigen::MatrixXd denseJacobian(const std::vector<MeasurementRows>& rows, int n) {
  int m = 0;
  for (const auto& r : rows) m += r.dim();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, n);
  int row = 0;
  for (const auto& r : rows) {
    for (const auto& b : r.blocks) H.block(row, b.col, r.dim(), b.H.cols()) += b.H;
    row += r.dim();
  }
  return H;
}

Eigen::MatrixXd noiseOf(const std::vector<MeasurementRows>& rows) {
  Eigen::VectorXd d(stackedResidual(rows).size());
  int row = 0;
  for (const auto& r : rows) {
    d.segment(row, r.dim()).setConstant(r.noise_var);
    row += r.dim();
  }
  return d.asDiagonal();
}

}  // namespace

TEST(KalmanUpdate, BlocksGiveTheDenseInnovationCovarianceAndNis) {
  std::mt19937_64 rng(11);
  const FilterState s = test::randomState(Mechanization::kSensorCentricComposition, 4, rng);
  const std::vector<MeasurementRows> rows = randomRows(s, rng, 1.0);
  const Eigen::MatrixXd& P = s.covariance();
  const Eigen::MatrixXd H = denseJacobian(rows, s.dim());
  Eigen::MatrixXd PHt, S;
  innovationCovariance(P, rows, &PHt, &S);
  EXPECT_LT((PHt - P * H.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((S - (H * P * H.transpose() + noiseOf(rows))).cwiseAbs().maxCoeff(), 1e-11);
  const Eigen::VectorXd dx = Eigen::VectorXd::LinSpaced(s.dim(), -1.0, 1.0);
  EXPECT_LT((applyJacobian(rows, dx) - H * dx).cwiseAbs().maxCoeff(), 1e-12);
  // One measurement's own NIS.
  const Eigen::MatrixXd H0 = denseJacobian({rows[0]}, s.dim());
  const Eigen::Matrix2d S0 = H0 * P * H0.transpose() + rows[0].noise_var * Eigen::Matrix2d::Identity();
  const Eigen::Vector2d r0 = rows[0].residual;
  EXPECT_NEAR(normalizedInnovation(P, rows[0]), r0.dot(S0.inverse() * r0), 1e-9);
}

TEST(KalmanUpdate, UpdateEqualsTheTextbookJosephForm) {
  std::mt19937_64 rng(12);
  for (Mechanization m : {Mechanization::kWorldCentric, Mechanization::kSensorCentricComposition}) {
    FilterState s = test::randomState(m, 3, rng);
    const FilterState before = s;
    const std::vector<MeasurementRows> rows = randomRows(s, rng, 0.1);
    const Eigen::MatrixXd P = s.covariance();
    const Eigen::MatrixXd H = denseJacobian(rows, s.dim());
    const Eigen::MatrixXd R = noiseOf(rows);
    const Eigen::MatrixXd S = H * P * H.transpose() + R;
    const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
    const Eigen::VectorXd r = stackedResidual(rows);
    const KalmanUpdateResult res = kalmanUpdate(s, rows, 0.999);
    ASSERT_TRUE(res.applied);
    EXPECT_NEAR(res.nis, r.dot(S.inverse() * r), 1e-9);
    const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(s.dim(), s.dim()) - K * H;
    const Eigen::MatrixXd P_joseph = IKH * P * IKH.transpose() + K * R * K.transpose();
    EXPECT_LT((s.covariance() - P_joseph).cwiseAbs().maxCoeff(), 1e-10);
    EXPECT_LT((s.boxminus(before) - K * r).cwiseAbs().maxCoeff(), 1e-10);
  }
}

TEST(KalmanUpdate, ANearlyExactMeasurementLeavesTheCovarianceSymmetricAndPositiveSemidefinite) {
  // The rank-m form P - A A^T subtracts nearly all of P's variance along what a measurement of
  // almost no noise observes: the result must stay exactly symmetric, without a negative
  // eigenvalue beyond rounding, and equal to the textbook Joseph form.
  std::mt19937_64 rng(13);
  const FilterState s = test::randomState(Mechanization::kSensorCentric, 2, rng);
  std::vector<MeasurementRows> rows = randomRows(s, rng, 1.0);
  for (auto& r : rows) r.noise_var = 1e-10;
  const Eigen::MatrixXd P0 = s.covariance();
  const Eigen::MatrixXd H = denseJacobian(rows, s.dim());
  const Eigen::MatrixXd R = noiseOf(rows);
  Eigen::MatrixXd P = P0, PHt, S;
  innovationCovariance(P, rows, &PHt, &S);
  Eigen::LLT<Eigen::MatrixXd> llt;
  ASSERT_TRUE(factorInnovation(S, &llt));
  optimalGainCovarianceUpdate(P, PHt, llt);
  EXPECT_EQ(P, P.transpose());
  const Eigen::MatrixXd K = P0 * H.transpose() * S.inverse();
  const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(s.dim(), s.dim()) - K * H;
  const Eigen::MatrixXd expected = IKH * P0 * IKH.transpose() + K * R * K.transpose();
  EXPECT_LT((P - expected).cwiseAbs().maxCoeff(), 1e-9 * P0.cwiseAbs().maxCoeff());
  const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P).eigenvalues();
  EXPECT_GT(eig.minCoeff(), -1e-9 * P0.cwiseAbs().maxCoeff());
  // What the 5 rows observe is now known to about their noise.
  EXPECT_LT((H * P * H.transpose()).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(KalmanUpdate, TheGateRefusesAnInnovationBeyondItsQuantileAndLeavesTheStateAlone) {
  std::mt19937_64 rng(14);
  FilterState s = test::randomState(Mechanization::kWorldCentric, 2, rng);
  std::vector<MeasurementRows> rows = randomRows(s, rng, 1.0);
  Eigen::MatrixXd PHt, S;
  innovationCovariance(s.covariance(), rows, &PHt, &S);
  // Scale the residual so that its NIS is 1.5 times the 99.9% quantile of 5 dof.
  const Eigen::VectorXd r = stackedResidual(rows);
  const double nis = r.dot(S.ldlt().solve(r));
  const double scale = std::sqrt(1.5 * chiSquaredQuantile(0.999, 5.0) / nis);
  for (auto& m : rows) m.residual *= scale;
  const FilterState before = s;
  const KalmanUpdateResult res = kalmanUpdate(s, rows, 0.999);
  EXPECT_FALSE(res.applied);
  EXPECT_NEAR(res.nis, 1.5 * chiSquaredQuantile(0.999, 5.0), 1e-6);
  EXPECT_EQ(s.covariance(), before.covariance());
  EXPECT_EQ(s.x.p_s_b, before.x.p_s_b);
  EXPECT_EQ(s.x.v_s_b, before.x.v_s_b);
  EXPECT_EQ(s.x.q_s_b.coeffs(), before.x.q_s_b.coeffs());
}

TEST(KalmanUpdate, ConsiderLandmarksGetTheSchmidtKalmanUpdate) {
  // Landmarks marked consider (the map's dormant points) correct the rest of the state through
  // their cross-covariance but are never corrected themselves: the gain's rows of their entries
  // are zero, their block of P stays, and P is the Joseph form of that gain, no smaller than the
  // optimal update's.
  std::mt19937_64 rng(15);
  for (Mechanization m : {Mechanization::kWorldCentric, Mechanization::kSensorCentricComposition}) {
    FilterState s = test::randomState(m, 3, rng);
    s.landmark(1).consider = true;  // the feature observes it
    s.landmark(2).consider = true;  // correlated with what is observed, not observed
    const std::vector<int> consider = s.considerEntries();
    ASSERT_EQ(consider.size(), 6u);
    EXPECT_EQ(consider.front(), s.landmarkIndex(1));
    const FilterState before = s;
    const std::vector<MeasurementRows> rows = randomRows(s, rng, 0.1);
    const Eigen::MatrixXd P = s.covariance();
    const Eigen::MatrixXd H = denseJacobian(rows, s.dim());
    const Eigen::MatrixXd R = noiseOf(rows);
    const Eigen::MatrixXd S = H * P * H.transpose() + R;
    const Eigen::MatrixXd K_opt = P * H.transpose() * S.inverse();
    Eigen::MatrixXd K = K_opt;
    for (int k : consider) K.row(k).setZero();
    const Eigen::VectorXd r = stackedResidual(rows);
    ASSERT_TRUE(kalmanUpdate(s, rows, 0.999).applied);
    const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(s.dim(), s.dim()) - K * H;
    const Eigen::MatrixXd P_schmidt = IKH * P * IKH.transpose() + K * R * K.transpose();
    EXPECT_LT((s.covariance() - P_schmidt).cwiseAbs().maxCoeff(), 1e-10);
    EXPECT_LT((s.boxminus(before) - K * r).cwiseAbs().maxCoeff(), 1e-10);
    for (int i : {1, 2}) EXPECT_EQ(s.landmark(i).l, before.landmark(i).l);
    EXPECT_EQ(s.covariance()(consider, consider), P(consider, consider));
    // The motion state is corrected (the consider points are information, not ignored) ...
    EXPECT_GT((s.x.p_s_b - before.x.p_s_b).norm(), 0.0);
    // ... and the covariance is honest about the gain it used: no smaller than the optimal one's.
    const Eigen::MatrixXd P_opt = P - K_opt * H * P;
    const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s.covariance() - P_opt).eigenvalues();
    EXPECT_GT(eig.minCoeff(), -1e-9 * P.cwiseAbs().maxCoeff());
    EXPECT_GT(eig.maxCoeff(), 1e-9 * P.cwiseAbs().maxCoeff());
  }
}
