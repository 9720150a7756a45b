// Converts an ASL/EuRoC folder (mav0/ with cam0, imu0, state_groundtruth_estimate0) into a bag
// with the topics of a real rig (bag_io.h): camera_info from cam0/sensor.yaml, /tf_static from
// its T_BS, IMU covariances from imu0/sensor.yaml, ground truth as /ground_truth/pose.
//
//   vi_ekf_slam_asl_to_bag --asl FOLDER/mav0 --out FILE [--imu-margin S] [--start S] [--duration S]
//                          [--euroc-topics]
// IMU samples outside the camera's time span (plus the margin, default 1 s) are left out, so a
// short image sequence does not carry the whole IMU log. --start S cuts the recording S seconds
// after its first image: images and IMU both begin there, as when a node is started mid-walk;
// --duration S keeps S seconds of images from there.
// --euroc-topics writes the official EuRoC bags' topics (/imu0, /cam0/image_raw) and
// /cam0/camera_info, as a driver of that rig publishes them.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <opencv2/imgcodecs.hpp>

#include "cli.h"
#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/ros/bag_io.h"

using namespace vi_ekf_slam;

int main(int argc, char** argv) {
  std::string asl, out;
  double margin = 1.0, start = 0.0, duration = 0.0;
  bool euroc_topics = false;
  const std::string usage =
      "vi_ekf_slam_asl_to_bag --asl FOLDER/mav0 --out FILE [--imu-margin S] [--start S] [--duration S] "
      "[--euroc-topics]";
  cli::po::options_description opts("options");
  opts.add_options()("asl", cli::po::value(&asl)->required(), "the ASL folder (mav0 with cam0, imu0)")(
      "out", cli::po::value(&out)->required(), "the bag to write")(
      "imu-margin", cli::po::value(&margin)->default_value(margin), "IMU kept around the images [s]")(
      "start", cli::po::value(&start)->default_value(start),
      "cut everything before this time after the first image [s] (images and IMU begin together)")(
      "duration", cli::po::value(&duration)->default_value(duration),
      "keep this many seconds of images from the start (0: all) [s]")(
      "euroc-topics", cli::po::bool_switch(&euroc_topics),
      "the EuRoC bags' topics /imu0, /cam0/image_raw (and /cam0/camera_info) instead of /imu, /camera/...");
  cli::parse(argc, argv, usage, "Converts an ASL/EuRoC folder into a bag with the topics of a real rig.", opts);
  if (!(margin >= 0.0)) cli::fail(usage, "--imu-margin must be >= 0");
  if (!(start >= 0.0)) cli::fail(usage, "--start must be >= 0");
  if (!(duration >= 0.0)) cli::fail(usage, "--duration must be >= 0");
  try {
    const io::AslCamera cam = io::readAslCamera(asl + "/cam0/sensor.yaml");
    const ImuNoiseParams noise = io::readAslImuNoise(asl + "/imu0/sensor.yaml");
    std::vector<io::AslImage> images = io::readAslImages(asl + "/cam0");
    if (start > 0.0 && !images.empty()) {
      const double t_cut = images.front().t + start;
      images.erase(images.begin(),
                   std::find_if(images.begin(), images.end(), [&](const io::AslImage& i) { return i.t >= t_cut; }));
    }
    if (duration > 0.0 && !images.empty()) {
      const double t_end = images.front().t + duration;
      images.erase(std::find_if(images.begin(), images.end(), [&](const io::AslImage& i) { return i.t > t_end; }),
                   images.end());
    }
    const std::vector<ImuData> imu = io::readAslImu(asl + "/imu0/data.csv");
    std::vector<io::AslState> gt;
    try {
      gt = io::readAslGroundTruth(asl + "/state_groundtruth_estimate0/data.csv");
    } catch (const std::runtime_error& e) {
      std::cerr << "warning: no ground truth (" << e.what() << ")\n";
    }
    if (images.empty()) throw std::runtime_error("no images in " + asl + "/cam0");
    const double t0 = images.front().t - (start > 0.0 ? 0.0 : margin), t1 = images.back().t + margin;
    const double imu_rate = imu.size() > 1 ? (imu.size() - 1) / (imu.back().timestamp - imu.front().timestamp) : 200.0;
    glue::RigTopics topics;
    if (euroc_topics) {
      topics.imu = "/imu0";
      topics.image = "/cam0/image_raw";
      topics.camera_info = "/cam0/camera_info";
    }
    glue::RigBagWriter bag(out, topics, CameraModel(cam.intrinsics), cam.T_b_c, noise, imu_rate,
                           ros::Time(std::max(t0, imu.front().timestamp)));
    size_t n_imu = 0, n_img = 0, n_gt = 0, k = 0;
    for (const auto& img : images) {
      for (; k < imu.size() && imu[k].timestamp <= img.t; ++k) {
        if (imu[k].timestamp < t0) continue;
        bag.imu(imu[k]);
        ++n_imu;
      }
      const cv::Mat m = cv::imread(img.path, cv::IMREAD_GRAYSCALE);
      if (m.empty()) throw std::runtime_error("cannot read image " + img.path);
      bag.image(img.t, m);
      ++n_img;
    }
    for (; k < imu.size() && imu[k].timestamp <= t1; ++k, ++n_imu) bag.imu(imu[k]);
    for (const auto& s : gt) {
      if (s.t < t0 || s.t > t1) continue;
      bag.groundTruth(s.t, s.p, s.q);
      ++n_gt;
    }
    std::printf("asl_to_bag: %s: %zu images, %zu IMU samples, %zu ground-truth poses (%.2f s)\n", out.c_str(), n_img,
                n_imu, n_gt, images.back().t - images.front().t);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
