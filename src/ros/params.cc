#include "vi_ekf_slam/ros/params.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace vi_ekf_slam::glue {

namespace {

std::optional<CompositionTrigger> triggerFromString(const std::string& s) {
  for (auto t : {CompositionTrigger::kNewLandmarks, CompositionTrigger::kEveryUpdate, CompositionTrigger::kNever}) {
    if (toString(t) == s) return t;
  }
  return std::nullopt;
}

/// Reads a parameter into value when set; a value of the wrong type is an error, not a silent
/// default.
class ParamReader {
 public:
  ParamReader(const ParamSource& src, std::ostringstream& err) : src_(src), err_(err) {}
  template <typename T>
  void operator()(const std::string& name, T& value) {
    if (!src_.has(name)) return;
    T v;
    if (src_.get(name, v))
      value = v;
    else
      err_ << name << " has the wrong type\n";
  }

 private:
  const ParamSource& src_;
  std::ostringstream& err_;
};

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

bool parseDouble(const std::string& s, double& v) {
  try {
    size_t used = 0;
    v = std::stod(s, &used);
    return used == s.size();
  } catch (const std::logic_error&) {
    return false;
  }
}

std::string detectorName(TrackerParams::Detector d) {
  return d == TrackerParams::Detector::kFast ? "fast" : "shi_tomasi";
}

/// The parameters shared with dynamic_reconfigure, in one place for both directions.
std::string fromReconfigure(const EkfSlamReconfigureConfig& c, NodeParams* p) {
  std::ostringstream err;
  EkfSlamConfig& f = p->filter;
  if (auto m = mechanizationFromString(c.mechanization))
    f.mechanization = *m;
  else
    err << "mechanization: unknown '" << c.mechanization << "'\n";
  if (auto t = triggerFromString(c.composition_trigger))
    f.composition_trigger = *t;
  else
    err << "composition_trigger: unknown '" << c.composition_trigger << "'\n";
  if (auto i = landmarkInitFromString(c.landmark_init))
    f.landmark_init = *i;
  else
    err << "landmark_init: unknown '" << c.landmark_init << "'\n";
  f.composition_new_landmarks = c.composition_new_landmarks;
  f.update.pixel_noise_px = c.pixel_noise_px;
  f.update.gate_probability = c.gate_probability;
  f.landmark_depth_m = c.landmark_depth_m;
  f.landmark_depth_sigma_m = c.landmark_depth_sigma_m;
  f.inverse_depth_initial_m = c.inverse_depth_initial_m;
  f.inverse_depth_sigma = c.inverse_depth_sigma;
  f.max_landmarks = c.max_landmarks;
  f.landmark_timeout_s = c.landmark_timeout_s;
  f.zero_velocity.enabled = c.zero_velocity;
  f.zero_velocity.window_s = c.zero_velocity_window_s;
  f.zero_velocity.max_parallax_px = c.zero_velocity_max_parallax_px;
  f.zero_velocity.velocity_sigma_mps = c.zero_velocity_sigma_mps;
  f.zero_velocity.rest_velocity_sigma_mps = c.zero_velocity_rest_sigma_mps;
  f.zero_velocity.min_features = c.zero_velocity_min_features;
  f.zero_velocity.gate_probability = c.zero_velocity_gate_probability;
  f.zero_velocity.defer_landmarks = c.zero_velocity_defer_landmarks;
  f.zero_velocity.moving_parallax_px = c.zero_velocity_moving_parallax_px;
  f.zero_velocity.still_accel_std_mps2 = c.zero_velocity_still_accel_std_mps2;
  f.zero_velocity.still_gyro_radps = c.zero_velocity_still_gyro_radps;
  f.imu_noise.accel_noise_density = c.accel_noise_density;
  f.imu_noise.gyro_noise_density = c.gyro_noise_density;
  f.imu_noise.accel_random_walk = c.accel_random_walk;
  f.imu_noise.gyro_random_walk = c.gyro_random_walk;
  TrackerParams& t = p->tracker;
  if (auto d = detectorFromString(c.detector))
    t.detector = *d;
  else
    err << "detector: unknown '" << c.detector << "'\n";
  t.max_tracks = c.max_tracks;
  t.min_distance_px = c.min_distance_px;
  t.quality_level = c.quality_level;
  t.fast_threshold = c.fast_threshold;
  t.klt_window_px = c.klt_window_px;
  t.klt_pyramid_levels = c.klt_pyramid_levels;
  t.fb_threshold_px = c.fb_threshold_px;
  t.ransac_threshold_px = c.ransac_threshold_px;
  t.redetect_fraction = c.redetect_fraction;
  err << f.validate() << t.validate();
  return err.str();
}

}  // namespace

