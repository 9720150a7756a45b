// The EKF-SLAM state: nominal motion state s', the landmark map m (paper eq. 1-3) and the
// error-state covariance P. Landmarks are expressed in the strapdown frame {s} (== {n} in the
// world-centric filter), so the measurement model (eq. 29) is the same for every mechanization.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include "vi_ekf_slam/core/camera_extrinsics.h"
#include "vi_ekf_slam/core/landmark.h"
#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/state_layout.h"

namespace vi_ekf_slam {

/// Fixed-capacity matrix for the motion block (15x15 or 21x21) without heap allocation.
using MotionMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, idx::kMaxMotionDim, idx::kMaxMotionDim>;
using MotionVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, idx::kMaxMotionDim, 1>;

/// Nominal motion state. In the world-centric filter {s} == {n}, p_n_s == 0 and q_n_s == I.
struct MotionState {
  Vec3 p_s_b = Vec3::Zero();  ///< position of the body in {s} [m]
  Vec3 v_s_b = Vec3::Zero();  ///< velocity of the body in {s} [m/s]
  Vec3 b_a = Vec3::Zero();    ///< accelerometer bias [m/s^2]
  Quat q_s_b = Quat::Identity();
  Vec3 b_g = Vec3::Zero();    ///< gyroscope bias [rad/s]
  double t_d = 0.0;           ///< camera-IMU time offset: t_imu = t_image + t_d [s]
  Vec3 p_n_s = Vec3::Zero();  ///< position of {s} in {n} [m]
  Quat q_n_s = Quat::Identity();
  /// The camera in the body frame: the calibration, refined when the filter estimates it.
  CameraExtrinsics T_b_c;
};

class FilterState {
 public:
  /// `extrinsic`: the camera-IMU extrinsic is part of the error state (idx::kExtrinsicDim entries
  /// at extrinsicIndex()); else x.T_b_c is a constant.
  explicit FilterState(Mechanization mechanization = Mechanization::kWorldCentric, bool extrinsic = false);

  Mechanization mechanization() const { return mechanization_; }
  /// Changes the mechanization tag only between layouts of equal size (the two sensor-centric
  /// variants); a change of layout goes through switchMechanization().
  void setMechanizationTag(Mechanization m);

  int motionDim() const { return vi_ekf_slam::motionDim(mechanization_, extrinsic_); }
  bool estimatesExtrinsic() const { return extrinsic_; }
  /// First row/column of the extrinsic's error (valid when estimatesExtrinsic()).
  int extrinsicIndex() const { return vi_ekf_slam::extrinsicIndex(mechanization_); }
  int numLandmarks() const { return static_cast<int>(landmark_ids_.size()); }
  int dim() const { return motionDim() + idx::kLandmarkDim * numLandmarks(); }
  /// Row/column of landmark i (by position in the map) in the error state.
  int landmarkIndex(int i) const { return motionDim() + idx::kLandmarkDim * i; }

  double timestamp = 0.0;  ///< time of the state [s]
  MotionState x;

  // --- map ---------------------------------------------------------------------------------
  const std::vector<std::int64_t>& landmarkIds() const { return landmark_ids_; }
  const Landmark& landmark(int i) const { return landmarks_[static_cast<size_t>(i)]; }
  Landmark& landmark(int i) { return landmarks_[static_cast<size_t>(i)]; }
  const std::vector<Landmark>& landmarks() const { return landmarks_; }
  /// Cartesian position in {s} of landmark i.
  Vec3 landmarkPosition(int i) const { return landmark(i).position(); }
  std::optional<int> findLandmark(std::int64_t id) const;
  /// The error-state entries of the consider landmarks (Landmark::consider), ascending.
  std::vector<int> considerEntries() const;

  /// Appends a landmark with its 3x3 covariance and its cross-covariance to the existing state
  /// (3 x dim(), in the current ordering).
  void appendLandmark(std::int64_t id, const Landmark& landmark, const Eigen::Matrix3d& P_ll,
                      const Eigen::MatrixXd& P_l_state);
  /// Deletes landmarks (by map position) with their rows and columns of P.
  void removeLandmarks(std::vector<int> indices);

  // --- covariance --------------------------------------------------------------------------
  /// Full covariance (applies any pending cross-covariance propagation first).
  const Eigen::MatrixXd& covariance() const;
  Eigen::MatrixXd& mutableCovariance();
  /// Motion block P_s's' (always current, never waits for a flush).
  MotionMatrix motionCovariance() const { return P_.topLeftCorner(motionDim(), motionDim()); }
  /// Replaces the covariance (and, if the layout changes, the mechanization and the map).
  void setCovariance(Eigen::MatrixXd P);

  /// One propagation step (paper eq. 18-19): P_s's' <- Phi P_s's' Phi^T + Qd and
  /// P_s'm <- Phi P_s'm. With lazy cross-covariance (default) the products Phi are accumulated
  /// and applied to P_s'm once, when the full covariance is next read, so an IMU sample costs
  /// the same whatever the map size.
  void propagateCovariance(const MotionMatrix& Phi, const MotionMatrix& Qd);
  /// The same with Qd = Phi diag(q) Phi^T (eq. 18 with G Q G^T dt diagonal), evaluated as
  /// Phi (P_s's' + diag(q)) Phi^T: one matrix product fewer per IMU sample.
  void propagateCovarianceDiagonalNoise(const MotionMatrix& Phi, const MotionVector& q);
  void setLazyCrossCovariance(bool lazy);
  bool hasPendingCrossPropagation() const { return has_pending_phi_; }

  // --- error state -------------------------------------------------------------------------
  /// Injects an error-state correction: additive for vectors, Exp(psi) * q for rotations.
  void boxplus(const Eigen::VectorXd& dx);
  /// Error state e such that other.boxplus(e) == *this (same layout and landmark ids).
  Eigen::VectorXd boxminus(const FilterState& other) const;

  /// Replaces nominal state, map and covariance at once (used by the frame changes); the layout
  /// keeps whether the extrinsic is estimated.
  void reset(Mechanization m, const MotionState& x, std::vector<std::int64_t> ids, std::vector<Landmark> landmarks,
             Eigen::MatrixXd P);

 private:
  /// P_s'm <- Phi P_s'm, or accumulated into the pending product (lazy cross-covariance).
  void propagateCrossCovariance(const MotionMatrix& Phi);
  void flush() const;
  void rebuildIndex();

  Mechanization mechanization_;
  bool extrinsic_ = false;
  std::vector<std::int64_t> landmark_ids_;
  std::vector<Landmark> landmarks_;
  std::unordered_map<std::int64_t, int> index_of_id_;
  mutable Eigen::MatrixXd P_;
  mutable MotionMatrix pending_phi_;
  mutable bool has_pending_phi_ = false;
  bool lazy_cross_ = true;
};

}  // namespace vi_ekf_slam
