#include "vi_ekf_slam/core/navigation_output.h"

#include <algorithm>
#include <cmath>

#include "vi_ekf_slam/core/delayed_landmarks.h"
#include "vi_ekf_slam/core/frame_change.h"
#include "vi_ekf_slam/core/matrix_utils.h"

namespace vi_ekf_slam {

Eigen::Matrix<double, 6, 6> NavState::poseCovariance() const {
  Eigen::Matrix<double, 6, 6> c;
  c.topLeftCorner<3, 3>() = cov.block<3, 3>(idx::kP, idx::kP);
  c.topRightCorner<3, 3>() = cov.block<3, 3>(idx::kP, idx::kPsi);
  c.bottomLeftCorner<3, 3>() = cov.block<3, 3>(idx::kPsi, idx::kP);
  c.bottomRightCorner<3, 3>() = cov.block<3, 3>(idx::kPsi, idx::kPsi);
  return c;
}

NavState navState(const FilterState& s) {
  NavState out;
  out.timestamp = s.timestamp;
  out.b_a = s.x.b_a;
  out.b_g = s.x.b_g;
  out.t_d = s.x.t_d;
  out.t_d_sigma = std::sqrt(std::max(0.0, s.motionCovariance()(idx::kTd, idx::kTd)));
  if (!isSensorCentric(s.mechanization())) {
    out.p_n_b = s.x.p_s_b;
    out.v_n_b = s.x.v_s_b;
    out.q_n_b = s.x.q_s_b;
    out.cov = s.motionCovariance().topLeftCorner<idx::kNavDim, idx::kNavDim>();
    return out;
  }
  out.p_n_b = s.x.p_n_s + s.x.q_n_s * s.x.p_s_b;
  out.v_n_b = s.x.q_n_s * s.x.v_s_b;
  out.q_n_b = (s.x.q_n_s * s.x.q_s_b).normalized();
  // Only the motion block of the structured Jacobian is needed: O(1) in the map size.
  const Eigen::MatrixXd J = sensorToWorldMotionJacobian(s.x);
  // (An estimated extrinsic's block, after the mechanization's, is not part of the navigation state.)
  const Eigen::MatrixXd C =
      s.estimatesExtrinsic()
          ? Eigen::MatrixXd(J * s.motionCovariance().topLeftCorner(J.cols(), J.cols()) * J.transpose())
          : Eigen::MatrixXd(J * s.motionCovariance() * J.transpose());
  out.cov = C.topLeftCorner<idx::kNavDim, idx::kNavDim>();
  out.cov = (0.5 * (out.cov + out.cov.transpose())).eval();
  return out;
}

std::vector<NavLandmark> navLandmarks(const FilterState& s) {
  std::vector<NavLandmark> out;
  out.reserve(static_cast<size_t>(s.numLandmarks()));
  const Eigen::MatrixXd& P = s.covariance();
  const bool sc = isSensorCentric(s.mechanization());
  const Mat3 R_n_s = s.x.q_n_s.toRotationMatrix();
  for (int i = 0; i < s.numLandmarks(); ++i) {
    if (isCloneId(s.landmarkIds()[static_cast<size_t>(i)])) continue;  // a camera position, not a point of the map
    auto& o = out.emplace_back();
    o.id = s.landmarkIds()[static_cast<size_t>(i)];
    const int li = s.landmarkIndex(i);
    Mat3 M;  // d(point in {s}) / d(landmark entries)
    const Vec3 p_s_l = s.landmark(i).position(&M);
    if (!sc) {
      o.p_n_l = p_s_l;
      o.cov = M * P.block<3, 3>(li, li) * M.transpose();
    } else {
      // Y_n = p_n_s + R_n_s Y_s -> dY_n = R_n_s M dl + dp_n_s - [R_n_s Y_s]x psi_n_s
      const Vec3 r = R_n_s * p_s_l;
      o.p_n_l = s.x.p_n_s + r;
      Eigen::Matrix<double, 3, 9> G;
      G << R_n_s * M, Mat3::Identity(), -skew(r);
      const int blocks[3] = {li, idx::kPns, idx::kPsiNs};
      o.cov = G * gatherBlocks<3>(P, blocks) * G.transpose();
    }
    o.cov = (0.5 * (o.cov + o.cov.transpose())).eval();
  }
  return out;
}

}  // namespace vi_ekf_slam
