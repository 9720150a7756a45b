// From sensor samples to estimates: the one path that the ROS node (EkfSlamProcessor), the
// offline bag runner and the simulator's runner all drive. It owns the filter, the queue of
// frames waiting for the IMU to reach them, the camera-to-IMU clock mapping, and the start
// policy: at rest (StaticInitializer), moving (DynamicInitializer), again after a reset or when
// the filter is lost. What it decides it tells a PipelineListener; it never logs or publishes.
#pragma once

#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>

#include "vi_ekf_slam/core/dynamic_init/dynamic_initializer.h"
#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/imu_sample_check.h"
#include "vi_ekf_slam/core/map_reuse/kept_map.h"
#include "vi_ekf_slam/core/map_reuse/relocalization.h"
#include "vi_ekf_slam/core/static_initializer.h"

namespace vi_ekf_slam {

struct PipelineParams {
  StaticInitParams static_init;
  bool dynamic_init_enabled = true;  ///< also start while moving (visual-inertial alignment)
  DynamicInitParams dynamic_init;    ///< with the filter's settings (withFilterSettings)
  int max_frame_queue = 20;          ///< frames waiting for the IMU beyond this are dropped [count]
  /// Each moving-start attempt on a worker thread: the live node's choice, as an attempt can take
  /// longer than a camera period and the sensor callbacks must not wait for it (the frames that
  /// arrive meanwhile go to the initializer, the next attempt starts with the newest). An attempt
  /// that ends before the next frame gives the same start as inline. false: inline, every frame
  /// tried in turn, reproducible (offline runs, the simulator).
  bool background_start_attempts = false;
  /// After a blind stretch, new tracks wait until the first frames' alignment with the IMU (the
  /// moving start's, dynamic_init) re-anchors the velocity (velocity_reanchor.h), at most this long after the camera
  /// sees again [s]; 0: they enter at once. Not when the first frame after the stretch finds landmarks of the map
  /// again.
  double reanchor_max_wait_s = 3.0;
  /// Every problem with the values above that the filter's and initializers' own validate() do not
  /// cover, one per line ("" if none).
  std::string validate() const;
};

/// A camera frame on its way to the filter: its stamp and how to get its features. The features
/// are asked for once, when the frame is used, with the camera's rotation since the previous
/// frame predicted from the gyro (none before the start): the node tracks the image then, the
/// simulator returns the frame it observed.
struct QueuedFrame {
  double t = 0.0;  ///< stamp on the camera clock [s]
  std::function<CameraFrame(const std::optional<Mat3>& R_cur_prev)> features;
};

enum class StartKind {
  kAtRest,  ///< the static initializer (the tracks start anew with the filter)
  kMoving,  ///< the dynamic initializer (the tracks it aligned go on)
};

enum class FrameDrop {
  kLate,       ///< older than the filter's state (it arrived after the IMU had moved past it)
  kQueueFull,  ///< no IMU past its stamp while max_frame_queue newer frames waited
};

/// What the pipeline tells its driver, with the filter it runs. Every method has a default that
/// ignores it.
class PipelineListener {
 public:
  virtual ~PipelineListener() = default;
  /// The filter started; `event` says how (with the initializer's figures).
  virtual void started(StartKind /*kind*/, const std::string& /*event*/, EkfSlam& /*filter*/) {}
  /// Still waiting to start, and why.
  virtual void waiting(const std::string& /*why*/) {}
  virtual void dropped(FrameDrop /*why*/) {}
  /// A frame went through the filter (r.processed false: it could not, r.error says why).
  virtual void processed(const CameraFrame& /*frame*/, const FrameResult& /*r*/, EkfSlam& /*filter*/) {}
  /// The filter was lost (or its state became non-finite) and the pipeline started over.
  virtual void lost(const std::string& /*why*/) {}
  /// An IMU sample was not integrated as it is (clipped at the range or implausible): bridged.
  virtual void imuBridged(const ImuData& /*imu*/, ImuSampleVerdict /*why*/) {}
  /// The filter was placed in the kept map (its world moved by r.T_m_n) before this frame's
  /// processed(); `event` says so with the figures.
  virtual void relocalized(const Relocalization& /*r*/, const std::string& /*event*/, EkfSlam& /*filter*/) {}
  /// After a blind stretch: the velocity was re-anchored by the first frames, or not (`event` says
  /// which, with the figures), and new tracks may become landmarks again.
  virtual void cameBack(const std::string& /*event*/, EkfSlam& /*filter*/) {}
};

class VioPipeline {
 public:
  /// The rest test runs from the first IMU sample on; the filter waits for setCamera().
  VioPipeline(const EkfSlamConfig& config, const PipelineParams& params, PipelineListener& listener);
  /// The same with the camera known from the start.
  VioPipeline(const EkfSlamConfig& config, const PipelineParams& params, const CameraModel& camera,
              const CameraExtrinsics& T_b_c, PipelineListener& listener);

  /// The camera (once its calibration and extrinsic are known, or when they change): a new filter
  /// and moving start for it; the filter starts with the camera's next frame. Throws
  /// std::invalid_argument if the filter's configuration or the camera is impossible.
  void setCamera(const CameraModel& camera, const CameraExtrinsics& T_b_c);
  bool hasCamera() const { return filter_ != nullptr; }
  /// Forgets the camera and its filter (a calibration that changed): nothing runs until setCamera().
  void clearCamera();
  /// A new filter configuration, for the running filter (false and *error: refused) and the next.
  bool setConfig(const EkfSlamConfig& config, std::string* error);

