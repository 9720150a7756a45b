#include "vi_ekf_slam/sim/hallway.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace vi_ekf_slam::sim {

namespace {

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

/// Walking speed: stand for standing_s, start from rest over 1.5 s, slow down for the sharp turn.
double speedAt(const HallwayParams& p, double t) {
  const double start = smoothstep((t - p.standing_s) / 1.5);
  const double dip = 1.0 - smoothstep(1.0 - std::abs(t - p.turn_time_s) / 1.5);  // 0 at the turn
  const double v = p.turn_speed_mps + (p.speed_mps - p.turn_speed_mps) * dip;
  return start * v;
}

/// Arc length walked by time t (trapezoid at 1 ms).
double arcLength(const HallwayParams& p, double t) {
  double s = 0.0;
  const double h = 1e-3;
  for (double x = 0.0; x < t; x += h) s += 0.5 * h * (speedAt(p, x) + speedAt(p, std::min(t, x + h)));
  return s;
}

struct Centerline {
  double s1;  ///< arc length where the turn starts
  double R;
  double turn_x;
};

Centerline centerline(const HallwayParams& p) {
  Centerline c;
  c.R = p.turn_radius_m;
  // The middle of the turn (a quarter of its arc) is reached at turn_time_s.
  c.s1 = arcLength(p, p.turn_time_s) - 0.25 * M_PI * c.R;
  c.turn_x = c.s1 + c.R;
  return c;
}

/// Point and heading of the centreline at arc length s.
void centerlineAt(const Centerline& c, double s, Vec3* pos, double* heading) {
  const double arc = 0.5 * M_PI * c.R;
  if (s <= c.s1) {
    *pos = Vec3(s, 0.0, 0.0);
    *heading = 0.0;
  } else if (s <= c.s1 + arc) {
    const double th = (s - c.s1) / c.R;
    *pos = Vec3(c.s1 + c.R * std::sin(th), c.R * (1.0 - std::cos(th)), 0.0);
    *heading = th;
  } else {
    *pos = Vec3(c.turn_x, c.R + (s - c.s1 - arc), 0.0);
    *heading = 0.5 * M_PI;
  }
}

Quad quad(const Vec3& o, const Vec3& u, double ul, const Vec3& v, double vl, const char* kind) {
  Quad q;
  q.origin = o;
  q.u = u;
  q.v = v;
  q.u_len = ul;
  q.v_len = vl;
  q.kind = kind;
  return q;
}

}  // namespace

HallwayLayout hallwayLayout(const HallwayParams& p) {
  const Centerline c = centerline(p);
  HallwayLayout l;
  l.turn_x_m = c.turn_x;
  l.main_end_x_m = c.turn_x + 0.5 * p.side_width_m + 4.0;
  const double walked_after_turn = arcLength(p, p.duration_s) - c.s1 - 0.5 * M_PI * c.R;
  l.side_end_y_m = c.R + std::max(0.0, walked_after_turn) + 4.0;
  return l;
}

std::vector<Quad> hallwayGeometry(const HallwayParams& p) {
  const HallwayLayout l = hallwayLayout(p);
  const double hw = 0.5 * p.main_width_m, sw = 0.5 * p.side_width_m;
  const double floor_z = p.body_height_m, ceil_z = p.body_height_m - p.height_m, h = p.height_m;
  const double x0 = -3.0, x1 = l.main_end_x_m;
  const double xa = l.turn_x_m - sw, xb = l.turn_x_m + sw, y1 = l.side_end_y_m;
  const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY(), Z = Vec3::UnitZ();  // z is down
  std::vector<Quad> q;
  // Main hallway along x. Each u x v points into the corridor.
  q.push_back(quad({x0, -hw, floor_z}, X, x1 - x0, -Z, h, "wall"));        // left wall, faces +y
  q.push_back(quad({x0, hw, ceil_z}, X, xa - x0, Z, h, "wall"));           // right wall up to the opening, faces -y
  q.push_back(quad({xb, hw, ceil_z}, X, x1 - xb, Z, h, "wall"));           // right wall after it
  q.push_back(quad({x0, -hw, ceil_z}, Y, 2 * hw, Z, h, "wall"));           // start wall, faces +x
  q.push_back(quad({x1, -hw, floor_z}, Y, 2 * hw, -Z, h, "wall"));         // end wall, faces -x
  q.push_back(quad({x0, -hw, floor_z}, Y, 2 * hw, X, x1 - x0, "floor"));   // faces up (-z)
  q.push_back(quad({x0, -hw, ceil_z}, X, x1 - x0, Y, 2 * hw, "ceiling"));  // faces down (+z)
  // Narrow side corridor towards +y.
  q.push_back(quad({xa, hw, ceil_z}, Y, y1 - hw, Z, h, "wall"));    // faces +x
  q.push_back(quad({xb, hw, floor_z}, Y, y1 - hw, -Z, h, "wall"));  // faces -x
  q.push_back(quad({xa, y1, ceil_z}, X, xb - xa, Z, h, "wall"));    // end wall, faces -y
  q.push_back(quad({xa, hw, floor_z}, Y, y1 - hw, X, xb - xa, "floor"));
  q.push_back(quad({xa, hw, ceil_z}, X, xb - xa, Y, y1 - hw, "ceiling"));
  return q;
}

