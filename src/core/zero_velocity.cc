#include "vi_ekf_slam/core/zero_velocity.h"

#include <Eigen/Cholesky>
#include <algorithm>

#include "vi_ekf_slam/core/chi_squared.h"

namespace vi_ekf_slam {

StationaryDetector::Decision StationaryDetector::update(const CameraFrame& frame, const Mat3& R_n_c,
                                                        const CameraModel& camera, const ZeroVelocityParams& params) {
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
    std::vector<double> disp;
    disp.reserve(now.xn.size());
    for (const auto& [id, xn] : now.xn) {
      const auto it = ref.xn.find(id);
      if (it == ref.xn.end()) continue;
      const Vec3 r = R_now_ref * Vec3(it->second.x(), it->second.y(), 1.0);
      if (r.z() <= 1e-6) continue;
      disp.push_back(camera.intrinsics().fx * (xn - r.head<2>() / r.z()).norm());
    }
    d.features = static_cast<int>(disp.size());
    if (d.features >= params.min_features) {
      std::nth_element(disp.begin(), disp.begin() + static_cast<long>(disp.size() / 2), disp.end());
      d.parallax_px = disp[disp.size() / 2];
      d.decided = true;
      d.stationary = d.parallax_px < params.max_parallax_px;
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
  ZeroVelocityResult res;
  Eigen::MatrixXd& P = state.mutableCovariance();
  const Eigen::MatrixXd B = P.middleCols<3>(idx::kV);  // P H^T, H = [0 I 0]
  Mat3 S = B.middleRows<3>(idx::kV);
  S.diagonal().array() += sigma * sigma;
  const Eigen::LLT<Mat3> llt(S);
  if (llt.info() != Eigen::Success) return res;
  const Vec3 r = -state.x.v_s_b;  // z - h(x) with z = 0
  res.nis = r.dot(llt.solve(r));
  if (!std::isfinite(res.nis) || res.nis > chiSquaredQuantile(params.gate_probability, 3.0)) return res;
  const Eigen::MatrixXd K = llt.solve(B.transpose()).transpose();
  const Eigen::VectorXd dx = K * r;
  P.triangularView<Eigen::Lower>() -= K * B.transpose();
  P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
  state.boxplus(dx);
  res.applied = true;
  return res;
}

}  // namespace vi_ekf_slam
