// Plain data structs that enter the core, in the spirit of OpenVINS' ImuData: no ROS types, SI
// units, timestamps in seconds.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
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

/// A binary appearance descriptor of 256 bits (OpenCV's ORB), compared by Hamming distance.
using Descriptor = std::array<std::uint8_t, 32>;

/// One tracked feature in one image: a landmark id (data association comes from the front end
/// or the simulator) and its distorted pixel coordinates.
struct FeatureObservation {
  std::int64_t id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< [px]
  /// The track's appearance where it was detected (the same on every image of the track), if the
  /// front end gives one: what finds the point again once the track has ended (map_reuse/revisit_matching.h).
  std::optional<Descriptor> descriptor = std::nullopt;
  /// Its appearance described again every kDescribeEveryFrames images (the latest view's): what
  /// the map kept across resets holds (map_reuse/kept_map.h), as a return to the same place sees that one.
  std::optional<Descriptor> latest_descriptor = std::nullopt;
};

/// How often a front end describes its tracks again [images]: the appearance kept with a landmark
/// is then its latest view's (a return to the same place sees that one, not the first view's).
constexpr int kDescribeEveryFrames = 10;

/// Where the filter expects a landmark whose track ended: its predicted pixel and the innovation
/// covariance of that prediction [px^2] (map_reuse/revisit_matching.h).
struct SearchRegion {
  std::int64_t landmark_id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();     ///< [px]
  Eigen::Matrix2d S = Eigen::Matrix2d::Identity();  ///< [px^2]
};

/// All features of one camera image.
struct CameraFrame {
  double timestamp = 0.0;  ///< [s] on the camera's clock; the filter adds its time offset estimate
  std::vector<FeatureObservation> features;
  /// Optional, from a front end that can look again at this image: the corners it finds inside
  /// the regions (not its tracks; ids unique in this image, descriptors set). The filter matches
  /// them with the landmarks it expects there.
  std::function<std::vector<FeatureObservation>(const std::vector<SearchRegion>&)> search;
  /// With search: the front end starts tracking a corner it returned; returns the new track's id.
  std::function<std::int64_t(const FeatureObservation&)> adopt;
};

}  // namespace vi_ekf_slam
