// EKF measurement update on the stacked observations of one image (paper Sec. III-G), with
// per-landmark chi-square gating and a Joseph-stable covariance update.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct UpdateParams {
  double pixel_noise_px = 1.0;     ///< std-dev of a feature position [px]
  double gate_probability = 0.95;  ///< chi^2 gate on each landmark's 2-dof innovation (0..1)
  /// The wider gate (0..1; below gate_probability: gate_probability always) once the tracks have
  /// shown no outlier over clean_gate_s seconds of moving images (OutlierWatch); an observation
  /// beyond its chi^2 quantile counts as an outlier (UpdateResult::outliers), whatever gate was used.
  double clean_gate_probability = 0.9999;
  double clean_gate_s = 1.0;  ///< [s] (see clean_gate_probability)
  /// The clean gate as used: at least gate_probability. An observation beyond its chi^2 quantile is
  /// an outlier.
  double outlierProbability() const { return std::max(gate_probability, clean_gate_probability); }
  /// Linearizations per update [count]: 1 is the EKF, more the iterated EKF (the gate uses the
  /// first); the iterations stop early once the correction no longer changes.
  int iterations = 1;
  /// Rolling shutter: time from the first to the last image row [s] (0: global shutter). A
  /// feature in row v is seen readout_time_s * (v / height - 1/2) after the image's middle row,
  /// the time the state is at; its prediction moves by its image velocity over that interval.
  double readout_time_s = 0.0;
};

struct UpdateResult {
  int accepted = 0;
  std::vector<std::int64_t> rejected_ids;  ///< failed the chi^2 gate
  std::vector<std::int64_t> invalid_ids;   ///< unknown id, behind the camera, or non-finite
  double nis_sum = 0.0;                    ///< sum of accepted normalized innovations squared
  int outliers = 0;  ///< observations beyond the clean gate's chi^2 quantile (rejected whatever the gate)
};

/// Updates state and covariance with observations of landmarks that are in the map. omega_b is
/// the body's angular rate [rad/s] (bias-corrected gyro): with the velocity in the state it gives
/// each observation's Jacobian w.r.t. the camera-IMU time offset (predictImageVelocity).
UpdateResult ekfUpdate(FilterState& state, const std::vector<FeatureObservation>& observations,
                       const CameraModel& camera, const CameraExtrinsics& T_b_c, const UpdateParams& params,
                       const Vec3& omega_b = Vec3::Zero());

/// Where landmark `landmark_index` (map position) should appear in the image and how uncertain
/// that is: the predicted pixel and the innovation covariance H P H^T + R [px^2] an observation of
/// it would have (the search region for a landmark whose track ended, map_reuse/revisit_matching.h). Nothing if
/// it cannot be predicted (behind the camera, outside the image).
struct PredictedPixel {
  Eigen::Vector2d uv;
  Eigen::Matrix2d S;
};
/// The stacked innovation of observations of landmarks in the map (what the update would see):
/// its NIS r^T S^-1 r with the joint S (cross-covariances included), and each observation's own
/// NIS. valid is false if one cannot be predicted.
struct JointInnovation {
  bool valid = false;
  double nis = 0.0;
  std::vector<double> each;
};
JointInnovation jointInnovation(const FilterState& state, const std::vector<FeatureObservation>& observations,
                                const CameraModel& camera, const CameraExtrinsics& T_b_c, const UpdateParams& params,
                                const Vec3& omega_b = Vec3::Zero());

std::optional<PredictedPixel> predictWithCovariance(const FilterState& state, int landmark_index,
                                                    const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                                    const UpdateParams& params, const Vec3& omega_b = Vec3::Zero());

}  // namespace vi_ekf_slam
