#include <gtest/gtest.h>

#include <random>

#include "test_helpers.h"
#include "vi_ekf_slam/core/blind_motion_prior.h"
#include "vi_ekf_slam/core/so3.h"

using namespace vi_ekf_slam;

namespace {
/// A state at time t whose body moves at v_b (in {b}), turned by a fixed q_s_b, with the given
/// velocity covariance in {s} and a small orientation one.
FilterState movingState(double t, const Vec3& v_b, const Mat3& P_v) {
  FilterState s(Mechanization::kSensorCentric);
  s.timestamp = t;
  s.x.q_s_b = Quat(Eigen::AngleAxisd(0.7, Vec3(0.2, -0.4, 0.9).normalized()));
  s.x.v_s_b = s.x.q_s_b * v_b;
  Eigen::MatrixXd P = 1e-6 * Eigen::MatrixXd::Identity(s.dim(), s.dim());
  P.block<3, 3>(idx::kV, idx::kV) = P_v;
  s.setCovariance(P);
  return s;
}

/// The prior after `seconds` of sight at 20 Hz of a body going back and forth along its x axis at
/// speed_mps, known to 1 mm/s.
BlindMotionPrior seenBackAndForth(double seconds, double speed_mps, const BlindMotionPriorParams& p) {
  BlindMotionPrior prior;
  for (int k = 0; 0.05 * k <= seconds + 1e-9; ++k) {
    const double sign = (k / 20) % 2 == 0 ? 1.0 : -1.0;  // turns every second
    prior.seen(movingState(0.05 * k, Vec3(sign * speed_mps, 0.0, 0.0), 1e-6 * Mat3::Identity()), p);
  }
  return prior;
}
}  // namespace

TEST(BodyVelocity, TheStatesCovarianceIsTheOneTheUpdateLinearizesWith) {
  std::mt19937_64 rng(11);
  FilterState s = test::randomState(Mechanization::kSensorCentricComposition, 2, rng);
  const BodyVelocity m = bodyVelocityOfState(s);
  EXPECT_LT((m.v_b - s.x.q_s_b.conjugate() * s.x.v_s_b).norm(), 1e-12);
  // d(R_s_b^T v_s_b)/d dx numerically, then H P H^T.
  const Eigen::MatrixXd H = test::numericJacobian(
      [&](const Eigen::VectorXd& dx) -> Eigen::VectorXd {
        FilterState x = s;
        x.boxplus(dx);
        return x.x.q_s_b.conjugate() * x.x.v_s_b;
      },
      s.dim());
  const Mat3 expected = H * s.covariance() * H.transpose();
  EXPECT_LT((m.cov - expected).cwiseAbs().maxCoeff(), 1e-5 * expected.cwiseAbs().maxCoeff());
}

TEST(BlindMotionPrior, IsTheSecondMomentOfTheVelocitySeenPlusTheFloorWithZeroMean) {
  BlindMotionPriorParams p;
  // Not before min_seen_s of sight.
  EXPECT_FALSE(seenBackAndForth(p.min_seen_s - 0.5, 0.3, p).prior(0.0, p));
  const std::optional<BodyVelocity> m = seenBackAndForth(20.0, 0.3, p).prior(20.0, p);
  ASSERT_TRUE(m);
  EXPECT_LT(m->v_b.norm(), 1e-12);  // which way the body went does not carry over
  const double sx = 0.3 + p.min_sigma_mps, s_other = p.min_sigma_mps;
  EXPECT_NEAR(m->cov(0, 0), sx * sx, 1e-3 * sx * sx);
  EXPECT_NEAR(m->cov(1, 1), s_other * s_other, 0.05 * s_other * s_other);
  EXPECT_NEAR(m->cov(2, 2), s_other * s_other, 0.05 * s_other * s_other);
  EXPECT_LT(std::abs(m->cov(0, 1)) + std::abs(m->cov(0, 2)) + std::abs(m->cov(1, 2)), 1e-6);
  // Switched off: none.
  BlindMotionPriorParams off = p;
  off.enabled = false;
  EXPECT_FALSE(seenBackAndForth(20.0, 0.3, off).prior(20.0, off));
}

