#include "vi_ekf_slam/core/dynamic_init/alignment_problem.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

namespace vi_ekf_slam {
namespace alignment {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMinDepth = 0.05;  ///< a point closer than this [m] counts as behind the camera

/// d (x / z, y / z) / d pc of a point pc in the camera.
Eigen::Matrix<double, 2, 3> projectionJacobian(const Vec3& pc) {
  Eigen::Matrix<double, 2, 3> Jp;
  Jp << 1.0 / pc.z(), 0.0, -pc.x() / (pc.z() * pc.z()), 0.0, 1.0 / pc.z(), -pc.y() / (pc.z() * pc.z());
  return Jp;
}

/// The two algebraic rows [1 0 -x; 0 1 -y] of an observation (x, y).
Eigen::Matrix<double, 2, 3> algebraicRows(const Eigen::Vector2d& xn) {
  Eigen::Matrix<double, 2, 3> E;
  E << 1.0, 0.0, -xn.x(), 0.0, 1.0, -xn.y();
  return E;
}

}  // namespace

AlignmentProblem::AlignmentProblem(const std::deque<ImuData>& imu, std::vector<double> stamps,
                                   std::vector<Track> tracks, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                   const ProblemSettings& settings)
    : imu_(imu),
      stamps_(std::move(stamps)),
      tracks_(std::move(tracks)),
      s_(settings),
      R_c_b_(T_b_c.R_b_c.transpose()),
      p_c_b_(-R_c_b_ * T_b_c.p_b_c),
      f_px_(0.5 * (camera.intrinsics().fx + camera.intrinsics().fy)),
      huber_px_(3.0 * settings.pixel_noise_px),
      M_(static_cast<int>(tracks_.size())),
      Hff_(static_cast<size_t>(M_)),
      Hfy_(static_cast<size_t>(M_)),
      bf_(static_cast<size_t>(M_)),
      p_f_(static_cast<size_t>(M_), Vec3::Zero()),
      active_(static_cast<size_t>(M_), 1),
      num_active_(M_) {}

// The accelerometer bias's prior as a weight on the normal equations whose unit is the residual's
// times `scale` (1: normalized coordinates, f_px: pixels).
double AlignmentProblem::biasPriorWeight(double scale) const {
  const double ba_sigma = std::max(1e-6, s_.accel_bias_sigma_mps2);
  return std::pow(scale * s_.pixel_noise_px / f_px_ / ba_sigma, 2);
}

// The time offset's prior (time_offset_sigma_s around the configured offset) in the cost: with
// little motion the images hardly tell the offset, and a free search wanders to its bounds.
double AlignmentProblem::timeOffsetPrior(double dt) const {
  return std::pow(s_.pixel_noise_px * dt / std::max(1e-6, s_.time_offset_sigma_s), 2);
}

Vec3 AlignmentProblem::bodyPosition(const Preintegrated& P, double t, const VecY& yy) {
  return Vec3(yy.head<3>() * t + 0.5 * yy.segment<3>(3) * t * t + P.alpha + P.A * yy.tail<3>());
}

Vec3 AlignmentProblem::cameraPointWith(const Preintegrated& P, double t, const Vec3& pf, const VecY& yy) const {
  return Vec3(R_c_b_ * P.R.transpose() * (pf - bodyPosition(P, t, yy)) + p_c_b_);
}

Vec3 AlignmentProblem::cameraPoint(int k, const Vec3& pf, const VecY& yy) const {
  return cameraPointWith(pre_[static_cast<size_t>(k)], times_[static_cast<size_t>(k)] - times_.front(), pf, yy);
}

void AlignmentProblem::setTimeShift(double dt) {
  times_ = stamps_;
  for (auto& t : times_) t += dt;
  pre_ = preintegrate(imu_, times_);
}

bool AlignmentProblem::linearPass(int pass) {
  MatY Hyy = MatY::Zero();
  VecY by = VecY::Zero();
  // The bias stays 0 here (it is barely observable in the linear problem, whose bias would feed
  // it): the refinement estimates it.
  Hyy.bottomRightCorner<3, 3>().diagonal().setConstant(1e12);
  for (int j = 0; j < M_; ++j) {
    Hff_[j].setZero();
    Hfy_[j].setZero();
    bf_[j].setZero();
    for (const Observation& o : tracks_[static_cast<size_t>(j)].observations) {
      const double t = times_[static_cast<size_t>(o.frame)] - times_.front();
      const Preintegrated& P = pre_[static_cast<size_t>(o.frame)];
      const Mat3 R_ck = R_c_b_ * P.R.transpose();
      // Rows scaled by 1 / depth (from the first pass) are errors in normalized coordinates.
      double w = 1.0;
      if (pass > 0) {
        const double z = cameraPoint(o.frame, p_f_[j], y_).z();
        w = 1.0 / std::max(z, kMinDepth);
      }
      const Eigen::Matrix<double, 2, 3> E = algebraicRows(o.xn);
      const Eigen::Matrix<double, 2, 3> Af = w * E * R_ck;
      Eigen::Matrix<double, 2, 9> Ay;
      Ay << -t * Af, -0.5 * t * t * Af, -Af * P.A;
      const Eigen::Vector2d b = w * E * (R_ck * P.alpha - p_c_b_);
      Hff_[j] += Af.transpose() * Af;
      Hfy_[j] += Af.transpose() * Ay;
      bf_[j] += Af.transpose() * b;
      Hyy += Ay.transpose() * Ay;
      by += Ay.transpose() * b;
    }
  }
  S_ = Hyy;
  VecY s = by;
  Hff_inv_.assign(static_cast<size_t>(M_), Mat3::Zero());
  for (int j = 0; j < M_; ++j) {
    Hff_inv_[j] = (Hff_[j] + 1e-12 * Mat3::Identity()).inverse();
    S_ -= Hfy_[j].transpose() * Hff_inv_[j] * Hfy_[j];
    s -= Hfy_[j].transpose() * Hff_inv_[j] * bf_[j];
  }
  // |g| = G: o = [v0, b_a] eliminated, then (S_g + lambda I) g = s_g with lambda such that |g| = G.
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Mat63 = Eigen::Matrix<double, 6, 3>;
  const double G = s_.gravity_mps2;
  Mat6 Soo;
  Soo << S_.topLeftCorner<3, 3>(), S_.topRightCorner<3, 3>(), S_.bottomLeftCorner<3, 3>(), S_.bottomRightCorner<3, 3>();
  Mat63 Sog;
  Sog << S_.block<3, 3>(0, 3), S_.block<3, 3>(6, 3);
  Eigen::Matrix<double, 6, 1> so;
  so << s.head<3>(), s.tail<3>();
  const Mat6 Soo_inv = (Soo + 1e-12 * Mat6::Identity()).inverse();
  const Mat3 Sg = S_.block<3, 3>(3, 3) - Sog.transpose() * Soo_inv * Sog;
  const Vec3 sg = s.segment<3>(3) - Sog.transpose() * Soo_inv * so;
  const Eigen::SelfAdjointEigenSolver<Mat3> es(0.5 * (Sg + Sg.transpose()));
  const Vec3& d = es.eigenvalues();
  const Vec3 c = es.eigenvectors().transpose() * sg;
  auto norm2 = [&](double lambda) {
    double n = 0.0;
    for (int i = 0; i < 3; ++i) n += c(i) * c(i) / ((d(i) + lambda) * (d(i) + lambda));
    return n;
  };
  double lo = -d.minCoeff() + 1e-12 * (1.0 + std::abs(d.minCoeff()));
  double hi = -d.minCoeff() + c.norm() / G + 1.0;
  if (!(norm2(lo) > G * G)) lo = -d.minCoeff();  // degenerate: the bisection ends at the lower end
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (norm2(mid) > G * G ? lo : hi) = mid;
  }
  const double lambda = 0.5 * (lo + hi);
  Vec3 g = Vec3::Zero();
  for (int i = 0; i < 3; ++i) g += es.eigenvectors().col(i) * c(i) / (d(i) + lambda);
  if (!(g.norm() > 0.5 * G)) return false;
  g *= G / g.norm();
  const Eigen::Matrix<double, 6, 1> yo = Soo_inv * (so - Sog * g);
  y_ << yo.head<3>(), g, yo.tail<3>();
  for (int j = 0; j < M_; ++j) p_f_[j] = Hff_inv_[j] * (bf_[j] - Hfy_[j] * y_);
  return y_.allFinite();
}

