// The camera-IMU extrinsic in the state (estimate_extrinsic): every Jacobian that involves it
// against numerical differentiation through the state's boxplus, as the rest of the filter's.
#include <gtest/gtest.h>

#include <iostream>

#include "test_helpers.h"
#include "vi_ekf_slam/core/ekf_update.h"
#include "vi_ekf_slam/core/frame_change.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/landmark_initialization.h"
#include "vi_ekf_slam/core/landmark_triangulation.h"
#include "vi_ekf_slam/core/measurement_model.h"

using namespace vi_ekf_slam;

namespace {

const Mechanization kAll[] = {Mechanization::kWorldCentric, Mechanization::kSensorCentric,
                              Mechanization::kSensorCentricComposition};

}  // namespace

TEST(ExtrinsicCalibration, TheLayoutCarriesSixMoreEntriesAfterTheMechanizations) {
  for (Mechanization m : kAll) {
    const FilterState s(m, true);
    EXPECT_EQ(s.motionDim(), motionDim(m) + 6);
    EXPECT_EQ(s.extrinsicIndex(), motionDim(m));
  }
  std::mt19937_64 rng(3);
  const FilterState s0 = test::randomState(Mechanization::kSensorCentric, 2, rng, true);
  Eigen::VectorXd d = Eigen::VectorXd::Zero(s0.dim());
  d.segment<3>(s0.extrinsicIndex()) = Vec3(0.01, -0.02, 0.03);
  d.segment<3>(s0.extrinsicIndex() + 3) = Vec3(-0.02, 0.01, 0.04);
  FilterState s = s0;
  s.boxplus(d);
  EXPECT_LT((s.boxminus(s0) - d).norm(), 1e-12);
  EXPECT_LT((s.x.T_b_c.p_b_c - s0.x.T_b_c.p_b_c - Vec3(0.01, -0.02, 0.03)).norm(), 1e-15);
}

// H_pbc, H_thc with the rest of the observation's Jacobian, for Cartesian and inverse-depth points.
TEST(ExtrinsicCalibration, ObservationJacobianMatchesNumeric) {
  std::mt19937_64 rng(71);
  const CameraModel cam = test::paperCamera();
  for (Mechanization m : kAll) {
    const FilterState s0 = test::randomState(m, 4, rng, true);
    const int e = s0.extrinsicIndex();
    for (int i = 0; i < s0.numLandmarks(); ++i) {
      Eigen::Vector2d uv;
      ObservationJacobians J;
      ASSERT_TRUE(predictObservation(s0.x, s0.landmark(i), cam, s0.x.T_b_c, &uv, &J));
      Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, s0.dim());
      H.middleCols<3>(idx::kP) = J.H_p;
      H.middleCols<3>(idx::kPsi) = J.H_psi;
      H.middleCols<3>(e) = J.H_pbc;
      H.middleCols<3>(e + 3) = J.H_thc;
      H.middleCols<3>(s0.landmarkIndex(i)) = J.H_l;
      const Eigen::MatrixXd Hn = test::numericJacobian(
          [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
            FilterState s = s0;
            s.boxplus(d);
            Eigen::Vector2d u;
            predictObservation(s.x, s.landmark(i), cam, s.x.T_b_c, &u);
            return u;
          },
          s0.dim());
      EXPECT_LT(test::maxAbs(Hn - H), 1e-5 * test::maxAbs(H)) << toString(m) << "\n" << Hn - H;
    }
  }
}

