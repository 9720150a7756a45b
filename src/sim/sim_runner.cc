#include "vi_ekf_slam/sim/sim_runner.h"

#include "vi_ekf_slam/sim/sensor_stream.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam::sim {

NavState trueNavState(const Trajectory& trajectory, double t) {
  const TrajectorySample s = trajectory.sample(t);
  NavState n;
  n.timestamp = t;
  n.p_n_b = s.p_n_b;
  n.v_n_b = s.v_n_b;
  n.q_n_b = s.q_n_b;
  return n;
}

namespace {
/// `aligned` turned about the vertical by yaw_rad and moved to position p_n_b (what a start that
/// knows neither position nor yaw is told); roll, pitch, body-frame velocity and biases stay.
NavState placed(const NavState& aligned, double yaw_rad, const Vec3& p_n_b) {
  const Quat R_z(Eigen::AngleAxisd(yaw_rad, Vec3::UnitZ()));
  NavState r = aligned;
  r.q_n_b = (R_z * aligned.q_n_b).normalized();
  r.v_n_b = R_z * aligned.v_n_b;
  r.p_n_b = p_n_b;
  return r;
}
}  // namespace

NavState registerToTruth(const NavState& aligned, const NavState& truth, const InitialUncertainty& u,
                         std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double yaw_error = u.yaw_rad * n(rng);
  const double x = n(rng), y = n(rng), z = n(rng);
  return placed(aligned, yawBetween(aligned.q_n_b, truth.q_n_b) - yaw_error,
                truth.p_n_b - u.position_m * Vec3(x, y, z));
}

NavState continueFrom(const NavState& aligned, const NavState& last) {
  return placed(aligned, yawBetween(aligned.q_n_b, last.q_n_b), last.p_n_b);
}

std::string toString(SensorFault::Kind kind) {
  switch (kind) {
    case SensorFault::Kind::kImageDropout:
      return "image_dropout";
    case SensorFault::Kind::kImuGap:
      return "imu_gap";
    case SensorFault::Kind::kOutlierBurst:
      return "outlier_burst";
    case SensorFault::Kind::kCameraCovered:
      return "camera_covered";
    case SensorFault::Kind::kImuClipped:
      return "imu_clipped";
    case SensorFault::Kind::kReset:
      return "reset";
  }
  return "unknown";
}

std::optional<SensorFault::Kind> sensorFaultKindFromString(const std::string& s) {
  for (auto k : {SensorFault::Kind::kImageDropout, SensorFault::Kind::kImuGap, SensorFault::Kind::kOutlierBurst,
                 SensorFault::Kind::kCameraCovered, SensorFault::Kind::kImuClipped, SensorFault::Kind::kReset}) {
    if (toString(k) == s) return k;
  }
  return std::nullopt;
}

const SensorFault* activeFault(const std::vector<SensorFault>& faults, SensorFault::Kind kind, double t) {
  for (const auto& f : faults) {
    if (f.kind == kind && f.covers(t)) return &f;
  }
  return nullptr;
}

namespace {

/// Mistracks a fraction of the features: each chosen one jumps 20-60 px in a random direction.
void corruptFeatures(CameraFrame& frame, double fraction, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (auto& f : frame.features) {
    if (u(rng) >= fraction) continue;
    const double r = 20.0 + 40.0 * u(rng), a = 2.0 * M_PI * u(rng);
    f.uv += r * Eigen::Vector2d(std::cos(a), std::sin(a));
  }
}

}  // namespace

PipelineParams simulatedNodeStart(const Scenario& sc, const EkfSlamConfig& config) {
  PipelineParams p;
  p.static_init.gravity_mps2 = config.gravity_mps2;
  p.dynamic_init = sc.dynamic_init ? *sc.dynamic_init : withFilterSettings(DynamicInitParams(), config);
  // The simulator's queue holds every frame the IMU has not reached (a node drops the oldest
  // beyond its bound; a simulated stream never falls that far behind).
  p.max_frame_queue = std::numeric_limits<int>::max();
  p.reanchor_max_wait_s = sc.reanchor_max_wait_s;
  return p;
}

namespace {

/// The simulator's side of the pipeline: records every frame with the truth at its time.
class RunRecorder : public PipelineListener {
 public:
  RunRecorder(const Scenario& sc, const ImuSequence& imu, const FrameCallback& callback, bool keep_frames, SimRun* run)
      : sc_(sc), imu_(imu), callback_(callback), keep_frames_(keep_frames), run_(run) {}
  /// Index of the IMU sample the stream has reached (the truth's biases there).
  size_t imu_index = 0;
  /// When the pipeline call that may process frames began (their wall time is counted from it).
  std::chrono::steady_clock::time_point tic;

