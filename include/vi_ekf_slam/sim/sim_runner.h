// Runs the core pipeline (VioPipeline, the node's own) over a simulated scenario: the sensor
// stream of one trajectory and world (sensor_stream.h) goes in, and the estimate and the truth
// come out at every camera time.
#pragma once

#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/vio_pipeline.h"
#include "vi_ekf_slam/sim/camera_simulator.h"
#include "vi_ekf_slam/sim/imu_simulator.h"
#include "vi_ekf_slam/sim/landmark_world.h"
#include "vi_ekf_slam/sim/trajectory.h"

namespace vi_ekf_slam::sim {

/// A sensor fault injected into a run during [start_s, start_s + duration_s] (absolute times).
struct SensorFault {
  enum class Kind {
    kImageDropout,   ///< no image reaches the filter
    kImuGap,         ///< no IMU sample reaches the filter
    kOutlierBurst,   ///< `outlier_fraction` of the tracks jump 20-60 px (mistracked features)
    kCameraCovered,  ///< images arrive without any feature
    kImuClipped,     ///< one IMU sample a second clipped at the range of ImuCheckParams (a bump)
    kReset,          ///< the filter is reset at start_s (the node's ~reset), its tracks end there
  };
  Kind kind = Kind::kImageDropout;
  double start_s = 0.0;
  double duration_s = 0.0;
  double outlier_fraction = 0.3;
  bool covers(double t) const { return t >= start_s && t < start_s + duration_s; }
};
std::string toString(SensorFault::Kind kind);
/// The kind named by toString(), or nothing.
std::optional<SensorFault::Kind> sensorFaultKindFromString(const std::string& s);
/// The fault of this kind active at time t, or nullptr.
const SensorFault* activeFault(const std::vector<SensorFault>& faults, SensorFault::Kind kind, double t);

struct Scenario {
  std::shared_ptr<const Trajectory> trajectory;
  LandmarkWorld world;
  CameraModel camera;
  CameraExtrinsics T_b_c;
  /// The extrinsic the filter is given, when it is not the true one (a rig measured with a ruler).
  std::optional<CameraExtrinsics> given_T_b_c;
  ImuSimParams imu;
  CameraSimParams cam;
  /// A recorded IMU stream to use instead of synthesizing one from the trajectory (see
  /// recorded_imu.h); its true biases are NaN where the ground truth does not know them.
  std::shared_ptr<const ImuSequence> recorded_imu;
  /// Monte-Carlo runs start from the true state (zero biases, no drawn initial error; the
  /// filter's initial covariance is only its belief), as OpenVINS's simulator does.
  bool start_at_truth = false;
  /// The simulated IMU's turn-on biases are drawn from the filter's prior (true), or zero (false:
  /// a diagnostic of what not knowing them costs a start; the filter still has its prior).
  bool draw_imu_biases = true;
  /// Faults injected while running (none by default).
  std::vector<SensorFault> faults;
  /// Start as the node does: the filter waits for the static initializer (a recent interval at
  /// rest) or the dynamic initializer (core/dynamic_initializer.h), whichever answers first on
  /// the frames and IMU from the start on, instead of starting from `initial`. Its estimate is
  /// registered to the truth's position and yaw (what it cannot know) with an error drawn from
  /// the filter's prior, as a prior start is.
  std::optional<DynamicInitParams> dynamic_init;
  /// After a blind stretch, new tracks wait for the re-anchor at most this long [s] (PipelineParams).
  double reanchor_max_wait_s = PipelineParams().reanchor_max_wait_s;
  /// Such a start is registered to the truth (false: the filter keeps the initializer's own
  /// position and yaw, as the node does).
  bool register_to_truth = true;
  /// The sensors' stamps are rounded to this, as a recorder's clock keeps them (1e-9: ROS time);
  /// 0: exact [s].
  double stamp_resolution_s = 0.0;
  /// A map file (VioPipeline::loadMap) the run starts with, and one it saves at its end ("": none).
  std::string load_map_file, save_map_file;
};

/// One camera time of a run.
struct FrameRecord {
  double t = 0.0;
  TrajectorySample truth;
  Vec3 true_accel_bias = Vec3::Zero();
  Vec3 true_gyro_bias = Vec3::Zero();
  NavState estimate;
  FrameResult result;
  int landmarks_in_state = 0;
  double filter_ms = 0.0;      ///< wall time of the pipeline on the IMU sample that released the frame (propagation,
                               ///< update, new landmarks, composition)
  double initialized_t = 0.0;  ///< when the filter was (last) initialized [s]
  /// The filter was placed in the kept map just before this frame: the relocalization's inliers
  /// and those of them that paired a feature with another point (the simulator knows).
  bool relocalized = false;
  int relocalization_inliers = 0;
  int relocalization_false_pairs = 0;
  bool in_map = false;  ///< the filter's world is the kept map's (VioPipeline::inMap)
};

struct SimRun {
  /// Frames from the initialization on (frames before a dynamic initialization are not recorded).
  std::vector<FrameRecord> frames;
  double initialized_t = std::nan("");  ///< when the filter was initialized; NaN: never [s]
  std::vector<NavLandmark> final_landmarks;
};

/// Called after each processed frame, with the filter (for extra per-frame metrics).
using FrameCallback = std::function<void(EkfSlam&, FrameRecord&)>;

/// Runs the filter from `initial` (usually the truth plus an error drawn by the caller), or with
/// Scenario::dynamic_init from the dynamic initializer (`initial.timestamp` is then the start).
/// The random generator drives sensor noise. keep_frames = false leaves SimRun::frames empty
/// (long runs that only need the callback).
SimRun runSimulation(const Scenario& scenario, const EkfSlamConfig& config, const NavState& initial,
                     std::mt19937_64& rng, const FrameCallback& callback = nullptr, bool keep_frames = true);

/// The node's start policy for a simulated run: its static initializer at the filter's gravity, the
/// scenario's dynamic initializer (its defaults with the filter's settings without one), and a
/// queue that holds every frame.
PipelineParams simulatedNodeStart(const Scenario& sc, const EkfSlamConfig& config);

/// The true navigation state at time t (zero biases) for initialization.
NavState trueNavState(const Trajectory& trajectory, double t);

/// A state known up to position and yaw (a dynamic initialization's, p = 0, yaw = 0) moved into
/// the truth's frame: the truth's position and yaw minus errors drawn with the sigmas of `u`
/// (what a registration to the map would leave); roll, pitch, velocity in the body frame and the
/// biases stay the estimate's.
NavState registerToTruth(const NavState& aligned, const NavState& truth, const InitialUncertainty& u,
                         std::mt19937_64& rng);

/// A start over after the filter was lost, placed where the last estimate was (its position and
/// yaw), as the node keeps its odometry continuous.
NavState continueFrom(const NavState& aligned, const NavState& last);

}  // namespace vi_ekf_slam::sim
