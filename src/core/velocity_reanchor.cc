#include "vi_ekf_slam/core/velocity_reanchor.h"

#include <Eigen/Cholesky>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam {

BodyVelocity bodyVelocityOf(const DynamicInitResult& aligned) {
  BodyVelocity m;
  m.t = aligned.state.timestamp;
  const Mat3 R_b_n = aligned.state.q_n_b.toRotationMatrix().transpose();
  const Vec3& v_n = aligned.state.v_n_b;
  m.v_b = R_b_n * v_n;
  // v_b = J [v_n, psi]: R_true = Exp(psi) R gives v_b = R^T Exp(-psi) v_n = R^T (v_n + [v_n]x psi).
  Eigen::Matrix<double, 3, 6> J;
  J << R_b_n, R_b_n * skew(v_n);
  m.cov = J * aligned.covariance.topLeftCorner<6, 6>() * J.transpose();
  return m;
}

KalmanUpdateResult bodyVelocityUpdate(FilterState& state, const BodyVelocity& m, double gate_probability) {
  // z - h(x) = H dx + n, n ~ N(0, cov), h = R_s_b^T v_s_b, psi_s_b global as above.
  const Mat3 R_b_s = state.x.q_s_b.toRotationMatrix().transpose();
  const Vec3& v_s = state.x.v_s_b;
  // Whitened: L^-1 (z - h) = L^-1 H dx + unit noise, with cov = L L^T.
  const Eigen::LLT<Mat3> llt(m.cov);
  if (llt.info() != Eigen::Success) return {};
  MeasurementRows rows;
  rows.residual = llt.matrixL().solve(m.v_b - R_b_s * v_s);
  rows.noise_var = 1.0;
  rows.blocks.push_back({idx::kV, llt.matrixL().solve(R_b_s)});
  rows.blocks.push_back({idx::kPsi, llt.matrixL().solve(Mat3(R_b_s * skew(v_s)))});
  return kalmanUpdate(state, {rows}, gate_probability);
}

}  // namespace vi_ekf_slam
