#include "vi_ekf_slam/ros/ekf_slam_ros.h"

#include <cv_bridge/cv_bridge.h>
#include <iomanip>
#include <sstream>
#include <std_msgs/String.h>
#include <stdexcept>
#include <tf2_eigen/tf2_eigen.h>

#include "vi_ekf_slam/ros/conversions.h"

namespace vi_ekf_slam::glue {

namespace {
/// An input silent this long while the node runs is named with its topic [s]: longer than any
/// driver's start, shorter than a user's patience.
constexpr double kInputSilenceS = 5.0;
}  // namespace

EkfSlamRos::EkfSlamRos(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh), pnh_(pnh), it_(nh), updater_(nh, pnh) {
  NodeParams params;
  const std::string err = loadParams(NodeHandleParams(pnh_), &params);
  if (!err.empty()) throw std::invalid_argument("vi_ekf_slam: impossible parameter values:\n" + err);
  ROS_INFO_STREAM(describeParams(params));
  // TF is read for the camera-IMU extrinsic, for base_frame <- IMU, and to find whether the frame
  // the node moves already has a parent.
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  if (params.node.publish_tf == TfMode::kOdom && !params.node.map_frame.empty() &&
      !params.filter.map.keptAcrossRuns()) {
    // No global localizer: map and odom coincide (REP-105). With the kept map, map -> odom goes
    // with the odometry (a relocalization moves it).
    geometry_msgs::TransformStamped t;
    t.header.stamp = ros::Time::now();
    t.header.frame_id = params.node.map_frame;
    t.child_frame_id = params.node.odom_frame;
    t.transform.rotation.w = 1.0;
    static_broadcaster_.sendTransform(t);
  }
  // Live: the sensor callbacks never wait for a moving-start attempt (it can take longer than a
  // camera period).
  params.background_start_attempts = true;
  processor_ = std::make_unique<EkfSlamProcessor>(params, *this, &tf_buffer_);

  updater_.setHardwareID("vi_ekf_slam");
  updater_.add("inputs", this, &EkfSlamRos::diagnoseInputs);
  imu_rate_min_hz_ = params.node.min_imu_rate_hz;
  image_rate_min_hz_ = params.node.min_image_rate_hz;
  using diagnostic_updater::FrequencyStatusParam;
  imu_rate_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      FrequencyStatusParam(&imu_rate_min_hz_, &no_max_hz_, 0.1, 5), "imu rate");
  image_rate_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      FrequencyStatusParam(&image_rate_min_hz_, &no_max_hz_, 0.1, 5), "image rate");
  updater_.add(*imu_rate_);
  updater_.add(*image_rate_);
  updater_.add("filter", this, &EkfSlamRos::diagnoseFilter);
  if (params.node.publish_tf != TfMode::kNone) updater_.add("tf", this, &EkfSlamRos::diagnoseTf);
  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odom", 50);
  odom_imu_pub_ = nh_.advertise<nav_msgs::Odometry>("odom_imu", 200);
  path_pub_ = nh_.advertise<nav_msgs::Path>("path", 2);
  landmarks_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("landmarks", 2);
  status_pub_ = nh_.advertise<vi_ekf_slam::FilterStatus>("status", 10);
  events_pub_ = nh_.advertise<std_msgs::String>("events", 10, true);
  tracks_pub_ = it_.advertise("tracks", 1);
  reset_srv_ = pnh_.advertiseService<std_srvs::Trigger::Request, std_srvs::Trigger::Response>(
      "reset", [this](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
        std::lock_guard<std::mutex> lock(mutex_);
        processor_->reset("reset service called");
        path_.poses.clear();
        updater_.force_update();
        res.success = true;
        res.message = processor_->params().dynamic_init_enabled
                          ? "filter reset; re-initializing at the next static interval or moving start"
                          : "filter reset; re-initializing at the next static interval";
        return true;
      });

  save_map_srv_ = pnh_.advertiseService<std_srvs::Trigger::Request, std_srvs::Trigger::Response>(
      "save_map", [this](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
        std::lock_guard<std::mutex> lock(mutex_);
        res.success = processor_->saveMap(&res.message);
        if (res.success) {
          ROS_INFO_STREAM("vi_ekf_slam: " << res.message);
        } else {
          ROS_WARN_STREAM("vi_ekf_slam: save_map: " << res.message);
        }
        return true;
      });

  // dynamic_reconfigure starts from the validated parameters. The server offers set_parameters as
  // soon as it is constructed: a request arriving before the callback is in place would be stored,
  // then overwritten by updateConfig and never applied (a `dynparam set` right after start
  // "succeeded" without effect), so the server's mutex is held until setup is complete and such a
  // request waits, then goes through the callback.
  {
    boost::recursive_mutex::scoped_lock setup(reconfigure_mutex_);
    reconfigure_ = std::make_unique<dynamic_reconfigure::Server<EkfSlamReconfigureConfig>>(reconfigure_mutex_, pnh_);
    reconfigure_->updateConfig(toReconfigure(params));
    reconfigure_->setCallback([this](EkfSlamReconfigureConfig& c, uint32_t) {
      std::lock_guard<std::mutex> lock(mutex_);
      const std::string e = processor_->reconfigure(c);
      if (!e.empty()) {
        ROS_ERROR_STREAM("vi_ekf_slam: reconfigure rejected:\n" << e);
        c = toReconfigure(processor_->params());
      }
    });
  }

  // The topics as resolved in the node's namespace, remaps applied: what the log and the
  // diagnostics name when an input stays silent.
  const std::string imu_topic = nh_.resolveName(params.node.imu_topic);
  const std::string info_topic = nh_.resolveName(params.node.camera_info_topic);
  // Resolved (and remapped) before image_transport sees it: it appends "/compressed" to the name it
  // is given, and a remap of "image" would not reach "image/compressed" otherwise.
  const std::string image_topic = nh_.resolveName(params.node.image_topic);
  input_watch_ = std::make_unique<InputWatch>(
      std::vector<InputWatch::Input>{{"imu", imu_topic, "remap imu:=YOUR_TOPIC or set ~imu_topic"},
                                     {"image", image_topic, "remap image:=YOUR_TOPIC or set ~image_topic"},
                                     {"camera_info", info_topic,
                                      "remap camera_info:=YOUR_TOPIC, set ~camera_info_topic, or give the "
                                      "intrinsics in the rig file"}},
      kInputSilenceS, ros::WallTime::now().toSec());
  imu_sub_ = nh_.subscribe<sensor_msgs::Imu>(
      imu_topic, 2000,
      [this](const sensor_msgs::ImuConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex_);
        input_watch_->arrived(kImuInput, ros::WallTime::now().toSec());
        imu_rate_->tick();
        processor_->imu(*m);
      },
      ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  info_sub_ = nh_.subscribe<sensor_msgs::CameraInfo>(info_topic, 5, [this](const sensor_msgs::CameraInfoConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    input_watch_->arrived(kCameraInfoInput, ros::WallTime::now().toSec());
    processor_->cameraInfo(*m);
  });
  image_sub_ = it_.subscribe(
      image_topic, 5,
      [this](const sensor_msgs::ImageConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex_);
        input_watch_->arrived(kImageInput, ros::WallTime::now().toSec());
        image_rate_->tick();
        processor_->image(*m);
      },
      ros::VoidPtr(), imageTransportHints());
  diag_timer_ = nh_.createTimer(ros::Duration(0.25), &EkfSlamRos::diagnosticsTimer, this);
  // On the wall clock: with /use_sim_time and no bag playing yet, ROS timers do not fire, and that
  // is when a user most needs to know which topic the node listens to.
  watch_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string waiting = waitingOn();
    const double now = ros::WallTime::now().toSec();
    // Every 10 s of wall time (ROS_WARN_THROTTLE counts ROS time, which stands still then).
    if (!waiting.empty() && now - last_waiting_log_s_ >= 10.0) {
      ROS_WARN_STREAM("vi_ekf_slam: " << waiting);
      last_waiting_log_s_ = now;
    }
  });
  ROS_INFO("vi_ekf_slam: inputs: imu %s, image %s (%s transport), camera_info %s", imu_topic.c_str(),
           image_sub_.getTopic().c_str(), image_sub_.getTransport().c_str(), info_topic.c_str());
}

