#include "vi_ekf_slam/ros/ekf_slam_processor.h"

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
      calibration_(params.node),
      clock_(params.node.time_jump_reset_s, params.filter.max_imu_gap_s),
      start_(params),
      frames_(params.node.publish_tf, params.node.world_frame, params.node.odom_frame, params.node.base_frame) {
  if (params_.node.tune_allocator) tuneAllocatorForLargeBuffers();
  body_frame_ = params_.node.body_frame;  // "": from the first IMU message
}

std::pair<int, std::string> EkfSlamProcessor::inputsHealth() const {
  const InputCounters& c = counters_;
  if (c.imu_received == 0 || c.images_received == 0) {
    return {1, c.imu_received == 0 ? "no IMU received" : "no image received"};
  }
  if (c.images_bad_encoding > 0 || c.camera_info_invalid > 0 || c.images_no_camera > 0) return {2, last_problem_};
  if (c.imu_nonfinite + c.imu_stale + c.imu_gaps + c.images_stale + c.images_late + c.images_queue_dropped > 0) {
    return {1, last_problem_};
  }
  return {0, "inputs ok"};
}

void EkfSlamProcessor::reportProblem(const std::string& what) {
  if (what != last_problem_) ROS_WARN_STREAM_THROTTLE(1.0, "vi_ekf_slam: " << what);
  last_problem_ = what;
}

void EkfSlamProcessor::reset(const std::string& reason) {
  ROS_WARN_STREAM("vi_ekf_slam: reset: " << reason);
  if (filter_) filter_->reset();
  if (tracker_) tracker_->reset();
  start_.reset();
  queue_.clear();
  births_.clear();
  prev_q_n_b_.reset();
  clock_.reset();
  last_processed_t_.reset();
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
  bool changed = false;
  const std::string err = calibration_.cameraInfo(msg, &changed);
  if (!err.empty()) {
    ++counters_.camera_info_invalid;
    reportProblem("camera_info ignored: " + err);
    return;
  }
  if (changed && filter_) {
    // A new calibration invalidates the map and the tracks: start over.
    filter_.reset();
    tracker_.reset();
    births_.clear();
    frames_.filterRestarted();
    ++counters_.resets;
    sink_.event("reset: camera calibration changed");
  }
}

bool EkfSlamProcessor::cameraReady(const std::string& image_frame) {
  const std::string missing = calibration_.ready(image_frame, body_frame_, tf_);
  if (!missing.empty()) {
    reportProblem(missing);
    return false;
  }
  if (!filter_) {
    try {
      // Tracker and filter share the camera of the tracked (possibly shrunk) image.
      const CameraModel camera(trackingIntrinsics(calibration_.intrinsics(), params_.tracker.max_image_width_px));
      filter_ = std::make_unique<EkfSlam>(params_.filter, camera, calibration_.extrinsics());
      tracker_ = std::make_unique<FeatureTracker>(camera, params_.tracker);
      start_.setCamera(camera, calibration_.extrinsics());
    } catch (const std::exception& e) {
      reportProblem(std::string("cannot start the filter: ") + e.what());
      filter_.reset();
      return false;
    }
  }
  return true;
}

void EkfSlamProcessor::tryInitialize(double t_now) {
  if (!filter_ || filter_->initialized()) return;
  const std::optional<std::string> started = start_.tryStatic(*filter_, t_now);
  if (!started) return;
  prev_q_n_b_.reset();
  sink_.event(*started);
  // Tracks start with the filter, as the images that reached the dynamic initializer meanwhile
  // depend on when they arrived (a live replay and an offline run then differ).
  if (tracker_) tracker_->reset();
}

