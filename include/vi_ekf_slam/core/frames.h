// The one conversion between the filter's navigation frame {n} (paper: x forward/north,
// z down along gravity) and z-up world frames: ROS's ENU-style `world` (REP-103) and the z-up
// worlds of TUM/EuRoC trajectory files. Both are a rotation by pi about x: x stays, y and z flip.
#pragma once

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam {

/// q_w_n: rotates {n} vectors into the z-up world frame {w} (its own inverse).
inline Quat zUpWorldFromNav() { return Quat(0.0, 1.0, 0.0, 0.0); }  // w, x, y, z: pi about x

/// A pose of the body in {n} expressed in {w} (and back: the same map).
inline void navToZUpWorld(const Vec3& p_n, const Quat& q_n_b, Vec3* p_w, Quat* q_w_b) {
  const Quat q_w_n = zUpWorldFromNav();
  *p_w = q_w_n * p_n;
  *q_w_b = (q_w_n * q_n_b).normalized();
}

}  // namespace vi_ekf_slam