// A back-projected point moves with the camera the extrinsic places: G_pbc, G_thc.
TEST(ExtrinsicCalibration, BackProjectionJacobianMatchesNumeric) {
  std::mt19937_64 rng(72);
  const CameraModel cam = test::paperCamera();
  const FilterState s0 = test::randomState(Mechanization::kSensorCentric, 0, rng, true);
  const Eigen::Vector2d uv(210.0, 330.0);
  InitializedLandmark l;
  ASSERT_TRUE(backProject(s0.x, uv, 4.0, cam, s0.x.T_b_c, &l));
  const int e = s0.extrinsicIndex();
  const Eigen::MatrixXd Gn = test::numericJacobian(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        FilterState s = s0;
        s.boxplus(d);
        InitializedLandmark o;
        backProject(s.x, uv, 4.0, cam, s.x.T_b_c, &o);
        return o.p_s_l;
      },
      s0.dim());
  EXPECT_LT(test::maxAbs(Gn.middleCols<3>(e) - l.G_pbc), 1e-7);
  EXPECT_LT(test::maxAbs(Gn.middleCols<3>(e + 3) - l.G_thc), 1e-6);
  EXPECT_LT(test::maxAbs(Gn.middleCols<3>(idx::kPsi) - l.G_psi), 1e-6);
}

// The depth of a landmark along the camera's axis (the map-depth prior of new points).
TEST(ExtrinsicCalibration, InverseDepthInCameraJacobianMatchesNumeric) {
  std::mt19937_64 rng(73);
  for (Mechanization m : kAll) {
    const FilterState s0 = test::randomState(m, 4, rng, true);
    for (int i = 0; i < s0.numLandmarks(); ++i) {
      Eigen::RowVectorXd J;
      inverseDepthInCamera(s0, i, s0.x.T_b_c, &J);
      const Eigen::MatrixXd Jn = test::numericJacobian(
          [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
            FilterState s = s0;
            s.boxplus(d);
            return Eigen::VectorXd::Constant(1, inverseDepthInCamera(s, i, s.x.T_b_c));
          },
          s0.dim());
      EXPECT_LT(test::maxAbs(Jn - Eigen::MatrixXd(J)), 1e-6 * std::max(1.0, test::maxAbs(Eigen::MatrixXd(J))))
          << toString(m) << "\n"
          << Jn - Eigen::MatrixXd(J);
    }
  }
}

// The cross-covariance a new landmark gets with the extrinsic is the first-order one: appending a
// back-projected point to a state equals propagating the state's covariance through the full
// numerical Jacobian of the new entries.
TEST(ExtrinsicCalibration, ANewLandmarksCovarianceWithTheExtrinsicIsFirstOrder) {
  std::mt19937_64 rng(74);
  const CameraModel cam = test::paperCamera();
  for (const bool inverse_depth : {false, true}) {
    const FilterState s0 = test::randomState(Mechanization::kSensorCentric, 2, rng, true);
    const FeatureObservation obs{900, Eigen::Vector2d(300.0, 250.0)};
    FilterState s = s0;
    InverseDepthParams ip;
    ip.pixel_noise_px = 0.0;  // the state's part alone
    ip.inverse_depth_sigma = 0.0;
    FixedDepthParams fp;
    fp.pixel_noise_px = 0.0;
    fp.depth_sigma_m = 0.0;
    ASSERT_TRUE(inverse_depth ? initializeLandmarkInverseDepth(s, obs, cam, s.x.T_b_c, ip)
                              : initializeLandmarkFixedDepth(s, obs, cam, s.x.T_b_c, fp));
    const int k = s.landmarkIndex(s.numLandmarks() - 1);
    const Landmark& lm = s.landmark(s.numLandmarks() - 1);
    // The new entries as a function of the old state: the point re-expressed in lm's
    // parameterization, its anchor riding on the perturbed extrinsic (landmark.h).
    const Eigen::MatrixXd G = test::numericJacobian(
        [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
          FilterState t = s0;
          t.boxplus(d);
          InitializedLandmark o;
          backProject(t.x, obs.uv, inverse_depth ? ip.initial_depth_m : fp.depth_m, cam, t.x.T_b_c, &o);
          return lm.withExtrinsic(s0.x.T_b_c.R_b_c, s0.x.T_b_c.p_b_c, t.x.T_b_c.R_b_c, t.x.T_b_c.p_b_c)
              .paramsOf(o.p_s_l);
        },
        s0.dim());
    const Eigen::MatrixXd& P0 = s0.covariance();
    const Eigen::MatrixXd& P = s.covariance();
    const double scale = test::maxAbs(G * P0 * G.transpose());
    EXPECT_LT(test::maxAbs(P.block(k, 0, 3, s0.dim()) - G * P0), 1e-6 * scale);
    EXPECT_LT(test::maxAbs(P.block<3, 3>(k, k) - G * P0 * G.transpose()), 1e-6 * scale);
  }
}

