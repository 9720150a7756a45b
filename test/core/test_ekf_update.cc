#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "test_helpers.h"
#include "vi_ekf_slam/core/ekf_update.h"

using namespace vi_ekf_slam;

namespace {
std::vector<FeatureObservation> perfectObservations(const FilterState& s, const CameraModel& cam,
                                                    const CameraExtrinsics& T) {
  std::vector<FeatureObservation> obs;
  for (int i = 0; i < s.numLandmarks(); ++i) {
    Eigen::Vector2d uv;
    if (predictObservation(s.x, s.landmark(i), cam, T, &uv)) obs.push_back({s.landmarkIds()[i], uv});
  }
  return obs;
}
}  // namespace

TEST(EkfUpdate, ReducesUncertaintyAlongObservedDirectionsOnly) {
  std::mt19937_64 rng(8);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s = test::randomState(Mechanization::kWorldCentric, 5, rng);
  const Eigen::MatrixXd P0 = s.covariance();
  // Observe only landmark 0 (id 100).
  Eigen::Vector2d uv;
  ObservationJacobians J;
  ASSERT_TRUE(predictObservation(s.x, s.landmark(0), cam, T, &uv, &J));
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, s.dim());
  H.middleCols<3>(idx::kP) = J.H_p;
  H.middleCols<3>(idx::kPsi) = J.H_psi;
  H.middleCols<3>(s.landmarkIndex(0)) = J.H_l;
  Eigen::Vector2d H_td;  // the time offset's column: the predicted image velocity (omega = 0)
  ASSERT_TRUE(predictImageVelocity(s.x, s.landmark(0), cam, T, Vec3::Zero(), &H_td));
  H.col(idx::kTd) = H_td;
  const UpdateResult r = ekfUpdate(s, {{100, uv}}, cam, T, UpdateParams());
  ASSERT_EQ(r.accepted, 1);
  const Eigen::MatrixXd& P1 = s.covariance();
  // Uncertainty of the observed quantity shrinks ...
  EXPECT_LT((H * P1 * H.transpose()).trace(), 0.9 * (H * P0 * H.transpose()).trace());
  // ... P never grows in any direction (P0 - P1 is PSD), and it stays symmetric.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(P0 - P1);
  EXPECT_GT(es.eigenvalues().minCoeff(), -1e-12);
  EXPECT_LT(test::maxAbs(P1 - P1.transpose()), 1e-15);
  // Directions H cannot see keep their variance: any u with H u = 0 and u orthogonal to the
  // range of P0 H^T is unchanged. Check via the exact Kalman form P0 - P0 H^T S^-1 H P0.
  const Eigen::MatrixXd S = H * P0 * H.transpose() + Eigen::Matrix2d::Identity();
  const Eigen::MatrixXd Pk = P0 - P0 * H.transpose() * S.inverse() * H * P0;
  EXPECT_LT(test::maxAbs(P1 - Pk), 1e-12);
}

TEST(EkfUpdate, PerfectObservationsLeaveTheStateUnchanged) {
  std::mt19937_64 rng(9);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s = test::randomState(Mechanization::kSensorCentric, 8, rng);
  const FilterState s0 = s;
  const UpdateResult r = ekfUpdate(s, perfectObservations(s, cam, T), cam, T, UpdateParams());
  EXPECT_EQ(r.accepted, 8);
  EXPECT_LT(s.boxminus(s0).norm(), 1e-12);
}

TEST(EkfUpdate, GateRejectsGrossOutlierAndReportsIt) {
  std::mt19937_64 rng(10);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s = test::randomState(Mechanization::kWorldCentric, 6, rng);
  s.setCovariance(Eigen::MatrixXd::Identity(s.dim(), s.dim()) * 1e-4);  // confident filter
  auto obs = perfectObservations(s, cam, T);
  ASSERT_EQ(obs.size(), 6u);
  obs[2].uv += Eigen::Vector2d(60.0, -45.0);      // a mismatched track
  obs.push_back({999, Eigen::Vector2d(10, 10)});  // not in the map
  const FilterState s0 = s;
  const UpdateResult r = ekfUpdate(s, obs, cam, T, UpdateParams());
  EXPECT_EQ(r.accepted, 5);
  ASSERT_EQ(r.rejected_ids.size(), 1u);
  EXPECT_EQ(r.rejected_ids[0], obs[2].id);
  ASSERT_EQ(r.invalid_ids.size(), 1u);
  EXPECT_EQ(r.invalid_ids[0], 999);
  EXPECT_LT(s.boxminus(s0).norm(), 1e-10);  // the outlier did not move the state
}

TEST(EkfUpdate, GateProbabilityIsConfigurable) {
  std::mt19937_64 rng(11);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s = test::randomState(Mechanization::kWorldCentric, 1, rng);
  s.setCovariance(Eigen::MatrixXd::Identity(s.dim(), s.dim()) * 1e-8);
  auto obs = perfectObservations(s, cam, T);
  obs[0].uv += Eigen::Vector2d(2.8, 0.0);  // NIS ~ 7.8: outside the 95% gate, inside 99%
  UpdateParams p;
  FilterState a = s;
  EXPECT_EQ(ekfUpdate(a, obs, cam, T, p).rejected_ids.size(), 1u);
  p.gate_probability = 0.99;
  FilterState b = s;
  EXPECT_EQ(ekfUpdate(b, obs, cam, T, p).accepted, 1);
}
