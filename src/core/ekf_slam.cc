#include "vi_ekf_slam/core/ekf_slam.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_set>

#include "vi_ekf_slam/core/filter_start.h"
#include "vi_ekf_slam/core/frame_change.h"

namespace vi_ekf_slam {

EkfSlam::EkfSlam(const EkfSlamConfig& config, const CameraModel& camera, const CameraExtrinsics& T_b_c)
    : config_(config),
      camera_(camera),
      T_b_c_(T_b_c),
      state_(emptyState(config, T_b_c, config.mechanization)),
      imu_(config) {
  const std::string err = config_.validate();
  if (!err.empty()) throw std::invalid_argument("EkfSlamConfig:\n" + err);
  if (!camera_.intrinsics().validate().empty() || camera_.width() <= 0) {
    throw std::invalid_argument("EkfSlam: invalid camera: " + camera_.intrinsics().validate());
  }
  const Mat3 RtR = T_b_c_.R_b_c.transpose() * T_b_c_.R_b_c;
  if (!T_b_c_.R_b_c.allFinite() || !T_b_c_.p_b_c.allFinite() || (RtR - Mat3::Identity()).norm() > 1e-6 ||
      T_b_c_.R_b_c.determinant() < 0.0) {
    throw std::invalid_argument("EkfSlam: camera-IMU rotation R_b_c is not a rotation");
  }
}

void EkfSlam::reset() {
  state_ = emptyState(config_, T_b_c_, config_.mechanization);
  initialized_ = false;
  imu_.clear();
  forgetRun();
}

void EkfSlam::forgetRun() {
  landmarks_.clear(nullptr);
  map_.clear();
  compositions_ = 0;
  zero_velocity_updates_ = 0;
  stationary_.reset();
  divergence_.reset();
  outlier_watch_.reset();
  seen_moving_ = false;
  blind_since_.reset();
  hold_new_landmarks_ = false;
  motion_prior_.reset();
}

void EkfSlam::initialize(const NavState& init) { initialize(init, config_.initial); }

void EkfSlam::initialize(const NavState& init, const InitialUncertainty& u, double scene_depth_m,
                         std::optional<double> time_offset_s) {
  start(startingState(config_, T_b_c_, init, u, time_offset_s), scene_depth_m);
}

int EkfSlam::initialize(const DynamicInitResult& aligned, const NavState& registered) {
  int added = 0;
  FilterState s = alignedStartingState(config_, camera_, T_b_c_, aligned, registered, &added);
  start(std::move(s), aligned.median_depth_m);
  return added;
}

void EkfSlam::start(FilterState s, double scene_depth_m) {
  // Sensor-centric: {s} := initial body frame; the pose in {s} is exact and the registration
  // uncertainty moves to p_n_s, q_n_s (the same frame change as a mechanization switch).
  if (isSensorCentric(config_.mechanization)) switchMechanization(s, config_.mechanization);
  state_ = std::move(s);
  forgetRun();
  landmarks_.started(state_, scene_depth_m);
  initialized_ = true;
  // Samples older than the start are of no use any more, except the one just before it.
  imu_.dropBefore(state_.timestamp);
}

bool EkfSlam::addImu(const ImuData& imu) { return imu_.add(imu, initialized_ ? &state_ : nullptr); }

bool EkfSlam::propagateTo(double t) {
  if (!initialized_ || !std::isfinite(t) || t < state_.timestamp) return false;
  return imu_.propagate(state_, t);
}

std::optional<NavState> EkfSlam::predictedNavState(Vec3* angular_rate) const {
  if (!initialized_) return std::nullopt;
  return imu_.predict(state_, angular_rate);
}

FilterView EkfSlam::view() { return {state_, camera_, config_, imu_.lastGyro() - state_.x.b_g}; }

FrameResult EkfSlam::processFrame(const CameraFrame& camera_frame) {
  FrameResult r;
  if (!initialized_) {
    r.error = "filter not initialized";
    return r;
  }
  // The frame on the IMU clock: its stamp plus the current time offset estimate.
  CameraFrame frame = camera_frame;
  frame.timestamp = imuTime(camera_frame.timestamp);
  if (!std::isfinite(frame.timestamp) || frame.timestamp < state_.timestamp) {
    r.error = "frame older than the filter state";
    return r;
  }
  // (From the samples kept for it: the caller may have propagated to the frame already.)
  const bool at_rest = r.imu_at_rest = imu_.atRestBefore(frame.timestamp);
  if (!propagateTo(frame.timestamp)) {
    r.error = "IMU does not reach the frame time yet";
    return r;
  }
  detectStanding(frame, at_rest, &r);
  // The features: of landmarks in the state (a track that found a landmark again observes it),
  // of new tracks, and of matches waiting for their confirmation.
  std::vector<FeatureObservation> known, fresh, pending;
  for (FeatureObservation f : frame.features) {
    // (An id in the clones' range is no track's: refused, it would observe a clone.)
    if (!f.uv.allFinite() || isCloneId(f.id)) continue;
    if (map_.pending(f.id)) {
      pending.push_back(f);
      continue;
    }
    f.id = map_.landmarkOf(f.id);
    (state_.findLandmark(f.id) ? known : fresh).push_back(f);
  }
  // A blind stretch is not a failure: the filter propagates on the IMU and says since when. Its
  // landmarks leave as their tracks end (landmark_timeout_s), with keep_map as dormant points that
  // stay in the map to be found again (holding the tracked ones through the stretch tied the points
  // entering after it to the stale map's depth). Coming back: knowAccelBiasAsAtStart, and the
  // pipeline's re-anchor (velocity_reanchor.h) while new tracks are held.
  const bool blind = known.empty() && fresh.empty() && pending.empty();
  if (blind) {
    if (!blind_since_) {
      blind_since_ = frame.timestamp;
      r.blind_started = true;
      knowAccelBiasAsAtStart();
    }
    r.blind_since = blind_since_;
    r.blind_s = blindFor();
  } else if (blind_since_) {
    r.blind_ended_after_s = frame.timestamp - *blind_since_;
    blind_since_.reset();
  }
  std::vector<RevisitMatch> revisits;
  if (config_.map.within_run) {
    const FilterView v = view();
    revisits =
        map_.confirm(v, pending, outlier_watch_.gateProbability(config_.update), &fresh, &known, &r.revisits_rejected);
    for (RevisitMatch& m : map_.find(v, camera_frame, &fresh, &known)) revisits.push_back(m);
  }
  updateSeenMoving(r);
  const int held = hold_new_landmarks_ ? static_cast<int>(fresh.size()) : 0;
  if (hold_new_landmarks_) fresh.clear();  // their tracks go on and enter once released
  const bool defer =
      config_.zero_velocity.enabled && config_.zero_velocity.defer_landmarks && !seen_moving_ && !at_rest;
  UpdateParams update = config_.update;
  update.gate_probability = r.gate_probability = outlier_watch_.gateProbability(config_.update);
  r.update = ekfUpdate(state_, known, camera_, state_.x.T_b_c, update, imu_.lastGyro() - state_.x.b_g);
  // The gate's watch counts the seconds the camera moved: the images' standing test where it has
  // decided (a crawl's IMU is as quiet as a stand's, its images are not), else the IMU's.
  const bool camera_still = r.stationary.decided ? r.stationary.stationary : at_rest;
  outlier_watch_.record(r.update, seen_moving_ && !camera_still, frame.timestamp, config_.update);
  boundBlindVelocity(&r);
  // A revisit the update's gate refused was a false match: its track is a new point from now on,
  // and the landmark stays dormant.
  std::unordered_set<std::int64_t> refused;
  r.revisits = map_.settle(revisits, r.update, &refused, &r.revisits_rejected);
  for (const auto& f : known) {
    if (refused.count(f.id)) continue;
    landmarks_.seen(f.id, frame.timestamp);
    map_.observed(state_, f.id);
  }
  if (LandmarkManager::triangulationActive(state_, config_)) {
    landmarks_.addDelayed(view(), map_, fresh, frame.timestamp, seen_moving_ || defer, defer, &r);
  } else {
    if (defer) {
      r.deferred_features = static_cast<int>(fresh.size());
      fresh.clear();  // their tracks go on and become landmarks once the rig is seen moving
    }
    r.new_ids = landmarks_.addNow(view(), map_, fresh, frame.timestamp, &r.removed_ids);
  }
  r.deferred_features += held;
  if (config_.map.within_run) {
    map_.rememberAppearance(state_, known);
    map_.rememberAppearance(state_, fresh);
    map_.forgetEndedTracks(state_, frame, revisits);
  }
  r.dormant_landmarks = map_.dormantCount();
  r.left_the_state = map_.takeLeftTheState();
  if (shouldCompose(static_cast<int>(r.new_ids.size()))) {
    try {
      landmarks_.delayed().beforeComposition(state_);
      compose(state_, config_.composition_second_order);
      ++compositions_;
      r.composed = true;
    } catch (const std::runtime_error& e) {  // a diverged state the frame change cannot carry
      r.lost = e.what();
      r.processed = true;
      return r;
    }
  }
  r.lost = divergence_.update(frame.timestamp, state_, r.update.accepted,
                              static_cast<int>(r.update.rejected_ids.size()), config_.divergence);
  r.processed = true;
  return r;
}

void EkfSlam::detectStanding(const CameraFrame& frame, bool at_rest, FrameResult* r) {
  if (!config_.zero_velocity.enabled) return;
  const Mat3 R_n_c = (state_.x.q_n_s * state_.x.q_s_b).toRotationMatrix() * state_.x.T_b_c.R_b_c;
  ExpectedMotion expected;
  expected.v_n_b = state_.x.q_n_s * state_.x.v_s_b;
  expected.scene_depth_m = landmarks_.newLandmarkDepth(state_, config_);
  expected.pixel_noise_px = config_.update.pixel_noise_px;
  r->stationary = stationary_.update(frame, R_n_c, camera_, config_.zero_velocity, expected);
  if (r->stationary.stationary)
    r->zero_velocity_applied = zeroVelocityUpdate(state_, config_.zero_velocity, at_rest).applied;
  if (r->zero_velocity_applied) ++zero_velocity_updates_;
}

void EkfSlam::boundBlindVelocity(FrameResult* r) {
  // Blind, or sight back with no landmark yet (new tracks held until the re-anchor): the velocity
  // is the IMU's alone. A standing update constrained it already.
  if (r->update.accepted > 0) {
    motion_prior_.seen(state_, config_.blind_motion);
  } else if (!r->zero_velocity_applied) {
    r->motion_prior_applied = motion_prior_.applyIfUncertain(state_, config_.blind_motion).applied;
  }
}

void EkfSlam::knowAccelBiasAsAtStart() {
  // While blind the accelerometer bias (and the tilt, whose error acts on the horizontal axes as a
  // bias does) is all that bounds the velocity's drift. What the images taught the filter of it
  // under weak motion is overconfident (a slow hand-held walk: the velocity ran 0.3 m/s off in 4 s
  // with a sigma of 0.03), so from the stretch's start it is known no better than at the start: its
  // variance is raised to the prior's, and the velocity's uncertainty grows with it honestly.
  const double prior = config_.initial.accel_bias_mps2 * config_.initial.accel_bias_mps2;
  Eigen::MatrixXd P = state_.covariance();
  bool raised = false;
  for (int i = idx::kBa; i < idx::kBa + 3; ++i) {
    if (P(i, i) >= prior) continue;
    P(i, i) = prior;  // adding to a diagonal entry keeps P positive definite
    raised = true;
  }
  if (raised) state_.setCovariance(std::move(P));
}

void EkfSlam::updateSeenMoving(const FrameResult& r) {
  // "Seen moving" is latched: it ends with a stand and starts again once the parallax over the
  // detector's window reaches moving_parallax_px. Before the detector has a window (start, reset)
  // the filter's own speed decides: surely a walk's (moving_speed_mps) or not. Standing only
  // counts when the filter agrees (the zero-velocity update passed its gate): walking towards a
  // distant scene can look like standing to the parallax test alone. A hand-held rig that is not
  // quite standing (parallax between max_parallax_px and moving_parallax_px) still has too little
  // baseline for a new point.
  const bool moving = confidentlyMoving();
  if (r.zero_velocity_applied || (!r.stationary.has_history && !moving)) {
    seen_moving_ = false;
  } else if ((moving && !r.stationary.has_history) ||
             (r.stationary.decided && r.stationary.parallax_px >= config_.zero_velocity.moving_parallax_px)) {
    seen_moving_ = true;
  }
}

bool EkfSlam::shouldCompose(int new_landmarks) const {
  if (state_.mechanization() != Mechanization::kSensorCentricComposition) return false;
  switch (config_.composition_trigger) {
    case CompositionTrigger::kNewLandmarks:
      return new_landmarks > config_.composition_new_landmarks;
    case CompositionTrigger::kEveryUpdate:
      return true;
    case CompositionTrigger::kNever:
      return false;
  }
  return false;
}

std::vector<MapPoint> EkfSlam::mapPoints() const { return map_.mapPoints(state_, config_); }

void EkfSlam::moveWorld(const Eigen::Isometry3d& T_new_old) {
  // In a sensor-centric layout only the pose of {s} in {n} lives in {n}; a world-centric state
  // goes through that layout and back (its clones' orientations are in the frame being left).
  const Mechanization m = state_.mechanization();
  if (!isSensorCentric(m)) {
    landmarks_.delayed().clear(&state_);
    switchMechanization(state_, Mechanization::kSensorCentric);
  }
  const Mat3 R = T_new_old.linear();
  state_.x.p_n_s = R * state_.x.p_n_s + T_new_old.translation();
  state_.x.q_n_s = (Quat(R) * state_.x.q_n_s).normalized();
  // The errors of p_n_s and psi_n_s (global, in {n}) turn with the world.
  Eigen::MatrixXd P = state_.covariance();
  for (int b : {idx::kPns, idx::kPsiNs}) {
    P.middleRows(b, 3) = (R * P.middleRows(b, 3)).eval();
    P.middleCols(b, 3) = (P.middleCols(b, 3) * R.transpose()).eval();
  }
  state_.setCovariance(std::move(P));
  if (!isSensorCentric(m)) switchMechanization(state_, m);
}

bool EkfSlam::confidentlyMoving() const {
  const Vec3 v = state_.x.v_s_b;
  const double speed = v.norm();
  if (!(speed > 0.0)) return false;
  const Vec3 u = v / speed;
  const double var = u.dot(state_.covariance().block<3, 3>(idx::kV, idx::kV) * u);
  return speed - 2.0 * std::sqrt(std::max(0.0, var)) >= config_.zero_velocity.moving_speed_mps;
}

bool EkfSlam::setConfig(const EkfSlamConfig& config, std::string* error) {
  const std::string err = config.validate();
  if (!err.empty()) {
    if (error) *error = err;
    return false;
  }
  const Mechanization previous = state_.mechanization();
  config_ = config;
  imu_.setConfig(config_);
  if (config.mechanization != previous) setMechanization(config.mechanization);
  // Waiting switched off (or no longer possible): the tracks start again as new ones, the clones go.
  if (!LandmarkManager::triangulationActive(state_, config_)) landmarks_.delayed().clear(&state_);
  return true;
}

void EkfSlam::setMechanization(Mechanization m) {
  config_.mechanization = m;
  landmarks_.delayed().clear(&state_);  // the clones' orientations are in the frame being left
  if (initialized_)
    switchMechanization(state_, m);
  else
    state_ = emptyState(config_, T_b_c_, m);  // the calibrated extrinsic stays what extrinsics() says before the start
}

}  // namespace vi_ekf_slam
