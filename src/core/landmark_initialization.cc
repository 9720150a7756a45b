#include "vi_ekf_slam/core/landmark_initialization.h"

#include "vi_ekf_slam/core/matrix_utils.h"

namespace vi_ekf_slam {

bool backProject(const MotionState& x, const Eigen::Vector2d& uv, double depth, const CameraModel& camera,
                 const CameraExtrinsics& T_b_c, InitializedLandmark* out) {
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

namespace {
/// Appends `lm` whose entries relate to the back-projected point by dl = D dY (D = I for a
/// Cartesian point) plus an independent variance `l_var` along the direction `l_dir` of l.
void appendTransformed(FilterState& state, std::int64_t id, const Landmark& lm, const InitializedLandmark& l,
                       const Mat3& D, double pixel_var, const Vec3& l_dir, double l_var) {
  const Eigen::MatrixXd& P = state.covariance();
  // Cross-covariance with the whole state: D G_x P_x,all, only position and orientation columns.
  const Mat3 DG_p = D * l.G_p, DG_psi = D * l.G_psi;
  Eigen::MatrixXd P_l_state(3, state.dim());
  P_l_state.noalias() = DG_p * P.middleRows<3>(idx::kP);
  P_l_state.noalias() += DG_psi * P.middleRows<3>(idx::kPsi);
  Eigen::Matrix<double, 3, 6> G_x;
  G_x << DG_p, DG_psi;
  const int blocks[2] = {idx::kP, idx::kPsi};
  const Eigen::Matrix<double, 3, 2> DG_uv = D * l.G_uv;
  const Eigen::Matrix3d P_ll = G_x * gatherBlocks<2>(P, blocks) * G_x.transpose() +
                               pixel_var * DG_uv * DG_uv.transpose() + l_var * l_dir * l_dir.transpose();
  state.appendLandmark(id, lm, P_ll, P_l_state);
}
}  // namespace

void appendInitializedLandmark(FilterState& state, std::int64_t id, const InitializedLandmark& l, double pixel_var,
                               double depth_var) {
  appendTransformed(state, id, Landmark::cartesian(l.p_s_l), l, Mat3::Identity(), pixel_var, l.G_depth, depth_var);
}

bool initializeLandmarkInverseDepth(FilterState& state, const FeatureObservation& obs, const CameraModel& camera,
                                    const CameraExtrinsics& T_b_c, const InverseDepthParams& params) {
  InitializedLandmark l;
  if (!backProject(state.x, obs.uv, params.initial_depth_m, camera, T_b_c, &l)) return false;
  // Anchor: the estimated camera frame; l = (u, v, rho) of the same point in it.
  Landmark lm;
  lm.kind = LandmarkKind::kInverseDepth;
  lm.R_s_a = state.x.q_s_b.toRotationMatrix() * T_b_c.R_b_c;
  lm.p_s_a = state.x.p_s_b + state.x.q_s_b * T_b_c.p_b_c;
  const Vec3 p_a = lm.R_s_a.transpose() * (l.p_s_l - lm.p_s_a);
  lm.l = Vec3(p_a.x() / p_a.z(), p_a.y() / p_a.z(), 1.0 / p_a.z());
  // Pose and pixel errors map through dl/dY; the depth prior is a variance on rho alone.
  const double sigma = params.inverse_depth_sigma;
  appendTransformed(state, obs.id, lm, l, lm.paramsFromPointJacobian(), params.pixel_noise_px * params.pixel_noise_px,
                    Vec3::UnitZ(), sigma * sigma);
  return true;
}

bool initializeLandmarkFixedDepth(FilterState& state, const FeatureObservation& obs, const CameraModel& camera,
                                  const CameraExtrinsics& T_b_c, const FixedDepthParams& params) {
  InitializedLandmark l;
  if (!backProject(state.x, obs.uv, params.depth_m, camera, T_b_c, &l)) return false;
  appendInitializedLandmark(state, obs.id, l, params.pixel_noise_px * params.pixel_noise_px,
                            params.depth_sigma_m * params.depth_sigma_m);
  return true;
}

}  // namespace vi_ekf_slam
