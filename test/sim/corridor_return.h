// The simulator's corridor walked there and back (generated_walks.h), cut to the end of the way
// out, the U-turn and the way back: the scenario of the map-keeping tests.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "scratch_dir.h"
#include "vi_ekf_slam/io/tum_io.h"
#include "vi_ekf_slam/sim/generated_walks.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam::sim {

/// 14 to 52 s of there_and_back, with `texture_patterns` repeated appearances (0: each unique).
inline Scenario corridorReturn(int texture_patterns) {
  const std::string path = test::programScratch() / "there_and_back.txt";
  io::writeTum(path, generatedWalk("there_and_back"));
  Scenario sc = tumScenario(path, 15.0, 1);
  sc.trajectory = std::make_shared<TruncatedTrajectory>(sc.trajectory, sc.trajectory->startTime() + 14.0,
                                                        sc.trajectory->startTime() + 52.0);
  sc.cam.descriptors.texture_patterns = texture_patterns;
  return sc;
}

}  // namespace vi_ekf_slam::sim
