// How the filter starts: from a static interval (StaticInitializer: roll, pitch, biases at rest)
// or, while moving, from the visual-inertial alignment of a window of tracks and IMU
// (DynamicInitializer). One job: say when and with what the filter can start, and start it.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "vi_ekf_slam/core/dynamic_initializer.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/static_initializer.h"
#include "vi_ekf_slam/ros/params.h"

namespace vi_ekf_slam::glue {

class FilterStart {
 public:
  explicit FilterStart(const NodeParams& params) : params_(params), static_init_(params.static_init) {}

  /// The camera the dynamic initializer aligns (when the filter is created).
  void setCamera(const CameraModel& camera, const CameraExtrinsics& T_b_c);
  /// Every IMU sample; `waiting`: the filter is not initialized (the dynamic initializer collects).
  void addImu(const ImuData& d, bool waiting);
  /// Initializes `filter` from a static interval that ended within 0.5 s of t_now; returns the
  /// event text, or nullopt when there is none.
  std::optional<std::string> tryStatic(EkfSlam& filter, double t_now);
  /// Adds a tracked frame (on the IMU clock; `image_t` its camera stamp) and initializes `filter`
  /// when the window aligns; returns the event text, or nullopt with *waiting saying why not.
  std::optional<std::string> tryDynamic(EkfSlam& filter, const CameraFrame& frame, double image_t,
                                        std::string* waiting);
  /// The attitude the dynamic initializer started the filter with (valid after tryDynamic).
  const Quat& dynamicAttitude() const { return dynamic_q_n_b_; }
  /// Forgets every interval and window (a reset, or the filter started).
  void reset();

 private:
  NodeParams params_;
  StaticInitializer static_init_;
  std::optional<StaticInitResult> static_result_;
  std::unique_ptr<DynamicInitializer> dynamic_init_;
  std::optional<double> first_image_t_;  ///< when waiting for initialization began [s]
  Quat dynamic_q_n_b_ = Quat::Identity();
};

}  // namespace vi_ekf_slam::glue
