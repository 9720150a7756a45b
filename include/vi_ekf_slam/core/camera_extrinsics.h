// The camera's pose in the body (IMU) frame: a calibration, or a state when it is estimated online.
#pragma once

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam {

/// Pose of the camera {c} in the body/IMU frame {b}.
struct CameraExtrinsics {
  Mat3 R_b_c = Mat3::Identity();
  Vec3 p_b_c = Vec3::Zero();  ///< [m]
};

}  // namespace vi_ekf_slam