image_transport::TransportHints EkfSlamRos::imageTransportHints() const {
  std::string transport = processor_->params().node.image_transport;
  if (transport == "compressed") transport = "vi_ekf_slam_compressed";
  // The transport is chosen here; TransportHints would read ~image_transport again, so it is
  // pointed at a parameter name nobody sets and falls back to the choice above.
  return image_transport::TransportHints(transport, ros::TransportHints(), pnh_, "image_transport_resolved_by_node");
}

void EkfSlamRos::odometry(const nav_msgs::Odometry& odom) {
  const NodeOptions& o = processor_->params().node;
  odom_pub_.publish(odom);
  if (o.publish_tf != TfMode::kNone && tfConflict(odom.header.frame_id, odom.child_frame_id).empty()) {
    // odom_frame -> base_frame, or world_frame -> IMU frame
    geometry_msgs::TransformStamped t;
    t.header = odom.header;
    t.child_frame_id = odom.child_frame_id;
    t.transform.translation.x = odom.pose.pose.position.x;
    t.transform.translation.y = odom.pose.pose.position.y;
    t.transform.translation.z = odom.pose.pose.position.z;
    t.transform.rotation = odom.pose.pose.orientation;
    tf_broadcaster_.sendTransform(t);
    tf_sent_ = true;
    if (o.publish_tf == TfMode::kOdom && !o.map_frame.empty() && processor_->params().filter.map.keptAcrossRuns()) {
      // map_frame -> odom_frame: where the kept map places odom (identity until a relocalization).
      const Eigen::Isometry3d T_m_o = processor_->outputFrames().odomFromMap().inverse();
      geometry_msgs::TransformStamped m = tf2::eigenToTransform(T_m_o);
      m.header.stamp = odom.header.stamp;
      m.header.frame_id = o.map_frame;
      m.child_frame_id = o.odom_frame;
      tf_broadcaster_.sendTransform(m);
    }
  }
  geometry_msgs::PoseStamped ps;
  ps.header = odom.header;
  ps.pose = odom.pose.pose;
  path_.header = odom.header;
  path_.poses.push_back(ps);
  const size_t max_len = static_cast<size_t>(o.path_max_length);
  if (path_.poses.size() > max_len)
    path_.poses.erase(path_.poses.begin(), path_.poses.end() - static_cast<long>(max_len));
  if (path_pub_.getNumSubscribers() > 0) path_pub_.publish(path_);
}

