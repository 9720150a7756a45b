#include "vi_ekf_slam/ros/ekf_slam_ros.h"

#include <camera_calibration_parsers/parse.h>
#include <cv_bridge/cv_bridge.h>
#include <chrono>
#include <std_msgs/String.h>
#include <stdexcept>

#include "vi_ekf_slam/FilterStatus.h"
#include "vi_ekf_slam/ros/conversions.h"

namespace vi_ekf_slam::glue {

EkfSlamRos::EkfSlamRos(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh), pnh_(pnh), it_(nh), tf_broadcaster_(), updater_(nh, pnh) {
  const std::string err = loadParams(pnh_, &params_);
  if (!err.empty()) throw std::invalid_argument("vi_ekf_slam: impossible parameter values:\n" + err);
  ROS_INFO_STREAM(describeParams(params_));
  static_init_ = StaticInitializer(params_.static_init);

  if (params_.node.extrinsic_source == "parameters") {
    const auto& v = params_.node.T_b_c;
    CameraExtrinsics T;
    T.p_b_c = Vec3(v[0], v[1], v[2]);
    T.R_b_c = Quat(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
    extrinsics_ = T;
  } else {
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  }
  if (!params_.node.camera_calibration_file.empty()) {
    std::string name;
    sensor_msgs::CameraInfo info;
    CameraIntrinsics in;
    if (!camera_calibration_parsers::readCalibration(params_.node.camera_calibration_file, name, info)) {
      throw std::invalid_argument("vi_ekf_slam: cannot read camera_calibration_file '" +
                                  params_.node.camera_calibration_file + "'");
    }
    const std::string e = intrinsicsFromCameraInfo(info, &in);
    if (!e.empty()) throw std::invalid_argument("vi_ekf_slam: camera_calibration_file: " + e);
    intrinsics_ = in;
    ROS_INFO("vi_ekf_slam: camera calibration from %s (%dx%d), used until camera_info arrives",
             params_.node.camera_calibration_file.c_str(), in.width, in.height);
  }

  updater_.setHardwareID("vi_ekf_slam");
  updater_.add("inputs", this, &EkfSlamRos::diagnoseInputs);
  updater_.add("filter", this, &EkfSlamRos::diagnoseFilter);

  odom_pub_ = nh_.advertise<nav_msgs::Odometry>("odom", 50);
  path_pub_ = nh_.advertise<nav_msgs::Path>("path", 2);
  landmarks_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("landmarks", 2);
  status_pub_ = nh_.advertise<vi_ekf_slam::FilterStatus>("status", 10);
  events_pub_ = nh_.advertise<std_msgs::String>("events", 10, true);
  tracks_pub_ = it_.advertise("tracks", 1);
  reset_srv_ = pnh_.advertiseService("reset", &EkfSlamRos::resetCallback, this);

  // dynamic_reconfigure calls back once from its constructor with the ~params loaded above.
  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<EkfSlamReconfigureConfig>>(reconfigure_mutex_, pnh_);
  reconfigure_->updateConfig(toReconfigure(params_));
  reconfigure_->setCallback([this](EkfSlamReconfigureConfig& c, uint32_t level) { reconfigureCallback(c, level); });

  imu_sub_ = nh_.subscribe("imu", 2000, &EkfSlamRos::imuCallback, this, ros::TransportHints().tcpNoDelay());
  info_sub_ = nh_.subscribe("camera_info", 5, &EkfSlamRos::cameraInfoCallback, this);
  // Resolve (and remap) the base topic first: image_transport appends "/compressed" to the name it
  // is given, and a remap of "image" would not reach "image/compressed" otherwise.
  image_sub_ = it_.subscribe(nh_.resolveName("image"), 5, &EkfSlamRos::imageCallback, this, image_transport::TransportHints("raw", ros::TransportHints(), pnh_));
  diag_timer_ = nh_.createTimer(ros::Duration(0.25), &EkfSlamRos::diagnosticsTimer, this);
  ROS_INFO("vi_ekf_slam: waiting for imu, image (%s transport) and camera_info", image_sub_.getTransport().c_str());
}

void EkfSlamRos::reportProblem(const std::string& what) {
  if (what != last_problem_) ROS_WARN_STREAM_THROTTLE(1.0, "vi_ekf_slam: " << what);
  last_problem_ = what;
}

void EkfSlamRos::resetFilter(const std::string& reason) {
  ROS_WARN_STREAM("vi_ekf_slam: reset: " << reason);
  if (filter_) filter_->reset();
  if (tracker_) tracker_->reset();
  static_init_.reset();
  static_result_.reset();
  queue_.clear();
  prev_q_n_b_.reset();
  path_.poses.clear();
  last_imu_t_ = last_image_t_ = -1e300;
  ++counters_.resets;
  std_msgs::String e;
  e.data = "reset: " + reason;
  events_pub_.publish(e);
  updater_.force_update();
}

bool EkfSlamRos::resetCallback(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  resetFilter("reset service called");
  res.success = true;
  res.message = "filter reset; re-initializing from the next static interval";
  return true;
}

void EkfSlamRos::reconfigureCallback(EkfSlamReconfigureConfig& config, uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  NodeParams next = params_;
  const std::string err = applyReconfigure(config, &next);
  if (!err.empty()) {
    ROS_ERROR_STREAM("vi_ekf_slam: reconfigure rejected:\n" << err);
    config = toReconfigure(params_);
    return;
  }
  const Mechanization before = params_.filter.mechanization;
  params_ = next;
  if (filter_) {
    std::string e;
    if (!filter_->setConfig(params_.filter, &e)) ROS_ERROR_STREAM("vi_ekf_slam: " << e);
  }
  if (tracker_) tracker_->setParams(params_.tracker);
  if (before != params_.filter.mechanization) {
    ROS_INFO("vi_ekf_slam: mechanization %s -> %s (state and map converted)", toString(before).c_str(),
             toString(params_.filter.mechanization).c_str());
    std_msgs::String e;
    e.data = "mechanization: " + toString(params_.filter.mechanization);
    events_pub_.publish(e);
  }
}

void EkfSlamRos::cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  CameraIntrinsics in;
  const std::string err = intrinsicsFromCameraInfo(*msg, &in);
  if (!err.empty()) {
    ++counters_.camera_info_invalid;
    reportProblem("camera_info ignored: " + err);
    return;
  }
  const bool changed = !intrinsics_ || in.fx != intrinsics_->fx || in.fy != intrinsics_->fy ||
                       in.cx != intrinsics_->cx || in.cy != intrinsics_->cy || in.width != intrinsics_->width ||
                       in.height != intrinsics_->height || in.distortion != intrinsics_->distortion ||
                       in.model != intrinsics_->model;
  if (!changed) return;
  if (filter_) {
    // A new calibration invalidates the map and the tracks.
    filter_.reset();
    tracker_.reset();
    ++counters_.resets;
  }
  intrinsics_ = in;
  intrinsics_from_topic_ = true;
  ROS_INFO("vi_ekf_slam: camera %dx%d fx=%.1f fy=%.1f from camera_info", in.width, in.height, in.fx, in.fy);
}

bool EkfSlamRos::cameraReady(const std::string& image_frame) {
  if (!intrinsics_) {
    reportProblem("no valid camera_info (and no camera_calibration_file) yet");
    return false;
  }
  if (!extrinsics_) {
    if (image_frame.empty()) {
      reportProblem("image has no frame_id: cannot look up the camera-IMU transform");
      return false;
    }
    if (image_frame == params_.node.body_frame) {
      extrinsics_ = CameraExtrinsics();
    } else {
      try {
        const auto t = tf_buffer_.lookupTransform(params_.node.body_frame, image_frame, ros::Time(0));
        extrinsics_ = extrinsicsFromTransform(t.transform);
        ROS_INFO("vi_ekf_slam: camera-IMU transform %s <- %s from TF", params_.node.body_frame.c_str(),
                 image_frame.c_str());
      } catch (const tf2::TransformException& e) {
        reportProblem("waiting for TF " + params_.node.body_frame + " <- " + image_frame + ": " + e.what());
        return false;
      }
    }
  }
  if (!filter_) {
    try {
      filter_ = std::make_unique<EkfSlam>(params_.filter, CameraModel(*intrinsics_), *extrinsics_);
      tracker_ = std::make_unique<FeatureTracker>(CameraModel(*intrinsics_), params_.tracker);
    } catch (const std::exception& e) {
      reportProblem(std::string("cannot start the filter: ") + e.what());
      filter_.reset();
      return false;
    }
  }
  return true;
}

void EkfSlamRos::tryInitialize(double t_now) {
  if (!filter_ || filter_->initialized() || !static_result_) return;
  // Only a recent static interval: if the rig moved since, wait for the next one.
  if (t_now - static_result_->timestamp > 0.5) return;
  NavState init;
  init.timestamp = static_result_->timestamp;
  init.q_n_b = static_result_->q_n_b;
  init.b_g = static_result_->b_g;
  filter_->initialize(init);
  prev_q_n_b_.reset();
  ROS_INFO("vi_ekf_slam: initialized from a %.1f s static interval (accel std %.3f m/s^2, gyro std %.4f rad/s)",
           params_.static_init.window_s, static_result_->accel_std_mps2, static_result_->gyro_std_radps);
  std_msgs::String e;
  e.data = "initialized";
  events_pub_.publish(e);
}

void EkfSlamRos::imuCallback(const sensor_msgs::ImuConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.imu_received;
  ++rate_imu_count_;
  const std::optional<ImuData> d = fromImuMsg(*msg);
  if (!d) {
    ++counters_.imu_nonfinite;
    reportProblem("IMU sample with NaN/Inf dropped");
    return;
  }
  if (d->timestamp <= last_imu_t_) {
    if (last_imu_t_ - d->timestamp > params_.node.time_jump_reset_s) {
      resetFilter("IMU time jumped back by " + std::to_string(last_imu_t_ - d->timestamp) + " s");
    } else {
      ++counters_.imu_stale;
      reportProblem("IMU sample not newer than the previous one dropped");
      return;
    }
  }
  if (last_imu_t_ > -1e299 && d->timestamp - last_imu_t_ > params_.filter.max_imu_gap_s) {
    ++counters_.imu_gaps;
    reportProblem("IMU gap of " + std::to_string(d->timestamp - last_imu_t_) + " s");
  }
  last_imu_t_ = d->timestamp;
  last_gyro_ = d->wm;
  if (auto r = static_init_.addImu(*d)) static_result_ = r;
  if (filter_) {
    filter_->addImu(*d);
    tryInitialize(d->timestamp);
    processQueue();
  }
}

void EkfSlamRos::imageCallback(const sensor_msgs::ImageConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counters_.images_received;
  ++rate_image_count_;
  const double t = msg->header.stamp.toSec() + params_.node.camera_time_offset_s;
  if (t <= last_image_t_) {
    if (last_image_t_ - t > params_.node.time_jump_reset_s) {
      resetFilter("image time jumped back by " + std::to_string(last_image_t_ - t) + " s");
    } else {
      ++counters_.images_stale;
      reportProblem("image not newer than the previous one dropped");
      return;
    }
  }
  last_image_t_ = t;
  PendingImage img{t, msg->header.stamp, cv::Mat()};
  const std::string err = toMono8(*msg, &img.mono);
  if (!err.empty()) {
    ++counters_.images_bad_encoding;
    reportProblem("image dropped: " + err);
    return;
  }
  if (!cameraReady(msg->header.frame_id)) {
    ++counters_.images_no_camera;
    return;
  }
  if (img.mono.cols != intrinsics_->width || img.mono.rows != intrinsics_->height) {
    ++counters_.images_no_camera;
    reportProblem("image size " + std::to_string(img.mono.cols) + "x" + std::to_string(img.mono.rows) +
                  " differs from the calibration " + std::to_string(intrinsics_->width) + "x" +
                  std::to_string(intrinsics_->height));
    return;
  }
  if (!filter_->initialized()) {
    ++counters_.images_before_init;
    reportProblem("waiting for a static IMU interval to initialize");
    return;
  }
  if (t < filter_->state().timestamp) {
    ++counters_.images_late;
    reportProblem("image older than the filter state dropped (arrived too late)");
    return;
  }
  queue_.push_back(std::move(img));
  while (static_cast<int>(queue_.size()) > params_.node.max_image_queue) {
    queue_.pop_front();
    ++counters_.images_queue_dropped;
    reportProblem("image dropped: no IMU data past its stamp");
  }
  processQueue();
}

void EkfSlamRos::processQueue() {
  while (!queue_.empty() && filter_ && filter_->initialized() && queue_.front().t <= filter_->latestImuTime()) {
    PendingImage img = std::move(queue_.front());
    queue_.pop_front();
    if (img.t < filter_->state().timestamp) {
      ++counters_.images_late;
      continue;
    }
    processImage(img);
  }
}

void EkfSlamRos::processImage(const PendingImage& img) {
  const auto tic = std::chrono::steady_clock::now();
  if (!filter_->propagateTo(img.t)) {
    ++counters_.images_late;
    return;
  }
  // Gyro-predicted camera rotation since the previous image seeds KLT.
  const Quat q_now = filter_->navState().q_n_b;
  std::optional<Eigen::Matrix3d> R_cur_prev;
  if (prev_q_n_b_) {
    const Mat3 R_b = (q_now.conjugate() * *prev_q_n_b_).toRotationMatrix();
    const Mat3& R_b_c = extrinsics_->R_b_c;
    R_cur_prev = R_b_c.transpose() * R_b * R_b_c;
  }
  const CameraFrame frame = tracker_->track(img.t, img.mono, R_cur_prev);
  last_tracks_ = tracker_->stats().total;
  const FrameResult r = filter_->processFrame(frame);
  last_update_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
  if (!r.processed) {
    reportProblem("frame not processed: " + r.error);
    return;
  }
  ++counters_.images_processed;
  counters_.rejected_observations += static_cast<long>(r.update.rejected_ids.size());
  const NavState nav = filter_->navState();
  if (!nav.p_n_b.allFinite() || !nav.q_n_b.coeffs().allFinite() || !nav.cov.allFinite()) {
    resetFilter("the filter state became non-finite");
    return;
  }
  prev_q_n_b_ = nav.q_n_b;
  publish(img, r, last_update_ms_);
}

void EkfSlamRos::publish(const PendingImage& img, const FrameResult& r, double update_ms) {
  const NavState nav = filter_->navState();
  const NodeOptions& o = params_.node;
  const double w_var = params_.filter.imu_noise.gyro_noise_density * params_.filter.imu_noise.gyro_noise_density * 200.0;
  nav_msgs::Odometry odom = toOdometry(nav, last_gyro_ - nav.b_g, w_var, img.stamp, o.world_frame, o.body_frame);
  if (!allFinite(odom)) {
    resetFilter("non-finite odometry");
    return;
  }
  odom_pub_.publish(odom);
  if (o.publish_tf) tf_broadcaster_.sendTransform(toTransform(nav, img.stamp, o.world_frame, o.body_frame));
  geometry_msgs::PoseStamped ps;
  ps.header = odom.header;
  ps.pose = odom.pose.pose;
  path_.header = odom.header;
  path_.poses.push_back(ps);
  if (static_cast<int>(path_.poses.size()) > o.path_max_length) {
    path_.poses.erase(path_.poses.begin(), path_.poses.begin() + (path_.poses.size() - o.path_max_length));
  }
  if (path_pub_.getNumSubscribers() > 0) path_pub_.publish(path_);
  if (landmarks_pub_.getNumSubscribers() > 0) landmarks_pub_.publish(toPointCloud(filter_->landmarks(), img.stamp, o.world_frame));
  if (tracks_pub_.getNumSubscribers() > 0) {
    cv_bridge::CvImage out(odom.header, "bgr8", tracker_->drawTracks(img.mono));
    tracks_pub_.publish(out.toImageMsg());
  }
  vi_ekf_slam::FilterStatus s;
  s.header = odom.header;
  s.mechanization = toString(filter_->mechanization());
  s.landmark_init = toString(params_.filter.landmark_init);
  s.initialized = filter_->initialized();
  s.landmarks_in_state = filter_->state().numLandmarks();
  s.tracks = last_tracks_;
  s.new_landmarks = static_cast<int>(r.new_ids.size());
  s.removed_landmarks = static_cast<int>(r.removed_ids.size());
  s.accepted_observations = r.update.accepted;
  s.rejected_observations = static_cast<int>(r.update.rejected_ids.size());
  s.compositions = filter_->compositions();
  s.resets = static_cast<int>(counters_.resets);
  s.update_time_ms = update_ms;
  const Vec3 g_b = nav.q_n_b.conjugate() * gravityInNav(params_.filter.gravity_mps2);
  s.gravity_body.x = g_b.x();
  s.gravity_body.y = g_b.y();
  s.gravity_body.z = g_b.z();
  s.accel_bias.x = nav.b_a.x();
  s.accel_bias.y = nav.b_a.y();
  s.accel_bias.z = nav.b_a.z();
  s.gyro_bias.x = nav.b_g.x();
  s.gyro_bias.y = nav.b_g.y();
  s.gyro_bias.z = nav.b_g.z();
  status_pub_.publish(s);
}

void EkfSlamRos::diagnosticsTimer(const ros::TimerEvent& ev) {
  std::lock_guard<std::mutex> lock(mutex_);
  const double now = ev.current_real.toSec();
  if (rate_window_start_ <= 0.0) rate_window_start_ = now;
  if (now - rate_window_start_ >= 1.0) {
    imu_rate_hz_ = rate_imu_count_ / (now - rate_window_start_);
    image_rate_hz_ = rate_image_count_ / (now - rate_window_start_);
    rate_imu_count_ = rate_image_count_ = 0;
    rate_window_start_ = now;
  }
  updater_.update();
}

void EkfSlamRos::diagnoseInputs(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const InputCounters& c = counters_;
  using diagnostic_msgs::DiagnosticStatus;
  if (c.imu_received == 0 || c.images_received == 0) {
    stat.summary(DiagnosticStatus::WARN, c.imu_received == 0 ? "no IMU received" : "no image received");
  } else if (c.images_bad_encoding > 0 || c.camera_info_invalid > 0 || c.images_no_camera > 0) {
    stat.summary(DiagnosticStatus::ERROR, last_problem_);
  } else if (c.imu_nonfinite + c.imu_stale + c.imu_gaps + c.images_stale + c.images_late + c.images_queue_dropped > 0) {
    stat.summary(DiagnosticStatus::WARN, last_problem_);
  } else {
    stat.summary(DiagnosticStatus::OK, "inputs ok");
  }
  stat.add("imu rate [Hz]", imu_rate_hz_);
  stat.add("image rate [Hz]", image_rate_hz_);
  stat.add("imu received", c.imu_received);
  stat.add("imu dropped: non-finite", c.imu_nonfinite);
  stat.add("imu dropped: stale stamp", c.imu_stale);
  stat.add("imu gaps", c.imu_gaps);
  stat.add("images received", c.images_received);
  stat.add("images processed", c.images_processed);
  stat.add("images dropped: bad encoding", c.images_bad_encoding);
  stat.add("images dropped: stale stamp", c.images_stale);
  stat.add("images dropped: arrived too late", c.images_late);
  stat.add("images dropped: before initialization", c.images_before_init);
  stat.add("images dropped: no camera calibration", c.images_no_camera);
  stat.add("images dropped: no IMU past stamp", c.images_queue_dropped);
  stat.add("camera_info invalid", c.camera_info_invalid);
  stat.add("last problem", last_problem_);
}

void EkfSlamRos::diagnoseFilter(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  using diagnostic_msgs::DiagnosticStatus;
  if (!filter_ || !filter_->initialized()) {
    stat.summary(DiagnosticStatus::WARN, "not initialized (waiting for camera and a static IMU interval)");
  } else {
    stat.summary(DiagnosticStatus::OK, "running");
  }
  stat.add("mechanization", toString(params_.filter.mechanization));
  stat.add("landmark init", toString(params_.filter.landmark_init));
  stat.add("landmarks in state", filter_ ? filter_->state().numLandmarks() : 0);
  stat.add("tracks", last_tracks_);
  stat.add("rejected observations", counters_.rejected_observations);
  stat.add("compositions", filter_ ? filter_->compositions() : 0);
  stat.add("resets", counters_.resets);
  stat.add("last update [ms]", last_update_ms_);
}

}  // namespace vi_ekf_slam::glue
