#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <variant>

#include "vi_ekf_slam/core/dynamic_init/alignment_problem.h"
#include "vi_ekf_slam/core/dynamic_init/alignment_uncertainty.h"
#include "vi_ekf_slam/core/dynamic_init/time_offset_search.h"
#include "vi_ekf_slam/core/dynamic_init/track_selection.h"
#include "vi_ekf_slam/core/param_ranges.h"

namespace vi_ekf_slam {

std::string DynamicInitParams::validate() const {
  std::ostringstream err;
  checkRange(err, "dynamic_init_window_s", window_s);
  checkRange(err, "dynamic_init_max_window_s", max_window_s);
  checkRange(err, "dynamic_init_min_frames", min_frames);
  checkRange(err, "dynamic_init_min_observations", min_observations);
  checkRange(err, "dynamic_init_min_features", min_features);
  checkRange(err, "dynamic_init_max_velocity_sigma_mps", max_velocity_sigma_mps);
  checkRange(err, "dynamic_init_max_tilt_sigma_rad", max_tilt_sigma_rad);
  checkRange(err, "dynamic_init_max_scale_sigma", max_scale_sigma);
  checkRange(err, "dynamic_init_gyro_bias_sigma_radps", gyro_bias_sigma_radps);
  checkRange(err, "dynamic_init_accel_bias_sigma_mps2", accel_bias_sigma_mps2);
  checkRange(err, "pixel_noise_px", pixel_noise_px);
  checkRange(err, "gravity_mps2", gravity_mps2);
  return err.str();
}

DynamicInitParams withFilterSettings(DynamicInitParams p, const EkfSlamConfig& filter) {
  p.pixel_noise_px = filter.update.pixel_noise_px;
  p.time_offset_sigma_s = filter.initial.time_offset_s;
  p.accel_bias_sigma_mps2 = filter.initial.accel_bias_mps2;
  p.gravity_mps2 = filter.gravity_mps2;
  return p;
}

DynamicInitializer::DynamicInitializer(const DynamicInitParams& params, const CameraModel& camera,
                                       const CameraExtrinsics& T_b_c)
    : params_(params), camera_(camera), T_b_c_(T_b_c) {}

void DynamicInitializer::reset() {
  imu_.clear();
  frames_.clear();
}

std::optional<alignment::Preintegrated> DynamicInitializer::imuBetween(double t0, double t1, const Vec3& b_g) const {
  if (imu_.empty() || !(t0 <= t1) || imu_.front().timestamp > t0 || imu_.back().timestamp < t1) return std::nullopt;
  return alignment::preintegrate(imu_, {t0, t1}, b_g).back();
}

void DynamicInitializer::addImu(const ImuData& imu) {
  if (!isFinite(imu)) return;
  if (!imu_.empty() && imu.timestamp <= imu_.back().timestamp) return;
  imu_.push_back(imu);
  // Keep what the window can need (frames wait for the IMU to pass them).
  const double keep_from = imu.timestamp - std::max(params_.window_s, params_.max_window_s) - 1.0;
  while (imu_.size() > 2 && imu_[1].timestamp < keep_from) imu_.pop_front();
}

void DynamicInitializer::addFrame(const CameraFrame& frame) {
  if (!std::isfinite(frame.timestamp)) return;
  if (!frames_.empty() && frame.timestamp <= frames_.back().timestamp) return;
  frames_.push_back(frame);
  const double keep_s = std::max(params_.window_s, params_.max_window_s) + 1.0;
  while (!frames_.empty() && frames_.front().timestamp < frame.timestamp - keep_s) frames_.pop_front();
}

std::vector<const CameraFrame*> DynamicInitializer::coveredFrames(double span_s) const {
  std::vector<const CameraFrame*> window;
  if (imu_.size() < 2) return window;
  const double search = params_.time_offset_search_s;
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    if (it->timestamp + search > imu_.back().timestamp) continue;
    if (it->timestamp - search < imu_.front().timestamp) break;
    if (!window.empty() && window.back()->timestamp - it->timestamp > span_s) break;
    window.insert(window.begin(), &*it);
  }
  return window;
}

std::optional<DynamicInitResult> DynamicInitializer::tryInitialize(std::string* why) {
  std::string first_why;
  bool degenerate = false;
  std::optional<DynamicInitResult> r = alignSpan(params_.window_s, &first_why, &degenerate);
  if (!r && degenerate && params_.max_window_s > params_.window_s) {
    // Too little motion in the window: the frames before it may hold the acceleration it lacks.
    const std::vector<const CameraFrame*> longer = coveredFrames(params_.max_window_s);
    const double span = longer.empty() ? 0.0 : longer.back()->timestamp - longer.front()->timestamp;
    if (span > 1.1 * params_.window_s) {
      std::string longer_why;
      r = alignSpan(span, &longer_why, nullptr);
      if (!r) {
        std::ostringstream w;
        w.precision(3);
        w << first_why << "; over " << span << " s: " << longer_why;
        first_why = w.str();
      }
    }
  }
  if (why) *why = r ? std::string() : first_why;
  return r;
}

