#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "test_helpers.h"
#include "vi_ekf_slam/core/frame_change.h"
#include "vi_ekf_slam/core/navigation_output.h"

using namespace vi_ekf_slam;

namespace {

/// Nav-frame pose, velocity and landmarks with covariances must be identical.
void expectSameNavigationView(const FilterState& a, const FilterState& b, double tol) {
  const NavState na = navState(a), nb = navState(b);
  EXPECT_LT((na.p_n_b - nb.p_n_b).norm(), tol);
  EXPECT_LT((na.v_n_b - nb.v_n_b).norm(), tol);
  EXPECT_LT(rotationError(na.q_n_b, nb.q_n_b).norm(), tol);
  EXPECT_LT(test::maxAbs(na.cov - nb.cov), tol);
  const auto la = navLandmarks(a), lb = navLandmarks(b);
  ASSERT_EQ(la.size(), lb.size());
  for (size_t i = 0; i < la.size(); ++i) {
    EXPECT_EQ(la[i].id, lb[i].id);
    EXPECT_LT((la[i].p_n_l - lb[i].p_n_l).norm(), tol);
    EXPECT_LT(test::maxAbs(la[i].cov - lb[i].cov), tol);
  }
}

}  // namespace

TEST(Composition, JacobianMatchesNumeric) {
  std::mt19937_64 rng(14);
  const FilterState s0 = test::randomState(Mechanization::kSensorCentricComposition, 4, rng);
  const Eigen::MatrixXd Jn = test::numericFrameChangeJacobian(s0, [](FilterState& s) { compose(s); });
  const Eigen::MatrixXd J = denseJacobian(compositionJacobian(s0), s0.numLandmarks());
  EXPECT_LT(test::maxAbs(Jn - J), 1e-7) << "\n" << Jn - J;
}

TEST(Composition, StructuredProductEqualsDenseProduct) {
  std::mt19937_64 rng(15);
  FilterState s = test::randomState(Mechanization::kSensorCentricComposition, 7, rng);
  const Eigen::MatrixXd J = denseJacobian(compositionJacobian(s), s.numLandmarks());
  const Eigen::MatrixXd expected = J * s.covariance() * J.transpose();
  EXPECT_LT(test::maxAbs(applyFrameChange(s.covariance(), compositionJacobian(s)) - expected), 1e-13);
}

TEST(Composition, PreservesNavigationFramePoseAndMapAndResetsSensorPose) {
  std::mt19937_64 rng(16);
  FilterState s = test::randomState(Mechanization::kSensorCentricComposition, 6, rng);
  const FilterState before = s;
  compose(s);
  expectSameNavigationView(before, s, 1e-9);
  EXPECT_LT(s.x.p_s_b.norm(), 1e-15);
  EXPECT_LT(rotationError(s.x.q_s_b, Quat::Identity()).norm(), 1e-15);
  const Eigen::MatrixXd& P = s.covariance();
  // The pose of {b} in the new {s} is exact: its rows and columns are zero.
  EXPECT_EQ(test::maxAbs(P.middleRows<3>(idx::kP)), 0.0);
  EXPECT_EQ(test::maxAbs(P.middleRows<3>(idx::kPsi)), 0.0);
  EXPECT_EQ((s.x.b_a - before.x.b_a).norm(), 0.0);
  EXPECT_EQ((s.x.b_g - before.x.b_g).norm(), 0.0);
}

TEST(MechanizationSwitch, WorldToSensorJacobianMatchesNumeric) {
  std::mt19937_64 rng(17);
  const FilterState s0 = test::randomState(Mechanization::kWorldCentric, 3, rng);
  const Eigen::MatrixXd Jn = test::numericFrameChangeJacobian(
      s0, [](FilterState& s) { switchMechanization(s, Mechanization::kSensorCentric); });
  const Eigen::MatrixXd J = denseJacobian(worldToSensorJacobian(s0), s0.numLandmarks());
  ASSERT_EQ(J.rows(), idx::kSensorCentricDim + 9);
  EXPECT_LT(test::maxAbs(Jn - J), 1e-7) << "\n" << Jn - J;
}

TEST(MechanizationSwitch, SensorToWorldJacobianMatchesNumeric) {
  std::mt19937_64 rng(18);
  const FilterState s0 = test::randomState(Mechanization::kSensorCentric, 3, rng);
  const Eigen::MatrixXd Jn = test::numericFrameChangeJacobian(
      s0, [](FilterState& s) { switchMechanization(s, Mechanization::kWorldCentric); });
  const Eigen::MatrixXd J = denseJacobian(sensorToWorldJacobian(s0), s0.numLandmarks());
  ASSERT_EQ(J.rows(), idx::kWorldCentricDim + 9);
  EXPECT_LT(test::maxAbs(Jn - J), 1e-7) << "\n" << Jn - J;
}

