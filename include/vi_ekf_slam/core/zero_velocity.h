// Standing still: a pedestrian stops at doors, waits, looks around. While the rig does not
// translate, the camera sees no parallax and constrains only the product of each landmark's
// inverse depth and the velocity; linearized, that product gives the filter false confidence in
// the forward velocity (README, TUM corridor). Like OpenVINS' zero-velocity updater, we detect
// standing from the images and tell the filter directly that the velocity is (nearly) zero.
#pragma once

#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <unordered_map>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct ZeroVelocityParams {
  bool enabled = true;
  /// Baseline over which the parallax is measured [s]; walking at 1 m/s moves the rig 0.5 m.
  double window_s = 0.5;
  /// Standing when the median de-rotated feature displacement over the window is below this
  /// [px] (pixel noise alone gives about 1.8 px for 1 px noise; walking gives tens of px).
  double max_parallax_px = 3.0;
  int min_features = 10;  ///< features seen at both ends of the window to decide at all
  /// Std-dev of the true velocity while standing (torso sway) [m/s]: the noise of the
  /// zero-velocity pseudo-measurement. A standing pedestrian or hand-held rig sways by a few
  /// centimetres per second, and the sway is correlated over a few tenths of a second while the
  /// update is applied at the frame rate as if each frame's sway were independent: a smaller value
  /// made the gyro bias and velocity overconfident at the TUM corridor's start.
  double velocity_sigma_mps = 0.08;
  /// The same while the IMU shows the rig at rest as well (imuAtRest: accelerometer std-dev below
  /// 0.2 m/s^2 over 0.1 s allows ~0.02 m/s of motion) [m/s]: a rig set down, a pedestrian leaning
  /// on a wall. The rendered demo bag starts so.
  double rest_velocity_sigma_mps = 0.03;
  double gate_probability = 0.999;  ///< chi^2 gate (3 dof): a moving filter refuses the update
  /// A point first seen while the rig stands (or before the detector's first window, when
  /// standing cannot be told from walking) has no parallax; when the rig sways or jitters in a
  /// hand, its unknown depth enters later observations only through the product depth x sway,
  /// which the linearized filter turns into false confidence in the velocity and, once walking
  /// starts, in roll and pitch (README, TUM corridor). So new tracks do not enter at the prior
  /// depth until the detector sees the rig move, unless the IMU shows it at rest (zero parallax
  /// then pins the velocity exactly, which is safe); with the delayed entry they wait on a clone
  /// meanwhile and enter only once their baseline triangulates them (a slow shuffle's does, a
  /// sway's does not; delayed_landmarks.h). Landmarks already in the map are updated as always.
  bool defer_landmarks = true;
  /// Seen moving (latched until the next stand): median de-rotated parallax over window_s at least
  /// this [px]. A rig swaying in a hand shows 2-5 px, above max_parallax_px but without the
  /// baseline a new point needs; walking shows tens of px.
  double moving_parallax_px = 8.0;
  /// Before the detector has its first window (at the start, after a reset), the rig counts as
  /// moving if the filter's own speed is at least this with 2-sigma confidence [m/s] (along the
  /// estimated velocity); a pedestrian's sway stays below 0.2 m/s. Holding every track back for
  /// that first window made walks that start moving inconsistent; using the speed
  /// later as well let points in during slow shuffles.
  double moving_speed_mps = 0.3;
  double still_accel_std_mps2 = 0.2;  ///< at rest: std-dev of each accelerometer axis below this [m/s^2]
  double still_gyro_radps = 0.05;     ///< at rest: every angular rate below this [rad/s]
  double still_window_s = 0.1;        ///< the rest test looks at the IMU samples of this long before a frame [s]
};

/// True if the samples of `imu` stamped in [t0, t1] (at least two) show a rig at rest: each
/// accelerometer axis varies less than still_accel_std_mps2 and no angular rate exceeds
/// still_gyro_radps (a pedestrian's torso, even standing, sways well above both).
bool imuAtRest(const std::deque<ImuData>& imu, double t0, double t1, const ZeroVelocityParams& params);

