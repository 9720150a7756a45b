#include "vi_ekf_slam/core/image_noise.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace vi_ekf_slam {

double imageNoiseSigma(const cv::Mat& mono8) {
  CV_Assert(mono8.type() == CV_8UC1);
  if (mono8.rows < 3 || mono8.cols < 3) return kImageNoiseFloor;
  const cv::Mat mask = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::Mat lap;
  cv::filter2D(mono8, lap, CV_16S, mask, cv::Point(-1, -1), 0.0, cv::BORDER_REPLICATE);
  // |L| <= 16 * 255: a histogram gives the median without sorting the pixels.
  constexpr int kMax = 16 * 255;
  std::vector<int> hist(kMax + 1, 0);
  for (int r = 1; r + 1 < lap.rows; ++r) {
    const auto* row = lap.ptr<std::int16_t>(r);
    for (int c = 1; c + 1 < lap.cols; ++c) ++hist[static_cast<size_t>(std::abs(row[c]))];
  }
  const long half = static_cast<long>(lap.rows - 2) * (lap.cols - 2) / 2;
  long seen = 0;
  int median = 0;
  for (; median <= kMax; ++median) {
    seen += hist[static_cast<size_t>(median)];
    if (seen > half) break;
  }
  // The median of |N(0, s^2)| is 0.6745 s, and the mask's output has s = 6 sigma.
  return std::max(kImageNoiseFloor, median / (0.6745 * 6.0));
}

CornerSignal::CornerSignal(const cv::Mat& mono8) : sigma_(imageNoiseSigma(mono8)), level_sigma_(sigma_ * 70.0 / 256.0) {
  cv::Mat f;
  mono8.convertTo(f, CV_32F);
  cv::pyrDown(f, level_);
}

double CornerSignal::snr(const cv::Point2f& p, int window_px) const {
  const int half = window_px / 2;
  // Pixel centres: u1 = (u0 + 0.5) / 2 - 0.5.
  const int cx = static_cast<int>(std::lround((p.x + 0.5) / 2.0 - 0.5));
  const int cy = static_cast<int>(std::lround((p.y + 0.5) / 2.0 - 0.5));
  // The window, cut to the level (central differences need one pixel beyond it on each side).
  const int r0 = std::max(1, cy - half), r1 = std::min(level_.rows - 2, cy + half);
  const int c0 = std::max(1, cx - half), c1 = std::min(level_.cols - 2, cx + half);
  if (r1 < r0 || c1 < c0) return 0.0;
  double xx = 0.0, yy = 0.0, xy = 0.0;
  for (int r = r0; r <= r1; ++r) {
    const float* up = level_.ptr<float>(r - 1);
    const float* row = level_.ptr<float>(r);
    const float* down = level_.ptr<float>(r + 1);
    for (int c = c0; c <= c1; ++c) {
      const double gx = 0.5 * (row[c + 1] - row[c - 1]), gy = 0.5 * (down[c] - up[c]);
      xx += gx * gx;
      yy += gy * gy;
      xy += gx * gy;
    }
  }
  const double lambda_min = 0.5 * (xx + yy) - std::sqrt(0.25 * (xx - yy) * (xx - yy) + xy * xy);
  const double n = static_cast<double>((r1 - r0 + 1) * (c1 - c0 + 1));
  return lambda_min / (n * level_sigma_ * level_sigma_ / 2.0);
}

}  // namespace vi_ekf_slam
