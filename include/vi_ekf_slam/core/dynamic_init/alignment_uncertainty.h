// The dynamic initializer's covariance stage: what the refined alignment gives at the window's last
// frame (attitude, gravity-aligned with the yaw of {I0} kept; velocity in {n}; the accelerometer
// bias) and how well: the covariance of [v_n, psi_n, b_a] from the normal equations (features
// eliminated), with the unestimated gyro bias's share (a "consider" parameter, Schmidt), the time
// offset's share and a bound for what first order leaves out; and the joint covariance of the
// last frame's feature depths, which share the window's scale error.
#pragma once

#include <array>
#include <deque>
#include <vector>

#include "vi_ekf_slam/core/dynamic_init/alignment_problem.h"
#include "vi_ekf_slam/core/dynamic_init/time_offset_search.h"
#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"

namespace vi_ekf_slam {
namespace alignment {

struct UncertaintySettings {
  double gyro_bias_sigma_radps = 0.01;  ///< the (unestimated) gyro bias's std-dev [rad/s]
  double time_offset_sigma_s = 0.05;    ///< the time offset's std-dev when not searched [s]
  double time_offset_search_s = 0.1;    ///< the search's half-width (0: not searched) [s]
};

struct AlignedState {
  Quat q_n_b = Quat::Identity();
  Vec3 v_n = Vec3::Zero();
};

/// The covariance of [v_n, psi_n, b_a] for a pixel noise, with the largest std-devs.
struct StateCovariance {
  Eigen::Matrix<double, 9, 9> covariance = Eigen::Matrix<double, 9, 9>::Zero();
  double velocity_sigma_mps = 0.0;  ///< largest axis, with every share
  /// largest axis, from the normal equations and the gyro bias alone (without the time offset's
  /// share and the bound)
  double velocity_sigma_ls_mps = 0.0;
  double tilt_sigma_rad = 0.0;  ///< roll / pitch, largest
};

class AlignmentUncertainty {
 public:
  /// `problem` at its solution after eliminateAtSolution(); it is linearized again (and restored)
  /// for the gyro bias's share. `imu` as the problem's.
  AlignmentUncertainty(AlignmentProblem& problem, const std::deque<ImuData>& imu, const TimeOffsetFit& fit,
                       const UncertaintySettings& settings);

  const AlignedState& state() const { return out_; }
  /// The covariance for a pixel noise sigma_px.
  StateCovariance covariance(double sigma_px) const;
  /// The features of the last frame with their inverse depths' joint covariance and their
  /// cross-covariances with the state and the gyro bias, into r (from `cov` at sigma_px).
  void addLandmarks(const AlignmentProblem& problem, double sigma_px, const StateCovariance& cov,
                    DynamicInitResult* r) const;

 private:
  AlignedState output(const VecY& yy, const Preintegrated& pk, const AlignedState* yaw_ref) const;
  Eigen::Matrix<double, 6, 1> outputDifference(const AlignedState& op, const AlignedState& om, double h) const;
  void gyroBiasShare(AlignmentProblem& problem);

  static constexpr double kBgStep = 1e-4;  ///< the gyro bias's numerical step [rad/s]
  UncertaintySettings s_;
  double G_, f_px_, t_K_, accel_rms_ = 0.0, dt_curvature_;
  VecY y_;
  Preintegrated PK_;  ///< the last frame's
  AlignedState out_;
  Eigen::Matrix<double, 9, 9> J_out_ = Eigen::Matrix<double, 9, 9>::Zero();  ///< d [v_n, psi_n, b_a] / d y
  MatY S_, S_inv_;
  Eigen::Matrix<double, 9, 3> dy_dbg_ = Eigen::Matrix<double, 9, 3>::Zero();
  std::vector<Mat3> dpf_dbg_;
  Eigen::Matrix<double, 9, 3> dout_dbg_ = Eigen::Matrix<double, 9, 3>::Zero();
  std::array<std::array<Preintegrated, 2>, 3> PK_bg_;  ///< the last frame's, at +-kBgStep per axis
};

}  // namespace alignment
}  // namespace vi_ekf_slam
