// The ROS glue's logic at the message level. It turns messages into the core pipeline's inputs
// (VioPipeline: queue, clock mapping, start policy, filter) through its parts, each with one job:
// InputClock (stamps: stale, restarts, gaps), CalibrationSource (intrinsics and extrinsic), the
// tracker; and the pipeline's results into outputs: OutputFrames (REP-105 frames) and the status
// (conversions). It counts every bad input and hands the results to an OutputSink. It owns no
// NodeHandle, so the live node (EkfSlamRos), the offline bag runner (tools/run_bag) and the
// gtests drive the very same code.
#pragma once

#include <chrono>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <string>
#include <tf2/buffer_core.h>
#include <unordered_map>
#include <vector>

#include "vi_ekf_slam/FilterStatus.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/feature_tracker.h"
#include "vi_ekf_slam/core/vio_pipeline.h"
#include "vi_ekf_slam/ros/calibration_source.h"
#include "vi_ekf_slam/ros/input_clock.h"
#include "vi_ekf_slam/ros/output_frames.h"
#include "vi_ekf_slam/ros/params.h"
#include <nav_msgs/Odometry.h>

namespace vi_ekf_slam::glue {

/// Counters shown in the diagnostics (and used by the tests).
struct InputCounters {
  long imu_received = 0, imu_nonfinite = 0, imu_stale = 0, imu_gaps = 0;
  long imu_clipped = 0, imu_implausible = 0;  ///< samples bridged (ImuSampleCheck)
  long images_received = 0, images_processed = 0, images_bad_encoding = 0, images_stale = 0;
  long images_late = 0, images_before_init = 0, images_no_camera = 0, images_queue_dropped = 0;
  long camera_info_invalid = 0, camera_info_ignored = 0, rejected_observations = 0, resets = 0;
  // Faults the filter rides through (reported, not dropped): no image for longer than
  // max_image_gap_s, images in which no feature could be tracked (camera covered, darkness), and
  // updates in which the gate rejected most observations (a burst of outlier tracks).
  long image_gaps = 0, images_without_features = 0, outlier_bursts = 0;
  long divergences = 0;  ///< resets because the filter was lost (DivergenceMonitor)
};

/// A landmark as published: its estimate and where its track started (time, pixel), which lets
/// an evaluation find its true position in a simulated world.
struct LandmarkOutput {
  NavLandmark landmark;
  double birth_time = 0.0;
  Eigen::Vector2d birth_uv = Eigen::Vector2d::Zero();
};

/// Where the results go: publishers in the node, files in the offline runner.
class OutputSink {
 public:
  virtual ~OutputSink() = default;
  virtual void odometry(const nav_msgs::Odometry& odom) = 0;
  virtual bool wantsLandmarks() const { return true; }
  virtual void landmarks(const std::vector<LandmarkOutput>& landmarks, const ros::Time& stamp) = 0;
  /// The IMU-rate pose (propagated from the last update at every IMU sample), when wanted.
  virtual bool wantsImuOdometry() const { return false; }
  virtual void imuOdometry(const nav_msgs::Odometry& /*odom*/) {}
  virtual bool wantsTracksImage() const { return false; }
  virtual void tracksImage(const std_msgs::Header& /*header*/, const cv::Mat& /*bgr*/) {}
  virtual void status(const vi_ekf_slam::FilterStatus& status) = 0;
  /// t_s: when it happened on the IMU clock (the filter's time, else the latest IMU stamp; NaN
  /// before any IMU sample) [s].
  virtual void event(const std::string& text, double t_s) = 0;
};

class EkfSlamProcessor : private PipelineListener {
 public:
  /// tf may be null when params.node.extrinsic_source is "parameters". Throws
  /// std::invalid_argument if the camera calibration file cannot be used.
  EkfSlamProcessor(const NodeParams& params, OutputSink& sink, const tf2::BufferCore* tf);

  void imu(const sensor_msgs::Imu& msg);
  void image(const sensor_msgs::Image& msg);
  /// A frame tracked elsewhere (another front end's feature tracks, a simulated camera): the same
  /// path as an image from the tracker on. header: the image's stamp (camera clock) and frame;
  /// the features' pixels are in the camera_info's calibration.
  void features(const CameraFrame& frame, const std_msgs::Header& header);
  void cameraInfo(const sensor_msgs::CameraInfo& msg);
  /// Forgets state, map, tracks and queue; re-initializes at the next static interval.
  void reset(const std::string& reason);
  /// Writes the kept map to map_file (~save_map); *message says how many points, or why not.
  bool saveMap(std::string* message) const;
  /// The core pipeline (its kept map, whether the filter is in it).
  const VioPipeline& pipeline() const { return *pipeline_; }
  /// Applies a dynamic_reconfigure update; returns the problems or an empty string.
  std::string reconfigure(const EkfSlamReconfigureConfig& config);