double AlignmentProblem::solveLinear(double dt) {
  setTimeShift(dt);
  for (int pass = 0; pass < 2; ++pass) {
    if (!linearPass(pass)) return kInf;
  }
  // The reprojection error; a feature the linear solution puts behind the camera counts with its
  // algebraic error over 5 cm (large, but finite: the search keeps its slope there).
  double chi2 = 0.0;
  for (int j = 0; j < M_; ++j) {
    for (const Observation& o : tracks_[static_cast<size_t>(j)].observations) {
      const Vec3 pc = cameraPoint(o.frame, p_f_[j], y_);
      chi2 += ((pc.head<2>() - o.xn * pc.z()) * f_px_ / std::max(pc.z(), kMinDepth)).squaredNorm();
    }
  }
  return chi2;
}

bool AlignmentProblem::linearize(double scale, double huber_px, MatY* Hyy, VecY* by) {
  Hyy->setZero();
  by->setZero();
  Hyy->bottomRightCorner<3, 3>().diagonal().setConstant(biasPriorWeight(scale));
  by->tail<3>() = biasPriorWeight(scale) * y_.tail<3>();
  for (int j = 0; j < M_; ++j) {
    Hff_[j].setZero();
    Hfy_[j].setZero();
    bf_[j].setZero();
    if (!active_[static_cast<size_t>(j)]) continue;
    for (const Observation& o : tracks_[static_cast<size_t>(j)].observations) {
      const double t = times_[static_cast<size_t>(o.frame)] - times_.front();
      const Mat3 R_ck = R_c_b_ * pre_[static_cast<size_t>(o.frame)].R.transpose();
      const Vec3 pc = cameraPoint(o.frame, p_f_[j], y_);
      if (!(pc.z() > kMinDepth)) return false;
      const Eigen::Vector2d e = scale * (pc.head<2>() / pc.z() - o.xn);
      const Eigen::Matrix<double, 2, 3> Jp = projectionJacobian(pc);
      const Eigen::Matrix<double, 2, 3> Jf = scale * Jp * R_ck;
      Eigen::Matrix<double, 2, 9> Jy;
      Jy << -t * Jf, -0.5 * t * t * Jf, -Jf * pre_[static_cast<size_t>(o.frame)].A;
      const double w = huber_px > 0.0 && e.norm() > huber_px ? huber_px / e.norm() : 1.0;
      Hff_[j] += w * Jf.transpose() * Jf;
      Hfy_[j] += w * Jf.transpose() * Jy;
      bf_[j] += w * Jf.transpose() * e;
      *Hyy += w * Jy.transpose().lazyProduct(Jy);  // small: no GEMM (same sums)
      *by += w * Jy.transpose() * e;
    }
  }
  return true;
}

