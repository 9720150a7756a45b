// Feeds recorded IMU + feature tracks (e.g. the EqVIO CSV of EuRoC V1_01) through the core
// pipeline (VioPipeline, as the node does), without image processing: a start at rest, then IMU
// samples and feature frames in the order of their stamps. Evaluated against ground truth with the single-run metrics.
#pragma once

#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/navigation_output.h"
#include "vi_ekf_slam/core/static_initializer.h"
#include "vi_ekf_slam/io/datasets.h"
#include "vi_ekf_slam/eval/run_evaluation.h"

namespace vi_ekf_slam::eval {

/// The estimated body pose and its covariance in the z-up world frame (from {n}).
EstimatedPose worldPoseFromNav(const NavState& nav);

struct FeatureReplayResult {
  RunMetrics metrics;
  std::vector<EstimatedPose> trajectory;
  int frames_processed = 0;
  int rejected_observations = 0;
  double init_time = 0.0;  ///< when the static initialization finished [s]
};

/// The filter settings for the EqVIO tracks of EuRoC V1_01 (the default configuration otherwise):
/// the VI-sensor's densities inflated for the MAV's vibration, EqVIO's ~2 px feature noise, the
/// zero-velocity noise of a MAV standing on the ground, lost tracks dropped at once, and a start
/// that defines the estimate's frame (no position or yaw uncertainty).
EkfSlamConfig eurocFeatureReplayConfig();

/// Throws std::runtime_error if the data never shows a static interval.
FeatureReplayResult replayFeatures(const io::FeatureTrackData& data, const std::vector<io::StampedPose>& truth,
                                   const EkfSlamConfig& config, const StaticInitParams& static_init);

}  // namespace vi_ekf_slam::eval
