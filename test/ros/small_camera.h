// A 64x48 pinhole camera for the glue's unit tests: small enough to build images by hand.
#pragma once

#include "vi_ekf_slam/core/camera_model.h"

namespace vi_ekf_slam::glue {

inline CameraIntrinsics smallCamera() {
  CameraIntrinsics in;
  in.width = 64;
  in.height = 48;
  in.fx = in.fy = 50.0;
  in.cx = 32.0;
  in.cy = 24.0;
  return in;
}

}  // namespace vi_ekf_slam::glue
