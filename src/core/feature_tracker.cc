#include "vi_ekf_slam/core/feature_tracker.h"

#include "vi_ekf_slam/core/orb_descriptors.h"
#include "vi_ekf_slam/core/param_ranges.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <sstream>

namespace vi_ekf_slam {

std::string TrackerParams::validate() const {
  std::ostringstream err;
  checkRange(err, "max_tracks", max_tracks);  // RANSAC needs 8 points
  checkRange(err, "tracker_grid_cells", grid_cols);
  checkRange(err, "tracker_grid_cells", grid_rows);
  checkRange(err, "min_distance_px", min_distance_px);
  checkRange(err, "quality_level", quality_level);
  checkRange(err, "fast_threshold", fast_threshold);
  checkRange(err, "min_corner_snr", min_corner_snr);
  checkRange(err, "klt_window_px", klt_window_px);
  if (klt_window_px % 2 == 0) err << "klt_window_px must be odd (got " << klt_window_px << ")\n";
  checkRange(err, "klt_pyramid_levels", klt_pyramid_levels);
  checkRange(err, "fb_threshold_px", fb_threshold_px);
  checkRange(err, "ransac_threshold_px", ransac_threshold_px);
  checkRange(err, "tracker_border_px", border_px);
  checkRange(err, "redetect_fraction", redetect_fraction);
  checkRange(err, "max_image_width_px", max_image_width_px);
  if (max_image_width_px != 0 && max_image_width_px < 160) {
    err << "max_image_width_px must be 0 (full resolution) or at least 160 (got " << max_image_width_px << ")\n";
  }
  return err.str();
}

std::optional<TrackerParams::Detector> detectorFromString(const std::string& s) {
  if (s == "shi_tomasi") return TrackerParams::Detector::kShiTomasi;
  if (s == "fast") return TrackerParams::Detector::kFast;
  return std::nullopt;
}

CameraIntrinsics trackingIntrinsics(const CameraIntrinsics& full, int max_width_px) {
  if (max_width_px <= 0 || full.width <= max_width_px) return full;
  CameraIntrinsics t = full;
  t.width = max_width_px;
  t.height = std::max(1, static_cast<int>(std::lround(full.height * static_cast<double>(max_width_px) / full.width)));
  const double sx = static_cast<double>(t.width) / full.width, sy = static_cast<double>(t.height) / full.height;
  t.fx = full.fx * sx;
  t.fy = full.fy * sy;
  t.cx = (full.cx + 0.5) * sx - 0.5;
  t.cy = (full.cy + 0.5) * sy - 0.5;
  return t;
}

cv::Mat toTrackingResolution(const cv::Mat& img, const CameraIntrinsics& tracking) {
  if (img.cols == tracking.width && img.rows == tracking.height) return img;
  cv::Mat out;
  cv::resize(img, out, cv::Size(tracking.width, tracking.height), 0.0, 0.0, cv::INTER_AREA);
  return out;
}

FeatureTracker::FeatureTracker(const CameraModel& camera, const TrackerParams& params)
    : camera_(camera), params_(params) {}

std::vector<FeatureObservation> FeatureTracker::searchCorners(const cv::Mat& img,
                                                              const std::vector<SearchRegion>& regions) {
  std::vector<cv::Point2f> found;
  const double min_d2 = params_.min_distance_px * params_.min_distance_px;
  auto farFromAll = [&](const cv::Point2f& p) {
    for (const auto& t : tracks_)
      if ((t.uv.x - p.x) * (t.uv.x - p.x) + (t.uv.y - p.y) * (t.uv.y - p.y) < min_d2) return false;
    for (const auto& q : found)  // regions overlap: a corner once
      if ((q.x - p.x) * (q.x - p.x) + (q.y - p.y) * (q.y - p.y) < 1.0) return false;
    return true;
  };
  const cv::Rect image(0, 0, img.cols, img.rows);
  for (const auto& r : regions) {
    const double half = std::min(64.0, 4.0 * std::sqrt(std::max(r.S(0, 0), r.S(1, 1))));
    const cv::Rect roi = cv::Rect(static_cast<int>(r.uv.x() - half), static_cast<int>(r.uv.y() - half),
                                  static_cast<int>(2 * half) + 1, static_cast<int>(2 * half) + 1) &
                         image;
    if (roi.width < 7 || roi.height < 7) continue;
    std::vector<cv::Point2f> pts;
    cv::goodFeaturesToTrack(img(roi), pts, 6, params_.quality_level, 3.0, cv::noArray(), 3);
    for (const auto& p : pts) {
      const cv::Point2f q = p + cv::Point2f(static_cast<float>(roi.x), static_cast<float>(roi.y));
      if (farFromAll(q) && aboveNoise(q)) found.push_back(q);
    }
  }
  std::vector<FeatureObservation> corners;
  const auto desc = describeOrb(*orb_, img, found);
  for (size_t i = 0; i < found.size(); ++i)
    if (desc[i]) corners.push_back({static_cast<std::int64_t>(i), Eigen::Vector2d(found[i].x, found[i].y), desc[i]});
  return corners;
}

std::int64_t FeatureTracker::adoptCorner(const FeatureObservation& corner) {
  const cv::Point2f p(static_cast<float>(corner.uv.x()), static_cast<float>(corner.uv.y()));
  tracks_.push_back({next_id_++, p, 1, {p}, corner.descriptor, corner.descriptor});
  return tracks_.back().id;
}

void FeatureTracker::reset() {
  tracks_.clear();
  prev_pyramid_.clear();
  prev_image_.release();
}

bool FeatureTracker::aboveNoise(const cv::Point2f& p) const {
  return !signal_ || signal_->snr(p, params_.klt_window_px) >= params_.min_corner_snr;
}

cv::Point2f FeatureTracker::predict(const cv::Point2f& uv, const Eigen::Matrix3d& R_cur_prev) const {
  // Rotation-only prediction (infinite homography), through the lens model.
  Eigen::Vector2d xn;
  if (!camera_.pixelToNormalized(Eigen::Vector2d(uv.x, uv.y), &xn)) return uv;
  const Eigen::Vector3d r = R_cur_prev * Eigen::Vector3d(xn.x(), xn.y(), 1.0);
  if (r.z() < 0.1) return uv;
  const Eigen::Vector2d p = camera_.normalizedToPixel(Eigen::Vector2d(r.x() / r.z(), r.y() / r.z()));
  return {static_cast<float>(p.x()), static_cast<float>(p.y())};
}

CameraFrame FeatureTracker::track(double timestamp, const cv::Mat& img,
                                  const std::optional<Eigen::Matrix3d>& R_cur_prev) {
  CV_Assert(img.type() == CV_8UC1);
  stats_ = TrackerStats();
  signal_.reset();
  if (params_.min_corner_snr > 0.0) {
    signal_.emplace(img);
    stats_.noise_sigma = signal_->noiseSigma();
  }
  const cv::Size win(params_.klt_window_px, params_.klt_window_px);
  std::vector<cv::Mat> pyramid;
  cv::buildOpticalFlowPyramid(img, pyramid, win, params_.klt_pyramid_levels);
  const bool same_size = !prev_image_.empty() && prev_image_.size() == img.size();
  if (!tracks_.empty() && same_size) {
    std::vector<cv::Point2f> p0, p1, p0_back;
    for (const auto& t : tracks_) {
      p0.push_back(t.uv);
      p1.push_back(R_cur_prev ? predict(t.uv, *R_cur_prev) : t.uv);
    }
    std::vector<uchar> st, st_back;
    std::vector<float> err;
    const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
    cv::calcOpticalFlowPyrLK(prev_pyramid_, pyramid, p0, p1, st, err, win, params_.klt_pyramid_levels, crit,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
    p0_back = p0;
    cv::calcOpticalFlowPyrLK(pyramid, prev_pyramid_, p1, p0_back, st_back, err, win, params_.klt_pyramid_levels, crit,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
    std::vector<Track> kept;
    std::vector<cv::Point2f> n0, n1;  // undistorted pixel coordinates for RANSAC
    const double b = params_.border_px;
    for (size_t i = 0; i < tracks_.size(); ++i) {
      const cv::Point2f& q = p1[i];
      if (!st[i] || q.x < b || q.y < b || q.x > img.cols - 1 - b || q.y > img.rows - 1 - b) {
        ++stats_.lost;
        continue;
      }
      if (!st_back[i] || cv::norm(p0_back[i] - p0[i]) > params_.fb_threshold_px) {
        ++stats_.fb_rejected;
        continue;
      }
      // KLT finds a best match in noise too, and noise matches itself back: a track into a dark
      // image ends here.
      if (!aboveNoise(q)) {
        ++stats_.noise_rejected;
        continue;
      }
      Eigen::Vector2d a, c;
      if (!camera_.pixelToNormalized(Eigen::Vector2d(p0[i].x, p0[i].y), &a) ||
          !camera_.pixelToNormalized(Eigen::Vector2d(q.x, q.y), &c)) {
        ++stats_.lost;
        continue;
      }
      const auto& K = camera_.intrinsics();
      n0.emplace_back(static_cast<float>(K.fx * a.x() + K.cx), static_cast<float>(K.fy * a.y() + K.cy));
      n1.emplace_back(static_cast<float>(K.fx * c.x() + K.cx), static_cast<float>(K.fy * c.y() + K.cy));
      Track t = tracks_[i];
      t.uv = q;
      ++t.age;
      t.history.push_back(q);
      if (t.history.size() > 10) t.history.erase(t.history.begin());
      kept.push_back(std::move(t));
    }
    // Epipolar RANSAC on undistorted points; skipped with too few points to be meaningful.
    if (kept.size() >= 12) {
      std::vector<uchar> inlier;
      const cv::Mat F = cv::findFundamentalMat(n0, n1, cv::FM_RANSAC, params_.ransac_threshold_px, 0.99, inlier);
      if (!F.empty() && inlier.size() == kept.size()) {
        std::vector<Track> in;
        for (size_t i = 0; i < kept.size(); ++i) {
          if (inlier[i])
            in.push_back(std::move(kept[i]));
          else
            ++stats_.ransac_rejected;
        }
        kept = std::move(in);
      }
    }
    tracks_ = std::move(kept);
    stats_.tracked = static_cast<int>(tracks_.size());
  } else {
    tracks_.clear();
  }
  // The corner search costs the same whether one track or ten are missing (every cell below
  // its quota is searched), so it can wait until redetect_fraction (<= 1) of the tracks are left.
  if (static_cast<double>(tracks_.size()) < params_.redetect_fraction * params_.max_tracks) detect(img);
  if (params_.descriptors && ++images_since_described_ >= kDescribeEveryFrames) {
    // The tracks' appearance in this view (one the ORB cannot describe, near the border, keeps its last).
    images_since_described_ = 0;
    std::vector<cv::Point2f> pts;
    for (const auto& t : tracks_) pts.push_back(t.uv);
    const auto desc = describeOrb(*orb_, img, pts);
    for (size_t i = 0; i < pts.size(); ++i)
      if (desc[i]) tracks_[i].latest_descriptor = desc[i];
  }
  prev_pyramid_ = std::move(pyramid);
  prev_image_ = img;
  CameraFrame f;
  f.timestamp = timestamp;
  for (const auto& t : tracks_) {
    f.features.push_back({t.id, Eigen::Vector2d(t.uv.x, t.uv.y), t.descriptor, t.latest_descriptor});
  }
  stats_.total = static_cast<int>(tracks_.size());
  if (params_.descriptors) {
    f.search = [this, img](const std::vector<SearchRegion>& regions) { return searchCorners(img, regions); };
    f.adopt = [this](const FeatureObservation& corner) { return adoptCorner(corner); };
  }
  return f;
}

void FeatureTracker::detect(const cv::Mat& img) {
  const int cols = params_.grid_cols, rows = params_.grid_rows;
  const int cells = cols * rows;
  const int quota = (params_.max_tracks + cells - 1) / cells;
  auto cellOf = [&](const cv::Point2f& p) {
    const int c = std::clamp(static_cast<int>(p.x * cols / img.cols), 0, cols - 1);
    const int r = std::clamp(static_cast<int>(p.y * rows / img.rows), 0, rows - 1);
    return r * cols + c;
  };
  std::vector<int> count(static_cast<size_t>(cells), 0);
  cv::Mat mask(img.size(), CV_8UC1, cv::Scalar(0));
  const int b = params_.border_px;
  mask(cv::Rect(b, b, img.cols - 2 * b, img.rows - 2 * b)).setTo(255);
  const int radius = static_cast<int>(params_.min_distance_px);
  for (const auto& t : tracks_) {
    ++count[static_cast<size_t>(cellOf(t.uv))];
    cv::circle(mask, t.uv, radius, cv::Scalar(0), -1);
  }
  // Candidates come only from the cells below their quota, each searched in its own region of
  // interest (in steady tracking most cells are full, so this costs a fraction of a whole-image
  // search). They are then taken strongest first over all those cells, as from one search of
  // the free area: a corner must reach quality_level times the best response found, and only
  // the strongest few (4 per wanted track) are considered, so weakly textured cells do not get
  // corners that track poorly.
  const int want = params_.max_tracks - static_cast<int>(tracks_.size());
  const int max_candidates = std::max(want * 4, 64);
  struct Candidate {
    cv::Point2f p;
    float response;
  };
  std::vector<Candidate> cand;
  for (int c = 0; c < cells; ++c) {
    if (count[static_cast<size_t>(c)] >= quota) continue;
    const int x0 = (c % cols) * img.cols / cols, x1 = (c % cols + 1) * img.cols / cols;
    const int y0 = (c / cols) * img.rows / rows, y1 = (c / cols + 1) * img.rows / rows;
    const cv::Rect roi(x0, y0, x1 - x0, y1 - y0);
    const cv::Point2f offset(static_cast<float>(x0), static_cast<float>(y0));
    if (params_.detector == TrackerParams::Detector::kShiTomasi) {
      if (cv::countNonZero(mask(roi)) == 0) continue;
      std::vector<cv::Point2f> pts;
      std::vector<float> quality;
      // The quality floor is applied below against the best of all cells. Asking each cell for
      // quality_level of its own best already drops only corners below that floor (a cell's best
      // is at most the overall best), so the result is the same as with a lower per-cell level,
      // but far fewer weak local maxima are collected and sorted.
      cv::goodFeaturesToTrack(img(roi), pts, max_candidates, params_.quality_level, params_.min_distance_px, mask(roi),
                              quality, 3);
      for (size_t i = 0; i < pts.size(); ++i) cand.push_back({pts[i] + offset, quality[i]});
    } else {
      std::vector<cv::KeyPoint> kps;
      cv::FAST(img(roi), kps, params_.fast_threshold, true);
      for (const auto& k : kps) cand.push_back({k.pt + offset, k.response});
    }
  }
  std::sort(cand.begin(), cand.end(), [](const Candidate& a, const Candidate& b) { return a.response > b.response; });
  if (params_.detector == TrackerParams::Detector::kShiTomasi && !cand.empty()) {
    const float floor = static_cast<float>(params_.quality_level) * cand.front().response;
    while (!cand.empty() && cand.back().response < floor) cand.pop_back();
  }
  // Fill the cells up to their quota, strongest candidates first, min_distance_px apart.
  int added = 0, considered = 0;
  for (const auto& k : cand) {
    if (added >= want || considered >= max_candidates) break;
    if (mask.at<uchar>(cv::Point(k.p)) == 0) continue;
    ++considered;
    const size_t c = static_cast<size_t>(cellOf(k.p));
    if (count[c] >= quota || !aboveNoise(k.p)) continue;
    ++count[c];
    cv::circle(mask, k.p, radius, cv::Scalar(0), -1);
    tracks_.push_back({next_id_++, k.p, 1, {k.p}, std::nullopt, std::nullopt});
    ++added;
  }
  stats_.detected = added;
  if (params_.descriptors && added > 0) {
    std::vector<cv::Point2f> pts;
    for (size_t i = tracks_.size() - static_cast<size_t>(added); i < tracks_.size(); ++i) pts.push_back(tracks_[i].uv);
    const auto desc = describeOrb(*orb_, img, pts);
    for (size_t i = 0; i < pts.size(); ++i) {
      Track& t = tracks_[tracks_.size() - pts.size() + i];
      t.descriptor = t.latest_descriptor = desc[i];
    }
  }
}

cv::Mat FeatureTracker::drawTracks(const cv::Mat& mono8) const {
  cv::Mat out;
  cv::cvtColor(mono8, out, cv::COLOR_GRAY2BGR);
  for (const auto& t : tracks_) {
    const cv::Scalar col = t.age > 5 ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 200, 255);
    for (size_t i = 1; i < t.history.size(); ++i) cv::line(out, t.history[i - 1], t.history[i], col, 1, cv::LINE_AA);
    cv::circle(out, t.uv, 3, col, 1, cv::LINE_AA);
    cv::putText(out, std::to_string(t.id), t.uv + cv::Point2f(4, -4), cv::FONT_HERSHEY_PLAIN, 0.7, col, 1);
  }
  return out;
}

}  // namespace vi_ekf_slam
