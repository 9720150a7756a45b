#include "vi_ekf_slam/core/filter_start.h"

#include <array>
#include <cmath>

#include "vi_ekf_slam/core/landmark_initialization.h"

namespace vi_ekf_slam {

FilterState emptyState(const EkfSlamConfig& config, const CameraExtrinsics& T_b_c, Mechanization m) {
  FilterState s(m, config.estimate_extrinsic);
  s.x.T_b_c = T_b_c;
  return s;
}

FilterState startingState(const EkfSlamConfig& config, const CameraExtrinsics& T_b_c, const NavState& init,
                          const InitialUncertainty& u, std::optional<double> time_offset_s) {
  using namespace idx;
  // Start world-centric: the initial pose uncertainty is the registration error in {n}.
  FilterState s = emptyState(config, T_b_c, Mechanization::kWorldCentric);  // (a restart forgets a refined extrinsic)
  s.timestamp = init.timestamp;
  s.x.p_s_b = init.p_n_b;
  s.x.v_s_b = init.v_n_b;
  s.x.q_s_b = init.q_n_b.normalized();
  s.x.b_a = init.b_a;
  s.x.b_g = init.b_g;
  s.x.t_d = time_offset_s.value_or(config.camera_time_offset_s);
  const int dim = s.motionDim();
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(dim, dim);
  P.block<3, 3>(kP, kP).diagonal().setConstant(u.position_m * u.position_m);
  P.block<3, 3>(kV, kV).diagonal().setConstant(u.velocity_mps * u.velocity_mps);
  P.block<3, 3>(kBa, kBa).diagonal().setConstant(u.accel_bias_mps2 * u.accel_bias_mps2);
  P.block<3, 3>(kPsi, kPsi).diagonal() << u.roll_pitch_rad * u.roll_pitch_rad, u.roll_pitch_rad * u.roll_pitch_rad,
      u.yaw_rad * u.yaw_rad;
  P.block<3, 3>(kBg, kBg).diagonal().setConstant(u.gyro_bias_radps * u.gyro_bias_radps);
  P(kTd, kTd) = u.time_offset_s * u.time_offset_s;
  if (s.estimatesExtrinsic()) {
    const int e = s.extrinsicIndex();
    P.block<3, 3>(e, e).diagonal().setConstant(u.extrinsic_translation_m * u.extrinsic_translation_m);
    P.block<3, 3>(e + 3, e + 3).diagonal().setConstant(u.extrinsic_rotation_rad * u.extrinsic_rotation_rad);
  }
  if (u.velocity_attitude_accel_bias) {
    // An initializer's [v, psi, b_a] with their correlations; the yaw's variance is the prior's.
    const std::array<int, 3> at{kV, kPsi, kBa};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        P.block<3, 3>(at[i], at[j]) = u.velocity_attitude_accel_bias->block<3, 3>(3 * i, 3 * j);
    }
    P.row(kPsi + 2).setZero();
    P.col(kPsi + 2).setZero();
    P(kPsi + 2, kPsi + 2) = u.yaw_rad * u.yaw_rad;
  }
  // An initializer that knows the velocity relative to its own heading: v_true = R_z(yaw error)
  // (v + dv), so the velocity error gains e_z x v times the yaw error.
  if (u.velocity_relative_to_heading) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Identity(dim, dim);
    J.block<3, 1>(kV, kPsi + 2) = Vec3::UnitZ().cross(init.v_n_b);
    P = J * P * J.transpose();
  }
  s.setCovariance(P);
  return s;
}

