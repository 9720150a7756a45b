#include "vi_ekf_slam/ros/ekf_slam_processor.h"

#include <camera_calibration_parsers/parse.h>
#include <chrono>
#include <ros/console.h>
#include <sstream>
#include <stdexcept>
#include <tf2/exceptions.h>

#include "vi_ekf_slam/core/allocator_tuning.h"
#include "vi_ekf_slam/ros/conversions.h"

namespace vi_ekf_slam::glue {

EkfSlamProcessor::EkfSlamProcessor(const NodeParams& params, OutputSink& sink, const tf2::BufferCore* tf)
    : params_(params),
      sink_(sink),
      tf_(tf),
      static_init_(params.static_init),
      frames_(params.node.publish_tf, params.node.world_frame, params.node.odom_frame, params.node.base_frame) {
  if (params_.node.tune_allocator) tuneAllocatorForLargeBuffers();
  body_frame_ = params_.node.body_frame;  // "": from the first IMU message
  if (params_.node.extrinsic_source == "parameters") {
    const auto& v = params_.node.T_b_c;
    CameraExtrinsics T;
    T.p_b_c = Vec3(v[0], v[1], v[2]);
    T.R_b_c = Quat(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
    extrinsics_ = T;
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
}

void EkfSlamProcessor::reportProblem(const std::string& what) {
  if (what != last_problem_) ROS_WARN_STREAM_THROTTLE(1.0, "vi_ekf_slam: " << what);
  last_problem_ = what;
}

void EkfSlamProcessor::reset(const std::string& reason) {
  ROS_WARN_STREAM("vi_ekf_slam: reset: " << reason);
  if (filter_) filter_->reset();
  if (tracker_) tracker_->reset();
  static_init_.reset();
  static_result_.reset();
  if (dynamic_init_) dynamic_init_->reset();
  first_uninitialized_image_t_.reset();
  queue_.clear();
  births_.clear();
  prev_q_n_b_.reset();
  last_imu_t_ = last_image_t_ = last_processed_t_ = -1e300;
  frames_.filterRestarted();
  ++counters_.resets;
  sink_.event("reset: " + reason);
}

std::string EkfSlamProcessor::reconfigure(const EkfSlamReconfigureConfig& config) {
  NodeParams next = params_;
  const std::string err = applyReconfigure(config, &next);
  if (!err.empty()) return err;
  const Mechanization before = params_.filter.mechanization;
  params_ = next;
  if (filter_) {
    std::string e;
    if (!filter_->setConfig(params_.filter, &e)) return e;
  }
  if (tracker_) tracker_->setParams(params_.tracker);
  if (before != params_.filter.mechanization) {
    ROS_INFO("vi_ekf_slam: mechanization %s -> %s (state and map converted)", toString(before).c_str(),
             toString(params_.filter.mechanization).c_str());
    sink_.event("mechanization: " + toString(params_.filter.mechanization));
  }
  return "";
}

void EkfSlamProcessor::cameraInfo(const sensor_msgs::CameraInfo& msg) {
  CameraIntrinsics in;
  const std::string err = intrinsicsFromCameraInfo(msg, &in);
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
    // A new calibration invalidates the map and the tracks: start over.
    filter_.reset();
    tracker_.reset();
    births_.clear();
    frames_.filterRestarted();
    ++counters_.resets;
    sink_.event("reset: camera calibration changed");
  }
  intrinsics_ = in;
  ROS_INFO("vi_ekf_slam: camera %dx%d fx=%.1f fy=%.1f from camera_info", in.width, in.height, in.fx, in.fy);
}

bool EkfSlamProcessor::cameraReady(const std::string& image_frame) {
  if (!intrinsics_) {
    reportProblem("no valid camera_info (and no camera_calibration_file) yet");
    return false;
  }
  if (!extrinsics_) {
    if (image_frame.empty()) {
      reportProblem("image has no frame_id: cannot look up the camera-IMU transform");
      return false;
    }
    if (body_frame_.empty()) {
      reportProblem("waiting for IMU messages (their frame_id is the IMU frame of the camera-IMU transform)");
      return false;
    }
    if (image_frame == body_frame_) {
      extrinsics_ = CameraExtrinsics();
    } else if (!tf_) {
      reportProblem("no TF available for the camera-IMU transform");
      return false;
    } else {
      try {
        const auto t = tf_->lookupTransform(body_frame_, image_frame, ros::Time(0));
        extrinsics_ = extrinsicsFromTransform(t.transform);
        ROS_INFO("vi_ekf_slam: camera-IMU transform %s <- %s from TF", body_frame_.c_str(), image_frame.c_str());
      } catch (const tf2::TransformException& e) {
        reportProblem("waiting for TF " + body_frame_ + " <- " + image_frame + ": " + e.what());
        return false;
      }
    }
  }
  if (!filter_) {
    try {
      // Tracker and filter share the camera of the tracked (possibly shrunk) image.
      const CameraModel camera(trackingIntrinsics(*intrinsics_, params_.tracker.max_image_width_px));
      filter_ = std::make_unique<EkfSlam>(params_.filter, camera, *extrinsics_);
      tracker_ = std::make_unique<FeatureTracker>(camera, params_.tracker);
      dynamic_init_ = std::make_unique<DynamicInitializer>(withFilterSettings(params_.dynamic_init, params_.filter),
                                                           camera, *extrinsics_);
    } catch (const std::exception& e) {
      reportProblem(std::string("cannot start the filter: ") + e.what());
      filter_.reset();
      return false;
    }
  }
  return true;
}

void EkfSlamProcessor::tryInitialize(double t_now) {
  if (!filter_ || filter_->initialized() || !static_result_) return;
  // Only a recent static interval: if the rig moved since, wait for the next one.
  if (t_now - static_result_->timestamp > 0.5) return;
  NavState init;
  init.timestamp = static_result_->timestamp;
  init.q_n_b = static_result_->q_n_b;
  init.b_g = static_result_->b_g;
  init.b_a = static_result_->b_a;
  filter_->initialize(init);
  prev_q_n_b_.reset();
  ROS_INFO("vi_ekf_slam: initialized from a %.1f s static interval (accel std %.3f m/s^2, gyro std %.4f rad/s)",
           params_.static_init.window_s, static_result_->accel_std_mps2, static_result_->gyro_std_radps);
  std::ostringstream e;
  e << "initialized: static, " << params_.static_init.window_s << " s at rest";
  sink_.event(e.str());
  first_uninitialized_image_t_.reset();
  // Tracks start with the filter, as the images that reached the dynamic initializer meanwhile
  // depend on when they arrived (a live replay and an offline run then differ).
  if (tracker_) tracker_->reset();
  if (dynamic_init_) dynamic_init_->reset();
}

void EkfSlamProcessor::imu(const sensor_msgs::Imu& msg) {
  ++counters_.imu_received;
  const std::optional<ImuData> d = fromImuMsg(msg);
  if (!d) {
    ++counters_.imu_nonfinite;
    reportProblem("IMU sample with NaN/Inf dropped");
    return;
  }
  if (d->timestamp <= last_imu_t_) {
    if (last_imu_t_ - d->timestamp > params_.node.time_jump_reset_s) {
      reset("IMU time jumped back by " + std::to_string(last_imu_t_ - d->timestamp) + " s");
      frames_.forget();  // a new recording (or a looped bag): odom starts over too
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
  if (last_imu_t_ > -1e299) {
    const double dt = d->timestamp - last_imu_t_;
    if (dt > 0.0 && dt <= params_.filter.max_imu_gap_s) {
      imu_period_s_ = imu_period_s_ > 0.0 ? 0.99 * imu_period_s_ + 0.01 * dt : dt;
    }
  }
  last_imu_t_ = d->timestamp;
  last_gyro_ = d->wm;
  if (body_frame_.empty()) {
    body_frame_ = !msg.header.frame_id.empty() ? msg.header.frame_id : "imu";
    ROS_INFO("vi_ekf_slam: IMU frame '%s' (the IMU messages' frame_id%s)", body_frame_.c_str(),
             msg.header.frame_id.empty() ? " is empty: the default" : "");
  }
  if (auto r = static_init_.addImu(*d)) static_result_ = r;
  if (dynamic_init_ && filter_ && !filter_->initialized()) dynamic_init_->addImu(*d);
  if (filter_) {
    filter_->addImu(*d);
    tryInitialize(d->timestamp);
    publishImuRatePose();
    processQueue();
  }
}

void EkfSlamProcessor::image(const sensor_msgs::Image& msg) {
  ++counters_.images_received;
  const double t = msg.header.stamp.toSec();  // camera clock; the filter maps it to the IMU clock
  if (t <= last_image_t_) {
    if (last_image_t_ - t > params_.node.time_jump_reset_s) {
      reset("image time jumped back by " + std::to_string(last_image_t_ - t) + " s");
      frames_.forget();
    } else {
      ++counters_.images_stale;
      reportProblem("image not newer than the previous one dropped");
      return;
    }
  }
  last_image_t_ = t;
  PendingImage img{t, msg.header, cv::Mat()};
  const std::string err = toMono8(msg, &img.mono);
  if (!err.empty()) {
    ++counters_.images_bad_encoding;
    reportProblem("image dropped: " + err);
    return;
  }
  if (!cameraReady(msg.header.frame_id)) {
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
    if (params_.dynamic_init_enabled) {
      tryDynamicInitialize(img);
    } else {
      reportProblem("waiting for a static IMU interval to initialize");
    }
    return;
  }
  if (filter_->imuTime(t) < filter_->state().timestamp) {
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

void EkfSlamProcessor::tryDynamicInitialize(PendingImage& img) {
  if (!first_uninitialized_image_t_) first_uninitialized_image_t_ = img.t;
  // The tracks it aligns are the tracks the filter goes on with: the same tracker, no gyro seed
  // (no attitude yet). Frames are on the IMU clock through the configured time offset.
  CameraFrame frame = trackImage(img, std::nullopt);
  frame.timestamp = filter_->imuTime(img.t);
  dynamic_init_->addFrame(frame);
  std::string why;
  const std::optional<DynamicInitResult> r = dynamic_init_->tryInitialize(&why);
  if (!r) {
    std::ostringstream w;
    w << "waiting to initialize: at rest for " << params_.static_init.window_s << " s, or moving: " << why;
    reportProblem(w.str());
    return;
  }
  if (r->state.timestamp < filter_->latestImuTime() - 1.0) return;  // the IMU no longer covers it
  const int added = filter_->initialize(*r, r->state);
  prev_q_n_b_ = r->state.q_n_b;
  last_processed_t_ = img.t;
  std::ostringstream e;
  e.precision(3);
  e << "initialized: dynamic, " << (img.t - *first_uninitialized_image_t_) << " s after the first image (" << r->frames
    << " images, " << r->features << " features, " << added << " landmarks, median depth " << r->median_depth_m
    << " m, velocity sigma " << r->velocity_sigma_mps << " m/s, roll/pitch sigma " << r->tilt_sigma_rad
    << " rad, time offset " << params_.filter.camera_time_offset_s + r->time_offset_correction_s << " s)";
  ROS_INFO_STREAM("vi_ekf_slam: " << e.str());
  sink_.event(e.str());
  first_uninitialized_image_t_.reset();
  static_result_.reset();
}

CameraFrame EkfSlamProcessor::trackImage(PendingImage& img, const std::optional<Eigen::Matrix3d>& R_cur_prev) {
  const auto tic = std::chrono::steady_clock::now();
  img.mono = toTrackingResolution(img.mono, tracker_->camera().intrinsics());
  CameraFrame frame = tracker_->track(img.t, img.mono, R_cur_prev);
  last_tracker_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
  last_tracks_ = tracker_->stats().total;
  return frame;
}

void EkfSlamProcessor::processQueue() {
  while (!queue_.empty() && filter_ && filter_->initialized() &&
         filter_->imuTime(queue_.front().t) <= filter_->latestImuTime()) {
    PendingImage img = std::move(queue_.front());
    queue_.pop_front();
    if (filter_->imuTime(img.t) < filter_->state().timestamp) {
      ++counters_.images_late;
      continue;
    }
    processImage(img);
  }
}

void EkfSlamProcessor::processImage(PendingImage& img) {
  const auto tic = std::chrono::steady_clock::now();
  if (!filter_->propagateTo(filter_->imuTime(img.t))) {
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
  const CameraFrame frame = trackImage(img, R_cur_prev);
  const FrameResult r = filter_->processFrame(frame);
  last_update_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
  total_processing_ms_ += last_update_ms_;
  if (!r.processed) {
    reportProblem("frame not processed: " + r.error);
    return;
  }
  ++counters_.images_processed;
  counters_.rejected_observations += static_cast<long>(r.update.rejected_ids.size());
  if (img.t - last_processed_t_ > params_.node.max_image_gap_s && last_processed_t_ > -1e299) {
    ++counters_.image_gaps;
    reportProblem("no image for " + std::to_string(img.t - last_processed_t_) + " s");
  }
  last_processed_t_ = img.t;
  if (frame.features.empty()) {
    ++counters_.images_without_features;
    reportProblem("no features tracked in the image (camera covered or dark?)");
  }
  const int rejected = static_cast<int>(r.update.rejected_ids.size());
  if (rejected >= 5 && rejected > r.update.accepted) {
    ++counters_.outlier_bursts;
    reportProblem("outlier burst: " + std::to_string(rejected) + " of " + std::to_string(rejected + r.update.accepted) +
                  " observations rejected by the gate");
  }
  if (!r.lost.empty()) {
    // Nothing of a lost filter is published: start over (re-initialization at the next static
    // interval), and say why in the events and the diagnostics.
    ++counters_.divergences;
    last_lost_ = r.lost;
    reset("lost: " + r.lost);
    return;
  }
  const NavState nav = filter_->navState();
  if (!nav.p_n_b.allFinite() || !nav.v_n_b.allFinite() || !nav.q_n_b.coeffs().allFinite() || !nav.b_g.allFinite() ||
      !nav.b_a.allFinite() || !nav.cov.allFinite()) {
    reset("the filter state became non-finite");
    return;
  }
  prev_q_n_b_ = nav.q_n_b;
  output(img, frame, r);
}

void EkfSlamProcessor::output(const PendingImage& img, const CameraFrame& frame, const FrameResult& r) {
  const NavState nav = filter_->navState();
  // Every output is stamped on the IMU clock, at the time of the state it carries (the image
  // stamp plus the estimated camera-IMU time offset).
  ros::Time stamp;
  stamp.fromSec(nav.timestamp);
  const std::optional<nav_msgs::Odometry> odom = odometryOf(nav, last_gyro_ - nav.b_g);
  if (odom) sink_.odometry(*odom);
  for (auto id : r.removed_ids) births_.erase(id);
  for (auto id : r.new_ids) {
    for (const auto& f : frame.features) {
      if (f.id == id) births_[id] = {img.t, f.uv};
    }
  }
  if (odom && sink_.wantsLandmarks()) {
    std::vector<LandmarkOutput> out;
    for (const auto& l : filter_->landmarks()) {
      LandmarkOutput lo;
      lo.landmark = l;
      auto it = births_.find(l.id);
      if (it != births_.end()) {
        lo.birth_time = it->second.t;
        lo.birth_uv = it->second.uv;
      }
      out.push_back(lo);
    }
    sink_.landmarks(out, stamp);
  }
  // The image's own header (stamp and camera frame), so that it overlays its source image.
  if (sink_.wantsTracksImage()) sink_.tracksImage(img.header, tracker_->drawTracks(img.mono));
  vi_ekf_slam::FilterStatus s;
  s.header.stamp = stamp;
  s.header.frame_id = frames_.fixedFrame();
  s.mechanization = toString(filter_->mechanization());
  s.landmark_init = toString(params_.filter.landmark_init);
  s.initialized = filter_->initialized();
  s.landmarks_in_state = filter_->state().numLandmarks();
  s.tracks = last_tracks_;
  s.new_landmarks = static_cast<int>(r.new_ids.size());
  s.deferred_features = r.deferred_features;
  s.removed_landmarks = static_cast<int>(r.removed_ids.size());
  s.accepted_observations = r.update.accepted;
  s.rejected_observations = static_cast<int>(r.update.rejected_ids.size());
  s.nis_per_dof = r.update.accepted > 0 ? r.update.nis_sum / (2.0 * r.update.accepted) : 0.0;
  s.time_offset_s = nav.t_d;
  s.time_offset_sigma_s = nav.t_d_sigma;
  s.compositions = filter_->compositions();
  s.stationary = r.zero_velocity_applied;
  s.parallax_px = r.stationary.parallax_px;
  s.zero_velocity_updates = filter_->zeroVelocityUpdates();
  s.resets = static_cast<int>(counters_.resets);
  s.update_time_ms = last_update_ms_;
  s.tracker_time_ms = last_tracker_ms_;
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
  sink_.status(s);
}

double EkfSlamProcessor::angularRateVariance() const {
  // The angular velocity published is one gyro sample: its variance is the noise density^2 times
  // the IMU's rate (measured; 200 Hz until known).
  const double rate_hz = imu_period_s_ > 0.0 ? 1.0 / imu_period_s_ : 200.0;
  return params_.filter.imu_noise.gyro_noise_density * params_.filter.imu_noise.gyro_noise_density * rate_hz;
}

void EkfSlamProcessor::publishImuRatePose() {
  if (!filter_ || !filter_->initialized() || !sink_.wantsImuOdometry()) return;
  Vec3 w_b;
  const std::optional<NavState> nav = filter_->predictedNavState(&w_b);
  if (!nav) return;
  if (const std::optional<nav_msgs::Odometry> odom = odometryOf(*nav, w_b)) sink_.imuOdometry(*odom);
}

std::optional<nav_msgs::Odometry> EkfSlamProcessor::odometryOf(const NavState& nav, const Vec3& w_b) {
  const std::string waiting = frames_.prepare(body_frame_, tf_);
  if (!waiting.empty()) {
    reportProblem(waiting);
    return std::nullopt;
  }
  ros::Time stamp;
  stamp.fromSec(nav.timestamp);
  const nav_msgs::Odometry imu =
      toOdometry(nav, w_b, angularRateVariance(), stamp, params_.node.world_frame, body_frame_);
  // The state was checked finite (processImage): this only guards what is derived from it.
  const nav_msgs::Odometry out = allFinite(imu) ? frames_.odometry(imu) : imu;
  if (!allFinite(out)) {
    reportProblem("non-finite odometry not published");
    return std::nullopt;
  }
  return out;
}

}  // namespace vi_ekf_slam::glue
