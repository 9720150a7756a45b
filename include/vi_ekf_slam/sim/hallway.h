// The built-in scenario of the paper's simulation (Sec. IV-A): a torso-worn rig walking along a
// hallway and turning sharply into a narrow side corridor. The building is a set of planar
// rectangles (walls, floor, ceiling) shared by the landmark sampler and the image renderer.
#pragma once

#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "vi_ekf_slam/sim/bspline_trajectory.h"
#include "vi_ekf_slam/sim/gait.h"
#include "vi_ekf_slam/sim/landmark_world.h"

namespace vi_ekf_slam::sim {

/// A planar rectangle {origin + a*u + b*v : a in [0, u_len], b in [0, v_len]}; u and v are unit
/// vectors and u x v points into the free space.
struct Quad {
  Vec3 origin = Vec3::Zero();
  Vec3 u = Vec3::UnitX();
  Vec3 v = Vec3::UnitY();
  double u_len = 1.0;
  double v_len = 1.0;
  std::string kind;  ///< "wall", "floor", "ceiling"
  Vec3 normal() const { return u.cross(v); }
  double area() const { return u_len * v_len; }
};

struct HallwayParams {
  double standing_s = 0.0;      ///< the rig stands still this long before walking (static init)
  double duration_s = 35.0;     ///< all times are from the start, standing included
  double speed_mps = 1.3;       ///< walking speed
  double turn_time_s = 23.0;    ///< middle of the 90 deg right turn
  double turn_radius_m = 0.6;   ///< a sharp turn
  double turn_speed_mps = 0.9;  ///< walkers slow down in a sharp turn
  double main_width_m = 2.4;
  double side_width_m = 1.4;  ///< the narrow side corridor
  double height_m = 2.6;
  double body_height_m = 1.3;  ///< IMU above the floor
  /// The walker's gait (a constant cadence; its cruise speed is speed_mps).
  GaitParams gait;
};

/// The centreline geometry: where the side corridor branches off (x of its axis, {n}).
struct HallwayLayout {
  double turn_x_m = 0.0;
  double main_end_x_m = 0.0;
  double side_end_y_m = 0.0;
};

HallwayLayout hallwayLayout(const HallwayParams& p);
/// Walls, floor and ceiling of the hallway and the side corridor ({n}: x along the hallway,
/// y to the right, z down; the walker's IMU is at z = 0).
std::vector<Quad> hallwayGeometry(const HallwayParams& p);
/// The walk as a C2 trajectory, t in [0, duration_s].
std::shared_ptr<BsplineTrajectory> pedestrianWalk(const HallwayParams& p);

/// A closed box room around a trajectory ({n}): its horizontal extent plus `margin_m`, the floor
/// `below_m` under and the ceiling `above_m` over the lowest/highest point of the path.
std::vector<Quad> roomAroundTrajectory(const Trajectory& trajectory, double margin_m, double below_m, double above_m);

/// Quads as text (one per line: kind ox oy oz ux uy uz vx vy vz u_len v_len), e.g. to store the
/// simulated world in a bag, and back. parseQuads throws std::runtime_error on bad input.
std::string serializeQuads(const std::vector<Quad>& quads);
std::vector<Quad> parseQuads(const std::string& text);

/// Where the ray from `origin` along `dir` ({n}) first hits a quad facing it; nullopt if none.
std::optional<Vec3> raycast(const std::vector<Quad>& quads, const Vec3& origin, const Vec3& dir);

/// Landmarks uniformly on the quads with `density_per_m2`, ids from `first_id`.
LandmarkWorld landmarksOnQuads(const std::vector<Quad>& quads, double density_per_m2, std::mt19937_64& rng,
                               std::int64_t first_id = 0);

/// Landmarks scattered around a trajectory: `per_metre` points per metre of path, at distances
/// uniform in [min_dist_m, max_dist_m] from the path point they were drawn for, and never closer
/// than min_dist_m to any point of the path.
LandmarkWorld landmarksAroundTrajectory(const Trajectory& traj, double per_metre, double min_dist_m, double max_dist_m,
                                        std::mt19937_64& rng);

}  // namespace vi_ekf_slam::sim
