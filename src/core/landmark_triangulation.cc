#include "vi_ekf_slam/core/landmark_triangulation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "vi_ekf_slam/core/landmark_initialization.h"
#include "vi_ekf_slam/core/matrix_utils.h"

namespace vi_ekf_slam {

CameraClone appendCameraClone(FilterState& state, std::int64_t id, const CameraExtrinsics& T_b_c) {
  const Mat3 R_s_b = state.x.q_s_b.toRotationMatrix();
  InitializedLandmark l;
  l.p_s_l = state.x.p_s_b + R_s_b * T_b_c.p_b_c;
  l.G_p.setIdentity();
  l.G_psi = -skew(R_s_b * T_b_c.p_b_c);
  l.G_pbc = R_s_b;  // (its rotation does not move the camera's position)
  l.G_uv.setZero();
  l.G_depth.setZero();
  appendInitializedLandmark(state, id, l, 0.0, 0.0);
  CameraClone c;
  c.id = id;
  c.t = state.timestamp;
  c.R_s_c = R_s_b * T_b_c.R_b_c;
  c.R_b_c = T_b_c.R_b_c;
  return c;  // relative to the current camera its orientation is exact (rotation_cov 0)
}

bool triangulateLandmark(const FilterState& state, const CameraClone& clone, const Eigen::Vector2d& uv_clone,
                         const Eigen::Vector2d& uv_now, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                         double pixel_var, double min_depth_m, TriangulatedLandmark* out) {
  const auto ci = state.findLandmark(clone.id);
  if (!ci || state.landmark(*ci).kind != LandmarkKind::kCartesian) return false;
  Eigen::Vector2d xn1, xn0;
  Eigen::Matrix2d J1, J0;  // d(normalized)/d(pixel)
  if (!uv_now.allFinite() || !uv_clone.allFinite() || !camera.pixelToNormalized(uv_now, &xn1, &J1) ||
      !camera.pixelToNormalized(uv_clone, &xn0, &J0)) {
    return false;
  }
  const Mat3 R_s_b = state.x.q_s_b.toRotationMatrix();
  const Mat3 R_s_c = R_s_b * T_b_c.R_b_c;
  const Vec3 Rp_bc = R_s_b * T_b_c.p_b_c;
  const Vec3 p_s_c = state.x.p_s_b + Rp_bc;
  const Vec3 m1(xn1.x(), xn1.y(), 1.0), m0(xn0.x(), xn0.y(), 1.0);
  // The clone's camera now (its body fixed, its camera turned by an estimated extrinsic's change).
  const Mat3 R_s_c0 =
      state.estimatesExtrinsic() ? Mat3(clone.R_s_c * clone.R_b_c.transpose() * T_b_c.R_b_c) : clone.R_s_c;
  // The point on each ray: p_s_c + a1 d1 = clone + a0 d0, solved for the depths (d1, d0) in the
  // least-squares sense (the rays' closest points).
  const Vec3 a1 = R_s_c * m1, a0 = R_s_c0 * m0, b = state.landmark(*ci).l - p_s_c;
  Eigen::Matrix<double, 3, 2> A;
  A << a1, -a0;
  const Eigen::Matrix2d N = A.transpose() * A;
  if (!(N.determinant() > 1e-12 * a1.squaredNorm() * a0.squaredNorm())) return false;  // parallel rays
  const Eigen::Matrix2d N_inv = N.inverse();
  const Eigen::Vector2d d = N_inv * (A.transpose() * b);
  if (!(d(0) >= min_depth_m) || !(d(1) >= min_depth_m) || !d.allFinite()) return false;
  const Vec3 gap = b - A * d;  // from the current ray's closest point to the clone's; along n
  const Vec3 n = a1.cross(a0).normalized();

  // First-order change of the point X = p_s_c + a1 d1 and of the gap along n, one input direction
  // at a time: body position (3), orientation (3), clone position (3), pixel now (2), pixel at the
  // clone (2), clone orientation (3). dd follows from the normal equations N d = A^T b.
  Eigen::Matrix<double, 3, 16> J_X;
  Eigen::Matrix<double, 1, 16> J_gap;
  auto direction = [&](int k, const Vec3& dp_c, const Vec3& da1, const Vec3& da0, const Vec3& db) {
    Eigen::Matrix<double, 3, 2> dA;
    dA << da1, -da0;
    const Vec3 db_eff = db - dA * d;
    const Eigen::Vector2d dd = N_inv * (A.transpose() * db_eff + dA.transpose() * gap);
    J_X.col(k) = dp_c + da1 * d(0) + a1 * dd(0);
    J_gap(k) = n.dot(db_eff);  // n is normal to both rays; the gap is parallel to n
  };
  const Vec3 z = Vec3::Zero();
  for (int j = 0; j < 3; ++j) {
    const Vec3 e = Vec3::Unit(j);
    direction(j, e, z, z, -e);                                          // p_s_b
    direction(3 + j, e.cross(Rp_bc), e.cross(a1), z, -e.cross(Rp_bc));  // psi_s_b: Exp(psi) R_s_b
    direction(6 + j, z, z, z, e);                                       // clone position
    direction(13 + j, z, z, e.cross(a0), z);                            // clone orientation
  }
  for (int k = 0; k < 2; ++k) {
    direction(9 + k, z, R_s_c * Vec3(J1(0, k), J1(1, k), 0.0), z, z);
    direction(11 + k, z, z, R_s_c0 * Vec3(J0(0, k), J0(1, k), 0.0), z);
  }

  // The extrinsic, when estimated: p_b_c moves the current camera (the clone's position is a state
  // of its own); R_b_c = Exp(theta) R_b_c turns both rays, the clone's as seen from its body.
  Eigen::Matrix<double, 3, 6> J_X_ext = Eigen::Matrix<double, 3, 6>::Zero();
  Eigen::Matrix<double, 1, 6> J_gap_ext = Eigen::Matrix<double, 1, 6>::Zero();
  if (state.estimatesExtrinsic()) {
    const Eigen::Matrix<double, 3, 16> J_X_kept = J_X;
    const Eigen::Matrix<double, 1, 16> J_gap_kept = J_gap;
    for (int j = 0; j < 3; ++j) {
      const Vec3 e = Vec3::Unit(j);
      direction(j, R_s_b * e, z, z, -(R_s_b * e));
      direction(3 + j, z, R_s_b * e.cross(T_b_c.R_b_c * m1), R_s_c0 * (T_b_c.R_b_c.transpose() * e).cross(m0), z);
    }
    J_X_ext = J_X.leftCols<6>();
    J_gap_ext = J_gap.leftCols<6>();
    J_X = J_X_kept;
    J_gap = J_gap_kept;
  }

  TriangulatedLandmark& t = *out;
  t.landmark.kind = LandmarkKind::kInverseDepth;
  t.landmark.R_s_a = R_s_c;
  t.landmark.p_s_a = p_s_c;
  t.landmark.l = Vec3(xn1.x(), xn1.y(), 1.0 / d(0));
  t.depth_m = d(0);
  const Mat3 D = t.landmark.paramsFromPointJacobian();
  t.J_state = D * J_X.leftCols<9>();
  t.J_noise = D * J_X.rightCols<7>();
  const int blocks[3] = {idx::kP, idx::kPsi, state.landmarkIndex(*ci)};
  const Eigen::Matrix<double, 9, 9> P_x = gatherBlocks<3>(state.covariance(), blocks);
  Eigen::Matrix<double, 7, 7> noise = Eigen::Matrix<double, 7, 7>::Zero();
  noise.topLeftCorner<4, 4>().diagonal().setConstant(pixel_var);
  noise.bottomRightCorner<3, 3>() = clone.rotation_cov;
  Mat3 P_from_state = t.J_state * P_x * t.J_state.transpose();
  double gap_var = (J_gap.leftCols<9>() * P_x * J_gap.leftCols<9>().transpose() +
                    J_gap.rightCols<7>() * noise * J_gap.rightCols<7>().transpose())(0, 0);
  if (state.estimatesExtrinsic()) {
    const int e = state.extrinsicIndex();
    const int all[5] = {idx::kP, idx::kPsi, state.landmarkIndex(*ci), e, e + 3};
    const Eigen::Matrix<double, 15, 15> P_xe = gatherBlocks<5>(state.covariance(), all);
    // The new point's anchor (the current camera) rides on the extrinsic (landmark.h): l carries
    // what the anchor does not.
    t.J_ext = D * (J_X_ext - t.landmark.extrinsicJacobian(T_b_c.R_b_c));
    Eigen::Matrix<double, 3, 15> J_se;
    J_se << t.J_state, t.J_ext;
    Eigen::Matrix<double, 1, 15> g_se;
    g_se << J_gap.leftCols<9>(), J_gap_ext;
    P_from_state = J_se * P_xe * J_se.transpose();
    gap_var = (g_se * P_xe * g_se.transpose() + J_gap.rightCols<7>() * noise * J_gap.rightCols<7>().transpose())(0, 0);
  }
  t.P_ll = P_from_state + t.J_noise * noise * t.J_noise.transpose();
  t.baseline_relative_sigma = std::sqrt(std::max(0.0, P_from_state(2, 2))) * d(0);
  const double g = n.dot(gap);
  t.ray_gap_nis = gap_var > 0.0 ? g * g / gap_var : std::numeric_limits<double>::infinity();
  return t.landmark.l.allFinite() && t.P_ll.allFinite();
}

void appendTriangulatedLandmark(FilterState& state, std::int64_t id, const CameraClone& clone,
                                const TriangulatedLandmark& l) {
  const int c = state.landmarkIndex(*state.findLandmark(clone.id));
  const Eigen::MatrixXd& P = state.covariance();
  Eigen::MatrixXd P_l_state(3, state.dim());
  P_l_state.noalias() = l.J_state.leftCols<3>() * P.middleRows<3>(idx::kP);
  P_l_state.noalias() += l.J_state.middleCols<3>(3) * P.middleRows<3>(idx::kPsi);
  P_l_state.noalias() += l.J_state.rightCols<3>() * P.middleRows<3>(c);
  if (state.estimatesExtrinsic()) {
    P_l_state.noalias() += l.J_ext.leftCols<3>() * P.middleRows<3>(state.extrinsicIndex());
    P_l_state.noalias() += l.J_ext.rightCols<3>() * P.middleRows<3>(state.extrinsicIndex() + 3);
  }
  state.appendLandmark(id, l.landmark, l.P_ll, P_l_state);
}

}  // namespace vi_ekf_slam