namespace {

constexpr size_t kMaxFeatures = 80;  ///< tracks the alignment uses at most (a bounded problem)

alignment::ProblemSettings problemSettings(const DynamicInitParams& p) {
  alignment::ProblemSettings s;
  s.gravity_mps2 = p.gravity_mps2;
  s.pixel_noise_px = p.pixel_noise_px;
  s.accel_bias_sigma_mps2 = p.accel_bias_sigma_mps2;
  s.time_offset_sigma_s = p.time_offset_sigma_s;
  s.min_features = p.min_features;
  return s;
}

alignment::UncertaintySettings uncertaintySettings(const DynamicInitParams& p) {
  alignment::UncertaintySettings s;
  s.gyro_bias_sigma_radps = p.gyro_bias_sigma_radps;
  s.time_offset_sigma_s = p.time_offset_sigma_s;
  s.time_offset_search_s = p.time_offset_search_s;
  return s;
}

/// Why an attempt failed; degenerate: the window's motion leaves the state unobservable (a
/// longer window may not).
struct Failure {
  std::string why;
  bool degenerate = false;
};

std::string formatted(const std::function<void(std::ostream&)>& write) {
  std::ostringstream s;
  s.precision(3);
  write(s);
  return s.str();
}

/// Whether a covariance knows the velocity and the tilt well enough to start; otherwise why.
std::optional<Failure> unobservable(const alignment::StateCovariance& c, const DynamicInitParams& p) {
  if (!(c.velocity_sigma_mps <= p.max_velocity_sigma_mps)) {
    return Failure{formatted([&](std::ostream& o) {
                     o << "degenerate motion: velocity known to " << c.velocity_sigma_mps << " m/s only (more than "
                       << p.max_velocity_sigma_mps << "): too little acceleration or parallax";
                   }),
                   true};
  }
  if (!(c.tilt_sigma_rad <= p.max_tilt_sigma_rad)) {
    return Failure{formatted([&](std::ostream& o) {
                     o << "degenerate motion: roll/pitch known to " << c.tilt_sigma_rad << " rad only (more than "
                       << p.max_tilt_sigma_rad << ")";
                   }),
                   true};
  }
  return std::nullopt;
}

/// The result stage: the refined problem's state, covariance and landmarks, unless the residuals
/// or the uncertainty say the window is not good enough to start from.
std::variant<DynamicInitResult, Failure> resultOf(alignment::AlignmentProblem& problem,
                                                  const alignment::TimeOffsetFit& fit, const std::deque<ImuData>& imu,
                                                  const DynamicInitParams& p) {
  const alignment::AlignmentUncertainty uncertainty(problem, imu, fit, uncertaintySettings(p));
  alignment::StateCovariance cov = uncertainty.covariance(p.pixel_noise_px);
  if (auto f = unobservable(cov, p)) return *f;
  double sum_sq = 0.0;
  int rows = 0;
  if (!problem.residuals(&sum_sq, &rows)) {
    return Failure{"alignment puts a feature behind the camera: wrong tracks or IMU"};
  }
  DynamicInitResult r;
  r.frames = static_cast<int>(problem.times().size());
  r.features = problem.numActive();
  r.residual_rms_px = std::sqrt(sum_sq / std::max(1, rows));
  if (r.residual_rms_px > 5.0 * p.pixel_noise_px) {
    return Failure{formatted([&](std::ostream& o) {
      o << "alignment residual " << r.residual_rms_px << " px: tracks or IMU inconsistent";
    })};
  }
  // The noise the residuals show, if more than the assumed pixel noise, scales the uncertainty.
  const int dof = std::max(1, rows - (3 * problem.numActive() + 5));
  const double sigma_px = std::max(p.pixel_noise_px, std::sqrt(sum_sq / dof));
  cov = uncertainty.covariance(sigma_px);
  if (auto f = unobservable(cov, p)) return *f;
  r.state.timestamp = problem.times().back();
  r.time_offset_correction_s = fit.dt_s;
  r.state.q_n_b = uncertainty.state().q_n_b;
  r.state.v_n_b = uncertainty.state().v_n;
  r.state.b_a = problem.y().tail<3>();
  r.covariance = cov.covariance;
  uncertainty.addLandmarks(problem, sigma_px, cov, &r);
  // The scale of the scene: the mean inverse depth of the last frame's features, whose error is
  // mostly the error they share (their own errors average out). A velocity known to 0.07 m/s is a
  // good start for a walk at 1.3 m/s and no start for a hand moving at 0.1 m/s: the velocity's
  // sigma is absolute, the scale's relative, and what a monocular start cannot do without.
  const int n = static_cast<int>(r.landmarks.size());
  if (n == 0) return Failure{"no feature of the last image placed: nothing to give the scale"};
  double mean_rho = 0.0;
  for (const DynamicInitLandmark& l : r.landmarks) mean_rho += 1.0 / l.depth_m;
  mean_rho /= n;
  r.scale_sigma = std::sqrt(std::max(0.0, r.landmark_covariance.sum())) / n / mean_rho;
  if (!(r.scale_sigma <= p.max_scale_sigma)) {
    return Failure{formatted([&](std::ostream& o) {
                     o << "degenerate motion: the scene's scale known to " << 100.0 * r.scale_sigma
                       << "% only (more than " << 100.0 * p.max_scale_sigma
                       << "%): too little acceleration for its depth";
                   }),
                   true};
  }
  // The scene's depth from the features whose depth the window determined (to 50%): without
  // parallax (a rig at rest) the depths are arbitrary.
  std::vector<double> depths;
  for (const DynamicInitLandmark& l : r.landmarks) {
    if (l.inverse_depth_sigma * l.depth_m < 0.5) depths.push_back(l.depth_m);
  }
  if (depths.size() >= 3) {
    std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
    r.median_depth_m = depths[depths.size() / 2];
  }
  r.velocity_sigma_mps = cov.velocity_sigma_mps;
  r.tilt_sigma_rad = cov.tilt_sigma_rad;
  r.gyro_bias_sigma_radps = p.gyro_bias_sigma_radps;
  r.accel_bias_sigma_mps2 = std::sqrt(std::max(
      0.0, Eigen::SelfAdjointEigenSolver<Mat3>(cov.covariance.bottomRightCorner<3, 3>()).eigenvalues().maxCoeff()));
  return r;
}

}  // namespace

