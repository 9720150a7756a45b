#include <gtest/gtest.h>

#include <random>

#include "test_helpers.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/velocity_reanchor.h"
#include "vi_ekf_slam/eval/monte_carlo.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;

namespace {
/// The alignment's velocity at its own time (nothing carried).
BodyVelocity atItsOwnTime(const DynamicInitResult& a) {
  return bodyVelocityOf(a, alignment::Preintegrated{}, a.state.timestamp, 0.0);
}
}  // namespace

TEST(VelocityReanchor, TheAlignmentsBodyVelocityCarriesItsTiltErrorAsANumericalDerivativeSays) {
  std::mt19937_64 rng(3);
  DynamicInitResult a;
  a.state.q_n_b = Quat(Eigen::AngleAxisd(0.4, Vec3(0.3, -0.5, 0.8).normalized()));
  a.state.v_n_b = Vec3(0.6, -0.3, 0.1);
  a.covariance = test::randomSpd(9, rng, 0.05 * 0.05);
  const BodyVelocity m = atItsOwnTime(a);
  const Mat3 R = a.state.q_n_b.toRotationMatrix();
  EXPECT_LT((m.v_b - R.transpose() * a.state.v_n_b).norm(), 1e-12);
  // d v_b / d [v_n, psi] numerically, with R_true = Exp(psi) R.
  Eigen::Matrix<double, 3, 6> J;
  const double eps = 1e-6;
  for (int j = 0; j < 6; ++j) {
    Vec3 v = a.state.v_n_b, psi = Vec3::Zero();
    (j < 3 ? v : psi)(j % 3) += eps;
    J.col(j) = ((expSO3(psi) * R).transpose() * v - m.v_b) / eps;
  }
  const Mat3 expected = J * a.covariance.topLeftCorner<6, 6>() * J.transpose();
  EXPECT_LT((m.cov - expected).cwiseAbs().maxCoeff(), 1e-6 * expected.cwiseAbs().maxCoeff());
}

namespace {
/// A body turning at a constant rate (in its own frame) and accelerating at a constant rate (in
/// {n}, z along gravity): its attitude and velocity at t, and the IMU it gives (with a bias).
struct Turning {
  Quat q0 = Quat(Eigen::AngleAxisd(0.3, Vec3(0.2, 0.9, -0.4).normalized()));
  Vec3 w_b = Vec3(0.4, -1.1, 0.7);  // [rad/s]
  Vec3 v0 = Vec3(0.8, -0.2, 0.15), a_n = Vec3(0.5, 1.2, -2.0);
  Vec3 b_a = Vec3(0.04, -0.03, 0.02);
  double g = 9.81;
  Mat3 R(double t) const { return q0.toRotationMatrix() * expSO3(w_b * t); }
  Vec3 v(double t) const { return v0 + a_n * t; }
  std::deque<ImuData> imu(double t0, double t1) const {
    std::deque<ImuData> out;
    for (double t = t0; t <= t1 + 1e-9; t += 0.001)
      out.push_back({t, w_b, R(t).transpose() * (a_n - gravityInNav(g)) + b_a});
    return out;
  }
  /// An alignment that found the truth at t, with covariance cov.
  DynamicInitResult alignedAt(double t, const Eigen::Matrix<double, 9, 9>& cov) const {
    DynamicInitResult a;
    a.state.timestamp = t;
    a.state.q_n_b = Quat(R(t));
    a.state.v_n_b = v(t);
    a.state.b_a = b_a;
    a.covariance = cov;
    return a;
  }
};
}  // namespace

TEST(VelocityReanchor, TheAlignmentsVelocityCarriedOnTheImuIsTheBodysAtTheLaterTime) {
  // The alignment's state lags the image the filter is at: its velocity, carried on the IMU, is
  // the body's at the filter's time, not at the alignment's.
  const Turning b;
  const double t1 = 0.4, t2 = 0.52;
  const DynamicInitResult a = b.alignedAt(t1, 0.01 * Eigen::Matrix<double, 9, 9>::Identity());
  const auto pre = alignment::preintegrate(b.imu(0.3, 0.6), {t1, t2});
  const BodyVelocity m = bodyVelocityOf(a, pre.back(), t2, b.g);
  const Vec3 truth = b.R(t2).transpose() * b.v(t2);
  EXPECT_DOUBLE_EQ(m.t, t2);
  EXPECT_LT((m.v_b - truth).norm(), 1e-4);
  // Not carried, it is off by what the body's velocity changed in those 0.12 s.
  EXPECT_GT((atItsOwnTime(a).v_b - truth).norm(), 0.1);
}

TEST(VelocityReanchor, TheCarriedVelocitysCovarianceIsTheAlignmentsThroughANumericalJacobian) {
  std::mt19937_64 rng(4);
  const Turning b;
  const double t1 = 0.4, t2 = 0.5;
  const DynamicInitResult a = b.alignedAt(t1, test::randomSpd(9, rng, 0.05 * 0.05));
  const alignment::Preintegrated pre = alignment::preintegrate(b.imu(0.3, 0.6), {t1, t2}).back();
  const BodyVelocity m = bodyVelocityOf(a, pre, t2, b.g);
  // d v_b / d [v_n, psi, b_a] numerically, R_true = Exp(psi) R.
  Eigen::Matrix<double, 3, 9> J;
  const double eps = 1e-6;
  for (int j = 0; j < 9; ++j) {
    DynamicInitResult x = a;
    if (j < 3) x.state.v_n_b(j) += eps;
    if (j >= 3 && j < 6) x.state.q_n_b = Quat(expSO3(eps * Vec3::Unit(j - 3)) * a.state.q_n_b.toRotationMatrix());
    if (j >= 6) x.state.b_a(j - 6) += eps;
    J.col(j) = (bodyVelocityOf(x, pre, t2, b.g).v_b - m.v_b) / eps;
  }
  const Mat3 expected = J * a.covariance * J.transpose();
  EXPECT_LT((m.cov - expected).cwiseAbs().maxCoeff(), 1e-5 * expected.cwiseAbs().maxCoeff());
}

