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
  double pixel_noise_px = 1.0;  ///< std-dev of the Gaussian pixel noise [px]
  double max_range_m = 20.0;
  double min_depth_m = 0.3;
  double border_px = 2.0;
  int max_features = 40;  ///< tracks kept per image, like a tracker's target count
  int grid_cols = 4;      ///< new tracks are spread over a grid, like a tracker's detector
  int grid_rows = 3;
  /// Camera-IMU clock offset of the simulated rig [s]: a frame taken at true (IMU) time t is
  /// stamped t - time_offset_s, so t_imu = t_image + time_offset_s.
  double time_offset_s = 0.0;
};

/// Noise-free projections of every landmark of `world` visible from the body pose at `sample`
/// (in front of the camera, inside the image, within range).
std::vector<FeatureObservation> visibleLandmarks(const TrajectorySample& sample, const LandmarkWorld& world,
                                                 const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                                 const CameraSimParams& params);

/// A simulated front end: keeps following its tracks while they stay visible and starts new ones
/// in the emptiest grid cells up to max_features, then adds pixel noise. Deterministic for a
/// given trajectory and random generator.
class TrackingCamera {
 public:
  TrackingCamera(const LandmarkWorld& world, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                 const CameraSimParams& params);
  CameraFrame observe(const TrajectorySample& sample, std::mt19937_64* rng);

 private:
  const LandmarkWorld& world_;
  CameraModel camera_;
  CameraExtrinsics T_b_c_;
  CameraSimParams params_;
  std::vector<std::int64_t> tracked_;
};

}  // namespace vi_ekf_slam::sim
