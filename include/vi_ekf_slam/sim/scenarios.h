// Ready-made simulation scenarios and the paper's sensor setup.
#pragma once

#include <cstdint>

#include "vi_ekf_slam/sim/hallway.h"
#include "vi_ekf_slam/sim/sim_runner.h"

namespace vi_ekf_slam::sim {

/// The paper's camera at half resolution (699 x 540 px, ~80 deg horizontal field of view) with
/// mild radial-tangential distortion.
CameraModel paperCamera();

/// A forward-looking camera on a torso-worn rig whose body frame is x forward, y right, z down:
/// camera z = body x, camera x = body y, camera y = body z; 8 cm ahead, 5 cm above the IMU.
CameraExtrinsics torsoCameraExtrinsics();

/// The paper's rig noise: accelerometer 7.5 mg RMS at 200 Hz (density 7.5 mg / sqrt(200 Hz)),
/// gyro angle random walk 0.0056 deg/s/sqrt(s); bias random walks of a MEMS unit.
ImuNoiseParams paperImuNoise();

/// A short walk on a circle inside a cylindrical room, for quick tests and the first demo.
Scenario circleScenario(double duration_s, bool noise, std::uint64_t world_seed);

/// A few landmarks (25) on and near a wall 5-8 m ahead, always in view, watched by a rig that
/// moves a few decimetres on every axis: the setting in which a noise-free filter must converge.
Scenario wallScenario(double duration_s, bool noise, std::uint64_t world_seed);

/// The paper's simulation: the built-in hallway walk with landmarks on walls, floor and ceiling
/// (`density_per_m2`), the paper's camera at 28 Hz and IMU at 200 Hz.
Scenario hallwayScenario(const HallwayParams& params, double density_per_m2, std::uint64_t world_seed);

/// A TUM pose file driven as a C2 motion, with landmarks scattered 1-10 m around the path
/// (`per_metre` of path) and a camera looking along the mean direction of travel in the body
/// frame (the files use different body conventions).
Scenario tumScenario(const std::string& path, double per_metre, std::uint64_t world_seed);

/// Camera extrinsic looking along the mean body-frame direction of travel, image "down" along
/// the mean body-frame gravity direction.
CameraExtrinsics forwardLookingExtrinsics(const Trajectory& trajectory);

}  // namespace vi_ekf_slam::sim
