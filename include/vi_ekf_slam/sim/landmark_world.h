// The simulated world: point landmarks with ids, in {n}.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam::sim {

struct WorldLandmark {
  std::int64_t id = 0;
  Vec3 p_n = Vec3::Zero();
};

using LandmarkWorld = std::vector<WorldLandmark>;

/// Points on a vertical cylinder around (center_x, center_y), z in [z_min, z_max] ({n}, z down).
LandmarkWorld cylinderWorld(const Vec3& center, double radius_m, double z_min, double z_max, int count,
                            std::mt19937_64& rng);

}  // namespace vi_ekf_slam::sim
