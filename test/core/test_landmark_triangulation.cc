#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstdio>

#include "test_helpers.h"
#include "vi_ekf_slam/core/delayed_landmarks.h"
#include "vi_ekf_slam/core/frame_change.h"

using namespace vi_ekf_slam;

namespace {
// A sensor-centric state whose camera position was cloned, then moved on (baseline ~0.4 m, a
// turn of ~0.1 rad) and composed, with a random covariance; a point seen from both cameras.
struct TwoViews {
  FilterState state{Mechanization::kSensorCentricComposition};
  CameraClone clone;
  Vec3 point;  ///< in {s}
  Eigen::Vector2d uv_clone, uv_now;
};

TwoViews twoViews(std::mt19937_64& rng, double depth_m = 4.0) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  TwoViews v;
  FilterState& s = v.state;
  s.x.p_s_b = test::randomVec(rng, 0.2);
  s.x.q_s_b = expQuat(test::randomVec(rng, 0.2));
  s.x.v_s_b = test::randomVec(rng, 1.0);
  s.setCovariance(test::randomSpd(s.dim(), rng, 1e-3));
  v.clone = appendCameraClone(s, kFirstCloneId, T);
  // The point: in front of the clone's camera.
  std::uniform_real_distribution<double> lateral(-0.3, 0.3);
  const Vec3 p_c0(lateral(rng) * depth_m, lateral(rng) * depth_m, depth_m);
  const Vec3 p_s_c0 = s.landmark(0).l;
  v.point = p_s_c0 + v.clone.R_s_c * p_c0;
  EXPECT_TRUE(cam.project(p_c0, &v.uv_clone));
  // Move on: a step of ~0.4 m mostly sideways to the view, a small turn, then compose as the
  // filter does after an update.
  MotionState& x = s.x;
  x.p_s_b += x.q_s_b * (T.R_b_c * Vec3(0.35, 0.05, 0.1)) + test::randomVec(rng, 0.02);
  x.q_s_b = (expQuat(test::randomVec(rng, 0.05)) * x.q_s_b).normalized();
  s.setCovariance(test::randomSpd(s.dim(), rng, 1e-3));
  const Mat3 R_b_s = x.q_s_b.conjugate().toRotationMatrix();
  const Vec3 p_s_b = x.p_s_b;
  v.clone.R_s_c = R_b_s * v.clone.R_s_c;
  v.clone.rotation_cov = 1e-6 * Mat3::Identity();
  compose(s);
  v.point = R_b_s * (v.point - p_s_b);
  EXPECT_TRUE(cam.project(landmarkInCamera(s.x, v.point, T), &v.uv_now));
  return v;
}
}  // namespace

// Noise-free views of a point give it back exactly: its depth, its (u, v) in the current camera,
// and rays that meet (no gap).
TEST(LandmarkTriangulation, NoiseFreeViewsGiveThePointExactly) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  for (int seed = 0; seed < 20; ++seed) {
    std::mt19937_64 rng(700 + seed);
    const TwoViews v = twoViews(rng, 2.0 + seed * 0.4);
    TriangulatedLandmark l;
    ASSERT_TRUE(triangulateLandmark(v.state, v.clone, v.uv_clone, v.uv_now, cam, T, 1.0, 0.1, &l)) << seed;
    EXPECT_LT((l.landmark.position() - v.point).norm(), 1e-6 * v.point.norm()) << seed;
    EXPECT_NEAR(l.depth_m, landmarkInCamera(v.state.x, v.point, T).z(), 1e-6) << seed;
    EXPECT_LT(l.ray_gap_nis, 1e-10) << seed;
    EXPECT_GT(l.P_ll(2, 2), 0.0);
  }
}

