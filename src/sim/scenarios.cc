#include "vi_ekf_slam/sim/scenarios.h"

#include <cmath>
#include <utility>

namespace vi_ekf_slam::sim {

CameraModel paperCamera() {
  CameraIntrinsics in;
  in.width = 699;
  in.height = 540;
  in.fx = 420.0;
  in.fy = 420.0;
  in.cx = 349.0;
  in.cy = 269.5;
  in.model = DistortionModel::kRadTan;
  in.distortion = {-0.12, 0.03, 0.0006, -0.0004, 0.0};
  return CameraModel(in);
}

CameraExtrinsics torsoCameraExtrinsics() {
  CameraExtrinsics T;
  T.R_b_c << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  T.p_b_c = Vec3(0.08, 0.0, -0.05);
  return T;
}

ImuNoiseParams paperImuNoise() {
  ImuNoiseParams n;
  const double mg = 9.81e-3;
  n.accel_noise_density = 7.5 * mg / std::sqrt(200.0);  // 5.2e-3 m/s^2/sqrt(Hz)
  n.gyro_noise_density = 0.0056 * M_PI / 180.0;         // 9.8e-5 rad/s/sqrt(Hz)
  n.accel_random_walk = 1.0e-3;                         // m/s^3/sqrt(Hz)
  n.gyro_random_walk = 1.0e-5;                          // rad/s^2/sqrt(Hz)
  return n;
}

namespace {
/// A scenario on `trajectory` with the paper's camera and IMU; `noise` false makes the sensors
/// exact (the scenarios that check the math).
Scenario paperSensors(std::shared_ptr<const Trajectory> trajectory, bool noise = true) {
  Scenario sc;
  sc.trajectory = std::move(trajectory);
  sc.camera = paperCamera();
  sc.T_b_c = torsoCameraExtrinsics();
  sc.imu.noise = paperImuNoise();
  sc.imu.noise_enabled = noise;
  sc.cam.pixel_noise_px = noise ? 1.0 : 0.0;
  return sc;
}
}  // namespace

Scenario circleScenario(double duration_s, bool noise, std::uint64_t world_seed) {
  const double radius = 6.0;
  Scenario sc = paperSensors(std::make_shared<CircleTrajectory>(radius, 0.25, 0.04, duration_s), noise);
  std::mt19937_64 rng(world_seed);
  sc.world = cylinderWorld(Vec3(0.0, radius, 0.0), radius + 4.0, -3.0, 1.5, 400, rng);
  return sc;
}

Scenario wallScenario(double duration_s, bool noise, std::uint64_t world_seed) {
  Scenario sc =
      paperSensors(std::make_shared<LissajousTrajectory>(Vec3::Zero(), Vec3(0.3, 0.4, 0.2), Vec3(1.1, 0.8, 1.7),
                                                         Vec3(0.1, 0.08, 0.15), Vec3(0.9, 1.3, 0.7), duration_s),
                   noise);
  std::mt19937_64 rng(world_seed);
  std::uniform_real_distribution<double> depth(5.0, 8.0), lateral(-2.5, 2.5), vertical(-1.8, 1.8);
  for (int i = 0; i < 25; ++i) {
    const double x = depth(rng), y = lateral(rng), z = vertical(rng);
    sc.world.push_back({i, Vec3(x, y, z)});
  }
  return sc;
}

Scenario hallwayScenario(const HallwayParams& params, double density_per_m2, std::uint64_t world_seed) {
  Scenario sc = paperSensors(pedestrianWalk(params));
  std::mt19937_64 rng(world_seed);
  sc.world = landmarksOnQuads(hallwayGeometry(params), density_per_m2, rng);
  return sc;
}

CameraExtrinsics forwardLookingExtrinsics(const Trajectory& traj) {
  Vec3 fwd = Vec3::Zero(), down = Vec3::Zero();
  for (double t = traj.startTime(); t <= traj.endTime(); t += 0.1) {
    const TrajectorySample s = traj.sample(t);
    if (s.v_n_b.norm() > 0.2) fwd += s.q_n_b.conjugate() * s.v_n_b.normalized();
    down += s.q_n_b.conjugate() * Vec3::UnitZ();
  }
  if (fwd.norm() < 1e-6) fwd = Vec3::UnitX();
  fwd.normalize();
  Vec3 y = down - down.dot(fwd) * fwd;
  if (y.norm() < 1e-6) y = fwd.unitOrthogonal();
  y.normalize();
  CameraExtrinsics T;
  T.R_b_c.col(2) = fwd;  // camera z: forward
  T.R_b_c.col(1) = y;    // camera y: image down
  T.R_b_c.col(0) = y.cross(fwd);
  return T;
}

Scenario tumScenario(const std::string& path, double per_metre, std::uint64_t world_seed) {
  Scenario sc = paperSensors(loadTumTrajectory(path));
  std::mt19937_64 rng(world_seed);
  sc.world = landmarksAroundTrajectory(*sc.trajectory, per_metre, 1.0, 10.0, rng);
  sc.T_b_c = forwardLookingExtrinsics(*sc.trajectory);  // a TUM file's body axes are its own
  return sc;
}

}  // namespace vi_ekf_slam::sim
