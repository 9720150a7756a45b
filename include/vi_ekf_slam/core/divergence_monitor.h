// Knows when the filter is lost: a pedestrian does not move at tens of m/s, a consistent filter's
// chi-square gate rejects about 1 - gate_probability of the observations (not most of them), and a
// covariance must stay positive definite. Each test looks at the filter after an image; the
// first two must hold over a window, so a swing of the arm or a 1 s burst of bad tracks is not a
// divergence. The caller (the node) resets and re-initializes on a verdict.
#pragma once

#include <deque>
#include <string>

#include "vi_ekf_slam/core/filter_state.h"

namespace vi_ekf_slam {

struct DivergenceParams {
  bool enabled = true;
  double max_speed_mps = 5.0;          ///< a faster body for the whole window is implausible [m/s]
  double max_rejected_fraction = 0.5;  ///< of the observations in the window (consistent: ~0.05) [ratio]
  double window_s = 2.0;               ///< both tests must hold over this long [s]
  int min_observations = 30;           ///< the rejection test needs this many observations in the window
  std::string validate() const;
};

class DivergenceMonitor {
 public:
  /// Looks at the filter after an image at time t [s] (IMU clock) with the update's accepted and
  /// rejected counts. Returns why the filter is lost, or an empty string.
  std::string update(double t, const FilterState& state, int accepted, int rejected, const DivergenceParams& params);
  void reset() { window_.clear(); }

 private:
  struct Sample {
    double t;
    double speed_mps;
    int accepted, rejected;
  };
  std::deque<Sample> window_;
};

}  // namespace vi_ekf_slam
