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

}  // namespace vi_ekf_slam
