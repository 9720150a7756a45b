// Coming back after a blind stretch (a covered lens, smoke, darkness). While the camera sees
// nothing the velocity drifts on the IMU alone; once it sees again, the first new landmarks are
// placed with that drifted velocity (their depth is tied to it) and then hold it: the filter runs
// off confidently, with no old landmark to tell it. So before new landmarks may enter, the first
// frames after the stretch are aligned with the IMU on their own (the dynamic initializer, as at a
// moving start, blind to the filter's estimate), and what the alignment knows independently of
// its own yaw and position, the body's velocity in the body frame, with its covariance, corrects
// the filter as a measurement. (Its accelerometer bias is not used: over a second of slow motion
// the alignment hardly knows it, and where the filter's disagreed the difference was many of the
// alignment's sigmas on the real recording.)
#pragma once

#include <Eigen/Core>

#include "vi_ekf_slam/core/body_velocity.h"
#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"

namespace vi_ekf_slam {

/// The alignment's velocity turned into its body frame, v_b = R_n_b^T v_n; the covariance carries
/// its tilt's error into v_b (v_b = R^T Exp(-psi) v_n to first order).
BodyVelocity bodyVelocityOf(const DynamicInitResult& aligned);

}  // namespace vi_ekf_slam
