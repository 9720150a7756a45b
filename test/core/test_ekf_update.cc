#include <gtest/gtest.h>

#include <cstdio>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <iostream>

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
  EXPECT_EQ(r.outliers, 1);                 // beyond the clean gate too: the tracks show an outlier
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
  const UpdateResult r = ekfUpdate(a, obs, cam, T, p);
  EXPECT_EQ(r.rejected_ids.size(), 1u);
  EXPECT_EQ(r.outliers, 0);  // a tail of the noise: inside the clean gate (99.99%)
  p.gate_probability = 0.99;
  FilterState b = s;
  EXPECT_EQ(ekfUpdate(b, obs, cam, T, p).accepted, 1);
}

namespace {
/// A state drawn from s0's mean and covariance.
FilterState drawFromPrior(const FilterState& s0, std::mt19937_64& rng) {
  const Eigen::MatrixXd L = s0.covariance().llt().matrixL();
  std::normal_distribution<double> n01;
  Eigen::VectorXd e(s0.dim());
  for (int i = 0; i < e.size(); ++i) e(i) = n01(rng);
  FilterState x = s0;
  x.boxplus(L * e);
  return x;
}

/// The iterated update's objective: the prior's and the observations' Mahalanobis terms at
/// x0 [+] d (observations noise-free from a true state). The filter's measurement model: the
/// state stays at the prior's time offset, a change d_td of it moves each prediction along the
/// feature's image velocity (omega 0, as the updates below are called).
double mapCost(const FilterState& s0, const Eigen::VectorXd& d, const std::vector<FeatureObservation>& obs,
               const CameraModel& cam, const CameraExtrinsics& T, double pixel_var) {
  FilterState x = s0;
  x.boxplus(d);
  double cost = d.dot(s0.covariance().ldlt().solve(d));
  for (const auto& o : obs) {
    Eigen::Vector2d uv, uv_dot;
    const Landmark& l = x.landmark(*x.findLandmark(o.id));
    EXPECT_TRUE(predictObservation(x.x, l, cam, T, &uv));
    EXPECT_TRUE(predictImageVelocity(x.x, l, cam, T, Vec3::Zero(), &uv_dot));
    cost += (o.uv - uv - uv_dot * d(idx::kTd)).squaredNorm() / pixel_var;
  }
  return cost;
}
}  // namespace

// The iterated update minimizes the prior + observation cost (Gauss-Newton), where one EKF step
// stops at the first linearization: from a wide prior (landmark depths and pose poorly known), its
// result has a lower cost than the single step, and no step along the cost's descent direction
// (central differences) lowers it further. One iteration is the EKF itself.
TEST(EkfUpdate, IteratedUpdateReachesTheMinimumOfThePriorAndObservationCost) {
  std::mt19937_64 rng(12);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s0 = test::randomState(Mechanization::kWorldCentric, 4, rng);
  Eigen::MatrixXd P0 = 9.0 * s0.covariance();  // sigmas 3x those of randomState
  // The time offset known: its first-order model has no curvature for Gauss-Newton to find (it
  // has its own test below).
  P0.row(idx::kTd).setZero();
  P0.col(idx::kTd).setZero();
  P0(idx::kTd, idx::kTd) = 1e-14;
  s0.setCovariance(P0);
  // The truth: a draw from the prior; noise-free observations of it.
  const auto obs = perfectObservations(drawFromPrior(s0, rng), cam, T);
  ASSERT_EQ(obs.size(), 4u);
  UpdateParams p;
  p.gate_probability = 1.0 - 1e-9;
  const double var = p.pixel_noise_px * p.pixel_noise_px;

  FilterState ekf = s0, iekf = s0;
  ASSERT_EQ(ekfUpdate(ekf, obs, cam, T, p).accepted, 4);
  p.iterations = 20;
  ASSERT_EQ(ekfUpdate(iekf, obs, cam, T, p).accepted, 4);
  const Eigen::VectorXd d_ekf = ekf.boxminus(s0), d_iekf = iekf.boxminus(s0);
  const double c_ekf = mapCost(s0, d_ekf, obs, cam, T, var), c_iekf = mapCost(s0, d_iekf, obs, cam, T, var);
  EXPECT_LT(c_iekf, c_ekf);
  // Stationary: the numerical gradient of the cost at the iterated solution is ~0 relative to
  // the one at the EKF's solution.
  auto gradient = [&](const Eigen::VectorXd& d) {
    Eigen::VectorXd g(d.size());
    for (int i = 0; i < d.size(); ++i) {
      Eigen::VectorXd h = Eigen::VectorXd::Zero(d.size());
      h(i) = 1e-6;
      g(i) = (mapCost(s0, d + h, obs, cam, T, var) - mapCost(s0, d - h, obs, cam, T, var)) / 2e-6;
    }
    return g;
  };
  const double g_ekf = gradient(d_ekf).norm(), g_iekf = gradient(d_iekf).norm();
  EXPECT_GT(g_ekf, 1.0);
  EXPECT_LT(g_iekf, 1e-3 * g_ekf);
  // Invariants of the update hold for the iterated one too.
  const Eigen::MatrixXd& P1 = iekf.covariance();
  EXPECT_LT(test::maxAbs(P1 - P1.transpose()), 1e-15);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(s0.covariance() - P1);
  EXPECT_GT(es.eigenvalues().minCoeff(), -1e-9);
}