void EkfSlamProcessor::imu(const sensor_msgs::Imu& msg) {
  ++counters_.imu_received;
  const std::optional<ImuData> d = fromImuMsg(msg);
  if (!d) {
    ++counters_.imu_nonfinite;
    reportProblem("IMU sample with NaN/Inf dropped");
    return;
  }
  switch (clock_.imu(d->timestamp)) {
    case StampVerdict::kStale:
      ++counters_.imu_stale;
      reportProblem("IMU sample not newer than the previous one dropped");
      return;
    case StampVerdict::kJumpedBack:
      reset("IMU time jumped back by " + std::to_string(clock_.lastStepBack()) + " s");
      frames_.forget();  // a new recording (or a looped bag): odom starts over too
      clock_.imu(d->timestamp);
      break;
    case StampVerdict::kNext:
      break;
  }
  if (const auto gap = clock_.lastImuGap()) {
    ++counters_.imu_gaps;
    reportProblem("IMU gap of " + std::to_string(*gap) + " s");
  }
  last_gyro_ = d->wm;
  if (body_frame_.empty()) {
    body_frame_ = !msg.header.frame_id.empty() ? msg.header.frame_id : "imu";
    ROS_INFO("vi_ekf_slam: IMU frame '%s' (the IMU messages' frame_id%s)", body_frame_.c_str(),
             msg.header.frame_id.empty() ? " is empty: the default" : "");
  }
  start_.addImu(*d, filter_ && !filter_->initialized());
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
  switch (clock_.image(t)) {
    case StampVerdict::kStale:
      ++counters_.images_stale;
      reportProblem("image not newer than the previous one dropped");
      return;
    case StampVerdict::kJumpedBack:
      reset("image time jumped back by " + std::to_string(clock_.lastStepBack()) + " s");
      frames_.forget();
      clock_.image(t);
      break;
    case StampVerdict::kNext:
      break;
  }
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
  const CameraIntrinsics& k = calibration_.intrinsics();
  if (img.mono.cols != k.width || img.mono.rows != k.height) {
    ++counters_.images_no_camera;
    reportProblem("image size " + std::to_string(img.mono.cols) + "x" + std::to_string(img.mono.rows) +
                  " differs from the calibration " + std::to_string(k.width) + "x" + std::to_string(k.height));
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
  // The tracks it aligns are the tracks the filter goes on with: the same tracker, no gyro seed
  // (no attitude yet). Frames are on the IMU clock through the configured time offset.
  CameraFrame frame = trackImage(img, std::nullopt);
  frame.timestamp = filter_->imuTime(img.t);
  std::string waiting;
  const std::optional<std::string> started = start_.tryDynamic(*filter_, frame, img.t, &waiting);
  if (!started) {
    if (!waiting.empty()) reportProblem(waiting);
    return;
  }
  prev_q_n_b_ = start_.dynamicAttitude();
  last_processed_t_ = img.t;
  sink_.event(*started);
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
    const Mat3& R_b_c = calibration_.extrinsics().R_b_c;
    R_cur_prev = R_b_c.transpose() * R_b * R_b_c;
  }
  const CameraFrame frame = trackImage(img, R_cur_prev);
  const FrameResult r = filter_->processFrame(frame);
  last_update_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
  if (!r.processed) {
    reportProblem("frame not processed: " + r.error);
    return;
  }
  ++counters_.images_processed;
  counters_.rejected_observations += static_cast<long>(r.update.rejected_ids.size());
  if (last_processed_t_ && img.t - *last_processed_t_ > params_.node.max_image_gap_s) {
    ++counters_.image_gaps;
    reportProblem("no image for " + std::to_string(img.t - *last_processed_t_) + " s");
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
  StatusExtras x;
  x.landmark_init = params_.filter.landmark_init;
  x.tracks = last_tracks_;
  x.resets = counters_.resets;
  x.update_ms = last_update_ms_;
  x.tracker_ms = last_tracker_ms_;
  x.gravity_mps2 = params_.filter.gravity_mps2;
  vi_ekf_slam::FilterStatus s = toFilterStatus(*filter_, nav, r, x);
  s.header.stamp = stamp;
  s.header.frame_id = frames_.fixedFrame();
  sink_.status(s);
}

double EkfSlamProcessor::angularRateVariance() const {
  // The angular velocity published is one gyro sample: its variance is the noise density^2 times
  // the IMU's rate (measured; 200 Hz until known).
  const double rate_hz = clock_.imuPeriod() ? 1.0 / *clock_.imuPeriod() : 200.0;
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
