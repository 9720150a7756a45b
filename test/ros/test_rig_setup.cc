// Bringing one's own rig: Kalibr's files as parameters, the choice of the calibration source, and
// the rig presets of config/rigs (each loads, validates, and runs on a synthetic bag written with
// its topic names and frames).
#include <gtest/gtest.h>

#include "../scratch_dir.h"
#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "synthetic_rig.h"
#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/ros/bag_replay.h"
#include "vi_ekf_slam/ros/calibration_source.h"
#include "vi_ekf_slam/ros/conversions.h"
#include "vi_ekf_slam/ros/kalibr_import.h"
#include "vi_ekf_slam/ros/params.h"

namespace vi_ekf_slam::glue {
namespace {

namespace fs = std::filesystem;
const std::string kSource = VI_EKF_SLAM_SOURCE_DIR;

std::string dataDir() {
  const char* d = std::getenv("DATA_DIR");
  return d ? d : "";
}

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = test::programScratch() / ("rig_" + name);
  std::ofstream(path) << text;
  return path;
}

NodeParams load(const ParamSource& src) {
  NodeParams p;
  EXPECT_EQ(loadParams(src, &p), "");
  return p;
}

// The recording's Kalibr files give the values of its rig file (the readout time aside, which a
// global-shutter Kalibr calibration does not hold) and the intrinsics of its camera.
TEST(KalibrImport, TheRecordingsKalibrFilesGiveItsRigFile) {
  const std::string dir = dataDir() + "/dmvio_handheld/";
  if (!fs::exists(dir + "kalibr/camchain-imucam.yaml")) GTEST_SKIP() << "no dmvio_handheld in DATA_DIR";
  YamlParams kalibr;
  kalibr.set("kalibr_camchain", dir + "kalibr/camchain-imucam.yaml");
  kalibr.set("kalibr_imu", dir + "kalibr/imu.yaml");
  const NodeParams from_kalibr = load(kalibr);
  const NodeParams from_rig = load(YamlParams(kSource + "/config/rigs/dmvio_handheld.yaml"));
  EXPECT_EQ(from_kalibr.node.extrinsic_source, "parameters");
  EXPECT_EQ(from_kalibr.node.T_b_c, from_rig.node.T_b_c);  // bit for bit
  EXPECT_EQ(from_kalibr.filter.imu_noise.accel_noise_density, from_rig.filter.imu_noise.accel_noise_density);
  EXPECT_EQ(from_kalibr.filter.imu_noise.gyro_noise_density, from_rig.filter.imu_noise.gyro_noise_density);
  EXPECT_EQ(from_kalibr.filter.imu_noise.accel_random_walk, from_rig.filter.imu_noise.accel_random_walk);
  EXPECT_EQ(from_kalibr.filter.imu_noise.gyro_random_walk, from_rig.filter.imu_noise.gyro_random_walk);
  EXPECT_EQ(from_kalibr.filter.camera_time_offset_s, from_rig.filter.camera_time_offset_s);
  // The intrinsics are those the recording's camera_info carries.
  const io::AslCamera cam = io::readAslCamera(dir + "mav0/cam0/sensor.yaml");
  std::optional<CameraIntrinsics> k;
  ASSERT_EQ(intrinsicsFromOptions(from_kalibr.node, &k), "");
  ASSERT_TRUE(k);
  EXPECT_EQ(k->width, cam.intrinsics.width);
  EXPECT_EQ(k->height, cam.intrinsics.height);
  EXPECT_NEAR(k->fx, cam.intrinsics.fx, 1e-9);
  EXPECT_NEAR(k->fy, cam.intrinsics.fy, 1e-9);
  EXPECT_NEAR(k->cx, cam.intrinsics.cx, 1e-9);
  EXPECT_NEAR(k->cy, cam.intrinsics.cy, 1e-9);
  // The rig file Kalibr's converter writes loads to the same parameters.
  const KalibrImport imp = importKalibr(dir + "kalibr/camchain-imucam.yaml", dir + "kalibr/imu.yaml");
  EXPECT_EQ(imp.image_topic, "/camera/image_raw");
  EXPECT_EQ(imp.imu_topic, "/imu");
  const std::string rig =
      writeFile("converted.yaml", kalibrRigFile(imp, dir + "kalibr/camchain-imucam.yaml", dir + "kalibr/imu.yaml"));
  EXPECT_EQ(load(YamlParams(rig)).node.T_b_c, from_rig.node.T_b_c);
  // ... and to the topics of Kalibr's recording, which are the preset's.
  EXPECT_EQ(load(YamlParams(rig)).node.imu_topic, from_rig.node.imu_topic);
  EXPECT_EQ(load(YamlParams(rig)).node.image_topic, from_rig.node.image_topic);
}

const char* kEquidistantCamchain = R"(cam0:
  T_cam_imu:
  - [0.0, -1.0, 0.0, 0.02]
  - [0.0, 0.0, -1.0, -0.01]
  - [1.0, 0.0, 0.0, 0.05]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: pinhole
  distortion_coeffs: [0.01, -0.002, 0.0003, -0.00004]
  distortion_model: equidistant
  intrinsics: [190.9, 190.8, 254.9, 256.8]
  resolution: [512, 512]
  line_delay: 5.0e-05
  rostopic: /cam0/image_raw
  timeshift_cam_imu: -0.0123
)";

