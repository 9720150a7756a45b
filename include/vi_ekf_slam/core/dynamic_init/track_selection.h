// The dynamic initializer's selection stage: which feature tracks of a window the alignment uses.
#pragma once

#include <cstdint>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {
namespace alignment {

struct Observation {
  int frame = 0;                                 ///< index in the window, oldest first
  Eigen::Vector2d xn = Eigen::Vector2d::Zero();  ///< normalized undistorted coordinates
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< pixel
};

struct Track {
  std::int64_t id = 0;
  std::vector<Observation> observations;  ///< in frame order
};

/// The tracks seen (finite, inside the camera model) in at least min_observations of the window's
/// frames, longest first (ties: smaller id first), at most max_tracks of them: a bounded problem
/// with the most parallax.
std::vector<Track> selectTracks(const std::vector<const CameraFrame*>& window, const CameraModel& camera,
                                int min_observations, size_t max_tracks);

}  // namespace alignment
}  // namespace vi_ekf_slam