FilterState alignedStartingState(const EkfSlamConfig& config, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                 const DynamicInitResult& aligned, const NavState& registered, int* landmarks_added) {
  using namespace idx;
  InitialUncertainty u = aligned.uncertainty(config.initial);
  // The registration turned the aligned state about {n}'s z axis: so are its v and psi.
  const Mat3 R_z = (registered.q_n_b * aligned.state.q_n_b.conjugate()).toRotationMatrix();
  Eigen::Matrix<double, 9, 9> T = Eigen::Matrix<double, 9, 9>::Identity();
  T.block<3, 3>(0, 0) = R_z;
  T.block<3, 3>(3, 3) = R_z;
  u.velocity_attitude_accel_bias = T * aligned.covariance * T.transpose();
  FilterState s =
      startingState(config, T_b_c, registered, u, config.camera_time_offset_s + aligned.time_offset_correction_s);
  {
    // The gyro bias the alignment only considered moved its velocity, tilt and bias.
    const Eigen::Matrix<double, 9, 3> X = aligned.gyro_bias_covariance.allFinite()
                                              ? Eigen::Matrix<double, 9, 3>(T * aligned.gyro_bias_covariance)
                                              : Eigen::Matrix<double, 9, 3>::Zero();
    Eigen::MatrixXd& P = s.mutableCovariance();
    const std::array<int, 3> at{kV, kPsi, kBa};
    for (int i = 0; i < 3; ++i) {
      P.block<3, 3>(at[static_cast<size_t>(i)], kBg) = X.middleRows<3>(3 * i);
      P.block<3, 3>(kBg, at[static_cast<size_t>(i)]) = X.middleRows<3>(3 * i).transpose();
    }
  }
  // The aligned features enter with the depth the alignment found (their first updates are then
  // nearly linear) when it knows it better than a new track's prior; the others later as any new
  // track. They enter together: one error of the window's scale moves all their depths and the
  // velocity (taken as independent, tens of landmarks would know the scale far better than the
  // alignment does), and each carries its anchor's registration error as any new landmark.
  std::vector<FeatureObservation> obs;
  std::vector<double> depths;
  std::vector<int> candidates;  // indices into aligned.landmarks
  const auto n = static_cast<Eigen::Index>(aligned.landmarks.size());
  // (Without a usable joint covariance, the marginals alone, as independent depths.)
  const bool joint = aligned.landmark_covariance.rows() == n && aligned.landmark_covariance.cols() == n &&
                     aligned.landmark_state_covariance.rows() == n &&
                     aligned.landmark_gyro_bias_covariance.rows() == n && aligned.landmark_covariance.allFinite() &&
                     aligned.landmark_state_covariance.allFinite() && aligned.landmark_gyro_bias_covariance.allFinite();
  for (int j = 0; j < static_cast<int>(n); ++j) {
    const DynamicInitLandmark& l = aligned.landmarks[static_cast<size_t>(j)];
    if (static_cast<int>(obs.size()) >= config.max_landmarks) break;
    if (!(l.inverse_depth_sigma > 0.0 && l.inverse_depth_sigma < config.inverse_depth_sigma) || !(l.depth_m > 0.0) ||
        !std::isfinite(l.depth_m)) {
      continue;
    }
    obs.push_back({l.id, l.uv});
    depths.push_back(l.depth_m);
    candidates.push_back(j);
  }
  // Their inverse depths' joint covariance, and its cross-covariance with [v, psi, b_a] turned as
  // the registration turned them (yaw: none).
  const auto m = static_cast<Eigen::Index>(candidates.size());
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(m, m), C = Eigen::MatrixXd::Zero(m, s.dim());
  for (Eigen::Index a = 0; a < m; ++a) {
    const int ja = candidates[static_cast<size_t>(a)];
    Q(a, a) = std::pow(aligned.landmarks[static_cast<size_t>(ja)].inverse_depth_sigma, 2);
    if (!joint) continue;
    for (Eigen::Index b = 0; b < m; ++b) Q(a, b) = aligned.landmark_covariance(ja, candidates[static_cast<size_t>(b)]);
    const Eigen::Matrix<double, 1, 9> c = aligned.landmark_state_covariance.row(ja) * T.transpose();
    C.block<1, 3>(a, kV) = c.segment<3>(0);
    C.block<1, 3>(a, kPsi) = c.segment<3>(3);
    C.block<1, 3>(a, kBa) = c.segment<3>(6);
    C.block<1, 3>(a, kBg) = aligned.landmark_gyro_bias_covariance.row(ja);
  }
  const int added = static_cast<int>(
      initializeLandmarksInverseDepthJointly(s, obs, depths, Q, C, camera, s.x.T_b_c, config.update.pixel_noise_px)
          .size());
  if (landmarks_added) *landmarks_added = added;
  return s;
}

}  // namespace vi_ekf_slam