std::shared_ptr<BsplineTrajectory> pedestrianWalk(const HallwayParams& p) {
  const Centerline c = centerline(p);
  std::vector<io::StampedPose> poses;
  const double dt = 0.01;
  GaitParams g = p.gait;
  g.cruise_speed_mps = p.speed_mps;
  Gait gait(g);
  double s = 0.0;
  for (double t = -0.1; t <= p.duration_s + 0.1 + 1e-9; t += dt) {
    const double v = t > p.standing_s ? speedAt(p, t) : 0.0;
    if (t > p.standing_s) {
      s += v * dt;
      gait.advance(v, dt);
    }
    Vec3 pos;
    double heading;
    centerlineAt(c, s, &pos, &heading);
    poses.push_back(gait.pose(t, pos, heading, v));
  }
  return std::make_shared<BsplineTrajectory>(poses, 0.02);
}

std::vector<Quad> roomAroundTrajectory(const Trajectory& traj, double margin, double below, double above) {
  Vec3 lo = Vec3::Constant(1e18), hi = Vec3::Constant(-1e18);
  for (double t = traj.startTime(); t <= traj.endTime(); t += 0.05) {
    const Vec3 p = traj.sample(t).p_n_b;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double x0 = lo.x() - margin, x1 = hi.x() + margin, y0 = lo.y() - margin, y1 = hi.y() + margin;
  const double floor_z = hi.z() + below, ceil_z = lo.z() - above, h = floor_z - ceil_z;  // z is down
  const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY(), Z = Vec3::UnitZ();
  return {quad({x0, y0, floor_z}, X, x1 - x0, -Z, h, "wall"),  // y = y0, faces +y
          quad({x0, y1, ceil_z}, X, x1 - x0, Z, h, "wall"),    // y = y1, faces -y
          quad({x0, y0, ceil_z}, Y, y1 - y0, Z, h, "wall"),    // x = x0, faces +x
          quad({x1, y0, floor_z}, Y, y1 - y0, -Z, h, "wall"),  // x = x1, faces -x
          quad({x0, y0, floor_z}, Y, y1 - y0, X, x1 - x0, "floor"),
          quad({x0, y0, ceil_z}, X, x1 - x0, Y, y1 - y0, "ceiling")};
}

std::string serializeQuads(const std::vector<Quad>& quads) {
  std::ostringstream s;
  s.precision(10);
  for (const auto& q : quads) {
    s << q.kind << " " << q.origin.x() << " " << q.origin.y() << " " << q.origin.z() << " " << q.u.x() << " " << q.u.y()
      << " " << q.u.z() << " " << q.v.x() << " " << q.v.y() << " " << q.v.z() << " " << q.u_len << " " << q.v_len
      << "\n";
  }
  return s.str();
}

std::vector<Quad> parseQuads(const std::string& text) {
  std::vector<Quad> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream l(line);
    Quad q;
    if (!(l >> q.kind >> q.origin.x() >> q.origin.y() >> q.origin.z() >> q.u.x() >> q.u.y() >> q.u.z() >> q.v.x() >>
          q.v.y() >> q.v.z() >> q.u_len >> q.v_len)) {
      throw std::runtime_error("parseQuads: bad line '" + line + "'");
    }
    out.push_back(q);
  }
  return out;
}

std::optional<Vec3> raycast(const std::vector<Quad>& quads, const Vec3& o, const Vec3& d) {
  double best = 1e18;
  std::optional<Vec3> hit;
  for (const auto& q : quads) {
    const Vec3 n = q.normal();
    const double denom = n.dot(d);
    if (denom > -1e-9) continue;
    const double t = n.dot(q.origin - o) / denom;
    if (t <= 1e-6 || t >= best) continue;
    const Vec3 h = o + t * d - q.origin;
    const double a = h.dot(q.u), b = h.dot(q.v);
    if (a < 0 || b < 0 || a > q.u_len || b > q.v_len) continue;
    best = t;
    hit = o + t * d;
  }
  return hit;
}

LandmarkWorld landmarksOnQuads(const std::vector<Quad>& quads, double density, std::mt19937_64& rng,
                               std::int64_t first_id) {
  LandmarkWorld w;
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::int64_t id = first_id;
  for (const auto& q : quads) {
    std::poisson_distribution<int> count(density * q.area());
    const int n = count(rng);
    for (int i = 0; i < n; ++i) {
      const double a = u01(rng), b = u01(rng);
      w.push_back({id++, q.origin + a * q.u_len * q.u + b * q.v_len * q.v});
    }
  }
  return w;
}

LandmarkWorld landmarksAroundTrajectory(const Trajectory& traj, double per_metre, double min_dist, double max_dist,
                                        std::mt19937_64& rng) {
  // Path points every 0.25 m.
  std::vector<Vec3> path;
  Vec3 last = traj.sample(traj.startTime()).p_n_b;
  path.push_back(last);
  for (double t = traj.startTime(); t <= traj.endTime(); t += 0.01) {
    const Vec3 p = traj.sample(t).p_n_b;
    if ((p - last).norm() >= 0.25) {
      path.push_back(p);
      last = p;
    }
  }
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> dist(min_dist, max_dist);
  std::poisson_distribution<int> count(per_metre * 0.25);
  LandmarkWorld w;
  std::int64_t id = 0;
  for (const Vec3& c : path) {
    const int n = count(rng);
    for (int i = 0; i < n; ++i) {
      const double gx = g(rng), gy = g(rng), gz = g(rng);
      const Vec3 dir = Vec3(gx, gy, gz).normalized();
      const Vec3 p = c + dist(rng) * dir;
      bool clear = true;
      for (const Vec3& q : path) {
        if ((p - q).squaredNorm() < min_dist * min_dist) {
          clear = false;
          break;
        }
      }
      if (clear) w.push_back({id++, p});
    }
  }
  return w;
}

}  // namespace vi_ekf_slam::sim
