// The node's processor on a real hand-held recording (../shared/data/dmvio_handheld, found through
// DATA_DIR; skipped without it): the first 15 s of 1280x720 JPEG frames and the real IMU, with the
// node's default configuration and only the recording's calibration (intrinsics on camera_info,
// the camera-IMU extrinsic, no time offset given). Compared with the vision-only SfM reference.
#include <gtest/gtest.h>
#include <cv_bridge/cv_bridge.h>
#include <opencv2/imgcodecs.hpp>
#include <tf2_eigen/tf2_eigen.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>

#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/eval/reference_comparison.h"
#include "vi_ekf_slam/ros/conversions.h"
#include "vi_ekf_slam/ros/ekf_slam_processor.h"

namespace vi_ekf_slam::glue {
namespace {

class KeepingSink : public OutputSink {
 public:
  std::vector<io::StampedPose> poses;
  std::vector<double> time_offsets;
  std::vector<std::string> events;
  double max_speed_mps = 0.0;
  double angular_rate_var = 0.0;  ///< the last odometry's twist covariance of omega_x [rad^2/s^2]
  void odometry(const nav_msgs::Odometry& o) override {
    angular_rate_var = o.twist.covariance[21];
    io::StampedPose p;
    p.t = o.header.stamp.toSec();
    tf2::fromMsg(o.pose.pose.position, p.p);
    tf2::fromMsg(o.pose.pose.orientation, p.q);
    Vec3 v;
    tf2::fromMsg(o.twist.twist.linear, v);
    max_speed_mps = std::max(max_speed_mps, v.norm());
    poses.push_back(p);
  }
  bool wantsLandmarks() const override { return false; }
  int imu_rate_poses = 0;
  bool imu_rate_finite = true;
  bool wantsImuOdometry() const override { return true; }
  void imuOdometry(const nav_msgs::Odometry& o) override {
    ++imu_rate_poses;
    imu_rate_finite = imu_rate_finite && std::isfinite(o.pose.pose.position.x) && std::isfinite(o.pose.covariance[0]);
  }
  void landmarks(const std::vector<LandmarkOutput>&, const ros::Time&) override {}
  void status(const vi_ekf_slam::FilterStatus& s) override { time_offsets.push_back(s.time_offset_s); }
  void event(const std::string& text, double) override { events.push_back(text); }
};

sensor_msgs::Imu imuMsg(const ImuData& d) {
  sensor_msgs::Imu m;
  m.header.stamp = ros::Time(d.timestamp);
  m.header.frame_id = "imu";
  tf2::toMsg(Vec3(d.wm), m.angular_velocity);
  tf2::toMsg(Vec3(d.am), m.linear_acceleration);
  m.orientation_covariance[0] = -1.0;
  return m;
}

struct RunResult {
  double first_image_t = 0.0;  ///< stamp of the first image given [s]
  double imu_rate_hz = 0.0;    ///< of the recording
  double gyro_noise_density = 0.0;
  KeepingSink sink;
  eval::ReferenceComparison sfm;
};

/// `seconds` of the recording from `start_s` after its first image (IMU and images cut there, as
/// a node started mid-walk sees them) through the processor, configured by the node's default
/// YAML with `rig_file` (if any) on top, against the SfM reference.
std::optional<RunResult> runSegment(double start_s, double seconds, const std::string& rig_file,
                                    const std::vector<std::pair<std::string, std::string>>& params_set = {}) {
  const char* dir = std::getenv("DATA_DIR");
  if (!dir) return std::nullopt;
  const std::string base = std::string(dir) + "/dmvio_handheld/";
  if (!std::ifstream(base + "mav0/cam0/sensor.yaml")) return std::nullopt;
  ros::Time::init();  // no master: wall time for the (throttled) log messages only
  const io::AslCamera cam = io::readAslCamera(base + "mav0/cam0/sensor.yaml");
  const std::vector<io::AslImage> images = io::readAslImages(base + "mav0/cam0");
  const std::vector<ImuData> imu = io::readAslImu(base + "mav0/imu0/data.csv");
  const std::vector<io::StampedPose> sfm = io::readTum(base + "reference/sfm_camera_poses.txt");

  YamlParams yaml(std::string(VI_EKF_SLAM_SOURCE_DIR) + "/config/vi_ekf_slam.yaml");
  if (!rig_file.empty()) yaml.overlay(YamlParams(std::string(VI_EKF_SLAM_SOURCE_DIR) + "/" + rig_file));
  for (const auto& [name, value] : params_set) yaml.set(name, value);
  NodeParams params;
  EXPECT_EQ(loadParams(yaml, &params), "");
  params.node.tune_allocator = false;
  if (params.node.extrinsic_source != "parameters") {  // the defaults: the recording's sensor.yaml
    params.node.extrinsic_source = "parameters";
    const Quat q_b_c(cam.T_b_c.R_b_c);
    params.node.T_b_c = {
        cam.T_b_c.p_b_c.x(), cam.T_b_c.p_b_c.y(), cam.T_b_c.p_b_c.z(), q_b_c.x(), q_b_c.y(), q_b_c.z(), q_b_c.w()};
  }
  RunResult out;
  out.imu_rate_hz = (imu.size() - 1) / (imu.back().timestamp - imu.front().timestamp);
  out.gyro_noise_density = params.filter.imu_noise.gyro_noise_density;
  EkfSlamProcessor processor(params, out.sink, nullptr);
  std_msgs::Header h;
  h.frame_id = "camera";
  processor.cameraInfo(toCameraInfo(cam.intrinsics, h));

  const double t_start = images.front().t + start_s, t_end = t_start + seconds;
  size_t k = 0;
  while (k < imu.size() && start_s > 0.0 && imu[k].timestamp < t_start) ++k;
  for (const auto& img : images) {
    if (img.t < t_start) continue;
    if (img.t > t_end) break;
    if (out.first_image_t == 0.0) out.first_image_t = img.t;
    for (; k < imu.size() && imu[k].timestamp <= img.t; ++k) processor.imu(imuMsg(imu[k]));
    h.stamp = ros::Time(img.t);
    processor.image(*cv_bridge::CvImage(h, "mono8", cv::imread(img.path, cv::IMREAD_GRAYSCALE)).toImageMsg());
  }
  for (; k < imu.size() && imu[k].timestamp <= t_end + 0.5; ++k) processor.imu(imuMsg(imu[k]));
  if (!out.sink.poses.empty()) {
    const auto view = eval::referenceView(out.sink.poses, cam.T_b_c, &out.sink.time_offsets);
    out.sfm = eval::compareWithReference(view, sfm, eval::Alignment::kSim3);
  }
  return out;
}

void expectTracked(const RunResult& r, const char* what) {
  ASSERT_GT(r.sink.poses.size(), 150u);
  for (const auto& e : r.sink.events) EXPECT_EQ(e.rfind("reset", 0), std::string::npos) << e;
  EXPECT_LT(r.sink.max_speed_mps, 2.0);  // a person walking through a bedroom
  std::printf("%s, 15 s: %d poses against SfM: RMSE %.3f m, scale %.2f SfM units per metre, time offset %.4f s\n", what,
              r.sfm.matched, r.sfm.position_rmse_m, r.sfm.scale, r.sink.time_offsets.back());
}

}  // namespace

// The bounds are about 30% above what was measured (docs/realdata.md); OpenVINS, tuned for this
// recording, has 0.092 m over the same 15 s.
TEST(RealHandheld, First15SecondsTrackWithTheDefaultsAndFindTheTimeOffset) {
  const auto r = runSegment(0.0, 15.0, "");
  if (!r) GTEST_SKIP() << "no dmvio_handheld in DATA_DIR";
  expectTracked(*r, "defaults");
  EXPECT_LT(r->sfm.position_rmse_m, 0.082);
  EXPECT_NEAR(r->sink.time_offsets.back(), -0.047, 0.005);  // from 0: the image stamps are 45-49 ms late
  // odom_imu: a pose per IMU sample (219 Hz against 20 Hz images) once initialized.
  EXPECT_GT(r->sink.imu_rate_poses, 8 * static_cast<int>(r->sink.poses.size()));
  EXPECT_TRUE(r->sink.imu_rate_finite);
  // The published angular velocity is one gyro sample: its variance is the white noise at the
  // IMU's own rate (219 Hz here, not an assumed 200 Hz) plus the gyro bias's (at most its prior).
  const double w_var = r->gyro_noise_density * r->gyro_noise_density * r->imu_rate_hz;
  std::printf("IMU %.1f Hz: omega variance %.3g, white noise %.3g rad^2/s^2\n", r->imu_rate_hz,
              r->sink.angular_rate_var, w_var);
  EXPECT_GE(r->sink.angular_rate_var, 0.98 * w_var);  // (the rate is a running average; 200 Hz would be 9% low)
  EXPECT_LT(r->sink.angular_rate_var, w_var + 0.002 * 0.002);
}

// The rig file holds only what a calibration gives (extrinsic, measured IMU white noise, the
// rolling shutter's readout time). The time offset then refers to the middle row (-0.048 s by the
// per-band measurement in docs/realdata.md).
TEST(RealHandheld, First15SecondsTrackWithTheRigFile) {
  const auto r = runSegment(0.0, 15.0, "config/rigs/dmvio_handheld.yaml");
  if (!r) GTEST_SKIP() << "no dmvio_handheld in DATA_DIR";
  expectTracked(*r, "rig file");
  EXPECT_LT(r->sfm.position_rmse_m, 0.088);
  EXPECT_NEAR(r->sink.time_offsets.back(), -0.048, 0.005);
}

// A Kalibr user gets the rig file's trajectory: the recording's Kalibr files (and the readout time,
// which a global-shutter Kalibr calibration does not hold) give the same poses to the bit, with the
// intrinsics from camera_info or from Kalibr's file.
TEST(RealHandheld, TheKalibrFilesGiveTheRigFilesTrajectory) {
  const char* dir = std::getenv("DATA_DIR");
  if (!dir) GTEST_SKIP() << "no DATA_DIR";
  const std::string kalibr = std::string(dir) + "/dmvio_handheld/kalibr/";
  const auto rig = runSegment(0.0, 8.0, "config/rigs/dmvio_handheld.yaml");
  if (!rig) GTEST_SKIP() << "no dmvio_handheld in DATA_DIR";
  for (const char* source : {"camera_info", "file"}) {
    SCOPED_TRACE(source);
    const auto k = runSegment(0.0, 8.0, "",
                              {{"kalibr_camchain", kalibr + "camchain-imucam.yaml"},
                               {"kalibr_imu", kalibr + "imu.yaml"},
                               {"camera_readout_time_s", "0.033"},
                               {"calibration_source", source}});
    ASSERT_TRUE(k);
    ASSERT_GT(rig->sink.poses.size(), 100u);
    ASSERT_EQ(k->sink.poses.size(), rig->sink.poses.size());
    double max_diff = 0.0;
    for (size_t i = 0; i < k->sink.poses.size(); ++i) {
      EXPECT_EQ(k->sink.poses[i].t, rig->sink.poses[i].t);
      max_diff = std::max(max_diff, (k->sink.poses[i].p - rig->sink.poses[i].p).norm());
    }
    EXPECT_EQ(max_diff, 0.0);
  }
}

// Started mid-walk (the node, a bag played with --start, a reset while walking): no rest to
// initialize from, so the dynamic initializer must; then it tracks as from the start. The run from
// the start is measured here too, over the same seconds (its poses from the cut run's first one to
// its end, aligned on their own), so the ratio the issue asks for is what the test prints. The
// issue names the cuts at 10 s and 30 s; one cut is one sample of where a hand happens to be slow
// or a reference happens to be exact, so every 2.5 s from 5 s to 30 s is measured, and their
// geometric mean held to 1.5x.
TEST(RealHandheld, StartedMidWalkInitializesWhileMoving) {
  const auto whole = runSegment(0.0, 46.0, "");
  if (!whole) GTEST_SKIP() << "no dmvio_handheld in DATA_DIR";
  const auto cam = io::readAslCamera(std::string(std::getenv("DATA_DIR")) + "/dmvio_handheld/mav0/cam0/sensor.yaml");
  const auto sfm = io::readTum(std::string(std::getenv("DATA_DIR")) + "/dmvio_handheld/reference/sfm_camera_poses.txt");
  const auto whole_view = eval::referenceView(whole->sink.poses, cam.T_b_c, &whole->sink.time_offsets);
  double log_ratio_sum = 0.0;
  int cuts = 0;
  for (double start = 5.0; start <= 30.0 + 1e-9; start += 2.5) {
    const auto r = runSegment(start, 15.0, "");
    ASSERT_TRUE(r);
    ASSERT_FALSE(r->sink.poses.empty());
    ASSERT_FALSE(r->sink.events.empty());
    EXPECT_EQ(r->sink.events.front().rfind("initialized: dynamic", 0), 0u) << r->sink.events.front();
    const double first_odom_after_s = r->sink.poses.front().t - r->first_image_t;
    std::printf("started %.1f s in: first odometry %.2f s after the first image; %s\n", start, first_odom_after_s,
                r->sink.events.front().c_str());
    EXPECT_LT(first_odom_after_s, 2.0);
    expectTracked(*r, "cut");
    std::vector<io::StampedPose> same_seconds;
    for (const auto& p : whole_view)
      if (p.t >= r->sfm.t.front() && p.t <= r->sfm.t.back()) same_seconds.push_back(p);
    const auto from_start = eval::compareWithReference(same_seconds, sfm, eval::Alignment::kSim3);
    const double ratio = r->sfm.position_rmse_m / from_start.position_rmse_m;
    std::printf(
        "started %.1f s in: RMSE %.4f m against %.4f m for the run from the start over the same %d poses: "
        "%.2fx\n",
        start, r->sfm.position_rmse_m, from_start.position_rmse_m, from_start.matched, ratio);
    // Bounds: the cuts the issue names (10 s and 30 s in), 1.5x the run from the start (its
    // target; measured 0.97x and 1.43x); every other cut 3.5x, above the worst measured (2.41x,
    // 20 s in; 2.68x for the 30 s cut before the gate watch; docs/initialization.md).
    const bool named = std::abs(start - 10.0) < 1e-9 || std::abs(start - 30.0) < 1e-9;
    EXPECT_LT(ratio, named ? 1.5 : 3.5) << "started " << start << " s in";
    log_ratio_sum += std::log(ratio);
    ++cuts;
  }
  const double geometric_mean = std::exp(log_ratio_sum / cuts);
  std::printf("%d cuts: geometric mean of the ratios %.2f\n", cuts, geometric_mean);
  EXPECT_LT(geometric_mean, 1.5);
}

}  // namespace vi_ekf_slam::glue
