#include "vi_ekf_slam/core/map_reuse/kept_map.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <opencv2/core.hpp>
#include <unordered_map>

#include "vi_ekf_slam/core/map_reuse/descriptor_matching.h"

namespace vi_ekf_slam {

namespace {

constexpr const char* kFormat = "vi_ekf_slam map";
constexpr int kVersion = 1;
/// Ids are written as doubles (cv::FileStorage has no 64-bit integer): exact below 2^53.
constexpr double kMaxExactId = 9007199254740992.0;

}  // namespace

void KeptMap::setMaxPoints(int max_points) {
  max_points_ = max_points;
  if (static_cast<int>(points_.size()) > max_points_) {
    points_.erase(points_.begin(), points_.end() - std::max(0, max_points_));
  }
}

void KeptMap::merge(const std::vector<MapPoint>& points) {
  std::unordered_map<std::int64_t, size_t> incoming;
  for (size_t i = 0; i < points.size(); ++i) incoming[points[i].id] = i;
  points_.erase(std::remove_if(points_.begin(), points_.end(), [&](const MapPoint& p) { return incoming.count(p.id); }),
                points_.end());
  points_.insert(points_.end(), points.begin(), points.end());
  setMaxPoints(max_points_);
}

bool KeptMap::save(const std::string& path, std::string* error) const {
  const int n = size();
  cv::Mat ids(n, 1, CV_64F), positions(n, 3, CV_64F), covariances(n, 9, CV_64F);
  std::vector<Descriptor> descriptors;
  for (int i = 0; i < n; ++i) {
    const MapPoint& p = points_[static_cast<size_t>(i)];
    if (std::abs(static_cast<double>(p.id)) > kMaxExactId) {
      if (error) *error = path + ": landmark id " + std::to_string(p.id) + " too large to store exactly";
      return false;
    }
    ids.at<double>(i) = static_cast<double>(p.id);
    for (int k = 0; k < 3; ++k) positions.at<double>(i, k) = p.p_m(k);
    for (int k = 0; k < 9; ++k) covariances.at<double>(i, k) = p.cov(k / 3, k % 3);
    descriptors.push_back(p.descriptor);
  }
  try {
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    if (!fs.isOpened()) {
      if (error) *error = path + ": cannot be written";
      return false;
    }
    fs << "format" << kFormat << "version" << kVersion << "points" << n;
    fs << "ids" << ids << "positions_m" << positions << "covariances_m2" << covariances << "descriptors"
       << descriptorRows(descriptors);
  } catch (const cv::Exception& e) {
    if (error) *error = path + ": " + e.what();
    return false;
  }
  return true;
}

bool KeptMap::load(const std::string& path, std::string* error) {
  const auto fail = [&](const std::string& what) {
    if (error) *error = path + ": " + what;
    return false;
  };
  std::vector<MapPoint> loaded;
  if (!std::ifstream(path).good()) return fail("cannot be read");
  try {
    cv::FileStorage fs(path, cv::FileStorage::READ);
    if (!fs.isOpened()) return fail("cannot be read");
    if (static_cast<std::string>(fs["format"]) != kFormat) return fail("not a vi_ekf_slam map (no 'format' key)");
    if (static_cast<int>(fs["version"]) != kVersion) return fail("map version is not " + std::to_string(kVersion));
    cv::Mat ids, positions, covariances, descriptors;
    fs["ids"] >> ids;
    fs["positions_m"] >> positions;
    fs["covariances_m2"] >> covariances;
    fs["descriptors"] >> descriptors;
    const int n = static_cast<int>(fs["points"]);
    if (n == 0) {
      points_.clear();
      return true;
    }
    if (ids.rows != n || positions.rows != n || covariances.rows != n || descriptors.rows != n || positions.cols != 3 ||
        covariances.cols != 9 || descriptors.cols != static_cast<int>(Descriptor().size()) || ids.type() != CV_64F ||
        positions.type() != CV_64F || covariances.type() != CV_64F || descriptors.type() != CV_8U) {
      return fail("ids, positions_m, covariances_m2 and descriptors must have 'points' rows of 1, 3, 9 and 32 values");
    }
    for (int i = 0; i < n; ++i) {
      MapPoint p;
      p.id = static_cast<std::int64_t>(ids.at<double>(i));
      for (int k = 0; k < 3; ++k) p.p_m(k) = positions.at<double>(i, k);
      for (int k = 0; k < 9; ++k) p.cov(k / 3, k % 3) = covariances.at<double>(i, k);
      std::copy(descriptors.ptr<std::uint8_t>(i), descriptors.ptr<std::uint8_t>(i) + p.descriptor.size(),
                p.descriptor.begin());
      if (!p.p_m.allFinite() || !p.cov.allFinite() || p.cov.trace() < 0.0) {
        return fail("point " + std::to_string(i) + " is not finite");
      }
      loaded.push_back(p);
    }
  } catch (const cv::Exception& e) {
    return fail(e.what());
  }
  points_ = std::move(loaded);
  setMaxPoints(max_points_);
  return true;
}

}  // namespace vi_ekf_slam
