// Shared fixtures for the core tests: random states with landmarks, a camera like the paper's,
// and central-difference numerical Jacobians.
#pragma once

#include <functional>
#include <random>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam::test {

inline Vec3 randomVec(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double x = u(rng), y = u(rng), z = u(rng);
  return scale * Vec3(x, y, z);
}

inline Quat randomQuat(std::mt19937_64& rng) { return expQuat(randomVec(rng, 2.0)); }

/// The paper's camera; other distortion models with similar strength for the model tests.
inline CameraModel paperCamera(DistortionModel model = DistortionModel::kRadTan) {
  CameraIntrinsics in = sim::paperCamera().intrinsics();
  in.model = model;
  if (model == DistortionModel::kNone) in.distortion.clear();
  if (model == DistortionModel::kEquidistant) in.distortion = {0.02, -0.01, 0.003, -0.001};
  return CameraModel(in);
}

/// A distortion-free camera of width x height px, focal length f [px], its principal point centred.
inline CameraModel pinholeCamera(int width, int height, double f) {
  return CameraModel(pinholeIntrinsics(width, height, f));
}

inline CameraExtrinsics forwardCamera() { return sim::torsoCameraExtrinsics(); }

inline Eigen::MatrixXd randomSpd(int n, std::mt19937_64& rng, double scale = 1.0) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  const Eigen::MatrixXd M = scale * (A * A.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n));
  return 0.5 * (M + M.transpose());  // exactly symmetric, as a filter covariance is kept
}

/// A state with N landmarks in front of the forward camera and a random SPD covariance; odd
/// landmarks are anchored inverse-depth points (anchor near the current camera), even ones are
/// Cartesian, so every Jacobian test covers both parameterizations.
/// With `extrinsic`, the state estimates the camera-IMU extrinsic: a forward camera a few degrees
/// and centimetres off.
inline FilterState randomState(Mechanization m, int N, std::mt19937_64& rng, bool extrinsic = false) {
  FilterState s(m, extrinsic);
  s.x.p_s_b = randomVec(rng, 2.0);
  s.x.v_s_b = randomVec(rng, 1.5);
  s.x.b_a = randomVec(rng, 0.1);
  s.x.b_g = randomVec(rng, 0.01);
  s.x.q_s_b = expQuat(randomVec(rng, 0.4));
  s.x.t_d = randomVec(rng, 0.05).x();
  if (isSensorCentric(m)) {
    s.x.p_n_s = randomVec(rng, 3.0);
    s.x.q_n_s = randomQuat(rng);
  }
  CameraExtrinsics T = forwardCamera();
  if (extrinsic) {
    T.p_b_c += randomVec(rng, 0.03);
    T.R_b_c = expSO3(randomVec(rng, 0.05)) * T.R_b_c;
  }
  s.x.T_b_c = T;
  std::uniform_real_distribution<double> depth(2.0, 10.0), lateral(-0.4, 0.4);
  const int n0 = s.dim();
  Eigen::MatrixXd P = randomSpd(n0, rng, 0.01);
  s.setCovariance(P);
  for (int i = 0; i < N; ++i) {
    const double d = depth(rng);
    const Vec3 p_c(lateral(rng) * d, lateral(rng) * d, d);
    const Vec3 p_s = s.x.q_s_b * (T.R_b_c * p_c + T.p_b_c) + s.x.p_s_b;
    Landmark lm = Landmark::cartesian(p_s);
    if (i % 2 == 1) {
      lm.kind = LandmarkKind::kInverseDepth;
      lm.p_s_a = s.x.p_s_b + s.x.q_s_b * T.p_b_c + randomVec(rng, 0.3);
      lm.R_s_a = s.x.q_s_b.toRotationMatrix() * T.R_b_c * expSO3(randomVec(rng, 0.1));
      const Vec3 p_a = lm.R_s_a.transpose() * (p_s - lm.p_s_a);
      lm.l = Vec3(p_a.x() / p_a.z(), p_a.y() / p_a.z(), 1.0 / p_a.z());
    }
    s.appendLandmark(100 + i, lm, 0.01 * Mat3::Identity(), Eigen::MatrixXd::Zero(3, s.dim()));
  }
  s.setCovariance(randomSpd(s.dim(), rng, 0.01));
  return s;
}

/// Central differences of f around zero: column j = (f(+e_j h) - f(-e_j h)) / 2h.
inline Eigen::MatrixXd numericJacobian(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f, int in_dim,
                                       double h = 1e-6) {
  const Eigen::VectorXd f0 = f(Eigen::VectorXd::Zero(in_dim));
  Eigen::MatrixXd J(f0.size(), in_dim);
  for (int j = 0; j < in_dim; ++j) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(in_dim);
    d(j) = h;
    J.col(j) = (f(d) - f(-d)) / (2.0 * h);
  }
  return J;
}

/// Numerical Jacobian of a state -> state map (error state in, error state out).
inline Eigen::MatrixXd numericFrameChangeJacobian(const FilterState& s0,
                                                  const std::function<void(FilterState&)>& change) {
  FilterState ref = s0;
  change(ref);
  return numericJacobian(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        FilterState s = s0;
        s.boxplus(d);
        change(s);
        return s.boxminus(ref);
      },
      s0.dim());
}

inline double maxAbs(const Eigen::MatrixXd& M) { return M.cwiseAbs().maxCoeff(); }

}  // namespace vi_ekf_slam::test
