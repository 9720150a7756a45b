// Ready-made simulation scenarios and the paper's sensor setup.
#pragma once

#include <cstdint>

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

}  // namespace vi_ekf_slam::sim
