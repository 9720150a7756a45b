// Parameters of the node: read from the private namespace, validated (every impossible value is
// reported at once), echoed at startup, and updated from dynamic_reconfigure.
#pragma once

#include <ros/node_handle.h>
#include <yaml-cpp/yaml.h>
#include <map>
#include <string>
#include <vector>

#include "vi_ekf_slam/EkfSlamReconfigureConfig.h"
#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/feature_tracker.h"
#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"
#include "vi_ekf_slam/core/static_initializer.h"
#include "vi_ekf_slam/core/vio_pipeline.h"
#include "vi_ekf_slam/core/vio_pipeline.h"
#include "vi_ekf_slam/ros/output_frames.h"

namespace vi_ekf_slam::glue {

struct NodeOptions {
  // Relative names, resolved in the node's namespace: `image:=/cam0/image_raw` remaps them as it
  // would any driver-agnostic node's; a rig file or launch argument names another topic instead.
  std::string imu_topic = "imu";                  ///< sensor_msgs/Imu
  std::string image_topic = "image";              ///< image_transport base topic
  std::string camera_info_topic = "camera_info";  ///< sensor_msgs/CameraInfo
  /// What the outputs are expressed in and which TF is broadcast (see output_frames.h): odom
  /// (REP-105: odom_frame -> base_frame), none (the same frames, no TF), world (world_frame -> IMU).
  TfMode publish_tf = TfMode::kOdom;
  std::string odom_frame = "odom";    ///< REP-105 odom: the pose of the base is continuous in it
  std::string base_frame;             ///< the robot's base ("": the IMU frame); base <- IMU from TF
  std::string map_frame;              ///< if set (odom mode), map -> odom: identity, or the kept map's placement
  std::string map_file;               ///< keep_map: loaded at start if it exists, written by ~save_map
  std::string world_frame = "world";  ///< publish_tf world: the filter's world, z up
  /// The IMU/body frame; "": the frame_id of the IMU messages ("imu" if they carry none).
  std::string body_frame;
  bool tune_allocator = true;           ///< see platform/allocator_tuning.h
  std::string camera_calibration_file;  ///< ROS camera YAML (intrinsics from a file)
  /// "camera_info": the driver's camera_info wins over a file; "file": the file's intrinsics are
  /// used and a differing camera_info is reported once and ignored.
  std::string calibration_source = "camera_info";
  std::vector<double> camera_intrinsics;              ///< fx fy cx cy [px] (intrinsics from the parameters)
  std::vector<double> camera_resolution;              ///< width height [px]
  std::string camera_distortion_model = "radtan";     ///< "radtan" (plumb_bob) or "equidistant"
  std::vector<double> camera_distortion_coeffs;       ///< radtan k1 k2 p1 p2 [k3]; equidistant k1..k4
  std::string kalibr_camchain;                        ///< Kalibr camchain-imucam.yaml (see kalibr_import.h)
  std::string kalibr_imu;                             ///< Kalibr imu.yaml
  std::string extrinsic_source = "tf";                ///< "tf" (body_frame <- image frame_id) or "parameters"
  std::string image_transport = "raw";                ///< "raw" or "compressed"
  std::vector<double> T_b_c = {0, 0, 0, 0, 0, 0, 1};  ///< x y z qx qy qz qw of the camera in the body [m]
  int max_image_queue = 20;                           ///< images waiting for IMU beyond this are dropped
  double time_jump_reset_s = 1.0;                     ///< a stamp this far backwards resets the filter [s]
  int path_max_length = 2000;                         ///< poses kept in the published path
  double max_image_gap_s = 0.5;                       ///< longer gaps between processed images are reported [s]
  double min_imu_rate_hz = 100.0;                     ///< the diagnostics warn below this IMU rate [Hz]
  double min_image_rate_hz = 5.0;                     ///< the diagnostics warn below this image rate [Hz]
};

struct NodeParams {
  EkfSlamConfig filter;
  TrackerParams tracker;
  StaticInitParams static_init;
  bool dynamic_init_enabled = true;  ///< also initialize while moving (visual-inertial alignment)
  DynamicInitParams dynamic_init;
  /// After a blind stretch, new tracks wait for the re-anchor at most this long [s] (PipelineParams).
  double reanchor_max_wait_s = PipelineParams().reanchor_max_wait_s;
  NodeOptions node;
  /// Not a parameter: the live node sets it, the offline runner does not (PipelineParams).
  bool background_start_attempts = false;
};

/// Where parameters come from: the parameter server (the node) or YAML files (offline tools).
/// get() returns false when the parameter exists but has another type.
class ParamSource {
 public:
  virtual ~ParamSource() = default;
  /// Every name set (top level), so that unknown ones are reported.
  virtual std::vector<std::string> names() const = 0;
  virtual bool has(const std::string& name) const = 0;
  virtual bool get(const std::string& name, double& v) const = 0;
  virtual bool get(const std::string& name, int& v) const = 0;
  virtual bool get(const std::string& name, bool& v) const = 0;
  virtual bool get(const std::string& name, std::string& v) const = 0;
  virtual bool get(const std::string& name, std::vector<double>& v) const = 0;
};

/// The private namespace of a node.
class NodeHandleParams : public ParamSource {
 public:
  explicit NodeHandleParams(const ros::NodeHandle& nh) : nh_(nh) {}
  std::vector<std::string> names() const override;
  bool has(const std::string& name) const override { return nh_.hasParam(name); }
  bool get(const std::string& name, double& v) const override;
  bool get(const std::string& name, int& v) const override { return nh_.getParam(name, v); }
  bool get(const std::string& name, bool& v) const override { return nh_.getParam(name, v); }
  bool get(const std::string& name, std::string& v) const override { return nh_.getParam(name, v); }
  bool get(const std::string& name, std::vector<double>& v) const override { return nh_.getParam(name, v); }

