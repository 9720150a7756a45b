// ORB descriptors at given points, computed in windows around them. cv::ORB pads and blurs the
// whole image it is handed, whatever the number of points: for the few points of an image (new
// tracks, the corners of a revisit search) that blur was most of the cost. A window of ORB's
// edge threshold plus the blur's reach around a point gives the descriptor the whole image gives
// (the sampling pattern and the blur stay inside it; a point too near the image's border is
// dropped as it would be), so many points are described on the whole image, few in windows.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <optional>
#include <vector>

#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

/// The ORB descriptor at each point of a mono8 image (keypoint size 31 px, angle -1: the
/// tracker's convention), none for a point too near the border to describe.
std::vector<std::optional<Descriptor>> describeOrb(cv::ORB& orb, const cv::Mat& img,
                                                   const std::vector<cv::Point2f>& pts);

}  // namespace vi_ekf_slam
