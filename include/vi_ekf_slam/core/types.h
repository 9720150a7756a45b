// Plain data structs that enter the core, in the spirit of OpenVINS' ImuData: no ROS types, SI
// units, timestamps in seconds.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

namespace vi_ekf_slam {

/// One IMU sample in the body (IMU) frame {b}.
struct ImuData {
  double timestamp = 0.0;                        ///< [s]
  Eigen::Vector3d wm = Eigen::Vector3d::Zero();  ///< measured angular rate [rad/s], eq. (6)
  Eigen::Vector3d am = Eigen::Vector3d::Zero();  ///< measured specific force [m/s^2], eq. (5)
};
/// A sample whose stamp and readings are all finite (the others are refused everywhere).
inline bool isFinite(const ImuData& d) { return std::isfinite(d.timestamp) && d.wm.allFinite() && d.am.allFinite(); }

/// One tracked feature in one image: a landmark id (data association comes from the front end
/// or the simulator) and its distorted pixel coordinates.
struct FeatureObservation {
  std::int64_t id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< [px]
};

/// All features of one camera image.
struct CameraFrame {
  double timestamp = 0.0;  ///< [s] on the camera's clock; the filter adds its time offset estimate
  std::vector<FeatureObservation> features;
};

}  // namespace vi_ekf_slam