// Every column of the landmark's Jacobians against central differences: the inputs perturbed
// (body position and orientation, clone position through the state's boxplus; both pixels; the
// clone's orientation), the point triangulated again and read in the unperturbed anchor, which is
// how the filter defines a landmark's error.
TEST(LandmarkTriangulation, JacobiansMatchNumericalDifferentiation) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  for (int seed = 0; seed < 5; ++seed) {
    std::mt19937_64 rng(710 + seed);
    const TwoViews v = twoViews(rng);
    TriangulatedLandmark l0;
    ASSERT_TRUE(triangulateLandmark(v.state, v.clone, v.uv_clone, v.uv_now, cam, T, 1.0, 0.1, &l0));
    const int c = v.state.landmarkIndex(0);
    auto lAt = [&](const Eigen::VectorXd& e) -> Eigen::VectorXd {
      FilterState s = v.state;
      Eigen::VectorXd dx = Eigen::VectorXd::Zero(s.dim());
      dx.segment<3>(idx::kP) = e.segment<3>(0);
      dx.segment<3>(idx::kPsi) = e.segment<3>(3);
      dx.segment<3>(c) = e.segment<3>(6);
      s.boxplus(dx);
      CameraClone clone = v.clone;
      clone.R_s_c = expSO3(e.segment<3>(13)) * clone.R_s_c;
      TriangulatedLandmark l;
      EXPECT_TRUE(triangulateLandmark(s, clone, v.uv_clone + e.segment<2>(11), v.uv_now + e.segment<2>(9), cam, T, 1.0,
                                      0.1, &l));
      return l0.landmark.paramsOf(l.landmark.position());
    };
    const Eigen::MatrixXd num = test::numericJacobian(lAt, 16);
    Eigen::Matrix<double, 3, 16> ana;
    ana << l0.J_state, l0.J_noise;
    EXPECT_LT(test::maxAbs(num - ana), 1e-5 * std::max(1.0, test::maxAbs(ana))) << "seed " << seed << "\n"
                                                                                << num << "\n\n"
                                                                                << ana;
  }
}

// The covariance is honest: true states drawn from the filter's covariance (body pose, clone
// position: ~3 mm and ~3 mrad, the relative pose's uncertainty over a wait), noisy pixels (1 px)
// of a fixed point 5 m away seen from them over a 0.4 m baseline, and a clone orientation error
// from rotation_cov; the estimate is triangulated from the mean state. The average NEES of
// (u, v, rho) over 2000 draws is the 3 of a consistent estimate (measured 2.99; the band is
// 4 sigma of its Monte-Carlo error). With 1 cm and 10 mrad it is 3.47: the first-order
// covariance misses the second-order terms there.
TEST(LandmarkTriangulation, CovarianceMatchesMonteCarlo) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  std::mt19937_64 rng(720);
  TwoViews v = twoViews(rng, 5.0);
  v.state.setCovariance(test::randomSpd(v.state.dim(), rng, 1e-5));  // ~3 mm, ~3 mrad
  v.clone.rotation_cov = 1e-6 * Mat3::Identity();
  const Eigen::MatrixXd L = v.state.covariance().llt().matrixL();
  const Eigen::Matrix3d Lr = v.clone.rotation_cov.llt().matrixL();
  std::normal_distribution<double> n01;
  const int draws = 2000;
  double nees = 0.0;
  int counted = 0;
  for (int k = 0; k < draws; ++k) {
    Eigen::VectorXd e(v.state.dim());
    for (int i = 0; i < e.size(); ++i) e(i) = n01(rng);
    FilterState truth = v.state;
    truth.boxplus(L * e);
    const Vec3 dtheta = Lr * Vec3(n01(rng), n01(rng), n01(rng));
    // The true cameras see the point; the clone's true orientation is Exp(dtheta) of the estimate.
    const Vec3 p_s_c0 = truth.landmark(0).l;
    const Mat3 R_s_c0 = expSO3(dtheta) * v.clone.R_s_c;
    Eigen::Vector2d uv0, uv1;
    if (!cam.project(R_s_c0.transpose() * (v.point - p_s_c0), &uv0) ||
        !cam.project(landmarkInCamera(truth.x, v.point, T), &uv1)) {
      continue;
    }
    uv0 += Eigen::Vector2d(n01(rng), n01(rng));
    uv1 += Eigen::Vector2d(n01(rng), n01(rng));
    TriangulatedLandmark l;
    if (!triangulateLandmark(v.state, v.clone, uv0, uv1, cam, T, 1.0, 0.1, &l)) continue;
    // The truth in the estimate's parameterization (its anchor).
    const Vec3 err = l.landmark.paramsOf(v.point) - l.landmark.l;
    nees += err.dot(l.P_ll.ldlt().solve(err));
    ++counted;
  }
  ASSERT_GT(counted, draws * 9 / 10);
  nees /= counted;
  std::printf("average NEES of the triangulated landmark: %.3f over %d draws\n", nees, counted);
  EXPECT_GT(nees, 2.85);  // the mean of 2000 chi^2(3) has a std-dev of 0.055
  EXPECT_LT(nees, 3.15);
}

