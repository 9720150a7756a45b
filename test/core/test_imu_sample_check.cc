// IMU samples that cannot be integrated as they are (core/imu_sample_check.h): a reading at the
// sensor's range is clipped, one that jumps from the last good sample implausible; either is left
// out and bridged, and the covariance grows by what it could have hidden. Through the pipeline
// the initializers never see it and the listener counts it.
#include <gtest/gtest.h>

#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/imu_sample_check.h"
#include "vi_ekf_slam/core/vio_pipeline.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam {
namespace {

ImuData sample(double t, const Vec3& am, const Vec3& wm = Vec3::Zero()) { return {t, wm, am}; }

TEST(ImuSampleCheck, ClippedAndImplausibleSamplesAreToldApartFromARealChange) {
  const ImuCheckParams p;  // 16 g, 2000 deg/s, 100 m/s^2 and 20 rad/s per sample, 2 in a row
  ImuSampleCheck check;
  const Vec3 g(0.0, 0.0, -9.81);
  EXPECT_EQ(check.check(sample(0.000, g), p), ImuSampleVerdict::kGood);
  EXPECT_EQ(check.check(sample(0.005, Vec3(0.999 * p.accel_range_mps2, 0, -9.81)), p), ImuSampleVerdict::kClipped);
  EXPECT_EQ(check.check(sample(0.010, g, Vec3(0, 0, -p.gyro_range_radps)), p), ImuSampleVerdict::kClipped);
  EXPECT_EQ(check.check(sample(0.015, g), p), ImuSampleVerdict::kGood);
  EXPECT_EQ(check.check(sample(0.020, g + Vec3(120.0, 0, 0)), p), ImuSampleVerdict::kImplausible);
  EXPECT_EQ(check.check(sample(0.025, g + Vec3(5.0, 0, 0)), p), ImuSampleVerdict::kGood);  // next to the last good
  // A level that stays (a third sample in a row) is real, and the reference from then on.
  EXPECT_EQ(check.check(sample(0.030, g + Vec3(150.0, 0, 0)), p), ImuSampleVerdict::kImplausible);
  EXPECT_EQ(check.check(sample(0.035, g + Vec3(150.0, 0, 0)), p), ImuSampleVerdict::kImplausible);
  EXPECT_EQ(check.check(sample(0.040, g + Vec3(150.0, 0, 0)), p), ImuSampleVerdict::kGood);
  EXPECT_EQ(check.check(sample(0.045, g + Vec3(150.0, 0, 0)), p), ImuSampleVerdict::kGood);
  // Range 0 and step 0: not checked.
  ImuCheckParams off;
  off.accel_range_mps2 = off.gyro_range_radps = off.max_accel_step_mps2 = off.max_gyro_step_radps = 0.0;
  ImuSampleCheck none;
  EXPECT_EQ(none.check(sample(0.0, g), off), ImuSampleVerdict::kGood);
  EXPECT_EQ(none.check(sample(0.005, Vec3(1e4, 0, 0)), off), ImuSampleVerdict::kGood);
  EXPECT_TRUE(p.validate().empty());
  ImuCheckParams bad;
  bad.accel_range_mps2 = -1.0;
  EXPECT_FALSE(bad.validate().empty());
}

TEST(EkfSlam, ABridgedSampleIsInterpolatedOverAndItsHiddenMotionEntersAsUncertainty) {
  EkfSlamConfig cfg;
  cfg.mechanization = Mechanization::kWorldCentric;
  EkfSlam bridged(cfg, sim::paperCamera(), sim::torsoCameraExtrinsics());
  EkfSlam missing(cfg, sim::paperCamera(), sim::torsoCameraExtrinsics());
  bridged.initialize(NavState());
  missing.initialize(NavState());
  const ImuCheckParams range;
  for (int k = 0; k <= 100; ++k) {
    const ImuData d = sample(0.005 * k, Vec3(0.0, 0.0, -9.81));
    if (k == 40) {  // clipped on x: 16 g
      bridged.bridgeImu(sample(d.timestamp, Vec3(range.accel_range_mps2, 0.0, -9.81)));
      continue;  // the other filter never got it
    }
    bridged.addImu(d);
    missing.addImu(d);
  }
  ASSERT_TRUE(bridged.propagateTo(0.5));
  ASSERT_TRUE(missing.propagateTo(0.5));
  // The same mean (the neighbours interpolated over it) ...
  EXPECT_LT((bridged.navState().p_n_b - missing.navState().p_n_b).norm(), 1e-12);
  EXPECT_LT((bridged.navState().v_n_b - missing.navState().v_n_b).norm(), 1e-12);
  // ... and the velocity along the clipped axis uncertain by what the sample departed from the
  // last good one over its 5 ms period: (16 g * 5 ms)^2 (the gyro did not move: no attitude term).
  const Eigen::MatrixXd dP = bridged.navState().cov - missing.navState().cov;
  EXPECT_NEAR(dP(idx::kV, idx::kV), std::pow(range.accel_range_mps2 * 0.005, 2), 1e-9);
  EXPECT_NEAR(dP(idx::kV + 1, idx::kV + 1), 0.0, 1e-12);
  EXPECT_NEAR(dP(idx::kV + 2, idx::kV + 2), 0.0, 1e-12);
}

struct Counting : PipelineListener {
  int clipped = 0, implausible = 0;
  void imuBridged(const ImuData&, ImuSampleVerdict why) override {
    clipped += why == ImuSampleVerdict::kClipped;
    implausible += why == ImuSampleVerdict::kImplausible;
  }
};

TEST(VioPipeline, ClippedSamplesReachNeitherTheInitializersNorTheFilterAsTheyAre) {
  // At rest for 2 s with a clipped sample every 0.5 s: the static start still comes (its rest
  // test never saw them), and the listener heard of each.
  Counting listener;
  PipelineParams params;
  VioPipeline pipeline(EkfSlamConfig(), params, sim::paperCamera(), sim::torsoCameraExtrinsics(), listener);
  const ImuCheckParams range;
  for (int k = 0; k <= 400; ++k) {
    ImuData d = sample(0.005 * k, Vec3(0.0, 0.0, -9.81));
    if (k % 100 == 50) d.am.x() = range.accel_range_mps2;
    if (k % 100 == 75) d.am.x() = 120.0;  // not at the range, but 12 g from the last
    pipeline.addImu(d);
    if (k % 10 == 0) pipeline.addFrame({d.timestamp, [&](const std::optional<Mat3>&) { return CameraFrame(); }});
  }
  EXPECT_EQ(listener.clipped, 4);
  EXPECT_EQ(listener.implausible, 4);
  EXPECT_TRUE(pipeline.filter().initialized());
}

}  // namespace
}  // namespace vi_ekf_slam