bool NodeHandleParams::get(const std::string& name, double& v) const {
  if (nh_.getParam(name, v)) return true;
  int i;
  if (!nh_.getParam(name, i)) return false;
  v = i;  // an integer literal is a fine double
  return true;
}

YamlParams::YamlParams(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open parameter file '" + path + "'");
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    // Drop comments (not inside quotes: our files have no '#' in strings).
    const auto hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    line = trim(line);
    if (line.empty()) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos || colon == 0) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": expected `name: value`");
    }
    values_[trim(line.substr(0, colon))] = trim(line.substr(colon + 1));
  }
}

bool YamlParams::get(const std::string& name, double& v) const { return parseDouble(values_.at(name), v); }

bool YamlParams::get(const std::string& name, int& v) const {
  double d;
  if (!parseDouble(values_.at(name), d) || d != std::floor(d)) return false;
  v = static_cast<int>(d);
  return true;
}

bool YamlParams::get(const std::string& name, bool& v) const {
  const std::string& s = values_.at(name);
  if (s == "true" || s == "True")
    v = true;
  else if (s == "false" || s == "False")
    v = false;
  else
    return false;
  return true;
}

bool YamlParams::get(const std::string& name, std::string& v) const {
  std::string s = values_.at(name);
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) s = s.substr(1, s.size() - 2);
  v = s;
  return true;
}

bool YamlParams::get(const std::string& name, std::vector<double>& v) const {
  const std::string& s = values_.at(name);
  if (s.size() < 2 || s.front() != '[' || s.back() != ']') return false;
  std::stringstream ss(s.substr(1, s.size() - 2));
  std::string item;
  std::vector<double> out;
  while (std::getline(ss, item, ',')) {
    double d;
    if (!parseDouble(trim(item), d)) return false;
    out.push_back(d);
  }
  v = out;
  return true;
}

EkfSlamReconfigureConfig toReconfigure(const NodeParams& p) {
  EkfSlamReconfigureConfig c = EkfSlamReconfigureConfig::__getDefault__();
  const EkfSlamConfig& f = p.filter;
  c.mechanization = toString(f.mechanization);
  c.composition_trigger = toString(f.composition_trigger);
  c.landmark_init = toString(f.landmark_init);
  c.composition_new_landmarks = f.composition_new_landmarks;
  c.pixel_noise_px = f.update.pixel_noise_px;
  c.gate_probability = f.update.gate_probability;
  c.landmark_depth_m = f.landmark_depth_m;
  c.landmark_depth_sigma_m = f.landmark_depth_sigma_m;
  c.inverse_depth_initial_m = f.inverse_depth_initial_m;
  c.inverse_depth_sigma = f.inverse_depth_sigma;
  c.max_landmarks = f.max_landmarks;
  c.landmark_timeout_s = f.landmark_timeout_s;
  c.zero_velocity = f.zero_velocity.enabled;
  c.zero_velocity_window_s = f.zero_velocity.window_s;
  c.zero_velocity_max_parallax_px = f.zero_velocity.max_parallax_px;
  c.zero_velocity_sigma_mps = f.zero_velocity.velocity_sigma_mps;
  c.zero_velocity_rest_sigma_mps = f.zero_velocity.rest_velocity_sigma_mps;
  c.zero_velocity_min_features = f.zero_velocity.min_features;
  c.zero_velocity_gate_probability = f.zero_velocity.gate_probability;
  c.zero_velocity_defer_landmarks = f.zero_velocity.defer_landmarks;
  c.zero_velocity_moving_parallax_px = f.zero_velocity.moving_parallax_px;
  c.zero_velocity_still_accel_std_mps2 = f.zero_velocity.still_accel_std_mps2;
  c.zero_velocity_still_gyro_radps = f.zero_velocity.still_gyro_radps;
  c.accel_noise_density = f.imu_noise.accel_noise_density;
  c.gyro_noise_density = f.imu_noise.gyro_noise_density;
  c.accel_random_walk = f.imu_noise.accel_random_walk;
  c.gyro_random_walk = f.imu_noise.gyro_random_walk;
  const TrackerParams& t = p.tracker;
  c.detector = detectorName(t.detector);
  c.max_tracks = t.max_tracks;
  c.min_distance_px = t.min_distance_px;
  c.quality_level = t.quality_level;
  c.fast_threshold = t.fast_threshold;
  c.klt_window_px = t.klt_window_px;
  c.klt_pyramid_levels = t.klt_pyramid_levels;
  c.fb_threshold_px = t.fb_threshold_px;
  c.ransac_threshold_px = t.ransac_threshold_px;
  c.redetect_fraction = t.redetect_fraction;
  return c;
}

