#include "vi_ekf_slam/core/orb_descriptors.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vi_ekf_slam {

namespace {
constexpr float kKeypointSize = 31.0f;
/// ORB's descriptor blur (7x7) reaches this far beyond a sampled pixel [px].
constexpr int kBlurReach = 3;

/// Describes pts[i] for i in `which` on `img` (the whole image or a window of it whose top left
/// corner is `origin`), into out.
void describeIn(cv::ORB& orb, const cv::Mat& img, const cv::Point2f& origin, const std::vector<cv::Point2f>& pts,
                const std::vector<size_t>& which, std::vector<std::optional<Descriptor>>* out) {
  std::vector<cv::KeyPoint> kps;
  kps.reserve(which.size());
  for (size_t i : which) kps.emplace_back(pts[i] - origin, kKeypointSize, -1.0f, 0.0f, 0, static_cast<int>(i));
  cv::Mat desc;
  orb.compute(img, kps, desc);  // drops the points too near the border; class_id says which is which
  for (size_t k = 0; k < kps.size() && static_cast<int>(k) < desc.rows; ++k) {
    Descriptor d;
    const std::uint8_t* row = desc.ptr<std::uint8_t>(static_cast<int>(k));
    std::copy(row, row + d.size(), d.begin());
    (*out)[static_cast<size_t>(kps[k].class_id)] = d;
  }
}
}  // namespace

std::vector<std::optional<Descriptor>> describeOrb(cv::ORB& orb, const cv::Mat& img,
                                                   const std::vector<cv::Point2f>& pts) {
  std::vector<std::optional<Descriptor>> out(pts.size());
  if (pts.empty()) return out;
  // ORB keeps a point whose pixel is at least edge_threshold from its image's border (one more on
  // the far side), and samples within the pattern's radius (under edge_threshold) of it: a window
  // reaching a pixel and the blur's reach further keeps every point the whole image keeps, with
  // the same pixels around it.
  const int half = orb.getEdgeThreshold() + 1 + kBlurReach;
  const int side = 2 * half + 2;  // and one more for an even origin (below)
  const double window_area = static_cast<double>(side) * side * static_cast<double>(pts.size());
  std::vector<size_t> all(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) all[i] = i;
  if (window_area >= 0.5 * static_cast<double>(img.total())) {  // windows would blur more than the image
    describeIn(orb, img, cv::Point2f(0.0f, 0.0f), pts, all, &out);
    return out;
  }
  const cv::Rect image(0, 0, img.cols, img.rows);
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!std::isfinite(pts[i].x) || !std::isfinite(pts[i].y)) continue;
    // ORB rounds a point to its pixel half to even (cvRound): only an even shift of the origin
    // leaves that pixel, and which points it keeps, as they are in the whole image.
    const auto origin = [&](float v) {
      const int o = static_cast<int>(std::floor(v)) - half;
      return o - (o & 1);
    };
    const cv::Rect window = cv::Rect(origin(pts[i].x), origin(pts[i].y), side, side) & image;
    if (window.empty()) continue;
    // (A window ROI shares the image's pixels: no copy.)
    describeIn(orb, img(window), cv::Point2f(static_cast<float>(window.x), static_cast<float>(window.y)), pts, {i},
               &out);
  }
  return out;
}

}  // namespace vi_ekf_slam
