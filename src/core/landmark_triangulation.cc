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
  l.G_uv.setZero();
  l.G_depth.setZero();
  appendInitializedLandmark(state, id, l, 0.0, 0.0);
  CameraClone c;
  c.id = id;
  c.t = state.timestamp;
  c.R_s_c = R_s_b * T_b_c.R_b_c;
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
  // The point on each ray: p_s_c + a1 d1 = clone + a0 d0, solved for the depths (d1, d0) in the
  // least-squares sense (the rays' closest points).
  const Vec3 a1 = R_s_c * m1, a0 = clone.R_s_c * m0, b = state.landmark(*ci).l - p_s_c;
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
    direction(11 + k, z, z, clone.R_s_c * Vec3(J0(0, k), J0(1, k), 0.0), z);
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
  const Mat3 P_from_state = t.J_state * P_x * t.J_state.transpose();
  t.P_ll = P_from_state + t.J_noise * noise * t.J_noise.transpose();
  t.baseline_relative_sigma = std::sqrt(std::max(0.0, P_from_state(2, 2))) * d(0);
  const double gap_var = (J_gap.leftCols<9>() * P_x * J_gap.leftCols<9>().transpose() +
                          J_gap.rightCols<7>() * noise * J_gap.rightCols<7>().transpose())(0, 0);
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
  state.appendLandmark(id, l.landmark, l.P_ll, P_l_state);
}

}  // namespace vi_ekf_slam