  /// The last estimate of a filter that was not lost (a start over continues from it).
  std::optional<NavState> last_estimate;
  bool lost_before = false;  ///< the filter was lost since the run began

  void started(StartKind /*kind*/, const std::string& /*event*/, EkfSlam& filter) override {
    run_->initialized_t = filter.state().timestamp;
  }
  void lost(const std::string& /*why*/) override { lost_before = true; }
  void relocalized(const Relocalization& r, const std::string& /*event*/, EkfSlam& /*filter*/) override {
    relocalization_ = r;
  }
  /// The pipeline, for whether the filter is in the kept map.
  const VioPipeline* pipeline = nullptr;
  void processed(const CameraFrame& frame, const FrameResult& r, EkfSlam& filter) override {
    FrameRecord rec;
    rec.result = r;
    rec.filter_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
    // The truth at the time of the estimate (the stamp plus the estimated time offset).
    rec.t = r.processed ? filter.state().timestamp : frame.timestamp + sc_.cam.time_offset_s;
    rec.truth = sc_.trajectory->sample(std::min(rec.t, sc_.trajectory->endTime()));
    const size_t k = std::min(imu_index, imu_.true_accel_bias.size() - 1);
    rec.true_accel_bias = imu_.true_accel_bias[k];
    rec.true_gyro_bias = imu_.true_gyro_bias[k];
    rec.estimate = filter.navState();
    if (r.processed && r.lost.empty()) last_estimate = rec.estimate;
    rec.landmarks_in_state = filter.state().numLandmarks();
    rec.initialized_t = run_->initialized_t;
    if (relocalization_) {
      rec.relocalized = true;
      rec.relocalization_inliers = relocalization_->inliers;
      // A pair is false when the map point's true landmark is not where the feature is (a searched
      // corner has no track id: its pixel is what the truth can check).
      MotionState truth;
      truth.p_s_b = rec.truth.p_n_b;
      truth.q_s_b = rec.truth.q_n_b;
      for (const auto& pair : relocalization_->pairs) {
        const Vec3 p_c = landmarkInCamera(truth, landmarkOfTrack(pair.point_id, sc_.world).p_n, sc_.T_b_c);
        Eigen::Vector2d uv;
        const bool there = p_c.z() > 0.0 && sc_.camera.project(p_c, &uv) &&
                           (uv - pair.uv).norm() <= 5.0 * std::max(1.0, sc_.cam.pixel_noise_px);
        if (!there) ++rec.relocalization_false_pairs;
      }
      relocalization_.reset();
    }
    rec.in_map = pipeline && pipeline->inMap();
    if (callback_) callback_(filter, rec);
    if (keep_frames_) run_->frames.push_back(std::move(rec));
  }

 private:
  const Scenario& sc_;
  const ImuSequence& imu_;
  const FrameCallback& callback_;
  bool keep_frames_;
  SimRun* run_;
  std::optional<Relocalization> relocalization_;  ///< told before the frame's processed()
};

}  // namespace

SensorStream::SensorStream(const Scenario& sc, double t0, std::mt19937_64& rng)
    : sc_(sc),
      rng_(rng),
      simulated_(sc.recorded_imu ? ImuSequence() : simulateImu(*sc.trajectory, sc.imu, rng)),
      imu_(sc.recorded_imu ? sc.recorded_imu.get() : &simulated_),
      camera_(sc.world, sc.camera, sc.T_b_c, sc.cam),
      t0_(t0),
      cam_dt_(1.0 / sc.cam.rate_hz),
      // The IMU runs on past the last image, as a recorder's does, so that an image whose stamp
      // plus the time offset estimate is up to 0.1 s later still finds IMU data past it.
      last_frame_t_(sc.trajectory->endTime() - 0.1) {}

double SensorStream::stamp(double t) const {
  const double r = sc_.stamp_resolution_s;
  return r > 0.0 ? std::round(t / r) * r : t;
}

