// IMU synthesis from a trajectory (paper eq. 5-6): specific force and angular rate in {b},
// plus white noise and bias random walks with the same densities the filter is told about.
#pragma once

#include <random>
#include <vector>

#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/types.h"
#include "vi_ekf_slam/sim/trajectory.h"

namespace vi_ekf_slam::sim {

struct ImuSimParams {
  double rate_hz = 200.0;
  ImuNoiseParams noise;                        ///< densities [SI / sqrt(Hz)]
  double initial_accel_bias_sigma_mps2 = 0.0;  ///< std-dev of the initial bias draw
  double initial_gyro_bias_sigma_radps = 0.0;
  bool noise_enabled = true;
  double gravity_mps2 = 9.81;
};

/// The samples with the true biases at each sample time (for evaluation).
struct ImuSequence {
  std::vector<ImuData> samples;
  std::vector<Vec3> true_accel_bias;
  std::vector<Vec3> true_gyro_bias;
};

ImuSequence simulateImu(const Trajectory& trajectory, const ImuSimParams& params, std::mt19937_64& rng);

}  // namespace vi_ekf_slam::sim
