#include "vi_ekf_slam/ros/filter_start.h"

#include <ros/console.h>
#include <sstream>

namespace vi_ekf_slam::glue {

void FilterStart::setCamera(const CameraModel& camera, const CameraExtrinsics& T_b_c) {
  dynamic_init_ =
      std::make_unique<DynamicInitializer>(withFilterSettings(params_.dynamic_init, params_.filter), camera, T_b_c);
}

void FilterStart::addImu(const ImuData& d, bool waiting) {
  if (auto r = static_init_.addImu(d)) static_result_ = r;
  if (dynamic_init_ && waiting) dynamic_init_->addImu(d);
}

std::optional<std::string> FilterStart::tryStatic(EkfSlam& filter, double t_now) {
  // Only a recent static interval: if the rig moved since, wait for the next one.
  if (!static_result_ || !static_result_->usableAt(t_now)) return std::nullopt;
  filter.initialize(static_result_->navState());
  ROS_INFO("vi_ekf_slam: initialized from a %.1f s static interval (accel std %.3f m/s^2, gyro std %.4f rad/s)",
           params_.static_init.window_s, static_result_->accel_std_mps2, static_result_->gyro_std_radps);
  std::ostringstream e;
  e << "initialized: static, " << params_.static_init.window_s << " s at rest";
  first_image_t_.reset();
  if (dynamic_init_) dynamic_init_->reset();
  return e.str();
}

std::optional<std::string> FilterStart::tryDynamic(EkfSlam& filter, const CameraFrame& frame, double image_t,
                                                   std::string* waiting) {
  if (!first_image_t_) first_image_t_ = image_t;
  dynamic_init_->addFrame(frame);
  std::string why;
  const std::optional<DynamicInitResult> r = dynamic_init_->tryInitialize(&why);
  if (!r) {
    std::ostringstream w;
    w << "waiting to initialize: at rest for " << params_.static_init.window_s << " s, or moving: " << why;
    *waiting = w.str();
    return std::nullopt;
  }
  if (r->state.timestamp < filter.latestImuTime() - 1.0) return std::nullopt;  // the IMU no longer covers it
  const int added = filter.initialize(*r, r->state);
  dynamic_q_n_b_ = r->state.q_n_b;
  std::ostringstream e;
  e.precision(3);
  e << "initialized: dynamic, " << (image_t - *first_image_t_) << " s after the first image (" << r->frames
    << " images, " << r->features << " features, " << added << " landmarks, median depth " << r->median_depth_m
    << " m, scale sigma " << 100.0 * r->scale_sigma << "%, velocity sigma " << r->velocity_sigma_mps
    << " m/s, roll/pitch sigma " << r->tilt_sigma_rad << " rad, time offset "
    << params_.filter.camera_time_offset_s + r->time_offset_correction_s << " s)";
  ROS_INFO_STREAM("vi_ekf_slam: " << e.str());
  first_image_t_.reset();
  static_result_.reset();
  return e.str();
}

void FilterStart::reset() {
  static_init_.reset();
  static_result_.reset();
  if (dynamic_init_) dynamic_init_->reset();
  first_image_t_.reset();
}

}  // namespace vi_ekf_slam::glue
