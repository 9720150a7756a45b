#include <gtest/gtest.h>

#include "scratch_dir.h"

#include <cstdlib>
#include <fstream>

#include "vi_ekf_slam/eval/feature_replay.h"

using namespace vi_ekf_slam;

// Real IMU + real EqVIO feature tracks of EuRoC V1_01 (first 30 s, take-off and flight, 8.2 m)
// through the best configuration (sensor-centric, composition after every update, inverse
// depth, zero-velocity update while the MAV stands on the ground). Measured 2026-11-27 (the first
// pose registered by the z rotation between the attitudes; EuRoC's IMU x axis points up, and its
// heading, used before, is ill-defined): ATE 0.031 m, final error 0.011 m. The bounds (0.040 m,
// 0.030 m) leave ~30% on the ATE for numerical differences between machines and compilers (the
// final error is one instant) while still failing for the paper's setup on the same data (ATE
// 0.077-0.147 m, final 0.086-0.169 m, see tools/run_features), for the other mechanizations with
// inverse depth (final 0.045 m) and for any real regression.
TEST(RealFeatures, BestConfigurationFollowsTheEurocGroundTruth) {
  const char* dir = std::getenv("DATA_DIR");
  if (!dir) GTEST_SKIP() << "DATA_DIR not set";
  const std::string csv = std::string(dir) + "/euroc_v1_01_features/eqvio_processed_30s.csv";
  const std::string gt = std::string(dir) + "/euroc_v1_01_micro/mav0/state_groundtruth_estimate0/data.csv";
  if (!std::ifstream(csv) || !std::ifstream(gt)) GTEST_SKIP() << "real data not found in " << dir;
  const io::FeatureTrackData data = io::readEqvioCsv(csv);
  ASSERT_EQ(data.frames.size(), 601u);
  // Defaults (sensor_centric_composition, every update, inverse depth) with the EuRoC settings of
  // vi_ekf_slam_run_features.
  const EkfSlamConfig c = eval::eurocFeatureReplayConfig();
  const auto r = eval::replayFeatures(data, io::toStampedPoses(io::readAslGroundTruth(gt)), c, StaticInitParams());
  EXPECT_GT(r.frames_processed, 500);
  EXPECT_GT(r.rejected_observations, 0);  // the take-off mismatches must be gated out
  EXPECT_GT(r.metrics.distance_m, 7.0);
  EXPECT_LT(r.metrics.ate_position_m, 0.040);
  EXPECT_LT(r.metrics.final_position_error_m, 0.030);
  RecordProperty("ate_mm", static_cast<int>(1000 * r.metrics.ate_position_m));
}

TEST(Datasets, ReadersRejectMalformedFiles) {
  const std::string path = vi_ekf_slam::test::programScratch() / "bad_imu.csv";
  std::ofstream(path) << "#timestamp,wx,wy,wz,ax,ay,az\n1,0,0,0,0,0\n";
  EXPECT_THROW(io::readAslImu(path), std::runtime_error);
  std::ofstream(path) << "1,0,0,x,0,0,9.8\n";
  EXPECT_THROW(io::readAslImu(path), std::runtime_error);
  EXPECT_THROW(io::readAslCamera("/nonexistent/sensor.yaml"), std::runtime_error);
}

TEST(Datasets, EurocCameraAndImuNoise) {
  const char* dir = std::getenv("DATA_DIR");
  if (!dir) GTEST_SKIP() << "DATA_DIR not set";
  const std::string base = std::string(dir) + "/euroc_v1_01_micro/mav0/";
  if (!std::ifstream(base + "cam0/sensor.yaml")) GTEST_SKIP();
  const io::AslCamera cam = io::readAslCamera(base + "cam0/sensor.yaml");
  EXPECT_EQ(cam.intrinsics.width, 752);
  EXPECT_NEAR(cam.intrinsics.fx, 458.654, 1e-9);
  EXPECT_NEAR(cam.T_b_c.p_b_c.x(), -0.0216401454975, 1e-12);
  EXPECT_NEAR(cam.T_b_c.R_b_c(1, 0), 0.999557249008, 1e-4);
  const ImuNoiseParams n = io::readAslImuNoise(base + "imu0/sensor.yaml");
  EXPECT_NEAR(n.gyro_noise_density, 1.6968e-4, 1e-12);
  EXPECT_EQ(io::readAslImages(base + "cam0").size(), 95u);
}