std::string applyReconfigure(const EkfSlamReconfigureConfig& c, NodeParams* p) {
  NodeParams candidate = *p;
  const std::string err = fromReconfigure(c, &candidate);
  if (err.empty()) *p = candidate;
  return err;
}

std::string loadParams(const ParamSource& source, NodeParams* out) {
  NodeParams p;
  std::ostringstream err;
  ParamReader rd(source, err);
  // Shared with dynamic_reconfigure: start from its defaults, overwrite with ~params.
  EkfSlamReconfigureConfig c = toReconfigure(p);
  rd("mechanization", c.mechanization);
  rd("composition_trigger", c.composition_trigger);
  rd("composition_new_landmarks", c.composition_new_landmarks);
  rd("pixel_noise_px", c.pixel_noise_px);
  rd("gate_probability", c.gate_probability);
  rd("landmark_init", c.landmark_init);
  rd("landmark_depth_m", c.landmark_depth_m);
  rd("landmark_depth_sigma_m", c.landmark_depth_sigma_m);
  rd("inverse_depth_initial_m", c.inverse_depth_initial_m);
  rd("inverse_depth_sigma", c.inverse_depth_sigma);
  rd("max_landmarks", c.max_landmarks);
  rd("landmark_timeout_s", c.landmark_timeout_s);
  rd("zero_velocity", c.zero_velocity);
  rd("zero_velocity_window_s", c.zero_velocity_window_s);
  rd("zero_velocity_max_parallax_px", c.zero_velocity_max_parallax_px);
  rd("zero_velocity_sigma_mps", c.zero_velocity_sigma_mps);
  rd("zero_velocity_rest_sigma_mps", c.zero_velocity_rest_sigma_mps);
  rd("zero_velocity_min_features", c.zero_velocity_min_features);
  rd("zero_velocity_gate_probability", c.zero_velocity_gate_probability);
  rd("zero_velocity_defer_landmarks", c.zero_velocity_defer_landmarks);
  rd("zero_velocity_moving_parallax_px", c.zero_velocity_moving_parallax_px);
  rd("zero_velocity_still_accel_std_mps2", c.zero_velocity_still_accel_std_mps2);
  rd("zero_velocity_still_gyro_radps", c.zero_velocity_still_gyro_radps);
  rd("accel_noise_density", c.accel_noise_density);
  rd("gyro_noise_density", c.gyro_noise_density);
  rd("accel_random_walk", c.accel_random_walk);
  rd("gyro_random_walk", c.gyro_random_walk);
  rd("detector", c.detector);
  rd("max_tracks", c.max_tracks);
  rd("min_distance_px", c.min_distance_px);
  rd("quality_level", c.quality_level);
  rd("fast_threshold", c.fast_threshold);
  rd("klt_window_px", c.klt_window_px);
  rd("klt_pyramid_levels", c.klt_pyramid_levels);
  rd("fb_threshold_px", c.fb_threshold_px);
  rd("ransac_threshold_px", c.ransac_threshold_px);
  rd("redetect_fraction", c.redetect_fraction);

  // Start-up only.
  EkfSlamConfig& f = p.filter;
  rd("gravity_mps2", f.gravity_mps2);
  rd("max_imu_gap_s", f.max_imu_gap_s);
  rd("initial_sigma_position_m", f.initial.position_m);
  rd("initial_sigma_velocity_mps", f.initial.velocity_mps);
  rd("initial_sigma_roll_pitch_rad", f.initial.roll_pitch_rad);
  rd("initial_sigma_yaw_rad", f.initial.yaw_rad);
  rd("initial_sigma_accel_bias_mps2", f.initial.accel_bias_mps2);
  rd("initial_sigma_gyro_bias_radps", f.initial.gyro_bias_radps);
  rd("lost_detection", f.divergence.enabled);
  rd("lost_max_speed_mps", f.divergence.max_speed_mps);
  rd("lost_max_rejected_fraction", f.divergence.max_rejected_fraction);
  rd("lost_window_s", f.divergence.window_s);
  rd("zero_velocity_moving_speed_mps", f.zero_velocity.moving_speed_mps);
  rd("camera_time_offset_s", f.camera_time_offset_s);
  rd("initial_sigma_time_offset_s", f.initial.time_offset_s);
  rd("max_image_width_px", p.tracker.max_image_width_px);
  rd("camera_readout_time_s", f.update.readout_time_s);
  rd("inverse_depth_scene_prior", f.inverse_depth_scene_prior);
  StaticInitParams& s = p.static_init;
  rd("static_window_s", s.window_s);
  rd("dynamic_init", p.dynamic_init_enabled);
  DynamicInitParams& di = p.dynamic_init;
  rd("dynamic_init_window_s", di.window_s);
  rd("dynamic_init_max_velocity_sigma_mps", di.max_velocity_sigma_mps);
  rd("dynamic_init_max_tilt_sigma_rad", di.max_tilt_sigma_rad);
  rd("dynamic_init_gyro_bias_sigma_radps", di.gyro_bias_sigma_radps);
  rd("static_max_accel_std_mps2", s.max_accel_std_mps2);
  rd("static_max_gyro_std_radps", s.max_gyro_std_radps);
  s.gravity_mps2 = f.gravity_mps2;
  di.gravity_mps2 = f.gravity_mps2;
  di.pixel_noise_px = f.update.pixel_noise_px;
  NodeOptions& n = p.node;
  std::string publish_tf = toString(n.publish_tf);
  rd("publish_tf", publish_tf);
  if (auto m = tfModeFromString(publish_tf)) {
    n.publish_tf = *m;
  } else {
    err << "publish_tf must be 'odom', 'none' or 'world' (got '" << publish_tf << "')\n";
  }
  rd("odom_frame", n.odom_frame);
  rd("base_frame", n.base_frame);
  rd("map_frame", n.map_frame);
  rd("world_frame", n.world_frame);
  rd("body_frame", n.body_frame);
  rd("tune_allocator", n.tune_allocator);
  rd("camera_calibration_file", n.camera_calibration_file);
  rd("extrinsic_source", n.extrinsic_source);
  rd("T_b_c", n.T_b_c);
  rd("max_image_queue", n.max_image_queue);
  rd("time_jump_reset_s", n.time_jump_reset_s);
  rd("path_max_length", n.path_max_length);
  rd("max_image_gap_s", n.max_image_gap_s);

  err << fromReconfigure(c, &p);
  if (n.world_frame.empty()) err << "world_frame must not be empty\n";
  if (n.world_frame == n.body_frame) err << "world_frame and body_frame must differ\n";
  if (n.odom_frame.empty()) err << "odom_frame must not be empty\n";
  if (n.odom_frame == n.base_frame || n.odom_frame == n.body_frame) {
    err << "odom_frame must differ from base_frame and body_frame\n";
  }
  if (!n.map_frame.empty() && n.map_frame == n.odom_frame) err << "map_frame and odom_frame must differ\n";
  if (n.extrinsic_source != "tf" && n.extrinsic_source != "parameters") {
    err << "extrinsic_source must be 'tf' or 'parameters' (got '" << n.extrinsic_source << "')\n";
  }
  if (n.T_b_c.size() != 7) {
    err << "T_b_c must have 7 numbers: x y z qx qy qz qw (got " << n.T_b_c.size() << ")\n";
  } else {
    const double qn = std::sqrt(n.T_b_c[3] * n.T_b_c[3] + n.T_b_c[4] * n.T_b_c[4] + n.T_b_c[5] * n.T_b_c[5] +
                                n.T_b_c[6] * n.T_b_c[6]);
    if (!(std::abs(qn - 1.0) < 1e-3)) err << "T_b_c quaternion must have unit norm (got " << qn << ")\n";
  }
  if (n.max_image_queue < 1) err << "max_image_queue must be >= 1\n";
  if (!(n.time_jump_reset_s > 0.0)) err << "time_jump_reset_s must be > 0 s\n";
  if (n.path_max_length < 1) err << "path_max_length must be >= 1\n";
  if (!(n.max_image_gap_s > 0.0)) err << "max_image_gap_s must be > 0 [s]\n";
  if (!(s.window_s > 0.05)) err << "static_window_s must be > 0.05 s\n";
  err << di.validate();
  if (!(s.max_accel_std_mps2 > 0.0) || !(s.max_gyro_std_radps > 0.0)) {
    err << "static_max_accel_std_mps2 and static_max_gyro_std_radps must be > 0\n";
  }
  *out = p;
  return err.str();
}