std::optional<DynamicInitResult> DynamicInitializer::alignSpan(double span_s, std::string* why, bool* degenerate) {
  auto fail = [&](const Failure& f) -> std::optional<DynamicInitResult> {
    if (why) *why = f.why;
    if (degenerate && f.degenerate) *degenerate = true;
    return std::nullopt;
  };
  if (imu_.size() < 2 || frames_.empty()) return fail({"waiting for IMU and images"});
  const std::vector<const CameraFrame*> window = coveredFrames(span_s);
  if (static_cast<int>(window.size()) < params_.min_frames) {
    return fail(
        {"collecting images (" + std::to_string(window.size()) + " of " + std::to_string(params_.min_frames) + ")"});
  }
  // A short span aligns poorly (velocity and gravity come from the curvature of the path): the
  // images must span the window (within 10%).
  if (window.back()->timestamp - window.front()->timestamp < 0.9 * span_s) {
    return fail({"collecting images (" + std::to_string(window.back()->timestamp - window.front()->timestamp) +
                 " s of " + std::to_string(span_s) + " s)"});
  }
  std::vector<alignment::Track> tracks =
      alignment::selectTracks(window, camera_, params_.min_observations, kMaxFeatures);
  if (static_cast<int>(tracks.size()) < params_.min_features) {
    return fail({"too few features tracked through " + std::to_string(params_.min_observations) + " images (" +
                 std::to_string(tracks.size()) + " of " + std::to_string(params_.min_features) + ")"});
  }
  std::vector<double> stamps;
  stamps.reserve(window.size());
  for (const auto* f : window) stamps.push_back(f->timestamp);
  alignment::AlignmentProblem problem(imu_, std::move(stamps), std::move(tracks), camera_, T_b_c_,
                                      problemSettings(params_));
  const alignment::TimeOffsetFit fit = alignment::searchTimeOffset(problem, params_.time_offset_search_s);
  if (!std::isfinite(problem.refine(fit.dt_s))) {
    return fail({"degenerate motion: the alignment has no solution with the features in front of the camera", true});
  }
  if (!problem.dropUndeterminedFeatures(fit.dt_s)) {
    return fail({"degenerate motion: too few features whose depth the window determines", true});
  }
  if (!problem.eliminateAtSolution()) return fail({"alignment puts a feature behind the camera: wrong tracks or IMU"});
  auto result = resultOf(problem, fit, imu_, params_);
  if (auto* f = std::get_if<Failure>(&result)) return fail(*f);
  if (why) why->clear();
  return std::get<DynamicInitResult>(std::move(result));
}

}  // namespace vi_ekf_slam
