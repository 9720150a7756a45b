// ImuBuffer: the IMU between images on its own, against a filter state it propagates.
#include <gtest/gtest.h>

#include <limits>

#include "test_helpers.h"
#include "vi_ekf_slam/core/filter_start.h"
#include "vi_ekf_slam/core/imu_buffer.h"

using namespace vi_ekf_slam;

namespace {

ImuData still(double t) {
  ImuData d;
  d.timestamp = t;
  d.am = Vec3(0, 0, -9.81);
  return d;
}

FilterState startAt(const EkfSlamConfig& cfg, double t) {
  NavState init;
  init.timestamp = t;
  return startingState(cfg, sim::torsoCameraExtrinsics(), init, cfg.initial, std::nullopt);
}

}  // namespace

TEST(ImuBuffer, TakesOnlyFiniteSamplesInTimeOrderAndCountsGaps) {
  EkfSlamConfig cfg;
  ImuBuffer b(cfg);
  EXPECT_EQ(b.latestTime(), -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(b.add(still(0.0), nullptr));
  EXPECT_FALSE(b.add(still(0.0), nullptr));    // repeated stamp
  EXPECT_FALSE(b.add(still(-0.01), nullptr));  // backwards
  ImuData bad = still(0.005);
  bad.wm.y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(b.add(bad, nullptr));
  EXPECT_TRUE(b.add(still(0.005), nullptr));
  EXPECT_EQ(b.gaps(), 0);
  EXPECT_TRUE(b.add(still(0.005 + 2.0 * cfg.max_imu_gap_s), nullptr));
  EXPECT_EQ(b.gaps(), 1);
  EXPECT_DOUBLE_EQ(b.latestTime(), 0.005 + 2.0 * cfg.max_imu_gap_s);
  b.clear();
  EXPECT_EQ(b.gaps(), 0);
  EXPECT_EQ(b.latestTime(), -std::numeric_limits<double>::infinity());
}

TEST(ImuBuffer, PropagatesOnlyAsFarAsTheSamplesReachAndThePredictionIsThatPropagation) {
  EkfSlamConfig cfg;
  ImuBuffer b(cfg);
  for (int k = 0; k <= 40; ++k) b.add(still(0.005 * k), nullptr);
  FilterState s = startAt(cfg, 0.0);
  // The prediction to the latest sample changes neither the state nor the buffer ...
  const FilterState before = s;
  Vec3 rate;
  const std::optional<NavState> predicted = b.predict(s, &rate);
  ASSERT_TRUE(predicted);
  EXPECT_EQ(s.timestamp, before.timestamp);
  EXPECT_DOUBLE_EQ(predicted->timestamp, 0.2);
  // ... and is what propagating there gives.
  EXPECT_FALSE(b.propagate(s, 0.25));  // beyond the samples: nothing done
  EXPECT_EQ(s.timestamp, 0.0);
  ASSERT_TRUE(b.propagate(s, 0.2));
  const NavState after = navState(s);
  EXPECT_LT((after.p_n_b - predicted->p_n_b).norm(), 1e-12);
  EXPECT_LT(test::maxAbs(after.cov - predicted->cov), 1e-12);
  EXPECT_LT(rate.norm(), 1e-12);
}

TEST(ImuBuffer, ABridgedSampleAddsWhatItCouldHaveHidden) {
  EkfSlamConfig cfg;
  cfg.mechanization = Mechanization::kWorldCentric;
  ImuBuffer bridged(cfg), clean(cfg);
  for (int k = 0; k <= 40; ++k) {
    bridged.add(still(0.005 * k), nullptr);
    clean.add(still(0.005 * k), nullptr);
    if (k == 10) {
      ImuData clipped = still(0.0525);  // between two samples, left out: 20 m/s^2 off the last good one
      clipped.am.x() = 20.0;
      bridged.bridge(clipped);
    }
  }
  FilterState a = startAt(cfg, 0.0), c = startAt(cfg, 0.0);
  ASSERT_TRUE(bridged.propagate(a, 0.2));
  ASSERT_TRUE(clean.propagate(c, 0.2));
  const double extra = a.covariance()(idx::kV, idx::kV) - c.covariance()(idx::kV, idx::kV);
  // (20 m/s^2 * 2.5 ms)^2 over the piece of the interval it hides.
  EXPECT_NEAR(extra, std::pow(20.0 * 0.0025, 2), 1e-9);
  EXPECT_NEAR(a.covariance()(idx::kV + 1, idx::kV + 1), c.covariance()(idx::kV + 1, idx::kV + 1), 1e-15);
  EXPECT_LT((a.x.p_s_b - c.x.p_s_b).norm(), 1e-12);  // the mean is the interpolation's
}

TEST(ImuBuffer, ABufferBeyondItsBoundIntegratesItsOldestHalfIntoTheRunningState) {
  EkfSlamConfig cfg;
  cfg.imu_buffer_max = 100;
  ImuBuffer b(cfg);
  FilterState s = startAt(cfg, 0.0);
  for (int k = 0; k <= 100; ++k) b.add(still(0.005 * k), &s);
  // The 101st sample overflowed it: the state moved to the middle sample's time.
  EXPECT_DOUBLE_EQ(s.timestamp, 0.005 * 50);
  // Before the start (no running state) the oldest samples are only dropped.
  ImuBuffer without_state(cfg);
  for (int k = 0; k <= 100; ++k) without_state.add(still(0.005 * k), nullptr);
  FilterState late = startAt(cfg, 0.0);
  ASSERT_TRUE(without_state.propagate(late, 0.5));
  EXPECT_DOUBLE_EQ(late.timestamp, 0.5);
}

TEST(ImuBuffer, RestIsTheStillWindowBeforeTheImage) {
  EkfSlamConfig cfg;
  ImuBuffer b(cfg);
  const double window = cfg.zero_velocity.still_window_s;
  for (int k = 0; 0.005 * k <= 2.0 * window + 1e-9; ++k) {
    ImuData d = still(0.005 * k);
    if (0.005 * k > window) d.am.x() = (k % 2 ? 2.0 : -2.0);  // a walk's jolts after the first window
    b.add(d, nullptr);
  }
  EXPECT_TRUE(b.atRestBefore(window));
  EXPECT_FALSE(b.atRestBefore(2.0 * window));
}
