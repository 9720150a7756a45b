#include "vi_ekf_slam/core/divergence_monitor.h"

#include "vi_ekf_slam/core/param_ranges.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <sstream>

namespace vi_ekf_slam {

std::string DivergenceParams::validate() const {
  std::ostringstream err;
  checkRange(err, "lost_max_speed_mps", max_speed_mps);
  checkRange(err, "lost_max_rejected_fraction", max_rejected_fraction);
  checkRange(err, "lost_window_s", window_s);
  checkRange(err, "lost_min_observations", min_observations);
  return err.str();
}

std::string DivergenceMonitor::update(double t, const FilterState& state, int accepted, int rejected,
                                      const DivergenceParams& params) {
  if (!params.enabled) return "";
  // The motion block carries every navigation quantity; a failed Cholesky factorization means it
  // lost positive definiteness (or a non-finite entry).
  const MotionMatrix P = state.motionCovariance();
  MotionMatrix Pd = P;
  for (int i = 0; i < Pd.rows(); ++i) {
    if (Pd(i, i) == 0.0) Pd(i, i) = 1.0;  // a fixed entry (e.g. the time offset) is not a fault
  }
  if (!P.allFinite() || Eigen::LLT<MotionMatrix>(Pd).info() != Eigen::Success || (P.diagonal().array() < 0.0).any()) {
    return "covariance no longer positive definite";
  }
  window_.push_back({t, state.x.v_s_b.norm(), accepted, rejected});
  while (!window_.empty() && window_.front().t < t - params.window_s) window_.pop_front();
  if (window_.back().t - window_.front().t < 0.9 * params.window_s) return "";  // window not yet full
  double min_speed = 1e300;
  int acc = 0, rej = 0;
  for (const auto& s : window_) {
    min_speed = std::min(min_speed, s.speed_mps);
    acc += s.accepted;
    rej += s.rejected;
  }
  std::ostringstream why;
  why.precision(3);
  if (min_speed > params.max_speed_mps) {
    why << "speed above " << params.max_speed_mps << " m/s for " << params.window_s << " s (now "
        << window_.back().speed_mps << " m/s)";
    return why.str();
  }
  if (acc + rej >= params.min_observations &&
      static_cast<double>(rej) > params.max_rejected_fraction * static_cast<double>(acc + rej)) {
    why << "the gate rejected " << rej << " of " << acc + rej << " observations in " << params.window_s << " s";
    return why.str();
  }
  return "";
}

}  // namespace vi_ekf_slam
