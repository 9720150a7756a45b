#include "vi_ekf_slam/core/map_reuse/descriptor_matching.h"

#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>

namespace vi_ekf_slam {

cv::Mat descriptorRows(const std::vector<Descriptor>& d) {
  cv::Mat m(static_cast<int>(d.size()), static_cast<int>(Descriptor().size()), CV_8U);
  for (size_t i = 0; i < d.size(); ++i) std::copy(d[i].begin(), d[i].end(), m.ptr<std::uint8_t>(static_cast<int>(i)));
  return m;
}

std::vector<NearestTwo> nearestTwo(const cv::Mat& query, const cv::Mat& train, const cv::Mat& mask) {
  std::vector<NearestTwo> out(static_cast<size_t>(query.rows));
  if (query.empty() || train.empty()) return out;
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_HAMMING).knnMatch(query, train, knn, 2, mask);
  for (const auto& k : knn) {
    if (k.empty()) continue;  // (a row the mask allows nothing in)
    NearestTwo& n = out[static_cast<size_t>(k[0].queryIdx)];
    n.index = k[0].trainIdx;
    n.distance = static_cast<int>(std::lround(k[0].distance));
    if (k.size() > 1) n.second = static_cast<int>(std::lround(k[1].distance));
  }
  return out;
}

}  // namespace vi_ekf_slam
