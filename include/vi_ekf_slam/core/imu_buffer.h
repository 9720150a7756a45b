// The IMU between images: the samples the filter has not integrated yet, the filter's propagation
// through them (interpolated between samples, with the uncertainty of a gap or of a bridged sample
// added), the IMU-rate prediction past the filter's state, and the rest test over the samples just
// before an image. One job: what the IMU says between two updates. EkfSlam owns one.
#pragma once

#include <deque>
#include <optional>

#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/navigation_output.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

class ImuBuffer {
 public:
  explicit ImuBuffer(const EkfSlamConfig& config) { setConfig(config); }
  /// Noise, gravity, gap and buffer bounds from now on.
  void setConfig(const EkfSlamConfig& config);
  /// Forgets every sample, bridge and count.
  void clear();

  /// Buffers one sample. False (and ignored) if it is non-finite or not newer than the last. A
  /// buffer beyond imu_buffer_max (no image for a long time) integrates its oldest half into
  /// `running` (the filter's state, null before the start) and drops it.
  bool add(const ImuData& imu, FilterState* running);
  /// A sample not to be integrated as it is (ImuSampleCheck): the propagation interpolates its
  /// neighbours over it and adds what it could have hidden (EkfSlam::bridgeImu).
  void bridge(const ImuData& imu);
  /// Propagates s to t (>= s.timestamp) and drops the samples it no longer needs. False (nothing
  /// done) if the buffer does not reach t.
  bool propagate(FilterState& s, double t);
  /// s propagated through every buffered sample past it (s is the motion state of the filter's, or
  /// the whole), and the bias-corrected angular rate at the end [rad/s]; nullopt when there is
  /// nothing past s.
  std::optional<NavState> predict(const FilterState& filter, Vec3* angular_rate) const;
  /// Whether the samples over [t - still_window_s, t] show the rig at rest; drops the samples
  /// older than that window (later images are newer).
  bool atRestBefore(double t);
  /// Drops the samples before t but the one just before it (a start at t).
  void dropBefore(double t);

  double latestTime() const;  ///< of the newest sample (or -inf)
  /// The raw angular rate of the last propagation step [rad/s].
  const Vec3& lastGyro() const { return last_gyro_; }
  int gaps() const { return gaps_; }  ///< samples that came after a gap longer than max_imu_gap_s

 private:
  /// Propagates s to t through the buffered samples (they must reach t).
  void integrate(FilterState& s, double t, Vec3* last_gyro) const;
  /// An unknown acceleration and rate over a gap of dt.
  void addGapUncertainty(FilterState& s, double dt) const;
  /// The bridges' uncertainty for the piece of [a, b] integrated (fraction of it).
  void addBridgeUncertainty(FilterState& s, double t_before, double fraction) const;
  /// Motion the IMU did not see: independent variances of position, velocity and attitude.
  static void addUnseenMotion(FilterState& s, const Vec3& var_p, const Vec3& var_v, const Vec3& var_psi);

  ImuNoiseParams noise_;
  Vec3 g_n_ = Vec3::Zero();
  double max_gap_s_ = 0.0, gap_accel_sigma_mps2_ = 0.0, gap_gyro_sigma_radps_ = 0.0;
  int max_samples_ = 0;
  ZeroVelocityParams rest_;
  std::deque<ImuData> imu_;
  std::deque<ImuData> recent_;  ///< samples since the last frame's rest window (bounded by imu_buffer_max)
  /// A left-out sample: after the buffered one at t_before, over dt, hiding up to sigma_a / sigma_g.
  struct Bridge {
    double t_before, dt;
    Vec3 sigma_a, sigma_g;
  };
  std::deque<Bridge> bridges_;
  Vec3 last_gyro_ = Vec3::Zero();
  int gaps_ = 0;
};

}  // namespace vi_ekf_slam
