// Which chi^2 gate the visual update uses. The gate is there for outliers (a track that slid onto
// another corner, an occlusion edge). On tracks without any, it only cuts the tails of the pixel
// noise, and not at random: where the state is off, it cuts the observations whose noise adds to
// the error and keeps those that agree with the state, so the error lingers (a slow start's
// scale). So the update gates at gate_probability while the tracks show outliers, and at
// the wider clean_gate_probability once the images of the last clean_gate_s seconds the rig moved
// had none beyond it. Seconds, not a count of observations: right after a start every track is
// fresh (a dynamic initialization even keeps only the features its alignment fits), and tracks
// slip as they age, so a few hundred observations of the first images said nothing of the
// hand-held recording's (its 10 s cut diverged with a 300-observation count). Images at rest do
// not count: a still camera's tracks do not slip. At rest is the images' standing test where it
// has decided, else the IMU's (a crawl is as quiet to the IMU as a stand; gtest
// SensorFaults.TheGateWidensDuringACrawlWhoseImuLooksAtRest). Real tracks do have outliers (1-6% of the
// observations beyond 99.99% on the hand-held recording), so there the gate stays narrow.
#pragma once

#include <optional>

#include "vi_ekf_slam/core/ekf_update.h"

namespace vi_ekf_slam {

class OutlierWatch {
 public:
  /// Outliers assumed until shown otherwise (a start, a reset).
  void reset() {
    clean_s_ = 0.0;
    last_moving_t_.reset();
  }
  /// The gate probability for the next update.
  double gateProbability(const UpdateParams& p) const;
  /// An update at time t [s]; moving: the rig was seen moving (not at rest, parallax).
  void record(const UpdateResult& r, bool moving, double t, const UpdateParams& p);
  /// Seconds of moving images since the last outlier (at most clean_gate_s) [s].
  double cleanSeconds() const { return clean_s_; }

 private:
  double clean_s_ = 0.0;
  std::optional<double> last_moving_t_;  ///< the last moving image's time [s]
};

}  // namespace vi_ekf_slam
