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
#include "vi_ekf_slam/core/dynamic_init/preintegration.h"

namespace vi_ekf_slam {

/// The alignment's velocity turned into its body frame, v_b = R_n_b^T v_n, and carried on the IMU
/// from the alignment's last frame to a later time t, where the filter is: the alignment only takes
/// frames the IMU covers beyond its time offset search, so its state lags the newest image by a few
/// frames (0.1 s at 28 Hz), and in that time a walker's vertical velocity swings by as much as the
/// alignment's sigma (the gait's bounce). `imu`: the IMU from aligned.state.timestamp to t in the
/// alignment's last body frame {b1} (R = R_b1_b, beta the velocity increment of the raw specific
/// force, B its dependence on the accelerometer bias; alignment::preintegrate; an empty one with
/// t = aligned.state.timestamp for the velocity at the alignment's own time), with gravity
/// g_n = gravityInNav(gravity_mps2) in the alignment's {n}: v_n(t) = v_n + g_n dt + R_n_b1 (beta +
/// B b_a), R_n_b(t) = R_n_b1 R. Its covariance is the alignment's, through the Jacobian of v_b(t) in
/// its velocity, tilt and accelerometer bias (v_b = R^T Exp(-psi) v_n to first order; the IMU's own
/// noise over the fraction of a second is left out: 1e-3 of the alignment's sigma).
BodyVelocity bodyVelocityOf(const DynamicInitResult& aligned, const alignment::Preintegrated& imu, double t,
                            double gravity_mps2);

}  // namespace vi_ekf_slam
