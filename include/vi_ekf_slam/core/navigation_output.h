// One output API for every mechanization: the body pose, velocity and biases in the navigation
// frame {n} with their covariance, and each landmark in {n} with its 3x3 covariance.
#pragma once

#include <cstdint>
#include <vector>

#include "vi_ekf_slam/core/filter_state.h"

namespace vi_ekf_slam {

struct NavState {
  double timestamp = 0.0;
  Vec3 p_n_b = Vec3::Zero();
  Vec3 v_n_b = Vec3::Zero();
  Quat q_n_b = Quat::Identity();
  Vec3 b_a = Vec3::Zero();
  Vec3 b_g = Vec3::Zero();
  double t_d = 0.0;        ///< camera-IMU time offset estimate: t_imu = t_image + t_d [s]
  double t_d_sigma = 0.0;  ///< its std-dev [s]
  /// Covariance in the world-centric error layout [p, v, b_a, psi_n_b, b_g] (idx::kP ...).
  Eigen::Matrix<double, idx::kNavDim, idx::kNavDim> cov = Eigen::Matrix<double, idx::kNavDim, idx::kNavDim>::Zero();

  /// 6x6 pose covariance ordered [position, orientation (psi_n_b, global)].
  Eigen::Matrix<double, 6, 6> poseCovariance() const;
};

struct NavLandmark {
  std::int64_t id = 0;
  Vec3 p_n_l = Vec3::Zero();
  Mat3 cov = Mat3::Zero();
};

NavState navState(const FilterState& state);
std::vector<NavLandmark> navLandmarks(const FilterState& state);

}  // namespace vi_ekf_slam
