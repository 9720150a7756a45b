#include "vi_ekf_slam/core/ekf_slam_config.h"

#include <cmath>
#include <sstream>

namespace vi_ekf_slam {

std::string toString(CompositionTrigger t) {
  switch (t) {
    case CompositionTrigger::kNewLandmarks:
      return "new_landmarks";
    case CompositionTrigger::kEveryUpdate:
      return "every_update";
    case CompositionTrigger::kNever:
      return "never";
  }
  return "unknown";
}

std::string toString(LandmarkInitMethod m) {
  switch (m) {
    case LandmarkInitMethod::kFixedDepth:
      return "fixed_depth";
    case LandmarkInitMethod::kInverseDepth:
      return "inverse_depth";
  }
  return "unknown";
}

std::optional<LandmarkInitMethod> landmarkInitFromString(const std::string& s) {
  for (auto m : {LandmarkInitMethod::kFixedDepth, LandmarkInitMethod::kInverseDepth}) {
    if (toString(m) == s) return m;
  }
  return std::nullopt;
}

namespace {
void requirePositive(std::ostringstream& err, const char* name, double v) {
  if (!std::isfinite(v) || v <= 0.0) err << name << " must be > 0 (got " << v << ")\n";
}
void requireNonNegative(std::ostringstream& err, const char* name, double v) {
  if (!std::isfinite(v) || v < 0.0) err << name << " must be >= 0 (got " << v << ")\n";
}
}  // namespace

std::string EkfSlamConfig::validate() const {
  std::ostringstream err;
  requirePositive(err, "imu_noise.accel_noise_density [m/s^2/sqrt(Hz)]", imu_noise.accel_noise_density);
  requirePositive(err, "imu_noise.gyro_noise_density [rad/s/sqrt(Hz)]", imu_noise.gyro_noise_density);
  requireNonNegative(err, "imu_noise.accel_random_walk [m/s^3/sqrt(Hz)]", imu_noise.accel_random_walk);
  requireNonNegative(err, "imu_noise.gyro_random_walk [rad/s^2/sqrt(Hz)]", imu_noise.gyro_random_walk);
  if (!std::isfinite(gravity_mps2) || gravity_mps2 < 9.7 || gravity_mps2 > 9.9) {
    err << "gravity_mps2 must be in [9.7, 9.9] (got " << gravity_mps2 << ")\n";
  }
  requirePositive(err, "update.pixel_noise_px [px]", update.pixel_noise_px);
  if (!(update.readout_time_s >= 0.0 && update.readout_time_s <= 0.1)) {
    err << "update.readout_time_s [s] must be in [0, 0.1] (got " << update.readout_time_s << ")\n";
  }
  if (update.iterations < 1 || update.iterations > 20) {
    err << "update.iterations must be in [1, 20] (got " << update.iterations << ")\n";
  }
  if (!(update.gate_probability > 0.0 && update.gate_probability < 1.0)) {
    err << "update.gate_probability must be in (0, 1) (got " << update.gate_probability << ")\n";
  }
  if (!(update.clean_gate_probability > 0.0 && update.clean_gate_probability < 1.0)) {
    err << "update.clean_gate_probability must be in (0, 1) (got " << update.clean_gate_probability << ")\n";
  }
  requireNonNegative(err, "update.clean_gate_s [s]", update.clean_gate_s);
  requirePositive(err, "landmark_depth_m [m]", landmark_depth_m);
  requirePositive(err, "landmark_depth_sigma_m [m]", landmark_depth_sigma_m);
  requirePositive(err, "inverse_depth_initial_m [m]", inverse_depth_initial_m);
  requirePositive(err, "inverse_depth_sigma [1/m]", inverse_depth_sigma);
  requirePositive(err, "triangulation.max_relative_depth_sigma", triangulation.max_relative_depth_sigma);
  requireNonNegative(err, "triangulation.clone_interval_s [s]", triangulation.clone_interval_s);
  requireNonNegative(err, "triangulation.max_wait_s [s]", triangulation.max_wait_s);
  requirePositive(err, "triangulation.min_depth_m [m]", triangulation.min_depth_m);
  if (triangulation.min_map_landmarks < 0) err << "triangulation.min_map_landmarks must be >= 0\n";
  requireNonNegative(err, "triangulation.starved_max_wait_s [s]", triangulation.starved_max_wait_s);
  if (max_landmarks < 1) err << "max_landmarks must be >= 1 (got " << max_landmarks << ")\n";
  if (composition_new_landmarks < 0) err << "composition_new_landmarks must be >= 0\n";
  if (!std::isfinite(landmark_timeout_s)) err << "landmark_timeout_s must be finite (use < 0 for never)\n";
  requirePositive(err, "max_imu_gap_s [s]", max_imu_gap_s);
  requireNonNegative(err, "imu_gap_accel_sigma_mps2 [m/s^2]", imu_gap_accel_sigma_mps2);
  requireNonNegative(err, "imu_gap_gyro_sigma_radps [rad/s]", imu_gap_gyro_sigma_radps);
  if (imu_buffer_max < 10) err << "imu_buffer_max must be >= 10\n";
  requireNonNegative(err, "initial.position_m [m]", initial.position_m);
  requirePositive(err, "initial.velocity_mps [m/s]", initial.velocity_mps);
  requireNonNegative(err, "initial.roll_pitch_rad [rad]", initial.roll_pitch_rad);
  requireNonNegative(err, "initial.yaw_rad [rad]", initial.yaw_rad);
  requirePositive(err, "initial.accel_bias_mps2 [m/s^2]", initial.accel_bias_mps2);
  requirePositive(err, "initial.gyro_bias_radps [rad/s]", initial.gyro_bias_radps);
  if (!std::isfinite(camera_time_offset_s) || std::abs(camera_time_offset_s) > 1.0) {
    err << "camera_time_offset_s [s] must be within [-1, 1] (got " << camera_time_offset_s << ")\n";
  }
  if (!std::isfinite(initial.time_offset_s) || initial.time_offset_s < 0.0 || initial.time_offset_s > 0.5) {
    err << "initial.time_offset_s [s] must be within [0, 0.5] (got " << initial.time_offset_s << ")\n";
  }
  requirePositive(err, "zero_velocity.window_s [s]", zero_velocity.window_s);
  requirePositive(err, "zero_velocity.still_window_s [s]", zero_velocity.still_window_s);
  requirePositive(err, "zero_velocity.still_accel_std_mps2 [m/s^2]", zero_velocity.still_accel_std_mps2);
  requirePositive(err, "zero_velocity.still_gyro_radps [rad/s]", zero_velocity.still_gyro_radps);
  requirePositive(err, "zero_velocity.max_parallax_px [px]", zero_velocity.max_parallax_px);
  if (!(zero_velocity.moving_speed_mps > 0.0)) {
    err << "zero_velocity.moving_speed_mps [m/s] must be > 0 (got " << zero_velocity.moving_speed_mps << ")\n";
  }
  if (!(zero_velocity.moving_parallax_px >= zero_velocity.max_parallax_px)) {
    err << "zero_velocity.moving_parallax_px [px] must be >= max_parallax_px (got " << zero_velocity.moving_parallax_px
        << ")\n";
  }
  if (zero_velocity.min_features < 3) err << "zero_velocity.min_features must be >= 3\n";
  requirePositive(err, "zero_velocity.velocity_sigma_mps [m/s]", zero_velocity.velocity_sigma_mps);
  requirePositive(err, "zero_velocity.rest_velocity_sigma_mps [m/s]", zero_velocity.rest_velocity_sigma_mps);
  if (!(zero_velocity.gate_probability > 0.0 && zero_velocity.gate_probability < 1.0)) {
    err << "zero_velocity.gate_probability must be in (0, 1) (got " << zero_velocity.gate_probability << ")\n";
  }
  err << divergence.validate();
  return err.str();
}

}  // namespace vi_ekf_slam
