#include <gtest/gtest.h>

#include <cmath>

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
  const Eigen::Matrix3d Pll =
      Gx * P0 * Gx.transpose() + l.G_uv * l.G_uv.transpose() + 16.0 * l.G_depth * l.G_depth.transpose();
  EXPECT_LT(test::maxAbs(P.block<3, 3>(n, n) - Pll), 1e-12);
  EXPECT_LT((s.landmark(3).l - l.p_s_l).norm(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Mechanizations, LandmarkInitTest,
                         ::testing::Values(Mechanization::kWorldCentric, Mechanization::kSensorCentric));

TEST(LandmarkInit, LargeVarianceAlongTheRayPixelNoiseAcross) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s(Mechanization::kSensorCentric);  // zero pose uncertainty in {s}
  FixedDepthParams p;                            // 8 m +- 4 m, 1 px
  ASSERT_TRUE(initializeLandmarkFixedDepth(s, {1, Eigen::Vector2d(349.0, 269.5)}, cam, T, p));
  const Mat3 P = s.covariance().block<3, 3>(s.landmarkIndex(0), s.landmarkIndex(0));
  // At the principal point the ray is the camera z axis = body x axis.
  EXPECT_NEAR(P(0, 0), 16.0, 1e-9);
  // Across: (depth * pixel / focal)^2 = (8 / 420)^2 for both axes.
  EXPECT_NEAR(P(1, 1), std::pow(8.0 / 420.0, 2), 1e-9);
  EXPECT_NEAR(P(2, 2), std::pow(8.0 / 420.0, 2), 1e-9);
  EXPECT_NEAR(s.landmark(0).l.x(), 8.0 + T.p_b_c.x(), 1e-9);
}

TEST(LandmarkInit, InverseDepthIsTheSameRayAndItsCovarianceIsFirstOrder) {
  std::mt19937_64 rng(29);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s = test::randomState(Mechanization::kSensorCentric, 2, rng);
  const FilterState s0 = s;
  const Eigen::MatrixXd P0 = s.covariance();
  InverseDepthParams p;
  const Eigen::Vector2d uv(220.0, 330.0);
  ASSERT_TRUE(initializeLandmarkInverseDepth(s, {7, uv}, cam, T, p));
  const Landmark& lm = s.landmark(2);
  ASSERT_EQ(lm.kind, LandmarkKind::kInverseDepth);
  EXPECT_NEAR(lm.l.z(), 1.0 / p.initial_depth_m, 1e-12);
  // The landmark re-projects onto its own pixel from the pose it was created at.
  Eigen::Vector2d uv_pred;
  ASSERT_TRUE(predictObservation(s.x, lm, cam, T, &uv_pred));
  EXPECT_LT((uv_pred - uv).norm(), 1e-9);
  // Numerical Jacobian of l = (u, v, rho) w.r.t. state error, pixel and rho, with the anchor
  // kept at the estimated camera pose (it is a constant of the parameterization).
  const int n = s0.dim();
  const Vec3 a = lm.p_s_a;
  const Mat3 Ra = lm.R_s_a;
  const Eigen::MatrixXd Jn = test::numericJacobian(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        FilterState t = s0;
        t.boxplus(d.head(n));
        InitializedLandmark l;
        backProject(t.x, uv + d.segment<2>(n), 1.0 / (1.0 / p.initial_depth_m + d(n + 2)), cam, T, &l);
        const Vec3 p_a = Ra.transpose() * (l.p_s_l - a);
        return Vec3(p_a.x() / p_a.z(), p_a.y() / p_a.z(), 1.0 / p_a.z());
      },
      n + 3);
  const Eigen::MatrixXd Jx = Jn.leftCols(n);
  const Eigen::MatrixXd Jz = Jn.rightCols(3);
  const Eigen::MatrixXd& P = s.covariance();
  EXPECT_LT(test::maxAbs(P.block(n, 0, 3, n) - Jx * P0), 1e-8);
  Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
  R(0, 0) = R(1, 1) = 1.0;
  R(2, 2) = p.inverse_depth_sigma * p.inverse_depth_sigma;
  const Eigen::Matrix3d expected = Jx * P0 * Jx.transpose() + Jz * R * Jz.transpose();
  EXPECT_LT(test::maxAbs(P.block<3, 3>(n, n) - expected), 1e-8);
}

TEST(Landmark, InverseDepthJacobiansAreInversesAndMatchNumeric) {
  Landmark lm;
  lm.kind = LandmarkKind::kInverseDepth;
  lm.p_s_a = Vec3(1, 2, 3);
  lm.R_s_a = expSO3(Vec3(0.3, -0.4, 1.0));
  lm.l = Vec3(0.2, -0.1, 0.25);
  Mat3 M;
  lm.position(&M);
  EXPECT_LT(test::maxAbs(lm.paramsFromPointJacobian() * M - Mat3::Identity()), 1e-12);
  const Eigen::MatrixXd Mn = test::numericJacobian(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        Landmark t = lm;
        t.l += Vec3(d);
        return t.position();
      },
      3);
  EXPECT_LT(test::maxAbs(Mn - M), 1e-7);
}

