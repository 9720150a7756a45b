#include "vi_ekf_slam/eval/metrics.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "vi_ekf_slam/core/chi_squared.h"

namespace vi_ekf_slam::eval {

double nees(const Eigen::VectorXd& e, const Eigen::MatrixXd& P) {
  const Eigen::LLT<Eigen::MatrixXd> llt(P);
  if (llt.info() != Eigen::Success || !e.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  return e.dot(llt.solve(e));
}

NeesBand neesBand(int dof, int runs, double prob) {
  if (dof < 1 || runs < 1) throw std::invalid_argument("neesBand: dof and runs must be >= 1");
  const double a = 0.5 * (1.0 - prob);
  const double k = static_cast<double>(dof) * runs;
  return {chiSquaredQuantile(a, k) / runs, chiSquaredQuantile(1.0 - a, k) / runs};
}

double rms(const std::vector<Vec3>& errors) {
  if (errors.empty()) return std::numeric_limits<double>::quiet_NaN();
  double s = 0.0;
  for (const auto& e : errors) s += e.squaredNorm();
  return std::sqrt(s / static_cast<double>(errors.size()));
}

double rms(const std::vector<double>& values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  double s = 0.0;
  for (double v : values) s += v * v;
  return std::sqrt(s / static_cast<double>(values.size()));
}

double meanOfFinite(const std::vector<double>& values) {
  double sum = 0.0;
  int n = 0;
  for (double x : values) {
    if (std::isfinite(x)) {
      sum += x;
      ++n;
    }
  }
  return n ? sum / n : std::nan("");
}

double scaleRatio(const std::vector<Vec3>& est, const std::vector<Vec3>& truth) {
  if (est.size() != truth.size()) throw std::invalid_argument("scaleRatio: size mismatch");
  double num = 0.0, den = 0.0;
  for (size_t i = 0; i < est.size(); ++i) {
    for (size_t j = i + 1; j < est.size(); ++j) {
      num += (est[i] - est[j]).norm();
      den += (truth[i] - truth[j]).norm();
    }
  }
  return den > 0.0 ? num / den : std::numeric_limits<double>::quiet_NaN();
}

Vec3 YawTranslation::apply(const Vec3& p) const { return Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * p + t; }
Quat YawTranslation::apply(const Quat& q) const { return Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ())) * q; }

YawTranslation alignPosYaw(const std::vector<Vec3>& est, const std::vector<Vec3>& truth) {
  if (est.size() != truth.size() || est.empty()) throw std::invalid_argument("alignPosYaw: bad sizes");
  Vec3 ce = Vec3::Zero(), ct = Vec3::Zero();
  for (size_t i = 0; i < est.size(); ++i) {
    ce += est[i];
    ct += truth[i];
  }
  ce /= static_cast<double>(est.size());
  ct /= static_cast<double>(est.size());
  // Maximize sum_i (Rz(yaw) a_i) . b_i over yaw: atan2 of the cross and dot sums in x-y.
  double sc = 0.0, ss = 0.0;
  for (size_t i = 0; i < est.size(); ++i) {
    const Vec3 a = est[i] - ce, b = truth[i] - ct;
    sc += a.x() * b.x() + a.y() * b.y();
    ss += a.x() * b.y() - a.y() * b.x();
  }
  YawTranslation T;
  T.yaw = std::atan2(ss, sc);
  T.t = ct - Eigen::AngleAxisd(T.yaw, Vec3::UnitZ()) * ce;
  return T;
}

double pathLength(const std::vector<Vec3>& p) {
  double d = 0.0;
  for (size_t i = 1; i < p.size(); ++i) d += (p[i] - p[i - 1]).norm();
  return d;
}

double rpePosition(const std::vector<Vec3>& p_true, const std::vector<Quat>& q_true, const std::vector<Vec3>& p_est,
                   const std::vector<Quat>& q_est, int delta) {
  std::vector<Vec3> e;
  for (size_t k = 0; k + static_cast<size_t>(delta) < p_true.size(); ++k) {
    const size_t j = k + static_cast<size_t>(delta);
    const Vec3 d_true = p_true[j] - p_true[k];
    const Vec3 d_est = q_true[k] * (q_est[k].conjugate() * (p_est[j] - p_est[k]));
    e.push_back(d_true - d_est);
  }
  return rms(e);
}

RevisitErrors revisitErrors(const std::vector<double>& t, const std::vector<Vec3>& p_true,
                            const std::vector<Vec3>& p_est, double radius_m, double min_gap_s) {
  RevisitErrors out;
  if (t.size() != p_true.size() || p_est.size() != p_true.size()) {
    throw std::invalid_argument("revisitErrors: one time and one estimate per true position");
  }
  std::vector<std::pair<size_t, size_t>> pairs;  // (earlier, later)
  for (size_t i = 0; i < t.size(); ++i) {
    for (size_t j = 0; j < i && t[i] - t[j] >= min_gap_s; ++j) {
      if ((p_true[i] - p_true[j]).norm() < radius_m) {
        pairs.emplace_back(j, i);
        break;  // the first visit only
      }
    }
  }
  out.pairs = static_cast<int>(pairs.size());
  if (pairs.empty() || pairs.front().second < 2) return out;
  // Registered (yaw and position) on the way to the first return, the part that mapped the places:
  // the start's yaw and position, which nothing observes, are then out of both errors.
  const size_t first_return = pairs.front().second;
  const YawTranslation T = alignPosYaw(std::vector<Vec3>(p_est.begin(), p_est.begin() + first_return),
                                       std::vector<Vec3>(p_true.begin(), p_true.begin() + first_return));
  std::vector<Vec3> first, again;
  for (const auto& [j, i] : pairs) {
    first.push_back(p_true[j] - T.apply(p_est[j]));
    again.push_back(p_true[i] - T.apply(p_est[i]));
  }
  out.first_m = rms(first);
  out.again_m = rms(again);
  return out;
}

}  // namespace vi_ekf_slam::eval
