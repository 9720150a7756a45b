#include "vi_ekf_slam/core/map_archive.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <unordered_map>

namespace vi_ekf_slam {

namespace {

constexpr const char* kFormat = "vi_ekf_slam map";
constexpr int kVersion = 1;
/// Ids are written as doubles (cv::FileStorage has no 64-bit integer): exact below 2^53.
constexpr double kMaxExactId = 9007199254740992.0;

cv::Mat descriptorRows(const std::vector<Descriptor>& d) {
  cv::Mat m(static_cast<int>(d.size()), static_cast<int>(Descriptor().size()), CV_8U);
  for (size_t i = 0; i < d.size(); ++i) std::copy(d[i].begin(), d[i].end(), m.ptr<std::uint8_t>(static_cast<int>(i)));
  return m;
}

}  // namespace

void MapArchive::setMaxPoints(int max_points) {
  max_points_ = max_points;
  if (static_cast<int>(points_.size()) > max_points_) {
    points_.erase(points_.begin(), points_.end() - std::max(0, max_points_));
  }
}

void MapArchive::merge(const std::vector<MapPoint>& points) {
  std::unordered_map<std::int64_t, size_t> incoming;
  for (size_t i = 0; i < points.size(); ++i) incoming[points[i].id] = i;
  points_.erase(std::remove_if(points_.begin(), points_.end(), [&](const MapPoint& p) { return incoming.count(p.id); }),
                points_.end());
  points_.insert(points_.end(), points.begin(), points.end());
  setMaxPoints(max_points_);
}

bool MapArchive::save(const std::string& path, std::string* error) const {
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

bool MapArchive::load(const std::string& path, std::string* error) {
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

std::vector<SearchRegion> wholeImageRegions(const CameraModel& camera) {
  // A front end searches at most 64 px around a region's centre (4 sigma): 32 px sigmas every 128 px.
  constexpr double kStepPx = 128.0, kSigmaPx = 32.0;
  std::vector<SearchRegion> regions;
  for (double v = 0.5 * kStepPx; v - 0.5 * kStepPx < camera.height(); v += kStepPx) {
    for (double u = 0.5 * kStepPx; u - 0.5 * kStepPx < camera.width(); u += kStepPx) {
      regions.push_back({-1, Eigen::Vector2d(u, v), kSigmaPx * kSigmaPx * Eigen::Matrix2d::Identity()});
    }
  }
  return regions;
}

std::optional<Relocalization> relocalize(const MapArchive& map, const std::vector<FeatureObservation>& features,
                                         const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                         const Eigen::Isometry3d& T_n_b, const MapMemoryParams& params,
                                         std::string* why) {
  const auto none = [&](const std::string& what) -> std::optional<Relocalization> {
    if (why) *why = what;
    return std::nullopt;
  };
  // The image's features with an appearance and a usable ray.
  std::vector<const FeatureObservation*> query;
  std::vector<Eigen::Vector2d> rays;
  std::vector<Descriptor> query_d;
  for (const auto& f : features) {
    Eigen::Vector2d xn;
    // A track's latest view is the nearest to this one.
    const std::optional<Descriptor>& d = f.latest_descriptor ? f.latest_descriptor : f.descriptor;
    if (!d || !f.uv.allFinite() || !camera.pixelToNormalized(f.uv, &xn)) continue;
    query.push_back(&f);
    rays.push_back(xn);
    query_d.push_back(*d);
  }
  const int min_inliers = std::max(4, params.relocalize_min_inliers);
  if (static_cast<int>(query.size()) < min_inliers || map.size() < min_inliers) {
    return none("too few features with descriptors or map points");
  }
  std::vector<Descriptor> map_d;
  map_d.reserve(map.points().size());
  for (const auto& p : map.points()) map_d.push_back(p.descriptor);
  const cv::Mat Q = descriptorRows(query_d), M = descriptorRows(map_d);
  // Appearance: the best map point of each feature within the distance bound, clearly better than
  // the second (ratio), and whose own best feature is this one (mutual).
  cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(Q, M, knn, 2);
  std::vector<cv::DMatch> back;
  matcher.match(M, Q, back);
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  std::vector<std::pair<int, int>> matched;  // (query index, map index)
  for (const auto& k : knn) {
    if (k.empty() || k[0].distance > static_cast<float>(params.max_descriptor_distance)) continue;
    if (k.size() > 1 && !(k[0].distance < static_cast<float>(params.descriptor_ratio) * k[1].distance)) continue;
    if (back[static_cast<size_t>(k[0].trainIdx)].trainIdx != k[0].queryIdx) continue;
    const Eigen::Vector3d& p = map.points()[static_cast<size_t>(k[0].trainIdx)].p_m;
    const Eigen::Vector2d& xn = rays[static_cast<size_t>(k[0].queryIdx)];
    object.emplace_back(p.x(), p.y(), p.z());
    image.emplace_back(xn.x(), xn.y());
    matched.emplace_back(k[0].queryIdx, k[0].trainIdx);
  }
  if (static_cast<int>(matched.size()) < min_inliers) {
    return none(std::to_string(matched.size()) + " appearance matches to the map");
  }
  // The camera in the map, on normalized coordinates (K = I): the threshold in focal lengths.
  const double f = 0.5 * (camera.intrinsics().fx + camera.intrinsics().fy);
  const double threshold = params.relocalize_reprojection_px / f;
  cv::Mat rvec, tvec;
  std::vector<int> ransac_inliers;
  const bool solved = cv::solvePnPRansac(object, image, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false, 200,
                                         static_cast<float>(threshold), 0.999, ransac_inliers, cv::SOLVEPNP_AP3P);
  if (!solved || static_cast<int>(ransac_inliers.size()) < min_inliers) {
    return none("PnP: " + std::to_string(ransac_inliers.size()) + " of " + std::to_string(matched.size()) +
                " matches agree");
  }
  // Refined on its inliers (Levenberg-Marquardt), then measured in pixels.
  std::vector<cv::Point3d> in_object;
  std::vector<cv::Point2d> in_image;
  for (int i : ransac_inliers) {
    in_object.push_back(object[static_cast<size_t>(i)]);
    in_image.push_back(image[static_cast<size_t>(i)]);
  }
  cv::solvePnPRefineLM(in_object, in_image, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec);
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  Eigen::Isometry3d T_c_m = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T_c_m.linear()(r, c) = R_cv.at<double>(r, c);
    T_c_m.translation()(r) = tvec.at<double>(r);
  }
  Relocalization out;
  out.matches = static_cast<int>(matched.size());
  double sum_sq = 0.0;
  for (int i : ransac_inliers) {
    const auto [qi, mi] = matched[static_cast<size_t>(i)];
    const Eigen::Vector3d p_c = T_c_m * map.points()[static_cast<size_t>(mi)].p_m;
    Eigen::Vector2d uv;
    if (p_c.z() <= 0.0 || !camera.project(p_c, &uv)) continue;
    const double e2 = (uv - query[static_cast<size_t>(qi)]->uv).squaredNorm();
    if (e2 > params.relocalize_reprojection_px * params.relocalize_reprojection_px) continue;
    sum_sq += e2;
    out.pairs.push_back({query[static_cast<size_t>(qi)]->id, map.points()[static_cast<size_t>(mi)].id,
                         query[static_cast<size_t>(qi)]->uv});
  }
  out.inliers = static_cast<int>(out.pairs.size());
  if (out.inliers < min_inliers) {
    return none("PnP refined: " + std::to_string(out.inliers) + " of " + std::to_string(out.matches) +
                " matches agree");
  }
  out.reprojection_rms_px = std::sqrt(sum_sq / out.inliers);
  Eigen::Isometry3d T_b_c_iso = Eigen::Isometry3d::Identity();
  T_b_c_iso.linear() = T_b_c.R_b_c;
  T_b_c_iso.translation() = T_b_c.p_b_c;
  const Eigen::Isometry3d T_m_b = T_c_m.inverse() * T_b_c_iso.inverse();
  const Eigen::Isometry3d T_m_n_full = T_m_b * T_n_b.inverse();
  const Eigen::Vector3d z_in_m = T_m_n_full.linear() * Eigen::Vector3d::UnitZ();
  out.tilt_deg = std::acos(std::clamp(z_in_m.z(), -1.0, 1.0)) * 180.0 / M_PI;
  if (out.tilt_deg > params.relocalize_max_tilt_deg) {
    return none("PnP camera tilted " + std::to_string(out.tilt_deg) + " deg from the filter's gravity");
  }
  // Both worlds are gravity-aligned: the PnP's yaw and the body's position, the filter's roll and pitch.
  out.T_m_n =
      registrationAtFirstPose(T_n_b.translation(), Quat(T_n_b.linear()), T_m_b.translation(), Quat(T_m_b.linear()));
  return out;
}

}  // namespace vi_ekf_slam
