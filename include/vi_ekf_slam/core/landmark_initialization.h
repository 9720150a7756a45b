// Landmark initialization.
// Fixed depth (the paper, Sec. IV-A): a new Cartesian landmark at a fixed depth along the ray of
//   its first observation, with a large variance along the ray and the pixel noise across it,
//   and its full cross-covariance to the state through the initialization Jacobians
//   (first-order propagation of pose, pixel and depth uncertainty).
// Inverse depth (beyond the paper, after Civera, Davison, Montiel 2008): the same ray as an
//   anchored inverse-depth landmark (landmark.h) whose inverse depth rho has a Gaussian prior
//   wide enough to cover every depth from about a metre to infinity. The measurement model is
//   close to linear in rho, so the depth is learned without the linearization errors that make
//   the fixed-depth filter inconsistent.
#pragma once

#include <vector>

#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct FixedDepthParams {
  double depth_m = 8.0;         ///< depth (camera z) of a new landmark [m]
  double depth_sigma_m = 4.0;   ///< std-dev of that depth [m]
  double pixel_noise_px = 1.0;  ///< std-dev of the observed pixel [px]
};

/// Landmark position and its Jacobians w.r.t. body position/orientation error, the camera-IMU
/// extrinsic's errors (used when the state estimates it), pixel, depth.
struct InitializedLandmark {
  Vec3 p_s_l;
  Mat3 G_p;
  Mat3 G_psi;
  Mat3 G_pbc = Mat3::Zero();  ///< w.r.t. the camera's position error in {b}
  Mat3 G_thc = Mat3::Zero();  ///< w.r.t. the camera's rotation error (R_b_c = Exp(theta) R_b_c)
  Eigen::Matrix<double, 3, 2> G_uv;
  Vec3 G_depth;
};

/// Back-projects pixel uv to depth `depth` (camera z) in the strapdown frame.
bool backProject(const MotionState& x, const Eigen::Vector2d& uv, double depth, const CameraModel& camera,
                 const CameraExtrinsics& T_b_c, InitializedLandmark* out);

/// Adds the landmark with its covariance and cross-covariance to the state.
void appendInitializedLandmark(FilterState& state, std::int64_t id, const InitializedLandmark& l, double pixel_var,
                               double depth_var);

/// Paper's rule: fixed depth along the ray. False if the pixel cannot be undistorted.
bool initializeLandmarkFixedDepth(FilterState& state, const FeatureObservation& obs, const CameraModel& camera,
                                  const CameraExtrinsics& T_b_c, const FixedDepthParams& params);

struct InverseDepthParams {
  double initial_depth_m = 5.0;      ///< prior mean of the depth, 1 / rho0 [m]
  double inverse_depth_sigma = 0.5;  ///< prior std-dev of rho [1/m]
  double pixel_noise_px = 1.0;       ///< std-dev of the observed pixel [px]
};

/// Anchored inverse depth; the anchor is the estimated camera frame. False if the pixel cannot
/// be undistorted.
bool initializeLandmarkInverseDepth(FilterState& state, const FeatureObservation& obs, const CameraModel& camera,
                                    const CameraExtrinsics& T_b_c, const InverseDepthParams& params);

/// Anchored inverse-depth landmarks whose inverse depths an initializer estimated together with
/// the state: obs[i] at depth_m[i] (camera z), the errors of their inverse depths with covariance
/// Q (one row per observation) [1/m^2] and cross-covariance C (one row per observation, dim()
/// columns) with the current state. Each also carries its ray's pose and pixel errors, as
/// initializeLandmarkInverseDepth's (the same result for a diagonal Q and C = 0). Returns the
/// indices of the observations that entered (in order); the others' pixel cannot be undistorted.
std::vector<int> initializeLandmarksInverseDepthJointly(FilterState& state, const std::vector<FeatureObservation>& obs,
                                                        const std::vector<double>& depth_m, const Eigen::MatrixXd& Q,
                                                        const Eigen::MatrixXd& C, const CameraModel& camera,
                                                        const CameraExtrinsics& T_b_c, double pixel_noise_px);

/// 1 / z of landmark i, z its depth along the current camera's axis [1/m], and J = d(1 / z)/d(error
/// state) (1 x dim()).
double inverseDepthInCamera(const FilterState& state, int i, const CameraExtrinsics& T_b_c,
                            Eigen::RowVectorXd* J = nullptr);

/// New anchored inverse-depth landmarks at the map's depth: each one's inverse depth is landmark
/// ref's 1 / z (inverseDepthInCamera) plus an error of its own, inverse_depth_sigma [1/m],
/// independent of the others'. A prior centred on the estimated map moves with the map's scale;
/// taken as independent of the map, every such point would tell the filter that scale once more,
/// and a walk whose scale the motion hardly observes (a crawl) would converge on the map's error.
/// Returns the indices of the observations that entered, as initializeLandmarksInverseDepthJointly.
std::vector<int> initializeLandmarksAtMapDepth(FilterState& state, const std::vector<FeatureObservation>& obs, int ref,
                                               double inverse_depth_sigma, const CameraModel& camera,
                                               const CameraExtrinsics& T_b_c, double pixel_noise_px);

}  // namespace vi_ekf_slam