/// The translation the filter believes in, to test the images against: a small median parallax
/// is standing only if the images could have shown that translation and did not.
struct ExpectedMotion {
  /// The body's estimated velocity in {n}, taken as the camera's (the lever arm's omega x p_b_c,
  /// millimetres over the window, left out) [m/s].
  Vec3 v_n_b = Vec3::Zero();
  double scene_depth_m = 5.0;   ///< depth of the features along the reference camera's axis [m]
  double pixel_noise_px = 1.0;  ///< std-dev of a tracked feature position [px]
};

/// Decides from the tracked features whether the rig translated over the last window: each
/// feature's ray from the start of the window is rotated into the current camera with the
/// filter's own relative rotation (gyro-accurate over 0.5 s) and compared with where it is seen
/// now, so turning on the spot is still "standing".
///
/// A small median parallax alone is not standing: walking slowly towards a far scene moves most
/// features by little more than the pixel noise (a 0.3 m/s walk: a median of 2.7-3.4 px over
/// 0.5 s), and a zero-velocity update there took a walk for a stand: the velocity 0.27 m/s off
/// with a sigma of 0.03 in one image. So, given the filter's own velocity
/// (ExpectedMotion), the displacements are fitted with the flow that translation would make at
/// the scene's depth: lambda, the share of it the images show (0 standing, 1 moving as the filter
/// says at that depth), by least squares robust to slipped tracks. Its pattern (which way each
/// feature moves) is what tells; its size depends on the scene's depth, unknown at a start
/// (lambda 0.46 in the image where that update fired: the points farther than the 5 m prior).
/// Where lambda is surely above 0 and lambda times the filter's speed is beyond a stand's sway
/// (velocity_sigma_mps: a swaying rig translates too, and along the filter's drift as often as
/// not), the images show the filter's translation and the rig is not standing, whatever the median
/// says. Where the filter's velocity is too small for the scene to show (a stand after a
/// zero-velocity update), lambda's sigma is large and the median decides as before.
class StationaryDetector {
 public:
  struct Decision {
    bool has_history = false;  ///< a frame at least window_s old was available
    bool decided = false;      ///< enough history and features to tell
    bool stationary = false;   ///< decided, the parallax below the threshold and the motion not shown
    double parallax_px = 0.0;
    int features = 0;
    /// The share of the filter's translation over the window that the images show (NaN: no
    /// ExpectedMotion or no feature to tell), and its std-dev from the pixel noise.
    double motion_shown = std::numeric_limits<double>::quiet_NaN();
    double motion_shown_sigma = std::numeric_limits<double>::infinity();
    /// lambda times the filter's speed: the speed the images show at the scene's depth [m/s].
    double motion_shown_speed_mps = 0.0;
    /// The images show the filter's translation (lambda above 0 by 4 sigmas) at a speed beyond a
    /// stand's sway (velocity_sigma_mps).
    bool motion_confirmed = false;
  };

  /// R_n_c: the estimated camera orientation at the frame's time; expected: the filter's
  /// translation to test against (none: the median parallax alone decides).
  Decision update(const CameraFrame& frame, const Mat3& R_n_c, const CameraModel& camera,
                  const ZeroVelocityParams& params, const std::optional<ExpectedMotion>& expected = std::nullopt);
  void reset() { history_.clear(); }

 private:
  struct Past {
    double t;
    Mat3 R_n_c;
    std::unordered_map<std::int64_t, Eigen::Vector2d> xn;  ///< normalized image coordinates
  };
  std::deque<Past> history_;
};

struct ZeroVelocityResult {
  bool applied = false;
  double nis = 0.0;  ///< normalized innovation squared (3 dof)
};

/// EKF update (kalman_update.h) with the pseudo-measurement v_s_b = 0 (zero velocity is zero in
/// every frame), noise velocity_sigma_mps per axis, gated on its 3-dof innovation.
/// at_rest (imuAtRest): the IMU shows the rig at rest too, and rest_velocity_sigma_mps is used.
ZeroVelocityResult zeroVelocityUpdate(FilterState& state, const ZeroVelocityParams& params, bool at_rest);

}  // namespace vi_ekf_slam
