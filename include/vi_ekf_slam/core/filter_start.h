// The state the filter starts from: at rest (static_initializer.h) or moving (dynamic_initializer.h),
// always world-centric (the initial pose uncertainty is the registration error in {n}; EkfSlam then
// switches to its mechanization). Its covariance is the initializer's (InitialUncertainty), and a
// moving start brings the landmarks it aligned, with their joint uncertainty. Stateless: the
// filter's start is these states.
#pragma once

#include <optional>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"
#include "vi_ekf_slam/core/ekf_slam_config.h"
#include "vi_ekf_slam/core/filter_state.h"
#include "vi_ekf_slam/core/navigation_output.h"

namespace vi_ekf_slam {

/// A state of the configured layout (estimate_extrinsic) with the calibrated extrinsic and nothing else.
FilterState emptyState(const EkfSlamConfig& config, const CameraExtrinsics& T_b_c, Mechanization m);

/// The world-centric starting state at `init` (its timestamp), the covariance u's (the
/// registration's: position and yaw; an initializer's velocity, tilt and accelerometer bias with
/// their correlations). time_offset_s, if given, replaces camera_time_offset_s as the time
/// offset's initial value. (A restart forgets a refined extrinsic: it starts from T_b_c.)
FilterState startingState(const EkfSlamConfig& config, const CameraExtrinsics& T_b_c, const NavState& init,
                          const InitialUncertainty& u, std::optional<double> time_offset_s);

/// The starting state of a dynamic initialization: its state (or `registered`, the same moved to a
/// known position and yaw), its uncertainty over config.initial, its time offset, and the features
/// it aligned as landmarks at their depth, with their joint uncertainty (one scale error for all
/// and the velocity); their number in *landmarks_added.
FilterState alignedStartingState(const EkfSlamConfig& config, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                                 const DynamicInitResult& aligned, const NavState& registered, int* landmarks_added);

}  // namespace vi_ekf_slam
