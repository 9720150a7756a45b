#include "vi_ekf_slam/core/blind_motion_prior.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

#include "vi_ekf_slam/core/kalman_update.h"
#include "vi_ekf_slam/core/matrix_utils.h"

namespace vi_ekf_slam {

namespace {
/// The prior is applied once the state's body-frame velocity covariance exceeds the prior's by
/// this factor along some direction: right after it the state knows the velocity a little better
/// than the prior alone (2/3 of its variance there), and the IMU's drift takes it back above; so
/// the velocity's uncertainty stays near the prior's, never far below what the person's motion
/// allows, whatever the frame rate.
constexpr double kApplyRatio = 2.0;
/// Frame intervals longer than this are gaps in the sight, not seconds of it [s].
constexpr double kMaxFrameInterval = 0.5;
}  // namespace

void BlindMotionPrior::seen(const FilterState& state, const BlindMotionPriorParams& params) {
  const double t = state.timestamp;
  const double dt = last_t_ ? t - *last_t_ : 0.0;
  last_t_ = t;
  if (!(dt > 0.0) || dt > kMaxFrameInterval) return;  // the first image, a gap, a clock going back
  const BodyVelocity v = bodyVelocityOfState(state);
  if (!v.v_b.allFinite() || !v.cov.allFinite()) return;
  const double keep = std::exp(-dt / params.window_s);
  weight_ = keep * weight_ + dt;
  sum_vv_ = keep * sum_vv_ + dt * v.v_b * v.v_b.transpose();
  sum_cov_ = keep * sum_cov_ + dt * v.cov;
  seen_s_ += dt;
}

std::optional<BodyVelocity> BlindMotionPrior::prior(double t, const BlindMotionPriorParams& params) const {
  if (!params.enabled || seen_s_ < params.min_seen_s || !(weight_ > 0.0)) return std::nullopt;
  BodyVelocity m;
  m.t = t;
  // Zero mean, the second moment as covariance: which way the body moved does not carry over
  // (a hand-held rig scanning a room goes back and forth, the body-frame mean of one 10 s flips
  // sign in the next on the real recording), how fast it moved along each axis does (a walker's
  // forward pace, a hand's slow sway); plus how well the filter knew the velocity then.
  const Mat3 second_moment = sum_vv_ / weight_ + sum_cov_ / weight_;
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (second_moment + second_moment.transpose()));
  // sigma_i + min_sigma_mps along each principal axis.
  const Vec3 sigma = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().array() + params.min_sigma_mps;
  m.cov = eig.eigenvectors() * sigma.cwiseAbs2().asDiagonal() * eig.eigenvectors().transpose();
  return m;
}

KalmanUpdateResult BlindMotionPrior::applyIfUncertain(FilterState& state, const BlindMotionPriorParams& params) const {
  const std::optional<BodyVelocity> m = prior(state.timestamp, params);
  if (!m) return {};
  const std::optional<MeasurementRows> whitened = whitenedBodyVelocityRows(state, *m);
  if (!whitened) return {};
  // The state's body-frame velocity covariance whitened by the prior's, L^-1 H P H^T L^-T with the
  // whitened rows' own Jacobian blocks (velocity and tilt: W = L^-1 H) over those two blocks of P:
  // its eigenvectors with eigenvalues above kApplyRatio are the directions along which the IMU
  // knows the velocity worse than the prior. Only they are measured: along the others the prior
  // would pull an estimate the state knows better towards its zero mean (a walker's forward pace),
  // and its error there is the same at every image.
  const JacobianBlock& wv = whitened->blocks[0];
  const JacobianBlock& wpsi = whitened->blocks[1];
  Eigen::Matrix<double, 3, 6> W;
  W << wv.H, wpsi.H;
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(
      Mat3(W * gatherBlocks(state.covariance(), {wv.col, wpsi.col}) * W.transpose()));
  std::vector<int> along;
  for (int i = 0; i < 3; ++i)
    if (eig.eigenvalues()(i) > kApplyRatio) along.push_back(i);
  if (along.empty()) return {};
  // Orthonormal rows of the whitened measurement keep its noise unit.
  Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 3, 3> A(static_cast<int>(along.size()), 3);
  for (size_t k = 0; k < along.size(); ++k) A.row(static_cast<int>(k)) = eig.eigenvectors().col(along[k]).transpose();
  MeasurementRows rows;
  rows.noise_var = 1.0;
  rows.residual = A * whitened->residual;
  for (const JacobianBlock& b : whitened->blocks) rows.blocks.push_back({b.col, A * b.H});
  return kalmanUpdate(state, {rows}, params.gate_probability);
}

}  // namespace vi_ekf_slam
