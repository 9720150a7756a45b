#include "vi_ekf_slam/core/dynamic_init/alignment_uncertainty.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/static_initializer.h"

namespace vi_ekf_slam {
namespace alignment {

namespace {

double largestSigma(const Mat3& P) {
  return std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat3>(P).eigenvalues().maxCoeff()));
}

/// RMS kinematic acceleration over [t0, t1] (with the gravity g and accelerometer bias b_a found):
/// the motion a time offset error turns into a velocity error.
double accelerationRms(const std::deque<ImuData>& imu, double t0, double t1, const Vec3& g, const Vec3& b_a) {
  double sum = 0.0;
  int n = 0;
  Mat3 R = Mat3::Identity();
  for (size_t i = 1; i < imu.size(); ++i) {
    const double a = imu[i - 1].timestamp, b = imu[i].timestamp;
    if (b <= t0 || a >= t1) continue;
    const ImuData m = interpolate(imu, 0.5 * (a + b));
    R = R * expSO3((b - a) * m.wm);
    sum += (R * (m.am - b_a) + g).squaredNorm();
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

}  // namespace

AlignmentUncertainty::AlignmentUncertainty(AlignmentProblem& problem, const std::deque<ImuData>& imu,
                                           const TimeOffsetFit& fit, const UncertaintySettings& settings)
    : s_(settings),
      G_(problem.settings().gravity_mps2),
      f_px_(problem.focalPx()),
      t_K_(problem.times().back() - problem.times().front()),
      dt_curvature_(fit.curvature),
      y_(problem.y()),
      PK_(problem.preintegrated().back()),
      S_(problem.schur()) {
  accel_rms_ = accelerationRms(imu, problem.times().front(), problem.times().back(), y_.segment<3>(3), y_.tail<3>());
  out_ = output(y_, PK_, nullptr);
  for (int i = 0; i < 9; ++i) {  // d [v_n, psi_n, b_a] / d y, numerically
    const double h = i < 3 ? 1e-4 : i < 6 ? 1e-4 * G_ : 1e-4;
    VecY yp = y_, ym = y_;
    yp(i) += h;
    ym(i) -= h;
    J_out_.block<6, 1>(0, i) = outputDifference(output(yp, PK_, &out_), output(ym, PK_, &out_), h);
  }
  J_out_.block<3, 3>(6, 6).setIdentity();
  S_inv_ = (S_ + 1e-12 * MatY::Identity()).inverse();
  gyroBiasShare(problem);
}

// The state at the last frame as a function of y; yaw_ref removes the heading a change of g would
// give (the heading is not the alignment's to know).
AlignedState AlignmentUncertainty::output(const VecY& yy, const Preintegrated& pk, const AlignedState* yaw_ref) const {
  const Quat q_n_I0 = gravityAlignedAttitude(-yy.segment<3>(3));
  AlignedState o;
  o.q_n_b = (q_n_I0 * Quat(pk.R)).normalized();
  o.v_n = q_n_I0 * (yy.head<3>() + yy.segment<3>(3) * t_K_ + pk.beta + pk.B * yy.tail<3>());
  if (yaw_ref) {
    const Quat unyaw(Eigen::AngleAxisd(-yawBetween(yaw_ref->q_n_b, o.q_n_b), Vec3::UnitZ()));
    o.q_n_b = unyaw * o.q_n_b;
    o.v_n = unyaw * o.v_n;
  }
  return o;
}

// [v_n, psi_n] of op minus om, over 2h (psi_n: R_true = Exp(psi) R_est; its yaw row is zero).
Eigen::Matrix<double, 6, 1> AlignmentUncertainty::outputDifference(const AlignedState& op, const AlignedState& om,
                                                                   double h) const {
  Eigen::Matrix<double, 6, 1> d;
  d.head<3>() = (op.v_n - om.v_n) / (2.0 * h);
  d.tail<3>() = (logSO3((op.q_n_b * out_.q_n_b.conjugate()).toRotationMatrix()) -
                 logSO3((om.q_n_b * out_.q_n_b.conjugate()).toRotationMatrix())) /
                (2.0 * h);
  d(5) = 0.0;
  return d;
}

// The gyro bias is not estimated (a 1 s window hardly observes it) but not known either: it turns
// every integrated attitude, so it moves the whole solution, the velocity, the tilt and every depth
// together. Its share, to first order: the solution's sensitivity d theta / d b_g = -H^-1 d grad /
// d b_g, the gradient of the normal equations at the solution differenced over b_g, plus the
// output's own dependence on it.
void AlignmentUncertainty::gyroBiasShare(AlignmentProblem& problem) {
  const int M = problem.size();
  dpf_dbg_.assign(static_cast<size_t>(M), Mat3::Zero());
  for (int k = 0; k < 3; ++k) {
    std::array<std::vector<Vec3>, 2> bfs;
    std::array<VecY, 2> bys;
    bool ok = true;
    for (int sgn = 0; sgn < 2; ++sgn) {
      const Vec3 b_g = (sgn == 0 ? kBgStep : -kBgStep) * Vec3::Unit(k);
      ok = problem.linearizeWithGyroBias(b_g, &bys[static_cast<size_t>(sgn)], &bfs[static_cast<size_t>(sgn)],
                                         &PK_bg_[static_cast<size_t>(k)][static_cast<size_t>(sgn)]) &&
           ok;
    }
    if (!ok) continue;
    std::vector<Vec3> dbf(static_cast<size_t>(M), Vec3::Zero());
    VecY rhs = (bys[0] - bys[1]) / (2.0 * kBgStep);
    for (int j = 0; j < M; ++j) {
      if (!problem.active(j)) continue;
      dbf[static_cast<size_t>(j)] = (bfs[0][static_cast<size_t>(j)] - bfs[1][static_cast<size_t>(j)]) / (2.0 * kBgStep);
      rhs -= problem.hfy(j).transpose() * problem.hffInverse(j) * dbf[static_cast<size_t>(j)];
    }
    dy_dbg_.col(k) = -S_inv_ * rhs;
    for (int j = 0; j < M; ++j) {
      if (!problem.active(j)) continue;
      dpf_dbg_[static_cast<size_t>(j)].col(k) =
          -problem.hffInverse(j) * (dbf[static_cast<size_t>(j)] + problem.hfy(j) * dy_dbg_.col(k));
    }
    dout_dbg_.block<6, 1>(0, k) = outputDifference(output(y_, PK_bg_[static_cast<size_t>(k)][0], &out_),
                                                   output(y_, PK_bg_[static_cast<size_t>(k)][1], &out_), kBgStep);
  }
  dout_dbg_ += J_out_ * dy_dbg_;
}

StateCovariance AlignmentUncertainty::covariance(double sigma_px) const {
  StateCovariance c;
  const double bg_var = s_.gyro_bias_sigma_radps * s_.gyro_bias_sigma_radps;
  const double sigma_n = sigma_px / f_px_;
  const MatY cov_y = sigma_n * sigma_n * (S_ + 1e-12 * MatY::Identity()).inverse();
  c.covariance = J_out_ * cov_y * J_out_.transpose() + bg_var * dout_dbg_ * dout_dbg_.transpose();
  c.velocity_sigma_ls_mps = largestSigma(c.covariance.topLeftCorner<3, 3>());
  // A camera-IMU time offset t_d shifts every frame's pose by the motion over t_d (velocity error
  // ~ a t_d): the offset as found (Fisher information of cost / sigma^2: half its curvature), not
  // below 1 ms, or as assumed when not searched.
  double td_sigma = s_.time_offset_sigma_s;
  if (s_.time_offset_search_s > 0.0) {
    td_sigma =
        dt_curvature_ > 0.0 ? std::max(0.001, sigma_px * std::sqrt(2.0 / dt_curvature_)) : s_.time_offset_search_s;
  }
  const double v_td = accel_rms_ * td_sigma;
  // What the first-order terms leave out (the IMU's own noise over the window, the linearization)
  // is kept as a bound: a tilt of b_g T and the gravity it leaks into the velocity. Without it,
  // simulated EuRoC starts leave the NEES band.
  const double tilt_bg = s_.gyro_bias_sigma_radps * t_K_;
  c.covariance.topLeftCorner<3, 3>().diagonal().array() += v_td * v_td + std::pow(0.5 * G_ * tilt_bg, 2);
  c.covariance.block<2, 2>(3, 3).diagonal().array() += tilt_bg * tilt_bg;
  c.velocity_sigma_mps = largestSigma(c.covariance.topLeftCorner<3, 3>());
  c.tilt_sigma_rad = std::sqrt(std::max(
      0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(c.covariance.block<2, 2>(3, 3)).eigenvalues().maxCoeff()));
  return c;
}

// The features of the last frame with their inverse depth rho = 1 / z in the last camera. To first
// order rho_j = g_j dy + a_j e_j: a_j = d rho / d p_f, e_j the feature's own error (p_f given y;
// covariance sigma^2 Hff^-1) and g_j the share of the window's [v0, g, b_a] error dy (covariance
// sigma^2 S^-1), through the feature (p_f follows y by -Hff^-1 Hfy dy) and through the last
// camera's position p_K(y). The shared part is the scale: taken as independent per landmark, tens
// of landmarks would "know" it several times better than the alignment does. Scaled up as the
// velocity by the time offset's and the bound's shares (a scale error); the gyro bias's share as
// above, through p_f, y and the last frame's attitude and position.
void AlignmentUncertainty::addLandmarks(const AlignmentProblem& problem, double sigma_px, const StateCovariance& cov,
                                        DynamicInitResult* r) const {
  const double bg_var = s_.gyro_bias_sigma_radps * s_.gyro_bias_sigma_radps;
  const double inflate = cov.velocity_sigma_ls_mps > 0.0 ? cov.velocity_sigma_mps / cov.velocity_sigma_ls_mps : 1.0;
  const double sigma_n2 = std::pow(sigma_px / f_px_, 2);
  const int last = static_cast<int>(problem.times().size()) - 1;
  const Mat3 R_cK = problem.cameraFromBody() * PK_.R.transpose();
  Mat3Y dpK_dy;  // d p_K / d y
  dpK_dy << t_K_ * Mat3::Identity(), 0.5 * t_K_ * t_K_ * Mat3::Identity(), PK_.A;
  std::vector<Eigen::Matrix<double, 1, 9>> shared;
  std::vector<Eigen::RowVector3d> from_bg;  // d rho / d b_g
  std::vector<double> own_var;
  for (int j = 0; j < problem.size(); ++j) {
    const Track& track = problem.tracks()[static_cast<size_t>(j)];
    if (!problem.active(j) || track.observations.back().frame != last) continue;
    const Vec3& p_f = problem.features()[static_cast<size_t>(j)];
    const Vec3 pc = problem.cameraPoint(last, p_f, y_);
    const Eigen::RowVector3d a = -R_cK.row(2) / (pc.z() * pc.z());
    shared.push_back(-a * dpK_dy - a * problem.hffInverse(j) * problem.hfy(j));
    own_var.push_back(sigma_n2 * a * problem.hffInverse(j) * a.transpose());
    Eigen::RowVector3d d = a * dpf_dbg_[static_cast<size_t>(j)] - a * dpK_dy * dy_dbg_;
    for (int k = 0; k < 3; ++k) {
      std::array<double, 2> rho{};
      for (int sgn = 0; sgn < 2; ++sgn) {
        const Preintegrated& pk = PK_bg_[static_cast<size_t>(k)][static_cast<size_t>(sgn)];
        rho[static_cast<size_t>(sgn)] = 1.0 / problem.cameraPointWith(pk, t_K_, p_f, y_).z();
      }
      d(k) += (rho[0] - rho[1]) / (2.0 * kBgStep);
    }
    from_bg.push_back(d);
    DynamicInitLandmark l;
    l.id = track.id;
    l.uv = track.observations.back().uv;
    l.depth_m = pc.z();
    r->landmarks.push_back(l);
  }
  const int n = static_cast<int>(r->landmarks.size());
  Eigen::Matrix<double, Eigen::Dynamic, 9> Gs(n, 9);
  Eigen::Matrix<double, Eigen::Dynamic, 3> Bs(n, 3);
  for (int i = 0; i < n; ++i) {
    Gs.row(i) = shared[static_cast<size_t>(i)];
    Bs.row(i) = from_bg[static_cast<size_t>(i)];
  }
  r->landmark_covariance = inflate * inflate * sigma_n2 * Gs * S_inv_ * Gs.transpose() + bg_var * Bs * Bs.transpose();
  for (int i = 0; i < n; ++i) r->landmark_covariance(i, i) += inflate * inflate * own_var[static_cast<size_t>(i)];
  r->landmark_state_covariance =
      inflate * sigma_n2 * Gs * S_inv_ * J_out_.transpose() + bg_var * Bs * dout_dbg_.transpose();
  r->landmark_gyro_bias_covariance = bg_var * Bs;
  r->gyro_bias_covariance = bg_var * dout_dbg_;
  for (int i = 0; i < n; ++i) {
    DynamicInitLandmark& l = r->landmarks[static_cast<size_t>(i)];
    l.inverse_depth_sigma = std::sqrt(std::max(0.0, r->landmark_covariance(i, i)));
  }
}

}  // namespace alignment
}  // namespace vi_ekf_slam
