#include "vi_ekf_slam/core/ekf_slam.h"

#include <array>
#include <map>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "vi_ekf_slam/core/chi_squared.h"
#include "vi_ekf_slam/core/ekf_update.h"
#include "vi_ekf_slam/core/frame_change.h"
#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/landmark_initialization.h"

namespace vi_ekf_slam {

EkfSlam::EkfSlam(const EkfSlamConfig& config, const CameraModel& camera, const CameraExtrinsics& T_b_c)
    : config_(config), camera_(camera), T_b_c_(T_b_c), state_(emptyState(config.mechanization)) {
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
  g_n_ = gravityInNav(config_.gravity_mps2);
}

void EkfSlam::reset() {
  state_ = emptyState(config_.mechanization);
  initialized_ = false;
  imu_.clear();
  recent_imu_.clear();
  last_seen_.clear();
  compositions_ = 0;
  imu_gaps_ = 0;
  bridges_.clear();
  zero_velocity_updates_ = 0;
  stationary_.reset();
  divergence_.reset();
  outlier_watch_.reset();
  delayed_.clear(nullptr);
  seen_moving_ = false;
  forgetMap();
}

void EkfSlam::initialize(const NavState& init) { initialize(init, config_.initial); }

void EkfSlam::initialize(const NavState& init, const InitialUncertainty& u, double scene_depth_m,
                         std::optional<double> time_offset_s) {
  start(startingState(init, u, time_offset_s), scene_depth_m);
}

FilterState EkfSlam::emptyState(Mechanization m) const {
  FilterState s(m, config_.estimate_extrinsic);
  s.x.T_b_c = T_b_c_;
  return s;
}

FilterState EkfSlam::startingState(const NavState& init, const InitialUncertainty& u,
                                   std::optional<double> time_offset_s) const {
  using namespace idx;
  // Start world-centric: the initial pose uncertainty is the registration error in {n}.
  FilterState s = emptyState(Mechanization::kWorldCentric);  // (a restart forgets a refined extrinsic)
  s.timestamp = init.timestamp;
  s.x.p_s_b = init.p_n_b;
  s.x.v_s_b = init.v_n_b;
  s.x.q_s_b = init.q_n_b.normalized();
  s.x.b_a = init.b_a;
  s.x.b_g = init.b_g;
  s.x.t_d = time_offset_s.value_or(config_.camera_time_offset_s);
  const int dim = s.motionDim();
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(dim, dim);
  P.block<3, 3>(kP, kP).diagonal().setConstant(u.position_m * u.position_m);
  P.block<3, 3>(kV, kV).diagonal().setConstant(u.velocity_mps * u.velocity_mps);
  P.block<3, 3>(kBa, kBa).diagonal().setConstant(u.accel_bias_mps2 * u.accel_bias_mps2);
  P.block<3, 3>(kPsi, kPsi).diagonal() << u.roll_pitch_rad * u.roll_pitch_rad, u.roll_pitch_rad * u.roll_pitch_rad,
      u.yaw_rad * u.yaw_rad;
  P.block<3, 3>(kBg, kBg).diagonal().setConstant(u.gyro_bias_radps * u.gyro_bias_radps);
  P(kTd, kTd) = u.time_offset_s * u.time_offset_s;
  if (s.estimatesExtrinsic()) {
    const int e = s.extrinsicIndex();
    P.block<3, 3>(e, e).diagonal().setConstant(u.extrinsic_translation_m * u.extrinsic_translation_m);
    P.block<3, 3>(e + 3, e + 3).diagonal().setConstant(u.extrinsic_rotation_rad * u.extrinsic_rotation_rad);
  }
  if (u.velocity_attitude_accel_bias) {
    // An initializer's [v, psi, b_a] with their correlations; the yaw's variance is the prior's.
    const std::array<int, 3> at{kV, kPsi, kBa};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        P.block<3, 3>(at[i], at[j]) = u.velocity_attitude_accel_bias->block<3, 3>(3 * i, 3 * j);
    }
    P.row(kPsi + 2).setZero();
    P.col(kPsi + 2).setZero();
    P(kPsi + 2, kPsi + 2) = u.yaw_rad * u.yaw_rad;
  }
  // An initializer that knows the velocity relative to its own heading: v_true = R_z(yaw error)
  // (v + dv), so the velocity error gains e_z x v times the yaw error.
  if (u.velocity_relative_to_heading) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Identity(dim, dim);
    J.block<3, 1>(kV, kPsi + 2) = Vec3::UnitZ().cross(init.v_n_b);
    P = J * P * J.transpose();
  }
  s.setCovariance(P);
  return s;
}

void EkfSlam::start(FilterState s, double scene_depth_m) {
  scene_depth_hint_m_ = scene_depth_m > 0.0 && std::isfinite(scene_depth_m) ? scene_depth_m : 0.0;
  // Sensor-centric: {s} := initial body frame; the pose in {s} is exact and the registration
  // uncertainty moves to p_n_s, q_n_s (the same frame change as a mechanization switch).
  if (isSensorCentric(config_.mechanization)) switchMechanization(s, config_.mechanization);
  state_ = std::move(s);
  delayed_.clear(nullptr);
  last_seen_.clear();
  forgetMap();
  for (int i = 0; i < state_.numLandmarks(); ++i)
    last_seen_[state_.landmarkIds()[static_cast<size_t>(i)]] = state_.timestamp;
  stationary_.reset();
  divergence_.reset();
  outlier_watch_.reset();
  seen_moving_ = false;
  compositions_ = 0;
  zero_velocity_updates_ = 0;
  initialized_ = true;
  // Samples older than the start are of no use any more, except the one just before it.
  while (imu_.size() > 1 && imu_[1].timestamp <= state_.timestamp) imu_.pop_front();
}