// Landmarks whose inverse depths an initializer estimated together with the state: the covariance
// is the first-order propagation of [state error, inverse-depth errors] (jointly Gaussian, with
// the given cross-covariance) and the pixel noise, through the numerical Jacobian of the exact map.
TEST(LandmarkInit, JointInverseDepthsAreFirstOrderPropagationOfTheirJointUncertainty) {
  std::mt19937_64 rng(31);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  for (const Mechanization mech : {Mechanization::kWorldCentric, Mechanization::kSensorCentric}) {
    FilterState s = test::randomState(mech, 2, rng);
    const FilterState s0 = s;
    const int n = s0.dim();
    const std::vector<FeatureObservation> obs{{7, {220.0, 330.0}}, {8, {400.0, 120.0}}, {9, {90.0, 250.0}}};
    const std::vector<double> depths{2.0, 4.5, 1.2};
    // A joint covariance of [state error, 3 inverse-depth errors]: the state's own block and a
    // random (positive definite) rest, correlated with it.
    Eigen::MatrixXd R = 0.05 * Eigen::MatrixXd::Random(3, n + 3);
    // rho = K x + e: correlated with the state through K, plus its own e.
    const Eigen::MatrixXd K = 0.1 * Eigen::MatrixXd::Random(3, n);
    const Eigen::Matrix3d E = 0.01 * Eigen::Matrix3d::Identity() + R.leftCols<3>() * R.leftCols<3>().transpose();
    const Eigen::MatrixXd C = K * s0.covariance();
    const Eigen::MatrixXd Q = K * s0.covariance() * K.transpose() + E;
    const std::vector<int> entered = initializeLandmarksInverseDepthJointly(s, obs, depths, Q, C, cam, T, 1.0);
    ASSERT_EQ(entered, (std::vector<int>{0, 1, 2}));
    ASSERT_EQ(s.numLandmarks(), 5);
    // The exact map from [state error, pixel errors, inverse-depth errors] to the three new l.
    std::vector<Landmark> anchors;
    for (int a = 0; a < 3; ++a) anchors.push_back(s.landmark(2 + a));
    const Eigen::MatrixXd Jn = test::numericJacobian(
        [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
          FilterState t = s0;
          t.boxplus(d.head(n));
          Eigen::VectorXd out(9);
          for (int a = 0; a < 3; ++a) {
            InitializedLandmark l;
            backProject(t.x, obs[static_cast<size_t>(a)].uv + d.segment<2>(n + 2 * a),
                        1.0 / (1.0 / depths[static_cast<size_t>(a)] + d(n + 6 + a)), cam, T, &l);
            out.segment<3>(3 * a) = anchors[static_cast<size_t>(a)].paramsOf(l.p_s_l);
          }
          return out;
        },
        n + 9);
    // Covariance of [state error, pixels (1 px each), inverse depths].
    Eigen::MatrixXd Zf = Eigen::MatrixXd::Zero(n + 9, n + 9);
    Zf.topLeftCorner(n, n) = s0.covariance();
    Zf.block(n, n, 6, 6).setIdentity();
    Zf.block(n + 6, 0, 3, n) = C;
    Zf.block(0, n + 6, n, 3) = C.transpose();
    Zf.block(n + 6, n + 6, 3, 3) = Q;
    Eigen::MatrixXd Jfull = Eigen::MatrixXd::Zero(n + 9, n + 9);
    Jfull.topLeftCorner(n, n).setIdentity();
    Jfull.bottomRows(9) = Jn;
    const Eigen::MatrixXd expected = Jfull * Zf * Jfull.transpose();
    const Eigen::MatrixXd& P = s.covariance();
    ASSERT_EQ(P.rows(), n + 9);
    EXPECT_LT(test::maxAbs(P - expected), 1e-8) << static_cast<int>(mech);
    // Independent depths and no cross-covariance: the same as one landmark at a time.
    FilterState a = s0, b = s0;
    initializeLandmarksInverseDepthJointly(a, obs, depths,
                                           Eigen::Matrix3d(Eigen::Vector3d(0.04, 0.09, 0.01).asDiagonal()),
                                           Eigen::MatrixXd::Zero(3, n), cam, T, 1.0);
    for (int k = 0; k < 3; ++k) {
      InverseDepthParams p;
      p.initial_depth_m = depths[static_cast<size_t>(k)];
      p.inverse_depth_sigma = std::sqrt(Eigen::Vector3d(0.04, 0.09, 0.01)(k));
      ASSERT_TRUE(initializeLandmarkInverseDepth(b, obs[static_cast<size_t>(k)], cam, T, p));
    }
    EXPECT_LT(test::maxAbs(a.covariance() - b.covariance()), 1e-12);
    for (int k = 2; k < 5; ++k) EXPECT_LT((a.landmark(k).l - b.landmark(k).l).norm(), 1e-12);
  }
}

