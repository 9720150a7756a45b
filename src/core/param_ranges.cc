#include "vi_ekf_slam/core/param_ranges.h"

#include <cmath>
#include <map>
#include <stdexcept>

namespace vi_ekf_slam {

namespace {

const std::map<std::string, ParamRange>& table() {
  static const std::map<std::string, ParamRange> t = {
      // camera and update [s, px, probability]
      {"camera_time_offset_s", {-1.0, 1.0}},
      {"camera_readout_time_s", {0.0, 0.1}},
      {"pixel_noise_px", {0.1, 10.0}},
      {"gate_probability", {0.5, 0.9999}},
      {"clean_gate_probability", {0.5, 0.999999}},
      {"clean_gate_s", {0.0, 1e6}},
      {"update_iterations", {1, 20}},
      // map [count, m, 1/m, s]
      {"composition_new_landmarks", {0, 100}},
      {"landmark_depth_m", {0.5, 100.0}},
      {"landmark_depth_sigma_m", {0.1, 100.0}},
      {"inverse_depth_initial_m", {0.5, 100.0}},
      {"inverse_depth_sigma", {0.01, 2.0}},
      {"triangulation_max_relative_depth_sigma", {0.01, 1.0}},
      {"triangulation_clone_interval_s", {0.0, 1.0}},
      {"triangulation_max_wait_s", {0.0, 10.0}},
      {"triangulation_min_depth_m", {0.01, 5.0}},
      {"triangulation_min_map_landmarks", {0, 1000}},
      {"triangulation_starved_max_wait_s", {0.0, 10.0}},
      {"max_landmarks", {1, 1000}},
      {"landmark_timeout_s", {-1.0, 60.0}},
      {"map_max_dormant_landmarks", {0, 1000}},
      {"map_max_descriptor_distance_bits", {0, 256}},
      {"map_dormant_spacing_m", {0.05, 100.0}},
      {"map_max_relative_sigma", {0.001, 10.0}},
      {"map_min_joint_revisits", {1, 100}},
      {"map_revisit_confirm_frames", {1, 100}},
      {"map_descriptor_ratio", {0.1, 1.0}},
      {"map_search_gate_probability", {0.5, 0.999999}},
      {"map_max_search_sigma_px", {1.0, 1000.0}},
      {"map_max_kept_points", {0, 100000}},
      {"map_relocalize_min_inliers", {4, 1000}},
      {"map_relocalize_reprojection_px", {0.1, 50.0}},
      {"map_relocalize_max_tilt_deg", {0.1, 90.0}},
      // standing [s, m/s, px, count, probability, m/s^2, rad/s]
      {"zero_velocity_window_s", {0.1, 5.0}},
      {"zero_velocity_sigma_mps", {0.001, 1.0}},
      {"zero_velocity_rest_sigma_mps", {0.001, 1.0}},
      {"zero_velocity_max_parallax_px", {0.1, 50.0}},
      {"zero_velocity_min_features", {3, 500}},
      {"zero_velocity_gate_probability", {0.5, 0.999999}},
      {"zero_velocity_moving_parallax_px", {0.1, 100.0}},
      {"zero_velocity_moving_speed_mps", {0.01, 10.0}},
      {"zero_velocity_still_accel_std_mps2", {0.001, 10.0}},
      {"zero_velocity_still_gyro_radps", {0.0001, 10.0}},
      {"zero_velocity_still_window_s", {0.01, 10.0}},
      // blind [s, m/s, probability]
      {"blind_motion_prior_window_s", {0.5, 600.0}},
      {"blind_motion_prior_min_seen_s", {0.0, 600.0}},
      {"blind_motion_prior_min_sigma_mps", {0.001, 10.0}},
      {"blind_motion_prior_gate_probability", {0.5, 0.999999}},
      // IMU [m/s^2/sqrt(Hz), rad/s/sqrt(Hz), m/s^3/sqrt(Hz), rad/s^2/sqrt(Hz), m/s^2, s, count]
      {"accel_noise_density", {1e-6, 1.0}},
      {"gyro_noise_density", {1e-7, 0.1}},
      {"accel_random_walk", {0.0, 1.0}},
      {"gyro_random_walk", {0.0, 0.1}},
      {"gravity_mps2", {9.7, 9.9}},
      {"max_imu_gap_s", {0.001, 10.0}},
      {"imu_gap_accel_sigma_mps2", {0.0, 100.0}},
      {"imu_gap_gyro_sigma_radps", {0.0, 10.0}},
      {"imu_buffer_max", {10, 1e7}},
      {"imu_accel_range_mps2", {0.0, 10000.0}},
      {"imu_gyro_range_radps", {0.0, 1000.0}},
      {"imu_max_accel_step_mps2", {0.0, 10000.0}},
      {"imu_max_gyro_step_radps", {0.0, 1000.0}},
      {"imu_max_bridged_samples", {0, 100}},
      // initialization [s, m/s, rad, ratio, rad/s, m/s^2, count, m, px]
      {"dynamic_init_window_s", {0.2, 10.0}},
      {"dynamic_init_max_window_s", {0.2, 10.0}},
      {"blind_reanchor_max_wait_s", {0.0, 30.0}},
      {"dynamic_init_min_frames", {3, 1000}},
      {"dynamic_init_min_observations", {3, 1000}},
      {"dynamic_init_min_features", {6, 10000}},
      {"dynamic_init_max_velocity_sigma_mps", {0.001, 10.0}},
      {"dynamic_init_max_scale_sigma", {0.01, 10.0}},
      {"dynamic_init_max_tilt_sigma_rad", {0.001, 1.0}},
      {"dynamic_init_gyro_bias_sigma_radps", {1e-6, 1.0}},
      {"dynamic_init_accel_bias_sigma_mps2", {0.0, 1.0}},
      {"static_window_s", {0.1, 60.0}},
      {"static_max_accel_std_mps2", {1e-4, 10.0}},
      {"static_max_gyro_std_radps", {1e-5, 10.0}},
      {"initial_sigma_position_m", {0.0, 100.0}},
      {"initial_sigma_velocity_mps", {1e-4, 10.0}},
      {"initial_sigma_roll_pitch_rad", {0.0, 1.0}},
      {"initial_sigma_yaw_rad", {0.0, 3.2}},
      {"initial_sigma_accel_bias_mps2", {1e-5, 1.0}},
      {"initial_sigma_gyro_bias_radps", {1e-6, 0.5}},
      {"initial_sigma_time_offset_s", {0.0, 0.5}},
      {"initial_sigma_extrinsic_rotation_rad", {1e-4, 0.5}},
      {"initial_sigma_extrinsic_translation_m", {1e-4, 0.5}},
      // lost detection [m/s, ratio, s, count]
      {"lost_max_speed_mps", {0.1, 1000.0}},
      {"lost_max_rejected_fraction", {0.01, 1.0}},
      {"lost_window_s", {0.1, 60.0}},
      {"lost_min_observations", {1, 1e6}},
      // tracker [count, px, ratio]
      {"max_tracks", {8, 1000}},
      {"min_distance_px", {1.0, 100.0}},
      {"quality_level", {0.0001, 0.5}},
      {"fast_threshold", {1, 200}},
      {"min_corner_snr", {0.0, 100.0}},
      {"klt_window_px", {5, 51}},
      {"klt_pyramid_levels", {0, 6}},
      {"fb_threshold_px", {0.05, 10.0}},
      {"ransac_threshold_px", {0.1, 10.0}},
      {"redetect_fraction", {0.05, 1.0}},
      {"max_image_width_px", {0, 10000}},
      {"tracker_grid_cells", {1, 100}},
      {"tracker_border_px", {0, 1000}},
  };
  return t;
}

}  // namespace

bool hasParamRange(const std::string& name) { return table().count(name) > 0; }

const ParamRange& paramRange(const std::string& name) {
  const auto it = table().find(name);
  if (it == table().end()) throw std::out_of_range("no range for parameter '" + name + "'");
  return it->second;
}

void checkRange(std::ostream& err, const std::string& name, double v) {
  const ParamRange& r = paramRange(name);
  if (!r.contains(v)) err << name << " must be in [" << r.min << ", " << r.max << "] (got " << v << ")\n";
}

}  // namespace vi_ekf_slam
