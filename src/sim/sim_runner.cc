#include "vi_ekf_slam/sim/sim_runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>

#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/core/static_initializer.h"

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

NavState registerToTruth(const NavState& aligned, const NavState& truth, const InitialUncertainty& u,
                         std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double yaw_error = u.yaw_rad * n(rng);
  const Quat R_z(Eigen::AngleAxisd(yawBetween(aligned.q_n_b, truth.q_n_b) - yaw_error, Vec3::UnitZ()));
  NavState r = aligned;
  r.q_n_b = (R_z * aligned.q_n_b).normalized();
  r.v_n_b = R_z * aligned.v_n_b;
  const double x = n(rng), y = n(rng), z = n(rng);
  r.p_n_b = truth.p_n_b - u.position_m * Vec3(x, y, z);
  return r;
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
  }
  return "unknown";
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

SimRun runSimulation(const Scenario& sc, const EkfSlamConfig& config, const NavState& initial, std::mt19937_64& rng,
                     const FrameCallback& callback, bool keep_frames) {
  const Trajectory& traj = *sc.trajectory;
  ImuSequence simulated;
  if (!sc.recorded_imu) simulated = simulateImu(traj, sc.imu, rng);
  const ImuSequence& imu = sc.recorded_imu ? *sc.recorded_imu : simulated;
  EkfSlam filter(config, sc.camera, sc.T_b_c);
  TrackingCamera camera(sc.world, sc.camera, sc.T_b_c, sc.cam);
  SimRun run;
  std::optional<DynamicInitializer> dynamic;
  std::optional<StaticInitializer> still;
  std::optional<StaticInitResult> at_rest;
  if (sc.dynamic_init) {
    dynamic.emplace(*sc.dynamic_init, sc.camera, sc.T_b_c);
    StaticInitParams sp;
    sp.gravity_mps2 = config.gravity_mps2;
    still.emplace(sp);
  } else {
    filter.initialize(initial);
    run.initialized_t = initial.timestamp;
  }
  // Until the filter starts, each frame (on the IMU clock through the configured time offset)
  // starts it from a recent interval at rest or goes to the dynamic initializer, as in the node;
  // the frames the initializer has seen are not replayed.
  auto tryInitialization = [&](CameraFrame frame) {
    frame.timestamp = filter.imuTime(frame.timestamp);
    if (at_rest && at_rest->usableAt(frame.timestamp)) {
      const NavState s = at_rest->navState();
      filter.initialize(registerToTruth(s, trueNavState(traj, s.timestamp), config.initial, rng));
      run.initialized_t = s.timestamp;
      return;
    }
    dynamic->addFrame(frame);
    const std::optional<DynamicInitResult> r = dynamic->tryInitialize(nullptr);
    if (!r) return;
    filter.initialize(*r, registerToTruth(r->state, trueNavState(traj, r->state.timestamp), config.initial, rng));
    run.initialized_t = r->state.timestamp;
  };
  const double cam_dt = 1.0 / sc.cam.rate_hz;
  int next_frame = 1;  // the first frame comes one camera period after the start
  auto frameTime = [&](int k) { return initial.timestamp + k * cam_dt; };
  // The IMU runs on past the last image, as a recorder's does, so that an image whose stamp plus
  // the time offset estimate is up to this much later still finds IMU data past it.
  constexpr double kImuTailS = 0.1;
  const double last_frame_time = traj.endTime() - kImuTailS;
  // Frames wait until the IMU reaches their stamp on the filter's IMU clock, as in the node's queue
  // (with a camera-IMU time offset the stamp is the true time minus the offset).
  std::deque<CameraFrame> pending;
  auto processPending = [&](size_t bias_index) {
    const CameraFrame frame = std::move(pending.front());
    pending.pop_front();
    FrameRecord rec;
    const auto tic = std::chrono::steady_clock::now();
    rec.result = filter.processFrame(frame);
    rec.filter_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
    // The truth at the time of the estimate (the stamp plus the estimated time offset).
    rec.t = rec.result.processed ? filter.state().timestamp : frame.timestamp + sc.cam.time_offset_s;
    rec.truth = traj.sample(std::min(rec.t, traj.endTime()));
    rec.true_accel_bias = imu.true_accel_bias[bias_index];
    rec.true_gyro_bias = imu.true_gyro_bias[bias_index];
    rec.estimate = filter.navState();
    rec.landmarks_in_state = filter.state().numLandmarks();
    rec.initialized_t = run.initialized_t;
    if (callback) callback(filter, rec);
    if (keep_frames) run.frames.push_back(std::move(rec));
  };
  for (size_t k = 0; k < imu.samples.size(); ++k) {
    if (!activeFault(sc.faults, SensorFault::Kind::kImuGap, imu.samples[k].timestamp)) {
      filter.addImu(imu.samples[k]);
      if (!filter.initialized()) {
        dynamic->addImu(imu.samples[k]);
        if (auto r = still->addImu(imu.samples[k])) at_rest = r;
      }
    }
    while (frameTime(next_frame) <= imu.samples[k].timestamp + 1e-12 && frameTime(next_frame) <= last_frame_time) {
      const double t = frameTime(next_frame++);
      // A dropped image never reaches the tracker, which goes on from the last image it got; a
      // covered lens shows it nothing to follow, so every track ends there (the points it finds
      // after are new tracks, as a KLT tracker's are).
      if (activeFault(sc.faults, SensorFault::Kind::kImageDropout, t)) continue;
      CameraFrame frame;
      if (activeFault(sc.faults, SensorFault::Kind::kCameraCovered, t)) {
        camera.loseTracks();
      } else {
        frame = camera.observe(traj.sample(t), &rng);
      }
      frame.timestamp = t - sc.cam.time_offset_s;
      if (const SensorFault* f = activeFault(sc.faults, SensorFault::Kind::kOutlierBurst, t)) {
        corruptFeatures(frame, f->outlier_fraction, rng);
      }
      if (filter.initialized()) {
        pending.push_back(std::move(frame));
      } else {
        tryInitialization(std::move(frame));
      }
    }
    while (!pending.empty() && filter.imuTime(pending.front().timestamp) <= filter.latestImuTime() + 1e-12) {
      processPending(std::min(k, imu.true_accel_bias.size() - 1));
    }
  }
  // Frames the IMU no longer reaches (a time offset estimate beyond the last sample) are
  // recorded unprocessed, so every run has the same frames.
  while (!pending.empty()) processPending(imu.true_accel_bias.size() - 1);
  run.final_landmarks = filter.landmarks();
  return run;
}

}  // namespace vi_ekf_slam::sim
