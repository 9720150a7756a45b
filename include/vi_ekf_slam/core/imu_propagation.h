// Strapdown integration (paper eq. 8-9, and eq. 21 for the sensor-centric case) and the
// covariance time update (eq. 11-19, 22-28).
//
// The discrete step is eq. (8)-(9) with one refinement: the specific force is rotated with the
// attitude at the middle of the step instead of its start, which makes the integration second-
// order accurate (a pedestrian's torso sways at a few rad/s; eq. 8 would turn that into a
// systematic acceleration error).
//
// Phi is the exact Jacobian of that discrete step with respect to the error state, i.e.
// I + F*dt of eq. (17) plus the higher-order terms the same step implies (0.5*dt^2 couplings into
// position, the right Jacobians of the half and full rotation on the gyro bias). That keeps it
// testable against numerical differentiation to round-off.
//
// Sign note: with the error definition of eq. (4) (R_true = Exp(psi) R_est) and
// b_true = b_est + b_err, the orientation error obeys d(psi)/dt = -C * b_g_err; the paper prints
// +C * b_g_err in eq. (15)/(25). The gravity term of eq. (23) is C(q_s^n)^T [g]x psi_s^n (the
// paper prints C(q_b^s)^T). Both are verified numerically in test_imu_propagation.
#pragma once

#include "vi_ekf_slam/core/filter_state.h"

namespace vi_ekf_slam {

/// Continuous-time IMU noise densities (paper eq. 5-6 and the bias random walks).
struct ImuNoiseParams {
  double accel_noise_density = 2.0e-3;  ///< white noise n_a [m/s^2/sqrt(Hz)]
  double gyro_noise_density = 1.7e-4;   ///< white noise n_g [rad/s/sqrt(Hz)]
  double accel_random_walk = 3.0e-3;    ///< bias random walk n_ba [m/s^3/sqrt(Hz)]
  double gyro_random_walk = 2.0e-5;     ///< bias random walk n_bg [rad/s^2/sqrt(Hz)]
};

/// Gravity in {n}: the paper's navigation frame has z along local gravity (pointing down).
inline Vec3 gravityInNav(double g_mps2) { return Vec3(0.0, 0.0, g_mps2); }

/// One strapdown step over dt with the (mean) raw measurements wm [rad/s], am [m/s^2].
void strapdownStep(MotionState& x, Mechanization m, const Vec3& wm, const Vec3& am, double dt, const Vec3& g_n);

/// Error-state transition matrix of strapdownStep() evaluated at the state before the step
/// (`extrinsic`: the layout carries the camera-IMU extrinsic, a constant).
MotionMatrix transitionMatrix(const MotionState& x, Mechanization m, const Vec3& wm, const Vec3& am, double dt,
                              const Vec3& g_n, bool extrinsic = false);

/// Diagonal of G Q G^T dt (isotropic noise through rotations stays diagonal), per error state.
MotionVector continuousNoiseDiagonal(Mechanization m, const ImuNoiseParams& noise, double dt, bool extrinsic = false);

/// Discrete process noise Phi * G Q G^T * Phi^T * dt (paper eq. 18).
MotionMatrix discreteNoise(const MotionMatrix& Phi, Mechanization m, const ImuNoiseParams& noise, double dt,
                           bool extrinsic = false);

/// Propagates nominal state and covariance of the filter by one IMU interval.
void propagateState(FilterState& state, const Vec3& wm, const Vec3& am, double dt, const ImuNoiseParams& noise,
                    const Vec3& g_n);

}  // namespace vi_ekf_slam
