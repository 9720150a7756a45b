// Placing a new run in the kept map (kept_map.h): when the camera sees mapped points again, their
// descriptors matched to the image's features (descriptor_matching.h) and a PnP RANSAC (OpenCV)
// give the camera in the map's frame {m}; with the filter's own pose in {n} that places {n} in {m}
// (a yaw and a translation: both worlds are gravity-aligned, so a tilt between them marks a false
// match).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/camera_extrinsics.h"
#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/map_reuse/kept_map.h"
#include "vi_ekf_slam/core/map_reuse/map_reuse_params.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

/// A new run's world placed in the map.
struct Relocalization {
  Eigen::Isometry3d T_m_n = Eigen::Isometry3d::Identity();  ///< a rotation about z and a translation
  int matches = 0;                                          ///< appearance matches tried [count]
  int inliers = 0;                                          ///< reprojecting within the threshold [count]
  double reprojection_rms_px = 0.0;                         ///< of the inliers [px]
  double tilt_deg = 0.0;                                    ///< between the PnP camera's gravity and the filter's [deg]
  /// An inlier: the image's feature (its id, or a searched corner's) and the map point it is.
  struct Pair {
    std::int64_t feature_id = 0;
    std::int64_t point_id = 0;
    Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< the feature's pixel [px]
  };
  std::vector<Pair> pairs;
};

/// Regions that tile the whole image for CameraFrame::search (a relocalization looks for mapped
/// points everywhere, not only where tracks are).
std::vector<SearchRegion> wholeImageRegions(const CameraModel& camera);

/// Places the world {n} of a filter whose body is at T_n_b (at the image's time) in the map: the
/// image's features with descriptors matched to the map's (within max_descriptor_distance, the
/// ratio test, mutual best), PnP RANSAC on them refined on its inliers, then the pose reduced to
/// yaw and translation (the filter's roll and pitch kept). None, and *why, when fewer than
/// relocalize_min_inliers reproject within relocalize_reprojection_px or the PnP camera's gravity
/// is off the filter's by more than relocalize_max_tilt_deg.
std::optional<Relocalization> relocalize(const KeptMap& map, const std::vector<FeatureObservation>& features,
                                         const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                         const Eigen::Isometry3d& T_n_b, const MapReuseParams& params,
                                         std::string* why = nullptr);

}  // namespace vi_ekf_slam