// A map point's inverse depth along the current camera's axis and its Jacobian (pose, orientation,
// the point's own entries; Cartesian and inverse-depth points) against numerical differentiation.
TEST(LandmarkInit, InverseDepthInCameraJacobianMatchesNumeric) {
  std::mt19937_64 rng(41);
  const CameraExtrinsics T = test::forwardCamera();
  for (const Mechanization mech : {Mechanization::kWorldCentric, Mechanization::kSensorCentric}) {
    const FilterState s0 = test::randomState(mech, 4, rng);
    for (int i = 0; i < s0.numLandmarks(); ++i) {
      Eigen::RowVectorXd J;
      const double rho = inverseDepthInCamera(s0, i, T, &J);
      const Vec3 p_c = T.R_b_c.transpose() * (s0.x.q_s_b.conjugate() * (s0.landmarkPosition(i) - s0.x.p_s_b) - T.p_b_c);
      EXPECT_NEAR(rho, 1.0 / p_c.z(), 1e-12);
      const Eigen::MatrixXd Jn = test::numericJacobian(
          [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
            FilterState s = s0;
            s.boxplus(d);
            return Eigen::VectorXd::Constant(1, inverseDepthInCamera(s, i, T));
          },
          s0.dim());
      EXPECT_LT(test::maxAbs(Jn - Eigen::MatrixXd(J)), 1e-6 * test::maxAbs(J)) << "\n" << Jn - Eigen::MatrixXd(J);
    }
  }
}

// Points entered at the map's depth move with the map's scale: when an observation then tells the
// reference point's inverse depth 25% larger, theirs follow by as much (a prior independent of the
// map would stay, and tell the filter the old scale once per point). Their own spread stays.
TEST(LandmarkInit, PointsAtTheMapDepthMoveWithTheMapsScale) {
  std::mt19937_64 rng(42);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s = test::randomState(Mechanization::kSensorCentric, 4, rng);
  // The pose known (1e-6 rad and m), the map's points to a few percent of their depth.
  Eigen::MatrixXd P = 1e-12 * Eigen::MatrixXd::Identity(s.dim(), s.dim());
  for (int i = 0; i < s.numLandmarks(); ++i)
    P.block<3, 3>(s.landmarkIndex(i), s.landmarkIndex(i)) = 1e-4 * Mat3::Identity();
  s.setCovariance(P);
  const int ref = 1;  // an inverse-depth point
  const double sigma = 0.5;
  const std::vector<FeatureObservation> obs{{7, {220.0, 330.0}}, {8, {400.0, 120.0}}};
  FilterState tied = s, independent = s;
  ASSERT_EQ(initializeLandmarksAtMapDepth(tied, obs, ref, sigma, cam, T, 1.0), (std::vector<int>{0, 1}));
  const double rho_ref = inverseDepthInCamera(s, ref, T);
  InverseDepthParams params;
  params.initial_depth_m = 1.0 / rho_ref;
  params.inverse_depth_sigma = sigma;
  for (const auto& o : obs) ASSERT_TRUE(initializeLandmarkInverseDepth(independent, o, cam, T, params));
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(tied.landmark(4 + k).l.z(), rho_ref, 1e-9);
    EXPECT_NEAR(std::sqrt(tied.covariance()(tied.landmarkIndex(4 + k) + 2, tied.landmarkIndex(4 + k) + 2)), sigma,
                0.01);
  }
  // A (linear) update that measures the reference's 1 / z as 1.25 times the estimate, almost exactly.
  auto shiftOfNewPoints = [&](const FilterState& f) {
    Eigen::RowVectorXd H;
    inverseDepthInCamera(f, ref, T, &H);
    const Eigen::VectorXd PHt = f.covariance() * H.transpose();
    const Eigen::VectorXd dx = PHt / (H.dot(PHt) + 1e-12) * (0.25 * rho_ref);
    return Eigen::Vector2d(dx(f.landmarkIndex(4) + 2), dx(f.landmarkIndex(5) + 2));
  };
  const Eigen::Vector2d tied_shift = shiftOfNewPoints(tied), independent_shift = shiftOfNewPoints(independent);
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(tied_shift(k), 0.25 * rho_ref, 1e-3 * rho_ref);
    EXPECT_NEAR(independent_shift(k), 0.0, 1e-3 * rho_ref);
  }
}
