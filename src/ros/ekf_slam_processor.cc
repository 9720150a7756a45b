#include "vi_ekf_slam/ros/ekf_slam_processor.h"

#include <chrono>
#include <fstream>
#include <ros/console.h>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <tf2/exceptions.h>

#include "vi_ekf_slam/platform/allocator_tuning.h"
#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/ros/conversions.h"

namespace vi_ekf_slam::glue {

EkfSlamProcessor::EkfSlamProcessor(const NodeParams& params, OutputSink& sink, const tf2::BufferCore* tf)
    : params_(params),
      sink_(sink),
      tf_(tf),
      calibration_(params.node),
      clock_(params.node.time_jump_reset_s, params.filter.max_imu_gap_s),
      pipeline_(
          std::make_unique<VioPipeline>(params.filter, pipelineParams(params), static_cast<PipelineListener&>(*this))),
      frames_(params.node.publish_tf, params.node.world_frame, params.node.odom_frame, params.node.base_frame) {
  if (params_.node.tune_allocator) tuneAllocatorForLargeBuffers();
  body_frame_ = params_.node.body_frame;  // "": from the first IMU message
  // A map walked before: the first run is placed in it once it sees it. No file yet is the first
  // walk of the building (~save_map writes it); a file that is not a map is a configuration error.
  if (!params_.node.map_file.empty() && std::ifstream(params_.node.map_file).good()) {
    std::string error;
    if (!pipeline_->loadMap(params_.node.map_file, &error)) throw std::invalid_argument("map_file: " + error);
    ROS_INFO_STREAM("vi_ekf_slam: map_file " << params_.node.map_file << ": " << pipeline_->map().size()
                                             << " points; the filter is placed in it when it sees them");
  }
}

bool EkfSlamProcessor::saveMap(std::string* message) const {
  const std::string& path = params_.node.map_file;
  if (path.empty()) {
    *message = "no map_file parameter: nowhere to save the map";
    return false;
  }
  if (!params_.filter.map.within_run) {
    *message = "keep_map is off: no landmark has an appearance to be found again by";
    return false;
  }
  std::string error;
  int points = 0;
  if (!pipeline_->saveMap(path, &error, &points)) {
    *message = error;
    return false;
  }
  *message = "map saved to " + path + ": " + std::to_string(points) + " points";
  return true;
}

std::pair<int, std::string> EkfSlamProcessor::inputsHealth() const {
  const InputCounters& c = counters_;
  if (c.imu_received == 0 || c.images_received == 0) {
    return {1, c.imu_received == 0 ? "no IMU received" : "no image received"};
  }
  if (c.images_bad_encoding > 0 || c.camera_info_invalid > 0 || c.images_no_camera > 0) return {2, last_problem_};
  if (c.imu_nonfinite + c.imu_stale + c.imu_gaps + c.imu_clipped + c.imu_implausible + c.images_stale + c.images_late +
          c.images_queue_dropped >
      0) {
    return {1, last_problem_};
  }
  return {0, "inputs ok"};
}

void EkfSlamProcessor::reportProblem(const std::string& what) {
  if (what != last_problem_) ROS_WARN_STREAM_THROTTLE(1.0, "vi_ekf_slam: " << what);
  last_problem_ = what;
}

void EkfSlamProcessor::event(const std::string& text) { sink_.event(text, eventTime()); }

double EkfSlamProcessor::eventTime() const {
  if (pipeline_->hasCamera() && pipeline_->filter().initialized()) return pipeline_->filter().state().timestamp;
  return latest_imu_t_;
}

void EkfSlamProcessor::startOver(const std::string& reason) {
  ROS_WARN_STREAM("vi_ekf_slam: reset: " << reason);
  if (tracker_) tracker_->reset();
  births_.clear();
  clock_.reset();
  last_processed_t_.reset();
  frames_.filterRestarted();
  ++counters_.resets;
  event("reset: " + reason);
}

void EkfSlamProcessor::reset(const std::string& reason) {
  pipeline_->reset();
  startOver(reason);
}

namespace {
/// The tracker describes its corners and searches again only for a filter that keeps its map.
TrackerParams trackerParams(const NodeParams& p) {
  TrackerParams t = p.tracker;
  t.descriptors = p.filter.map.within_run;
  return t;
}
}  // namespace

std::string EkfSlamProcessor::reconfigure(const EkfSlamReconfigureConfig& config) {
  NodeParams next = params_;
  const std::string err = applyReconfigure(config, &next);
  if (!err.empty()) return err;
  const Mechanization before = params_.filter.mechanization;
  params_ = next;
  std::string e;
  if (!pipeline_->setConfig(params_.filter, &e)) return e;
  if (tracker_) tracker_->setParams(trackerParams(params_));
  if (before != params_.filter.mechanization) {
    ROS_INFO("vi_ekf_slam: mechanization %s -> %s (state and map converted)", toString(before).c_str(),
             toString(params_.filter.mechanization).c_str());
    event("mechanization: " + toString(params_.filter.mechanization));
  }
  return "";
}

void EkfSlamProcessor::cameraInfo(const sensor_msgs::CameraInfo& msg) {
  const CameraInfoUse use = calibration_.cameraInfo(msg);
  if (!use.error.empty()) {
    ++counters_.camera_info_invalid;
    reportProblem("camera_info ignored: " + use.error);
    return;
  }
  if (use.ignored) ++counters_.camera_info_ignored;
  if (!use.ignored_once.empty()) {
    ROS_WARN_STREAM("vi_ekf_slam: " << use.ignored_once);
    last_problem_ = use.ignored_once;
  }
  if (use.changed && pipeline_->hasCamera()) {
    // A new calibration invalidates the map and the tracks: start over.
    pipeline_->clearCamera();
    tracker_.reset();
    births_.clear();
    frames_.filterRestarted();
    ++counters_.resets;
    event("reset: camera calibration changed");
  }
}

bool EkfSlamProcessor::cameraReady(const std::string& image_frame) {
  const std::string missing = calibration_.ready(image_frame, body_frame_, tf_);
  if (!missing.empty()) {
    reportProblem(missing);
    return false;
  }
  if (!pipeline_->hasCamera()) {
    try {
      // Tracker and filter share the camera of the tracked (possibly shrunk) image.
      const CameraModel camera(trackingIntrinsics(calibration_.intrinsics(), params_.tracker.max_image_width_px));
      pipeline_->setCamera(camera, calibration_.extrinsics());
      tracker_ = std::make_unique<FeatureTracker>(camera, trackerParams(params_));
    } catch (const std::exception& e) {
      reportProblem(std::string("cannot start the filter: ") + e.what());
      pipeline_->clearCamera();
      return false;
    }
  }
  return true;
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
  latest_imu_t_ = d->timestamp;
  if (body_frame_.empty()) {
    body_frame_ = !msg.header.frame_id.empty() ? msg.header.frame_id : "imu";
    ROS_INFO("vi_ekf_slam: IMU frame '%s' (the IMU messages' frame_id%s)", body_frame_.c_str(),
             msg.header.frame_id.empty() ? " is empty: the default" : "");
  }
  pipeline_->addImu(*d);
  publishImuRatePose();
}

bool EkfSlamProcessor::acceptImageStamp(double t) {
  ++counters_.images_received;
  switch (clock_.image(t)) {
    case StampVerdict::kStale:
      ++counters_.images_stale;
      reportProblem("image not newer than the previous one dropped");
      return false;
    case StampVerdict::kJumpedBack:
      reset("image time jumped back by " + std::to_string(clock_.lastStepBack()) + " s");
      frames_.forget();
      clock_.image(t);
      break;
    case StampVerdict::kNext:
      break;
  }
  return true;
}

void EkfSlamProcessor::image(const sensor_msgs::Image& msg) {
  const double t = msg.header.stamp.toSec();  // camera clock; the filter maps it to the IMU clock
  if (!acceptImageStamp(t)) return;
  auto img = std::make_shared<PendingImage>(PendingImage{t, msg.header, cv::Mat()});
  const std::string err = toMono8(msg, &img->mono);
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
  if (img->mono.cols != k.width || img->mono.rows != k.height) {
    ++counters_.images_no_camera;
    reportProblem("image size " + std::to_string(img->mono.cols) + "x" + std::to_string(img->mono.rows) +
                  " differs from the calibration " + std::to_string(k.width) + "x" + std::to_string(k.height));
    return;
  }
  queueFrame(img, [this](PendingImage& i, const std::optional<Mat3>& R_cur_prev) { return trackImage(i, R_cur_prev); });
}

void EkfSlamProcessor::features(const CameraFrame& frame, const std_msgs::Header& header) {
  const double t = header.stamp.toSec();
  if (!acceptImageStamp(t)) return;
  if (!cameraReady(header.frame_id)) {
    ++counters_.images_no_camera;
    return;
  }
  auto img = std::make_shared<PendingImage>(PendingImage{t, header, cv::Mat()});
  queueFrame(img, [this, frame](PendingImage&, const std::optional<Mat3>&) {
    last_tracks_ = static_cast<int>(frame.features.size());
    last_tracker_ms_ = 0.0;
    return frame;
  });
}

void EkfSlamProcessor::queueFrame(const std::shared_ptr<PendingImage>& img,
                                  std::function<CameraFrame(PendingImage&, const std::optional<Mat3>&)> track) {
  if (!pipeline_->filter().initialized()) ++counters_.images_before_init;
  // The pipeline asks for the tracks when it uses the image: before the start at once, after it
  // once the IMU reaches the image (then with the gyro's rotation since the previous image).
  pipeline_->addFrame({img->t, [this, img, track = std::move(track)](const std::optional<Mat3>& R_cur_prev) {
                         frame_tic_ = std::chrono::steady_clock::now();
                         current_ = img;
                         return track(*img, R_cur_prev);
                       }});
}

void EkfSlamProcessor::started(StartKind kind, const std::string& event, EkfSlam& /*filter*/) {
  ROS_INFO_STREAM("vi_ekf_slam: " << event);
  // A moving start used the current image; a start at rest begins the tracks anew, as the images
  // that reached the dynamic initializer meanwhile depend on when they arrived (a live replay and
  // an offline run then differ).
  if (kind == StartKind::kAtRest) {
    if (tracker_) tracker_->reset();
  } else if (current_) {
    last_processed_t_ = current_->t;
  }
  // A run that defines the kept map (it was empty): the map's frame is this world's place in odom.
  if (pipeline_->inMap()) frames_.worldIsMap();
  this->event(event);
}

void EkfSlamProcessor::waiting(const std::string& why) { reportProblem(why); }

void EkfSlamProcessor::dropped(FrameDrop why) {
  switch (why) {
    case FrameDrop::kLate:
      ++counters_.images_late;
      reportProblem("image older than the filter state dropped (arrived too late)");
      break;
    case FrameDrop::kQueueFull:
      ++counters_.images_queue_dropped;
      reportProblem("image dropped: no IMU data past its stamp");
      break;
  }
}

void EkfSlamProcessor::imuBridged(const ImuData& imu, ImuSampleVerdict why) {
  std::ostringstream w;
  w.precision(3);
  if (why == ImuSampleVerdict::kClipped) {
    ++counters_.imu_clipped;
    w << "IMU sample at " << std::fixed << imu.timestamp << " s clipped at the sensor's range: bridged";
  } else {
    ++counters_.imu_implausible;
    w << "IMU sample at " << std::fixed << imu.timestamp << " s implausible next to the last: bridged";
  }
  reportProblem(w.str());
}

void EkfSlamProcessor::relocalized(const Relocalization& r, const std::string& event, EkfSlam& /*filter*/) {
  ROS_INFO_STREAM("vi_ekf_slam: " << event);
  // The move in the z-up world the outputs are in: the same move seen through the fixed turn {n} -> world.
  Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
  C.linear() = zUpWorldFromNav().toRotationMatrix();
  frames_.relocalized(C * r.T_m_n * C.inverse(), !params_.node.map_frame.empty());
  this->event(event);
}

void EkfSlamProcessor::cameBack(const std::string& event, EkfSlam& /*filter*/) {
  ROS_INFO_STREAM("vi_ekf_slam: " << event);
  this->event(event);
}

void EkfSlamProcessor::lost(const std::string& why) {
  // Nothing of a lost filter is published: start over (the pipeline re-initializes at rest or
  // moving), and say why in the events and the diagnostics.
  ++counters_.divergences;
  last_lost_ = why;
  startOver("lost: " + why);
}

CameraFrame EkfSlamProcessor::trackImage(PendingImage& img, const std::optional<Eigen::Matrix3d>& R_cur_prev) {
  const auto tic = std::chrono::steady_clock::now();
  img.mono = toTrackingResolution(img.mono, tracker_->camera().intrinsics());
  CameraFrame frame = tracker_->track(img.t, img.mono, R_cur_prev);
  last_tracker_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
  last_tracks_ = tracker_->stats().total;
  return frame;
}

void EkfSlamProcessor::processed(const CameraFrame& frame, const FrameResult& r, EkfSlam& /*filter*/) {
  last_update_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_tic_).count();
  if (!r.processed) {
    reportProblem("frame not processed: " + r.error);
    return;
  }
  const PendingImage& img = *current_;
  ++counters_.images_processed;
  counters_.rejected_observations += static_cast<long>(r.update.rejected_ids.size());
  if (last_processed_t_ && img.t - *last_processed_t_ > params_.node.max_image_gap_s) {
    ++counters_.image_gaps;
    reportProblem("no image for " + std::to_string(img.t - *last_processed_t_) + " s");
  }
  last_processed_t_ = img.t;
  if (frame.features.empty()) ++counters_.images_without_features;
  if (r.blind_since) {
    if (r.blind_started) blind_prior_updates_ = 0;
    if (r.motion_prior_applied) ++blind_prior_updates_;
    std::ostringstream w;
    w << std::fixed << std::setprecision(2) << "blind since t = " << *r.blind_since << " (" << r.blind_s
      << " s): no usable feature in the image (lens covered, dark?); propagating on the IMU";
    if (r.blind_started) event(w.str());
    reportProblem(w.str());
  } else if (r.blind_ended_after_s > 0.0) {
    std::ostringstream w;
    w << std::fixed << std::setprecision(2) << "sight back after " << r.blind_ended_after_s << " s blind ("
      << blind_prior_updates_ << " motion prior updates bounded the velocity)";
    event(w.str());
  }
  const int rejected = static_cast<int>(r.update.rejected_ids.size());
  if (rejected >= 5 && rejected > r.update.accepted) {
    ++counters_.outlier_bursts;
    reportProblem("outlier burst: " + std::to_string(rejected) + " of " + std::to_string(rejected + r.update.accepted) +
                  " observations rejected by the gate");
  }
  if (!r.lost.empty()) return;  // the pipeline starts over (lost())
  output(img, frame, r);
}

void EkfSlamProcessor::output(const PendingImage& img, const CameraFrame& frame, const FrameResult& r) {
  const EkfSlam& filter = pipeline_->filter();
  const NavState nav = filter.navState();
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
    for (const auto& l : filter.landmarks()) {
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
  if (sink_.wantsTracksImage() && !img.mono.empty()) sink_.tracksImage(img.header, tracker_->drawTracks(img.mono));
  StatusExtras x;
  x.landmark_init = params_.filter.landmark_init;
  x.tracks = last_tracks_;
  x.resets = counters_.resets;
  x.update_ms = last_update_ms_;
  x.tracker_ms = last_tracker_ms_;
  x.gravity_mps2 = params_.filter.gravity_mps2;
  x.in_map = pipeline_->inMap();
  x.map_points = pipeline_->map().size();
  x.relocalizations = pipeline_->relocalizations();
  vi_ekf_slam::FilterStatus s = toFilterStatus(filter, nav, r, x);
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
  if (!pipeline_->hasCamera() || !pipeline_->filter().initialized() || !sink_.wantsImuOdometry()) return;
  Vec3 w_b;
  const std::optional<NavState> nav = pipeline_->filter().predictedNavState(&w_b);
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
