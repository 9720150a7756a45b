#include "vi_ekf_slam/core/map_reuse/relocalization.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "vi_ekf_slam/core/map_reuse/descriptor_matching.h"

namespace vi_ekf_slam {

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

std::optional<Relocalization> relocalize(const KeptMap& map, const std::vector<FeatureObservation>& features,
                                         const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                         const Eigen::Isometry3d& T_n_b, const MapReuseParams& params,
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
  // the second (ratio, in single precision as OpenCV's distances), and whose own best feature is
  // this one (mutual).
  const std::vector<NearestTwo> nearest = nearestTwo(Q, M), back = nearestTwo(M, Q);
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  std::vector<std::pair<int, int>> matched;  // (query index, map index)
  for (int q = 0; q < static_cast<int>(nearest.size()); ++q) {
    const NearestTwo& k = nearest[static_cast<size_t>(q)];
    if (k.index < 0 || k.distance > params.max_descriptor_distance) continue;
    if (k.second != NearestTwo::kNone &&
        !(static_cast<float>(k.distance) < static_cast<float>(params.descriptor_ratio) * static_cast<float>(k.second)))
      continue;
    if (back[static_cast<size_t>(k.index)].index != q) continue;
    const Eigen::Vector3d& p = map.points()[static_cast<size_t>(k.index)].p_m;
    const Eigen::Vector2d& xn = rays[static_cast<size_t>(q)];
    object.emplace_back(p.x(), p.y(), p.z());
    image.emplace_back(xn.x(), xn.y());
    matched.emplace_back(q, k.index);
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
