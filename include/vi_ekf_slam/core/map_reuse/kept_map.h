// The map kept across the filter's runs. A reset (lost, ~reset, a bag restart) starts a new filter
// in a new gravity-aligned world {n}; what the old runs mapped stays here, in the map's own frame
// {m}: each well-mapped landmark's position, covariance and appearance. A new run is placed in it
// by relocalization.h. A map saved to a file (cv::FileStorage, YAML or JSON by the name's
// extension) starts a later run the same way: it is localized as soon as it sees the building it
// walked before.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

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

class KeptMap {
 public:
  /// At most max_points kept [count]; beyond it the points archived first leave first.
  explicit KeptMap(int max_points = 2000) : max_points_(max_points) {}

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

}  // namespace vi_ekf_slam
