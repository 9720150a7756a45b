#include "vi_ekf_slam/core/static_initializer.h"

#include <cmath>
#include <vector>

namespace vi_ekf_slam {

NavState StaticInitResult::navState() const {
  NavState s;
  s.timestamp = timestamp;
  s.q_n_b = q_n_b;
  s.b_g = b_g;
  s.b_a = b_a;
  return s;
}

Quat gravityAlignedAttitude(const Vec3& f_b) {
  // At rest f_b = -R_n_b^T g_n with g_n = +g e_z ({n} has z down), so -f_b is "down" in {b}.
  const Quat q = Quat::FromTwoVectors(-f_b.normalized(), Vec3::UnitZ());
  // Remove the heading that FromTwoVectors may have chosen: a rotation about {n}'s z axis keeps
  // the gravity alignment.
  const Mat3 R = q.toRotationMatrix();
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return (Quat(Eigen::AngleAxisd(-yaw, Vec3::UnitZ())) * q).normalized();
}

StaticInitializer::StaticInitializer(const StaticInitParams& params) : params_(params) {}

std::optional<StaticInitResult> StaticInitializer::addImu(const ImuData& imu) {
  if (!isFinite(imu)) return std::nullopt;
  if (!window_.empty() && imu.timestamp <= window_.back().timestamp) return std::nullopt;
  window_.push_back(imu);
  while (window_.size() > 2 && window_.back().timestamp - window_[1].timestamp >= params_.window_s) {
    window_.pop_front();
  }
  if (window_.back().timestamp - window_.front().timestamp < params_.window_s) return std::nullopt;

  const double n = static_cast<double>(window_.size());
  Vec3 mean_a = Vec3::Zero(), mean_w = Vec3::Zero();
  for (const auto& s : window_) {
    mean_a += s.am / n;
    mean_w += s.wm / n;
  }
  // Means over blocks of block_s (a low-pass that keeps motion and drops vibration).
  std::vector<Vec3> block_a, block_w;
  {
    Vec3 sa = Vec3::Zero(), sw = Vec3::Zero();
    int count = 0;
    double block_start = window_.front().timestamp;
    for (const auto& s : window_) {
      if (s.timestamp - block_start >= params_.block_s && count > 0) {
        block_a.push_back(sa / count);
        block_w.push_back(sw / count);
        sa.setZero();
        sw.setZero();
        count = 0;
        block_start = s.timestamp;
      }
      sa += s.am;
      sw += s.wm;
      ++count;
    }
    if (count > 0) {
      block_a.push_back(sa / count);
      block_w.push_back(sw / count);
    }
  }
  const double nb = static_cast<double>(block_a.size());
  double mean_norm = 0.0;
  for (const auto& a : block_a) mean_norm += a.norm() / nb;
  double var_norm = 0.0;
  Vec3 var_w = Vec3::Zero();
  for (size_t i = 0; i < block_a.size(); ++i) {
    var_norm += std::pow(block_a[i].norm() - mean_norm, 2) / nb;
    var_w += (block_w[i] - mean_w).cwiseAbs2() / nb;
  }
  StaticInitResult r;
  r.accel_std_mps2 = std::sqrt(var_norm);
  r.gyro_std_radps = std::sqrt(var_w.maxCoeff());
  if (r.accel_std_mps2 > params_.max_accel_std_mps2 || r.gyro_std_radps > params_.max_gyro_std_radps ||
      std::abs(mean_a.norm() - params_.gravity_mps2) > params_.max_gravity_error_mps2) {
    return std::nullopt;
  }
  r.timestamp = window_.back().timestamp;
  r.q_n_b = gravityAlignedAttitude(mean_a);
  r.b_g = mean_w;
  r.b_a = (mean_a.norm() - params_.gravity_mps2) * mean_a.normalized();
  return r;
}

}  // namespace vi_ekf_slam
