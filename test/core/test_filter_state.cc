#include <gtest/gtest.h>

#include "test_helpers.h"

using namespace vi_ekf_slam;

TEST(FilterState, LayoutFollowsMechanization) {
  // p v b_a psi b_g t_d (16), plus p_n_s psi_n_s (22) in the sensor-centric layouts.
  EXPECT_EQ(FilterState(Mechanization::kWorldCentric).dim(), 16);
  EXPECT_EQ(FilterState(Mechanization::kSensorCentric).dim(), 22);
  EXPECT_EQ(FilterState(Mechanization::kSensorCentricComposition).dim(), 22);
  std::mt19937_64 rng(22);
  const FilterState s = test::randomState(Mechanization::kSensorCentric, 4, rng);
  EXPECT_EQ(s.dim(), 22 + 12);
  EXPECT_EQ(s.landmarkIndex(2), 28);
}

TEST(FilterState, RemovingLandmarksDeletesTheirRowsAndColumnsOnly) {
  std::mt19937_64 rng(23);
  FilterState s = test::randomState(Mechanization::kWorldCentric, 5, rng);
  const Eigen::MatrixXd P0 = s.covariance();
  const auto ids0 = s.landmarkIds();
  s.removeLandmarks({3, 1});
  ASSERT_EQ(s.numLandmarks(), 3);
  EXPECT_EQ(s.landmarkIds(), (std::vector<std::int64_t>{ids0[0], ids0[2], ids0[4]}));
  std::vector<int> keep;
  for (int r = 0; r < idx::kWorldCentricDim; ++r) keep.push_back(r);
  for (int i : {0, 2, 4})
    for (int r = 0; r < 3; ++r) keep.push_back(idx::kWorldCentricDim + 3 * i + r);
  const Eigen::MatrixXd& P = s.covariance();
  for (size_t i = 0; i < keep.size(); ++i)
    for (size_t j = 0; j < keep.size(); ++j) ASSERT_EQ(P(i, j), P0(keep[i], keep[j]));
  EXPECT_EQ(*s.findLandmark(ids0[4]), 2);
  EXPECT_FALSE(s.findLandmark(ids0[1]).has_value());
}

TEST(FilterState, BoxplusBoxminusRoundTrip) {
  std::mt19937_64 rng(24);
  const FilterState s0 = test::randomState(Mechanization::kSensorCentric, 3, rng);
  Eigen::VectorXd d = Eigen::VectorXd::Random(s0.dim()) * 0.3;
  FilterState s = s0;
  s.boxplus(d);
  EXPECT_LT((s.boxminus(s0) - d).norm(), 1e-12);
}

TEST(FilterState, AppendLandmarkKeepsSymmetryAndRejectsDuplicates) {
  std::mt19937_64 rng(25);
  FilterState s = test::randomState(Mechanization::kWorldCentric, 1, rng);
  EXPECT_THROW(
      s.appendLandmark(100, Landmark::cartesian(Vec3::Zero()), Mat3::Identity(), Eigen::MatrixXd::Zero(3, s.dim())),
      std::invalid_argument);
  const Eigen::MatrixXd cross = Eigen::MatrixXd::Random(3, s.dim()) * 1e-3;
  s.appendLandmark(7, Landmark::cartesian(Vec3(1, 2, 3)), Mat3::Identity(), cross);
  const Eigen::MatrixXd& P = s.covariance();
  EXPECT_EQ(test::maxAbs(P - P.transpose()), 0.0);
  EXPECT_EQ(test::maxAbs(P.block(s.dim() - 3, 0, 3, s.dim() - 3) - cross), 0.0);
}
