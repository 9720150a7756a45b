// Error-state layout (paper eq. 10 and the sensor-centric extension of eq. 20). Index constants
// are used everywhere instead of magic numbers.
#pragma once

#include <optional>
#include <string>

namespace vi_ekf_slam {

/// How the strapdown equations are formulated (paper Sec. III-E/F/H).
enum class Mechanization {
  kWorldCentric,              ///< strapdown frame {s} == navigation frame {n}
  kSensorCentric,             ///< {s} = body frame at start; p_n_s, q_n_s estimated
  kSensorCentricComposition,  ///< as above, {s} reset to the body frame by the composition step
};

/// Does this mechanization carry p_n_s, q_n_s in the state?
inline bool isSensorCentric(Mechanization m) { return m != Mechanization::kWorldCentric; }

std::string toString(Mechanization m);
std::optional<Mechanization> mechanizationFromString(const std::string& s);

namespace idx {
// Error-state block offsets. In the world-centric filter {s} == {n}.
constexpr int kP = 0;    ///< position of {b} in {s}
constexpr int kV = 3;    ///< velocity of {b} in {s}
constexpr int kBa = 6;   ///< accelerometer bias
constexpr int kPsi = 9;  ///< orientation error psi_s_b (global, in {s})
constexpr int kBg = 12;  ///< gyroscope bias
/// Camera-IMU time offset t_d (t_imu = t_image + t_d) [s], estimated online like OpenVINS's
/// calib_dt; a zero initial sigma keeps it fixed (its row and column of P stay zero).
constexpr int kTd = 15;
constexpr int kPns = 16;    ///< position of {s} in {n} (sensor-centric only)
constexpr int kPsiNs = 19;  ///< orientation error psi_n_s (sensor-centric only)
constexpr int kWorldCentricDim = 16;
constexpr int kSensorCentricDim = 22;
/// Camera-IMU extrinsic (online calibration, off by default, like OpenVINS's calib_cam_extrinsics):
/// [dp_b_c, dtheta_b_c] after the mechanization's blocks, at extrinsicIndex(). dp_b_c is the
/// camera position error in {b} [m]; dtheta_b_c the rotation error, R_b_c = Exp(dtheta) R_b_c_est.
constexpr int kExtrinsicDim = 6;
constexpr int kMaxMotionDim = kSensorCentricDim + kExtrinsicDim;
/// The navigation output's covariance layout [p, v, b_a, psi, b_g] (NavState::cov).
constexpr int kNavDim = 15;
constexpr int kLandmarkDim = 3;
}  // namespace idx

/// Where the extrinsic's error state starts (when it is estimated): after the mechanization's blocks.
inline int extrinsicIndex(Mechanization m) {
  return isSensorCentric(m) ? idx::kSensorCentricDim : idx::kWorldCentricDim;
}
/// Error-state dimension of the motion part s' for a mechanization (with the extrinsic, if it is
/// estimated).
inline int motionDim(Mechanization m, bool extrinsic = false) {
  return extrinsicIndex(m) + (extrinsic ? idx::kExtrinsicDim : 0);
}

}  // namespace vi_ekf_slam