// The landmark enters with its cross-covariance with the state: the joint covariance stays
// positive semi-definite, and the cross terms are J_state times the rows it depends on.
TEST(LandmarkTriangulation, AppendedLandmarkCarriesItsCrossCovariance) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  std::mt19937_64 rng(730);
  TwoViews v = twoViews(rng);
  TriangulatedLandmark l;
  ASSERT_TRUE(triangulateLandmark(v.state, v.clone, v.uv_clone, v.uv_now, cam, T, 1.0, 0.1, &l));
  const Eigen::MatrixXd P0 = v.state.covariance();
  appendTriangulatedLandmark(v.state, 5, v.clone, l);
  const Eigen::MatrixXd& P = v.state.covariance();
  const int n = v.state.landmarkIndex(1), c = v.state.landmarkIndex(0);
  Eigen::MatrixXd expected = l.J_state.leftCols<3>() * P0.middleRows<3>(idx::kP) +
                             l.J_state.middleCols<3>(3) * P0.middleRows<3>(idx::kPsi) +
                             l.J_state.rightCols<3>() * P0.middleRows<3>(c);
  EXPECT_LT(test::maxAbs(P.block(n, 0, 3, n) - expected), 1e-12);
  EXPECT_LT(test::maxAbs(P.block<3, 3>(n, n) - l.P_ll), 1e-12);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(P);
  EXPECT_GT(es.eigenvalues().minCoeff(), -1e-12);
}

// The bookkeeping: a track waits on a clone of the camera taken where it was first seen, enters
// once its depth is known, and the clone leaves the state when no track waits on it. A track whose
// baseline does not come within max_wait_s (a point ahead, near the focus of expansion) is
// forgotten; it would start again on a new clone. A map short of min_map_landmarks takes the
// longest waiting at the prior depth once they waited starved_max_wait_s.
TEST(DelayedLandmarks, TracksWaitForTheirBaselineAndClonesLeaveWhenUnused) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s(Mechanization::kSensorCentricComposition);
  s.setCovariance(1e-8 * Eigen::MatrixXd::Identity(s.dim(), s.dim()));
  TriangulationParams p;
  DelayedLandmarks d;
  // In the first camera; the rig moves forward (camera z), so the two points ahead get no parallax.
  const Vec3 near_point(1.0, 0.5, 3.0), far_point(-0.01, 0.005, 40.0), far_point2(0.01, -0.005, 30.0);
  const double scene_inverse_depth = 1.0 / 3.0;  // a 3 m scene
  auto observe = [&](const Vec3& p_c) {
    Eigen::Vector2d uv;
    EXPECT_TRUE(cam.project(landmarkInCamera(s.x, T.R_b_c * p_c + T.p_b_c, T), &uv));
    return uv;
  };
  auto frame = [&]() {
    return std::vector<FeatureObservation>{{1, observe(near_point)}, {2, observe(far_point)}, {3, observe(far_point2)}};
  };
  // First image: the tracks start waiting on one clone.
  s.timestamp = 0.0;
  auto sel = d.select(s, frame(), cam, T, p, 1.0, 0.99, true, scene_inverse_depth);
  EXPECT_TRUE(sel.triangulated.empty() && sel.expired.empty());
  EXPECT_TRUE(d.commit(s, sel, frame(), 10, T, p).empty());
  EXPECT_EQ(d.clones(), 1);
  EXPECT_EQ(d.waitingTracks(), 3);
  EXPECT_EQ(s.numLandmarks(), 1);  // the clone
  // Move 0.3 m forward: the near point (off the axis) is triangulated, the two ahead wait.
  s.timestamp = 0.3;
  s.x.p_s_b = T.R_b_c * Vec3(0.0, 0.0, 0.3);
  sel = d.select(s, frame(), cam, T, p, 1.0, 0.99, true, scene_inverse_depth);
  ASSERT_EQ(sel.triangulated.size(), 1u);
  EXPECT_EQ(sel.triangulated[0].obs.id, 1);
  EXPECT_NEAR(sel.triangulated[0].landmark.depth_m, 2.7, 0.01);
  EXPECT_EQ(d.commit(s, sel, frame(), 10, T, p), std::vector<std::int64_t>{1});
  ASSERT_TRUE(s.findLandmark(1));
  EXPECT_EQ(d.waitingTracks(), 2);
  // A map short of landmarks (2 wanted, 1 there) takes the longest waiting point ahead at the prior
  // depth: only one, the map is then full enough.
  const std::vector<FeatureObservation> far = {frame()[1], frame()[2]};
  sel = d.select(s, far, cam, T, p, 1.0, 0.99, true, scene_inverse_depth, /*fill=*/1);
  ASSERT_EQ(sel.expired.size(), 1u);
  d.commit(s, sel, far, 10, T, p);
  EXPECT_EQ(d.waitingTracks(), 1);
  // After max_wait_s the other one ahead is forgotten, and its clone goes; it starts again on a new
  // clone (clone_interval_s has passed).
  s.timestamp = 0.1 + p.max_wait_s;
  const std::vector<FeatureObservation> last = {frame()[2]};
  sel = d.select(s, last, cam, T, p, 1.0, 0.99, true, scene_inverse_depth);
  EXPECT_TRUE(sel.triangulated.empty() && sel.expired.empty());
  EXPECT_EQ(d.waitingTracks(), 0);
  d.commit(s, sel, last, 10, T, p);
  EXPECT_EQ(d.clones(), 1);
  EXPECT_EQ(d.waitingTracks(), 1);
  EXPECT_EQ(s.numLandmarks(), 2);  // the near point and the new clone
  EXPECT_FALSE(isCloneId(s.landmarkIds()[0]));
  EXPECT_TRUE(isCloneId(s.landmarkIds()[1]));
  EXPECT_NE(s.landmarkIds()[1], kFirstCloneId);  // not the first clone
}