  /// One IMU sample: offered to the start policy and, once the first frame has arrived, buffered
  /// for the filter; every queued frame it reaches is processed. A sample clipped at the IMU's
  /// range or implausible next to its neighbours (ImuSampleCheck) reaches neither: the filter
  /// bridges it.
  void addImu(const ImuData& imu);
  /// One camera frame: before the start it goes to the dynamic initializer, after it to the queue.
  void addFrame(QueuedFrame frame);
  /// Starts from a known state (a study's prior), instead of waiting for the start policy.
  void initialize(const NavState& state);
  /// The end of the stream: the frames still waiting go to the filter, which cannot process
  /// those the IMU does not reach (the listener hears of each).
  void flush();
  /// Forgets state, map, queue and the start policy's windows; starts again at rest or moving.
  void reset();
  /// Background attempts: blocks until the one in flight (if any) has ended; the next sample or
  /// frame takes its outcome (offline drivers and tests that want an attempt per frame).
  void waitForStartAttempt();
  /// Background attempts: whether one is in flight.
  bool startAttemptInFlight() const { return attempt_.has_value(); }

  /// How a start's state is placed in the world before the filter takes it (the simulator
  /// registers it to the truth's position and yaw; none: as the initializer gives it).
  void setRegistration(std::function<NavState(const NavState&)> registration) {
    registration_ = std::move(registration);
  }
  /// The map kept across resets (keep_map with map_relocalize): what earlier runs and a loaded
  /// file mapped, in the map's frame. A new filter is placed in it by relocalization; the first
  /// one of an empty map defines it.
  const KeptMap& map() const { return map_; }
  /// Whether the running filter's world is the map's frame (false: not relocalized yet).
  bool inMap() const { return in_map_; }
  int relocalizations() const { return relocalizations_; }
  /// Replaces the kept map by a file's (KeptMap::load); the running filter is then placed in it
  /// by relocalization. False and *error if the file cannot be used.
  bool loadMap(const std::string& path, std::string* error);
  /// Writes the kept map with the running filter's points (when it is in the map) to a file, and
  /// how many points that is to *points.
  bool saveMap(const std::string& path, std::string* error, int* points = nullptr) const;

  /// The filter (hasCamera() must be true).
  EkfSlam& filter() { return *filter_; }
  const EkfSlam& filter() const { return *filter_; }

 private:
  void tryStatic(double t_now);
  void tryDynamic(QueuedFrame& frame);
  /// An attempt's outcome: the filter starts (true) or the listener hears why it waits.
  bool startMoving(const std::optional<DynamicInitResult>& r, const std::string& why, double frame_t);
  /// Takes a background attempt's outcome if it has ended (true: the filter started).
  bool takeFinishedAttempt();
  void processQueue();
  void process(QueuedFrame& frame);
  /// The state the filter starts from: the registration's, or `s` itself.
  NavState registered(const NavState& s) const { return registration_ ? registration_(s) : s; }
  void forgetStart();
  /// A filter started: it defines the map if the map is empty, else waits to be placed in it.
  void startedMapRun();
  /// Before the filter forgets its run: its points join the map (when its world is the map's).
  void archiveRun();
  /// The filter not in the map yet: this frame's features against the map (PnP); placed on success.
  void tryRelocalize(const CameraFrame& frame);
  /// A blind stretch and the frames after it: hold new landmarks, align the first frames after
  /// it, correct the filter by their body velocity, release (reanchor_max_wait_s).
  void comeBack(const CameraFrame& frame, const FrameResult& r);
  /// Ends a come-back: new tracks may enter again; the listener hears `event`.
  void endComeBack(const std::string& event);

  EkfSlamConfig config_;
  PipelineParams params_;
  PipelineListener& listener_;
  std::unique_ptr<EkfSlam> filter_;
  ImuSampleCheck imu_check_;
  StaticInitializer static_init_;
  std::optional<StaticInitResult> at_rest_;
  std::unique_ptr<DynamicInitializer> dynamic_init_;
  std::optional<double> first_frame_t_;  ///< when waiting for a moving start began (camera clock) [s]
  std::deque<QueuedFrame> queue_;
  std::optional<Quat> prev_q_n_b_;  ///< attitude at the previous frame (the gyro's rotation seed)
  bool camera_running_ = false;     ///< a frame has arrived since setCamera()
  std::function<NavState(const NavState&)> registration_;
  struct StartAttempt {
    double frame_t = 0.0;  ///< the stamp of the frame it was launched at (camera clock) [s]
    std::future<std::pair<std::optional<DynamicInitResult>, std::string>> outcome;
  };
  std::optional<StartAttempt> attempt_;  ///< background attempts: the one in flight
  /// Since a blind stretch began until the come-back ends: the alignment of the frames after it.
  std::unique_ptr<DynamicInitializer> comeback_;
  std::optional<double> sight_back_t_;  ///< the first frame after the stretch [s, IMU clock]
  KeptMap map_;
  bool in_map_ = false;
  int relocalizations_ = 0;
};

}  // namespace vi_ekf_slam
