// Pedestrian walks the shared recordings lack, made by formula for the study and the suite: round
// a rectangular block of corridors (rounded corners) with the simulator's gait model (gait.h; a
// cadence that falls with the square root of the speed, amplitudes capped at 1.2x cruise, postural
// sway when standing). The suite's kinds:
//   slow_start  a slow walk (0.5 m/s) reaching 1.3 m/s only after 20 s;
//   crawl       a crawl (0.3 m/s: feeling the way in smoke or the dark) for 10 s, 1.3 m/s from 12 s;
//   stops       1.3 m/s with stands of 5, 12 and 20 s (about a third of the time standing);
//   stairs      walks, climbs a flight of stairs (2.8 m up over 5 m), walks on, comes back down;
//   fast        a brisk walk at 2.4 m/s from the start (a hurried responder);
//   stairwell   from a stand, within a second up a stairwell that turns all the time (a helix of
//               1.6 m radius, 0.75 rad/s, 0.24 m up per second) for 34 s, then the block.
// Probes the suite does not run by default: slow_walk (0.6 m/s), start04 (0.4 m/s for 10 s),
// stop_and_go (a 1 s stop every 7 s), small_room (1.0 m/s round a 6 m x 4 m room), run (3.5 m/s),
// and the walks that come back to where they have been (a map's revisits): there_and_back (40 m
// down a corridor and back), laps (twice round the block); steady (0.3 m/s for 60 s down a straight,
// the gait's torso angles without its bounce and sway: no acceleration at all, so the scale is
// unobservable and any information the filter gains on it is false, docs/evaluation.md#known-limits).
#pragma once

#include <string>
#include <vector>

#include "vi_ekf_slam/io/tum_io.h"

namespace vi_ekf_slam::sim {

/// The kinds, the suite's first; suite_only: only those.
std::vector<std::string> generatedWalkKinds(bool suite_only);

/// The walk of a kind: poses at 100 Hz from t = 0, z up, body x forward (a TUM trajectory).
/// Throws std::invalid_argument for an unknown kind.
std::vector<io::StampedPose> generatedWalk(const std::string& kind);

}  // namespace vi_ekf_slam::sim
