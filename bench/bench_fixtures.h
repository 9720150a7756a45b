// Shared set-up for the benchmarks: a filter state with N landmarks in front of the camera, built
// through the filter's own initialization (so the covariance is a real, positive-definite one),
// and the observations of an image.
#pragma once

#include <random>
#include <vector>

#include "vi_ekf_slam/core/ekf_update.h"
#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/landmark_initialization.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam::bench {

struct MapFixture {
  FilterState state;
  CameraModel camera = sim::paperCamera();
  CameraExtrinsics T_b_c = sim::torsoCameraExtrinsics();
  std::vector<FeatureObservation> observations;  ///< 30 observations of landmarks in the map

  MapFixture(Mechanization m, int num_landmarks, int num_observations = 30) : state(m) {
    Eigen::MatrixXd P = Eigen::MatrixXd::Identity(state.motionDim(), state.motionDim()) * 1e-4;
    state.setCovariance(P);
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> u(40.0, 650.0), v(40.0, 500.0), depth(2.0, 12.0);
    InverseDepthParams ip;
    std::vector<Vec3> positions;
    for (int i = 0; i < num_landmarks; ++i) {
      const FeatureObservation obs{i, Eigen::Vector2d(u(rng), v(rng))};
      initializeLandmarkInverseDepth(state, obs, camera, T_b_c, ip);
    }
    // Observations: the predicted pixels of the first landmarks, moved by ~1 px.
    std::normal_distribution<double> px(0.0, 1.0);
    for (int i = 0; i < std::min(num_observations, num_landmarks); ++i) {
      Eigen::Vector2d uv;
      if (!predictObservation(state.x, state.landmark(i), camera, T_b_c, &uv)) continue;
      observations.push_back({state.landmarkIds()[static_cast<size_t>(i)], uv + Eigen::Vector2d(px(rng), px(rng))});
    }
  }
};

}  // namespace vi_ekf_slam::bench
