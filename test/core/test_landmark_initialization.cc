#include <gtest/gtest.h>

#include "test_helpers.h"
#include "vi_ekf_slam/core/landmark_initialization.h"

using namespace vi_ekf_slam;

class LandmarkInitTest : public ::testing::TestWithParam<Mechanization> {};

// The initialization Jacobians (pose, pixel, depth) against numerical differentiation.
TEST_P(LandmarkInitTest, JacobiansMatchNumeric) {
  std::mt19937_64 rng(12);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  const FilterState s0 = test::randomState(GetParam(), 0, rng);
  const Eigen::Vector2d uv(120.0, 400.0);
  const double depth = 8.0;
  InitializedLandmark l;
  ASSERT_TRUE(backProject(s0.x, uv, depth, cam, T, &l));
  const int n = s0.dim();
  const Eigen::MatrixXd Jn = test::numericJacobian(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        FilterState s = s0;
        s.boxplus(d.head(n));
        InitializedLandmark o;
        backProject(s.x, uv + d.segment<2>(n), depth + d(n + 2), cam, T, &o);
        return o.p_s_l;
      },
      n + 3);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, n + 3);
  J.middleCols<3>(idx::kP) = l.G_p;
  J.middleCols<3>(idx::kPsi) = l.G_psi;
  J.middleCols<2>(n) = l.G_uv;
  J.col(n + 2) = l.G_depth;
  EXPECT_LT(test::maxAbs(Jn - J), 1e-6) << "\n" << Jn - J;
}

TEST_P(LandmarkInitTest, CovarianceIsFirstOrderPropagation) {
  std::mt19937_64 rng(13);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s = test::randomState(GetParam(), 3, rng);
  const Eigen::MatrixXd P0 = s.covariance();
  FixedDepthParams p;
  ASSERT_TRUE(initializeLandmarkFixedDepth(s, {42, Eigen::Vector2d(500.0, 100.0)}, cam, T, p));
  ASSERT_EQ(s.numLandmarks(), 4);
  // Recompute the expected blocks from the dense Jacobian [G_x, G_uv, G_d].
  InitializedLandmark l;
  ASSERT_TRUE(backProject(s.x, Eigen::Vector2d(500.0, 100.0), p.depth_m, cam, T, &l));
  const int n = static_cast<int>(P0.rows());
  Eigen::MatrixXd Gx = Eigen::MatrixXd::Zero(3, n);
  Gx.middleCols<3>(idx::kP) = l.G_p;
  Gx.middleCols<3>(idx::kPsi) = l.G_psi;
  const Eigen::MatrixXd& P = s.covariance();
  EXPECT_LT(test::maxAbs(P.block(n, 0, 3, n) - Gx * P0), 1e-12);
  const Eigen::Matrix3d Pll = Gx * P0 * Gx.transpose() + l.G_uv * l.G_uv.transpose() +
                              16.0 * l.G_depth * l.G_depth.transpose();
  EXPECT_LT(test::maxAbs(P.block<3, 3>(n, n) - Pll), 1e-12);
  EXPECT_LT((s.landmark(3) - l.p_s_l).norm(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Mechanizations, LandmarkInitTest,
                         ::testing::Values(Mechanization::kWorldCentric, Mechanization::kSensorCentric));

TEST(LandmarkInit, LargeVarianceAlongTheRayPixelNoiseAcross) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s(Mechanization::kSensorCentric);  // zero pose uncertainty in {s}
  FixedDepthParams p;  // 8 m +- 4 m, 1 px
  ASSERT_TRUE(initializeLandmarkFixedDepth(s, {1, Eigen::Vector2d(349.0, 269.5)}, cam, T, p));
  const Mat3 P = s.covariance().block<3, 3>(s.landmarkIndex(0), s.landmarkIndex(0));
  // At the principal point the ray is the camera z axis = body x axis.
  EXPECT_NEAR(P(0, 0), 16.0, 1e-9);
  // Across: (depth * pixel / focal)^2 = (8 / 420)^2 for both axes.
  EXPECT_NEAR(P(1, 1), std::pow(8.0 / 420.0, 2), 1e-9);
  EXPECT_NEAR(P(2, 2), std::pow(8.0 / 420.0, 2), 1e-9);
  EXPECT_NEAR(s.landmark(0).x(), 8.0 + T.p_b_c.x(), 1e-9);
}