TEST(BlindMotionPrior, GapsInTheSightAreNotSecondsOfItAndOldMotionIsForgotten) {
  BlindMotionPriorParams p;
  BlindMotionPrior prior;
  // Images 1 s apart: every interval a gap, no second of sight.
  for (int k = 0; k < 20; ++k) prior.seen(movingState(k, Vec3(0.2, 0, 0), 1e-6 * Mat3::Identity()), p);
  EXPECT_EQ(prior.seenSeconds(), 0.0);
  EXPECT_FALSE(prior.prior(20.0, p));
  // A fast minute, then a slow one: the prior is the slow one's, up to exp(-60 s / window_s).
  BlindMotionPrior walk;
  for (int k = 0; k <= 2400; ++k) {
    const double speed = k < 1200 ? 1.5 : 0.2;
    walk.seen(movingState(0.05 * k, Vec3(0, 0, speed), 1e-6 * Mat3::Identity()), p);
  }
  const std::optional<BodyVelocity> m = walk.prior(120.0, p);
  ASSERT_TRUE(m);
  const double forgotten = std::exp(-60.0 / p.window_s);
  const double expected = std::sqrt((1.0 - forgotten) * 0.2 * 0.2 + forgotten * 1.5 * 1.5) + p.min_sigma_mps;
  EXPECT_NEAR(std::sqrt(m->cov(2, 2)), expected, 0.01 * expected);
}

TEST(BlindMotionPrior, MeasuresOnlyAlongTheDirectionsTheStateKnowsWorseThanThePrior) {
  BlindMotionPriorParams p;
  p.gate_probability = 0.0;  // the textbook update, no gate
  const BlindMotionPrior prior = seenBackAndForth(20.0, 0.3, p);
  const Mat3 prior_cov = prior.prior(20.0, p)->cov;
  // Known well on every axis (0.02 m/s, below the prior's floor): nothing happens.
  FilterState known = movingState(20.0, Vec3(0.25, 0.01, 0.0), 0.02 * 0.02 * Mat3::Identity());
  const FilterState before_known = known;
  EXPECT_FALSE(prior.applyIfUncertain(known, p).applied);
  EXPECT_EQ(known.x.v_s_b, before_known.x.v_s_b);
  // Drifted: 1 m/s sigma along {b}'s x (the prior's 0.35), 0.02 along the others.
  const Mat3 R_s_b = known.x.q_s_b.toRotationMatrix();
  const Mat3 P_v_b = Vec3(1.0, 0.02 * 0.02, 0.02 * 0.02).asDiagonal();
  FilterState drifted = movingState(20.0, Vec3(0.8, 0.01, 0.0), R_s_b * P_v_b * R_s_b.transpose());
  const FilterState before = drifted;
  const KalmanUpdateResult r = prior.applyIfUncertain(drifted, p);
  ASSERT_TRUE(r.applied);
  const BodyVelocity after = bodyVelocityOfState(drifted), was = bodyVelocityOfState(before);
  // Along x the textbook scalar update by v_x = 0 with the prior's variance (the orientation's
  // share of the state's variance is 1e-6 * 0.8^2: left out of the check's precision).
  const double k = was.cov(0, 0) / (was.cov(0, 0) + prior_cov(0, 0));
  EXPECT_NEAR(after.v_b.x(), was.v_b.x() * (1.0 - k), 1e-4);
  EXPECT_NEAR(after.cov(0, 0), was.cov(0, 0) * (1.0 - k), 1e-4);
  EXPECT_LT(after.cov(0, 0), prior_cov(0, 0));
  // The other axes were known better than the prior: untouched but for the orientation's share
  // (the measured x row holds psi, which y and z share: 1e-6 * 0.8^2).
  EXPECT_NEAR(after.v_b.y(), was.v_b.y(), 1e-6);
  EXPECT_NEAR(after.cov(1, 1), was.cov(1, 1), 1e-6);
  EXPECT_NEAR(after.cov(2, 2), was.cov(2, 2), 1e-6);
  // Switched off: nothing happens.
  BlindMotionPriorParams off = p;
  off.enabled = false;
  FilterState again = before;
  EXPECT_FALSE(prior.applyIfUncertain(again, off).applied);
}