  const NodeParams& params() const { return params_; }
  const InputCounters& counters() const { return counters_; }
  const std::string& lastProblem() const { return last_problem_; }
  std::string calibrationSummary() const { return calibration_.summary(); }
  /// No intrinsics yet: images wait for a camera_info.
  bool needsCameraInfo() const { return !calibration_.hasIntrinsics(); }
  /// The inputs' health for the diagnostics: level (diagnostic_msgs::DiagnosticStatus OK 0, WARN 1,
  /// ERROR 2: nothing usable arrives) and its summary.
  std::pair<int, std::string> inputsHealth() const;
  /// The IMU frame: body_frame, or the frame_id of the first IMU message ("" before it).
  const std::string& bodyFrame() const { return body_frame_; }
  /// The frames of the outputs (odom or world) and the filter's world in them.
  const OutputFrames& outputFrames() const { return frames_; }
  /// Why the filter was last found lost (empty if never).
  const std::string& lastLost() const { return last_lost_; }
  const EkfSlam* filter() const { return pipeline_->hasCamera() ? &pipeline_->filter() : nullptr; }
  int lastTracks() const { return last_tracks_; }
  double lastUpdateMs() const { return last_update_ms_; }

 private:
  struct PendingImage {
    double t;
    std_msgs::Header header;  ///< the image's own (camera clock, camera frame)
    cv::Mat mono;
  };
  struct Birth {
    double t;
    Eigen::Vector2d uv;
  };

  bool cameraReady(const std::string& image_frame);
  /// The stamp check every frame passes (stale, restart); false: drop it.
  bool acceptImageStamp(double t);
  /// Hands a frame to the pipeline: `track` gives its features when the pipeline uses it.
  void queueFrame(const std::shared_ptr<PendingImage>& img,
                  std::function<CameraFrame(PendingImage&, const std::optional<Mat3>&)> track);
  /// odom_imu: the filter's state propagated to the latest IMU sample (when the sink wants it).
  void publishImuRatePose();
  double angularRateVariance() const;  ///< of one published angular-rate sample [rad^2/s^2]
  /// Shrinks img.mono to the tracking resolution (for the tracks image too) and tracks it.
  CameraFrame trackImage(PendingImage& img, const std::optional<Eigen::Matrix3d>& R_cur_prev);
  void output(const PendingImage& img, const CameraFrame& frame, const FrameResult& r);
  /// The published odometry of the IMU state `nav` (in the output frames), or nullopt when the
  /// base frame's transform is not known yet or a number is not finite.
  std::optional<nav_msgs::Odometry> odometryOf(const NavState& nav, const Vec3& w_b);
  void reportProblem(const std::string& what);
  /// Tells the sink what happened, at eventTime().
  void event(const std::string& text);
  /// The filter's time while it runs, else the latest IMU stamp (NaN before any) [s].
  double eventTime() const;
  /// Forgets what belongs to one run of the filter (tracks, births, stamps) and says why.
  void startOver(const std::string& reason);

  // PipelineListener: what the core pipeline decided.
  void started(StartKind kind, const std::string& event, EkfSlam& filter) override;
  void waiting(const std::string& why) override;
  void dropped(FrameDrop why) override;
  void processed(const CameraFrame& frame, const FrameResult& r, EkfSlam& filter) override;
  void lost(const std::string& why) override;
  void imuBridged(const ImuData& imu, ImuSampleVerdict why) override;
  void relocalized(const Relocalization& r, const std::string& event, EkfSlam& filter) override;
  void cameBack(const std::string& event, EkfSlam& filter) override;

  NodeParams params_;
  OutputSink& sink_;
  const tf2::BufferCore* tf_;
  CalibrationSource calibration_;
  InputClock clock_;
  std::unique_ptr<VioPipeline> pipeline_;
  std::unique_ptr<FeatureTracker> tracker_;
  std::shared_ptr<PendingImage> current_;  ///< the image the pipeline last asked to track
  std::unordered_map<std::int64_t, Birth> births_;
  Vec3 last_gyro_ = Vec3::Zero();
  double latest_imu_t_ = std::numeric_limits<double>::quiet_NaN();  ///< [s]
  std::optional<double> last_processed_t_;                          ///< stamp of the last processed image [s]
  int blind_prior_updates_ = 0;  ///< the motion prior's updates in the current blind stretch
  InputCounters counters_;
  int last_tracks_ = 0;
  double last_update_ms_ = 0.0, last_tracker_ms_ = 0.0;
  std::chrono::steady_clock::time_point frame_tic_;  ///< when the pipeline asked for the current image's tracks
  std::string last_problem_, last_lost_;
  std::string body_frame_;  ///< see bodyFrame()
  OutputFrames frames_;
};

}  // namespace vi_ekf_slam::glue