// Step control: far from the truth, plain Gauss-Newton can overshoot (the iterations diverged on
// some simulated walks); the iterated update keeps an iterate only while the cost decreases, so
// its result never costs more than the single EKF step, whatever the prior's width.
TEST(EkfUpdate, IteratedUpdateNeverEndsAboveTheSingleStepsCost) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  int tried = 0, improved = 0;
  for (int seed = 0; seed < 100; ++seed) {
    std::mt19937_64 rng(100 + seed);
    FilterState s0 = test::randomState(Mechanization::kWorldCentric, 6, rng);
    s0.setCovariance((seed % 2 ? 25.0 : 100.0) * s0.covariance());
    const auto obs = perfectObservations(drawFromPrior(s0, rng), cam, T);
    if (obs.size() < 3) continue;
    UpdateParams p;
    p.gate_probability = 1.0 - 1e-12;
    FilterState ekf = s0, iekf = s0;
    const int n_ekf = ekfUpdate(ekf, obs, cam, T, p).accepted;
    p.iterations = 5;
    const int n_iekf = ekfUpdate(iekf, obs, cam, T, p).accepted;
    ASSERT_EQ(n_ekf, n_iekf);
    if (n_ekf != static_cast<int>(obs.size())) continue;
    bool predictable = true;
    for (const auto& o : obs) {
      Eigen::Vector2d uv;
      predictable = predictable && predictObservation(ekf.x, ekf.landmark(*ekf.findLandmark(o.id)), cam, T, &uv) &&
                    predictObservation(iekf.x, iekf.landmark(*iekf.findLandmark(o.id)), cam, T, &uv);
    }
    if (!predictable) continue;
    ++tried;
    const double var = p.pixel_noise_px * p.pixel_noise_px;
    const double c_ekf = mapCost(s0, ekf.boxminus(s0), obs, cam, T, var);
    const double c_iekf = mapCost(s0, iekf.boxminus(s0), obs, cam, T, var);
    EXPECT_LE(c_iekf, c_ekf * (1.0 + 1e-9) + 1e-9) << "seed " << seed;
    improved += c_iekf < 0.99 * c_ekf;
  }
  std::printf("%d updates compared, %d lowered by the iterations\n", tried, improved);
  EXPECT_GE(tried, 10);
  EXPECT_GE(improved, 3);  // the iterations do run (and help) where they can
}

// The time offset in the iterated update: the state stays propagated to the prior's offset, so
// every iterate's prediction must include its own offset change through the image velocity. A
// state whose pose and landmarks are uncertain and whose time offset is off, seen by a moving
// camera: the iterations end at no higher cost than the single step and no farther from the
// offset (with its effect added once more at every iteration they ended at 60x the cost).
TEST(EkfUpdate, IteratedUpdateCountsTheTimeOffsetOnce) {
  std::mt19937_64 rng(41);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s0 = test::randomState(Mechanization::kWorldCentric, 10, rng);
  s0.x.v_s_b = Vec3(1.5, -0.5, 0.3);  // [m/s]: the features move in the image
  Eigen::MatrixXd P0 = s0.covariance();
  P0.row(idx::kTd).setZero();
  P0.col(idx::kTd).setZero();
  P0(idx::kTd, idx::kTd) = 0.02 * 0.02;  // [s^2]
  s0.setCovariance(P0);
  const double true_offset_change = 0.015;  // [s]
  std::vector<FeatureObservation> obs;
  for (int i = 0; i < s0.numLandmarks(); ++i) {
    Eigen::Vector2d uv, uv_dot;
    if (!predictObservation(s0.x, s0.landmark(i), cam, T, &uv) ||
        !predictImageVelocity(s0.x, s0.landmark(i), cam, T, Vec3::Zero(), &uv_dot)) {
      continue;
    }
    obs.push_back({s0.landmarkIds()[i], uv + uv_dot * true_offset_change});
  }
  ASSERT_GE(obs.size(), 4u);
  UpdateParams p;
  p.pixel_noise_px = 0.1;
  p.gate_probability = 1.0 - 1e-12;
  FilterState ekf = s0, iekf = s0;
  ASSERT_EQ(ekfUpdate(ekf, obs, cam, T, p).accepted, static_cast<int>(obs.size()));
  p.iterations = 10;
  ASSERT_EQ(ekfUpdate(iekf, obs, cam, T, p).accepted, static_cast<int>(obs.size()));
  const double td0 = s0.x.t_d;
  std::printf("time offset change: single step %.5f s, iterated %.5f s (true %.5f s)\n", ekf.x.t_d - td0,
              iekf.x.t_d - td0, true_offset_change);
  EXPECT_LE(std::abs(iekf.x.t_d - td0 - true_offset_change), std::abs(ekf.x.t_d - td0 - true_offset_change) + 1e-5);
  EXPECT_LE(mapCost(s0, iekf.boxminus(s0), obs, cam, T, p.pixel_noise_px * p.pixel_noise_px),
            mapCost(s0, ekf.boxminus(s0), obs, cam, T, p.pixel_noise_px * p.pixel_noise_px) * (1.0 + 1e-9));
}