// Not waiting (the rig not seen moving): new tracks are handed back at once and no clone is taken.
TEST(DelayedLandmarks, NewTracksDoNotWaitWhenTheRigIsNotSeenMoving) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  FilterState s(Mechanization::kSensorCentricComposition);
  TriangulationParams p;
  DelayedLandmarks d;
  const std::vector<FeatureObservation> fresh = {{1, Eigen::Vector2d(300, 200)}, {2, Eigen::Vector2d(100, 150)}};
  const auto sel = d.select(s, fresh, cam, T, p, 1.0, 0.99, false, 0.2);
  EXPECT_EQ(sel.expired.size(), 2u);
  d.commit(s, sel, fresh, 10, T, p);
  EXPECT_EQ(d.clones(), 0);
  EXPECT_EQ(s.numLandmarks(), 0);
}

// A map short of landmarks takes tracks that have waited starved_max_wait_s with the inverse depth
// their two views give where it beats the prior (two-view inverse depth is as well known for a far
// point as for a near one: sigma(rho) ~ pixel noise / (f baseline)), and at the prior depth where
// the baseline is too short for that.
TEST(DelayedLandmarks, AShortMapTakesTheTwoViewDepthWhenItBeatsThePrior) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  const Vec3 mid_point(0.3, 0.5, 20.0), far_point(-0.4, 0.2, 400.0);  // in the first camera
  for (const double baseline_m : {0.1, 0.002}) {
    FilterState s(Mechanization::kSensorCentricComposition);
    s.setCovariance(1e-8 * Eigen::MatrixXd::Identity(s.dim(), s.dim()));
    TriangulationParams p;
    DelayedLandmarks d;
    auto frame = [&]() {
      std::vector<FeatureObservation> f;
      for (const auto& [id, p_c] : {std::pair{1, mid_point}, std::pair{2, far_point}}) {
        Eigen::Vector2d uv;
        EXPECT_TRUE(cam.project(landmarkInCamera(s.x, T.R_b_c * p_c + T.p_b_c, T), &uv));
        f.push_back({id, uv});
      }
      return f;
    };
    const double scene_inverse_depth = 1.0 / 20.0;  // a 20 m scene
    s.timestamp = 0.0;
    auto sel = d.select(s, frame(), cam, T, p, 1.0, 0.99, true, scene_inverse_depth);
    d.commit(s, sel, frame(), 10, T, p);
    // The rig moved sideways by the baseline in 0.4 s: neither point is known to 30% of the scene's
    // inverse depth.
    s.timestamp = 0.4;
    s.x.p_s_b = T.R_b_c * Vec3(baseline_m, 0.0, 0.0);
    sel = d.select(s, frame(), cam, T, p, 1.0, 0.99, true, scene_inverse_depth, /*fill=*/2,
                   /*prior_inverse_depth_sigma=*/0.5);
    if (baseline_m > 0.01) {
      ASSERT_EQ(sel.triangulated.size(), 2u);
      EXPECT_TRUE(sel.expired.empty());
      for (const auto& r : sel.triangulated) {
        const double rho_true = 1.0 / (r.obs.id == 1 ? mid_point.z() : far_point.z());
        EXPECT_NEAR(r.landmark.landmark.l.z(), rho_true, 1e-6) << r.obs.id;  // noise-free views
        EXPECT_GT(std::sqrt(r.landmark.P_ll(2, 2)), p.max_relative_depth_sigma * scene_inverse_depth) << r.obs.id;
        EXPECT_LT(std::sqrt(r.landmark.P_ll(2, 2)), 0.5) << r.obs.id;
      }
    } else {
      EXPECT_TRUE(sel.triangulated.empty());
      EXPECT_EQ(sel.expired.size(), 2u);  // at the prior depth
    }
  }
}

