#include "vi_ekf_slam/core/vio_pipeline.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "vi_ekf_slam/core/param_ranges.h"

namespace vi_ekf_slam {

std::string PipelineParams::validate() const {
  std::ostringstream err;
  checkRange(err, "blind_reanchor_max_wait_s", reanchor_max_wait_s);
  return err.str();
}

namespace {
/// A moving start older than this behind the newest IMU sample is not taken: the IMU buffer no
/// longer reaches back to it [s].
constexpr double kMaxStartAgeS = 1.0;

bool allFinite(const NavState& n) {
  return n.p_n_b.allFinite() && n.v_n_b.allFinite() && n.q_n_b.coeffs().allFinite() && n.b_g.allFinite() &&
         n.b_a.allFinite() && n.cov.allFinite();
}
}  // namespace

VioPipeline::VioPipeline(const EkfSlamConfig& config, const PipelineParams& params, PipelineListener& listener)
    : config_(config),
      params_(params),
      listener_(listener),
      static_init_(params.static_init),
      map_(config.map.max_kept_points) {}

VioPipeline::VioPipeline(const EkfSlamConfig& config, const PipelineParams& params, const CameraModel& camera,
                         const CameraExtrinsics& T_b_c, PipelineListener& listener)
    : VioPipeline(config, params, listener) {
  setCamera(camera, T_b_c);
}

void VioPipeline::setCamera(const CameraModel& camera, const CameraExtrinsics& T_b_c) {
  clearCamera();
  filter_ = std::make_unique<EkfSlam>(config_, camera, T_b_c);
  dynamic_init_ = std::make_unique<DynamicInitializer>(params_.dynamic_init, camera, T_b_c);
}

void VioPipeline::clearCamera() {
  archiveRun();
  attempt_.reset();
  filter_.reset();
  dynamic_init_.reset();
  first_frame_t_.reset();
  queue_.clear();
  prev_q_n_b_.reset();
  camera_running_ = false;
}

bool VioPipeline::setConfig(const EkfSlamConfig& config, std::string* error) {
  if (filter_ && !filter_->setConfig(config, error)) return false;
  config_ = config;
  map_.setMaxPoints(config.map.max_kept_points);
  return true;
}

void VioPipeline::startedMapRun() { in_map_ = map_.empty(); }

void VioPipeline::archiveRun() {
  if (config_.map.keptAcrossRuns() && filter_ && filter_->initialized() && in_map_) map_.merge(filter_->mapPoints());
  in_map_ = false;
}

bool VioPipeline::loadMap(const std::string& path, std::string* error) {
  if (!map_.load(path, error)) return false;
  in_map_ = false;
  return true;
}

bool VioPipeline::saveMap(const std::string& path, std::string* error, int* points) const {
  KeptMap all = map_;
  all.setMaxPoints(std::numeric_limits<int>::max());
  if (filter_ && filter_->initialized() && in_map_) all.merge(filter_->mapPoints());
  if (points) *points = all.size();
  return all.save(path, error);
}

void VioPipeline::tryRelocalize(const CameraFrame& frame) {
  const NavState nav = filter_->navState();
  Eigen::Isometry3d T_n_b = Eigen::Isometry3d::Identity();
  T_n_b.linear() = nav.q_n_b.toRotationMatrix();
  T_n_b.translation() = nav.p_n_b;
  // The tracks, and the corners the front end finds over the whole image (a new tracker follows
  // few of the points the map has; its detector finds more of them).
  std::vector<FeatureObservation> features = frame.features;
  if (frame.search) {
    std::vector<FeatureObservation> corners = frame.search(wholeImageRegions(filter_->camera()));
    features.insert(features.end(), corners.begin(), corners.end());
  }
  const std::optional<Relocalization> r =
      relocalize(map_, features, filter_->camera(), filter_->extrinsics(), T_n_b, config_.map);
  if (!r) return;
  filter_->moveWorld(r->T_m_n);
  in_map_ = true;
  ++relocalizations_;
  std::ostringstream e;
  e.precision(3);
  const Eigen::Vector3d& t = r->T_m_n.translation();
  e << "relocalized in the kept map: " << r->inliers << " of " << r->matches << " matches to " << map_.size()
    << " map points agree (" << r->reprojection_rms_px << " px rms, tilt " << r->tilt_deg
    << " deg); the world moved by " << t.norm() << " m and "
    << std::atan2(r->T_m_n.linear()(1, 0), r->T_m_n.linear()(0, 0)) * 180.0 / M_PI << " deg of yaw";
  listener_.relocalized(*r, e.str(), *filter_);
}

void VioPipeline::forgetStart() {
  attempt_.reset();  // waits for a worker still running (it works on its own copy)
  comeback_.reset();
  sight_back_t_.reset();
  static_init_.reset();
  at_rest_.reset();
  if (dynamic_init_) dynamic_init_->reset();
  first_frame_t_.reset();
}

void VioPipeline::reset() {
  archiveRun();
  if (filter_) filter_->reset();
  forgetStart();
  queue_.clear();
  prev_q_n_b_.reset();
}

void VioPipeline::initialize(const NavState& state) {
  if (!filter_) throw std::logic_error("VioPipeline::initialize: no camera yet");
  filter_->initialize(state);
  forgetStart();
  prev_q_n_b_.reset();
  startedMapRun();
}

void VioPipeline::addImu(const ImuData& imu) {
  // The rest test looks at every sample; the filter and the moving start only from the first
  // frame (or a start from a known state) on: a start before the camera runs would drift on the
  // IMU alone until then.
  if (isFinite(imu)) {
    const ImuSampleVerdict v = imu_check_.check(imu, config_.imu_check);
    if (v != ImuSampleVerdict::kGood) {
      if (filter_ && (camera_running_ || filter_->initialized())) filter_->bridgeImu(imu);
      listener_.imuBridged(imu, v);
      return;
    }
  }
  if (auto r = static_init_.addImu(imu)) at_rest_ = r;
  if (!filter_ || (!camera_running_ && !filter_->initialized())) return;
  if (!filter_->initialized()) dynamic_init_->addImu(imu);
  if (comeback_) comeback_->addImu(imu);
  filter_->addImu(imu);
  takeFinishedAttempt();
  tryStatic(imu.timestamp);
  processQueue();
}

void VioPipeline::tryStatic(double t_now) {
  // Only a recent static interval: if the rig moved since, wait for the next one.
  if (filter_->initialized() || !at_rest_ || !at_rest_->usableAt(t_now)) return;
  filter_->initialize(registered(at_rest_->navState()));
  std::ostringstream e;
  e.precision(3);
  e << "initialized: static, " << params_.static_init.window_s << " s at rest (accel std " << at_rest_->accel_std_mps2
    << " m/s^2, gyro std " << at_rest_->gyro_std_radps << " rad/s)";
  forgetStart();
  // The tracks start with the filter: no rotation seed for the first frame.
  prev_q_n_b_.reset();
  startedMapRun();
  listener_.started(StartKind::kAtRest, e.str(), *filter_);
}

void VioPipeline::addFrame(QueuedFrame frame) {
  if (!filter_) return;
  camera_running_ = true;
  takeFinishedAttempt();  // a start found meanwhile takes this frame as its first
  if (!filter_->initialized()) {
    tryDynamic(frame);
    return;
  }
  if (filter_->imuTime(frame.t) < filter_->state().timestamp) {
    listener_.dropped(FrameDrop::kLate);
    return;
  }
  queue_.push_back(std::move(frame));
  while (static_cast<int>(queue_.size()) > params_.max_frame_queue) {
    queue_.pop_front();
    listener_.dropped(FrameDrop::kQueueFull);
  }
  processQueue();
}

void VioPipeline::tryDynamic(QueuedFrame& frame) {
  if (!params_.dynamic_init_enabled) {
    listener_.waiting("waiting for a static IMU interval to initialize");
    return;
  }
  if (!first_frame_t_) first_frame_t_ = frame.t;
  // The tracks it aligns are the tracks the filter goes on with; no rotation seed (no attitude
  // yet). The frame goes to the IMU clock through the configured time offset.
  CameraFrame features = frame.features(std::nullopt);
  features.timestamp = filter_->imuTime(frame.t);
  dynamic_init_->addFrame(features);
  if (!params_.background_start_attempts) {
    std::string why;
    const std::optional<DynamicInitResult> r = dynamic_init_->tryInitialize(&why);
    startMoving(r, why, frame.t);
    return;
  }
  if (attempt_) return;  // the frame waits in the initializer's window for the next attempt
  StartAttempt attempt;
  attempt.frame_t = frame.t;
  attempt.outcome = std::async(std::launch::async, [init = *dynamic_init_]() mutable {
    std::string why;
    std::optional<DynamicInitResult> r = init.tryInitialize(&why);
    return std::make_pair(std::move(r), why);
  });
  attempt_ = std::move(attempt);
}

bool VioPipeline::takeFinishedAttempt() {
  if (!attempt_ || attempt_->outcome.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return false;
  const auto [r, why] = attempt_->outcome.get();
  const double frame_t = attempt_->frame_t;
  attempt_.reset();
  return startMoving(r, why, frame_t);
}

void VioPipeline::waitForStartAttempt() {
  if (attempt_) attempt_->outcome.wait();
}

bool VioPipeline::startMoving(const std::optional<DynamicInitResult>& r, const std::string& why, double frame_t) {
  if (!r) {
    std::ostringstream w;
    w << "waiting to initialize: at rest for " << params_.static_init.window_s << " s, or moving: " << why;
    listener_.waiting(w.str());
    return false;
  }
  if (r->state.timestamp < filter_->latestImuTime() - kMaxStartAgeS) return false;
  const int added = filter_->initialize(*r, registered(r->state));
  std::ostringstream e;
  e.precision(3);
  e << "initialized: dynamic, " << (frame_t - *first_frame_t_) << " s after the first image (" << r->frames
    << " images, " << r->features << " features, " << added << " landmarks, median depth " << r->median_depth_m
    << " m, scale sigma " << 100.0 * r->scale_sigma << "%, velocity sigma " << r->velocity_sigma_mps
    << " m/s, roll/pitch sigma " << r->tilt_sigma_rad << " rad, time offset "
    << filter_->config().camera_time_offset_s + r->time_offset_correction_s << " s)";
  forgetStart();
  prev_q_n_b_ = filter_->navState().q_n_b;
  startedMapRun();
  listener_.started(StartKind::kMoving, e.str(), *filter_);
  return true;
}

void VioPipeline::processQueue() {
  while (!queue_.empty() && filter_ && filter_->initialized() &&
         filter_->imuTime(queue_.front().t) <= filter_->latestImuTime()) {
    QueuedFrame f = std::move(queue_.front());
    queue_.pop_front();
    if (filter_->imuTime(f.t) < filter_->state().timestamp) {
      listener_.dropped(FrameDrop::kLate);
      continue;
    }
    process(f);
  }
}

void VioPipeline::flush() {
  takeFinishedAttempt();
  while (!queue_.empty() && filter_ && filter_->initialized()) {
    QueuedFrame f = std::move(queue_.front());
    queue_.pop_front();
    process(f);
  }
}

void VioPipeline::process(QueuedFrame& f) {
  // The gyro-predicted camera rotation since the previous frame seeds the tracker.
  std::optional<Mat3> R_cur_prev;
  if (filter_->propagateTo(filter_->imuTime(f.t)) && prev_q_n_b_) {
    const Mat3 R_b = (filter_->navState().q_n_b.conjugate() * *prev_q_n_b_).toRotationMatrix();
    const Mat3& R_b_c = filter_->extrinsics().R_b_c;
    R_cur_prev = R_b_c.transpose() * R_b * R_b_c;
  }
  CameraFrame features = f.features(R_cur_prev);
  features.timestamp = f.t;
  FrameResult r = filter_->processFrame(features);
  std::optional<NavState> nav;
  // The map kept across resets: the points leaving a filter that is in it, or placing one that is not.
  if (r.processed && r.lost.empty() && config_.map.keptAcrossRuns()) {
    if (in_map_) {
      map_.merge(r.left_the_state);
    } else if (!map_.empty()) {
      tryRelocalize(features);
    }
  }
  if (r.processed && r.lost.empty()) {
    nav = filter_->navState();
    if (!allFinite(*nav)) r.lost = "the filter state became non-finite";
  }
  listener_.processed(features, r, *filter_);
  if (!r.processed) return;
  if (!r.lost.empty()) {
    // Nothing of a lost filter is used, its map neither: start over, at rest or moving.
    in_map_ = false;
    reset();
    listener_.lost(r.lost);
    return;
  }
  prev_q_n_b_ = nav->q_n_b;
  comeBack(features, r);
}

void VioPipeline::comeBack(const CameraFrame& frame, const FrameResult& r) {
  if (params_.reanchor_max_wait_s <= 0.0) return;
  if (r.blind_since) {
    // Blind again before the re-anchor (a flicker of sight in the dark): the images of that sight
    // are of the stretch, so the come-back, and its wait, start over from the next sight.
    if (!comeback_ || sight_back_t_) {
      comeback_ = std::make_unique<DynamicInitializer>(params_.dynamic_init, filter_->camera(), filter_->extrinsics());
      sight_back_t_.reset();
      filter_->holdNewLandmarks(true);
    }
    return;
  }
  if (!comeback_) return;
  const double t = filter_->state().timestamp;  // the frame on the IMU clock
  std::ostringstream e;
  e.precision(3);
  if (!sight_back_t_) {
    sight_back_t_ = t;
    // Landmarks of the map seen again anchor the velocity themselves.
    if (r.update.accepted > 0) {
      e << "sight back with " << r.update.accepted << " observations of the map's landmarks: no re-anchor";
      endComeBack(e.str());
      return;
    }
  }
  CameraFrame f = frame;
  f.timestamp = t;
  comeback_->addFrame(f);
  std::string why;
  const std::optional<DynamicInitResult> aligned = comeback_->tryInitialize(&why);
  // The alignment's state is at its last frame, a few frames before this one: its velocity is
  // carried on the IMU to the filter's time before it is compared (velocity_reanchor.h).
  const std::optional<alignment::Preintegrated> since =
      aligned ? comeback_->imuBetween(aligned->state.timestamp, t, filter_->state().x.b_g) : std::nullopt;
  if (aligned && !since) why = "the IMU does not reach this image from the alignment's last frame";
  if (since) {
    const Vec3 v_before = filter_->state().x.q_s_b.conjugate() * filter_->state().x.v_s_b;
    const BodyVelocity m = bodyVelocityOf(*aligned, *since, t, filter_->config().gravity_mps2);
    const KalmanUpdateResult u = filter_->updateBodyVelocity(m);
    const Vec3 v_after = filter_->state().x.q_s_b.conjugate() * filter_->state().x.v_s_b;
    e << (u.applied ? "re-anchored" : "not re-anchored (refused by the gate)") << " " << t - *sight_back_t_
      << " s after sight came back: the first " << aligned->frames << " images say a speed of " << m.v_b.norm()
      << " m/s (sigma " << std::sqrt(m.cov.trace() / 3.0) << ", carried " << t - aligned->state.timestamp
      << " s on the IMU to this image), the filter had " << v_before.norm() << " m/s, now " << v_after.norm()
      << " m/s (NIS " << u.nis << ", 3 dof)";
  } else if (t - *sight_back_t_ >= params_.reanchor_max_wait_s) {
    e << "not re-anchored " << t - *sight_back_t_ << " s after sight came back: " << why;
  } else {
    return;
  }
  endComeBack(e.str());
}

void VioPipeline::endComeBack(const std::string& event) {
  comeback_.reset();
  sight_back_t_.reset();
  filter_->holdNewLandmarks(false);
  listener_.cameBack(event, *filter_);
}

}  // namespace vi_ekf_slam
