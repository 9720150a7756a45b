#include "vi_ekf_slam/sim/loop_walk.h"

#include <cmath>

#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam::sim {

namespace {

/// Point and heading at arc length s on a rounded rectangle centred at the origin ({n}: x along
/// the long side, y to the right), travelled clockwise from the middle of the side y = -W/2.
void onLoop(const LoopParams& l, double s, Vec3* p, double* yaw) {
  const double r = l.corner_radius_m;
  const double a = l.length_m - 2 * r, b = l.width_m - 2 * r;  // straight parts
  const double arc = 0.5 * M_PI * r;
  const double perimeter = 2 * a + 2 * b + 4 * arc;
  s = std::fmod(s + 0.5 * a, perimeter);  // start in the middle of the first long side
  if (s < 0) s += perimeter;
  // Four sides in turn: +x along y = -W/2, +y along x = +L/2, -x along y = +W/2, -y along x = -L/2.
  const double lens[4] = {a, b, a, b};
  const Vec3 starts[4] = {Vec3(-a / 2, -l.width_m / 2, 0), Vec3(l.length_m / 2, -b / 2, 0),
                          Vec3(a / 2, l.width_m / 2, 0), Vec3(-l.length_m / 2, b / 2, 0)};
  for (int k = 0; k < 4; ++k) {
    const double heading = k * 0.5 * M_PI;
    const Vec3 dir(std::cos(heading), std::sin(heading), 0.0);
    if (s < lens[k]) {
      *p = starts[k] + s * dir;
      *yaw = heading;
      return;
    }
    s -= lens[k];
    if (s < arc) {
      // Right turn of radius r around the corner's centre.
      const Vec3 left(dir.y(), -dir.x(), 0.0);  // towards the turn centre is +90 deg (right)
      const Vec3 centre = starts[k] + lens[k] * dir - r * left;
      const double phi = s / r;
      *p = centre + r * (std::cos(phi) * left + std::sin(phi) * dir);
      *yaw = heading + phi;
      return;
    }
    s -= arc;
  }
  *p = starts[0];
  *yaw = 0.0;
}

}  // namespace

std::shared_ptr<BsplineTrajectory> loopWalk(const HallwayParams& g, const LoopParams& l) {
  std::vector<io::StampedPose> poses;
  const double dt = 0.05, ramp = 1.0;
  GaitParams gp = g.gait;
  gp.cruise_speed_mps = g.speed_mps;
  Gait gait(gp);
  for (double t = 0.0; t <= l.duration_s + 4 * dt; t += dt) {
    const double tau = std::max(0.0, t - g.standing_s);
    const double s = tau < ramp ? g.speed_mps * tau * tau / (2 * ramp) : g.speed_mps * (tau - 0.5 * ramp);
    Vec3 p;
    double yaw;
    onLoop(l, s, &p, &yaw);
    const double v = g.speed_mps * std::min(1.0, tau / ramp);
    if (tau > 0.0) gait.advance(v, dt);
    poses.push_back(gait.pose(t, p, yaw, v));
  }
  return std::make_shared<BsplineTrajectory>(poses, dt);
}

Scenario loopScenario(const HallwayParams& gait, const LoopParams& loop, std::uint64_t world_seed) {
  Scenario sc;
  sc.trajectory = loopWalk(gait, loop);
  LoopParams one = loop;
  const double lap_s = (2 * (loop.length_m + loop.width_m)) / gait.speed_mps;
  one.duration_s = std::min(loop.duration_s, gait.standing_s + lap_s + 2.0);
  std::mt19937_64 rng(world_seed);
  sc.world = landmarksAroundTrajectory(*loopWalk(gait, one), 15.0, 1.0, 10.0, rng);
  sc.camera = paperCamera();
  sc.T_b_c = torsoCameraExtrinsics();
  sc.imu.noise = paperImuNoise();
  return sc;
}

}  // namespace vi_ekf_slam::sim