TEST(EkfUpdate, RollingShutterRowTimesAreCompensated) {
  // A rolling-shutter image of a moving rig: the row at v is read readout * (v / height - 1/2)
  // after the middle row, when the state is at. Observations made at those times fit the state
  // once the readout time is known, and do not without it.
  std::mt19937_64 rng(31);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s = test::randomState(Mechanization::kWorldCentric, 8, rng);
  s.x.v_s_b = Vec3(4.0, -2.5, 1.5);  // [m/s], attitude constant (omega = 0)
  const double readout = 0.05;       // [s]
  std::vector<FeatureObservation> obs;
  for (int i = 0; i < s.numLandmarks(); ++i) {
    Eigen::Vector2d uv;
    if (!predictObservation(s.x, s.landmark(i), cam, T, &uv)) continue;
    for (int it = 0; it < 5; ++it) {  // the row's time depends on the row it lands in
      MotionState x = s.x;
      x.p_s_b += s.x.v_s_b * readout * (uv.y() / cam.height() - 0.5);
      ASSERT_TRUE(predictObservation(x, s.landmark(i), cam, T, &uv));
    }
    obs.push_back({s.landmarkIds()[i], uv});
  }
  ASSERT_GE(obs.size(), 6u);
  double misfit_px = 0.0;  // what the rolling shutter moves the features by
  for (const auto& o : obs) {
    Eigen::Vector2d uv;
    ASSERT_TRUE(predictObservation(s.x, s.landmark(*s.findLandmark(o.id)), cam, T, &uv));
    misfit_px = std::max(misfit_px, (o.uv - uv).norm());
  }
  EXPECT_GT(misfit_px, 2.0);
  UpdateParams global, rolling;
  global.gate_probability = rolling.gate_probability = 1.0 - 1e-12;  // keep every observation
  rolling.readout_time_s = readout;
  FilterState a = s, b = s;
  const UpdateResult ra = ekfUpdate(a, obs, cam, T, global);
  const UpdateResult rb = ekfUpdate(b, obs, cam, T, rolling);
  ASSERT_EQ(ra.accepted, static_cast<int>(obs.size()));
  ASSERT_EQ(rb.accepted, static_cast<int>(obs.size()));
  // Left: first-order model, so a second-order remainder; it is far below the uncompensated misfit.
  std::cout << "rolling shutter misfit " << misfit_px << " px, NIS " << ra.nis_sum << " -> " << rb.nis_sum << "\n";
  EXPECT_LT(rb.nis_sum, 1e-3 * ra.nis_sum);
  EXPECT_LT(b.boxminus(s).norm(), 1e-2 * a.boxminus(s).norm());
}

TEST(EkfUpdate, AnObservedConsiderLandmarkCorrectsThePoseAndStaysAsItWas) {
  // A dormant point seen again (map.dormant_consider): the update moves the pose by it, iterated
  // or not, but neither its mean nor its own covariance.
  std::mt19937_64 rng(21);
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  for (int iterations : {1, 3}) {
    FilterState s = test::randomState(Mechanization::kSensorCentricComposition, 4, rng);
    s.landmark(0).consider = true;
    std::vector<FeatureObservation> obs = perfectObservations(s, cam, T);
    ASSERT_EQ(obs.size(), 4u);
    for (auto& o : obs) o.uv += Eigen::Vector2d(1.5, -1.0);  // the pose is off
    const FilterState before = s;
    const std::vector<int> c = s.considerEntries();
    const Eigen::MatrixXd P0 = s.covariance();
    UpdateParams p;
    p.gate_probability = 0.9999;
    p.iterations = iterations;
    ASSERT_EQ(ekfUpdate(s, obs, cam, T, p).accepted, 4);
    EXPECT_EQ(s.landmark(0).l, before.landmark(0).l);
    EXPECT_EQ(s.covariance()(c, c), P0(c, c));
    EXPECT_GT((s.x.p_s_b - before.x.p_s_b).norm() + (s.x.q_s_b.vec() - before.x.q_s_b.vec()).norm(), 1e-6);
    // The others are corrected, and P stays symmetric positive semi-definite.
    EXPECT_NE(s.landmark(1).l, before.landmark(1).l);
    const Eigen::MatrixXd& P1 = s.covariance();
    EXPECT_LT(test::maxAbs(P1 - P1.transpose()), 1e-15);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P1).eigenvalues().minCoeff(), -1e-12);
  }
}
