#include "vi_ekf_slam/core/landmark_initialization.h"

#include <cmath>
#include <stdexcept>

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
  out->G_pbc = R_s_b;
  out->G_thc = -R_s_b * skew(T_b_c.R_b_c * (depth * ray_c));
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
  Eigen::Matrix3d P_ll;
  if (state.estimatesExtrinsic()) {
    // The ray also starts at the estimated camera: the extrinsic's errors move it. An inverse-depth
    // anchor moves with them (landmark.h), so l carries only what the anchor does not.
    const int e = state.extrinsicIndex();
    const Eigen::Matrix<double, 3, 6> Y_ext = lm.extrinsicJacobian(state.x.T_b_c.R_b_c);
    const Mat3 DG_pbc = D * (l.G_pbc - Y_ext.leftCols<3>()), DG_thc = D * (l.G_thc - Y_ext.rightCols<3>());
    P_l_state.noalias() += DG_pbc * P.middleRows<3>(e);
    P_l_state.noalias() += DG_thc * P.middleRows<3>(e + 3);
    Eigen::Matrix<double, 3, 12> G_xe;
    G_xe << DG_p, DG_psi, DG_pbc, DG_thc;
    const int blocks_e[4] = {idx::kP, idx::kPsi, e, e + 3};
    P_ll = G_xe * gatherBlocks<4>(P, blocks_e) * G_xe.transpose() + pixel_var * DG_uv * DG_uv.transpose() +
           l_var * l_dir * l_dir.transpose();
  } else {
    P_ll = G_x * gatherBlocks<2>(P, blocks) * G_x.transpose() + pixel_var * DG_uv * DG_uv.transpose() +
           l_var * l_dir * l_dir.transpose();
  }
  state.appendLandmark(id, lm, P_ll, P_l_state);
}
}  // namespace

void appendInitializedLandmark(FilterState& state, std::int64_t id, const InitializedLandmark& l, double pixel_var,
                               double depth_var) {
  appendTransformed(state, id, Landmark::cartesian(l.p_s_l), l, Mat3::Identity(), pixel_var, l.G_depth, depth_var);
}

namespace {
/// The inverse-depth landmark of back-projected point l, anchored at the estimated camera frame.
Landmark anchoredInverseDepth(const MotionState& x, const InitializedLandmark& l, const CameraExtrinsics& T_b_c) {
  Landmark lm;
  lm.kind = LandmarkKind::kInverseDepth;
  lm.R_s_a = x.q_s_b.toRotationMatrix() * T_b_c.R_b_c;
  lm.p_s_a = x.p_s_b + x.q_s_b * T_b_c.p_b_c;
  const Vec3 p_a = lm.R_s_a.transpose() * (l.p_s_l - lm.p_s_a);
  lm.l = Vec3(p_a.x() / p_a.z(), p_a.y() / p_a.z(), 1.0 / p_a.z());
  return lm;
}
}  // namespace

bool initializeLandmarkInverseDepth(FilterState& state, const FeatureObservation& obs, const CameraModel& camera,
                                    const CameraExtrinsics& T_b_c, const InverseDepthParams& params) {
  InitializedLandmark l;
  if (!backProject(state.x, obs.uv, params.initial_depth_m, camera, T_b_c, &l)) return false;
  // Anchor: the estimated camera frame; l = (u, v, rho) of the same point in it.
  const Landmark lm = anchoredInverseDepth(state.x, l, T_b_c);
  // Pose and pixel errors map through dl/dY; the depth prior is a variance on rho alone.
  const double sigma = params.inverse_depth_sigma;
  appendTransformed(state, obs.id, lm, l, lm.paramsFromPointJacobian(), params.pixel_noise_px * params.pixel_noise_px,
                    Vec3::UnitZ(), sigma * sigma);
  return true;
}

