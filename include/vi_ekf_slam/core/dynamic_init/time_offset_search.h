// The dynamic initializer's time-offset stage: the camera-IMU time offset is part of the
// alignment. The best of the refined alignments on a 10 ms grid over +-search_s, then a
// golden-section search over +-10 ms around it. (The linear solution's cost is no guide: its bias
// moves its best by tens of ms with 1 px noise, into a minimum the refinement cannot leave.) Grid
// points compare by their cost per observation, as each keeps the features in front of the camera
// there.
#pragma once

#include "vi_ekf_slam/core/dynamic_init/alignment_problem.h"

namespace vi_ekf_slam {
namespace alignment {

struct TimeOffsetFit {
  double dt_s = 0.0;       ///< the shift of the frames on the IMU clock with the best alignment [s]
  double curvature = 0.0;  ///< d^2 cost / d dt^2 there [px^2/s^2] (0: not searched or not convex)
};

/// Leaves `problem` with its active features chosen at the best shift (search_s <= 0: at 0, not
/// searched); the caller refines at the returned dt.
TimeOffsetFit searchTimeOffset(AlignmentProblem& problem, double search_s);

}  // namespace alignment
}  // namespace vi_ekf_slam
