// Appearance matching for map reuse, within a run (revisit_matching.h) and across runs
// (relocalization.h): the Hamming distances of 256-bit ORB descriptors by OpenCV's brute-force
// matcher, as the nearest two of each query among the train descriptors it may match.
#pragma once

#include <limits>
#include <opencv2/core.hpp>
#include <vector>

#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct NearestTwo {
  static constexpr int kNone = std::numeric_limits<int>::max();
  int index = -1;        ///< of the nearest train descriptor (-1: none it may match)
  int distance = kNone;  ///< its Hamming distance [bits]
  int second = kNone;    ///< the second nearest's [bits] (kNone: there is one)
  /// The nearest is clearly nearer than the second (Lowe's ratio test), or alone.
  bool passesRatio(double ratio) const { return second == kNone || distance < ratio * second; }
};

/// One row of 32 bytes per descriptor (CV_8U), as cv::ORB writes them.
cv::Mat descriptorRows(const std::vector<Descriptor>& d);

/// The nearest two train descriptors of each query (cv::BFMatcher, NORM_HAMMING; of equal
/// distances the first in train order). mask: CV_8U, query rows x train columns, nonzero where the
/// pair may match (empty: every pair).
std::vector<NearestTwo> nearestTwo(const cv::Mat& query, const cv::Mat& train, const cv::Mat& mask = cv::Mat());

}  // namespace vi_ekf_slam
