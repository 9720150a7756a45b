// Writing the standard input topics of a rig to a rosbag, shared by the simulator's bag writer
// and the ASL/EuRoC converter so both produce what real drivers publish.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <opencv2/core.hpp>
#include <rosbag/bag.h>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/types.h"
#include "vi_ekf_slam/eval/run_evaluation.h"
#include "vi_ekf_slam/io/tum_io.h"
#include "vi_ekf_slam/sim/hallway.h"

namespace vi_ekf_slam::glue {

struct RigTopics {
  std::string imu = "/imu";
  std::string image = "/camera/image_raw";
  std::string camera_info = "/camera/camera_info";
  std::string ground_truth = "/ground_truth/pose";
  std::string imu_frame = "imu";
  std::string camera_frame = "camera";
  std::string world_frame = "world";
};

class RigBagWriter {
 public:
  /// Opens the bag and writes /tf_static (imu <- camera) at `start`.
  RigBagWriter(const std::string& path, const RigTopics& topics, const CameraModel& camera,
               const CameraExtrinsics& T_b_c, const ImuNoiseParams& noise, double imu_rate_hz, const ros::Time& start);
  /// sensor_msgs/Imu with REP-145 conventions (no orientation, covariances from the noise).
  void imu(const ImuData& d);
  /// mono8 image and its camera_info at t [s].
  void image(double t, const cv::Mat& mono8);
  /// Ground-truth body pose in the z-up world frame.
  void groundTruth(double t, const Vec3& p_w_b, const Quat& q_w_b);
  /// Any std_msgs/String (e.g. the scenario description).
  void text(const std::string& topic, double t, const std::string& s);

 private:
  rosbag::Bag bag_;
  RigTopics topics_;
  CameraModel camera_;
  double gyro_var_, accel_var_;
};

/// What an input bag says about itself: ground truth (z-up world), the simulated world if any,
/// the camera calibration and the camera-IMU extrinsic (from /tf_static).
struct InputBagInfo {
  std::vector<io::StampedPose> truth;
  std::vector<sim::Quad> world;  ///< in {n}; empty for real data
  std::optional<CameraIntrinsics> camera;
  std::optional<CameraExtrinsics> T_b_c;
  double start = 0.0, end = 0.0;
};
/// Throws std::runtime_error if the bag cannot be read.
InputBagInfo readInputBag(const std::string& path, const RigTopics& topics = RigTopics());

/// True landmark positions in the truth world frame: the ray of each landmark's first
/// observation from the true camera pose, cast into the simulated world. Empty function if the
/// bag has no world or calibration.
eval::LandmarkTruth landmarkTruthFromWorld(const InputBagInfo& info);

}  // namespace vi_ekf_slam::glue