bool SensorStream::next(Event* e) {
  *e = Event();
  while (true) {
    if (imu_given_) {
      const double t_imu = imu_->samples[k_ - 1].timestamp;
      const double t = t0_ + next_frame_ * cam_dt_;
      if (t <= t_imu + 1e-12 && t <= last_frame_t_) {
        ++next_frame_;
        // A dropped image never reaches the tracker, which goes on from the last image it got; a
        // covered lens shows it nothing to follow, so every track ends there (the points it finds
        // after are new tracks, as a KLT tracker's are).
        if (activeFault(sc_.faults, SensorFault::Kind::kImageDropout, t)) continue;
        CameraFrame frame;
        // A reset ends every track (the node's tracker starts over with the filter).
        for (const auto& f : sc_.faults) {
          if (f.kind == SensorFault::Kind::kReset && f.start_s > t - cam_dt_ && f.start_s <= t) {
            camera_.loseTracks();
            e->reset_before = true;
          }
        }
        if (activeFault(sc_.faults, SensorFault::Kind::kCameraCovered, t)) {
          camera_.loseTracks();
        } else {
          frame = camera_.observe(sc_.trajectory->sample(t), &rng_);
        }
        frame.timestamp = stamp(t - sc_.cam.time_offset_s);
        if (const SensorFault* f = activeFault(sc_.faults, SensorFault::Kind::kOutlierBurst, t)) {
          corruptFeatures(frame, f->outlier_fraction, rng_);
        }
        e->frame = std::move(frame);
        e->imu_index = k_ - 1;
        return true;
      }
      imu_given_ = false;
    }
    if (k_ >= imu_->samples.size()) return false;
    const ImuData& d = imu_->samples[k_++];
    imu_given_ = true;
    if (activeFault(sc_.faults, SensorFault::Kind::kImuGap, d.timestamp)) continue;
    e->imu = d;
    if (const SensorFault* f = activeFault(sc_.faults, SensorFault::Kind::kImuClipped, d.timestamp)) {
      // One sample a second at the sensor's range (an accelerometer and a gyro axis), as a bump does.
      if (next_clip_t_ < f->start_s) next_clip_t_ = f->start_s;
      if (d.timestamp >= next_clip_t_) {
        const ImuCheckParams range;
        e->imu->am.x() = std::copysign(range.accel_range_mps2, d.am.x());
        e->imu->wm.z() = std::copysign(range.gyro_range_radps, d.wm.z());
        next_clip_t_ += 1.0;
      }
    }
    e->imu->timestamp = stamp(d.timestamp);
    e->imu_index = k_ - 1;
    return true;
  }
}

SimRun runSimulation(const Scenario& sc, const EkfSlamConfig& config, const NavState& initial, std::mt19937_64& rng,
                     const FrameCallback& callback, bool keep_frames) {
  const Trajectory& traj = *sc.trajectory;
  SensorStream stream(sc, initial.timestamp, rng);
  const ImuSequence& imu = stream.imu();
  SimRun run;
  RunRecorder recorder(sc, imu, callback, keep_frames, &run);
  VioPipeline pipeline(config, simulatedNodeStart(sc, config), sc.camera, sc.given_T_b_c.value_or(sc.T_b_c), recorder);
  recorder.pipeline = &pipeline;
  std::string map_error;
  if (!sc.load_map_file.empty() && !pipeline.loadMap(sc.load_map_file, &map_error)) {
    throw std::runtime_error(map_error);
  }
  // A start from the initializers knows neither position nor yaw: it is registered to the truth's
  // with an error drawn from the filter's prior, as a prior start is. A start over after the filter
  // was lost continues from its last estimate, as the node's odometry does.
  if (sc.register_to_truth) {
    pipeline.setRegistration([&](const NavState& s) {
      if (recorder.lost_before && recorder.last_estimate) return continueFrom(s, *recorder.last_estimate);
      return registerToTruth(s, trueNavState(traj, s.timestamp), config.initial, rng);
    });
  }
  if (!sc.dynamic_init) {
    pipeline.initialize(initial);
    run.initialized_t = initial.timestamp;
  }
  SensorStream::Event e;
  while (stream.next(&e)) {
    recorder.imu_index = e.imu_index;
    recorder.tic = std::chrono::steady_clock::now();
    if (e.imu) {
      pipeline.addImu(*e.imu);
    } else {
      if (e.reset_before) {
        pipeline.reset();
        recorder.lost_before = true;  // the start over continues from the last estimate, as odom does
      }
      // The camera observed the frame now; the pipeline uses it once the IMU reaches it.
      auto observed = std::make_shared<CameraFrame>(std::move(*e.frame));
      pipeline.addFrame({observed->timestamp, [observed](const std::optional<Mat3>&) { return *observed; }});
    }
  }
  // Frames the IMU no longer reaches (a time offset estimate beyond the last sample) are
  // recorded unprocessed, so every run has the same frames.
  recorder.imu_index = imu.true_accel_bias.size() - 1;
  recorder.tic = std::chrono::steady_clock::now();
  pipeline.flush();
  run.final_landmarks = pipeline.filter().landmarks();
  if (!sc.save_map_file.empty() && !pipeline.saveMap(sc.save_map_file, &map_error)) {
    throw std::runtime_error(map_error);
  }
  return run;
}

}  // namespace vi_ekf_slam::sim
