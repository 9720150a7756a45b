#include "vi_ekf_slam/core/landmark_initialization.h"

#include "vi_ekf_slam/core/matrix_utils.h"

namespace vi_ekf_slam {

bool backProject(const MotionState& x, const Eigen::Vector2d& uv, double depth,
                 const CameraModel& camera, const CameraExtrinsics& T_b_c, InitializedLandmark* out) {
  Eigen::Vector2d xn;
  Eigen::Matrix2d J_xn_uv;
  if (!uv.allFinite() || !camera.pixelToNormalized(uv, &xn, &J_xn_uv)) return false;
  const Vec3 ray_c(xn.x(), xn.y(), 1.0);
  const Mat3 R_s_b = x.q_s_b.toRotationMatrix();
  const Mat3 R_s_c = R_s_b * T_b_c.R_b_c;
  const Vec3 p_b_l = T_b_c.R_b_c * (depth * ray_c) + T_b_c.p_b_c;
  out->p_s_l = R_s_b * p_b_l + x.p_s_b;
  out->G_p.setIdentity();
  out->G_psi = -skew(R_s_b * p_b_l);  // Exp(psi) R p ~= R p - [R p]x psi
  out->G_uv = depth * R_s_c.leftCols<2>() * J_xn_uv;
  out->G_depth = R_s_c * ray_c;
  return out->p_s_l.allFinite();
}

void appendInitializedLandmark(FilterState& state, std::int64_t id, const InitializedLandmark& l,
                               double pixel_var, double depth_var) {
  const Eigen::MatrixXd& P = state.covariance();
  // Cross-covariance with the whole state: G_x P_x,all, only position and orientation columns.
  Eigen::MatrixXd P_l_state(3, state.dim());
  P_l_state.noalias() = l.G_p * P.middleRows<3>(idx::kP);
  P_l_state.noalias() += l.G_psi * P.middleRows<3>(idx::kPsi);
  Eigen::Matrix<double, 3, 6> G_x;
  G_x << l.G_p, l.G_psi;
  const int blocks[2] = {idx::kP, idx::kPsi};
  const Eigen::Matrix3d P_ll = G_x * gatherBlocks<2>(P, blocks) * G_x.transpose() +
                               pixel_var * l.G_uv * l.G_uv.transpose() +
                               depth_var * l.G_depth * l.G_depth.transpose();
  state.appendLandmark(id, l.p_s_l, P_ll, P_l_state);
}

bool initializeLandmarkFixedDepth(FilterState& state, const FeatureObservation& obs,
                                  const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                  const FixedDepthParams& params) {
  InitializedLandmark l;
  if (!backProject(state.x, obs.uv, params.depth_m, camera, T_b_c, &l)) return false;
  appendInitializedLandmark(state, obs.id, l, params.pixel_noise_px * params.pixel_noise_px,
                            params.depth_sigma_m * params.depth_sigma_m);
  return true;
}

}  // namespace vi_ekf_slam
