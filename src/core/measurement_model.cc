#include "vi_ekf_slam/core/measurement_model.h"

namespace vi_ekf_slam {

Vec3 landmarkInCamera(const MotionState& x, const Vec3& p_s_l, const CameraExtrinsics& T_b_c) {
  const Vec3 p_b_l = x.q_s_b.conjugate() * (p_s_l - x.p_s_b);
  return T_b_c.R_b_c.transpose() * (p_b_l - T_b_c.p_b_c);
}

bool predictObservation(const MotionState& x, const Landmark& lm, const CameraModel& camera,
                        const CameraExtrinsics& T_b_c, Eigen::Vector2d* uv, ObservationJacobians* J) {
  const Mat3 R_s_b = x.q_s_b.toRotationMatrix();
  const Vec3 p_s_c = x.p_s_b + R_s_b * T_b_c.p_b_c;
  const Mat3 R_c_s = T_b_c.R_b_c.transpose() * R_s_b.transpose();
  // q_s = w * (p_s_l - p_s_c) with w = 1 (Cartesian) or rho (inverse depth); pi(q_c) = pi(p_c).
  Vec3 q_s;
  double w = 1.0;
  Mat3 dq_dl;
  if (lm.kind == LandmarkKind::kCartesian) {
    q_s = lm.l - p_s_c;
    dq_dl.setIdentity();
  } else {
    w = lm.l.z();
    q_s = w * (lm.p_s_a - p_s_c) + lm.R_s_a * Vec3(lm.l.x(), lm.l.y(), 1.0);
    dq_dl << lm.R_s_a.col(0), lm.R_s_a.col(1), lm.p_s_a - p_s_c;
  }
  const Vec3 q_c = R_c_s * q_s;
  Eigen::Matrix<double, 2, 3> J_pi;
  if (!camera.project(q_c, uv, J ? &J_pi : nullptr)) return false;
  if (J) {
    // With R_true = Exp(psi) R: d q_c = R_c_s (dq_dl dl - w dp + [q_s + w R_s_b p_b_c]x psi),
    // since q_s + w R_s_b p_b_c = w (p_s_l - p_s_b).
    const Eigen::Matrix<double, 2, 3> JR = J_pi * R_c_s;
    J->H_l = JR * dq_dl;                                    // J_Y
    J->H_p = -w * JR;                                       // J_p
    J->H_psi = JR * skew(q_s + w * (R_s_b * T_b_c.p_b_c));  // J_psi
    // The extrinsic: p_s_c = p_s_b + R_s_b p_b_c moves as the body position does, through R_s_b;
    // with R_b_c = Exp(theta) R_b_c, q_c = R_b_c^T (I - [theta]x) R_s_b^T q_s.
    J->H_pbc = J->H_p * R_s_b;
    J->H_thc = J_pi * T_b_c.R_b_c.transpose() * skew(R_s_b.transpose() * q_s);
    // An inverse-depth anchor rides on the extrinsic (landmark.h): q_s = w (Y - p_s_c) moves with it.
    if (lm.kind == LandmarkKind::kInverseDepth) {
      const Eigen::Matrix<double, 2, 6> H_anchor = w * JR * lm.extrinsicJacobian(T_b_c.R_b_c);
      J->H_pbc += H_anchor.leftCols<3>();
      J->H_thc += H_anchor.rightCols<3>();
    }
  }
  return true;
}

bool predictImageVelocity(const MotionState& x, const Landmark& lm, const CameraModel& camera,
                          const CameraExtrinsics& T_b_c, const Vec3& omega_b, Eigen::Vector2d* velocity) {
  const Mat3 R_s_b = x.q_s_b.toRotationMatrix();
  const Vec3 p_s_c = x.p_s_b + R_s_b * T_b_c.p_b_c;
  const Mat3 R_c_s = T_b_c.R_b_c.transpose() * R_s_b.transpose();
  // q_c = w R_c_s (Y - p_s_c) as in predictObservation (w = rho for inverse depth, else 1).
  Vec3 q_s;
  double w = 1.0;
  if (lm.kind == LandmarkKind::kCartesian) {
    q_s = lm.l - p_s_c;
  } else {
    w = lm.l.z();
    q_s = w * (lm.p_s_a - p_s_c) + lm.R_s_a * Vec3(lm.l.x(), lm.l.y(), 1.0);
  }
  const Vec3 q_c = R_c_s * q_s;
  Eigen::Vector2d uv;
  Eigen::Matrix<double, 2, 3> J_pi;
  if (!camera.project(q_c, &uv, &J_pi)) return false;
  // The camera turns with omega_c = R_c_b omega_b (dR_c_s/dt = -[omega_c]x R_c_s) and moves with
  // v_s_c = v_s_b + R_s_b (omega_b x p_b_c).
  const Vec3 omega_c = T_b_c.R_b_c.transpose() * omega_b;
  const Vec3 v_s_c = x.v_s_b + R_s_b * omega_b.cross(T_b_c.p_b_c);
  const Vec3 q_c_dot = -omega_c.cross(q_c) - w * (R_c_s * v_s_c);
  *velocity = J_pi * q_c_dot;
  return true;
}

}  // namespace vi_ekf_slam