bool EkfSlam::addImu(const ImuData& imu) {
  if (!isFinite(imu)) return false;
  if (!imu_.empty() && imu.timestamp <= imu_.back().timestamp) return false;
  if (!imu_.empty() && imu.timestamp - imu_.back().timestamp > config_.max_imu_gap_s) ++imu_gaps_;
  imu_.push_back(imu);
  recent_imu_.push_back(imu);
  // Pruned by frame time in processFrame (the IMU may run ahead of the images); bounded here.
  while (static_cast<int>(recent_imu_.size()) > config_.imu_buffer_max) recent_imu_.pop_front();
  if (static_cast<int>(imu_.size()) > config_.imu_buffer_max) {
    // No image for a long time: integrate the oldest samples so the buffer stays bounded.
    if (initialized_) propagateTo(imu_[imu_.size() / 2].timestamp);
    while (static_cast<int>(imu_.size()) > config_.imu_buffer_max) imu_.pop_front();
  }
  return true;
}

void EkfSlam::bridgeImu(const ImuData& imu) {
  if (imu_.empty() || !(imu.timestamp > imu_.back().timestamp)) return;
  const ImuData& good = imu_.back();
  bridges_.push_back(
      {good.timestamp, imu.timestamp - good.timestamp, (imu.am - good.am).cwiseAbs(), (imu.wm - good.wm).cwiseAbs()});
}

void EkfSlam::addBridgeUncertainty(FilterState& s, double t_before, double fraction) const {
  // What the left-out sample could have hidden: its departure from the last good sample, as an
  // unknown acceleration and rate over its period (the velocity and attitude it could have moved).
  for (const ImuBridge& b : bridges_) {
    if (b.t_before != t_before) continue;
    addUnseenMotion(s, Vec3::Zero(), fraction * (b.sigma_a * b.dt).cwiseAbs2(),
                    fraction * (b.sigma_g * b.dt).cwiseAbs2());
  }
}

double EkfSlam::latestImuTime() const {
  return imu_.empty() ? -std::numeric_limits<double>::infinity() : imu_.back().timestamp;
}

bool EkfSlam::propagateTo(double t) {
  if (!initialized_ || !std::isfinite(t) || t < state_.timestamp) return false;
  if (imu_.empty() || imu_.back().timestamp < t) return false;
  integrateImu(state_, t, &last_gyro_);
  while (imu_.size() > 1 && imu_[1].timestamp <= t) imu_.pop_front();
  while (!bridges_.empty() && bridges_.front().t_before < imu_.front().timestamp) bridges_.pop_front();
  return true;
}

void EkfSlam::integrateImu(FilterState& s, double t, Vec3* last_gyro) const {
  auto integrate = [&](double t0, double t1, const Vec3& wm, const Vec3& am) {
    if (t1 <= t0) return;
    propagateState(s, wm, am, t1 - t0, config_.imu_noise, g_n_);
    *last_gyro = wm;
  };
  // Before the first buffered sample: hold it.
  if (s.timestamp < imu_.front().timestamp) {
    integrate(s.timestamp, std::min(t, imu_.front().timestamp), imu_.front().wm, imu_.front().am);
  }
  for (size_t k = 0; k + 1 < imu_.size(); ++k) {
    const ImuData& a = imu_[k];
    const ImuData& b = imu_[k + 1];
    const double t0 = std::max(a.timestamp, s.timestamp);
    const double t1 = std::min(b.timestamp, t);
    if (t1 > t0) {
      // Mean of the linearly interpolated measurements over [t0, t1] = value at its middle.
      const double alpha = (0.5 * (t0 + t1) - a.timestamp) / (b.timestamp - a.timestamp);
      integrate(t0, t1, (1.0 - alpha) * a.wm + alpha * b.wm, (1.0 - alpha) * a.am + alpha * b.am);
      if (b.timestamp - a.timestamp > config_.max_imu_gap_s) addGapUncertainty(s, t1 - t0);
      if (!bridges_.empty()) addBridgeUncertainty(s, a.timestamp, (t1 - t0) / (b.timestamp - a.timestamp));
    }
    if (b.timestamp >= t) break;
  }
  s.timestamp = t;
}

std::optional<NavState> EkfSlam::predictedNavState(Vec3* angular_rate) const {
  if (!initialized_ || imu_.empty() || imu_.back().timestamp < state_.timestamp) return std::nullopt;
  // The motion state alone (no landmarks): the same propagation at a 21x21 cost.
  FilterState s(state_.mechanization());
  s.timestamp = state_.timestamp;
  s.x = state_.x;
  s.setCovariance(state_.motionCovariance());
  Vec3 w = last_gyro_;
  integrateImu(s, imu_.back().timestamp, &w);
  if (angular_rate) *angular_rate = w - s.x.b_g;
  return vi_ekf_slam::navState(s);
}

