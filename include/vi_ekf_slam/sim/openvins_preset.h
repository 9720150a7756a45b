// The setup of OpenVINS's simulator defaults (rpng/open_vins, config rpng_sim, monocular), so our
// study numbers can be set beside theirs: IMU 400 Hz, camera 10 Hz, 752x480 with the
// EuRoC cam0 intrinsics, radial-tangential distortion and camera-IMU transform, 1 px noise, their
// IMU noise densities, map points generated 5-7 m in front of the camera, and a start from the
// true state (no drawn error, zero initial biases) with 1 deg, 5 cm, 1 cm/s initial sigmas.
#pragma once

#include <cstdint>
#include <string>

#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/sim/sim_runner.h"

namespace vi_ekf_slam::sim {

/// Points seen from the camera along the trajectory: every `spacing_s`, `per_view` random pixels
/// back-projected to a depth uniform in [min_depth_m, max_depth_m] (as OpenVINS's simulator
/// creates map points where the camera looks).
LandmarkWorld landmarksInView(const Trajectory& trajectory, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                              double min_depth_m, double max_depth_m, int per_view, double spacing_s,
                              std::mt19937_64& rng);

/// The TUM trajectory in OpenVINS's simulator setup.
Scenario openvinsSimScenario(const std::string& tum_path, std::uint64_t world_seed);

/// The filter's initial sigmas of that setup (1 deg, 5 cm, 1 cm/s).
InitialUncertainty openvinsSimInitialUncertainty();

}  // namespace vi_ekf_slam::sim