// Frame changes carry the extrinsic unchanged (it is body-relative): their Jacobians, with the
// identity block, against numerical differentiation.
TEST(ExtrinsicCalibration, FrameChangeJacobiansMatchNumeric) {
  std::mt19937_64 rng(75);
  const FilterState sc = test::randomState(Mechanization::kSensorCentricComposition, 3, rng, true);
  EXPECT_LT(test::maxAbs(test::numericFrameChangeJacobian(sc, [](FilterState& s) { compose(s); }) -
                         denseJacobian(compositionJacobian(sc), sc.numLandmarks())),
            1e-7);
  const FilterState w = test::randomState(Mechanization::kWorldCentric, 3, rng, true);
  EXPECT_LT(test::maxAbs(test::numericFrameChangeJacobian(
                             w, [](FilterState& s) { switchMechanization(s, Mechanization::kSensorCentric); }) -
                         denseJacobian(worldToSensorJacobian(w), w.numLandmarks())),
            1e-7);
  const FilterState s = test::randomState(Mechanization::kSensorCentric, 3, rng, true);
  EXPECT_LT(test::maxAbs(test::numericFrameChangeJacobian(
                             s, [](FilterState& t) { switchMechanization(t, Mechanization::kWorldCentric); }) -
                         denseJacobian(sensorToWorldJacobian(s), s.numLandmarks())),
            1e-7);
  FilterState round = w;
  switchMechanization(round, Mechanization::kSensorCentricComposition);
  EXPECT_TRUE(round.estimatesExtrinsic());
  switchMechanization(round, Mechanization::kWorldCentric);
  EXPECT_LT(round.boxminus(w).norm(), 1e-12);
}

// The IMU step leaves the extrinsic and its covariance alone (a constant), and its transition
// matrix is still the numerical one.
TEST(ExtrinsicCalibration, PropagationKeepsTheExtrinsicConstant) {
  std::mt19937_64 rng(76);
  const FilterState s0 = test::randomState(Mechanization::kSensorCentric, 0, rng, true);
  const Vec3 wm(0.3, -0.2, 0.5), am(0.5, 0.2, 9.5), g = gravityInNav(9.81);
  const MotionMatrix Phi = transitionMatrix(s0.x, s0.mechanization(), wm, am, 0.005, g, true);
  const int e = s0.extrinsicIndex();
  Eigen::MatrixXd expected_rows = Eigen::MatrixXd::Zero(6, Phi.cols());
  expected_rows.rightCols(6).setIdentity();
  EXPECT_EQ(test::maxAbs(Eigen::MatrixXd(Phi.block(e, 0, 6, Phi.cols())) - expected_rows), 0.0);
  FilterState s = s0;
  propagateState(s, wm, am, 0.005, ImuNoiseParams(), g);
  EXPECT_EQ((s.x.T_b_c.p_b_c - s0.x.T_b_c.p_b_c).norm(), 0.0);
  EXPECT_EQ(test::maxAbs(s.covariance().block(e, e, 6, 6) - s0.covariance().block(e, e, 6, 6)), 0.0);
}

