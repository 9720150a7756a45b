// The processor's parts on their own: the input clock (stale samples, a bag restart, IMU gaps and
// rate) and the calibration source (what is missing, when a camera_info changes the calibration).
#include <gtest/gtest.h>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/ros/calibration_source.h"
#include "vi_ekf_slam/ros/conversions.h"
#include "vi_ekf_slam/ros/input_clock.h"

namespace vi_ekf_slam::glue {

TEST(InputClock, SortsSamplesIntoNextStaleAndRestartAndMeasuresTheImu) {
  InputClock clock(1.0, 0.1);
  EXPECT_EQ(clock.imu(10.0), StampVerdict::kNext);
  EXPECT_FALSE(clock.imuPeriod());
  for (int k = 1; k <= 400; ++k) EXPECT_EQ(clock.imu(10.0 + 0.005 * k), StampVerdict::kNext);
  ASSERT_TRUE(clock.imuPeriod());
  EXPECT_NEAR(*clock.imuPeriod(), 0.005, 1e-9);
  EXPECT_FALSE(clock.lastImuGap());
  EXPECT_EQ(clock.imu(12.0), StampVerdict::kStale);  // repeated stamp
  EXPECT_EQ(clock.imu(11.5), StampVerdict::kStale);  // a small step back
  EXPECT_NEAR(clock.lastStepBack(), 0.5, 1e-12);
  EXPECT_EQ(clock.imu(12.5), StampVerdict::kNext);  // after a 0.5 s gap
  ASSERT_TRUE(clock.lastImuGap());
  EXPECT_NEAR(*clock.lastImuGap(), 0.5, 1e-12);
  EXPECT_NEAR(*clock.imuPeriod(), 0.005, 1e-9) << "a gap is not a sample interval";
  EXPECT_EQ(clock.imu(2.0), StampVerdict::kJumpedBack);  // the bag restarted
  EXPECT_EQ(clock.imu(2.005), StampVerdict::kNext) << "the restart's stamp is the latest";
  // The image stream has its own clock.
  EXPECT_EQ(clock.image(100.0), StampVerdict::kNext);
  EXPECT_EQ(clock.image(100.0), StampVerdict::kStale);
  clock.reset();
  EXPECT_EQ(clock.image(100.0), StampVerdict::kNext);
}

TEST(CalibrationSource, SaysWhatIsMissingAndWhenTheCalibrationChanges) {
  NodeOptions o;
  CalibrationSource cal(o);
  EXPECT_NE(cal.ready("cam0", "imu0", nullptr).find("no valid camera_info"), std::string::npos);
  CameraIntrinsics in = pinholeIntrinsics(64, 48, 50.0);
  std_msgs::Header h;
  h.frame_id = "cam0";
  sensor_msgs::CameraInfo zero = toCameraInfo(in, h);
  zero.K.fill(0.0);
  EXPECT_NE(cal.cameraInfo(zero).error, "");
  EXPECT_FALSE(cal.cameraInfo(zero).changed);
  const CameraInfoUse first = cal.cameraInfo(toCameraInfo(in, h));
  EXPECT_EQ(first.error, "");
  EXPECT_TRUE(first.changed);
  EXPECT_FALSE(cal.cameraInfo(toCameraInfo(in, h)).changed) << "the same calibration again";
  EXPECT_NE(cal.ready("", "imu0", nullptr).find("image has no frame_id"), std::string::npos);
  EXPECT_NE(cal.ready("cam0", "", nullptr).find("waiting for IMU messages"), std::string::npos);
  EXPECT_NE(cal.ready("cam0", "imu0", nullptr).find("no TF"), std::string::npos);
  tf2::BufferCore tf;
  EXPECT_NE(cal.ready("cam0", "imu0", &tf).find("waiting for TF imu0 <- cam0"), std::string::npos);
  geometry_msgs::TransformStamped T;
  T.header.frame_id = "imu0";
  T.child_frame_id = "cam0";
  T.transform.translation.x = 0.1;
  T.transform.rotation.w = 1.0;
  tf.setTransform(T, "test", true);
  ASSERT_EQ(cal.ready("cam0", "imu0", &tf), "");
  EXPECT_NEAR(cal.extrinsics().p_b_c.x(), 0.1, 1e-12);
  in.fx = 60.0;
  const CameraInfoUse use = cal.cameraInfo(toCameraInfo(in, h));
  EXPECT_EQ(use.error, "");
  EXPECT_TRUE(use.changed);
  EXPECT_EQ(cal.intrinsics().fx, 60.0);
}

}  // namespace vi_ekf_slam::glue
