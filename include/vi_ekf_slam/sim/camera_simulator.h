// Simulated feature observations: projections of the visible landmarks with Gaussian pixel
// noise; ids are kept, so the estimator gets data association from the simulator.
#pragma once

#include <random>

#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/types.h"
#include "vi_ekf_slam/sim/landmark_world.h"
#include "vi_ekf_slam/sim/trajectory.h"

namespace vi_ekf_slam::sim {

struct CameraSimParams {
  double rate_hz = 28.0;
  double pixel_noise_px = 1.0;
  double max_range_m = 20.0;
  double min_depth_m = 0.3;
  double border_px = 2.0;
  int max_features = 1000;  ///< keep at most this many (nearest first)
};

/// Observations of `world` from the body pose at sample.
CameraFrame observe(const TrajectorySample& sample, const LandmarkWorld& world, const CameraModel& camera,
                    const CameraExtrinsics& T_b_c, const CameraSimParams& params, std::mt19937_64* rng);

}  // namespace vi_ekf_slam::sim
