// The map kept across the filter's runs. A reset (lost, ~reset, a bag restart) starts a new filter
// in a new gravity-aligned world {n}; what the old runs mapped stays here, in the map's own frame
// {m}: each well-mapped landmark's position, covariance and appearance. When the camera sees
// mapped points again, their descriptors matched to the image's features and a PnP RANSAC (OpenCV)
// give the camera in {m}; with the filter's own pose in {n} that places {n} in {m} (a yaw and a
// translation: both worlds are gravity-aligned, so a tilt between them marks a false match). A map
// saved to a file (cv::FileStorage, YAML or JSON by the name's extension) starts a later run the
// same way: it is localized as soon as it sees the building it walked before.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/camera_extrinsics.h"
#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/map_memory.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

/// One kept landmark: the id of the track that mapped it, its position in the map frame {m} with
/// its 3x3 covariance [m^2], and its appearance.
struct MapPoint {
  std::int64_t id = 0;
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  Descriptor descriptor{};
};

class MapArchive {
 public:
  /// At most max_points kept [count]; beyond it the points archived first leave first.
  explicit MapArchive(int max_points = 2000) : max_points_(max_points) {}

  bool empty() const { return points_.empty(); }
  int size() const { return static_cast<int>(points_.size()); }
  const std::vector<MapPoint>& points() const { return points_; }
  void setMaxPoints(int max_points);
  /// Adds the points; one of the same id replaces the older one (a landmark mapped again).
  void merge(const std::vector<MapPoint>& points);
  void clear() { points_.clear(); }

  /// Writes the points (YAML or JSON by the extension; .gz compresses). False and *error if not.
  bool save(const std::string& path, std::string* error) const;
  /// Replaces the points by the file's. False and *error (naming the file and what is wrong) if
  /// it cannot be read; the archive is then unchanged.
  bool load(const std::string& path, std::string* error);

 private:
  int max_points_;
  std::vector<MapPoint> points_;
};

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
std::optional<Relocalization> relocalize(const MapArchive& map, const std::vector<FeatureObservation>& features,
                                         const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                         const Eigen::Isometry3d& T_n_b, const MapMemoryParams& params,
                                         std::string* why = nullptr);

}  // namespace vi_ekf_slam
