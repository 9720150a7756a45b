#include "vi_ekf_slam/core/measurement_model.h"

namespace vi_ekf_slam {

Vec3 landmarkInCamera(const MotionState& x, const Vec3& p_s_l, const CameraExtrinsics& T_b_c) {
  const Vec3 p_b_l = x.q_s_b.conjugate() * (p_s_l - x.p_s_b);
  return T_b_c.R_b_c.transpose() * (p_b_l - T_b_c.p_b_c);
}

bool predictObservation(const MotionState& x, const Vec3& p_s_l, const CameraModel& camera,
                        const CameraExtrinsics& T_b_c, Eigen::Vector2d* uv,
                        ObservationJacobians* J) {
  const Vec3 p_c_l = landmarkInCamera(x, p_s_l, T_b_c);
  Eigen::Matrix<double, 2, 3> J_pi;
  if (!camera.project(p_c_l, uv, J ? &J_pi : nullptr)) return false;
  if (J) {
    // p_c = R_b_c^T (R_s_b^T (Y - p) - p_b_c); with R_true = Exp(psi) R:
    // d p_c = R_c_s (dY - dp) + R_c_s [Y - p]x psi.
    const Mat3 R_c_s = T_b_c.R_b_c.transpose() * x.q_s_b.conjugate().toRotationMatrix();
    J->H_l = J_pi * R_c_s;                 // J_Y
    J->H_p = -J->H_l;                      // J_p
    J->H_psi = J->H_l * skew(p_s_l - x.p_s_b);  // J_psi
  }
  return true;
}

}  // namespace vi_ekf_slam
