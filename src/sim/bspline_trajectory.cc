#include "vi_ekf_slam/sim/bspline_trajectory.h"

#include "vi_ekf_slam/core/frames.h"

#include <cmath>
#include <memory>
#include <stdexcept>

namespace vi_ekf_slam::sim {

namespace {

/// Cumulative cubic B-spline basis B~_1..3(u) and its first two derivatives in u.
struct Basis {
  Vec3 b, db, ddb;
};

Basis cumulativeBasis(double u) {
  const double u2 = u * u, u3 = u2 * u;
  Basis B;
  B.b = Vec3((5.0 + 3.0 * u - 3.0 * u2 + u3) / 6.0, (1.0 + 3.0 * u + 3.0 * u2 - 2.0 * u3) / 6.0, u3 / 6.0);
  B.db = Vec3((3.0 - 6.0 * u + 3.0 * u2) / 6.0, (3.0 + 6.0 * u - 6.0 * u2) / 6.0, 3.0 * u2 / 6.0);
  B.ddb = Vec3((-6.0 + 6.0 * u) / 6.0, (6.0 - 12.0 * u) / 6.0, 6.0 * u / 6.0);
  return B;
}

}  // namespace

BsplineTrajectory::BsplineTrajectory(const std::vector<io::StampedPose>& poses, double knot_spacing_s)
    : dt_(knot_spacing_s) {
  if (!(knot_spacing_s > 0.0)) throw std::invalid_argument("B-spline knot spacing must be > 0");
  if (poses.size() < 4) throw std::invalid_argument("trajectory needs at least 4 poses");
  t0_ = poses.front().t;
  const double span = poses.back().t - t0_;
  // (A span of years is a file whose stamps are not seconds; the knot count would overflow.)
  if (!(span / dt_ < 1e8))
    throw std::invalid_argument("trajectory spans more than 1e8 knot spacings: stamps in seconds?");
  const int n = static_cast<int>(std::floor(span / dt_ + 1e-9)) + 1;
  if (n < 5) throw std::invalid_argument("trajectory is shorter than 4 knot spacings");
  // Resample at the knots: linear in position, slerp in attitude.
  size_t k = 0;
  Quat q_prev = poses.front().q;
  for (int i = 0; i < n; ++i) {
    const double t = t0_ + i * dt_;
    while (k + 2 < poses.size() && poses[k + 1].t < t) ++k;
    const auto& a = poses[k];
    const auto& b = poses[k + 1];
    const double s = std::clamp((t - a.t) / (b.t - a.t), 0.0, 1.0);
    p_.push_back((1.0 - s) * a.p + s * b.p);
    Quat q = a.q.slerp(s, b.q).normalized();
    if (q.dot(q_prev) < 0.0) q.coeffs() = -q.coeffs();  // keep the sign continuous
    q_.push_back(q);
    q_prev = q;
  }
}

double BsplineTrajectory::startTime() const { return t0_ + dt_; }
double BsplineTrajectory::endTime() const { return t0_ + (static_cast<double>(p_.size()) - 2.0) * dt_; }

TrajectorySample BsplineTrajectory::sample(double t) const {
  t = std::clamp(t, startTime(), endTime());
  const double x = (t - t0_) / dt_;
  int i = static_cast<int>(std::floor(x));
  i = std::clamp(i, 1, static_cast<int>(p_.size()) - 3);
  const double u = x - i;
  const Basis B = cumulativeBasis(u);
  TrajectorySample s;
  s.t = t;
  // Position: p = p_{i-1} + sum_j B~_j (p_{i+j-1} - p_{i+j-2}).
  s.p_n_b = p_[static_cast<size_t>(i - 1)];
  for (int j = 1; j <= 3; ++j) {
    const Vec3 d = p_[static_cast<size_t>(i + j - 1)] - p_[static_cast<size_t>(i + j - 2)];
    s.p_n_b += B.b(j - 1) * d;
    s.v_n_b += B.db(j - 1) * d / dt_;
    s.a_n_b += B.ddb(j - 1) * d / (dt_ * dt_);
  }
  // Attitude: R = R_{i-1} prod_j Exp(B~_j Omega_j); body rate by the recursion
  // w <- A_j^T w + B~_j' Omega_j (Omega_j constant, A_j = Exp(B~_j Omega_j)).
  Quat q = q_[static_cast<size_t>(i - 1)];
  Vec3 w = Vec3::Zero();
  for (int j = 1; j <= 3; ++j) {
    const Vec3 omega = logQuat(q_[static_cast<size_t>(i + j - 2)].conjugate() * q_[static_cast<size_t>(i + j - 1)]);
    const Quat A = expQuat(B.b(j - 1) * omega);
    q = q * A;
    w = A.conjugate() * w + B.db(j - 1) * omega / dt_;
  }
  s.q_n_b = q.normalized();
  s.w_b = w;
  return s;
}

io::StampedPose worldZUpToNav(const io::StampedPose& pose_w) {
  io::StampedPose p = pose_w;
  navToZUpWorld(pose_w.p, pose_w.q, &p.p, &p.q);  // the map is its own inverse
  return p;
}

std::shared_ptr<BsplineTrajectory> loadTumTrajectory(const std::string& path, double knot_spacing_s) {
  std::vector<io::StampedPose> poses = io::readTum(path);
  if (poses.size() < 4) {
    throw std::runtime_error(path + ": only " + std::to_string(poses.size()) + " poses; a trajectory needs at least 4");
  }
  if (poses.back().t - poses.front().t < 1.0) throw std::runtime_error(path + ": shorter than 1 s");
  for (auto& p : poses) p = worldZUpToNav(p);
  return std::make_shared<BsplineTrajectory>(poses, knot_spacing_s);
}

}  // namespace vi_ekf_slam::sim
