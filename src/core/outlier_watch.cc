#include "vi_ekf_slam/core/outlier_watch.h"

#include <algorithm>

namespace vi_ekf_slam {

double OutlierWatch::gateProbability(const UpdateParams& p) const {
  return clean_s_ >= p.clean_gate_s ? p.outlierProbability() : p.gate_probability;
}

void OutlierWatch::record(const UpdateResult& r, bool moving, double t, const UpdateParams& p) {
  if (!moving) {
    last_moving_t_.reset();  // the seconds at rest do not count
    return;
  }
  if (r.outliers > 0) {
    clean_s_ = 0.0;
  } else if (last_moving_t_ && t > *last_moving_t_) {
    clean_s_ = std::min(clean_s_ + (t - *last_moving_t_), p.clean_gate_s);
  }
  last_moving_t_ = t;
}

}  // namespace vi_ekf_slam
