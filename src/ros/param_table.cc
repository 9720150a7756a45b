#include "vi_ekf_slam/ros/param_table.h"

#include "vi_ekf_slam/core/param_ranges.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <type_traits>
#include <sstream>

namespace vi_ekf_slam::glue {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string toString(TrackerParams::Detector d) { return d == TrackerParams::Detector::kFast ? "fast" : "shi_tomasi"; }

/// The member a parameter is stored in.
#define VI_FIELD(expr) \
  [](NodeParams & p) -> auto& { return expr; }

/// A parameter stored as is (bool, int, double, string, list of doubles).
template <typename Ref>
ParamSpec field(std::string name, std::string group, Ref ref, std::string unit, std::string description,
                bool dynamic = false, double min = -kInf, double max = kInf) {
  using T = std::remove_reference_t<decltype(ref(std::declval<NodeParams&>()))>;
  ParamSpec s;
  s.name = std::move(name);
  s.group = std::move(group);
  s.unit = std::move(unit);
  s.description = std::move(description);
  s.dynamic = dynamic;
  // The core's parameters have their range in the core (param_ranges.h), written once there.
  if (hasParamRange(s.name)) {
    s.min = paramRange(s.name).min;
    s.max = paramRange(s.name).max;
  } else {
    s.min = min;
    s.max = max;
  }
  // Reading through the accessor does not modify the parameters.
  s.get = [ref](const NodeParams& p) { return ParamValue(T(ref(const_cast<NodeParams&>(p)))); };
  s.set = [ref](NodeParams& p, const ParamValue& v) { ref(p) = std::get<T>(v); };
  return s;
}

/// A parameter with fixed choices, stored as an enum: toString and fromString convert.
template <typename Ref, typename E>
ParamSpec choice(std::string name, std::string group, Ref ref, std::string description, bool dynamic,
                 std::vector<std::pair<E, std::string>> values) {
  ParamSpec s;
  s.name = std::move(name);
  s.group = std::move(group);
  s.description = std::move(description);
  s.dynamic = dynamic;
  for (const auto& [e, meaning] : values) s.choices.emplace_back(toString(e), meaning);
  s.get = [ref](const NodeParams& p) { return ParamValue(toString(ref(const_cast<NodeParams&>(p)))); };
  s.set = [ref, values](NodeParams& p, const ParamValue& v) {
    for (const auto& [e, meaning] : values) {
      if (toString(e) == std::get<std::string>(v)) ref(p) = e;
    }
  };
  return s;
}

/// A string parameter with fixed choices, stored as the string.
template <typename Ref>
ParamSpec stringChoice(std::string name, std::string group, Ref ref, std::string description,
                       std::vector<std::pair<std::string, std::string>> values) {
  ParamSpec s = field(std::move(name), std::move(group), ref, "", std::move(description));
  s.choices = std::move(values);
  return s;
}

const std::string kDynHelp = "rosrun dynamic_reconfigure dynparam set /vi_ekf_slam/filter NAME VALUE";

std::vector<ParamSpec> makeTable() {
  using M = Mechanization;
  using C = CompositionTrigger;
  using L = LandmarkInitMethod;
  using D = TrackerParams::Detector;
  const bool dyn = true;
  return {
      // --- topics
      field("imu_topic", "topics", VI_FIELD(p.node.imu_topic), "",
            "sensor_msgs/Imu (the default follows a remap imu:=YOUR_TOPIC)"),
      field("image_topic", "topics", VI_FIELD(p.node.image_topic), "",
            "image_transport base topic, sensor_msgs/Image or <topic>/compressed (the default follows a remap "
            "image:=YOUR_TOPIC)"),
      field("camera_info_topic", "topics", VI_FIELD(p.node.camera_info_topic), "",
            "sensor_msgs/CameraInfo, optional when the intrinsics come from a file (the default follows a "
            "remap camera_info:=YOUR_TOPIC)"),
      // --- frames
      choice("publish_tf", "frames", VI_FIELD(p.node.publish_tf),
             "which TF the node broadcasts, and the frames of its outputs", false,
             std::vector<std::pair<TfMode, std::string>>{
                 {TfMode::kOdom, "REP-105: odom_frame -> base_frame"},
                 {TfMode::kNone, "the same frames, no TF (another node owns odom -> base_link)"},
                 {TfMode::kWorld, "the filter's own world_frame -> IMU frame, restarting at every reset"}}),
      field("odom_frame", "frames", VI_FIELD(p.node.odom_frame), "",
            "odometry, path and landmarks are in it; the base's pose is continuous in it across resets"),
      field("base_frame", "frames", VI_FIELD(p.node.base_frame), "",
            "the robot's base (base_link); \"\": the IMU frame. base_frame <- IMU frame is looked up on TF (URDF)"),
      field("map_frame", "frames", VI_FIELD(p.node.map_frame), "",
            "if set (publish_tf odom): broadcast map_frame -> odom_frame; identity, or with keep_map the kept map's "
            "placement of odom (odom stays continuous, map -> odom takes a relocalization's correction)"),
      field("world_frame", "frames", VI_FIELD(p.node.world_frame), "",
            "publish_tf world: the filter's own world, z up (REP-103), restarting at every reset"),
      field("body_frame", "frames", VI_FIELD(p.node.body_frame), "",
            "the IMU frame; \"\": the frame_id of the sensor_msgs/Imu messages"),
      field("tune_allocator", "frames", VI_FIELD(p.node.tune_allocator), "",
            "keep large per-frame buffers in the heap (glibc mallopt, process-wide): faster on VMs"),
      // --- camera
      field("camera_time_offset_s", "camera", VI_FIELD(p.filter.camera_time_offset_s), "s",
            "t_imu = t_image + offset (camera-IMU clock offset) at the start; estimated online", false),
      field("camera_readout_time_s", "camera", VI_FIELD(p.filter.update.readout_time_s), "s",
            "rolling shutter: first to last row (0: global shutter)", false),
      stringChoice("calibration_source", "camera", VI_FIELD(p.node.calibration_source),
                   "where the intrinsics come from when both a file and camera_info give them",
                   {{"camera_info", "the driver's camera_info (a file's intrinsics until it arrives)"},
                    {"file",
                     "the file (camera_calibration_file, camera_intrinsics or kalibr_camchain); a "
                     "differing camera_info is reported once and ignored"}}),
      field("camera_calibration_file", "camera", VI_FIELD(p.node.camera_calibration_file), "",
            "intrinsics from a ROS camera YAML (camera_calibration_parsers)"),
      field("camera_intrinsics", "camera", VI_FIELD(p.node.camera_intrinsics), "px",
            "intrinsics from the parameters: fx fy cx cy ([]: none; needs camera_resolution)"),
      field("camera_resolution", "camera", VI_FIELD(p.node.camera_resolution), "px",
            "width height of the images camera_intrinsics belong to"),
      stringChoice("camera_distortion_model", "camera", VI_FIELD(p.node.camera_distortion_model),
                   "distortion of camera_intrinsics",
                   {{"radtan", "radial-tangential (ROS plumb_bob)"}, {"equidistant", "Kannala-Brandt (fisheye)"}}),
      field("camera_distortion_coeffs", "camera", VI_FIELD(p.node.camera_distortion_coeffs), "",
            "distortion of camera_intrinsics: radtan k1 k2 p1 p2 [k3], equidistant k1 k2 k3 k4 ([]: none)"),
      field("kalibr_camchain", "camera", VI_FIELD(p.node.kalibr_camchain), "",
            "Kalibr camchain-imucam.yaml: its intrinsics, T_b_c, time offset and line delay replace those "
            "parameters"),
      field("kalibr_imu", "camera", VI_FIELD(p.node.kalibr_imu), "",
            "Kalibr imu.yaml: its noise densities and random walks replace those parameters"),
      stringChoice("extrinsic_source", "camera", VI_FIELD(p.node.extrinsic_source),
                   "where the camera-IMU extrinsic comes from",
                   {{"tf", "TF: IMU frame <- the images' frame_id"}, {"parameters", "T_b_c"}}),
      field("T_b_c", "camera", VI_FIELD(p.node.T_b_c), "",
            "camera pose in the IMU frame: x y z [m] qx qy qz qw (extrinsic_source parameters)"),
      field("estimate_extrinsic", "camera", VI_FIELD(p.filter.estimate_extrinsic), "",
            "refine the camera-IMU extrinsic online (rotation and translation in the state). Experimental: not yet "
            "consistent, see docs/evaluation.md#known-limits"),
      stringChoice("image_transport", "camera", VI_FIELD(p.node.image_transport), "how images arrive",
                   {{"raw", "sensor_msgs/Image"}, {"compressed", "sensor_msgs/CompressedImage on <image>/compressed"}}),
      // --- filter
      choice("mechanization", "filter", VI_FIELD(p.filter.mechanization),
             "inertial mechanization; switching converts the running filter", dyn,
             std::vector<std::pair<M, std::string>>{
                 {M::kWorldCentric, "strapdown in the navigation frame (paper)"},
                 {M::kSensorCentric, "strapdown in the body frame at start (paper)"},
                 {M::kSensorCentricComposition, "sensor-centric with the robocentric composition step (paper)"}}),
      field("composition_second_order", "filter", VI_FIELD(p.filter.composition_second_order), "",
            "the composition keeps the second-order term of an inverse-depth landmark's depth error times the "
            "pose error (off: the paper's first order)"),
      choice("composition_trigger", "filter", VI_FIELD(p.filter.composition_trigger),
             "when the composition step runs (sensor_centric_composition only)", dyn,
             std::vector<std::pair<C, std::string>>{
                 {C::kNewLandmarks, "paper: when more than composition_new_landmarks were added"},
                 {C::kEveryUpdate, "after every image (most consistent)"},
                 {C::kNever, "never compose"}}),
      field("composition_new_landmarks", "filter", VI_FIELD(p.filter.composition_new_landmarks), "count",
            "new_landmarks trigger: compose when more than this many landmarks were added", dyn),
      field("pixel_noise_px", "filter", VI_FIELD(p.filter.update.pixel_noise_px), "px",
            "std-dev of a tracked feature position", dyn),
      field("gate_probability", "filter", VI_FIELD(p.filter.update.gate_probability), "probability",
            "chi-square gate on each observation (2 dof) while the tracks show outliers", dyn),
      field("clean_gate_probability", "filter", VI_FIELD(p.filter.update.clean_gate_probability), "probability",
            "the gate once the images of clean_gate_s seconds of moving had no outlier (none beyond this gate); "
            "below gate_probability: gate_probability always",
            dyn),
      field("clean_gate_s", "filter", VI_FIELD(p.filter.update.clean_gate_s), "s",
            "seconds of moving images without an outlier before the gate widens to clean_gate_probability", dyn),
      // --- map
      choice("landmark_init", "map", VI_FIELD(p.filter.landmark_init), "how new landmarks enter the state", dyn,
             std::vector<std::pair<L, std::string>>{{L::kFixedDepth, "paper: Cartesian point at a fixed depth"},
                                                    {L::kInverseDepth, "anchored inverse depth (consistent)"}}),
      field("landmark_depth_m", "map", VI_FIELD(p.filter.landmark_depth_m), "m", "fixed_depth: depth of a new landmark",
            dyn),
      field("landmark_depth_sigma_m", "map", VI_FIELD(p.filter.landmark_depth_sigma_m), "m",
            "fixed_depth: std-dev along the ray", dyn),
      field("inverse_depth_initial_m", "map", VI_FIELD(p.filter.inverse_depth_initial_m), "m",
            "inverse_depth: prior depth 1/rho0", dyn),
      field("inverse_depth_scene_prior", "map", VI_FIELD(p.filter.inverse_depth_scene_prior), "",
            "inverse_depth: centre the prior at the median depth of the landmarks already seen"),
      field("inverse_depth_sigma", "map", VI_FIELD(p.filter.inverse_depth_sigma), "1/m",
            "inverse_depth: prior std-dev of rho (0.5: 95% of it spans 0.8 m to infinity)", dyn),
      field("triangulate_new_landmarks", "map", VI_FIELD(p.filter.triangulation.enabled), "",
            "inverse_depth, composed every update: a new track waits, on a clone of the camera position, for the "
            "baseline that triangulates it, instead of entering at the prior depth",
            dyn),
      field("triangulation_max_relative_depth_sigma", "map", VI_FIELD(p.filter.triangulation.max_relative_depth_sigma),
            "ratio",
            "a waiting track enters once the std-dev of its inverse depth is below this fraction of the scene's "
            "inverse depth (that of the depth prior of new landmarks), and the share of it the baseline's "
            "uncertainty brings below this fraction of its own inverse depth",
            dyn),
      field("triangulation_clone_interval_s", "map", VI_FIELD(p.filter.triangulation.clone_interval_s), "s",
            "at most one clone of the camera position per this interval (the new tracks of later images wait on the "
            "next)",
            dyn),
      field("triangulation_max_wait_s", "map", VI_FIELD(p.filter.triangulation.max_wait_s), "s",
            "a track without its baseline after this long starts again on a newer clone", dyn),
      field("triangulation_min_depth_m", "map", VI_FIELD(p.filter.triangulation.min_depth_m), "m",
            "a track triangulated nearer than this to either camera is a mismatch", dyn),
      field("triangulation_min_map_landmarks", "map", VI_FIELD(p.filter.triangulation.min_map_landmarks), "count",
            "a map with fewer landmarks (a start, a reset, a new scene) takes the longest waiting tracks once they "
            "waited triangulation_starved_max_wait_s: with their two-view depth where it beats the prior, else at "
            "the prior depth",
            dyn),
      field("triangulation_starved_max_wait_s", "map", VI_FIELD(p.filter.triangulation.starved_max_wait_s), "s",
            "how long a track waits for its baseline while the map is short of landmarks", dyn),
      field("max_landmarks", "map", VI_FIELD(p.filter.max_landmarks), "count",
            "bound on landmarks in the state, dormant ones included (tracked ones take precedence)", dyn),
      field("landmark_timeout_s", "map", VI_FIELD(p.filter.landmark_timeout_s), "s",
            "landmarks not observed for this long leave the tracked map: dormant with keep_map, else marginalized "
            "(-1: never)",
            dyn),
      field("keep_map", "map", VI_FIELD(p.filter.map.within_run), "",
            "keep landmarks whose tracks ended as dormant and find them again by appearance in their predicted region",
            dyn),
      field("map_max_dormant_landmarks", "map", VI_FIELD(p.filter.map.max_dormant), "count",
            "dormant landmarks kept, in the room tracked ones leave below max_landmarks; beyond it the most crowded "
            "places give up their least certain",
            dyn),
      field(
          "map_max_relative_sigma", "map", VI_FIELD(p.filter.map.max_relative_sigma), "ratio",
          "only landmarks whose position std-dev is at most this fraction of their distance are kept and searched for",
          dyn),
      field("map_min_joint_revisits", "map", VI_FIELD(p.filter.map.min_joint_revisits), "count",
            "the matches to dormant landmarks of one image must agree on one pose error (joint chi^2 gate); fewer "
            "than this many agreeing matches are none",
            dyn),
      field("map_revisit_confirm_frames", "map", VI_FIELD(p.filter.map.revisit_confirm_frames), "count",
            "a match to a dormant landmark is believed once its track has landed where the landmark is predicted "
            "in this many images (the first included; 1: at once): a look-alike at another depth drifts off, but "
            "waiting also loses true revisits whose corners the tracker drops",
            dyn),
      field("map_dormant_consider", "map", VI_FIELD(p.filter.map.dormant_consider), "",
            "dormant landmarks are consider states (Schmidt-Kalman): while unobserved no update changes them, and "
            "when seen again the first update corrects the pose by them without sharpening them",
            dyn),
      field("map_dormant_spacing_m", "map", VI_FIELD(p.filter.map.dormant_spacing_m), "m",
            "dormant landmarks are counted in cells of this size; the fullest cell gives up its least certain first",
            dyn),
      field("map_max_descriptor_distance_bits", "map", VI_FIELD(p.filter.map.max_descriptor_distance), "bits",
            "largest Hamming distance (of 256) of a match to a dormant landmark", dyn),
      field("map_descriptor_ratio", "map", VI_FIELD(p.filter.map.descriptor_ratio), "ratio",
            "a match's distance must be below this fraction of the second best's, from either side", dyn),
      field("map_distinct_in_view", "map", VI_FIELD(p.filter.map.distinct_in_view), "",
            "a dormant landmark is recognized only if nothing else in the image looks like it (its side of the ratio "
            "test over the whole image: where the texture repeats, the region's one look-alike may be another point "
            "while the landmark itself went undetected); false: over its search region only",
            dyn),
      field("map_search_gate_probability", "map", VI_FIELD(p.filter.map.search_gate_probability), "probability",
            "chi^2 gate (2 dof) of the region a dormant landmark is searched in", dyn),
      field("map_max_search_sigma_px", "map", VI_FIELD(p.filter.map.max_search_sigma_px), "px",
            "a dormant landmark is searched for only while its predicted pixel's std-dev is below this", dyn),
      field("map_relocalize", "map", VI_FIELD(p.filter.map.across_runs), "",
            "keep_map: the map outlives resets (and map_file loads one); a new run is placed back in it when the "
            "camera sees mapped points again (appearance matches + PnP RANSAC)",
            dyn),
      field("map_max_kept_points", "map", VI_FIELD(p.filter.map.max_kept_points), "count",
            "points kept across resets and saved; beyond it the first archived leave first", dyn),
      field("map_relocalize_min_inliers", "map", VI_FIELD(p.filter.map.relocalize_min_inliers), "count",
            "matches to the kept map that must agree on the camera's pose for a relocalization", dyn),
      field("map_relocalize_reprojection_px", "map", VI_FIELD(p.filter.map.relocalize_reprojection_px), "px",
            "a match agrees with the relocalized pose when it reprojects within this", dyn),
      field("map_relocalize_max_tilt_deg", "map", VI_FIELD(p.filter.map.relocalize_max_tilt_deg), "deg",
            "largest angle between the relocalized camera's gravity and the filter's (a larger one is a false "
            "match)",
            dyn),
      field("map_file", "map", VI_FIELD(p.node.map_file), "",
            "keep_map: a map (YAML or JSON, from ~save_map) loaded at start when the file exists, so a building "
            "walked before is started in localized; ~save_map writes it"),
      // --- standing
      field("zero_velocity", "standing", VI_FIELD(p.filter.zero_velocity.enabled), "",
            "detect standing from the images and apply v = 0", dyn),
      field("zero_velocity_window_s", "standing", VI_FIELD(p.filter.zero_velocity.window_s), "s",
            "baseline of the parallax test", dyn),
      field(
          "zero_velocity_max_parallax_px", "standing", VI_FIELD(p.filter.zero_velocity.max_parallax_px), "px",
          "standing below this median de-rotated parallax, unless the images show the translation the filter estimates",
          dyn),
      field("zero_velocity_sigma_mps", "standing", VI_FIELD(p.filter.zero_velocity.velocity_sigma_mps), "m/s",
            "std-dev of the true velocity while standing (sway); images showing a translation faster than this are no "
            "stand",
            dyn),
      field("zero_velocity_rest_sigma_mps", "standing", VI_FIELD(p.filter.zero_velocity.rest_velocity_sigma_mps), "m/s",
            "the same while the IMU also shows the rig at rest", dyn),
      field("zero_velocity_min_features", "standing", VI_FIELD(p.filter.zero_velocity.min_features), "count",
            "features seen at both ends of the window to decide at all", dyn),
      field("zero_velocity_gate_probability", "standing", VI_FIELD(p.filter.zero_velocity.gate_probability),
            "probability", "chi-square gate of the zero-velocity update", dyn),
      field("zero_velocity_defer_landmarks", "standing", VI_FIELD(p.filter.zero_velocity.defer_landmarks), "",
            "new tracks enter at the prior depth only once the rig is seen moving (parallax) or the IMU shows "
            "rest; with the delayed entry they may enter triangulated meanwhile",
            dyn),
      field("zero_velocity_moving_parallax_px", "standing", VI_FIELD(p.filter.zero_velocity.moving_parallax_px), "px",
            "seen moving (new landmarks enter) from this parallax, latched until the next stand; >= "
            "zero_velocity_max_parallax_px",
            dyn),
      field("zero_velocity_moving_speed_mps", "standing", VI_FIELD(p.filter.zero_velocity.moving_speed_mps), "m/s",
            "before the detector's first window: moving if the estimated speed is above this by 2 sigma", false),
      field("zero_velocity_still_accel_std_mps2", "standing", VI_FIELD(p.filter.zero_velocity.still_accel_std_mps2),
            "m/s^2", "at rest: std-dev of each accelerometer axis below this", dyn),
      field("zero_velocity_still_gyro_radps", "standing", VI_FIELD(p.filter.zero_velocity.still_gyro_radps), "rad/s",
            "at rest: every angular rate below this", dyn),
      // --- blind
      field("blind_motion_prior", "blind", VI_FIELD(p.filter.blind_motion.enabled), "",
            "while no image constrains the velocity (a covered lens, darkness), bound it by the body-frame velocity "
            "of the seconds of sight before (a walking person's pace and way of holding the rig); off for rigs that "
            "may speed up while blind (vehicles, drones)",
            dyn),
      field("blind_motion_prior_window_s", "blind", VI_FIELD(p.filter.blind_motion.window_s), "s",
            "the seconds of sight the prior is learned from (time constant of its forgetting)", dyn),
      field("blind_motion_prior_min_seen_s", "blind", VI_FIELD(p.filter.blind_motion.min_seen_s), "s",
            "seconds of sight needed before the prior is used", dyn),
      field("blind_motion_prior_min_sigma_mps", "blind", VI_FIELD(p.filter.blind_motion.min_sigma_mps), "m/s",
            "added to the prior's std-dev on each axis: the blind seconds' pace is never known better", dyn),
      field("blind_motion_prior_gate_probability", "blind", VI_FIELD(p.filter.blind_motion.gate_probability),
            "probability", "chi-square gate of the prior (a body moving unlike before refuses it)", dyn),
      // --- imu
      field("accel_noise_density", "imu", VI_FIELD(p.filter.imu_noise.accel_noise_density), "m/s^2/sqrt(Hz)",
            "accelerometer white noise", dyn),
      field("gyro_noise_density", "imu", VI_FIELD(p.filter.imu_noise.gyro_noise_density), "rad/s/sqrt(Hz)",
            "gyroscope white noise", dyn),
      field("accel_random_walk", "imu", VI_FIELD(p.filter.imu_noise.accel_random_walk), "m/s^3/sqrt(Hz)",
            "accelerometer bias random walk", dyn),
      field("gyro_random_walk", "imu", VI_FIELD(p.filter.imu_noise.gyro_random_walk), "rad/s^2/sqrt(Hz)",
            "gyroscope bias random walk", dyn),
      field("gravity_mps2", "imu", VI_FIELD(p.filter.gravity_mps2), "m/s^2", "local gravity", false),
      field("max_imu_gap_s", "imu", VI_FIELD(p.filter.max_imu_gap_s), "s",
            "longer IMU gaps are reported in the diagnostics (and bridged with added uncertainty)", false),
      field("imu_accel_range_mps2", "imu", VI_FIELD(p.filter.imu_check.accel_range_mps2), "m/s^2",
            "the accelerometer's measurement range per axis (datasheet): a reading at it is clipped, bridged "
            "(0: not checked)",
            false),
      field("imu_gyro_range_radps", "imu", VI_FIELD(p.filter.imu_check.gyro_range_radps), "rad/s",
            "the gyro's measurement range per axis (datasheet): a reading at it is clipped, bridged (0: not checked)",
            false),
      field("imu_max_accel_step_mps2", "imu", VI_FIELD(p.filter.imu_check.max_accel_step_mps2), "m/s^2",
            "a sample departing from the last good one by more on an axis is implausible, bridged (0: not checked)",
            false),
      field("imu_max_gyro_step_radps", "imu", VI_FIELD(p.filter.imu_check.max_gyro_step_radps), "rad/s",
            "the same for the gyro (0: not checked)", false),
      field("imu_max_bridged_samples", "imu", VI_FIELD(p.filter.imu_check.max_bridged_samples), "count",
            "more clipped or implausible samples in a row than this are taken as they are (a real change)", false),
      // --- initialization
      field("dynamic_init", "initialization", VI_FIELD(p.dynamic_init_enabled), "",
            "also initialize while moving (visual-inertial alignment of a window of tracks and IMU)"),
      field("dynamic_init_window_s", "initialization", VI_FIELD(p.dynamic_init.window_s), "s",
            "window of images it aligns", false),
      field("dynamic_init_max_window_s", "initialization", VI_FIELD(p.dynamic_init.max_window_s), "s",
            "when that window's motion is too little, the images of up to this long are aligned (the acceleration "
            "it lacked may be in the frames before it)",
            false),
      field("dynamic_init_max_velocity_sigma_mps", "initialization", VI_FIELD(p.dynamic_init.max_velocity_sigma_mps),
            "m/s", "waits while the velocity would be known worse than this (too little motion)", false),
      field("dynamic_init_max_scale_sigma", "initialization", VI_FIELD(p.dynamic_init.max_scale_sigma), "ratio",
            "waits while the scene's scale (mean inverse depth of the last image's features) would be known worse "
            "than this fraction (too little acceleration for the depth)",
            false),
      field("dynamic_init_max_tilt_sigma_rad", "initialization", VI_FIELD(p.dynamic_init.max_tilt_sigma_rad), "rad",
            "waits while roll/pitch would be known worse than this", false),
      field("dynamic_init_gyro_bias_sigma_radps", "initialization", VI_FIELD(p.dynamic_init.gyro_bias_sigma_radps),
            "rad/s", "initial std-dev of the gyro bias it cannot see (turn-on bias)", false),
      field("blind_reanchor_max_wait_s", "initialization", VI_FIELD(p.reanchor_max_wait_s), "s",
            "after a blind stretch (no usable image feature) new tracks wait until the first images' alignment with "
            "the IMU re-anchors the velocity, at most this long after the camera sees again "
            "(0: they enter at once)",
            false),
      field("static_window_s", "initialization", VI_FIELD(p.static_init.window_s), "s",
            "the filter starts after this long at rest", false),
      field("static_max_accel_std_mps2", "initialization", VI_FIELD(p.static_init.max_accel_std_mps2), "m/s^2",
            "\"at rest\": std-dev of |accel| (its 50 ms means: vibration averages out) below this", false),
      field("static_max_gyro_std_radps", "initialization", VI_FIELD(p.static_init.max_gyro_std_radps), "rad/s",
            "\"at rest\": std-dev of each gyro axis (its 50 ms means) below this", false),
      field("initial_sigma_position_m", "initialization", VI_FIELD(p.filter.initial.position_m), "m",
            "registration error of the start position", false),
      field("initial_sigma_velocity_mps", "initialization", VI_FIELD(p.filter.initial.velocity_mps), "m/s",
            "initial velocity std-dev (static start)", false),
      field("initial_sigma_roll_pitch_rad", "initialization", VI_FIELD(p.filter.initial.roll_pitch_rad), "rad",
            "initial roll and pitch std-dev (~1 deg)", false),
      field("initial_sigma_yaw_rad", "initialization", VI_FIELD(p.filter.initial.yaw_rad), "rad",
            "initial yaw std-dev (~2 deg; yaw is unobservable: 0 is the reference)", false),
      field("initial_sigma_accel_bias_mps2", "initialization", VI_FIELD(p.filter.initial.accel_bias_mps2), "m/s^2",
            "initial accelerometer bias std-dev", false),
      field("initial_sigma_gyro_bias_radps", "initialization", VI_FIELD(p.filter.initial.gyro_bias_radps), "rad/s",
            "initial gyro bias std-dev after the static gyro-bias estimate", false),
      field("initial_sigma_time_offset_s", "initialization", VI_FIELD(p.filter.initial.time_offset_s), "s",
            "camera-IMU time offset std-dev, estimated online (0: fixed at camera_time_offset_s)", false),
      field("initial_sigma_extrinsic_rotation_rad", "initialization", VI_FIELD(p.filter.initial.extrinsic_rotation_rad),
            "rad", "camera-IMU rotation std-dev (estimate_extrinsic)", false),
      field("initial_sigma_extrinsic_translation_m", "initialization",
            VI_FIELD(p.filter.initial.extrinsic_translation_m), "m",
            "camera-IMU translation std-dev per axis (estimate_extrinsic)", false),
      // --- lost
      field("lost_detection", "lost", VI_FIELD(p.filter.divergence.enabled), "",
            "detect a lost (diverged) filter, reset it and re-initialize"),
      field("lost_max_speed_mps", "lost", VI_FIELD(p.filter.divergence.max_speed_mps), "m/s",
            "lost when the body moved faster than this all the time (a pedestrian does not)", false),
      field("lost_max_rejected_fraction", "lost", VI_FIELD(p.filter.divergence.max_rejected_fraction), "ratio",
            "lost when the gate rejected more than this of the observations (consistent: ~0.05)", false),
      field("lost_window_s", "lost", VI_FIELD(p.filter.divergence.window_s), "s", "window of both tests", false),
      // --- tracker
      choice("detector", "tracker", VI_FIELD(p.tracker.detector), "corner detector", dyn,
             std::vector<std::pair<D, std::string>>{{D::kShiTomasi, "Shi-Tomasi corners (cv::goodFeaturesToTrack)"},
                                                    {D::kFast, "FAST corners (cv::FAST)"}}),
      field("max_tracks", "tracker", VI_FIELD(p.tracker.max_tracks), "count", "target number of feature tracks", dyn),
      field("min_distance_px", "tracker", VI_FIELD(p.tracker.min_distance_px), "px", "minimum distance between corners",
            dyn),
      field("quality_level", "tracker", VI_FIELD(p.tracker.quality_level), "ratio",
            "Shi-Tomasi quality relative to the best corner", dyn),
      field("fast_threshold", "tracker", VI_FIELD(p.tracker.fast_threshold), "gray levels", "FAST intensity threshold",
            dyn),
      field("min_corner_snr", "tracker", VI_FIELD(p.tracker.min_corner_snr), "ratio",
            "a corner or track needs this many times the gradient the image's own noise gives over the KLT window, "
            "at half size (noise alone reaches about 3; 5 makes images of noise, darkness, blind; 0: off)",
            dyn),
      field("klt_window_px", "tracker", VI_FIELD(p.tracker.klt_window_px), "px", "KLT window size (odd)", dyn),
      field("klt_pyramid_levels", "tracker", VI_FIELD(p.tracker.klt_pyramid_levels), "count", "KLT pyramid levels",
            dyn),
      field("fb_threshold_px", "tracker", VI_FIELD(p.tracker.fb_threshold_px), "px", "forward-backward check bound",
            dyn),
      field("ransac_threshold_px", "tracker", VI_FIELD(p.tracker.ransac_threshold_px), "px",
            "epipolar RANSAC threshold", dyn),
      field("redetect_fraction", "tracker", VI_FIELD(p.tracker.redetect_fraction), "ratio",
            "search new corners once the tracks fall below this fraction of max_tracks (1: whenever one is lost)", dyn),
      field("max_image_width_px", "tracker", VI_FIELD(p.tracker.max_image_width_px), "px",
            "wider images are shrunk to this width before tracking; every [px] value refers to the tracked image (0: "
            "full size)",
            false),
      // --- outputs
      field("max_image_queue", "outputs", VI_FIELD(p.node.max_image_queue), "count",
            "images waiting for IMU beyond this are dropped", false, 1, 1000),
      field("time_jump_reset_s", "outputs", VI_FIELD(p.node.time_jump_reset_s), "s",
            "stamps this far backwards reset the filter (bag restart)", false, 0.001, 1e6),
      field("path_max_length", "outputs", VI_FIELD(p.node.path_max_length), "count", "poses kept in the published path",
            false, 1, 1000000),
      field("max_image_gap_s", "outputs", VI_FIELD(p.node.max_image_gap_s), "s",
            "longer gaps between processed images are reported in the diagnostics", false, 0.001, 1e6),
      field("min_imu_rate_hz", "outputs", VI_FIELD(p.node.min_imu_rate_hz), "Hz",
            "the diagnostics (\"imu rate\") warn while the IMU arrives slower than this", false, 0.0, 10000.0),
      field("min_image_rate_hz", "outputs", VI_FIELD(p.node.min_image_rate_hz), "Hz",
            "the diagnostics (\"image rate\") warn while images arrive slower than this", false, 0.0, 1000.0),
  };
}

#undef VI_FIELD

std::string typeName(const ParamValue& v) {
  static const char* names[] = {"bool", "int", "double", "string", "list of doubles"};
  return names[v.index()];
}

double asNumber(const ParamValue& v) {
  if (const int* i = std::get_if<int>(&v)) return *i;
  return std::get<double>(v);
}

std::string rangeText(const ParamSpec& s) {
  if (!std::isfinite(s.min) && !std::isfinite(s.max)) return "";
  const bool is_int = std::holds_alternative<int>(s.defaultValue());
  auto num = [&](double x) { return is_int ? std::to_string(static_cast<long>(x)) : toYaml(ParamValue(x)); };
  return "[" + num(s.min) + ", " + num(s.max) + "]";
}

std::string choicesText(const ParamSpec& s, const char* sep) {
  std::string out;
  for (const auto& c : s.choices) out += (out.empty() ? "" : sep) + c.first;
  return out;
}

}  // namespace

