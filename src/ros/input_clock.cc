#include "vi_ekf_slam/ros/input_clock.h"

namespace vi_ekf_slam::glue {

StampVerdict InputClock::check(std::optional<double>& last, double t) {
  step_back_ = 0.0;
  if (last && t <= *last) {
    step_back_ = *last - t;
    if (step_back_ <= jump_s_) return StampVerdict::kStale;
    last = t;
    return StampVerdict::kJumpedBack;
  }
  last = t;
  return StampVerdict::kNext;
}

StampVerdict InputClock::imu(double t) {
  const std::optional<double> previous = last_imu_t_;
  const StampVerdict v = check(last_imu_t_, t);
  imu_gap_.reset();
  if (v == StampVerdict::kNext && previous) {
    const double dt = t - *previous;
    if (dt > max_imu_gap_s_) {
      imu_gap_ = dt;
    } else {
      imu_period_s_ = imu_period_s_ ? 0.99 * *imu_period_s_ + 0.01 * dt : dt;
    }
  }
  return v;
}

StampVerdict InputClock::image(double t) { return check(last_image_t_, t); }

void InputClock::reset() {
  last_imu_t_.reset();
  last_image_t_.reset();
  imu_gap_.reset();
  step_back_ = 0.0;
}

}  // namespace vi_ekf_slam::glue
