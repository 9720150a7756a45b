// Real IMU, simulated camera: a recorded IMU stream (ASL imu0/data.csv) replaces the
// synthesized one, the ground truth of the same recording (ASL state_groundtruth_estimate0 csv
// or a TUM file in the same time base) gives the motion, and the camera observations are
// simulated from the ground-truth poses. So the filter meets the real IMU's noise, biases,
// vibration and timing, while data association and landmark truth stay exact.
#pragma once

#include <cstdint>
#include <string>

#include "vi_ekf_slam/sim/sim_runner.h"

namespace vi_ekf_slam::sim {

/// Builds the scenario: the IMU samples inside the ground truth's time span, the true biases
/// interpolated from the ground truth (NaN when the file has none, e.g. a TUM file), IMU noise
/// densities from imu0/sensor.yaml beside the csv (the paper's rig otherwise), the camera from
/// cam0/sensor.yaml of the same recording (intrinsics, distortion, T_BS, rate; the paper's
/// camera looking along the direction of travel otherwise), and landmarks scattered 1-10 m
/// around the path (`per_metre`). Throws std::runtime_error with the file name for unreadable
/// files and for an IMU stream that does not overlap the ground truth.
Scenario recordedImuScenario(const std::string& trajectory_path, const std::string& imu_csv, double per_metre,
                             std::uint64_t world_seed);

}  // namespace vi_ekf_slam::sim
