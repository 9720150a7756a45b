#include "vi_ekf_slam/eval/feature_replay.h"

#include <chrono>
#include <memory>
#include <stdexcept>

#include "vi_ekf_slam/core/vio_pipeline.h"
#include "vi_ekf_slam/core/frames.h"

namespace vi_ekf_slam::eval {

EkfSlamConfig eurocFeatureReplayConfig() {
  EkfSlamConfig c;
  c.imu_noise = io::eurocMavImuNoise();  // datasheet densities inflated as EqVIO's settings do (6x accel)
  c.zero_velocity.velocity_sigma_mps = io::kEurocMavStandingVelocitySigma;
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

namespace {
/// Collects the processed frames' poses.
class ReplayRecorder : public PipelineListener {
 public:
  explicit ReplayRecorder(FeatureReplayResult* out) : out_(out) {}
  std::chrono::steady_clock::time_point tic;  ///< when the pipeline call began

  void started(StartKind /*kind*/, const std::string& /*event*/, EkfSlam& filter) override {
    out_->init_time = filter.state().timestamp;
  }
  void processed(const CameraFrame& /*frame*/, const FrameResult& r, EkfSlam& filter) override {
    if (!r.processed) return;
    ++out_->frames_processed;
    out_->rejected_observations += static_cast<int>(r.update.rejected_ids.size());
    EstimatedPose e = worldPoseFromNav(filter.navState());
    e.processing_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tic).count();
    out_->trajectory.push_back(e);
  }

 private:
  FeatureReplayResult* out_;
};
}  // namespace

FeatureReplayResult replayFeatures(const io::FeatureTrackData& data, const std::vector<io::StampedPose>& truth,
                                   const EkfSlamConfig& config, const StaticInitParams& static_params) {
  FeatureReplayResult out;
  ReplayRecorder recorder(&out);
  PipelineParams params;
  params.static_init = static_params;
  params.dynamic_init_enabled = false;
  VioPipeline pipeline(config, params, CameraModel(data.camera), data.T_b_c, recorder);
  // The two streams in the order of their stamps, as a recording plays them.
  size_t f = 0;
  for (const ImuData& imu : data.imu) {
    while (f < data.frames.size() && data.frames[f].timestamp <= imu.timestamp) {
      const auto frame = std::make_shared<CameraFrame>(data.frames[f++]);
      recorder.tic = std::chrono::steady_clock::now();
      pipeline.addFrame({frame->timestamp, [frame](const std::optional<Mat3>&) { return *frame; }});
    }
    recorder.tic = std::chrono::steady_clock::now();
    pipeline.addImu(imu);
  }
  if (!pipeline.filter().initialized() && out.frames_processed == 0) {
    throw std::runtime_error("replayFeatures: no static interval to initialize from");
  }
  out.metrics = evaluateRun(out.trajectory, truth);
  return out;
}

}  // namespace vi_ekf_slam::eval
