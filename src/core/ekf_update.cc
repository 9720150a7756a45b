#include "vi_ekf_slam/core/ekf_update.h"

#include <limits>
#include <optional>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "vi_ekf_slam/core/chi_squared.h"
#include "vi_ekf_slam/core/kalman_update.h"

namespace vi_ekf_slam {

namespace {
struct AcceptedObservation {
  std::int64_t id;
  int col;           ///< landmark column in the error state
  int ext_col = -1;  ///< the extrinsic's first column, when the state estimates it
  ObservationJacobians J;
  Eigen::Vector2d H_td;      ///< w.r.t. the time offset: the feature's image velocity [px/s]
  Eigen::Vector2d residual;  ///< measured - h(x) at the current linearization point [px]
  Eigen::Vector2d measured;  ///< [px]
};
/// The observation's rows for the one update step: its Jacobian blocks (pose, landmark, time
/// offset), residual and pixel noise.
MeasurementRows rowsOf(const AcceptedObservation& a, double r_var) {
  MeasurementRows m;
  m.blocks = {{idx::kP, a.J.H_p}, {idx::kPsi, a.J.H_psi}, {a.col, a.J.H_l}, {idx::kTd, a.H_td}};
  if (a.ext_col >= 0) {
    m.blocks.push_back({a.ext_col, a.J.H_pbc});
    m.blocks.push_back({a.ext_col + 3, a.J.H_thc});
  }
  m.residual = a.residual;
  m.noise_var = r_var;
  return m;
}
std::vector<MeasurementRows> rowsOf(const std::vector<AcceptedObservation>& acc, double r_var) {
  std::vector<MeasurementRows> rows;
  rows.reserve(acc.size());
  for (const auto& a : acc) rows.push_back(rowsOf(a, r_var));
  return rows;
}
/// The iterations stop once the correction changes less than this (max over its entries: m,
/// rad, m/s, 1/m, s).
constexpr double kIterationTolerance = 1e-6;

/// How a landmark is seen: its pixel, the Jacobians and the image velocity, at a state.
struct ObservationModel {
  const CameraModel& camera;
  const CameraExtrinsics& T_b_c;
  Vec3 omega_b;
  double row_time_per_px;
  /// Rolling shutter: when the row at v was read, relative to the state's time (the middle row).
  /// First order, as the time offset: the prediction moves by the image velocity over it.
  double rowTime(double v) const { return row_time_per_px * (v - 0.5 * camera.height()); }
  /// a's Jacobians and residual at `state`, for a time offset dtd off the state's (the iterate's):
  /// the pixel z seen at image time t_i belongs to the state at t_i + t_d; the filter is at
  /// t_i + t_d_est, so z = h(x) + velocity * (t_d - t_d_est). False if it cannot be predicted.
  bool linearize(const FilterState& state, double dtd, AcceptedObservation* a) const {
    const auto li = state.findLandmark(a->id);
    // An estimated extrinsic is the iterate's.
    const CameraExtrinsics& T = state.estimatesExtrinsic() ? state.x.T_b_c : T_b_c;
    Eigen::Vector2d uv;
    if (!li || !predictObservation(state.x, state.landmark(*li), camera, T, &uv, &a->J)) return false;
    a->col = state.landmarkIndex(*li);
    a->ext_col = state.estimatesExtrinsic() ? state.extrinsicIndex() : -1;
    if (!predictImageVelocity(state.x, state.landmark(*li), camera, T, omega_b, &a->H_td)) a->H_td.setZero();
    a->residual = a->measured - uv - a->H_td * (rowTime(a->measured.y()) + dtd);
    return true;
  }
};

/// Stage 1: every observation predicted, linearized and gated on its own 2-dof innovation; the
/// outcome of each (invalid, rejected, outlier) into *result.
std::vector<AcceptedObservation> gateObservations(const FilterState& state,
                                                  const std::vector<FeatureObservation>& observations,
                                                  const ObservationModel& model, const UpdateParams& params,
                                                  UpdateResult* result) {
  const double r_var = params.pixel_noise_px * params.pixel_noise_px;
  const double gate = chiSquaredQuantile(params.gate_probability, 2.0);
  const double outlier = chiSquaredQuantile(params.outlierProbability(), 2.0);
  std::vector<AcceptedObservation> acc;
  acc.reserve(observations.size());
  for (const auto& obs : observations) {
    AcceptedObservation a;
    a.id = obs.id;
    a.measured = obs.uv;
    if (!obs.uv.allFinite() || !model.linearize(state, 0.0, &a)) {
      result->invalid_ids.push_back(obs.id);
      continue;
    }
    const double d2 = normalizedInnovation(state.covariance(), rowsOf(a, r_var));
    if (!std::isfinite(d2) || d2 > outlier) ++result->outliers;
    if (!std::isfinite(d2) || d2 > gate) {
      result->rejected_ids.push_back(obs.id);
      continue;
    }
    acc.push_back(a);
  }
  return acc;
}
}  // namespace

std::optional<PredictedPixel> predictWithCovariance(const FilterState& state, int landmark_index,
                                                    const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                                    const UpdateParams& params, const Vec3& omega_b) {
  const double row_time_per_px = camera.height() > 0 ? params.readout_time_s / camera.height() : 0.0;
  const ObservationModel model{camera, T_b_c, omega_b, row_time_per_px};
  AcceptedObservation a;
  a.id = state.landmarkIds()[static_cast<size_t>(landmark_index)];
  a.measured = Eigen::Vector2d(0.0, 0.5 * camera.height());  // the middle row: no readout shift
  if (!model.linearize(state, 0.0, &a)) return std::nullopt;
  PredictedPixel out;
  out.uv = a.measured - a.residual;  // h(x)
  if (!camera.inImage(out.uv)) return std::nullopt;
  Eigen::MatrixXd PHt, S;
  innovationCovariance(state.covariance(), {rowsOf(a, params.pixel_noise_px * params.pixel_noise_px)}, &PHt, &S);
  out.S = S;
  return out;
}

JointInnovation jointInnovation(const FilterState& state, const std::vector<FeatureObservation>& observations,
                                const CameraModel& camera, const CameraExtrinsics& T_b_c, const UpdateParams& params,
                                const Vec3& omega_b) {
  const double r_var = params.pixel_noise_px * params.pixel_noise_px;
  const double row_time_per_px = camera.height() > 0 ? params.readout_time_s / camera.height() : 0.0;
  const ObservationModel model{camera, T_b_c, omega_b, row_time_per_px};
  std::vector<AcceptedObservation> acc;
  JointInnovation out;
  for (const auto& obs : observations) {
    AcceptedObservation a;
    a.id = obs.id;
    a.measured = obs.uv;
    if (!obs.uv.allFinite() || !model.linearize(state, 0.0, &a)) return out;
    acc.push_back(a);
  }
  const std::vector<MeasurementRows> rows = rowsOf(acc, r_var);
  Eigen::MatrixXd PHt, S;
  innovationCovariance(state.covariance(), rows, &PHt, &S);
  const Eigen::VectorXd r = stackedResidual(rows);
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return out;
  out.nis = r.dot(llt.solve(r));
  for (size_t i = 0; i < acc.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(2 * i);
    const Eigen::Vector2d ri = r.segment<2>(k);
    out.each.push_back(ri.dot(S.block<2, 2>(k, k).ldlt().solve(ri)));
  }
  out.valid = std::isfinite(out.nis);
  return out;
}

UpdateResult ekfUpdate(FilterState& state, const std::vector<FeatureObservation>& observations,
                       const CameraModel& camera, const CameraExtrinsics& T_b_c, const UpdateParams& params,
                       const Vec3& omega_b) {
  UpdateResult result;
  const double r_var = params.pixel_noise_px * params.pixel_noise_px;
  const double row_time_per_px = camera.height() > 0 ? params.readout_time_s / camera.height() : 0.0;
  const ObservationModel model{camera, T_b_c, omega_b, row_time_per_px};
  std::vector<AcceptedObservation> acc = gateObservations(state, observations, model, params, &result);
  result.accepted = static_cast<int>(acc.size());
  if (acc.empty()) return result;

  // 2) Stacked update, iterated (Gauss-Newton on the prior and the accepted observations): each
  //    pass relinearizes h at the current iterate x_i = x_0 [+] d_i and solves
  //    d_{i+1} = K_i (z - h(x_i) + H_i d_i), K_i = P_0 H_i^T (H_i P_0 H_i^T + R)^-1. A new
  //    landmark's first observations depend on the product of its inverse depth and the camera's
  //    motion, both poorly known: one linearization at the prior depth misplaces the correction
  //    between them (false confidence in the velocity); relinearizing at the corrected depth does
  //    not. The covariance is updated once, with the last K and H (kalman_update.h).
  Eigen::MatrixXd& P = state.mutableCovariance();
  const int n = state.dim();
  const MotionState x0 = state.x;
  const std::vector<Landmark> l0 = state.landmarks();
  auto restorePrior = [&] {  // the mean back to x_0 (the iterates only move the mean)
    state.x = x0;
    for (int i = 0; i < state.numLandmarks(); ++i) state.landmark(i) = l0[static_cast<size_t>(i)];
  };
  Eigen::MatrixXd PHt, S;
  Eigen::VectorXd r, d = Eigen::VectorXd::Zero(n);
  Eigen::LLT<Eigen::MatrixXd> llt;
  const int iterations = std::max(1, params.iterations);
  // Consider landmarks (Landmark::consider) are never corrected: every iterate leaves them at x_0.
  const std::vector<int> consider = state.considerEntries();
  // Step control: an iterate is kept only while the cost it minimizes, |d|^2_{P0^-1} +
  // |z - h(x0 [+] d)|^2_R, decreases (plain Gauss-Newton overshot and diverged on some walks).
  // Every iterate is d = P0 H^T lambda, so its prior term is lambda^T (S - R) lambda for the S of
  // the linearization that produced it: no n x n inverse is needed.
  double prior_cost = 0.0, accepted_cost = std::numeric_limits<double>::infinity();
  struct Iterate {
    Eigen::VectorXd d;
    Eigen::MatrixXd PHt;
    Eigen::LLT<Eigen::MatrixXd> llt;
    std::vector<AcceptedObservation> acc;
  };
  std::optional<Iterate> kept;
  // Predicts every observation at x_0 [+] dd: their Jacobians and residuals into obs, and the
  // observations' cost |z - h|^2_R. False if one can no longer be predicted.
  auto relinearizeAt = [&](const Eigen::VectorXd& dd, std::vector<AcceptedObservation>* obs, double* cost) {
    restorePrior();
    state.boxplus(dd);
    *cost = 0.0;
    for (auto& a : *obs) {
      // The state stays propagated to the prior's time offset: the iterate's offset moves the
      // prediction through the image velocity, as the linear model says (leaving it out counted
      // H_td d_td once more at every iteration).
      if (!model.linearize(state, dd(idx::kTd), &a)) return false;
      *cost += a.residual.squaredNorm() / r_var;
    }
    return true;
  };
  auto revertToKept = [&] {
    d = kept->d;
    PHt = kept->PHt;
    llt = kept->llt;
    acc = kept->acc;
  };
  for (int it = 0; it < iterations; ++it) {
    if (it > 0) {
      // Relinearize at x_i; an observation that can no longer be predicted ends the iterations
      // at the previous iterate (whose K is kept).
      std::vector<AcceptedObservation> next = acc;
      double meas_cost = 0.0;
      if (!relinearizeAt(d, &next, &meas_cost)) break;
      const double cost = prior_cost + meas_cost;
      if (kept && !(cost < accepted_cost)) {  // worse than the last iterate: keep that one
        revertToKept();
        break;
      }
      accepted_cost = cost;
      acc = std::move(next);
      kept = Iterate{d, PHt, llt, acc};
    }
    const std::vector<MeasurementRows> rows = rowsOf(acc, r_var);
    innovationCovariance(P, rows, &PHt, &S);
    r = stackedResidual(rows);
    const Eigen::VectorXd Hd = applyJacobian(rows, d);
    if (!factorInnovation(S, &llt)) {  // numerically broken P: refuse rather than corrupt it
      restorePrior();
      for (const auto& a : acc) result.invalid_ids.push_back(a.id);
      result.accepted = 0;
      return result;
    }
    const Eigen::VectorXd lambda = llt.solve(r + Hd);
    Eigen::VectorXd d_next = PHt * lambda;  // = K (r + H d)
    zeroConsider(d_next, consider);
    // (With consider landmarks this is the prior cost of the iterate before their entries were
    // zeroed: an approximation of the step control, not of the update.)
    if (iterations > 1) prior_cost = lambda.dot(S * lambda) - r_var * lambda.squaredNorm();
    const double change = (d_next - d).lpNorm<Eigen::Infinity>();
    d = d_next;
    if (it == 0) result.nis_sum = r.dot(llt.solve(r));  // of the prior's prediction, as gated
    if (change < kIterationTolerance) break;
    if (it + 1 == iterations && kept) {
      // The last iterate, too, only if it lowers the cost.
      std::vector<AcceptedObservation> last = acc;
      double meas_cost = 0.0;
      if (!relinearizeAt(d, &last, &meas_cost) || !(prior_cost + meas_cost < accepted_cost)) revertToKept();
    }
  }
  restorePrior();

  // 3) The covariance, once, with the last gain.
  optimalGainCovarianceUpdate(P, PHt, llt, consider);
  state.boxplus(d);
  return result;
}

}  // namespace vi_ekf_slam