 private:
  ros::NodeHandle nh_;
};

/// A YAML parameter file as written in config/ (a map of names to scalars and lists), read with
/// yaml-cpp. Throws std::runtime_error naming the file when it cannot be read.
class YamlParams : public ParamSource {
 public:
  YamlParams() = default;
  explicit YamlParams(const std::string& path);
  /// Sets one value, written as in YAML (`1.5`, `true`, `[0, 1]`, `name`).
  void set(const std::string& name, const std::string& value);
  /// Takes every value of `other` (a rig file on top of the defaults).
  void overlay(const YamlParams& other) {
    for (const auto& [k, v] : other.values_) values_[k] = v;
  }
  std::vector<std::string> names() const override;
  bool has(const std::string& name) const override { return values_.count(name) > 0; }
  bool get(const std::string& name, double& v) const override;
  bool get(const std::string& name, int& v) const override;
  bool get(const std::string& name, bool& v) const override;
  bool get(const std::string& name, std::string& v) const override;
  bool get(const std::string& name, std::vector<double>& v) const override;

 private:
  std::map<std::string, YAML::Node> values_;
};

/// `top` where it has a value, else `below` (the values of Kalibr files over the other parameters).
class LayeredParams : public ParamSource {
 public:
  LayeredParams(const ParamSource& top, const ParamSource& below) : top_(top), below_(below) {}
  std::vector<std::string> names() const override;
  bool has(const std::string& name) const override { return top_.has(name) || below_.has(name); }
  bool get(const std::string& name, double& v) const override { return from(name).get(name, v); }
  bool get(const std::string& name, int& v) const override { return from(name).get(name, v); }
  bool get(const std::string& name, bool& v) const override { return from(name).get(name, v); }
  bool get(const std::string& name, std::string& v) const override { return from(name).get(name, v); }
  bool get(const std::string& name, std::vector<double>& v) const override { return from(name).get(name, v); }

 private:
  const ParamSource& from(const std::string& name) const { return top_.has(name) ? top_ : below_; }
  const ParamSource& top_;
  const ParamSource& below_;
};

/// The rig file `rig` names: a path as given (it has a '/' or ends in .yaml), else the preset
/// <package_share>/config/rigs/<rig>.yaml. Throws std::runtime_error listing the presets when
/// there is no such preset.
std::string rigFile(const std::string& rig, const std::string& package_share);
/// The presets of <package_share>/config/rigs, sorted.
std::vector<std::string> rigPresets(const std::string& package_share);

/// Reads every parameter of the table (param_table.h; defaults where unset; where kalibr_camchain
/// or kalibr_imu is set, the values of those files replace the parameters they set). Returns the problems,
/// one per line (unknown names with the closest valid one, wrong types, values out of range,
/// impossible combinations), or an empty string.
std::string loadParams(const ParamSource& source, NodeParams* out);
/// Every effective value with its unit, one per line (the startup echo).
std::string describeParams(const NodeParams& p);
/// The start policy and queue of the core pipeline (VioPipeline) from the node's parameters.
PipelineParams pipelineParams(const NodeParams& p);
/// Every problem the core's own checks find in p's values (the filter's, the tracker's, the moving
/// start's and the pipeline's validate()), one per line ("" if none).
std::string coreProblems(const NodeParams& p);
/// Applies a dynamic_reconfigure update; returns the problems or an empty string.
std::string applyReconfigure(const EkfSlamReconfigureConfig& c, NodeParams* p);
/// The dynamic_reconfigure view of the current parameters.
EkfSlamReconfigureConfig toReconfigure(const NodeParams& p);

}  // namespace vi_ekf_slam::glue