// Every field of a camchain lands in its parameter: T_b_c is T_cam_imu's inverse, the line delay
// over the rows is the readout time, timeshift_cam_imu keeps its sign (t_imu = t_cam + shift).
TEST(KalibrImport, EveryCamchainFieldLandsInItsParameter) {
  const std::string camchain = writeFile("equi_camchain.yaml", kEquidistantCamchain);
  const std::string imu = writeFile("imu_top_level.yaml",
                                    "accelerometer_noise_density: 0.002\naccelerometer_random_walk: 0.0003\n"
                                    "gyroscope_noise_density: 0.00017\ngyroscope_random_walk: 1.9e-05\n"
                                    "rostopic: /imu0\nupdate_rate: 200.0\n");
  const KalibrImport k = importKalibr(camchain, imu);
  EXPECT_EQ(k.image_topic, "/cam0/image_raw");
  EXPECT_EQ(k.imu_topic, "/imu0");
  EXPECT_EQ(k.imu_rate_hz, 200.0);
  YamlParams yaml;
  yaml.set("kalibr_camchain", camchain);
  yaml.set("kalibr_imu", imu);
  const NodeParams p = load(yaml);
  EXPECT_NEAR(p.filter.update.readout_time_s, 5.0e-5 * 511, 1e-12);
  EXPECT_EQ(p.filter.camera_time_offset_s, -0.0123);
  EXPECT_EQ(p.filter.imu_noise.accel_noise_density, 0.002);
  EXPECT_EQ(p.filter.imu_noise.gyro_random_walk, 1.9e-05);
  std::optional<CameraIntrinsics> in;
  ASSERT_EQ(intrinsicsFromOptions(p.node, &in), "");
  EXPECT_EQ(in->model, DistortionModel::kEquidistant);
  EXPECT_EQ(in->distortion, std::vector<double>({0.01, -0.002, 0.0003, -0.00004}));
  EXPECT_EQ(in->width, 512);
  // T_b_c * T_cam_imu = identity: the camera's z (forward) is the IMU's x.
  const auto& v = p.node.T_b_c;
  const Quat q_b_c(v[6], v[3], v[4], v[5]);
  const Vec3 p_b_c(v[0], v[1], v[2]);
  Eigen::Matrix3d R_c_i;
  R_c_i << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  EXPECT_LT((q_b_c.toRotationMatrix() * R_c_i - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_LT((q_b_c * Vec3(0.02, -0.01, 0.05) + p_b_c).norm(), 1e-12);
}

TEST(KalibrImport, RefusesWhatItCannotUseAndSaysWhere) {
  auto fails = [](const std::string& text, const std::string& expected) {
    const std::string path = writeFile("bad_camchain.yaml", text);
    try {
      importKalibr(path, "");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  std::string omni = kEquidistantCamchain;
  omni.replace(omni.find("pinhole"), 7, "omni");
  fails(omni, "camera_model 'omni'");
  std::string skewed = kEquidistantCamchain;
  skewed.replace(skewed.find("[0.0, -1.0, 0.0, 0.02]"), 22, "[0.0, -1.0, 0.3, 0.02]");
  fails(skewed, "not a rigid transform");
  std::string no_intrinsics = kEquidistantCamchain;
  no_intrinsics.replace(no_intrinsics.find("intrinsics"), 10, "intrinsicz");
  fails(no_intrinsics, "no 'intrinsics'");
  fails("cam1: {}\n", "no cam0");
  // Through the node's parameters: the problem is reported, not thrown past loadParams.
  YamlParams yaml;
  yaml.set("kalibr_camchain", "/nonexistent/camchain.yaml");
  NodeParams p;
  EXPECT_NE(loadParams(yaml, &p).find("cannot read Kalibr file"), std::string::npos);
}

// Kalibr's values replace those of the configuration (which lists every parameter).
TEST(KalibrImport, ReplacesTheConfigurationsValues) {
  YamlParams yaml(kSource + "/config/vi_ekf_slam.yaml");
  yaml.set("kalibr_camchain", writeFile("equi_camchain2.yaml", kEquidistantCamchain));
  const NodeParams p = load(yaml);
  EXPECT_EQ(p.node.extrinsic_source, "parameters");
  EXPECT_EQ(p.node.camera_intrinsics, std::vector<double>({190.9, 190.8, 254.9, 256.8}));
  EXPECT_EQ(p.node.calibration_source, "camera_info");  // still the user's choice
}

// calibration_source file: a differing camera_info is said once and never used; camera_info: the
// driver's calibration replaces the file's.
TEST(CalibrationSource, TheChosenSourceWins) {
  NodeOptions o;
  o.camera_intrinsics = {500, 500, 320, 240};
  o.camera_resolution = {640, 480};
  o.extrinsic_source = "parameters";
  std_msgs::Header h;
  h.frame_id = "camera";
  const sensor_msgs::CameraInfo factory = toCameraInfo(pinholeIntrinsics(640, 480, 480.0), h);
  const sensor_msgs::CameraInfo same = toCameraInfo(pinholeIntrinsics(640, 480, 500.0), h);

  o.calibration_source = "file";
  CalibrationSource file(o);
  EXPECT_EQ(file.ready("camera", "imu", nullptr), "");
  const CameraInfoUse first = file.cameraInfo(factory);
  EXPECT_TRUE(first.ignored);
  EXPECT_FALSE(first.changed);
  EXPECT_NE(first.ignored_once.find("ignored"), std::string::npos);
  const CameraInfoUse second = file.cameraInfo(factory);
  EXPECT_TRUE(second.ignored);
  EXPECT_EQ(second.ignored_once, "");  // said once
  EXPECT_EQ(file.intrinsics().fx, 500.0);
  EXPECT_FALSE(file.cameraInfo(same).ignored);
  EXPECT_NE(file.summary().find("ignored"), std::string::npos);

  o.calibration_source = "camera_info";
  CalibrationSource driver(o);
  EXPECT_EQ(driver.intrinsics().fx, 500.0);  // until camera_info arrives
  const CameraInfoUse taken = driver.cameraInfo(factory);
  EXPECT_TRUE(taken.changed);
  EXPECT_FALSE(taken.ignored);
  EXPECT_EQ(driver.intrinsics().fx, 480.0);

  // calibration_source file without a file is refused at load time.
  YamlParams yaml;
  yaml.set("calibration_source", "file");
  NodeParams p;
  EXPECT_NE(loadParams(yaml, &p).find("calibration_source file needs"), std::string::npos);
}

std::vector<std::string> presets() { return rigPresets(kSource); }

TEST(RigPresets, EachLoadsAndValidatesOnTopOfTheDefaults) {
  const std::vector<std::string> names = presets();
  for (const char* expected : {"d435i", "d455", "tum_vi", "euroc", "dmvio_handheld"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  }
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    YamlParams yaml(kSource + "/config/vi_ekf_slam.yaml");
    yaml.overlay(YamlParams(rigFile(name, kSource)));
    NodeParams p;
    EXPECT_EQ(loadParams(yaml, &p), "");
    // A preset with its intrinsics in the file can be built into a camera.
    std::optional<CameraIntrinsics> k;
    EXPECT_EQ(intrinsicsFromOptions(p.node, &k), "");
  }
  EXPECT_THROW(rigFile("no_such_rig", kSource), std::runtime_error);
  EXPECT_EQ(rigFile("/my/rig.yaml", kSource), "/my/rig.yaml");
}

/// A topic name as a node at the root resolves it (the node's defaults are relative).
std::string atRoot(const std::string& topic) { return topic.rfind('/', 0) == 0 ? topic : "/" + topic; }

/// A synthetic walk written as a bag under the preset's topic names and frames: the camera is the
/// preset's where it holds intrinsics and T_b_c; /tf_static has IMU <- camera and, for a driver
/// tree (base_frame set), base <- IMU.

std::string presetBag(const std::string& name, const NodeParams& p) {
  test::RigOptions o;
  o.duration_s = 7.0;
  std::optional<CameraIntrinsics> k;
  intrinsicsFromOptions(p.node, &k);
  o.camera = k;
  if (p.node.extrinsic_source == "parameters") {
    const auto& v = p.node.T_b_c;
    CameraExtrinsics T;
    T.p_b_c = Vec3(v[0], v[1], v[2]);
    T.R_b_c = Quat(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
    o.T_b_c = T;
  }
  o.imu_frame = p.node.body_frame.empty() ? name + "_imu_frame" : p.node.body_frame;
  o.camera_frame = name + "_camera_frame";
  const test::RigStream s = test::makeRigStream(o, 100.0);
  const std::string path = test::programScratch() / ("preset_" + name + ".bag");
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(s.imu_camera);
  tf.transforms.back().header.stamp = ros::Time(100.0);
  if (!p.node.base_frame.empty()) {
    geometry_msgs::TransformStamped b;
    b.header = tf.transforms.back().header;
    b.header.frame_id = p.node.base_frame;
    b.child_frame_id = o.imu_frame;
    b.transform.rotation.w = 1.0;
    tf.transforms.push_back(b);
  }
  bag.write("/tf_static", ros::Time(100.0), tf);
  for (const test::RigMessage& m : s.messages) {
    const ros::Time t(100.0 + m.play_t);
    if (auto* imu = std::get_if<sensor_msgs::Imu>(&m.msg)) bag.write(atRoot(p.node.imu_topic), t, *imu);
    if (auto* img = std::get_if<sensor_msgs::Image>(&m.msg)) bag.write(atRoot(p.node.image_topic), t, *img);
    if (auto* ci = std::get_if<sensor_msgs::CameraInfo>(&m.msg)) bag.write(atRoot(p.node.camera_info_topic), t, *ci);
  }
  // Topics the preset does not use, as a real recording has them: the choice must not be ambiguous.
  sensor_msgs::Imu other;
  other.header.stamp = ros::Time(100.0);
  bag.write("/other/imu", ros::Time(100.0), other);
  return path;
}

TEST(RigPresets, ASyntheticBagWithEachPresetsTopicsAndFramesGivesOdometry) {
  ros::Time::init();
  for (const std::string& name : presets()) {
    SCOPED_TRACE(name);
    YamlParams yaml(kSource + "/config/vi_ekf_slam.yaml");
    yaml.overlay(YamlParams(rigFile(name, kSource)));
    NodeParams p = load(yaml);
    p.node.tune_allocator = false;
    const std::string bag = presetBag(name, p);
    InputTopics preferred;
    preferred.imu = p.node.imu_topic;
    preferred.image = p.node.image_topic;
    preferred.camera_info = p.node.camera_info_topic;
    const InputTopics topics = chooseInputTopics(bag, std::nullopt, std::nullopt, std::nullopt, &preferred);
    EXPECT_EQ(topics.imu, atRoot(p.node.imu_topic)) << topics.imu_why;
    EXPECT_EQ(topics.image, atRoot(p.node.image_topic)) << topics.image_why;
    RecordingSink sink;
    tf2::BufferCore tf;
    EkfSlamProcessor processor(p, sink, &tf);
    replayBag(bag, topics, processor, tf);
    EXPECT_GT(sink.poses.size(), 60u) << "of " << processor.counters().images_received << " images";
    EXPECT_EQ(sink.resets, 0);
    if (!sink.poses.empty()) {
      // The walk goes about 1.3 m/s for 5 s: the odometry moves by metres, finitely.
      const double moved = (sink.poses.back().p - sink.poses.front().p).norm();
      std::printf("%s: %zu poses, moved %.2f m\n", name.c_str(), sink.poses.size(), moved);
      EXPECT_TRUE(std::isfinite(moved));
      EXPECT_GT(moved, 2.0);
    }
    fs::remove(bag);
  }
}

}  // namespace
}  // namespace vi_ekf_slam::glue
