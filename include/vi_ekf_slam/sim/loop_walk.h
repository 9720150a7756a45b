// An endurance walk: a pedestrian doing laps around a rectangular block of corridors, with the
// gait of the built-in hallway walk (step bounce, sway, torso oscillation), for any duration.
#pragma once

#include <memory>

#include "vi_ekf_slam/sim/bspline_trajectory.h"
#include "vi_ekf_slam/sim/hallway.h"
#include "vi_ekf_slam/sim/sim_runner.h"

namespace vi_ekf_slam::sim {

struct LoopParams {
  double length_m = 30.0;        ///< block length (centreline)
  double width_m = 12.0;         ///< block width (centreline)
  double corner_radius_m = 1.0;  ///< turns at the corners
  double duration_s = 1800.0;    ///< standing included
};

/// Laps (clockwise seen from above, right turns) starting at the middle of a long side, after
/// gait.standing_s of standing; gait.speed_mps along the path, reached within 1 s.
std::shared_ptr<BsplineTrajectory> loopWalk(const HallwayParams& gait, const LoopParams& loop);

/// The loop walk with landmarks scattered 1-10 m around one lap (later laps see them again),
/// the paper's camera (28 Hz) and IMU (200 Hz).
Scenario loopScenario(const HallwayParams& gait, const LoopParams& loop, std::uint64_t world_seed);

}  // namespace vi_ekf_slam::sim
