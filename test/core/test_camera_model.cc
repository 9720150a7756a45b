#include <gtest/gtest.h>

#include "test_helpers.h"

using namespace vi_ekf_slam;

class CameraModelTest : public ::testing::TestWithParam<DistortionModel> {};

TEST_P(CameraModelTest, ProjectionJacobianMatchesNumeric) {
  const CameraModel cam = test::paperCamera(GetParam());
  std::mt19937_64 rng(3);
  for (int i = 0; i < 50; ++i) {
    const Vec3 p_c = Vec3(0, 0, 4.0) + test::randomVec(rng, 2.5);
    Eigen::Vector2d uv;
    Eigen::Matrix<double, 2, 3> J;
    ASSERT_TRUE(cam.project(p_c, &uv, &J));
    const Eigen::MatrixXd Jn = test::numericJacobian(
        [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
          Eigen::Vector2d u;
          cam.project(p_c + Vec3(d), &u);
          return u;
        },
        3);
    EXPECT_LT(test::maxAbs(Jn - J), 1e-5 * std::max(1.0, test::maxAbs(J)));
  }
}

TEST_P(CameraModelTest, UndistortionInvertsProjectionWithJacobian) {
  const CameraModel cam = test::paperCamera(GetParam());
  for (double u = 5; u < 699; u += 97) {
    for (double v = 5; v < 540; v += 83) {
      const Eigen::Vector2d uv(u, v);
      Eigen::Vector2d xn;
      Eigen::Matrix2d J;
      ASSERT_TRUE(cam.pixelToNormalized(uv, &xn, &J));
      EXPECT_LT((cam.normalizedToPixel(xn) - uv).norm(), 1e-9);
      const Eigen::MatrixXd Jn = test::numericJacobian(
          [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
            Eigen::Vector2d x;
            cam.pixelToNormalized(uv + Eigen::Vector2d(d), &x);
            return x;
          },
          2, 1e-4);
      EXPECT_LT(test::maxAbs(Jn - J), 1e-8);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CameraModelTest,
                         ::testing::Values(DistortionModel::kNone, DistortionModel::kRadTan,
                                           DistortionModel::kEquidistant));

TEST(CameraModel, RejectsImpossibleIntrinsics) {
  CameraIntrinsics in;
  in.width = 640;
  in.height = 480;
  in.fx = 0.0;  // all-zero camera_info, as some drivers publish before calibration
  in.fy = 0.0;
  EXPECT_FALSE(in.validate().empty());
  EXPECT_THROW(CameraModel{in}, std::invalid_argument);
  in.fx = in.fy = 400.0;
  in.cx = std::nan("");
  EXPECT_THROW(CameraModel{in}, std::invalid_argument);
}

TEST(CameraModel, PointBehindCameraIsNotProjected) {
  const CameraModel cam = test::paperCamera();
  Eigen::Vector2d uv;
  EXPECT_FALSE(cam.project(Vec3(0.1, 0.2, -1.0), &uv));
  EXPECT_TRUE(cam.project(Vec3(0.0, 0.0, 1.0), &uv));
  EXPECT_NEAR(uv.x(), 349.0, 1e-12);
  EXPECT_NEAR(uv.y(), 269.5, 1e-12);
}
