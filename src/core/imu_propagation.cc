#include "vi_ekf_slam/core/imu_propagation.h"

namespace vi_ekf_slam {

namespace {
/// Gravity expressed in the strapdown frame: g_n itself (world-centric) or R_n_s^T g_n.
Vec3 gravityInStrapdown(const MotionState& x, Mechanization m, const Vec3& g_n) {
  return isSensorCentric(m) ? Vec3(x.q_n_s.conjugate() * g_n) : g_n;
}
}  // namespace

void strapdownStep(MotionState& x, Mechanization m, const Vec3& wm, const Vec3& am, double dt, const Vec3& g_n) {
  const Vec3 w = wm - x.b_g;
  // eq. (8) / (21), with the specific force rotated by the attitude in the middle of the step
  // (second-order accurate; eq. 8 uses the attitude at its start).
  const Quat q_mid = x.q_s_b * expQuat(0.5 * dt * w);
  const Vec3 a = q_mid * (am - x.b_a) + gravityInStrapdown(x, m, g_n);
  x.p_s_b += x.v_s_b * dt + 0.5 * a * dt * dt;
  x.v_s_b += a * dt;
  x.q_s_b = (x.q_s_b * expQuat(w * dt)).normalized();  // eq. (9)
}

MotionMatrix transitionMatrix(const MotionState& x, Mechanization m, const Vec3& wm, const Vec3& am, double dt,
                              const Vec3& g_n, bool extrinsic) {
  using namespace idx;
  const int n = motionDim(m, extrinsic);  // the extrinsic is constant: its block stays identity
  MotionMatrix Phi = MotionMatrix::Identity(n, n);
  const Mat3 R = x.q_s_b.toRotationMatrix();
  const Vec3 f = am - x.b_a;
  const Vec3 w_dt = (wm - x.b_g) * dt;
  const Mat3 R_mid = R * expSO3(0.5 * w_dt);
  const Mat3 R_next = R * expSO3(w_dt);
  // Derivatives of the acceleration a = R_mid f + g_s of one step:
  const Mat3 dA_dpsi = -skew(R_mid * f);  // eq. (13)/(23): [-C (am - ba)]x
  const Mat3 dA_dba = -R_mid;             // eq. (13)/(23): -C
  // Through the half-step rotation in R_mid (vanishes as dt -> 0, absent from eq. 13).
  const Mat3 dA_dbg = R_mid * skew(f) * rightJacobianSO3(0.5 * w_dt) * (0.5 * dt);
  const double h = 0.5 * dt * dt;
  Phi.block<3, 3>(kP, kV) = dt * Mat3::Identity();  // eq. (12)
  Phi.block<3, 3>(kP, kBa) = h * dA_dba;
  Phi.block<3, 3>(kP, kPsi) = h * dA_dpsi;
  Phi.block<3, 3>(kP, kBg) = h * dA_dbg;
  Phi.block<3, 3>(kV, kBa) = dt * dA_dba;  // eq. (13)
  Phi.block<3, 3>(kV, kPsi) = dt * dA_dpsi;
  Phi.block<3, 3>(kV, kBg) = dt * dA_dbg;
  Phi.block<3, 3>(kPsi, kBg) = -R_next * rightJacobianSO3(w_dt) * dt;  // eq. (15)
  if (isSensorCentric(m)) {
    // Gravity in {s} depends on the estimated q_n_s (eq. 21, 23).
    const Mat3 dG_dpsins = x.q_n_s.conjugate().toRotationMatrix() * skew(g_n);
    Phi.block<3, 3>(kP, kPsiNs) = h * dG_dpsins;
    Phi.block<3, 3>(kV, kPsiNs) = dt * dG_dpsins;
  }
  return Phi;
}

MotionVector continuousNoiseDiagonal(Mechanization m, const ImuNoiseParams& noise, double dt, bool extrinsic) {
  using namespace idx;
  // G Q G^T: the noise enters through rotations (C n_a, C n_g) of isotropic white noise, so
  // the rotated blocks stay sigma^2 * I.
  MotionVector q = MotionVector::Zero(motionDim(m, extrinsic));
  q.segment<3>(kV).setConstant(noise.accel_noise_density * noise.accel_noise_density * dt);
  q.segment<3>(kBa).setConstant(noise.accel_random_walk * noise.accel_random_walk * dt);
  q.segment<3>(kPsi).setConstant(noise.gyro_noise_density * noise.gyro_noise_density * dt);
  q.segment<3>(kBg).setConstant(noise.gyro_random_walk * noise.gyro_random_walk * dt);
  return q;
}

MotionMatrix discreteNoise(const MotionMatrix& Phi, Mechanization m, const ImuNoiseParams& noise, double dt,
                           bool extrinsic) {
  MotionMatrix Qd = Phi * continuousNoiseDiagonal(m, noise, dt, extrinsic).asDiagonal() * Phi.transpose();
  return 0.5 * (Qd + Qd.transpose());
}

void propagateState(FilterState& state, const Vec3& wm, const Vec3& am, double dt, const ImuNoiseParams& noise,
                    const Vec3& g_n) {
  const Mechanization m = state.mechanization();
  const bool e = state.estimatesExtrinsic();
  const MotionMatrix Phi = transitionMatrix(state.x, m, wm, am, dt, g_n, e);
  strapdownStep(state.x, m, wm, am, dt, g_n);
  state.propagateCovarianceDiagonalNoise(Phi, continuousNoiseDiagonal(m, noise, dt, e));
  state.timestamp += dt;
}

}  // namespace vi_ekf_slam