void EkfSlamRos::landmarks(const std::vector<LandmarkOutput>& lms, const ros::Time& stamp) {
  const OutputFrames& frames = processor_->outputFrames();
  landmarks_pub_.publish(toPointCloud(lms, stamp, frames.fixedFrame(), frames.fixedFromWorld()));
}

void EkfSlamRos::tracksImage(const std_msgs::Header& header, const cv::Mat& bgr) {
  tracks_pub_.publish(cv_bridge::CvImage(header, "bgr8", bgr).toImageMsg());
}

void EkfSlamRos::status(const vi_ekf_slam::FilterStatus& s) { status_pub_.publish(s); }

void EkfSlamRos::event(const std::string& text, double /*t_s*/) {
  std_msgs::String e;
  e.data = text;
  events_pub_.publish(e);
  if (text.rfind("reset", 0) == 0) {
    path_.poses.clear();
    updater_.force_update();
  }
}

const std::string& EkfSlamRos::tfConflict(const std::string& parent, const std::string& child) {
  if (tf_sent_ || !tf_conflict_.empty()) return tf_conflict_;
  std::string existing;
  if (tf_buffer_._getParent(child, ros::Time(), existing) && existing != parent) {
    tf_conflict_ = "'" + child + "' already has the parent '" + existing + "' on TF: " + parent + " -> " + child +
                   " is not broadcast (a frame has one parent). Set base_frame to the root of that tree (e.g. " +
                   "base_frame:=" + existing + ") or publish_tf:=none";
    ROS_ERROR_STREAM("vi_ekf_slam: " << tf_conflict_);
  }
  return tf_conflict_;
}

void EkfSlamRos::diagnoseTf(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  using diagnostic_msgs::DiagnosticStatus;
  // From startup on, before there is anything to broadcast: the frame the node will move.
  const OutputFrames& frames = processor_->outputFrames();
  const std::string child = frames.movedFrame(processor_->bodyFrame());
  if (!child.empty()) tfConflict(frames.fixedFrame(), child);
  if (!tf_conflict_.empty()) {
    stat.summary(DiagnosticStatus::ERROR, tf_conflict_);
  } else if (tf_sent_) {
    stat.summary(DiagnosticStatus::OK, "broadcasting");
  } else {
    stat.summary(DiagnosticStatus::OK, "nothing to broadcast yet (not initialized)");
  }
}