// A triangulated point moves with both cameras the extrinsic places: the current one (p_b_c,
// theta) and the clone's orientation (theta, through its body).
TEST(ExtrinsicCalibration, TriangulationJacobianMatchesNumeric) {
  std::mt19937_64 rng(77);
  const CameraModel cam = test::paperCamera();
  FilterState s0 = test::randomState(Mechanization::kSensorCentricComposition, 0, rng, true);
  // The clone: the camera 0.4 m back along the body's x; the point 4 m ahead of both.
  const Vec3 X = s0.x.p_s_b + s0.x.q_s_b * (s0.x.T_b_c.p_b_c + s0.x.T_b_c.R_b_c * Vec3(0.3, -0.2, 4.0));
  const Mat3 R_s_b = s0.x.q_s_b.toRotationMatrix();
  const Vec3 p_clone = s0.x.p_s_b + R_s_b * (Vec3(-0.4, 0.1, 0.0) + s0.x.T_b_c.p_b_c);
  s0.appendLandmark(5, Landmark::cartesian(p_clone), 1e-4 * Mat3::Identity(),
                    1e-3 * Eigen::MatrixXd::Random(3, s0.dim()));
  s0.setCovariance(test::randomSpd(s0.dim(), rng, 0.001));
  CameraClone clone;
  clone.id = 5;
  clone.R_s_c = R_s_b * expSO3(Vec3(0.0, 0.02, 0.01)) * s0.x.T_b_c.R_b_c;
  clone.R_b_c = s0.x.T_b_c.R_b_c;
  Eigen::Vector2d uv_now, uv_clone;
  ASSERT_TRUE(
      cam.project(s0.x.T_b_c.R_b_c.transpose() * (R_s_b.transpose() * (X - s0.x.p_s_b) - s0.x.T_b_c.p_b_c), &uv_now));
  ASSERT_TRUE(cam.project(clone.R_s_c.transpose() * (X - p_clone), &uv_clone));
  TriangulatedLandmark t;
  ASSERT_TRUE(triangulateLandmark(s0, clone, uv_clone, uv_now, cam, s0.x.T_b_c, 1.0, 0.1, &t));
  const Eigen::MatrixXd Jn = test::numericJacobian(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        FilterState s = s0;
        s.boxplus(d);
        TriangulatedLandmark o;  // (the clone's body is fixed, its camera turns with R_b_c)
        triangulateLandmark(s, clone, uv_clone, uv_now, cam, s.x.T_b_c, 1.0, 0.1, &o);
        // in t's parameterization, its anchor riding on the perturbed extrinsic (landmark.h)
        return t.landmark.withExtrinsic(s0.x.T_b_c.R_b_c, s0.x.T_b_c.p_b_c, s.x.T_b_c.R_b_c, s.x.T_b_c.p_b_c)
            .paramsOf(o.landmark.position());
      },
      s0.dim());
  const int e = s0.extrinsicIndex();
  EXPECT_LT(test::maxAbs(Jn.middleCols<6>(e) - t.J_ext), 1e-5 * test::maxAbs(t.J_ext)) << "\n"
                                                                                       << Jn.middleCols<6>(e) - t.J_ext;
  EXPECT_LT(test::maxAbs(Jn.middleCols<3>(idx::kP) - t.J_state.leftCols<3>()), 1e-5 * test::maxAbs(t.J_state));
}

