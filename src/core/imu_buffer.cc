#include "vi_ekf_slam/core/imu_buffer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "vi_ekf_slam/core/imu_propagation.h"
#include "vi_ekf_slam/core/zero_velocity.h"

namespace vi_ekf_slam {

void ImuBuffer::setConfig(const EkfSlamConfig& config) {
  noise_ = config.imu_noise;
  g_n_ = gravityInNav(config.gravity_mps2);
  max_gap_s_ = config.max_imu_gap_s;
  gap_accel_sigma_mps2_ = config.imu_gap_accel_sigma_mps2;
  gap_gyro_sigma_radps_ = config.imu_gap_gyro_sigma_radps;
  max_samples_ = config.imu_buffer_max;
  rest_ = config.zero_velocity;
}

void ImuBuffer::clear() {
  imu_.clear();
  recent_.clear();
  bridges_.clear();
  gaps_ = 0;
}

bool ImuBuffer::add(const ImuData& imu, FilterState* running) {
  if (!isFinite(imu)) return false;
  if (!imu_.empty() && imu.timestamp <= imu_.back().timestamp) return false;
  if (!imu_.empty() && imu.timestamp - imu_.back().timestamp > max_gap_s_) ++gaps_;
  imu_.push_back(imu);
  recent_.push_back(imu);
  // Pruned by frame time in atRestBefore (the IMU may run ahead of the images); bounded here.
  while (static_cast<int>(recent_.size()) > max_samples_) recent_.pop_front();
  if (static_cast<int>(imu_.size()) > max_samples_) {
    // No image for a long time: integrate the oldest samples so the buffer stays bounded.
    if (running) {
      const double t = imu_[imu_.size() / 2].timestamp;
      if (std::isfinite(t) && t >= running->timestamp) propagate(*running, t);
    }
    while (static_cast<int>(imu_.size()) > max_samples_) imu_.pop_front();
  }
  return true;
}

void ImuBuffer::bridge(const ImuData& imu) {
  if (imu_.empty() || !(imu.timestamp > imu_.back().timestamp)) return;
  const ImuData& good = imu_.back();
  bridges_.push_back(
      {good.timestamp, imu.timestamp - good.timestamp, (imu.am - good.am).cwiseAbs(), (imu.wm - good.wm).cwiseAbs()});
}

void ImuBuffer::addBridgeUncertainty(FilterState& s, double t_before, double fraction) const {
  // What the left-out sample could have hidden: its departure from the last good sample, as an
  // unknown acceleration and rate over its period (the velocity and attitude it could have moved).
  for (const Bridge& b : bridges_) {
    if (b.t_before != t_before) continue;
    addUnseenMotion(s, Vec3::Zero(), fraction * (b.sigma_a * b.dt).cwiseAbs2(),
                    fraction * (b.sigma_g * b.dt).cwiseAbs2());
  }
}

double ImuBuffer::latestTime() const {
  return imu_.empty() ? -std::numeric_limits<double>::infinity() : imu_.back().timestamp;
}

bool ImuBuffer::propagate(FilterState& s, double t) {
  if (imu_.empty() || imu_.back().timestamp < t) return false;
  integrate(s, t, &last_gyro_);
  while (imu_.size() > 1 && imu_[1].timestamp <= t) imu_.pop_front();
  while (!bridges_.empty() && bridges_.front().t_before < imu_.front().timestamp) bridges_.pop_front();
  return true;
}

void ImuBuffer::integrate(FilterState& s, double t, Vec3* last_gyro) const {
  auto step = [&](double t0, double t1, const Vec3& wm, const Vec3& am) {
    if (t1 <= t0) return;
    propagateState(s, wm, am, t1 - t0, noise_, g_n_);
    *last_gyro = wm;
  };
  // Before the first buffered sample: hold it.
  if (s.timestamp < imu_.front().timestamp) {
    step(s.timestamp, std::min(t, imu_.front().timestamp), imu_.front().wm, imu_.front().am);
  }
  for (size_t k = 0; k + 1 < imu_.size(); ++k) {
    const ImuData& a = imu_[k];
    const ImuData& b = imu_[k + 1];
    const double t0 = std::max(a.timestamp, s.timestamp);
    const double t1 = std::min(b.timestamp, t);
    if (t1 > t0) {
      // Mean of the linearly interpolated measurements over [t0, t1] = value at its middle.
      const double alpha = (0.5 * (t0 + t1) - a.timestamp) / (b.timestamp - a.timestamp);
      step(t0, t1, (1.0 - alpha) * a.wm + alpha * b.wm, (1.0 - alpha) * a.am + alpha * b.am);
      if (b.timestamp - a.timestamp > max_gap_s_) addGapUncertainty(s, t1 - t0);
      if (!bridges_.empty()) addBridgeUncertainty(s, a.timestamp, (t1 - t0) / (b.timestamp - a.timestamp));
    }
    if (b.timestamp >= t) break;
  }
  s.timestamp = t;
}

std::optional<NavState> ImuBuffer::predict(const FilterState& filter, Vec3* angular_rate) const {
  if (imu_.empty() || imu_.back().timestamp < filter.timestamp) return std::nullopt;
  // The motion state alone (no landmarks): the same propagation at a 21x21 cost.
  FilterState s(filter.mechanization());
  s.timestamp = filter.timestamp;
  s.x = filter.x;
  s.setCovariance(filter.motionCovariance());
  Vec3 w = last_gyro_;
  integrate(s, imu_.back().timestamp, &w);
  if (angular_rate) *angular_rate = w - s.x.b_g;
  return vi_ekf_slam::navState(s);
}

bool ImuBuffer::atRestBefore(double t) {
  const double from = t - rest_.still_window_s;
  const bool at_rest = imuAtRest(recent_, from, t, rest_);
  // Later frames are newer: what is older than this frame's window is of no further use.
  while (!recent_.empty() && recent_.front().timestamp < from) recent_.pop_front();
  return at_rest;
}

void ImuBuffer::dropBefore(double t) {
  while (imu_.size() > 1 && imu_[1].timestamp <= t) imu_.pop_front();
}

void ImuBuffer::addGapUncertainty(FilterState& s, double dt) const {
  // An unknown acceleration of size sa ~ N(0, sa^2 I) over dt moves v by up to a dt and p by
  // a dt^2/2; an unknown rate turns the attitude by w dt. The position and velocity parts are
  // kept uncorrelated: a walking torso's acceleration swings within a gap, so the velocity it
  // ends with does not follow from how far it went. (A constant-acceleration model would make
  // them fully correlated, and the first image after the gap would then fix the velocity from
  // the position alone, wrongly and with confidence: the gate then rejects every later
  // observation. SensorFaults.FilterRidesThroughDropoutGapOutliersAndCoveredCamera.)
  const double sa = gap_accel_sigma_mps2_, sg = gap_gyro_sigma_radps_;
  const double qa = sa * sa;
  addUnseenMotion(s, Vec3::Constant(qa * std::pow(dt, 4) / 4.0), Vec3::Constant(qa * dt * dt),
                  Vec3::Constant(sg * sg * dt * dt));
}

void ImuBuffer::addUnseenMotion(FilterState& s, const Vec3& var_p, const Vec3& var_v, const Vec3& var_psi) {
  using namespace idx;
  const int m = s.motionDim();
  MotionMatrix Q = MotionMatrix::Zero(m, m);
  Q.block<3, 3>(kP, kP).diagonal() = var_p;
  Q.block<3, 3>(kV, kV).diagonal() = var_v;
  Q.block<3, 3>(kPsi, kPsi).diagonal() = var_psi;
  s.propagateCovariance(MotionMatrix::Identity(m, m), Q);
}

}  // namespace vi_ekf_slam