std::vector<int> initializeLandmarksInverseDepthJointly(FilterState& state, const std::vector<FeatureObservation>& obs,
                                                        const std::vector<double>& depth_m, const Eigen::MatrixXd& Q,
                                                        const Eigen::MatrixXd& C, const CameraModel& camera,
                                                        const CameraExtrinsics& T_b_c, double pixel_noise_px) {
  const auto n = static_cast<Eigen::Index>(obs.size());
  const int d0 = state.dim();
  if (static_cast<Eigen::Index>(depth_m.size()) != n || Q.rows() != n || Q.cols() != n || C.rows() != n ||
      C.cols() != d0) {
    throw std::invalid_argument("initializeLandmarksInverseDepthJointly: Q must be n x n and C n x dim()");
  }
  std::vector<int> entered;
  std::vector<Landmark> lms;
  std::vector<InitializedLandmark> rays;
  for (int i = 0; i < static_cast<int>(n); ++i) {
    InitializedLandmark l;
    if (state.findLandmark(obs[static_cast<size_t>(i)].id) ||
        !backProject(state.x, obs[static_cast<size_t>(i)].uv, depth_m[static_cast<size_t>(i)], camera, T_b_c, &l)) {
      continue;
    }
    entered.push_back(i);
    rays.push_back(l);
    lms.push_back(anchoredInverseDepth(state.x, l, T_b_c));
  }
  const auto m = static_cast<Eigen::Index>(entered.size());
  // z = [state error; the m inverse-depth errors] with covariance Z; the new entries are
  // l = A z + (pixel errors): l_i = D_i (G_p dp + G_psi dpsi) + e_z rho_i.
  Eigen::MatrixXd Z(d0 + m, d0 + m);
  Z.topLeftCorner(d0, d0) = state.covariance();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3 * m, d0 + m);
  Eigen::MatrixXd pixel = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  const double pixel_var = pixel_noise_px * pixel_noise_px;
  for (Eigen::Index a = 0; a < m; ++a) {
    const auto ia = static_cast<Eigen::Index>(entered[static_cast<size_t>(a)]);
    Z.block(d0 + a, 0, 1, d0) = C.row(ia);
    Z.block(0, d0 + a, d0, 1) = C.row(ia).transpose();
    for (Eigen::Index b = 0; b < m; ++b)
      Z(d0 + a, d0 + b) = Q(ia, static_cast<Eigen::Index>(entered[static_cast<size_t>(b)]));
    const Mat3 D = lms[static_cast<size_t>(a)].paramsFromPointJacobian();
    const InitializedLandmark& l = rays[static_cast<size_t>(a)];
    A.block<3, 3>(3 * a, idx::kP) = D * l.G_p;
    A.block<3, 3>(3 * a, idx::kPsi) = D * l.G_psi;
    if (state.estimatesExtrinsic()) {  // less what the riding anchor carries (landmark.h)
      const Eigen::Matrix<double, 3, 6> Y_ext = lms[static_cast<size_t>(a)].extrinsicJacobian(state.x.T_b_c.R_b_c);
      A.block<3, 3>(3 * a, state.extrinsicIndex()) = D * (l.G_pbc - Y_ext.leftCols<3>());
      A.block<3, 3>(3 * a, state.extrinsicIndex() + 3) = D * (l.G_thc - Y_ext.rightCols<3>());
    }
    A(3 * a + 2, d0 + a) = 1.0;
    const Eigen::Matrix<double, 3, 2> DG_uv = D * l.G_uv;
    pixel.block<3, 3>(3 * a, 3 * a) = pixel_var * DG_uv * DG_uv.transpose();
  }
  const Eigen::MatrixXd X = A * Z.leftCols(d0);             // new entries x state
  const Eigen::MatrixXd L = A * Z * A.transpose() + pixel;  // new entries x new entries
  for (Eigen::Index a = 0; a < m; ++a) {
    Eigen::MatrixXd P_l_state(3, d0 + 3 * a);
    P_l_state << X.middleRows(3 * a, 3), L.block(3 * a, 0, 3, 3 * a);
    state.appendLandmark(obs[static_cast<size_t>(entered[static_cast<size_t>(a)])].id, lms[static_cast<size_t>(a)],
                         L.block<3, 3>(3 * a, 3 * a), P_l_state);
  }
  return entered;
}

