#include "vi_ekf_slam/core/zero_velocity.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "vi_ekf_slam/core/kalman_update.h"

namespace vi_ekf_slam {

namespace {
/// The images show the filter's translation when lambda is this many of its sigmas above 0: a
/// standing rig's pixel noise does so with a probability of 3e-5 per image.
constexpr double kMotionSigmas = 4.0;
/// Huber threshold of the lambda fit, in sigmas of a feature's displacement: a slipped track
/// weighs as a few pixels of noise, not as its full error.
constexpr double kHuberSigmas = 3.0;

struct MotionFit {
  double lambda = std::numeric_limits<double>::quiet_NaN();
  double sigma = std::numeric_limits<double>::infinity();
};

/// measured ~ lambda * predicted + noise (sigma_px per axis), by iteratively reweighted least
/// squares with Huber weights on each feature's residual.
MotionFit fitMotionShare(const std::vector<Eigen::Vector2d>& measured, const std::vector<Eigen::Vector2d>& predicted,
                         double sigma_px) {
  MotionFit fit;
  std::vector<double> w(measured.size(), 1.0);
  const double k = kHuberSigmas * sigma_px;
  for (int it = 0; it < 4; ++it) {
    if (it > 0) {  // reweighted by the residuals of the last fit
      for (size_t i = 0; i < measured.size(); ++i) {
        const double e = (measured[i] - fit.lambda * predicted[i]).norm();
        w[i] = e <= k ? 1.0 : k / e;
      }
    }
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < measured.size(); ++i) {
      num += w[i] * measured[i].dot(predicted[i]);
      den += w[i] * predicted[i].squaredNorm();
    }
    if (!(den > 0.0)) return MotionFit{};
    fit.lambda = num / den;
    fit.sigma = sigma_px / std::sqrt(den);
  }
  return fit;
}
}  // namespace

StationaryDetector::Decision StationaryDetector::update(const CameraFrame& frame, const Mat3& R_n_c,
                                                        const CameraModel& camera, const ZeroVelocityParams& params,
                                                        const std::optional<ExpectedMotion>& expected) {
  Decision d;
  Past now{frame.timestamp, R_n_c, {}};
  for (const auto& f : frame.features) {
    Eigen::Vector2d xn;
    if (f.uv.allFinite() && camera.pixelToNormalized(f.uv, &xn)) now.xn.emplace(f.id, xn);
  }
  // A stamp going back (bag restart) invalidates the history.
  if (!history_.empty() && frame.timestamp <= history_.back().t) history_.clear();
  // The reference frame: the newest one at least window_s old.
  while (history_.size() > 1 && history_[1].t <= frame.timestamp - params.window_s) history_.pop_front();
  if (!history_.empty() && frame.timestamp - history_.front().t >= params.window_s) {
    d.has_history = true;
    const Past& ref = history_.front();
    const Mat3 R_now_ref = R_n_c.transpose() * ref.R_n_c;
    const Eigen::Vector2d focal(camera.intrinsics().fx, camera.intrinsics().fy);
    // The filter's translation over the window, in the current camera [m].
    const Vec3 t_c = expected ? Vec3(R_n_c.transpose() * expected->v_n_b * (frame.timestamp - ref.t)) : Vec3::Zero();
    std::vector<double> disp;
    std::vector<Eigen::Vector2d> measured, predicted;
    disp.reserve(now.xn.size());
    for (const auto& [id, xn] : now.xn) {
      const auto it = ref.xn.find(id);
      if (it == ref.xn.end()) continue;
      const Vec3 r = R_now_ref * Vec3(it->second.x(), it->second.y(), 1.0);
      if (r.z() <= 1e-6) continue;
      const Eigen::Vector2d m = focal.cwiseProduct(xn - r.head<2>() / r.z());
      disp.push_back(m.norm());
      if (!expected) continue;
      const Vec3 X = expected->scene_depth_m * r - t_c;  // the point at the scene's depth, moved
      if (X.z() <= 1e-6) continue;
      measured.push_back(m);
      predicted.push_back(focal.cwiseProduct(X.head<2>() / X.z() - r.head<2>() / r.z()));
    }
    d.features = static_cast<int>(disp.size());
    if (d.features >= params.min_features) {
      std::nth_element(disp.begin(), disp.begin() + static_cast<long>(disp.size() / 2), disp.end());
      d.parallax_px = disp[disp.size() / 2];
      d.decided = true;
      if (expected) {
        // A displacement is the difference of two positions: sqrt(2) pixel noises per axis.
        const MotionFit fit = fitMotionShare(measured, predicted, std::sqrt(2.0) * expected->pixel_noise_px);
        d.motion_shown = fit.lambda;
        d.motion_shown_sigma = fit.sigma;
        // The speed the images show (at the scene's depth) must also be beyond a stand's sway:
        // a swaying rig translates too, and along the filter's drift as often as not.
        d.motion_shown_speed_mps = fit.lambda * expected->v_n_b.norm();
        d.motion_confirmed =
            fit.lambda >= kMotionSigmas * fit.sigma && d.motion_shown_speed_mps > params.velocity_sigma_mps;
      }
      d.stationary = d.parallax_px < params.max_parallax_px && !d.motion_confirmed;
    }
  }
  history_.push_back(std::move(now));
  return d;
}

bool imuAtRest(const std::deque<ImuData>& imu, double t0, double t1, const ZeroVelocityParams& params) {
  Vec3 sum = Vec3::Zero(), sum_sq = Vec3::Zero();
  int n = 0;
  for (const auto& s : imu) {
    if (s.timestamp < t0 || s.timestamp > t1) continue;
    if (!(s.wm.cwiseAbs().maxCoeff() < params.still_gyro_radps)) return false;
    sum += s.am;
    sum_sq += s.am.cwiseProduct(s.am);
    ++n;
  }
  if (n < 2) return false;
  const Vec3 var = (sum_sq - sum.cwiseProduct(sum) / n) / (n - 1);
  return var.maxCoeff() < params.still_accel_std_mps2 * params.still_accel_std_mps2;
}

ZeroVelocityResult zeroVelocityUpdate(FilterState& state, const ZeroVelocityParams& params, bool at_rest) {
  const double sigma = at_rest ? params.rest_velocity_sigma_mps : params.velocity_sigma_mps;
  MeasurementRows zero_velocity;  // z = 0 = v_s_b, H = [0 I 0]
  zero_velocity.blocks = {{idx::kV, Mat3::Identity()}};
  zero_velocity.residual = -state.x.v_s_b;
  zero_velocity.noise_var = sigma * sigma;
  const KalmanUpdateResult r = kalmanUpdate(state, {zero_velocity}, params.gate_probability);
  return {r.applied, r.nis};
}

}  // namespace vi_ekf_slam
