// The dynamic initializer's IMU stage: the gyro's attitude and the accelerometer's position and
// velocity increments between the frames of a window, in the first body frame {I0}, with their
// (exact, linear) dependence on the accelerometer bias.
#pragma once

#include <deque>
#include <vector>

#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {
namespace alignment {

/// The IMU sample interpolated at time t (clamped to the buffer, which must not be empty).
ImuData interpolate(const std::deque<ImuData>& imu, double t);

/// Attitude R_I0_Ik and the position / velocity increments (in {I0}, gravity left out) at a time
/// after the window's first.
struct Preintegrated {
  Mat3 R = Mat3::Identity();
  Vec3 alpha = Vec3::Zero();
  Vec3 beta = Vec3::Zero();
  Mat3 A = Mat3::Zero();  ///< d alpha / d b_a (exact: alpha is linear in the accelerometer bias)
  Mat3 B = Mat3::Zero();  ///< d beta / d b_a
};

/// One entry per sorted time in `times`, from the first one (midpoint rule between the IMU's
/// samples and the times). b_g: a gyro bias taken off the rates (the alignment's sensitivity to it).
std::vector<Preintegrated> preintegrate(const std::deque<ImuData>& imu, const std::vector<double>& times,
                                        const Vec3& b_g = Vec3::Zero());

}  // namespace alignment
}  // namespace vi_ekf_slam