// A waiting track is tried at every image until it enters. Gated on its own estimate (sigma(rho) /
// rho), it would enter at the first image whose pixel noise puts it near, and the map's inverse
// depths would be biased high: on a slow simulated start, points entered at half their distance
// and the velocity followed them (docs/evaluation.md). Gated on sigma(rho) against the scene's inverse
// depth, the entered inverse depths are nearly unbiased. 400 points 4-16 m ahead, a rig walking
// forward at 0.5 m/s with exact poses, 1 px noise on every view: the mean of (rho - rho_true) /
// sigma(rho) over the entered points is 0.19 (260 entered; a gate on the track's own sigma(rho) /
// rho gives 1.08 over 302). What remains: sigma(rho) is computed along the noisy rays, so the
// draw still moves it a little (a ray pushed away from the focus of expansion has both a smaller
// sigma and a larger rho).
TEST(DelayedLandmarks, EnteredInverseDepthsAreNotSelectedByTheirNoise) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  std::mt19937_64 rng(750);
  std::normal_distribution<double> pixel_noise(0.0, 1.0);
  std::uniform_real_distribution<double> depth(4.0, 16.0), lateral(-0.4, 0.4);
  const TriangulationParams p;
  const double scene_inverse_depth = 1.0 / 8.0;
  std::vector<double> z;
  for (int trial = 0; trial < 8; ++trial) {
    FilterState s(Mechanization::kSensorCentricComposition);
    s.setCovariance(1e-10 * Eigen::MatrixXd::Identity(s.dim(), s.dim()));
    DelayedLandmarks d;
    std::vector<Vec3> points;  // in {s}, the body frame at the first image
    for (int i = 0; i < 50; ++i) {
      const double dz = depth(rng);
      points.push_back(T.R_b_c * Vec3(lateral(rng) * dz, 0.5 * lateral(rng) * dz, dz) + T.p_b_c);
    }
    for (int k = 0; k < 40; ++k) {
      s.timestamp = 0.05 * k;
      s.x.p_s_b = T.R_b_c * Vec3(0.0, 0.0, 0.025 * k);
      std::vector<FeatureObservation> fresh;
      for (size_t i = 0; i < points.size(); ++i) {
        Eigen::Vector2d uv;
        const auto id = static_cast<std::int64_t>(i);
        if (s.findLandmark(id) || !cam.project(landmarkInCamera(s.x, points[i], T), &uv)) continue;
        fresh.push_back({id, uv + Eigen::Vector2d(pixel_noise(rng), pixel_noise(rng))});
      }
      const auto sel = d.select(s, fresh, cam, T, p, 1.0, 0.99, true, scene_inverse_depth);
      for (const auto& r : sel.triangulated) {
        const double rho_true = r.landmark.landmark.paramsOf(points[static_cast<size_t>(r.obs.id)]).z();
        z.push_back((r.landmark.landmark.l.z() - rho_true) / std::sqrt(r.landmark.P_ll(2, 2)));
      }
      d.commit(s, sel, fresh, 1000, T, p);
    }
  }
  ASSERT_GT(z.size(), 250u);
  double mean = 0.0, var = 0.0;
  for (double v : z) mean += v / static_cast<double>(z.size());
  for (double v : z) var += (v - mean) * (v - mean) / static_cast<double>(z.size() - 1);
  std::printf("%zu entered: mean (rho - rho_true) / sigma %.3f, variance %.3f\n", z.size(), mean, var);
  EXPECT_LT(std::abs(mean), 0.4);  // the standard error of the mean is 0.06
  EXPECT_LT(var, 1.5);             // and their sigma is honest (0.82)
}

