#include "vi_ekf_slam/sim/openvins_preset.h"

#include <cmath>

#include "vi_ekf_slam/sim/bspline_trajectory.h"

namespace vi_ekf_slam::sim {

LandmarkWorld landmarksInView(const Trajectory& traj, const CameraModel& camera, const CameraExtrinsics& T_b_c,
                              double min_depth_m, double max_depth_m, int per_view, double spacing_s,
                              std::mt19937_64& rng) {
  LandmarkWorld world;
  std::uniform_real_distribution<double> u(0.0, camera.width()), v(0.0, camera.height()),
      depth(min_depth_m, max_depth_m);
  for (double t = traj.startTime(); t <= traj.endTime(); t += spacing_s) {
    const TrajectorySample s = traj.sample(t);
    const Mat3 R_n_c = s.q_n_b.toRotationMatrix() * T_b_c.R_b_c;
    const Vec3 p_n_c = s.p_n_b + s.q_n_b * T_b_c.p_b_c;
    for (int i = 0; i < per_view; ++i) {
      Eigen::Vector2d xn;
      if (!camera.pixelToNormalized(Eigen::Vector2d(u(rng), v(rng)), &xn)) continue;
      const Vec3 p_c = depth(rng) * Vec3(xn.x(), xn.y(), 1.0);
      world.push_back({static_cast<std::int64_t>(world.size()), p_n_c + R_n_c * p_c});
    }
  }
  return world;
}

Scenario openvinsSimScenario(const std::string& tum_path, std::uint64_t world_seed) {
  Scenario sc;
  sc.trajectory = loadTumTrajectory(tum_path);
  CameraIntrinsics in;  // EuRoC cam0 (as in OpenVINS's rpng_sim config)
  in.width = 752;
  in.height = 480;
  in.fx = 458.654;
  in.fy = 457.296;
  in.cx = 367.215;
  in.cy = 248.375;
  in.model = DistortionModel::kRadTan;
  in.distortion = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0};
  sc.camera = CameraModel(in);
  // EuRoC T_BS of cam0: the camera in the IMU frame.
  sc.T_b_c.R_b_c << 0.0148655429818, -0.999880929698, 0.00414029679422, 0.999557249008, 0.0149672133247, 0.025715529948,
      -0.0257744366974, 0.00375618835797, 0.999660727178;
  sc.T_b_c.p_b_c = Vec3(-0.0216401454975, -0.064676986768, 0.00981073058949);
  sc.imu.rate_hz = 400.0;
  sc.imu.noise.gyro_noise_density = 1.6968e-4;
  sc.imu.noise.gyro_random_walk = 1.9393e-5;
  sc.imu.noise.accel_noise_density = 2.0e-3;
  sc.imu.noise.accel_random_walk = 3.0e-3;
  sc.start_at_truth = true;
  sc.cam.rate_hz = 10.0;
  sc.cam.pixel_noise_px = 1.0;
  sc.cam.max_range_m = 10.0;
  sc.cam.max_features = 100;
  sc.cam.grid_cols = 5;
  sc.cam.grid_rows = 4;
  std::mt19937_64 rng(world_seed);
  sc.world = landmarksInView(*sc.trajectory, sc.camera, sc.T_b_c, 5.0, 7.0, 40, 0.5, rng);
  return sc;
}

InitialUncertainty openvinsSimInitialUncertainty() {
  InitialUncertainty u;
  u.roll_pitch_rad = u.yaw_rad = M_PI / 180.0;
  u.position_m = 0.05;
  u.velocity_mps = 0.01;
  return u;
}

}  // namespace vi_ekf_slam::sim
