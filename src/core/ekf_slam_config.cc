#include "vi_ekf_slam/core/ekf_slam_config.h"

#include "vi_ekf_slam/core/param_ranges.h"

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

std::string EkfSlamConfig::validate() const {
  std::ostringstream err;
  checkRange(err, "accel_noise_density", imu_noise.accel_noise_density);
  checkRange(err, "gyro_noise_density", imu_noise.gyro_noise_density);
  checkRange(err, "accel_random_walk", imu_noise.accel_random_walk);
  checkRange(err, "gyro_random_walk", imu_noise.gyro_random_walk);
  checkRange(err, "gravity_mps2", gravity_mps2);
  checkRange(err, "pixel_noise_px", update.pixel_noise_px);
  checkRange(err, "camera_readout_time_s", update.readout_time_s);
  checkRange(err, "update_iterations", update.iterations);
  checkRange(err, "gate_probability", update.gate_probability);
  checkRange(err, "clean_gate_probability", update.clean_gate_probability);
  checkRange(err, "clean_gate_s", update.clean_gate_s);
  checkRange(err, "landmark_depth_m", landmark_depth_m);
  checkRange(err, "landmark_depth_sigma_m", landmark_depth_sigma_m);
  checkRange(err, "inverse_depth_initial_m", inverse_depth_initial_m);
  checkRange(err, "inverse_depth_sigma", inverse_depth_sigma);
  checkRange(err, "triangulation_max_relative_depth_sigma", triangulation.max_relative_depth_sigma);
  checkRange(err, "triangulation_clone_interval_s", triangulation.clone_interval_s);
  checkRange(err, "triangulation_max_wait_s", triangulation.max_wait_s);
  checkRange(err, "triangulation_min_depth_m", triangulation.min_depth_m);
  checkRange(err, "triangulation_min_map_landmarks", triangulation.min_map_landmarks);
  checkRange(err, "triangulation_starved_max_wait_s", triangulation.starved_max_wait_s);
  checkRange(err, "max_landmarks", max_landmarks);
  checkRange(err, "composition_new_landmarks", composition_new_landmarks);
  checkRange(err, "landmark_timeout_s", landmark_timeout_s);
  checkRange(err, "map_max_dormant_landmarks", map.max_dormant);
  checkRange(err, "map_max_descriptor_distance_bits", map.max_descriptor_distance);
  checkRange(err, "map_dormant_spacing_m", map.dormant_spacing_m);
  checkRange(err, "map_max_relative_sigma", map.max_relative_sigma);
  checkRange(err, "map_min_joint_revisits", map.min_joint_revisits);
  checkRange(err, "map_revisit_confirm_frames", map.revisit_confirm_frames);
  checkRange(err, "map_descriptor_ratio", map.descriptor_ratio);
  checkRange(err, "map_search_gate_probability", map.search_gate_probability);
  checkRange(err, "map_max_search_sigma_px", map.max_search_sigma_px);
  checkRange(err, "map_max_kept_points", map.max_kept_points);
  checkRange(err, "map_relocalize_min_inliers", map.relocalize_min_inliers);
  checkRange(err, "map_relocalize_reprojection_px", map.relocalize_reprojection_px);
  checkRange(err, "map_relocalize_max_tilt_deg", map.relocalize_max_tilt_deg);
  checkRange(err, "max_imu_gap_s", max_imu_gap_s);
  err << imu_check.validate();
  checkRange(err, "imu_gap_accel_sigma_mps2", imu_gap_accel_sigma_mps2);
  checkRange(err, "imu_gap_gyro_sigma_radps", imu_gap_gyro_sigma_radps);
  checkRange(err, "imu_buffer_max", imu_buffer_max);
  checkRange(err, "initial_sigma_position_m", initial.position_m);
  checkRange(err, "initial_sigma_velocity_mps", initial.velocity_mps);
  checkRange(err, "initial_sigma_roll_pitch_rad", initial.roll_pitch_rad);
  checkRange(err, "initial_sigma_yaw_rad", initial.yaw_rad);
  checkRange(err, "initial_sigma_accel_bias_mps2", initial.accel_bias_mps2);
  checkRange(err, "initial_sigma_gyro_bias_radps", initial.gyro_bias_radps);
  checkRange(err, "initial_sigma_time_offset_s", initial.time_offset_s);
  checkRange(err, "initial_sigma_extrinsic_rotation_rad", initial.extrinsic_rotation_rad);
  checkRange(err, "initial_sigma_extrinsic_translation_m", initial.extrinsic_translation_m);
  checkRange(err, "camera_time_offset_s", camera_time_offset_s);
  checkRange(err, "zero_velocity_window_s", zero_velocity.window_s);
  checkRange(err, "zero_velocity_still_window_s", zero_velocity.still_window_s);
  checkRange(err, "zero_velocity_still_accel_std_mps2", zero_velocity.still_accel_std_mps2);
  checkRange(err, "zero_velocity_still_gyro_radps", zero_velocity.still_gyro_radps);
  checkRange(err, "zero_velocity_max_parallax_px", zero_velocity.max_parallax_px);
  checkRange(err, "zero_velocity_moving_speed_mps", zero_velocity.moving_speed_mps);
  checkRange(err, "zero_velocity_moving_parallax_px", zero_velocity.moving_parallax_px);
  if (!(zero_velocity.moving_parallax_px >= zero_velocity.max_parallax_px)) {
    err << "zero_velocity_moving_parallax_px must be >= zero_velocity_max_parallax_px (got "
        << zero_velocity.moving_parallax_px << " < " << zero_velocity.max_parallax_px << ")\n";
  }
  checkRange(err, "zero_velocity_min_features", zero_velocity.min_features);
  checkRange(err, "zero_velocity_sigma_mps", zero_velocity.velocity_sigma_mps);
  checkRange(err, "zero_velocity_rest_sigma_mps", zero_velocity.rest_velocity_sigma_mps);
  checkRange(err, "zero_velocity_gate_probability", zero_velocity.gate_probability);
  checkRange(err, "blind_motion_prior_window_s", blind_motion.window_s);
  checkRange(err, "blind_motion_prior_min_seen_s", blind_motion.min_seen_s);
  checkRange(err, "blind_motion_prior_min_sigma_mps", blind_motion.min_sigma_mps);
  checkRange(err, "blind_motion_prior_gate_probability", blind_motion.gate_probability);
  err << divergence.validate();
  return err.str();
}

}  // namespace vi_ekf_slam
