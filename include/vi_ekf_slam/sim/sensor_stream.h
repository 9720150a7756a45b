// The simulated rig's two sensor streams in the order a recorder would deliver them: each IMU
// sample (synthesized from the trajectory, or a recorded one), then the camera frames stamped up to
// it, with the scenario's faults injected. Whoever drives the core pipeline (the simulator's
// runner, the tests that feed the ROS processor) reads the same events.
#pragma once

#include <optional>
#include <random>

#include "vi_ekf_slam/sim/camera_simulator.h"
#include "vi_ekf_slam/sim/sim_runner.h"

namespace vi_ekf_slam::sim {

class SensorStream {
 public:
  struct Event {
    std::optional<ImuData> imu;        ///< an IMU sample, or
    std::optional<CameraFrame> frame;  ///< a camera frame (stamp on the camera clock)
    size_t imu_index = 0;              ///< the IMU sample the stream has reached
    bool reset_before = false;         ///< a kReset fault: the filter is reset before this frame
  };

  /// Frames start one camera period after t0; the IMU noise is drawn now, the frames' as they come.
  SensorStream(const Scenario& sc, double t0, std::mt19937_64& rng);
  /// The next event; false at the end of the stream.
  bool next(Event* e);
  const ImuSequence& imu() const { return *imu_; }

 private:
  /// A stamp as the scenario's recorder keeps it (Scenario::stamp_resolution_s).
  double stamp(double t) const;

  const Scenario& sc_;
  std::mt19937_64& rng_;
  ImuSequence simulated_;
  const ImuSequence* imu_;
  TrackingCamera camera_;
  double t0_, cam_dt_, last_frame_t_;
  size_t k_ = 0;                 ///< next IMU sample
  int next_frame_ = 1;           ///< next camera frame (index from t0)
  bool imu_given_ = false;       ///< sample k_ - 1 was handed out; its frames follow
  double next_clip_t_ = -1e300;  ///< the next sample a kImuClipped fault clips at or after [s]
};

}  // namespace vi_ekf_slam::sim
