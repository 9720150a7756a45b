// The one gait model of the simulator: how a torso-worn rig moves about a walker's centreline.
// The step bounce at the step frequency; lateral sway, torso yaw and roll at the stride frequency
// (half of it); torso pitch at the step frequency; all scaled with the speed (standing still: none),
// and, standing, a small postural sway at 0.2-0.5 Hz. The built-in hallway walk, the loop walk and
// the generated walks (generated_walks.h) are this model with their parameters.
#pragma once

#include <cstdint>

#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/io/tum_io.h"

namespace vi_ekf_slam::sim {

struct GaitParams {
  double cruise_speed_mps = 1.3;   ///< the speed at which the amplitudes below hold [m/s]
  double step_frequency_hz = 1.9;  ///< steps per second at the cruise speed (two per stride) [Hz]
  /// The cadence scales as (speed / cruise)^this [-]: 0 a constant cadence; 0.5 the step length
  /// and the cadence both grow with the speed (1.9 steps/s at 1.3 m/s, 1.2 at 0.5 m/s).
  double cadence_speed_exponent = 0.0;
  double max_amplitude = 1e9;       ///< the amplitudes scale with speed / cruise, up to this [ratio]
  double bounce_m = 0.025;          ///< vertical amplitude at the step frequency [m]
  double sway_m = 0.03;             ///< lateral amplitude at the stride frequency [m]
  double yaw_sway_rad = 0.035;      ///< torso yaw oscillation (~2 deg) [rad]
  double roll_sway_rad = 0.026;     ///< torso roll oscillation (~1.5 deg) [rad]
  double pitch_bob_rad = 0.017;     ///< torso pitch at the step frequency (~1 deg) [rad]
  double postural_sway_m = 0.0;     ///< standing: lateral sway [m]
  double postural_pitch_rad = 0.0;  ///< standing: pitch sway [rad]
};

class Gait {
 public:
  /// seed draws the postural sway's two frequencies (0.2-0.5 Hz).
  explicit Gait(const GaitParams& params, std::uint64_t seed = 0);
  /// The step phase advanced over dt [s] walking at v [m/s].
  void advance(double v, double dt);
  /// The rig at time t [s] whose centreline point is `centre` with heading `heading` [rad] (yaw
  /// about the frame's z), walking at v [m/s]. The lateral offset is along the heading turned by
  /// +90 deg about z; the vertical along z.
  io::StampedPose pose(double t, Vec3 centre, double heading, double v) const;
  double phase() const { return phase_; }

 private:
  GaitParams p_;
  double phase_ = 0.0;
  double f1_hz_ = 0.0, f2_hz_ = 0.0;
};

}  // namespace vi_ekf_slam::sim
