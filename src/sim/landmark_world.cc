#include "vi_ekf_slam/sim/landmark_world.h"

#include <cmath>

namespace vi_ekf_slam::sim {

LandmarkWorld cylinderWorld(const Vec3& center, double radius_m, double z_min, double z_max, int count,
                            std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI), height(z_min, z_max);
  LandmarkWorld w;
  for (int i = 0; i < count; ++i) {
    const double a = angle(rng);
    w.push_back({i, center + Vec3(radius_m * std::cos(a), radius_m * std::sin(a), height(rng))});
  }
  return w;
}

}  // namespace vi_ekf_slam::sim