TEST(MechanizationSwitch, RoundTripsPreserveNavigationQuantitiesAndMap) {
  std::mt19937_64 rng(19);
  FilterState w = test::randomState(Mechanization::kWorldCentric, 8, rng);
  const FilterState w0 = w;
  switchMechanization(w, Mechanization::kSensorCentricComposition);
  EXPECT_EQ(w.mechanization(), Mechanization::kSensorCentricComposition);
  EXPECT_EQ(w.dim(), idx::kSensorCentricDim + 24);
  expectSameNavigationView(w0, w, 1e-9);
  switchMechanization(w, Mechanization::kWorldCentric);
  expectSameNavigationView(w0, w, 1e-9);
  // World -> sensor -> world is the identity on the state and the covariance.
  EXPECT_LT(w.boxminus(w0).norm(), 1e-12);
  EXPECT_LT(test::maxAbs(w.covariance() - w0.covariance()), 1e-12);
  EXPECT_EQ(w.landmarkIds(), w0.landmarkIds());

  FilterState s = test::randomState(Mechanization::kSensorCentric, 5, rng);
  const FilterState s0 = s;
  switchMechanization(s, Mechanization::kWorldCentric);
  expectSameNavigationView(s0, s, 1e-9);
  switchMechanization(s, Mechanization::kSensorCentric);
  expectSameNavigationView(s0, s, 1e-9);
}

TEST(MechanizationSwitch, BetweenSensorCentricVariantsOnlyTheTagChanges) {
  std::mt19937_64 rng(20);
  FilterState s = test::randomState(Mechanization::kSensorCentric, 2, rng);
  const FilterState s0 = s;
  switchMechanization(s, Mechanization::kSensorCentricComposition);
  EXPECT_EQ(s.mechanization(), Mechanization::kSensorCentricComposition);
  EXPECT_LT(s.boxminus(s0).norm(), 1e-12);
}

TEST(NavigationOutput, SensorCentricCovarianceMatchesNumericPropagation) {
  // navState's covariance is J P J^T with J the derivative of the nav pose w.r.t. the state.
  std::mt19937_64 rng(21);
  const FilterState s0 = test::randomState(Mechanization::kSensorCentric, 2, rng);
  const NavState n0 = navState(s0);
  const Eigen::MatrixXd J = test::numericJacobian(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        FilterState s = s0;
        s.boxplus(d);
        const NavState n = navState(s);
        Eigen::VectorXd e(idx::kNavDim);
        e << n.p_n_b - n0.p_n_b, n.v_n_b - n0.v_n_b, n.b_a - n0.b_a, rotationError(n.q_n_b, n0.q_n_b), n.b_g - n0.b_g;
        return e;
      },
      s0.dim());
  const Eigen::MatrixXd expected = J * s0.covariance() * J.transpose();
  EXPECT_LT(test::maxAbs(Eigen::MatrixXd(n0.cov) - expected), 1e-9);
}

// The composition's Jacobian moves an inverse-depth landmark's bearing with the pose error in
// proportion to its inverse depth, taken at the estimate. With a depth known to 50% (a new point),
// the product of the two errors is missing from the first order: the exact composition of states
// drawn from the covariance spreads the bearing by (1 + (sigma_rho / rho)^2) times what the first
// order says. The second-order term puts it back.
TEST(Composition, SecondOrderTermIsTheSpreadThatAnUncertainDepthAdds) {
  std::mt19937_64 rng(21);
  FilterState s = test::randomState(Mechanization::kSensorCentricComposition, 2, rng);  // landmark 1: inverse depth
  ASSERT_EQ(s.landmark(1).kind, LandmarkKind::kInverseDepth);
  const int c = s.landmarkIndex(1);
  const double rho = s.landmark(1).l.z();
  // Independent errors: the position 0.1 m, the orientation 2 mrad, the bearing 1 mrad, rho 50%.
  Eigen::MatrixXd P = 1e-10 * Eigen::MatrixXd::Identity(s.dim(), s.dim());
  P.block<3, 3>(idx::kP, idx::kP) = 0.01 * Mat3::Identity();
  P.block<3, 3>(idx::kPsi, idx::kPsi) = 4e-6 * Mat3::Identity();
  P(c, c) = P(c + 1, c + 1) = 1e-6;
  P(c + 2, c + 2) = std::pow(0.5 * rho, 2);
  s.setCovariance(P);
  FilterState first = s, second = s;
  compose(first);
  compose(second, true);
  // The spread of the exact composition's bearing error over draws of the state's error.
  const Eigen::MatrixXd L = P.llt().matrixL();
  std::normal_distribution<double> n01;
  const int draws = 20000;
  Eigen::Matrix2d spread = Eigen::Matrix2d::Zero();
  for (int k = 0; k < draws; ++k) {
    Eigen::VectorXd z(s.dim());
    for (int j = 0; j < s.dim(); ++j) z(j) = n01(rng);
    FilterState x = s;
    x.boxplus(L * z);
    compose(x);
    const Eigen::Vector2d e = x.boxminus(first).segment<2>(c);
    spread += e * e.transpose() / draws;
  }
  const double sampled = spread.trace();
  const double first_order = first.covariance().block<2, 2>(c, c).trace();
  const double second_order = second.covariance().block<2, 2>(c, c).trace();
  EXPECT_LT(first_order, 0.85 * sampled) << "first order " << first_order << ", sampled " << sampled;
  EXPECT_NEAR(second_order / sampled, 1.0, 0.05) << "second order " << second_order << ", sampled " << sampled;
  // Only inverse-depth landmarks get it, and a Cartesian one is left as it was.
  const int c0 = s.landmarkIndex(0);
  EXPECT_EQ(test::maxAbs(second.covariance().block<3, 3>(c0, c0) - first.covariance().block<3, 3>(c0, c0)), 0.0);
}
