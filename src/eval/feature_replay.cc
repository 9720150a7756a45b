#include "vi_ekf_slam/eval/feature_replay.h"

#include <chrono>
#include <stdexcept>

#include "vi_ekf_slam/core/ekf_slam.h"
#include "vi_ekf_slam/core/frames.h"

namespace vi_ekf_slam::eval {

EkfSlamConfig eurocFeatureReplayConfig() {
  EkfSlamConfig c;
  c.imu_noise = eurocMavImuNoise();  // datasheet densities inflated as EqVIO's settings do (6x accel)
  c.zero_velocity.velocity_sigma_mps = kEurocMavStandingVelocitySigma;
  c.update.pixel_noise_px = 2.0;
  c.landmark_timeout_s = 0.1;  // a lost track never comes back
  c.max_landmarks = 100;
  c.initial.position_m = 0.0;  // the estimate defines its frame at the start
  c.initial.yaw_rad = 0.0;
  c.initial.roll_pitch_rad = 0.01;
  return c;
}

EstimatedPose worldPoseFromNav(const NavState& nav) {
  EstimatedPose e;
  e.t = nav.timestamp;
  navToZUpWorld(nav.p_n_b, nav.q_n_b, &e.p, &e.q);
  // Position and global orientation errors both rotate with R_w_n.
  Eigen::Matrix<double, 6, 6> G = Eigen::Matrix<double, 6, 6>::Zero();
  G.topLeftCorner<3, 3>() = zUpWorldFromNav().toRotationMatrix();
  G.bottomRightCorner<3, 3>() = G.topLeftCorner<3, 3>();
  e.cov = G * nav.poseCovariance() * G.transpose();
  return e;
}

FeatureReplayResult replayFeatures(const FeatureTrackData& data, const std::vector<StampedPose>& truth,
                                   const EkfSlamConfig& config, const StaticInitParams& static_params) {
  FeatureReplayResult out;
  EkfSlam filter(config, CameraModel(data.camera), data.T_b_c);
  StaticInitializer init(static_params);
  size_t k = 0;
  for (; k < data.imu.size() && !filter.initialized(); ++k) {
    if (auto r = init.addImu(data.imu[k])) {
      filter.initialize(r->navState());
      out.init_time = r->timestamp;
    }
  }
  if (!filter.initialized()) throw std::runtime_error("replayFeatures: no static interval to initialize from");
  size_t f = 0;
  while (f < data.frames.size() && data.frames[f].timestamp <= out.init_time) ++f;
  for (; k < data.imu.size(); ++k) {
    filter.addImu(data.imu[k]);
    // A frame is processed once the IMU reaches its stamp on the IMU clock (stamp + time offset).
    while (f < data.frames.size() && filter.imuTime(data.frames[f].timestamp) <= data.imu[k].timestamp) {
      const auto tic = std::chrono::steady_clock::now();
      const FrameResult r = filter.processFrame(data.frames[f++]);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
      if (!r.processed) continue;
      ++out.frames_processed;
      out.rejected_observations += static_cast<int>(r.update.rejected_ids.size());
      EstimatedPose e = worldPoseFromNav(filter.navState());
      e.processing_ms = ms;
      out.trajectory.push_back(e);
    }
  }
  out.metrics = evaluateRun(out.trajectory, truth);
  return out;
}

}  // namespace vi_ekf_slam::eval
