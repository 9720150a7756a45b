#include "vi_ekf_slam/core/frame_change.h"

#include <cmath>
#include <stdexcept>

#include "vi_ekf_slam/core/matrix_utils.h"

namespace vi_ekf_slam {

namespace {

/// Every landmark's pose blocks stacked, [A_pos_i A_rot_i] as rows 3i..3i+2 (3N x 6): the
/// landmarks' pose terms of a frame change are then one product from either side (N small 3x3
/// products vectorized badly and were the composition's largest cost once the map is kept).
Eigen::MatrixXd stackedPoseBlocks(const FrameChangeJacobian& J) {
  const int N = static_cast<int>(J.A_rot.size());
  Eigen::MatrixXd A(3 * N, 6);
  for (int i = 0; i < N; ++i) {
    const size_t k = static_cast<size_t>(i);
    A.block<3, 3>(3 * i, 0) = J.A_pos[k];
    A.block<3, 3>(3 * i, 3) = J.A_rot[k];
  }
  return A;
}

/// M J^T for any M with as many columns as the input state (column blocks only, O(rows * n)).
Eigen::MatrixXd multiplyByTransposeOnRight(const Eigen::MatrixXd& M, const FrameChangeJacobian& J) {
  const int m_in = static_cast<int>(J.J_motion.cols());
  const int m_out = static_cast<int>(J.J_motion.rows());
  const int N = static_cast<int>(J.A_rot.size());
  const Eigen::Index rows = M.rows();
  Eigen::MatrixXd out(rows, m_out + 3 * N);
  out.leftCols(m_out).noalias() = M.leftCols(m_in) * J.J_motion.transpose();
  if (N == 0) return out;
  Eigen::MatrixXd M_pose(rows, 6);
  M_pose << M.middleCols<3>(J.pos_col), M.middleCols<3>(J.rot_col);
  auto lm = out.rightCols(3 * N);
  lm.noalias() = M_pose * stackedPoseBlocks(J).transpose();
  for (int i = 0; i < N; ++i) {
    const size_t k = static_cast<size_t>(i);
    auto o = lm.middleCols<3>(3 * i);
    if (J.L[k] == Mat3::Identity()) {  // an inverse-depth landmark's own parameters are unchanged
      o += M.middleCols<3>(m_in + 3 * i);
    } else {
      o.noalias() += M.middleCols<3>(m_in + 3 * i) * J.L[k].transpose();
    }
  }
  return out;
}

/// J T for any T with as many rows as the input state (row blocks only): the same structure as
/// multiplyByTransposeOnRight from the left, without forming T^T.
Eigen::MatrixXd multiplyOnLeft(const FrameChangeJacobian& J, const Eigen::MatrixXd& T) {
  const int m_in = static_cast<int>(J.J_motion.cols());
  const int m_out = static_cast<int>(J.J_motion.rows());
  const int N = static_cast<int>(J.A_rot.size());
  const Eigen::Index cols = T.cols();
  Eigen::MatrixXd out(m_out + 3 * N, cols);
  out.topRows(m_out).noalias() = J.J_motion * T.topRows(m_in);
  if (N == 0) return out;
  Eigen::MatrixXd T_pose(6, cols);
  T_pose << T.middleRows<3>(J.pos_col), T.middleRows<3>(J.rot_col);
  auto lm = out.bottomRows(3 * N);
  lm.noalias() = stackedPoseBlocks(J) * T_pose;
  for (int i = 0; i < N; ++i) {
    const size_t k = static_cast<size_t>(i);
    auto o = lm.middleRows<3>(3 * i);
    if (J.L[k] == Mat3::Identity()) {
      o += T.middleRows<3>(m_in + 3 * i);
    } else {
      o.noalias() += J.L[k] * T.middleRows<3>(m_in + 3 * i);
    }
  }
  return out;
}

/// Landmark rows of a frame change whose points move as y' = R y + t with the point-level
/// derivatives A_pos_point, A_rot_point w.r.t. the motion blocks. For an inverse-depth landmark
/// l is unchanged (its anchor moves), so its error maps through dl/dy' of the moved anchor.
void setLandmarkRows(FrameChangeJacobian* J, size_t i, const Landmark& lm, const Mat3& R, const Mat3& A_pos_point,
                     const Mat3& A_rot_point) {
  if (lm.kind == LandmarkKind::kCartesian) {
    J->L[i] = R;
    J->A_pos[i] = A_pos_point;
    J->A_rot[i] = A_rot_point;
    return;
  }
  const Mat3 dl_dy_new = lm.paramsFromPointJacobian() * R.transpose();
  J->L[i].setIdentity();
  J->A_pos[i] = dl_dy_new * A_pos_point;
  J->A_rot[i] = dl_dy_new * A_rot_point;
}

void resizeLandmarkRows(FrameChangeJacobian* J, int N) {
  J->L.resize(static_cast<size_t>(N));
  J->A_pos.resize(static_cast<size_t>(N));
  J->A_rot.resize(static_cast<size_t>(N));
}

/// Error-state Jacobian blocks shared by world->sensor and the composition: a new strapdown
/// frame is placed at the current body pose (p, R) of the reference frame.
///   v'  = R^T v          -> dv'  = R^T dv + R^T [v]x dpsi
///   Y'  = R^T (Y - p)    -> dY'  = R^T dY - R^T dp + R^T [Y - p]x dpsi
void resetToBodyLandmarks(const FilterState& s, const Mat3& R, FrameChangeJacobian* J) {
  J->pos_col = idx::kP;
  J->rot_col = idx::kPsi;
  resizeLandmarkRows(J, s.numLandmarks());
  for (int i = 0; i < s.numLandmarks(); ++i) {
    setLandmarkRows(J, static_cast<size_t>(i), s.landmark(i), R.transpose(), -R.transpose(),
                    R.transpose() * skew(s.landmarkPosition(i) - s.x.p_s_b));
  }
}

/// The landmarks moved to the new frame: y' = R y + t.
std::vector<Landmark> transformLandmarks(const FilterState& s, const Mat3& R, const Vec3& t) {
  std::vector<Landmark> out;
  out.reserve(s.landmarks().size());
  for (const auto& lm : s.landmarks()) out.push_back(lm.transformed(R, t));
  return out;
}

/// The extrinsic (body-relative) is the same in every strapdown frame: an identity block after the
/// mechanization's blocks, when the state estimates it.
void addExtrinsicBlock(const FilterState& s, Eigen::MatrixXd* J_motion) {
  if (!s.estimatesExtrinsic()) return;
  const Eigen::Index r = J_motion->rows(), c = J_motion->cols();
  J_motion->conservativeResize(r + idx::kExtrinsicDim, c + idx::kExtrinsicDim);
  J_motion->bottomRows(idx::kExtrinsicDim).setZero();
  J_motion->rightCols(idx::kExtrinsicDim).setZero();
  J_motion->bottomRightCorner(idx::kExtrinsicDim, idx::kExtrinsicDim).setIdentity();
}

void checkFinite(const Eigen::MatrixXd& P) {
  if (!P.allFinite()) throw std::runtime_error("frame change produced a non-finite covariance");
}

}  // namespace

Eigen::MatrixXd applyFrameChange(const Eigen::MatrixXd& P, const FrameChangeJacobian& J) {
  // P' = J (P J^T): T = P J^T, then J T, both by blocks of J.
  const Eigen::MatrixXd T = multiplyByTransposeOnRight(P, J);
  Eigen::MatrixXd Pn = multiplyOnLeft(J, T);
  symmetrize(Pn);
  return Pn;
}

Eigen::MatrixXd denseJacobian(const FrameChangeJacobian& J, int N) {
  const int m_in = static_cast<int>(J.J_motion.cols());
  const int m_out = static_cast<int>(J.J_motion.rows());
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(m_out + 3 * N, m_in + 3 * N);
  D.topLeftCorner(m_out, m_in) = J.J_motion;
  for (int i = 0; i < N; ++i) {
    const size_t k = static_cast<size_t>(i);
    D.block<3, 3>(m_out + 3 * i, m_in + 3 * i) = J.L[k];
    D.block<3, 3>(m_out + 3 * i, J.pos_col) += J.A_pos[k];
    D.block<3, 3>(m_out + 3 * i, J.rot_col) += J.A_rot[k];
  }
  return D;
}

FrameChangeJacobian compositionJacobian(const FilterState& s) {
  using namespace idx;
  if (!isSensorCentric(s.mechanization())) throw std::logic_error("composition needs a sensor-centric state");
  const Mat3 R = s.x.q_s_b.toRotationMatrix();
  const Mat3 R_n_s = s.x.q_n_s.toRotationMatrix();
  FrameChangeJacobian J;
  J.J_motion = Eigen::MatrixXd::Zero(kSensorCentricDim, kSensorCentricDim);
  // p_s2_b = 0 and q_s2_b = I exactly: their rows stay zero (eq. 31 applied to {b} itself).
  J.J_motion.block<3, 3>(kV, kV) = R.transpose();
  J.J_motion.block<3, 3>(kV, kPsi) = R.transpose() * skew(s.x.v_s_b);
  J.J_motion.block<3, 3>(kBa, kBa).setIdentity();
  J.J_motion.block<3, 3>(kBg, kBg).setIdentity();
  J.J_motion(kTd, kTd) = 1.0;
  // eq. (32): T_n_s2 = T_n_s T_s_b.
  J.J_motion.block<3, 3>(kPns, kPns).setIdentity();
  J.J_motion.block<3, 3>(kPns, kP) = R_n_s;
  J.J_motion.block<3, 3>(kPns, kPsiNs) = -skew(R_n_s * s.x.p_s_b);
  J.J_motion.block<3, 3>(kPsiNs, kPsiNs).setIdentity();
  J.J_motion.block<3, 3>(kPsiNs, kPsi) = R_n_s;
  addExtrinsicBlock(s, &J.J_motion);
  resetToBodyLandmarks(s, R, &J);
  return J;
}

Mat3 compositionSecondOrderTerm(const FilterState& s, const FrameChangeJacobian& J, int i) {
  const Landmark& lm = s.landmark(i);
  if (lm.kind != LandmarkKind::kInverseDepth) return Mat3::Zero();
  const Eigen::MatrixXd& P = s.covariance();
  const int c = s.landmarkIndex(i);
  const double rho = lm.l.z();
  const double k = P(c + 2, c + 2) / (rho * rho);
  if (!std::isfinite(k)) return Mat3::Zero();
  Eigen::Matrix<double, 3, 6> DA;
  DA << J.A_pos[static_cast<size_t>(i)], J.A_rot[static_cast<size_t>(i)];
  DA.row(2) *= 2.0;  // rho's row goes with rho^2
  return k * DA * gatherBlocks(P, {J.pos_col, J.rot_col}) * DA.transpose();
}

void compose(FilterState& s, bool second_order) {
  const FrameChangeJacobian J = compositionJacobian(s);
  Eigen::MatrixXd Pn = applyFrameChange(s.covariance(), J);
  if (second_order) {
    for (int i = 0; i < s.numLandmarks(); ++i) {
      const int c = s.landmarkIndex(i);
      Pn.block<3, 3>(c, c) += compositionSecondOrderTerm(s, J, i);
    }
  }
  checkFinite(Pn);
  const Mat3 Rt = s.x.q_s_b.conjugate().toRotationMatrix();
  MotionState x = s.x;
  x.p_n_s = s.x.p_n_s + s.x.q_n_s * s.x.p_s_b;
  x.q_n_s = (s.x.q_n_s * s.x.q_s_b).normalized();
  x.v_s_b = Rt * s.x.v_s_b;
  x.p_s_b.setZero();
  x.q_s_b.setIdentity();
  std::vector<Landmark> lms = transformLandmarks(s, Rt, -Rt * s.x.p_s_b);
  s.reset(s.mechanization(), x, s.landmarkIds(), std::move(lms), std::move(Pn));
}

FrameChangeJacobian worldToSensorJacobian(const FilterState& s) {
  using namespace idx;
  if (isSensorCentric(s.mechanization())) throw std::logic_error("worldToSensor needs a world-centric state");
  const Mat3 R = s.x.q_s_b.toRotationMatrix();  // R_n_b
  FrameChangeJacobian J;
  J.J_motion = Eigen::MatrixXd::Zero(kSensorCentricDim, kWorldCentricDim);
  J.J_motion.block<3, 3>(kV, kV) = R.transpose();
  J.J_motion.block<3, 3>(kV, kPsi) = R.transpose() * skew(s.x.v_s_b);
  J.J_motion.block<3, 3>(kBa, kBa).setIdentity();
  J.J_motion.block<3, 3>(kBg, kBg).setIdentity();
  J.J_motion(kTd, kTd) = 1.0;
  J.J_motion.block<3, 3>(kPns, kP).setIdentity();      // p_n_s = p_n_b
  J.J_motion.block<3, 3>(kPsiNs, kPsi).setIdentity();  // q_n_s = q_n_b
  addExtrinsicBlock(s, &J.J_motion);
  resetToBodyLandmarks(s, R, &J);
  return J;
}

Eigen::MatrixXd sensorToWorldMotionJacobian(const MotionState& x) {
  using namespace idx;
  const Mat3 R_n_s = x.q_n_s.toRotationMatrix();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(kWorldCentricDim, kSensorCentricDim);
  // p_n_b = p_n_s + R_n_s p_s_b
  J.block<3, 3>(kP, kP) = R_n_s;
  J.block<3, 3>(kP, kPns).setIdentity();
  J.block<3, 3>(kP, kPsiNs) = -skew(R_n_s * x.p_s_b);
  // v_n_b = R_n_s v_s_b
  J.block<3, 3>(kV, kV) = R_n_s;
  J.block<3, 3>(kV, kPsiNs) = -skew(R_n_s * x.v_s_b);
  J.block<3, 3>(kBa, kBa).setIdentity();
  // R_n_b = R_n_s R_s_b -> psi_n_b = psi_n_s + R_n_s psi_s_b
  J.block<3, 3>(kPsi, kPsi) = R_n_s;
  J.block<3, 3>(kPsi, kPsiNs).setIdentity();
  J.block<3, 3>(kBg, kBg).setIdentity();
  J(kTd, kTd) = 1.0;
  return J;
}

FrameChangeJacobian sensorToWorldJacobian(const FilterState& s) {
  using namespace idx;
  if (!isSensorCentric(s.mechanization())) throw std::logic_error("sensorToWorld needs a sensor-centric state");
  const Mat3 R_n_s = s.x.q_n_s.toRotationMatrix();
  FrameChangeJacobian J;
  J.J_motion = sensorToWorldMotionJacobian(s.x);
  addExtrinsicBlock(s, &J.J_motion);
  // Y_n = p_n_s + R_n_s Y_s
  J.pos_col = kPns;
  J.rot_col = kPsiNs;
  resizeLandmarkRows(&J, s.numLandmarks());
  for (int i = 0; i < s.numLandmarks(); ++i) {
    setLandmarkRows(&J, static_cast<size_t>(i), s.landmark(i), R_n_s, Mat3::Identity(),
                    -skew(R_n_s * s.landmarkPosition(i)));
  }
  return J;
}

void switchMechanization(FilterState& s, Mechanization target) {
  const bool from_sc = isSensorCentric(s.mechanization());
  const bool to_sc = isSensorCentric(target);
  if (from_sc == to_sc) {
    s.setMechanizationTag(target);
    return;
  }
  MotionState x;
  std::vector<Landmark> lms;
  FrameChangeJacobian J;
  if (!from_sc) {  // world -> sensor: {s} := current body frame
    J = worldToSensorJacobian(s);
    const Mat3 Rt = s.x.q_s_b.conjugate().toRotationMatrix();
    x.p_n_s = s.x.p_s_b;
    x.q_n_s = s.x.q_s_b;
    x.v_s_b = Rt * s.x.v_s_b;
    lms = transformLandmarks(s, Rt, -Rt * s.x.p_s_b);
  } else {  // sensor -> world
    J = sensorToWorldJacobian(s);
    x.p_s_b = s.x.p_n_s + s.x.q_n_s * s.x.p_s_b;
    x.q_s_b = (s.x.q_n_s * s.x.q_s_b).normalized();
    x.v_s_b = s.x.q_n_s * s.x.v_s_b;
    lms = transformLandmarks(s, s.x.q_n_s.toRotationMatrix(), s.x.p_n_s);
  }
  x.b_a = s.x.b_a;
  x.b_g = s.x.b_g;
  x.t_d = s.x.t_d;
  x.T_b_c = s.x.T_b_c;
  Eigen::MatrixXd Pn = applyFrameChange(s.covariance(), J);
  checkFinite(Pn);
  s.reset(target, x, s.landmarkIds(), std::move(lms), std::move(Pn));
}

}  // namespace vi_ekf_slam