void EkfSlam::addGapUncertainty(FilterState& s, double dt) const {
  // An unknown acceleration of size sa ~ N(0, sa^2 I) over dt moves v by up to a dt and p by
  // a dt^2/2; an unknown rate turns the attitude by w dt. The position and velocity parts are
  // kept uncorrelated: a walking torso's acceleration swings within a gap, so the velocity it
  // ends with does not follow from how far it went. (A constant-acceleration model would make
  // them fully correlated, and the first image after the gap would then fix the velocity from
  // the position alone, wrongly and with confidence: the gate then rejects every later
  // observation. SensorFaults.FilterRidesThroughDropoutGapOutliersAndCoveredCamera.)
  const double sa = config_.imu_gap_accel_sigma_mps2, sg = config_.imu_gap_gyro_sigma_radps;
  const double qa = sa * sa;
  addUnseenMotion(s, Vec3::Constant(qa * std::pow(dt, 4) / 4.0), Vec3::Constant(qa * dt * dt),
                  Vec3::Constant(sg * sg * dt * dt));
}

void EkfSlam::addUnseenMotion(FilterState& s, const Vec3& var_p, const Vec3& var_v, const Vec3& var_psi) {
  using namespace idx;
  const int m = s.motionDim();
  MotionMatrix Q = MotionMatrix::Zero(m, m);
  Q.block<3, 3>(kP, kP).diagonal() = var_p;
  Q.block<3, 3>(kV, kV).diagonal() = var_v;
  Q.block<3, 3>(kPsi, kPsi).diagonal() = var_psi;
  s.propagateCovariance(MotionMatrix::Identity(m, m), Q);
}

int EkfSlam::initialize(const DynamicInitResult& aligned, const NavState& registered) {
  using namespace idx;
  InitialUncertainty u = aligned.uncertainty(config_.initial);
  // The registration turned the aligned state about {n}'s z axis: so are its v and psi.
  const Mat3 R_z = (registered.q_n_b * aligned.state.q_n_b.conjugate()).toRotationMatrix();
  Eigen::Matrix<double, 9, 9> T = Eigen::Matrix<double, 9, 9>::Identity();
  T.block<3, 3>(0, 0) = R_z;
  T.block<3, 3>(3, 3) = R_z;
  u.velocity_attitude_accel_bias = T * aligned.covariance * T.transpose();
  FilterState s = startingState(registered, u, config_.camera_time_offset_s + aligned.time_offset_correction_s);
  {
    // The gyro bias the alignment only considered moved its velocity, tilt and bias.
    const Eigen::Matrix<double, 9, 3> X = aligned.gyro_bias_covariance.allFinite()
                                              ? Eigen::Matrix<double, 9, 3>(T * aligned.gyro_bias_covariance)
                                              : Eigen::Matrix<double, 9, 3>::Zero();
    Eigen::MatrixXd& P = s.mutableCovariance();
    const std::array<int, 3> at{kV, kPsi, kBa};
    for (int i = 0; i < 3; ++i) {
      P.block<3, 3>(at[static_cast<size_t>(i)], kBg) = X.middleRows<3>(3 * i);
      P.block<3, 3>(kBg, at[static_cast<size_t>(i)]) = X.middleRows<3>(3 * i).transpose();
    }
  }
  // The aligned features enter with the depth the alignment found (their first updates are then
  // nearly linear) when it knows it better than a new track's prior; the others later as any new
  // track. They enter together: one error of the window's scale moves all their depths and the
  // velocity (taken as independent, tens of landmarks would know the scale far better than the
  // alignment does), and each carries its anchor's registration error as any new landmark.
  std::vector<FeatureObservation> obs;
  std::vector<double> depths;
  std::vector<int> candidates;  // indices into aligned.landmarks
  const auto n = static_cast<Eigen::Index>(aligned.landmarks.size());
  // (Without a usable joint covariance, the marginals alone, as independent depths.)
  const bool joint = aligned.landmark_covariance.rows() == n && aligned.landmark_covariance.cols() == n &&
                     aligned.landmark_state_covariance.rows() == n &&
                     aligned.landmark_gyro_bias_covariance.rows() == n && aligned.landmark_covariance.allFinite() &&
                     aligned.landmark_state_covariance.allFinite() && aligned.landmark_gyro_bias_covariance.allFinite();
  for (int j = 0; j < static_cast<int>(n); ++j) {
    const DynamicInitLandmark& l = aligned.landmarks[static_cast<size_t>(j)];
    if (static_cast<int>(obs.size()) >= config_.max_landmarks) break;
    if (!(l.inverse_depth_sigma > 0.0 && l.inverse_depth_sigma < config_.inverse_depth_sigma) || !(l.depth_m > 0.0) ||
        !std::isfinite(l.depth_m)) {
      continue;
    }
    obs.push_back({l.id, l.uv});
    depths.push_back(l.depth_m);
    candidates.push_back(j);
  }
  // Their inverse depths' joint covariance, and its cross-covariance with [v, psi, b_a] turned as
  // the registration turned them (yaw: none).
  const auto m = static_cast<Eigen::Index>(candidates.size());
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(m, m), C = Eigen::MatrixXd::Zero(m, s.dim());
  for (Eigen::Index a = 0; a < m; ++a) {
    const int ja = candidates[static_cast<size_t>(a)];
    Q(a, a) = std::pow(aligned.landmarks[static_cast<size_t>(ja)].inverse_depth_sigma, 2);
    if (!joint) continue;
    for (Eigen::Index b = 0; b < m; ++b) Q(a, b) = aligned.landmark_covariance(ja, candidates[static_cast<size_t>(b)]);
    const Eigen::Matrix<double, 1, 9> c = aligned.landmark_state_covariance.row(ja) * T.transpose();
    C.block<1, 3>(a, kV) = c.segment<3>(0);
    C.block<1, 3>(a, kPsi) = c.segment<3>(3);
    C.block<1, 3>(a, kBa) = c.segment<3>(6);
    C.block<1, 3>(a, kBg) = aligned.landmark_gyro_bias_covariance.row(ja);
  }
  const int added = static_cast<int>(
      initializeLandmarksInverseDepthJointly(s, obs, depths, Q, C, camera_, s.x.T_b_c, config_.update.pixel_noise_px)
          .size());
  start(std::move(s), aligned.median_depth_m);
  return added;
}