double AlignmentProblem::reprojectionCost(const VecY& yy, const std::vector<Vec3>& pf, double huber_px) const {
  double cost = biasPriorWeight(f_px_) * yy.tail<3>().squaredNorm();
  for (int j = 0; j < M_; ++j) {
    if (!active_[static_cast<size_t>(j)]) continue;
    for (const Observation& o : tracks_[static_cast<size_t>(j)].observations) {
      const Vec3 pc = cameraPoint(o.frame, pf[static_cast<size_t>(j)], yy);
      if (!(pc.z() > kMinDepth)) return kInf;
      const double e = ((pc.head<2>() / pc.z() - o.xn) * f_px_).norm();
      cost += e <= huber_px ? e * e : huber_px * (2.0 * e - huber_px);
    }
  }
  return cost;
}

int AlignmentProblem::activeObservations() const {
  int k = 0;
  for (int j = 0; j < M_; ++j)
    k += active_[static_cast<size_t>(j)] ? static_cast<int>(tracks_[static_cast<size_t>(j)].observations.size()) : 0;
  return k;
}

// The linear solution is biased: its equations multiply the noisy measurement by the unknown
// depth (errors in variables), which pulls the scale, hence the velocity, down (-25% on a
// simulated walk with 1 px noise). Levenberg-Marquardt on the reprojection error in pixels, from
// there, with |g| held on its sphere (a 2-dof tangent step) and a Huber loss, removes it.
double AlignmentProblem::levenbergMarquardt() {
  const double G = s_.gravity_mps2;
  double cost = reprojectionCost(y_, p_f_, huber_px_), lambda = 1e-4;
  for (int it = 0; it < 20 && std::isfinite(cost); ++it) {
    MatY Hyy;
    VecY by;
    if (!linearize(f_px_, huber_px_, &Hyy, &by)) break;
    // g on its sphere: steps in the plane normal to it.
    const Vec3 u = y_.segment<3>(3).normalized();
    const Vec3 a = std::abs(u.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    Eigen::Matrix<double, 9, 8> T = Eigen::Matrix<double, 9, 8>::Zero();
    T.topLeftCorner<3, 3>().setIdentity();
    T.block<3, 1>(3, 3) = u.cross(a).normalized();
    T.block<3, 1>(3, 4) = u.cross(T.block<3, 1>(3, 3));
    T.bottomRightCorner<3, 3>().setIdentity();
    bool accepted = false;
    for (int tries = 0; tries < 8 && !accepted; ++tries) {
      MatY Sy = Hyy;
      VecY sy = by;
      std::vector<Mat3> Hinv(static_cast<size_t>(M_));
      for (int j = 0; j < M_; ++j) {
        if (!active_[static_cast<size_t>(j)]) continue;
        Mat3 D = Hff_[j];
        D.diagonal() *= 1.0 + lambda;
        Hinv[static_cast<size_t>(j)] = (D + 1e-12 * Mat3::Identity()).inverse();
        Sy -= Hfy_[j].transpose() * Hinv[static_cast<size_t>(j)] * Hfy_[j];
        sy -= Hfy_[j].transpose() * Hinv[static_cast<size_t>(j)] * bf_[j];
      }
      Eigen::Matrix<double, 8, 8> S8 = T.transpose() * Sy * T;
      S8.diagonal() *= 1.0 + lambda;
      const Eigen::Matrix<double, 8, 1> d8 = -S8.ldlt().solve(T.transpose() * sy);
      const VecY dy = T * d8;
      VecY y_new = y_ + dy;
      y_new.segment<3>(3) = G * y_new.segment<3>(3).normalized();
      std::vector<Vec3> pf_new = p_f_;
      for (int j = 0; j < M_; ++j) {
        if (active_[static_cast<size_t>(j)])
          pf_new[static_cast<size_t>(j)] -= Hinv[static_cast<size_t>(j)] * (bf_[j] + Hfy_[j] * dy);
      }
      const double c = y_new.allFinite() ? reprojectionCost(y_new, pf_new, huber_px_) : cost + 1.0;
      if (c < cost) {
        const double gain = (cost - c) / cost;
        y_ = y_new;
        p_f_ = pf_new;
        cost = c;
        lambda = std::max(1e-8, 0.1 * lambda);
        accepted = true;
        if (gain < 1e-8) it = 1000;  // converged
      } else {
        lambda *= 10.0;
      }
    }
    if (!accepted) break;
  }
  return cost;
}

// A point the window cannot tell from one at infinity says nothing of y, and its position (x, y, z)
// is then far from linear in the observations. The information is taken along its ray from the
// last camera (pf = c_K + m / rho), finite for a point the refinement has pushed far out, where
// the Cartesian normal equations are singular.
bool AlignmentProblem::depthDetermined(int j, const Vec3& pf) const {
  const std::vector<Observation>& obs = tracks_[static_cast<size_t>(j)].observations;
  const int k = obs.back().frame;
  const Mat3 R_cK = R_c_b_ * pre_[static_cast<size_t>(k)].R.transpose();
  const Vec3 pc_K = cameraPoint(k, pf, y_);
  const double z = pc_K.z();
  if (!(z > kMinDepth)) return false;
  const double rho = 1.0 / z;
  const Vec3 dpf_drho = -R_cK.transpose() * (pc_K / z) / (rho * rho);
  double info = 0.0;
  for (const Observation& o : obs) {
    const Vec3 pc = cameraPoint(o.frame, pf, y_);
    const Mat3 R_ck = R_c_b_ * pre_[static_cast<size_t>(o.frame)].R.transpose();
    const Vec3 d = R_ck * dpf_drho;
    info += (Eigen::Vector2d(d.x() - pc.x() / pc.z() * d.z(), d.y() - pc.y() / pc.z() * d.z()) / pc.z()).squaredNorm();
  }
  const double sigma_rho = s_.pixel_noise_px / f_px_ / std::sqrt(std::max(info, 1e-300));
  return sigma_rho < 0.5 * rho;
}

// The linear triangulation of its rays, then Gauss-Newton on its reprojection error (y fixed).
bool AlignmentProblem::placeFeature(int j) {
  const std::vector<Observation>& obs = tracks_[static_cast<size_t>(j)].observations;
  Mat3 H = Mat3::Zero();
  Vec3 b = Vec3::Zero();
  for (const Observation& o : obs) {
    const double t = times_[static_cast<size_t>(o.frame)] - times_.front();
    const Preintegrated& P = pre_[static_cast<size_t>(o.frame)];
    const Mat3 R_ck = R_c_b_ * P.R.transpose();
    const Vec3 p_k = bodyPosition(P, t, y_);
    const Eigen::Matrix<double, 2, 3> E = algebraicRows(o.xn);
    const Eigen::Matrix<double, 2, 3> Af = E * R_ck;
    H += Af.transpose() * Af;
    b += Af.transpose() * (E * (R_ck * p_k - p_c_b_));
  }
  Vec3 pf = (H + 1e-12 * Mat3::Identity()).ldlt().solve(b);
  for (int it = 0; it < 5; ++it) {
    Mat3 Hj = Mat3::Zero();
    Vec3 bj = Vec3::Zero();
    for (const Observation& o : obs) {
      const Vec3 pc = cameraPoint(o.frame, pf, y_);
      if (!(pc.z() > kMinDepth)) return false;
      const Mat3 R_ck = R_c_b_ * pre_[static_cast<size_t>(o.frame)].R.transpose();
      const Eigen::Matrix<double, 2, 3> Jf = projectionJacobian(pc) * R_ck;
      Hj += Jf.transpose() * Jf;
      bj += Jf.transpose() * (pc.head<2>() / pc.z() - o.xn);
    }
    pf -= (Hj + 1e-12 * Mat3::Identity()).ldlt().solve(bj);
  }
  for (const Observation& o : obs) {
    if (!(cameraPoint(o.frame, pf, y_).z() > kMinDepth)) return false;
  }
  if (!depthDetermined(j, pf)) return false;
  p_f_[static_cast<size_t>(j)] = pf;
  return true;
}

void AlignmentProblem::chooseInFront() {
  num_active_ = 0;
  for (int j = 0; j < M_; ++j) {
    bool in_front = true;
    for (const Observation& o : tracks_[static_cast<size_t>(j)].observations) {
      in_front = in_front && cameraPoint(o.frame, p_f_[j], y_).z() > kMinDepth;
    }
    active_[static_cast<size_t>(j)] = in_front;
    num_active_ += in_front;
  }
}

// The linear solution can be far enough off to put most of a window's features behind the
// camera, and a refinement on the few it kept only confirms it: hence the rounds of placement.
double AlignmentProblem::refine(double dt, bool choose_active) {
  if (choose_active) {
    if (!std::isfinite(solveLinear(dt))) return kInf;
    chooseInFront();
  } else {
    setTimeShift(dt);
  }
  if (num_active_ < s_.min_features) return kInf;
  double cost = levenbergMarquardt();
  for (int round = 0; choose_active && std::isfinite(cost) && round < 3; ++round) {
    int joined = 0;
    for (int j = 0; j < M_; ++j) {
      if (!active_[static_cast<size_t>(j)] && placeFeature(j)) {
        active_[static_cast<size_t>(j)] = 1;
        ++joined;
      }
    }
    if (joined == 0) break;
    num_active_ += joined;
    cost = levenbergMarquardt();
  }
  return cost + timeOffsetPrior(dt);
}

// A feature whose depth the refined window leaves undetermined (pushed far out along its ray)
// leaves the alignment: its Cartesian normal equations are singular and would make up a
// covariance for it and for y.
bool AlignmentProblem::dropUndeterminedFeatures(double dt) {
  for (int round = 0;; ++round) {
    int dropped = 0;
    for (int j = 0; j < M_; ++j) {
      if (active_[static_cast<size_t>(j)] && !depthDetermined(j, p_f_[j])) {
        active_[static_cast<size_t>(j)] = 0;
        --num_active_;
        ++dropped;
      }
    }
    if (dropped == 0) return true;
    if (round == 4 || !std::isfinite(refine(dt))) return false;
  }
}

bool AlignmentProblem::eliminateAtSolution() {
  MatY Hyy;
  VecY by;
  if (!linearize(1.0, 0.0, &Hyy, &by)) return false;
  S_ = Hyy;
  for (int j = 0; j < M_; ++j) {
    if (!active_[static_cast<size_t>(j)]) continue;
    Hff_inv_[static_cast<size_t>(j)] = (Hff_[j] + 1e-12 * Mat3::Identity()).inverse();
    S_ -= Hfy_[j].transpose() * Hff_inv_[static_cast<size_t>(j)] * Hfy_[j];
  }
  return true;
}

bool AlignmentProblem::linearizeWithGyroBias(const Vec3& b_g, VecY* by, std::vector<Vec3>* bf,
                                             Preintegrated* pre_last) {
  const std::vector<Preintegrated> pre0 = pre_;
  const std::vector<Mat3> Hff0 = Hff_;
  const std::vector<Mat3Y> Hfy0 = Hfy_;
  const std::vector<Vec3> bf0 = bf_;
  pre_ = preintegrate(imu_, times_, b_g);
  *pre_last = pre_.back();
  MatY H;
  const bool ok = linearize(1.0, 0.0, &H, by);
  *bf = bf_;
  pre_ = pre0;
  Hff_ = Hff0;
  Hfy_ = Hfy0;
  bf_ = bf0;
  return ok;
}

bool AlignmentProblem::residuals(double* sum_sq, int* rows) const {
  *sum_sq = 0.0;
  *rows = 0;
  for (int j = 0; j < M_; ++j) {
    if (!active_[static_cast<size_t>(j)]) continue;
    for (const Observation& o : tracks_[static_cast<size_t>(j)].observations) {
      const Vec3 pc = cameraPoint(o.frame, p_f_[j], y_);
      if (!(pc.z() > kMinDepth)) return false;
      *sum_sq += ((pc.head<2>() / pc.z() - o.xn) * f_px_).squaredNorm();
      *rows += 2;
    }
  }
  return true;
}

}  // namespace alignment
}  // namespace vi_ekf_slam
