// Landmark observation model (paper eq. 29-30): z = pi(C_s^c (Y - p_s_c)) + v, with the
// camera-IMU extrinsic R_b_c, p_b_c. The same model serves every mechanization because
// landmarks live in the strapdown frame {s}.
#pragma once

#include <Eigen/Core>

#include "vi_ekf_slam/core/camera_extrinsics.h"
#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/landmark.h"

namespace vi_ekf_slam {

/// Jacobians of one predicted observation (2 rows): J_pi * [J_p, J_psi, J_Y] of eq. (30).
struct ObservationJacobians {
  Eigen::Matrix<double, 2, 3> H_p;    ///< w.r.t. position error of {b} in {s}
  Eigen::Matrix<double, 2, 3> H_psi;  ///< w.r.t. orientation error psi_s_b
  Eigen::Matrix<double, 2, 3> H_l;    ///< w.r.t. the landmark's three state entries
  /// w.r.t. the camera's position error in {b} (extrinsic); an inverse-depth anchor moves with it
  /// (landmark.h), as in a state that estimates the extrinsic
  Eigen::Matrix<double, 2, 3> H_pbc;
  Eigen::Matrix<double, 2, 3> H_thc;  ///< w.r.t. the camera's rotation error: R_b_c = Exp(theta) R_b_c
};

/// A Cartesian point p_s_l in the camera frame.
Vec3 landmarkInCamera(const MotionState& x, const Vec3& p_s_l, const CameraExtrinsics& T_b_c);

/// Predicts the pixel of a landmark; false if it is behind the camera. Inverse-depth landmarks
/// are projected through rho * (p_s_l - p_s_c), which stays finite as rho -> 0.
bool predictObservation(const MotionState& x, const Landmark& landmark, const CameraModel& camera,
                        const CameraExtrinsics& T_b_c, Eigen::Vector2d* uv, ObservationJacobians* J = nullptr);

/// Image velocity [px/s] of a landmark's projection while the body moves with the velocity
/// x.v_s_b and the angular rate omega_b [rad/s] (body frame): d(pixel)/dt, which is also the
/// observation's Jacobian w.r.t. the camera-IMU time offset t_d (the image at t_i is the state at
/// t_i + t_d). It comes from the state alone: a velocity from differences of measured pixels
/// would share the current pixel's noise with the residual and bias t_d. False if behind the camera.
bool predictImageVelocity(const MotionState& x, const Landmark& landmark, const CameraModel& camera,
                          const CameraExtrinsics& T_b_c, const Vec3& omega_b, Eigen::Vector2d* velocity_pxps);

}  // namespace vi_ekf_slam
