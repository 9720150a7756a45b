// Which IMU samples can be integrated as they are. A MEMS IMU that is bumped (a door frame, a
// wall, a fall) clips at its measurement range for a sample or two; a driver glitch gives a sample
// no rigid motion of a worn or hand-held rig produces next to its neighbours. Either, integrated
// as it is, puts a velocity error of the order of range x sample period (16 g x 5 ms = 0.8 m/s)
// into the filter, which then rejects every observation and is lost. Such a sample is left out:
// the propagation bridges it (the neighbours are interpolated) and the covariance grows by what
// it could have hidden (its own departure from the last good sample over its period).
#pragma once

#include <cmath>
#include <optional>
#include <string>

#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct ImuCheckParams {
  /// The sensor's measurement range per axis [m/s^2] (datasheet; REP-145 has no field for it): a
  /// reading at 99.9% of it or beyond is clipped. 0: not checked.
  double accel_range_mps2 = 16.0 * 9.80665;
  double gyro_range_radps = 2000.0 * M_PI / 180.0;  ///< the same for the gyro [rad/s]
  /// A sample that departs from the last good one by more than this on any axis is implausible
  /// (10 g within one sample) [m/s^2]; 0: not checked.
  double max_accel_step_mps2 = 100.0;
  double max_gyro_step_radps = 20.0;  ///< the same for the gyro [rad/s]
  /// More consecutive implausible samples than this are a real change of level, taken as it is.
  int max_bridged_samples = 2;
  std::string validate() const;
};

enum class ImuSampleVerdict { kGood, kClipped, kImplausible };

class ImuSampleCheck {
 public:
  /// The verdict on a finite sample; a good one (or one taken after max_bridged_samples) becomes
  /// the reference of the next.
  ImuSampleVerdict check(const ImuData& imu, const ImuCheckParams& p);
  /// The last sample taken as good.
  const std::optional<ImuData>& lastGood() const { return last_good_; }
  void reset() {
    last_good_.reset();
    bridged_ = 0;
  }

 private:
  std::optional<ImuData> last_good_;
  int bridged_ = 0;  ///< consecutive samples left out
};

}  // namespace vi_ekf_slam
