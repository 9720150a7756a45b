#include "vi_ekf_slam/core/filter_state.h"

#include <algorithm>
#include <stdexcept>

namespace vi_ekf_slam {

std::string toString(Mechanization m) {
  switch (m) {
    case Mechanization::kWorldCentric:
      return "world_centric";
    case Mechanization::kSensorCentric:
      return "sensor_centric";
    case Mechanization::kSensorCentricComposition:
      return "sensor_centric_composition";
  }
  return "unknown";
}

std::optional<Mechanization> mechanizationFromString(const std::string& s) {
  for (auto m :
       {Mechanization::kWorldCentric, Mechanization::kSensorCentric, Mechanization::kSensorCentricComposition}) {
    if (toString(m) == s) return m;
  }
  return std::nullopt;
}

FilterState::FilterState(Mechanization mechanization, bool extrinsic)
    : mechanization_(mechanization),
      extrinsic_(extrinsic),
      P_(Eigen::MatrixXd::Zero(vi_ekf_slam::motionDim(mechanization, extrinsic),
                               vi_ekf_slam::motionDim(mechanization, extrinsic))) {}

void FilterState::setMechanizationTag(Mechanization m) {
  if (vi_ekf_slam::motionDim(m, extrinsic_) != motionDim()) {
    throw std::logic_error("setMechanizationTag: layout change needs switchMechanization()");
  }
  mechanization_ = m;
}

std::optional<int> FilterState::findLandmark(std::int64_t id) const {
  auto it = index_of_id_.find(id);
  if (it == index_of_id_.end()) return std::nullopt;
  return it->second;
}

void FilterState::rebuildIndex() {
  index_of_id_.clear();
  for (size_t i = 0; i < landmark_ids_.size(); ++i) index_of_id_[landmark_ids_[i]] = static_cast<int>(i);
}

void FilterState::appendLandmark(std::int64_t id, const Landmark& lm, const Eigen::Matrix3d& P_ll,
                                 const Eigen::MatrixXd& P_l_state) {
  if (findLandmark(id)) throw std::invalid_argument("appendLandmark: id already in the map");
  flush();
  const int n = dim();
  if (P_l_state.rows() != 3 || P_l_state.cols() != n) {
    throw std::invalid_argument("appendLandmark: cross-covariance must be 3 x dim()");
  }
  P_.conservativeResize(n + 3, n + 3);
  P_.block(n, 0, 3, n) = P_l_state;
  P_.block(0, n, n, 3) = P_l_state.transpose();
  P_.block<3, 3>(n, n) = 0.5 * (P_ll + P_ll.transpose());
  landmark_ids_.push_back(id);
  landmarks_.push_back(lm);
  index_of_id_[id] = numLandmarks() - 1;
}

void FilterState::removeLandmarks(std::vector<int> indices) {
  if (indices.empty()) return;
  flush();
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  // Rows/columns that survive, in order.
  std::vector<int> keep_rows;
  keep_rows.reserve(static_cast<size_t>(dim()));
  for (int r = 0; r < motionDim(); ++r) keep_rows.push_back(r);
  std::vector<std::int64_t> ids;
  std::vector<Landmark> lms;
  size_t k = 0;
  for (int i = 0; i < numLandmarks(); ++i) {
    if (k < indices.size() && indices[k] == i) {
      ++k;
      continue;
    }
    ids.push_back(landmark_ids_[static_cast<size_t>(i)]);
    lms.push_back(landmarks_[static_cast<size_t>(i)]);
    for (int r = 0; r < 3; ++r) keep_rows.push_back(landmarkIndex(i) + r);
  }
  // One gather into the smaller matrix (compacting in place and then resizing copied P twice).
  Eigen::MatrixXd kept = P_(keep_rows, keep_rows);
  P_.swap(kept);
  landmark_ids_ = std::move(ids);
  landmarks_ = std::move(lms);
  rebuildIndex();
}

const Eigen::MatrixXd& FilterState::covariance() const {
  flush();
  return P_;
}

Eigen::MatrixXd& FilterState::mutableCovariance() {
  flush();
  return P_;
}

void FilterState::setCovariance(Eigen::MatrixXd P) {
  if (P.rows() != dim() || P.cols() != dim()) {
    throw std::invalid_argument("setCovariance: wrong size");
  }
  P_ = std::move(P);
  has_pending_phi_ = false;
}

void FilterState::setLazyCrossCovariance(bool lazy) {
  flush();
  lazy_cross_ = lazy;
}

void FilterState::propagateCovariance(const MotionMatrix& Phi, const MotionMatrix& Qd) {
  const int m = motionDim();
  if (Phi.rows() != m || Qd.rows() != m) throw std::invalid_argument("propagateCovariance: size");
  auto Pss = P_.topLeftCorner(m, m);
  MotionMatrix Pn = Phi * Pss * Phi.transpose() + Qd;
  Pss = 0.5 * (Pn + Pn.transpose());
  propagateCrossCovariance(Phi);
}

void FilterState::propagateCovarianceDiagonalNoise(const MotionMatrix& Phi, const MotionVector& q) {
  const int m = motionDim();
  if (Phi.rows() != m || q.size() != m) throw std::invalid_argument("propagateCovariance: size");
  auto Pss = P_.topLeftCorner(m, m);
  MotionMatrix Pq = Pss;
  Pq.diagonal() += q;
  MotionMatrix PhiPq;
  PhiPq.noalias() = Phi * Pq;
  MotionMatrix Pn;
  Pn.noalias() = PhiPq * Phi.transpose();
  Pss = 0.5 * (Pn + Pn.transpose());
  propagateCrossCovariance(Phi);
}

void FilterState::propagateCrossCovariance(const MotionMatrix& Phi) {
  const int m = motionDim();
  if (numLandmarks() == 0) return;
  if (!lazy_cross_) {
    const int nm = dim() - m;
    Eigen::MatrixXd cross = Phi * P_.topRightCorner(m, nm);
    P_.topRightCorner(m, nm) = cross;
    P_.bottomLeftCorner(nm, m) = cross.transpose();
    return;
  }
  if (has_pending_phi_) {
    MotionMatrix acc;
    acc.noalias() = Phi * pending_phi_;
    pending_phi_ = acc;
  } else {
    pending_phi_ = Phi;
    has_pending_phi_ = true;
  }
}

void FilterState::flush() const {
  if (!has_pending_phi_) return;
  has_pending_phi_ = false;
  const int m = motionDim();
  const int nm = static_cast<int>(P_.rows()) - m;
  if (nm == 0) return;
  Eigen::MatrixXd cross = pending_phi_ * P_.topRightCorner(m, nm);
  P_.topRightCorner(m, nm) = cross;
  P_.bottomLeftCorner(nm, m) = cross.transpose();
}

std::vector<int> FilterState::considerEntries() const {
  std::vector<int> out;
  for (int i = 0; i < numLandmarks(); ++i) {
    if (!landmark(i).consider) continue;
    for (int k = 0; k < idx::kLandmarkDim; ++k) out.push_back(landmarkIndex(i) + k);
  }
  return out;
}

void FilterState::boxplus(const Eigen::VectorXd& dx) {
  if (dx.size() != dim()) throw std::invalid_argument("boxplus: wrong size");
  x.p_s_b += dx.segment<3>(idx::kP);
  x.v_s_b += dx.segment<3>(idx::kV);
  x.b_a += dx.segment<3>(idx::kBa);
  x.q_s_b = (expQuat(dx.segment<3>(idx::kPsi)) * x.q_s_b).normalized();
  x.b_g += dx.segment<3>(idx::kBg);
  x.t_d += dx(idx::kTd);
  if (isSensorCentric(mechanization_)) {
    x.p_n_s += dx.segment<3>(idx::kPns);
    x.q_n_s = (expQuat(dx.segment<3>(idx::kPsiNs)) * x.q_n_s).normalized();
  }
  if (extrinsic_) {
    const int e = extrinsicIndex();
    const CameraExtrinsics before = x.T_b_c;
    x.T_b_c.p_b_c += dx.segment<3>(e);
    x.T_b_c.R_b_c = (expQuat(dx.segment<3>(e + 3)) * Quat(x.T_b_c.R_b_c)).normalized().toRotationMatrix();
    // Inverse-depth anchors ride on the extrinsic (landmark.h).
    for (Landmark& lm : landmarks_) lm = lm.withExtrinsic(before.R_b_c, before.p_b_c, x.T_b_c.R_b_c, x.T_b_c.p_b_c);
  }
  for (int i = 0; i < numLandmarks(); ++i) landmarks_[static_cast<size_t>(i)].l += dx.segment<3>(landmarkIndex(i));
}

Eigen::VectorXd FilterState::boxminus(const FilterState& other) const {
  if (other.dim() != dim() || other.landmark_ids_ != landmark_ids_) {
    throw std::invalid_argument("boxminus: states have different layouts");
  }
  Eigen::VectorXd e(dim());
  e.segment<3>(idx::kP) = x.p_s_b - other.x.p_s_b;
  e.segment<3>(idx::kV) = x.v_s_b - other.x.v_s_b;
  e.segment<3>(idx::kBa) = x.b_a - other.x.b_a;
  e.segment<3>(idx::kPsi) = rotationError(x.q_s_b, other.x.q_s_b);
  e.segment<3>(idx::kBg) = x.b_g - other.x.b_g;
  e(idx::kTd) = x.t_d - other.x.t_d;
  if (isSensorCentric(mechanization_)) {
    e.segment<3>(idx::kPns) = x.p_n_s - other.x.p_n_s;
    e.segment<3>(idx::kPsiNs) = rotationError(x.q_n_s, other.x.q_n_s);
  }
  if (extrinsic_) {
    const int k = extrinsicIndex();
    e.segment<3>(k) = x.T_b_c.p_b_c - other.x.T_b_c.p_b_c;
    e.segment<3>(k + 3) = rotationError(Quat(x.T_b_c.R_b_c), Quat(other.x.T_b_c.R_b_c));
  }
  for (int i = 0; i < numLandmarks(); ++i) {
    // Compare the points in the other landmark's parameterization (anchors may differ after a
    // frame change of a perturbed state), this point taken under the other's extrinsic when the
    // extrinsic is estimated (its anchor rides on it): l's error, not the extrinsic's.
    const Landmark& o = other.landmark(i);
    const Landmark& mine = landmark(i);
    const Vec3 p =
        extrinsic_
            ? mine.withExtrinsic(x.T_b_c.R_b_c, x.T_b_c.p_b_c, other.x.T_b_c.R_b_c, other.x.T_b_c.p_b_c).position()
            : mine.position();
    e.segment<3>(landmarkIndex(i)) = o.paramsOf(p) - o.l;
  }
  return e;
}

void FilterState::reset(Mechanization m, const MotionState& xs, std::vector<std::int64_t> ids,
                        std::vector<Landmark> lms, Eigen::MatrixXd P) {
  const int n = vi_ekf_slam::motionDim(m, extrinsic_) + 3 * static_cast<int>(ids.size());
  if (lms.size() != ids.size() || P.rows() != n || P.cols() != n) {
    throw std::invalid_argument("FilterState::reset: inconsistent sizes");
  }
  mechanization_ = m;
  x = xs;
  if (!isSensorCentric(m)) {
    x.p_n_s.setZero();
    x.q_n_s.setIdentity();
  }
  landmark_ids_ = std::move(ids);
  landmarks_ = std::move(lms);
  P_ = std::move(P);
  has_pending_phi_ = false;
  rebuildIndex();
}

}  // namespace vi_ekf_slam
