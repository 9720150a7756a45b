// The body's velocity in its own frame as a measurement of the filter: what an independent
// alignment or a prior of the body's motion can say about the state without sharing its world.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/kalman_update.h"

namespace vi_ekf_slam {

/// The body's velocity in the body frame, as something measured it (an alignment of the first
/// images after a blind stretch, velocity_reanchor.h; the motion prior, blind_motion_prior.h): no
/// yaw and no position, so no world needs to be shared with the filter.
struct BodyVelocity {
  double t = 0.0;           ///< when [s, IMU clock]
  Vec3 v_b = Vec3::Zero();  ///< the body's velocity in {b} [m/s]
  Mat3 cov = Mat3::Zero();  ///< its covariance [m^2/s^2]
};

/// The state's own body-frame velocity, R_s_b^T v_s_b, with its covariance from the velocity and
/// orientation blocks of P (the Jacobian bodyVelocityUpdate linearizes with).
BodyVelocity bodyVelocityOfState(const FilterState& state);

/// m as the filter's measurement rows, whitened by m's covariance (cov = L L^T: L^-1 (z - h) =
/// L^-1 H dx + unit noise); none if the covariance is not positive definite.
std::optional<MeasurementRows> whitenedBodyVelocityRows(const FilterState& state, const BodyVelocity& m);

/// The EKF update by m: the filter predicts R_s_b^T v_s_b; m's covariance is whitened into
/// unit-noise rows; gated at gate_probability (3 dof; <= 0: no gate).
KalmanUpdateResult bodyVelocityUpdate(FilterState& state, const BodyVelocity& m, double gate_probability);

}  // namespace vi_ekf_slam