std::string ParamSpec::check(const ParamValue& v) const {
  const ParamValue d = defaultValue();
  if (v.index() != d.index()) return name + " must be a " + typeName(d) + " (got a " + typeName(v) + ")";
  if (std::holds_alternative<int>(v) || std::holds_alternative<double>(v)) {
    const double x = asNumber(v);
    if (!(x >= min && x <= max)) return name + " must be in " + rangeText(*this) + " (got " + toYaml(v) + ")";
  }
  if (!choices.empty()) {
    const std::string& s = std::get<std::string>(v);
    if (std::none_of(choices.begin(), choices.end(), [&](const auto& c) { return c.first == s; })) {
      return name + " must be one of " + choicesText(*this, ", ") + " (got '" + s + "')";
    }
  }
  return "";
}

const std::vector<ParamGroup>& paramGroups() {
  static const std::vector<ParamGroup> groups = {
      {"topics", "input topics (names resolved in the node's namespace; remapping applies)"},
      {"frames", "frames (REP-105)"},
      {"camera", "camera"},
      {"filter", "filter"},
      {"map", "map"},
      {"standing", "standing: zero-velocity update when the camera sees no translation parallax"},
      {"blind", "blind: what bounds the velocity while no image constrains it"},
      {"imu", "IMU: continuous-time noise densities (datasheet or Allan variance), gravity"},
      {"initialization", "initialization"},
      {"lost", "lost detection: reset and re-initialize when, over lost_window_s, ..."},
      {"tracker", "tracker"},
      {"outputs", "synchronization and outputs"},
  };
  return groups;
}