void EkfSlamRos::diagnosticsTimer(const ros::TimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  updater_.update();
}

std::string EkfSlamRos::waitingOn() {
  input_watch_->setNeeded(kCameraInfoInput, processor_->needsCameraInfo());
  return input_watch_->waitingOn(ros::WallTime::now().toSec());
}

void EkfSlamRos::diagnoseInputs(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const InputCounters& c = processor_->counters();
  const auto [level, summary] = processor_->inputsHealth();
  const std::string waiting = waitingOn();
  if (!waiting.empty() && level <= diagnostic_msgs::DiagnosticStatus::WARN) {
    stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, waiting);
  } else {
    stat.summary(static_cast<unsigned char>(level), summary);
  }
  for (const InputWatch::Input& in : input_watch_->inputs()) stat.add(in.name + " topic", in.topic);
  stat.add("imu received", c.imu_received);
  stat.add("imu dropped: non-finite", c.imu_nonfinite);
  stat.add("imu dropped: stale stamp", c.imu_stale);
  stat.add("imu gaps", c.imu_gaps);
  stat.add("imu bridged: clipped at the range", c.imu_clipped);
  stat.add("imu bridged: implausible", c.imu_implausible);
  stat.add("images received", c.images_received);
  stat.add("images processed", c.images_processed);
  stat.add("images dropped: bad encoding", c.images_bad_encoding);
  stat.add("images dropped: stale stamp", c.images_stale);
  stat.add("images dropped: arrived too late", c.images_late);
  stat.add("images dropped: before initialization", c.images_before_init);
  stat.add("images dropped: no camera calibration", c.images_no_camera);
  stat.add("images dropped: no IMU past stamp", c.images_queue_dropped);
  stat.add("camera_info invalid", c.camera_info_invalid);
  stat.add("camera_info ignored (calibration_source file)", c.camera_info_ignored);
  stat.add("calibration", processor_->calibrationSummary());
  stat.add("image gaps", c.image_gaps);
  stat.add("images without features", c.images_without_features);
  stat.add("outlier bursts", c.outlier_bursts);
  stat.add("last problem", processor_->lastProblem());
}

void EkfSlamRos::diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  using diagnostic_msgs::DiagnosticStatus;
  const EkfSlam* f = processor_->filter();
  if (!f || !f->initialized()) {
    const std::string start = processor_->params().dynamic_init_enabled
                                  ? "a static IMU interval or enough motion for the moving start"
                                  : "a static IMU interval";
    stat.summary(DiagnosticStatus::WARN,
                 processor_->lastLost().empty()
                     ? "not initialized (waiting for the camera and " + start + ")"
                     : "lost (" + processor_->lastLost() + "): reset, waiting for " + start + " to re-initialize");
  } else if (f->blindSince()) {
    std::ostringstream w;
    w << std::fixed << std::setprecision(2) << "blind for " << f->blindFor()
      << " s (no usable image feature): propagating on the IMU";
    stat.summary(DiagnosticStatus::WARN, w.str());
  } else {
    stat.summary(DiagnosticStatus::OK, "running");
  }
  stat.add("mechanization", toString(processor_->params().filter.mechanization));
  stat.add("landmark init", toString(processor_->params().filter.landmark_init));
  stat.add("landmarks in state", f ? f->state().numLandmarks() : 0);
  stat.add("tracks", processor_->lastTracks());
  stat.add("rejected observations", processor_->counters().rejected_observations);
  // narrow while the tracks show outliers (core/outlier_watch.h)
  stat.add("gate probability", f ? f->gateProbability() : processor_->params().filter.update.gate_probability);
  stat.add("compositions", f ? f->compositions() : 0);
  stat.add("zero-velocity updates (standing)", f ? f->zeroVelocityUpdates() : 0);
  stat.add("resets", processor_->counters().resets);
  stat.add("lost (divergence resets)", processor_->counters().divergences);
  stat.add("last lost", processor_->lastLost());
  stat.add("last update [ms]", processor_->lastUpdateMs());
  if (processor_->params().filter.map.keptAcrossRuns()) {
    const VioPipeline& p = processor_->pipeline();
    stat.add("kept map points", p.map().size());
    stat.add("in the kept map", p.inMap() ? "yes" : "no: not relocalized since the last reset");
    stat.add("relocalizations", p.relocalizations());
  }
}

}  // namespace vi_ekf_slam::glue