bool initializeLandmarkFixedDepth(FilterState& state, const FeatureObservation& obs, const CameraModel& camera,
                                  const CameraExtrinsics& T_b_c, const FixedDepthParams& params) {
  InitializedLandmark l;
  if (!backProject(state.x, obs.uv, params.depth_m, camera, T_b_c, &l)) return false;
  appendInitializedLandmark(state, obs.id, l, params.pixel_noise_px * params.pixel_noise_px,
                            params.depth_sigma_m * params.depth_sigma_m);
  return true;
}

double inverseDepthInCamera(const FilterState& state, int i, const CameraExtrinsics& T_b_c, Eigen::RowVectorXd* J) {
  const Mat3 R_s_b = state.x.q_s_b.toRotationMatrix();
  const Mat3 R_c_s = T_b_c.R_b_c.transpose() * R_s_b.transpose();
  Mat3 M;
  const Vec3 p_s_l = state.landmark(i).position(&M);
  const double z = R_c_s.row(2).dot(p_s_l - state.x.p_s_b - R_s_b * T_b_c.p_b_c);
  if (J) {
    // With R_true = Exp(psi) R: d p_c = R_c_s (M dl - dp + [p_s_l - p_s_b]x psi).
    const Eigen::RowVector3d dz = -R_c_s.row(2) / (z * z);  // d(1 / z) per unit of R_c_s^T d p_c
    J->setZero(state.dim());
    J->segment<3>(idx::kP) = -dz;
    J->segment<3>(idx::kPsi) = dz * skew(p_s_l - state.x.p_s_b);
    J->segment<3>(state.landmarkIndex(i)) = dz * M;
    if (state.estimatesExtrinsic()) {
      // p_s_c = p_s_b + R_s_b p_b_c; R_c_s = R_b_c^T (I - [theta]x) R_s_b^T.
      const int e = state.extrinsicIndex();
      const Vec3 v = p_s_l - state.x.p_s_b - R_s_b * T_b_c.p_b_c;
      // An inverse-depth anchor rides on the extrinsic (landmark.h).
      const Eigen::Matrix<double, 3, 6> Y_ext = state.landmark(i).extrinsicJacobian(T_b_c.R_b_c);
      J->segment<3>(e) = -dz * (R_s_b - Y_ext.leftCols<3>());
      J->segment<3>(e + 3) =
          -(1.0 / (z * z)) * Eigen::RowVector3d(T_b_c.R_b_c.col(2).transpose()) * skew(R_s_b.transpose() * v) +
          dz * Y_ext.rightCols<3>();
    }
  }
  return 1.0 / z;
}

std::vector<int> initializeLandmarksAtMapDepth(FilterState& state, const std::vector<FeatureObservation>& obs, int ref,
                                               double inverse_depth_sigma, const CameraModel& camera,
                                               const CameraExtrinsics& T_b_c, double pixel_noise_px) {
  Eigen::RowVectorXd J;
  const double rho = inverseDepthInCamera(state, ref, T_b_c, &J);
  if (!(rho > 0.0) || !std::isfinite(rho)) return {};
  const Eigen::RowVectorXd JP = J * state.covariance();
  const auto n = static_cast<Eigen::Index>(obs.size());
  Eigen::MatrixXd Q = Eigen::MatrixXd::Constant(n, n, JP.dot(J));
  Q.diagonal().array() += inverse_depth_sigma * inverse_depth_sigma;
  return initializeLandmarksInverseDepthJointly(state, obs, std::vector<double>(static_cast<size_t>(n), 1.0 / rho), Q,
                                                JP.replicate(n, 1), camera, T_b_c, pixel_noise_px);
}
}  // namespace vi_ekf_slam
