// The offline replay of a bag through the node's own processor: messages in bag order, no
// threads, no master, as fast as the CPU allows (vi_ekf_slam_run_bag), and what the processor
// outputs, kept for the evaluation.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <tf2/buffer_core.h>

#include "vi_ekf_slam/eval/run_evaluation.h"
#include "vi_ekf_slam/eval/run_health.h"
#include "vi_ekf_slam/ros/bag_io.h"
#include "vi_ekf_slam/ros/ekf_slam_processor.h"

namespace vi_ekf_slam::glue {

/// Keeps what the processor outputs: every pose (in the continuous odom frame the runner asks for,
/// across resets), the map since the last reset, the events with the time of the pose before them.
class RecordingSink : public OutputSink {
 public:
  struct Event {
    double t = 0.0;  ///< when it happened on the IMU clock (see OutputSink::event) [s]
    std::string text;
  };
  std::vector<eval::EstimatedPose> poses;
  std::map<std::int64_t, eval::EstimatedLandmark> map;
  std::vector<Event> events;
  std::vector<eval::StatusSample> trace;             ///< every processed image, across resets
  double speed_mps = 0.0, velocity_sigma_mps = 0.0;  ///< of the latest odometry [m/s]
  int resets = 0;
  /// If set, each pose is also kept in the filter's own world of the time (which starts over at
  /// every reset): `segments[k]` holds the poses after the k-th reset.
  const EkfSlamProcessor* processor = nullptr;
  std::vector<std::vector<io::StampedPose>> segments;

  void odometry(const nav_msgs::Odometry& o) override;
  void landmarks(const std::vector<LandmarkOutput>& lms, const ros::Time&) override;
  void status(const vi_ekf_slam::FilterStatus& s) override;
  void event(const std::string& text, double t_s) override;
};

/// The topics the processor is fed from, and why each was chosen (for the user: a topic that was
/// not the one asked for is said).
struct InputTopics {
  std::string imu, image, camera_info;
  std::string imu_why, image_why, camera_info_why;
};

/// The topics as requested (checked against the bag), else the preferred one where the bag has it
/// (the node's imu_topic, image_topic, camera_info_topic; a relative name is resolved as a node at
/// the root would, "imu" as "/imu"), else the one topic of each type the bag holds; several, or
/// none, is an error (std::runtime_error) that lists them. camera_info is optional.
InputTopics chooseInputTopics(const std::string& bag_path, const std::optional<std::string>& imu,
                              const std::optional<std::string>& image, const std::optional<std::string>& camera_info,
                              const InputTopics* preferred = nullptr);

/// Feeds the bag's IMU, images (raw or compressed), camera_info and TF to the processor in bag
/// order; returns the wall time it took [s]. `progress` (if set) is told the seconds of the bag
/// done and its length after each message.
double replayBag(const std::string& bag_path, const InputTopics& topics, EkfSlamProcessor& processor,
                 tf2::BufferCore& tf, const std::function<void(double done_s, double total_s)>& progress = {});

/// A recording of the node's outputs (odom, status, landmarks) evaluated against the input bag's
/// ground truth; *mean_tracks: tracks per image.
eval::RunMetrics evaluateRecording(const std::string& path, const InputBagInfo& info, double* mean_tracks);

}  // namespace vi_ekf_slam::glue