// Seen again from where they were first seen, new landmarks tell nothing about the extrinsic: the
// camera's pose relative to them is known exactly as well as at their initialization, whatever
// the extrinsic is. (Only the landmarks' own pixel noise shrinks.)
TEST(ExtrinsicCalibration, LandmarksSeenAgainFromTheSamePoseAddNoExtrinsicInformation) {
  std::mt19937_64 rng(78);
  const CameraModel cam = test::paperCamera();
  FilterState s = test::randomState(Mechanization::kSensorCentricComposition, 0, rng, true);
  s.x.v_s_b.setZero();  // standing: the time offset's Jacobian (the image velocity) is zero too
  std::vector<FeatureObservation> obs;
  for (int i = 0; i < 30; ++i) {
    const Eigen::Vector2d uv(60.0 + 20.0 * i, 100.0 + 12.0 * (i % 7) * 5.0);
    obs.push_back({1000 + i, uv});
    InverseDepthParams ip;
    ASSERT_TRUE(initializeLandmarkInverseDepth(s, obs.back(), cam, s.x.T_b_c, ip));
  }
  const int e = s.extrinsicIndex();
  const Eigen::MatrixXd before = s.covariance().block(e, e, 6, 6);
  UpdateParams up;
  up.gate_probability = 0.999999;
  ekfUpdate(s, obs, cam, s.x.T_b_c, up);
  const Eigen::MatrixXd after = s.covariance().block(e, e, 6, 6);
  std::cout << "extrinsic std-devs before " << before.diagonal().cwiseSqrt().transpose() << "\n after  "
            << after.diagonal().cwiseSqrt().transpose() << "\n";
  EXPECT_LT(test::maxAbs(after - before), 1e-6 * test::maxAbs(before));
}

// The same after the estimate has moved: a first update with noisy pixels corrects the pose, the
// extrinsic and the points, and a second one from the same place must still tell nothing about the
// extrinsic. With inverse-depth anchors fixed at the camera first estimated, the points' entries
// absorbed the extrinsic's error times their uncertain inverse depth, and the second update,
// linearized where the first left the state, took that product for information: the simulator's
// walk lost 85% of its 3 cm extrinsic sigma two images a millisecond apart (landmark.h).
TEST(ExtrinsicCalibration, ASecondLookFromTheSamePlaceAddsNoExtrinsicInformationEither) {
  std::mt19937_64 rng(79);
  const CameraModel cam = test::paperCamera();
  FilterState s(Mechanization::kSensorCentricComposition, true);
  s.x.T_b_c = test::forwardCamera();
  Eigen::MatrixXd P = 1e-8 * Eigen::MatrixXd::Identity(s.dim(), s.dim());
  const int e = s.extrinsicIndex();
  P.block<3, 3>(e, e) = 0.03 * 0.03 * Mat3::Identity();
  P.block<3, 3>(e + 3, e + 3) = 0.05 * 0.05 * Mat3::Identity();
  P.block<3, 3>(idx::kBa, idx::kBa) = 0.1 * Mat3::Identity();
  P.block<3, 3>(idx::kBg, idx::kBg) = 0.01 * Mat3::Identity();
  P(idx::kTd, idx::kTd) = 1e-4;
  s.setCovariance(P);
  std::vector<FeatureObservation> obs;
  for (int i = 0; i < 40; ++i) {
    obs.push_back({1000 + i, Eigen::Vector2d(40.0 + 14.0 * i, 60.0 + 9.0 * (i % 9) * 4.0)});
    InverseDepthParams ip;  // the prior depth and its (wide) inverse-depth sigma
    ASSERT_TRUE(initializeLandmarkInverseDepth(s, obs.back(), cam, s.x.T_b_c, ip));
  }
  UpdateParams up;
  up.gate_probability = 1.0 - 1e-12;  // every observation, whatever its draw
  std::normal_distribution<double> px(0.0, up.pixel_noise_px);
  for (int look = 0; look < 2; ++look) {
    std::vector<FeatureObservation> noisy = obs;
    for (auto& o : noisy) o.uv += Eigen::Vector2d(3.0 * px(rng), 3.0 * px(rng));
    ekfUpdate(s, noisy, cam, s.x.T_b_c, up);
  }
  const Eigen::VectorXd sigma = s.covariance().block<6, 6>(e, e).diagonal().cwiseSqrt();
  std::cout << "extrinsic std-devs after two looks " << sigma.transpose() << "\n";
  for (int k = 0; k < 3; ++k) EXPECT_GT(sigma(k), 0.98 * 0.03) << k;
  for (int k = 3; k < 6; ++k) EXPECT_GT(sigma(k), 0.98 * 0.05) << k;
}
