#include "vi_ekf_slam/core/velocity_reanchor.h"

#include <Eigen/Cholesky>

#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam {

BodyVelocity bodyVelocityOf(const DynamicInitResult& aligned, const alignment::Preintegrated& imu, double t,
                            double gravity_mps2) {
  BodyVelocity m;
  m.t = t;
  const double dt = t - aligned.state.timestamp;
  const Mat3 R_n_b1 = aligned.state.q_n_b.toRotationMatrix();
  const Mat3 R_b_n = (R_n_b1 * imu.R).transpose();
  // The part of v_n(t) that turns with the tilt's error: R_true = Exp(psi) R turns R_n_b1 and
  // hence the body at t, but not v_n nor gravity; the increment, measured in {b1}, turns with the body.
  const Vec3 u = aligned.state.v_n_b + gravityInNav(gravity_mps2) * dt;
  const Vec3 dv_b1 = imu.beta + imu.B * aligned.state.b_a;
  m.v_b = R_b_n * u + imu.R.transpose() * dv_b1;
  // v_b = R_b_n Exp(-psi) u + R^T dv_b1 = R_b_n (u + [u]x psi) + ...: J [v_n, psi, b_a].
  Eigen::Matrix<double, 3, 9> J;
  J << R_b_n, R_b_n * skew(u), imu.R.transpose() * imu.B;
  m.cov = J * aligned.covariance * J.transpose();
  return m;
}

}  // namespace vi_ekf_slam