std::string describeParams(const NodeParams& p) {
  std::ostringstream s;
  const EkfSlamConfig& f = p.filter;
  const TrackerParams& t = p.tracker;
  const NodeOptions& n = p.node;
  s << "vi_ekf_slam parameters:\n"
    << "  frames: publish_tf=" << toString(n.publish_tf) << " odom_frame=" << n.odom_frame
    << " base_frame=" << (n.base_frame.empty() ? "(the IMU frame)" : n.base_frame)
    << " map_frame=" << (n.map_frame.empty() ? "(none)" : n.map_frame) << " world_frame=" << n.world_frame
    << " body_frame=" << (n.body_frame.empty() ? "(the IMU messages' frame_id)" : n.body_frame)
    << " tune_allocator=" << n.tune_allocator << "\n"
    << "  mechanization=" << toString(f.mechanization) << " composition_trigger=" << toString(f.composition_trigger)
    << " composition_new_landmarks=" << f.composition_new_landmarks << "\n"
    << "  landmark_init=" << toString(f.landmark_init) << " landmark_depth_m=" << f.landmark_depth_m
    << " [m] landmark_depth_sigma_m=" << f.landmark_depth_sigma_m
    << " [m] inverse_depth_initial_m=" << f.inverse_depth_initial_m
    << " [m] inverse_depth_sigma=" << f.inverse_depth_sigma
    << " [1/m] inverse_depth_scene_prior=" << f.inverse_depth_scene_prior << "\n"
    << "  max_landmarks=" << f.max_landmarks << " landmark_timeout_s=" << f.landmark_timeout_s
    << " [s] pixel_noise_px=" << f.update.pixel_noise_px << " [px] gate_probability=" << f.update.gate_probability
    << "\n"
    << "  zero velocity: " << (f.zero_velocity.enabled ? "on" : "off") << ", window " << f.zero_velocity.window_s
    << " [s], parallax < " << f.zero_velocity.max_parallax_px << " [px] over >= " << f.zero_velocity.min_features
    << " features, sigma " << f.zero_velocity.velocity_sigma_mps << " [m/s] (at rest "
    << f.zero_velocity.rest_velocity_sigma_mps << " [m/s]), gate " << f.zero_velocity.gate_probability
    << ", new landmarks " << (f.zero_velocity.defer_landmarks ? "wait until the rig is seen moving" : "enter at once")
    << " (moving: parallax >= " << f.zero_velocity.moving_parallax_px
    << " [px], before the first window speed >= " << f.zero_velocity.moving_speed_mps
    << " [m/s] by 2 sigma; at rest: accel std < " << f.zero_velocity.still_accel_std_mps2 << " [m/s^2], gyro < "
    << f.zero_velocity.still_gyro_radps << " [rad/s])\n"
    << "  imu noise: accel " << f.imu_noise.accel_noise_density << " [m/s^2/sqrt(Hz)], gyro "
    << f.imu_noise.gyro_noise_density << " [rad/s/sqrt(Hz)], accel walk " << f.imu_noise.accel_random_walk
    << " [m/s^3/sqrt(Hz)], gyro walk " << f.imu_noise.gyro_random_walk << " [rad/s^2/sqrt(Hz)]\n"
    << "  gravity_mps2=" << f.gravity_mps2 << " max_imu_gap_s=" << f.max_imu_gap_s << " [s]\n"
    << "  initial sigmas: position " << f.initial.position_m << " [m], velocity " << f.initial.velocity_mps
    << " [m/s], roll/pitch " << f.initial.roll_pitch_rad << " [rad], yaw " << f.initial.yaw_rad << " [rad], accel bias "
    << f.initial.accel_bias_mps2 << " [m/s^2], gyro bias " << f.initial.gyro_bias_radps << " [rad/s], time offset "
    << f.initial.time_offset_s << " [s]\n"
    << "  lost detection: " << (f.divergence.enabled ? "on" : "off") << ", speed > " << f.divergence.max_speed_mps
    << " [m/s] or more than " << f.divergence.max_rejected_fraction << " of the observations rejected, for "
    << f.divergence.window_s << " [s]\n"
    << "  static init: window " << p.static_init.window_s << " [s], accel std < " << p.static_init.max_accel_std_mps2
    << " [m/s^2], gyro std < " << p.static_init.max_gyro_std_radps << " [rad/s]\n"
    << "  dynamic init: " << (p.dynamic_init_enabled ? "on" : "off") << ", window " << p.dynamic_init.window_s
    << " [s], velocity sigma <= " << p.dynamic_init.max_velocity_sigma_mps
    << " [m/s], roll/pitch sigma <= " << p.dynamic_init.max_tilt_sigma_rad << " [rad], gyro bias sigma "
    << p.dynamic_init.gyro_bias_sigma_radps << " [rad/s]\n"
    << "  tracker: detector=" << detectorName(t.detector) << " max_tracks=" << t.max_tracks
    << " min_distance_px=" << t.min_distance_px << " quality_level=" << t.quality_level
    << " fast_threshold=" << t.fast_threshold << " klt_window_px=" << t.klt_window_px
    << " klt_pyramid_levels=" << t.klt_pyramid_levels << " fb_threshold_px=" << t.fb_threshold_px
    << " ransac_threshold_px=" << t.ransac_threshold_px << " redetect_fraction=" << t.redetect_fraction
    << " max_image_width_px=" << t.max_image_width_px << " [px]\n"
    << "  camera: time_offset " << f.camera_time_offset_s << " [s] (t_imu = t_image + offset), readout time "
    << f.update.readout_time_s << " [s] (0: global shutter), calibration_file='" << n.camera_calibration_file
    << "', extrinsic_source=" << n.extrinsic_source << "\n"
    << "  sync: max_image_queue=" << n.max_image_queue << " time_jump_reset_s=" << n.time_jump_reset_s
    << " [s] path_max_length=" << n.path_max_length << " max_image_gap_s=" << n.max_image_gap_s << " [s]";
  if (n.extrinsic_source == "parameters" && n.T_b_c.size() == 7) {
    s << "\n  T_b_c (x y z qx qy qz qw) = ";
    for (double v : n.T_b_c) s << v << " ";
  }
  return s.str();
}

}  // namespace vi_ekf_slam::glue
