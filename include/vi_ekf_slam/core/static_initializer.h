// Initialization from a short static interval: roll and pitch from the mean specific force
// (gravity alignment), yaw set to zero (unobservable), gyro bias from the mean angular rate, and
// the accelerometer bias along gravity from the mean specific force's magnitude against the
// local gravity (the horizontal bias is indistinguishable from roll and pitch at rest).
#pragma once

#include <deque>
#include <optional>

#include "vi_ekf_slam/core/navigation_output.h"
#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct StaticInitParams {
  double window_s = 1.0;             ///< length of the static window [s]
  double max_accel_std_mps2 = 0.15;  ///< max std-dev of |am| inside the window [m/s^2]
  double max_gyro_std_radps = 0.02;  ///< max std-dev of each gyro axis inside the window [rad/s]
  /// Both std-devs are taken over the means of blocks this long [s]: vibration (a MAV's rotors, a
  /// vehicle's engine) averages out, the motion of a hand or a walk (a few Hz) does not.
  double block_s = 0.05;
  double gravity_mps2 = 9.81;           ///< local gravity [m/s^2]
  double max_gravity_error_mps2 = 0.5;  ///< | |mean am| - g | must stay below this [m/s^2]
};

struct StaticInitResult {
  double timestamp = 0.0;  ///< end of the static window [s]
  Quat q_n_b = Quat::Identity();
  Vec3 b_g = Vec3::Zero();
  /// (|mean am| - g) along the mean specific force [m/s^2]: a rig whose accelerometer reads
  /// 9.93 m/s^2 at rest under 9.81 would otherwise start 0.12 m/s^2 off and drift 6 cm in 1 s.
  Vec3 b_a = Vec3::Zero();
  double accel_std_mps2 = 0.0;
  double gyro_std_radps = 0.0;

  /// The filter's start at the end of the window: attitude and biases, at rest.
  NavState navState() const;
  /// Whether a filter starting at time t may use it: only a recent interval (the rig may have
  /// moved since; then the next interval or the dynamic initializer starts it).
  bool usableAt(double t) const { return t - timestamp <= 0.5; }
};

/// Attitude with the given body-frame "down" direction mapped to {n}'s z axis and zero yaw.
Quat gravityAlignedAttitude(const Vec3& mean_specific_force_b);

class StaticInitializer {
 public:
  explicit StaticInitializer(const StaticInitParams& params = StaticInitParams());
  /// Adds a sample (non-finite or out-of-order samples are ignored); returns the result as soon
  /// as the last window_s of samples were static.
  std::optional<StaticInitResult> addImu(const ImuData& imu);
  void reset() { window_.clear(); }

 private:
  StaticInitParams params_;
  std::deque<ImuData> window_;
};

}  // namespace vi_ekf_slam
