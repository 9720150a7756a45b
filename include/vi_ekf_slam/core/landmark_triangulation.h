// A new landmark from two views of its track, at the depth their baseline gives.
//
// A point that enters at a prior depth (landmark_initialization.h) is the filter's main source of
// inconsistency where the parallax is small at first (a slow start, stairs): its first updates and
// compositions are linearized at a depth that may be off by a factor of five, and the products of
// the depth error and the motion error they drop make the velocity over-confident. With the
// camera's position at the track's first view kept in the state as a clone (a Cartesian point
// that every frame change carries exactly), the point can wait until the two rays meet at a
// well-defined depth and then enter with that depth, its covariance and its cross-covariance with
// the state (the clone's included), to first order; the baseline's error, and so the velocity's,
// is in them. The clone's orientation is not a state: its error relative to the current camera is
// a variance accumulated from the relative rotations it was carried through (DelayedLandmarks).
// OpenVINS initializes its SLAM features from its clones in the same way.
#pragma once

#include <cstdint>

#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

/// The camera at an earlier image: its position is the Cartesian point `id` in the state.
struct CameraClone {
  std::int64_t id = 0;
  double t = 0.0;                 ///< when it was taken (state time) [s]
  Mat3 R_s_c = Mat3::Identity();  ///< its orientation as estimated, in the current {s}
  /// The extrinsic's rotation R_s_c was taken with: the clone's body is fixed, its camera turns
  /// with the extrinsic's estimate (triangulateLandmark uses R_s_c R_b_c^T times the current one).
  Mat3 R_b_c = Mat3::Identity();
  Mat3 rotation_cov = Mat3::Zero();  ///< variance of R_s_c relative to the current body [rad^2] (global, in {s})
};

/// Appends the camera's current position (p_s_b + R_s_b p_b_c) as the Cartesian point `id` with
/// its covariance and cross-covariance, and returns the clone (orientation as estimated now).
CameraClone appendCameraClone(FilterState& state, std::int64_t id, const CameraExtrinsics& T_b_c);

struct TriangulatedLandmark {
  Landmark landmark;  ///< inverse depth, anchored at the current camera: l = (u, v, rho) of the current view
  /// d(l)/d(p_s_b, psi_s_b, clone position) and d(l)/d(pixel now, pixel at the clone, clone rotation)
  Eigen::Matrix<double, 3, 9> J_state;
  Eigen::Matrix<double, 3, 7> J_noise;
  /// d(l)/d(the extrinsic's errors [p_b_c, theta_b_c]), when the state estimates it (else zero).
  Eigen::Matrix<double, 3, 6> J_ext = Eigen::Matrix<double, 3, 6>::Zero();
  Mat3 P_ll = Mat3::Zero();  ///< covariance of l
  double depth_m = 0.0;      ///< along the current camera's z axis [m]
  /// The std-dev of rho from the state's uncertainty alone (the baseline from the clone to the
  /// camera, the camera's orientation), over rho: how well the baseline that makes the depth is
  /// itself known. About sigma(baseline) / baseline, whatever the pixel noise's draw.
  double baseline_relative_sigma = 0.0;
  /// The two rays' closest distance, squared, over its variance (chi^2 with 1 dof): a track whose
  /// two views do not meet is a mismatch.
  double ray_gap_nis = 0.0;
};

/// Triangulates the point seen at uv_now by the current camera and at uv_clone by the clone, and
/// its uncertainty (pixel_var [px^2] on both pixels). False if a pixel cannot be undistorted, the
/// rays are parallel, or the point is closer than min_depth_m [m] to either camera.
bool triangulateLandmark(const FilterState& state, const CameraClone& clone, const Eigen::Vector2d& uv_clone,
                         const Eigen::Vector2d& uv_now, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                         double pixel_var, double min_depth_m, TriangulatedLandmark* out);

/// Appends a triangulated landmark with its covariance and its cross-covariance with the state.
/// (The state may have lost other landmarks since the triangulation, not the clone.)
void appendTriangulatedLandmark(FilterState& state, std::int64_t id, const CameraClone& clone,
                                const TriangulatedLandmark& l);

}  // namespace vi_ekf_slam