TEST(VelocityReanchor, AfterALongBlindStretchTheVelocityIsKnownAsWellAsItsSigmaSays) {
  // A walk (with the gait's bounce) whose camera is covered for 8 s: once it sees again, the
  // re-anchor corrects the velocity by the first images' alignment. Over the two seconds after it,
  // each axis's normalized squared velocity error, averaged over 8 runs (and their frames), stays
  // below 2.74, the 99% bound of the mean of 8 chi-square(1) draws. The alignment's velocity
  // applied at its own last frame, a few frames before the filter's, was off by the bounce of
  // those frames: 5.3 along the vertical (1.1 carried to the filter's time).
  sim::HallwayParams walk;
  walk.duration_s = 19.0;
  sim::Scenario sc = sim::hallwayScenario(walk, 1.0, 1);
  sim::SensorFault covered;
  covered.kind = sim::SensorFault::Kind::kCameraCovered;
  covered.start_s = 6.0;
  covered.duration_s = 8.0;
  sc.faults = {covered};
  EkfSlamConfig cfg;  // the node's defaults, told the simulated sensors' noise
  cfg.imu_noise = sc.imu.noise;
  cfg.update.pixel_noise_px = sc.cam.pixel_noise_px;
  Vec3 sum = Vec3::Zero();
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    for (const eval::FrameMetrics& f : eval::runMonteCarloRun(sc, cfg, seed).frames) {
      if (f.t < 15.2 || f.t > 17.0) continue;
      sum += f.e_v.cwiseQuotient(f.s_v).cwiseAbs2();
      ++n;
    }
  }
  ASSERT_GT(n, 100);
  const Vec3 per_axis = sum / n;
  std::printf("velocity NEES per axis after the stretch: %.2f %.2f %.2f\n", per_axis.x(), per_axis.y(), per_axis.z());
  EXPECT_LT(per_axis.maxCoeff(), 2.74);
}

TEST(VelocityReanchor, TheUpdateIsTheTextbookOneWithANumericalJacobian) {
  std::mt19937_64 rng(5);
  for (Mechanization mech : {Mechanization::kWorldCentric, Mechanization::kSensorCentricComposition}) {
    FilterState s = test::randomState(mech, 3, rng);
    s.x.v_s_b = Vec3(0.4, -0.2, 0.3);
    const FilterState before = s;
    const Eigen::MatrixXd P = s.covariance();
    auto h = [](const FilterState& x) -> Vec3 { return x.x.q_s_b.conjugate() * x.x.v_s_b; };
    Eigen::MatrixXd H(3, s.dim());
    const double eps = 1e-7;
    for (int j = 0; j < s.dim(); ++j) {
      FilterState x = before;
      Eigen::VectorXd dx = Eigen::VectorXd::Zero(s.dim());
      dx(j) = eps;
      x.boxplus(dx);
      H.col(j) = (h(x) - h(before)) / eps;
    }
    BodyVelocity m;
    m.v_b = h(before) + Vec3(0.05, -0.03, 0.02);
    m.cov = test::randomSpd(3, rng, 0.05 * 0.05);
    const KalmanUpdateResult r = bodyVelocityUpdate(s, m, 0.0);
    ASSERT_TRUE(r.applied);
    const Mat3 S = H * P * H.transpose() + m.cov;
    const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
    const Vec3 res = m.v_b - h(before);
    EXPECT_NEAR(r.nis, res.dot(S.inverse() * res), 1e-6 * r.nis);
    EXPECT_LT((s.boxminus(before) - K * res).cwiseAbs().maxCoeff(), 1e-6);
    const Eigen::MatrixXd P_expected = P - K * H * P;
    EXPECT_LT((s.covariance() - P_expected).cwiseAbs().maxCoeff(), 1e-6 * P.cwiseAbs().maxCoeff());
  }
}

TEST(VelocityReanchor, AVelocityFarOutsideBothUncertaintiesIsRefused) {
  std::mt19937_64 rng(8);
  FilterState s = test::randomState(Mechanization::kSensorCentric, 2, rng);
  const FilterState before = s;
  BodyVelocity m;
  m.v_b = s.x.q_s_b.conjugate() * s.x.v_s_b + Vec3(5.0, 0.0, 0.0);
  m.cov = 0.01 * Mat3::Identity();
  const KalmanUpdateResult r = bodyVelocityUpdate(s, m, 0.999);
  EXPECT_FALSE(r.applied);
  EXPECT_GT(r.nis, 100.0);
  EXPECT_EQ(s.x.v_s_b, before.x.v_s_b);
  EXPECT_EQ(s.covariance(), before.covariance());
}
