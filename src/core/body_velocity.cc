#include "vi_ekf_slam/core/body_velocity.h"

#include <Eigen/Cholesky>

#include "vi_ekf_slam/core/matrix_utils.h"
#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam {

namespace {
/// d(R_s_b^T v_s_b) / d[v, psi_s_b] (psi global, in {s}): R_b_s [I, [v_s]x].
Eigen::Matrix<double, 3, 6> bodyVelocityJacobian(const FilterState& state) {
  const Mat3 R_b_s = state.x.q_s_b.toRotationMatrix().transpose();
  Eigen::Matrix<double, 3, 6> H;
  H << R_b_s, R_b_s * skew(state.x.v_s_b);
  return H;
}
}  // namespace

BodyVelocity bodyVelocityOfState(const FilterState& state) {
  BodyVelocity m;
  m.t = state.timestamp;
  m.v_b = state.x.q_s_b.conjugate() * state.x.v_s_b;
  const Eigen::Matrix<double, 3, 6> H = bodyVelocityJacobian(state);
  m.cov = H * gatherBlocks(state.covariance(), {idx::kV, idx::kPsi}) * H.transpose();
  return m;
}

std::optional<MeasurementRows> whitenedBodyVelocityRows(const FilterState& state, const BodyVelocity& m) {
  // z - h(x) = H dx + n, n ~ N(0, cov), h = R_s_b^T v_s_b, psi_s_b global as above.
  const Eigen::Matrix<double, 3, 6> H = bodyVelocityJacobian(state);
  const Eigen::LLT<Mat3> llt(m.cov);
  if (llt.info() != Eigen::Success) return std::nullopt;
  MeasurementRows rows;
  rows.residual = llt.matrixL().solve(Vec3(m.v_b - state.x.q_s_b.conjugate() * state.x.v_s_b));
  rows.noise_var = 1.0;
  rows.blocks.push_back({idx::kV, llt.matrixL().solve(Mat3(H.leftCols<3>()))});
  rows.blocks.push_back({idx::kPsi, llt.matrixL().solve(Mat3(H.rightCols<3>()))});
  return rows;
}

KalmanUpdateResult bodyVelocityUpdate(FilterState& state, const BodyVelocity& m, double gate_probability) {
  const std::optional<MeasurementRows> rows = whitenedBodyVelocityRows(state, m);
  if (!rows) return {};
  return kalmanUpdate(state, {*rows}, gate_probability);
}

}  // namespace vi_ekf_slam
