// The stamps of the two input streams: which sample is the next one, which is stale, which means
// that time jumped back (a bag restarted), where the IMU has gaps, and the IMU's own rate.
#pragma once

#include <optional>

namespace vi_ekf_slam::glue {

enum class StampVerdict {
  kNext,        ///< newer than the previous sample: use it
  kStale,       ///< not newer, by less than the jump threshold: drop it
  kJumpedBack,  ///< older by more than the jump threshold: start over (the sample is the first)
};

class InputClock {
 public:
  /// jump_s: how far back a stamp must go to count as a restart [s]; max_imu_gap_s: longer IMU
  /// intervals are gaps (and stay out of the rate estimate) [s].
  InputClock(double jump_s, double max_imu_gap_s) : jump_s_(jump_s), max_imu_gap_s_(max_imu_gap_s) {}

  /// On kNext and kJumpedBack the stamp becomes the stream's latest.
  StampVerdict imu(double t);
  StampVerdict image(double t);
  /// How far the last verdict's stamp lay behind the previous one [s] (for kStale, kJumpedBack).
  double lastStepBack() const { return step_back_; }
  /// The gap before the last accepted IMU sample, if longer than max_imu_gap_s [s].
  std::optional<double> lastImuGap() const { return imu_gap_; }
  /// The IMU's sample interval, averaged over the last ~100 samples (nullopt: not yet known) [s].
  std::optional<double> imuPeriod() const { return imu_period_s_; }
  void reset();

 private:
  StampVerdict check(std::optional<double>& last, double t);

  double jump_s_, max_imu_gap_s_;
  std::optional<double> last_imu_t_, last_image_t_, imu_period_s_, imu_gap_;
  double step_back_ = 0.0;
};

}  // namespace vi_ekf_slam::glue