const std::vector<ParamSpec>& paramTable() {
  static const std::vector<ParamSpec> table = makeTable();
  return table;
}

const ParamSpec* findParam(const std::string& name) {
  for (const auto& s : paramTable()) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

std::string closestParamName(const std::string& name) {
  // Levenshtein distance; a suggestion only within a third of the name's length (at least 2).
  auto distance = [](const std::string& a, const std::string& b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
      size_t diag = row[0];
      row[0] = i;
      for (size_t j = 1; j <= b.size(); ++j) {
        const size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diag = up;
      }
    }
    return row[b.size()];
  };
  std::string best;
  size_t best_d = std::max<size_t>(2, name.size() / 3) + 1;
  for (const auto& s : paramTable()) {
    const size_t d = distance(name, s.name);
    if (d < best_d) {
      best_d = d;
      best = s.name;
    }
  }
  return best;
}

std::string toYaml(const ParamValue& v) {
  struct Visitor {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(int i) const { return std::to_string(i); }
    std::string operator()(double d) const {
      // The shortest decimal that reads back exactly, always with a '.' or an exponent (a double).
      // Plain decimals for everyday magnitudes, exponents for the tiny and the huge.
      const bool plain = d == 0.0 || (std::abs(d) >= 1e-4 && std::abs(d) < 1e7);
      char buf[64];
      for (int precision = plain ? 0 : 1; precision <= 17; ++precision) {
        std::snprintf(buf, sizeof(buf), plain ? "%.*f" : "%.*g", precision, d);
        if (std::strtod(buf, nullptr) == d) break;
      }
      // A '.' in the mantissa: YAML 1.1 (rosparam's PyYAML) reads "2e-05" as a string.
      std::string s = buf;
      const size_t e = s.find_first_of("eE");
      const std::string mantissa = s.substr(0, e);
      if (mantissa.find_first_of(".n") == std::string::npos) s.insert(mantissa.size(), ".0");
      return s;
    }
    std::string operator()(const std::string& s) const { return s.empty() ? "\"\"" : s; }
    std::string operator()(const std::vector<double>& v) const {
      std::string s = "[";
      for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + (*this)(v[i]);
      return s + "]";
    }
  };
  return std::visit(Visitor(), v);
}

