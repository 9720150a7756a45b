// Finding a landmark again within a run (within_run_map.h): a new track that is the same point as
// a landmark whose track had ended is recognized by its appearance inside the region where the
// filter predicts the landmark, then observes it as any other track does. The search region is
// the landmark's predicted pixel with its innovation covariance (the uncertainty the filter
// already carries), so a repeated texture outside it cannot be taken, and a landmark with a
// look-alike anywhere in the image is not recognized by its appearance at all. The appearance is
// compared by descriptor_matching.h (OpenCV's matcher), as the kept map's relocalization does.
#pragma once

#include <cstdint>
#include <vector>

#include "vi_ekf_slam/core/map_reuse/map_reuse_params.h"
#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

int hammingDistance(const Descriptor& a, const Descriptor& b);

/// A landmark that may be seen again: its predicted pixel, the innovation covariance of that
/// prediction (pixel noise included) and its appearance.
struct RevisitCandidate {
  std::int64_t landmark_id = 0;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();     ///< [px]
  Eigen::Matrix2d S = Eigen::Matrix2d::Identity();  ///< [px^2]
  Descriptor descriptor{};
};

struct RevisitMatch {
  std::int64_t track_id = 0;
  std::int64_t landmark_id = 0;
  int distance = 0;  ///< [bits]
};

/// A pending match (revisit_confirm_frames) in a later image: its track's innovation against the
/// landmark's prediction `e` (covariance S) must pass the chi^2 gate of probability
/// gate_probability (the caller's: EkfSlam uses the wider of the update's and the search's), and its drift since the
/// image of the match, e - first_e, must stay within the search gate of two pixel noises: the true point keeps the
/// filter's error of the moment, a look-alike at another depth drifts off as the camera moves.
bool pendingRevisitAgrees(const Eigen::Vector2d& e, const Eigen::Matrix2d& S, const Eigen::Vector2d& first_e,
                          double gate_probability, double pixel_noise_px, const MapReuseParams& params);

/// The features (with descriptors) that are landmarks of `candidates` seen again: inside the
/// landmark's search region, within max_descriptor_distance, the mutual best, and passing the
/// ratio test on both sides: against the other landmarks whose region holds the feature, and
/// against the other features in the landmark's region or, with distinct_in_view, everything else
/// in the image (the other `features` and `elsewhere`, the image's other features with their
/// latest appearance): a landmark with a look-alike anywhere in view is not recognized by its
/// appearance.
/// Candidates wider than max_search_sigma_px are not searched.
std::vector<RevisitMatch> matchRevisits(const std::vector<RevisitCandidate>& candidates,
                                        const std::vector<FeatureObservation>& features, const MapReuseParams& params,
                                        const std::vector<FeatureObservation>& elsewhere = {});

}  // namespace vi_ekf_slam