// rho ~ 1 / baseline is far from linear where the baseline is poorly known: a track waits until
// the baseline that makes its depth is known to max_relative_depth_sigma of itself, even if its
// sigma(rho) already passes the scene's gate (a point far beyond a near scene). A 10 m point in a
// 2 m scene, 0.2 m sideways: with the baseline known to 0.1 m it waits, to 0.02 m it enters.
TEST(DelayedLandmarks, ATrackWaitsWhileTheBaselineThatMakesItsDepthIsUncertain) {
  const CameraModel cam = test::paperCamera();
  const CameraExtrinsics T = test::forwardCamera();
  const Vec3 point(1.0, 0.5, 10.0);  // in the first camera
  const double scene_inverse_depth = 0.5;
  for (const double baseline_sigma_m : {0.1, 0.02}) {
    FilterState s(Mechanization::kSensorCentricComposition);
    s.setCovariance(1e-8 * Eigen::MatrixXd::Identity(s.dim(), s.dim()));
    TriangulationParams p;
    DelayedLandmarks d;
    auto frame = [&]() {
      Eigen::Vector2d uv;
      EXPECT_TRUE(cam.project(landmarkInCamera(s.x, T.R_b_c * point + T.p_b_c, T), &uv));
      return std::vector<FeatureObservation>{{1, uv}};
    };
    s.timestamp = 0.0;
    auto sel = d.select(s, frame(), cam, T, p, 1.0, 0.99, true, scene_inverse_depth);
    d.commit(s, sel, frame(), 10, T, p);
    ASSERT_EQ(d.clones(), 1);
    // Moved 0.2 m sideways; the position's uncertainty grew by baseline_sigma_m since the clone.
    s.timestamp = 0.4;
    s.x.p_s_b = T.R_b_c * Vec3(0.2, 0.0, 0.0);
    Eigen::MatrixXd P = s.covariance();
    P.block<3, 3>(idx::kP, idx::kP) += baseline_sigma_m * baseline_sigma_m * Mat3::Identity();
    s.setCovariance(P);
    // The triangulation itself: sigma(rho) passes the scene's gate either way.
    CameraClone clone;
    clone.id = s.landmarkIds()[0];
    clone.R_s_c = T.R_b_c;
    clone.R_b_c = T.R_b_c;
    TriangulatedLandmark l;
    Eigen::Vector2d uv0;
    ASSERT_TRUE(cam.project(point, &uv0));
    ASSERT_TRUE(triangulateLandmark(s, clone, uv0, frame()[0].uv, cam, T, 1.0, p.min_depth_m, &l));
    EXPECT_LT(std::sqrt(l.P_ll(2, 2)), p.max_relative_depth_sigma * scene_inverse_depth);
    EXPECT_NEAR(l.baseline_relative_sigma, baseline_sigma_m / 0.2, 0.25 * baseline_sigma_m / 0.2);
    sel = d.select(s, frame(), cam, T, p, 1.0, 0.99, true, scene_inverse_depth);
    EXPECT_EQ(sel.triangulated.size(), baseline_sigma_m > 0.05 ? 0u : 1u) << baseline_sigma_m;
  }
}