double EkfSlam::newLandmarkDepth() const { return sceneDepth().depth_m; }

EkfSlam::SceneDepth EkfSlam::sceneDepth() const {
  SceneDepth out;
  out.depth_m = config_.inverse_depth_initial_m;
  if (!config_.inverse_depth_scene_prior) return out;
  if (scene_depth_hint_m_ > 0.0) out.depth_m = scene_depth_hint_m_;
  const double max_var = 0.25 * config_.inverse_depth_sigma * config_.inverse_depth_sigma;
  std::vector<std::pair<double, int>> depths;
  for (int i = 0; i < state_.numLandmarks(); ++i) {
    if (state_.landmark(i).kind != LandmarkKind::kInverseDepth) continue;
    const int c = state_.landmarkIndex(i);
    if (!(state_.covariance()(c + 2, c + 2) < max_var)) continue;
    // The depth the new points are then tied to (initializeLandmarksAtMapDepth), as it reads it.
    const double rho = inverseDepthInCamera(state_, i, state_.x.T_b_c);
    if (rho > 0.0 && std::isfinite(1.0 / rho)) depths.emplace_back(1.0 / rho, i);
  }
  if (depths.size() < 10) return out;
  auto mid = depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2);
  std::nth_element(depths.begin(), mid, depths.end());
  out.depth_m = mid->first;
  out.landmark = mid->second;
  return out;
}

bool EkfSlam::initializeLandmark(const FeatureObservation& obs, double inverse_depth_initial_m) {
  switch (config_.landmark_init) {
    case LandmarkInitMethod::kFixedDepth: {
      FixedDepthParams p;
      p.depth_m = config_.landmark_depth_m;
      p.depth_sigma_m = config_.landmark_depth_sigma_m;
      p.pixel_noise_px = config_.update.pixel_noise_px;
      return initializeLandmarkFixedDepth(state_, obs, camera_, state_.x.T_b_c, p);
    }
    case LandmarkInitMethod::kInverseDepth: {
      InverseDepthParams p;
      p.initial_depth_m = inverse_depth_initial_m;
      p.inverse_depth_sigma = config_.inverse_depth_sigma;
      p.pixel_noise_px = config_.update.pixel_noise_px;
      return initializeLandmarkInverseDepth(state_, obs, camera_, state_.x.T_b_c, p);
    }
  }
  return false;
}