std::string documentedYaml() {
  std::ostringstream o;
  o << "# vi_ekf_slam parameters (private namespace of the node/nodelet), generated from\n"
    << "# src/ros/param_table.cc by `make params`: edit the table, not this file. Every value is\n"
    << "# validated at startup; unknown names and impossible values stop the node with a list of the\n"
    << "# problems. (dyn): can also change while running: " << kDynHelp << "\n";
  for (const auto& g : paramGroups()) {
    std::string head = "# --- " + g.title + " ";
    head.resize(std::max<size_t>(head.size(), 100), '-');
    o << "\n" << head << "\n";
    for (const auto& s : paramTable()) {
      if (s.group != g.id) continue;
      std::string line = s.name + ": " + toYaml(s.defaultValue());
      line.resize(std::max<size_t>(line.size() + 1, 44), ' ');
      line += "# ";
      if (s.dynamic) line += "(dyn) ";
      if (!s.unit.empty()) line += "[" + s.unit + "] ";
      line += s.description;
      if (!s.choices.empty()) line += ": " + choicesText(s, " | ");
      const std::string range = rangeText(s);
      if (!range.empty()) line += ", in " + range;
      o << line << "\n";
    }
  }
  return o.str();
}

std::string reconfigureCfg() {
  std::ostringstream o;
  auto quoted = [](const std::string& s) {
    std::string q = "\"";
    for (char c : s) q += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
    return q + "\"";
  };
  o << "#!/usr/bin/env python3\n"
    << "# The parameters of vi_ekf_slam that can change while the filter runs (dynamic_reconfigure),\n"
    << "# generated from src/ros/param_table.cc by `make params`: edit the table, not this file.\n"
    << "# Changing `mechanization` converts the running filter (state and covariance) and keeps the map.\n"
    << "PACKAGE = \"vi_ekf_slam\"\n\n"
    << "from dynamic_reconfigure.parameter_generator_catkin import ParameterGenerator, int_t, double_t, str_t, "
       "bool_t\n\n"
    << "gen = ParameterGenerator()\n";
  for (const auto& g : paramGroups()) {
    bool any = false;
    for (const auto& s : paramTable()) any = any || (s.group == g.id && s.dynamic);
    if (!any) continue;
    o << "\n" << g.id << "_group = gen.add_group(" << quoted(g.id) << ")\n";
    for (const auto& s : paramTable()) {
      if (s.group != g.id || !s.dynamic) continue;
      const ParamValue d = s.defaultValue();
      const std::string desc = s.description + (s.unit.empty() ? "" : " [" + s.unit + "]");
      static const char* types[] = {"bool_t", "int_t", "double_t", "str_t", "?"};
      o << g.id << "_group.add(" << quoted(s.name) << ", " << types[d.index()] << ", 0, " << quoted(desc) << ", ";
      if (std::holds_alternative<std::string>(d)) {
        o << quoted(std::get<std::string>(d));
      } else if (const bool* b = std::get_if<bool>(&d)) {
        o << (*b ? "True" : "False") << ")\n";  // Python
        continue;
      } else {
        o << toYaml(d);
      }
      if (std::holds_alternative<int>(d)) o << ", " << static_cast<long>(s.min) << ", " << static_cast<long>(s.max);
      if (std::holds_alternative<double>(d))
        o << ", " << toYaml(ParamValue(s.min)) << ", " << toYaml(ParamValue(s.max));
      if (!s.choices.empty()) {
        o << ",\n    edit_method=gen.enum([";
        for (size_t i = 0; i < s.choices.size(); ++i) {
          o << (i ? ",\n                         " : "") << "gen.const(" << quoted(s.choices[i].first) << ", str_t, "
            << quoted(s.choices[i].first) << ", " << quoted(s.choices[i].second) << ")";
        }
        o << "], " << quoted(s.description) << ")";
      }
      o << ")\n";
    }
  }
  o << "\n# The generated class is vi_ekf_slam::EkfSlamReconfigureConfig (EkfSlamConfig is the core struct).\n"
    << "exit(gen.generate(PACKAGE, \"vi_ekf_slam\", \"EkfSlamReconfigure\"))\n";
  return o.str();
}

std::string parameterReference() {
  std::ostringstream o;
  o << "# Parameters\n\n"
    << "Generated from `src/ros/param_table.cc` by `make params` (as are `config/vi_ekf_slam.yaml` and\n"
    << "`cfg/EkfSlamReconfigure.cfg`). Private parameters of the node/nodelet; \"dyn\": can also change while\n"
    << "running (`" << kDynHelp << "`). Unknown names and values outside their range stop the node with\n"
    << "the list of problems; the values in effect are echoed at startup.\n";
  for (const auto& g : paramGroups()) {
    o << "\n## " << g.title
      << "\n\n| name | default | unit | range / choices | dyn | description |\n|---|---|---|---|---|---|\n";
    for (const auto& s : paramTable()) {
      if (s.group != g.id) continue;
      o << "| `" << s.name << "` | `" << toYaml(s.defaultValue()) << "` | " << s.unit << " | "
        << (s.choices.empty() ? rangeText(s) : choicesText(s, ", ")) << " | " << (s.dynamic ? "yes" : "") << " | "
        << s.description;
      for (const auto& c : s.choices) o << "; `" << c.first << "`: " << c.second;
      o << " |\n";
    }
  }
  return o.str();
}

}  // namespace vi_ekf_slam::glue