void EkfSlam::removeLandmarksById(const std::vector<std::int64_t>& ids) {
  // The well-mapped ones leave for the map kept across resets (VioPipeline's archive).
  if (config_.map.enabled && config_.map.relocalize) {
    const std::unordered_set<std::int64_t> leaving(ids.begin(), ids.end());
    for (const MapPoint& p : mapPoints())
      if (leaving.count(p.id)) left_the_state_.push_back(p);
  }
  std::vector<int> indices;
  for (auto id : ids) {
    if (auto i = state_.findLandmark(id)) indices.push_back(*i);
    last_seen_.erase(id);
    descriptors_.erase(id);
    latest_descriptors_.erase(id);
    dormant_.erase(id);
  }
  state_.removeLandmarks(indices);
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
  const bool at_rest = r.imu_at_rest = imuAtRestBefore(frame.timestamp);
  if (!propagateTo(frame.timestamp)) {
    r.error = "IMU does not reach the frame time yet";
    return r;
  }
  detectStanding(frame, at_rest, &r);
  std::vector<FeatureObservation> known, fresh, pending;
  for (FeatureObservation f : frame.features) {
    // (An id in the clones' range is no track's: refused, it would observe a clone.)
    if (!f.uv.allFinite() || isCloneId(f.id)) continue;
    if (pending_.count(f.id)) {
      pending.push_back(f);
      continue;
    }
    if (const auto a = revisiting_.find(f.id); a != revisiting_.end() && a->second != kNotRevisit) f.id = a->second;
    (state_.findLandmark(f.id) ? known : fresh).push_back(f);
  }
  std::vector<RevisitMatch> revisits;
  if (config_.map.enabled) {
    revisits = confirmRevisits(pending, &fresh, &known, &r.revisits_rejected);
    for (RevisitMatch& m : findRevisits(camera_frame, &fresh, &known)) revisits.push_back(m);
  }
  updateSeenMoving(r);
  const bool defer =
      config_.zero_velocity.enabled && config_.zero_velocity.defer_landmarks && !seen_moving_ && !at_rest;
  UpdateParams update = config_.update;
  update.gate_probability = r.gate_probability = outlier_watch_.gateProbability(config_.update);
  r.update = ekfUpdate(state_, known, camera_, state_.x.T_b_c, update, last_gyro_ - state_.x.b_g);
  // The gate's watch counts the seconds the camera moved: the images' standing test where it has
  // decided (a crawl's IMU is as quiet as a stand's, its images are not), else the IMU's.
  const bool camera_still = r.stationary.decided ? r.stationary.stationary : at_rest;
  outlier_watch_.record(r.update, seen_moving_ && !camera_still, frame.timestamp, config_.update);
  // A revisit the update's gate refused was a false match: its track is a new point from now on,
  // and the landmark stays dormant.
  std::unordered_set<std::int64_t> refused;
  for (const auto& m : revisits) {
    const bool gated_out = std::find(r.update.rejected_ids.begin(), r.update.rejected_ids.end(), m.landmark_id) !=
                               r.update.rejected_ids.end() ||
                           std::find(r.update.invalid_ids.begin(), r.update.invalid_ids.end(), m.landmark_id) !=
                               r.update.invalid_ids.end();
    if (gated_out) {
      revisiting_[m.track_id] = kNotRevisit;
      refused.insert(m.landmark_id);
      ++r.revisits_rejected;
    } else {
      revisiting_[m.track_id] = m.landmark_id;
      r.revisits.push_back(m);
    }
  }
  for (const auto& f : known) {
    if (refused.count(f.id)) continue;
    last_seen_[f.id] = frame.timestamp;
    dormant_.erase(f.id);
  }
  if (triangulationActive()) {
    addLandmarksDelayed(fresh, frame.timestamp, defer, &r);
  } else {
    if (defer) {
      r.deferred_features = static_cast<int>(fresh.size());
      fresh.clear();  // their tracks go on and become landmarks once the rig is seen moving
    }
    r.removed_ids = makeRoomInTheMap(frame.timestamp, static_cast<int>(fresh.size()));
    r.new_ids = addLandmarks(fresh, frame.timestamp);
  }
  if (config_.map.enabled) {
    rememberAppearance(known);
    rememberAppearance(fresh);
    forgetEndedRevisits(frame, revisits);
  }
  r.dormant_landmarks = static_cast<int>(dormant_.size());
  r.left_the_state = std::move(left_the_state_);
  left_the_state_.clear();
  if (shouldCompose(static_cast<int>(r.new_ids.size()))) {
    try {
      delayed_.beforeComposition(state_);
      compose(state_);
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

bool EkfSlam::imuAtRestBefore(double t) {
  // From the samples kept for it (the caller may have propagated to the frame already).
  const double from = t - config_.zero_velocity.still_window_s;
  const bool at_rest = imuAtRest(recent_imu_, from, t, config_.zero_velocity);
  // Later frames are newer: what is older than this frame's window is of no further use.
  while (!recent_imu_.empty() && recent_imu_.front().timestamp < from) recent_imu_.pop_front();
  return at_rest;
}

void EkfSlam::detectStanding(const CameraFrame& frame, bool at_rest, FrameResult* r) {
  if (!config_.zero_velocity.enabled) return;
  const Mat3 R_n_c = (state_.x.q_n_s * state_.x.q_s_b).toRotationMatrix() * state_.x.T_b_c.R_b_c;
  ExpectedMotion expected;
  expected.v_n_b = state_.x.q_n_s * state_.x.v_s_b;
  expected.scene_depth_m = newLandmarkDepth();
  expected.pixel_noise_px = config_.update.pixel_noise_px;
  r->stationary = stationary_.update(frame, R_n_c, camera_, config_.zero_velocity, expected);
  if (r->stationary.stationary)
    r->zero_velocity_applied = zeroVelocityUpdate(state_, config_.zero_velocity, at_rest).applied;
  if (r->zero_velocity_applied) ++zero_velocity_updates_;
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

std::vector<std::int64_t> EkfSlam::makeRoomInTheMap(double t, int wanted) {
  // Tracked landmarks not seen for landmark_timeout_s leave the tracked map, then those seen
  // longest ago make room for the new ones (never one observed in this frame).
  std::vector<std::pair<double, std::int64_t>> by_age;
  for (const auto& [id, seen] : last_seen_)
    if (!dormant_.count(id)) by_age.emplace_back(seen, id);
  std::sort(by_age.begin(), by_age.end());
  std::vector<std::int64_t> leaving;
  size_t k = 0;
  if (config_.landmark_timeout_s >= 0.0) {
    for (; k < by_age.size() && by_age[k].first < t - config_.landmark_timeout_s; ++k)
      leaving.push_back(by_age[k].second);
  }
  while (trackedLandmarks() - static_cast<int>(leaving.size()) + wanted > config_.max_landmarks && k < by_age.size() &&
         by_age[k].first < t) {
    leaving.push_back(by_age[k++].second);
  }
  std::vector<std::int64_t> drop;
  retire(leaving, wanted, &drop);
  removeLandmarksById(drop);
  return drop;
}

void EkfSlam::retire(const std::vector<std::int64_t>& leaving, int wanted, std::vector<std::int64_t>* drop) {
  for (auto id : leaving) {
    const auto i = state_.findLandmark(id);
    if (config_.map.enabled && descriptors_.count(id) && i && wellMapped(*i))
      dormant_.insert(id);
    else
      drop->push_back(id);
  }
  // Dormant points use the room the tracked ones leave in the map (max_landmarks bounds them all,
  // so the cost at the bound is the same), up to map.max_dormant.
  const int tracked = state_.numLandmarks() - static_cast<int>(dormant_.size()) - static_cast<int>(drop->size());
  const int allowed = std::clamp(config_.max_landmarks - wanted - tracked, 0, config_.map.max_dormant);
  int excess = static_cast<int>(dormant_.size()) - allowed;
  if (excess <= 0) return;
  // What a kept point is worth is the place it lets the filter recognize: the map should cover
  // every place walked, not the last few metres. So the dormant points are binned in cells of
  // map.dormant_spacing_m and the most crowded cell gives up a point first, the least certain of
  // its points (the trace of its covariance): a point the filter knows well corrects the pose
  // most when it is seen again.
  std::map<std::array<long, 3>, std::vector<std::pair<double, std::int64_t>>> cells;
  for (auto id : dormant_) {
    const auto i = state_.findLandmark(id);
    if (!i) continue;
    const auto [position, variance] = landmarkPositionVariance(*i);
    const Vec3 p = position / config_.map.dormant_spacing_m;
    const std::array<long, 3> key{std::lround(std::floor(p.x())), std::lround(std::floor(p.y())),
                                  std::lround(std::floor(p.z()))};
    cells[key].emplace_back(variance, id);
  }
  for (auto& [key, points] : cells) std::sort(points.begin(), points.end());  // most certain first
  for (; excess > 0; --excess) {
    auto crowded = cells.begin();
    for (auto it = cells.begin(); it != cells.end(); ++it)
      if (it->second.size() > crowded->second.size()) crowded = it;
    if (crowded == cells.end() || crowded->second.empty()) break;
    const std::int64_t id = crowded->second.back().second;
    crowded->second.pop_back();
    dormant_.erase(id);
    drop->push_back(id);
  }
}

std::vector<RevisitMatch> EkfSlam::findRevisits(const CameraFrame& frame, std::vector<FeatureObservation>* fresh,
                                                std::vector<FeatureObservation>* known) {
  std::vector<RevisitMatch> matches;
  if (descriptors_.empty()) return matches;
  // The well-mapped landmarks not observed in this image (dormant, or whose track just ended),
  // where the filter predicts them.
  std::unordered_set<std::int64_t> observed;
  for (const auto& f : *known) observed.insert(f.id);
  for (const auto& [track, q] : pending_) observed.insert(q.landmark_id);  // one match at a time
  std::vector<RevisitCandidate> candidates;
  const Vec3 omega_b = last_gyro_ - state_.x.b_g;
  for (int i = 0; i < state_.numLandmarks(); ++i) {
    const std::int64_t id = state_.landmarkIds()[static_cast<size_t>(i)];
    const auto d = descriptors_.find(id);
    if (d == descriptors_.end() || observed.count(id) || !wellMapped(i)) continue;
    const auto p = predictWithCovariance(state_, i, camera_, state_.x.T_b_c, config_.update, omega_b);
    if (p) candidates.push_back({id, p->uv, p->S, d->second});
  }
  if (candidates.empty()) return matches;
  // Proposals: each a landmark and the observation that would be it.
  struct Proposal {
    RevisitMatch match;
    FeatureObservation obs;  ///< under its own id (a fresh track's, or the search's corner's)
    bool searched = false;
  };
  std::vector<Proposal> proposals;
  // 1) The new tracks of this image (a point the detector found again), told apart from the
  //    image's other tracks too (matchRevisits).
  std::vector<FeatureObservation> searching;
  std::unordered_set<std::int64_t> searching_ids;
  for (const auto& f : *fresh) {
    if (f.descriptor && !revisiting_.count(f.id)) {
      searching.push_back(f);
      searching_ids.insert(f.id);
    }
  }
  std::vector<FeatureObservation> other_tracks, all_tracks;
  for (const auto& f : frame.features) {
    const auto& d = f.latest_descriptor ? f.latest_descriptor : f.descriptor;
    if (!d) continue;
    all_tracks.push_back({f.id, f.uv, d});
    if (!searching_ids.count(f.id)) other_tracks.push_back(all_tracks.back());
  }
  for (const auto& m : matchRevisits(candidates, searching, config_.map, other_tracks)) {
    const auto f = std::find_if(searching.begin(), searching.end(), [&](const auto& o) { return o.id == m.track_id; });
    proposals.push_back({m, *f, false});
  }
  // 2) The others: the front end looks again inside their regions.
  std::vector<FeatureObservation> corners;
  if (frame.search && frame.adopt) {
    std::vector<RevisitCandidate> rest;
    std::vector<SearchRegion> regions;
    const double max_var = config_.map.max_search_sigma_px * config_.map.max_search_sigma_px;
    for (const auto& c : candidates) {
      const bool taken = std::any_of(proposals.begin(), proposals.end(),
                                     [&](const auto& q) { return q.match.landmark_id == c.landmark_id; });
      if (taken || !(c.S.trace() <= 2.0 * max_var)) continue;
      rest.push_back(c);
      regions.push_back({c.landmark_id, c.uv, c.S});
    }
    if (!regions.empty()) corners = frame.search(regions);
    for (const auto& m : matchRevisits(rest, corners, config_.map, all_tracks)) {
      const auto c = std::find_if(corners.begin(), corners.end(), [&](const auto& o) { return o.id == m.track_id; });
      proposals.push_back({m, *c, true});
    }
  }
  // 3) Joint compatibility: one look-alike alone in a region passes every test above, but the
  //    matches of one image must agree on the one pose error that moved their landmarks. The
  //    stacked innovation (with the landmarks' cross-covariances) must pass the chi^2 gate of its
  //    dimension; the match that disagrees most leaves until it does, and fewer than
  //    map.min_joint_revisits agreeing matches are none.
  const double joint_gate = config_.update.gate_probability;
  while (static_cast<int>(proposals.size()) >= std::max(1, config_.map.min_joint_revisits)) {
    std::vector<FeatureObservation> as_landmarks;
    as_landmarks.reserve(proposals.size());
    for (const auto& q : proposals) as_landmarks.push_back({q.match.landmark_id, q.obs.uv, std::nullopt});
    const JointInnovation j = jointInnovation(state_, as_landmarks, camera_, state_.x.T_b_c, config_.update, omega_b);
    if (j.valid && j.nis <= chiSquaredQuantile(joint_gate, 2.0 * static_cast<double>(proposals.size()))) break;
    const size_t worst =
        j.valid ? static_cast<size_t>(std::max_element(j.each.begin(), j.each.end()) - j.each.begin()) : 0;
    proposals.erase(proposals.begin() + static_cast<std::ptrdiff_t>(worst));
  }
  if (static_cast<int>(proposals.size()) < config_.map.min_joint_revisits) return matches;
  // The agreeing matches observe their landmarks under their ids (or, with revisit_confirm_frames
  // > 1, are pending until their tracks have agreed that long); a searched corner becomes a track
  // of the front end, which observes the landmark from then on.
  for (const auto& q : proposals) {
    RevisitMatch m = q.match;
    if (q.searched) {
      m.track_id = frame.adopt(q.obs);
    } else {
      fresh->erase(std::find_if(fresh->begin(), fresh->end(), [&](const auto& o) { return o.id == q.obs.id; }));
    }
    if (config_.map.revisit_confirm_frames > 1) {
      const auto c = std::find_if(candidates.begin(), candidates.end(),
                                  [&](const auto& x) { return x.landmark_id == m.landmark_id; });
      pending_[m.track_id] = {m.landmark_id, m.distance, 1, q.obs.uv - c->uv, state_.timestamp};
      continue;
    }
    known->push_back(q.obs);
    known->back().id = m.landmark_id;
    matches.push_back(m);
  }
  return matches;
}

std::vector<RevisitMatch> EkfSlam::confirmRevisits(const std::vector<FeatureObservation>& pending,
                                                   std::vector<FeatureObservation>* fresh,
                                                   std::vector<FeatureObservation>* known, int* refused) {
  std::vector<RevisitMatch> confirmed;
  std::unordered_set<std::int64_t> observed;
  for (const auto& f : *known) observed.insert(f.id);
  // (The search's gate at least: a match at the edge of the update's narrow gate is no look-alike.)
  const double gate_probability =
      std::max(config_.map.search_gate_probability, outlier_watch_.gateProbability(config_.update));
  const Vec3 omega_b = last_gyro_ - state_.x.b_g;
  for (const auto& f : pending) {
    PendingRevisit& q = pending_.at(f.id);
    const std::optional<int> i = state_.findLandmark(q.landmark_id);
    std::optional<PredictedPixel> p;
    if (i && !observed.count(q.landmark_id))
      p = predictWithCovariance(state_, *i, camera_, state_.x.T_b_c, config_.update, omega_b);
    if (!p || !pendingRevisitAgrees(f.uv - p->uv, p->S, q.first_innovation, gate_probability,
                                    config_.update.pixel_noise_px, config_.map)) {
      revisiting_[f.id] = kNotRevisit;  // a new point from now on
      pending_.erase(f.id);
      fresh->push_back(f);
      ++*refused;
      continue;
    }
    if (++q.frames < config_.map.revisit_confirm_frames) continue;
    confirmed.push_back({f.id, q.landmark_id, q.distance});
    observed.insert(q.landmark_id);
    known->push_back(f);
    known->back().id = q.landmark_id;
    pending_.erase(f.id);
  }
  return confirmed;
}

std::pair<Vec3, double> EkfSlam::landmarkPositionVariance(int i) const {
  Mat3 M;
  const Vec3 p = state_.landmark(i).position(&M);
  const int c = state_.landmarkIndex(i);
  return {p, (M * state_.covariance().block<3, 3>(c, c) * M.transpose()).trace()};
}

bool EkfSlam::wellMapped(int i) const {
  const auto [p, var] = landmarkPositionVariance(i);
  const double distance = (p - state_.x.p_s_b).norm();
  return std::isfinite(var) && var <= std::pow(config_.map.max_relative_sigma * distance, 2);
}

void EkfSlam::rememberAppearance(const std::vector<FeatureObservation>& observed) {
  for (const auto& f : observed) {
    if (!state_.findLandmark(f.id)) continue;
    if (f.descriptor && !descriptors_.count(f.id)) descriptors_[f.id] = *f.descriptor;
    if (const auto& d = f.latest_descriptor ? f.latest_descriptor : f.descriptor) latest_descriptors_[f.id] = *d;
  }
}

void EkfSlam::forgetEndedRevisits(const CameraFrame& frame, const std::vector<RevisitMatch>& started) {
  if (revisiting_.empty() && pending_.empty()) return;
  std::unordered_set<std::int64_t> live;
  for (const auto& f : frame.features) live.insert(f.id);
  for (const auto& m : started) live.insert(m.track_id);  // adopted in this image: seen from the next on
  for (auto it = revisiting_.begin(); it != revisiting_.end();)
    it = live.count(it->first) ? std::next(it) : revisiting_.erase(it);
  for (auto it = pending_.begin(); it != pending_.end();) {
    // (A corner adopted in this image is tracked from the next.)
    it = live.count(it->first) || it->second.found_t == state_.timestamp ? std::next(it) : pending_.erase(it);
  }
}

std::vector<MapPoint> EkfSlam::mapPoints() const {
  std::vector<MapPoint> out;
  for (const NavLandmark& l : navLandmarks(state_)) {
    const auto d = latest_descriptors_.find(l.id);
    const std::optional<int> i = state_.findLandmark(l.id);
    if (d == latest_descriptors_.end() || !i || !wellMapped(*i)) continue;
    out.push_back({l.id, l.p_n_l, l.cov, d->second});
  }
  return out;
}

void EkfSlam::moveWorld(const Eigen::Isometry3d& T_new_old) {
  // In a sensor-centric layout only the pose of {s} in {n} lives in {n}; a world-centric state
  // goes through that layout and back (its clones' orientations are in the frame being left).
  const Mechanization m = state_.mechanization();
  if (!isSensorCentric(m)) {
    delayed_.clear(&state_);
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

void EkfSlam::forgetMap() {
  descriptors_.clear();
  latest_descriptors_.clear();
  dormant_.clear();
  revisiting_.clear();
  pending_.clear();
}

std::vector<std::int64_t> EkfSlam::addLandmarks(const std::vector<FeatureObservation>& fresh, double t) {
  std::vector<std::int64_t> added;
  if (fresh.empty()) return added;
  const SceneDepth scene = sceneDepth();
  if (scene.landmark >= 0 && config_.landmark_init == LandmarkInitMethod::kInverseDepth) {
    // At the map's depth, tied to the map's median point (initializeLandmarksAtMapDepth).
    const auto room = static_cast<size_t>(std::max(0, config_.max_landmarks - state_.numLandmarks()));
    const std::vector<FeatureObservation> obs(fresh.begin(), fresh.begin() + std::min(room, fresh.size()));
    for (int k : initializeLandmarksAtMapDepth(state_, obs, scene.landmark, config_.inverse_depth_sigma, camera_,
                                               state_.x.T_b_c, config_.update.pixel_noise_px)) {
      added.push_back(obs[static_cast<size_t>(k)].id);
      last_seen_[added.back()] = t;
    }
    return added;
  }
  const double new_depth_m = scene.depth_m;
  for (const auto& f : fresh) {
    if (state_.numLandmarks() >= config_.max_landmarks) break;
    if (initializeLandmark(f, new_depth_m)) {
      added.push_back(f.id);
      last_seen_[f.id] = t;
    }
  }
  return added;
}

bool EkfSlam::triangulationActive() const {
  return config_.triangulation.enabled && config_.landmark_init == LandmarkInitMethod::kInverseDepth &&
         state_.mechanization() == Mechanization::kSensorCentricComposition &&
         config_.composition_trigger == CompositionTrigger::kEveryUpdate;
}

void EkfSlam::addLandmarksDelayed(const std::vector<FeatureObservation>& fresh, double t, bool defer, FrameResult* r) {
  const double pixel_var = config_.update.pixel_noise_px * config_.update.pixel_noise_px;
  // Tracks wait for their baseline while the rig is seen moving (the baseline then comes within
  // max_wait_s; a point entering at the prior depth would be linearized at a depth that may be
  // off by a factor of five while the camera moves under it) and while the zero-velocity rules
  // hold new tracks back (standing, swaying, a start the detector cannot tell yet): a track then
  // enters only with the full baseline and depth gate, never at the prior depth, and a short map
  // does not take the waiting ones early (a sway's two views are what the rules keep out). At
  // rest by the IMU they enter at the prior depth, as without the delay.
  const bool wait = seen_moving_ || defer;
  const int fill = defer ? 0 : config_.triangulation.min_map_landmarks - (trackedLandmarks() - delayed_.clones());
  const DelayedLandmarks::Selection sel = delayed_.select(state_, fresh, camera_, state_.x.T_b_c, config_.triangulation,
                                                          pixel_var, config_.update.gate_probability, wait,
                                                          1.0 / newLandmarkDepth(), fill, config_.inverse_depth_sigma);
  // The expired (not waiting, or taken by a map short of landmarks) enter at the prior depth.
  const std::vector<FeatureObservation>& at_prior = sel.expired;
  // Room for both and for a clone.
  r->removed_ids = makeRoomInTheMap(t, static_cast<int>(sel.triangulated.size() + at_prior.size()) + 1);
  const int capacity = config_.max_landmarks - state_.numLandmarks();
  r->new_ids = delayed_.commit(state_, sel, fresh, capacity, state_.x.T_b_c, config_.triangulation);
  r->new_triangulated = static_cast<int>(r->new_ids.size());
  for (auto id : r->new_ids) last_seen_[id] = t;
  for (auto id : addLandmarks(at_prior, t)) r->new_ids.push_back(id);
  if (defer) r->deferred_features = static_cast<int>(fresh.size()) - r->new_triangulated;
  r->waiting_features = delayed_.waitingTracks();
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
  g_n_ = gravityInNav(config_.gravity_mps2);
  if (config.mechanization != previous) setMechanization(config.mechanization);
  // Waiting switched off (or no longer possible): the tracks start again as new ones, the clones go.
  if (!triangulationActive()) delayed_.clear(&state_);
  return true;
}

void EkfSlam::setMechanization(Mechanization m) {
  config_.mechanization = m;
  delayed_.clear(&state_);  // the clones' orientations are in the frame being left
  if (initialized_)
    switchMechanization(state_, m);
  else
    state_ = FilterState(m);
}

}  // namespace vi_ekf_slam
