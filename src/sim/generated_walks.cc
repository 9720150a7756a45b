#include "vi_ekf_slam/sim/generated_walks.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "vi_ekf_slam/sim/gait.h"

namespace vi_ekf_slam::sim {

namespace {

constexpr double kRateHz = 100.0;
constexpr double kCruiseMps = 1.3;
using Path = std::vector<Eigen::Vector2d>;

/// Centreline of a rectangular loop with rounded corners (turning left): a point every ds metres.
Path blockPath(double length = 30.0, double width = 12.0, double radius = 1.5, double ds = 0.01) {
  Path pts;
  Eigen::Vector2d pos(0.0, 0.0);
  double heading = 0.0;
  for (int k = 0; k < 4; ++k) {
    const double straight = (k % 2 == 0 ? length : width) - 2.0 * radius;
    const Eigen::Vector2d d(std::cos(heading), std::sin(heading));
    for (int i = 0; i * ds < straight; ++i) pts.push_back(pos + i * ds * d);
    pos += straight * d;
    const Eigen::Vector2d centre = pos + radius * Eigen::Vector2d(-d.y(), d.x());
    for (int i = 0; i * ds / radius < 0.5 * M_PI; ++i) {
      const double ang = heading - 0.5 * M_PI + i * ds / radius;
      pts.push_back(centre + radius * Eigen::Vector2d(std::cos(ang), std::sin(ang)));
    }
    heading += 0.5 * M_PI;
    pos = centre + radius * Eigen::Vector2d(std::cos(heading - 0.5 * M_PI), std::sin(heading - 0.5 * M_PI));
  }
  return pts;
}

/// A helix's ground track (a circle of `radius`, `turns` times round, turning left), then the
/// block from the circle's exit.
Path stairwellPath(double radius, double turns, double ds = 0.01) {
  Path pts;
  for (int i = 0; i * ds / radius < 2.0 * M_PI * turns; ++i) {
    const double a = i * ds / radius;
    pts.emplace_back(radius * std::sin(a), radius * (1.0 - std::cos(a)));
  }
  const Path block = blockPath();
  pts.insert(pts.end(), block.begin() + 1, block.end());
  return pts;
}

/// A corridor walked there and back: `length` metres straight, a U-turn to the left of `radius`,
/// over 6 m back to 0.2 m beside the way out, and on back along it.
Path thereAndBackPath(double length, double radius, double ds = 0.01) {
  Path pts;
  for (int i = 0; i * ds < length; ++i) pts.emplace_back(i * ds, 0.0);
  for (int i = 0; i * ds / radius < M_PI; ++i) {
    const double a = i * ds / radius;
    pts.emplace_back(length + radius * std::sin(a), radius * (1.0 - std::cos(a)));
  }
  constexpr double kShift = 6.0, kBeside = 0.2;
  for (int i = 0; i * ds <= length; ++i) {
    const double s = i * ds;
    const double y =
        s < kShift ? 2.0 * radius - (2.0 * radius - kBeside) * 0.5 * (1.0 - std::cos(M_PI * s / kShift)) : kBeside;
    pts.emplace_back(length - s, y);
  }
  return pts;
}

/// Piecewise-constant speed [(t_start, speed), ...] with 1.5 s cosine ramps between levels.
double smoothSteps(double t, const std::vector<std::pair<double, double>>& knots) {
  constexpr double kRamp = 1.5;
  double v = knots.front().second;
  for (size_t k = 1; k < knots.size(); ++k) {
    const auto [t0, v0] = knots[k - 1];
    const auto [t1, v1] = knots[k];
    if (t >= t1) {
      v = v1;
    } else if (t >= t1 - kRamp) {
      const double a = (t - (t1 - kRamp)) / kRamp;
      v = v0 + (v1 - v0) * 0.5 * (1.0 - std::cos(M_PI * a));
    }
  }
  return v;
}

/// The path's point at arc length s, by linear interpolation: periodic over its length for a
/// closed path (a loop), held at its ends for an open one.
class ArcLengthPath {
 public:
  explicit ArcLengthPath(Path pts) : pts_(std::move(pts)), s_(pts_.size(), 0.0) {
    for (size_t i = 1; i < pts_.size(); ++i) s_[i] = s_[i - 1] + (pts_[i] - pts_[i - 1]).norm();
    closed_ = (pts_.front() - pts_.back()).norm() < 0.1;
  }
  double length() const { return s_.back(); }
  Eigen::Vector2d at(double s) const {
    if (closed_) {
      s = std::fmod(s, length());
      if (s < 0.0) s += length();
    } else {
      s = std::clamp(s, 0.0, length());
    }
    const size_t i = static_cast<size_t>(std::upper_bound(s_.begin(), s_.end(), s) - s_.begin());
    if (i == 0) return pts_.front();
    if (i >= pts_.size()) return pts_.back();
    const double u = (s - s_[i - 1]) / (s_[i] - s_[i - 1]);
    return pts_[i - 1] + u * (pts_[i] - pts_[i - 1]);
  }

 private:
  Path pts_;
  std::vector<double> s_;
  bool closed_ = true;
};

struct WalkSpec {
  std::function<double(double)> speed;  ///< [m/s] at t [s]
  double duration_s = 90.0;
  std::function<double(double)> height = [](double) { return 0.0; };  ///< [m] above the start at arc length s
  std::uint64_t seed = 0;
  Path path = blockPath();
  /// false: the body on the centreline itself, without the gait's bounce and sway (no acceleration
  /// on a straight at a constant speed); the gait's torso angles stay.
  bool gait_translation = true;
};

/// Samples the walk at 100 Hz: the centreline at the distance walked, its heading from the tangent
/// (over +-0.3 m, continuous over laps), the gait about it.
std::vector<io::StampedPose> sample(const WalkSpec& w) {
  const ArcLengthPath path(w.path);
  GaitParams g;
  g.cruise_speed_mps = kCruiseMps;
  g.cadence_speed_exponent = 0.5;
  g.max_amplitude = 1.2;
  g.postural_sway_m = 0.004;
  g.postural_pitch_rad = 0.004;
  Gait gait(g, w.seed);
  std::vector<io::StampedPose> poses;
  double s = 0.0, v_prev = w.speed(0.0), heading = 0.0;
  for (int i = 0; i / kRateHz < w.duration_s; ++i) {
    const double t = i / kRateHz, v = w.speed(t);
    if (i > 0) {
      s += 0.5 * (v + v_prev) / kRateHz;
      gait.advance(0.5 * (v + v_prev), 1.0 / kRateHz);
    }
    v_prev = v;
    const Eigen::Vector2d tangent = path.at(s + 0.3) - path.at(s - 0.3);
    const double h = std::atan2(tangent.y(), tangent.x());
    heading = i == 0 ? h : heading + std::remainder(h - heading, 2.0 * M_PI);  // unwrapped
    const Eigen::Vector2d xy = path.at(s);
    const Vec3 centre(xy.x(), xy.y(), 1.3 + w.height(s));
    poses.push_back(gait.pose(t, centre, heading, v));
    if (!w.gait_translation) poses.back().p = centre;
  }
  return poses;
}

/// The stairs walk's speed: 0.5 m/s on the flights (a function of the distance, integrated in
/// time), smoothed over 1 s.
std::function<double(double)> stairsSpeed(double up0, double up1, double down0, double down1, double duration_s) {
  std::vector<double> profile;
  double s = 0.0;
  for (int i = 0; i / kRateHz < duration_s; ++i) {
    const double v = (up0 <= s && s <= up1) || (down0 <= s && s <= down1) ? 0.5 : kCruiseMps;
    profile.push_back(v);
    s += v / kRateHz;
  }
  std::vector<double> smooth(profile.size(), 0.0);  // a 100-sample moving mean, zero beyond the ends
  for (size_t i = 0; i < profile.size(); ++i) {
    for (int m = -50; m < 50; ++m) {
      const long j = static_cast<long>(i) + m;
      if (j >= 0 && j < static_cast<long>(profile.size())) smooth[i] += profile[static_cast<size_t>(j)] / 100.0;
    }
  }
  return [smooth](double t) {
    const double x = std::clamp(t * kRateHz, 0.0, static_cast<double>(smooth.size() - 1));
    const size_t i = std::min(static_cast<size_t>(x), smooth.size() - 2);
    return smooth[i] + (x - i) * (smooth[i + 1] - smooth[i]);
  };
}

WalkSpec spec(const std::string& kind) {
  WalkSpec w;
  auto constant = [](double v) { return [v](double) { return v; }; };
  if (kind == "slow_start") {
    w.speed = [](double t) {
      if (t < 8.0) return 0.5;
      const double a = std::min(1.0, (t - 8.0) / 12.0);
      return 0.5 + (kCruiseMps - 0.5) * 0.5 * (1.0 - std::cos(M_PI * a));
    };
    w.seed = 1;
  } else if (kind == "crawl") {
    w.speed = [](double t) { return smoothSteps(t, {{0, 0.3}, {12, kCruiseMps}, {90, kCruiseMps}}); };
    w.seed = 5;
  } else if (kind == "stops") {
    w.speed = [](double t) {
      return smoothSteps(t, {{0, 1.3}, {15, 0.0}, {20, 1.3}, {40, 0.0}, {52, 1.3}, {75, 0.0}, {95, 1.3}, {120, 1.3}});
    };
    w.duration_s = 120.0;
    w.seed = 2;
  } else if (kind == "stairs") {  // a flight from 20 m to 25 m of the walk, back down from 78 m to 83 m
    w.speed = stairsSpeed(20.0, 25.0, 78.0, 83.0, w.duration_s);
    w.height = [](double s) {
      return 2.8 * std::clamp((s - 20.0) / 5.0, 0.0, 1.0) - 2.8 * std::clamp((s - 78.0) / 5.0, 0.0, 1.0);
    };
    w.seed = 3;
  } else if (kind == "fast") {
    w.speed = constant(2.4);
    w.duration_s = 60.0;
    w.seed = 4;
  } else if (kind == "stairwell") {  // stands 0.2 s, 1.2 m/s within 0.8 s, 0.2 m up per metre
    const double radius = 1.6, turns = 4.0, helix_len = 2.0 * M_PI * radius * turns;
    w.path = stairwellPath(radius, turns);
    w.height = [helix_len](double s) { return 0.2 * std::clamp(s, 0.0, helix_len); };
    w.speed = [](double t) { return 1.2 * 0.5 * (1.0 - std::cos(M_PI * std::clamp((t - 0.2) / 0.8, 0.0, 1.0))); };
    w.seed = 6;
  } else if (kind == "slow_walk") {
    w.speed = constant(0.6);
    w.seed = 13;
  } else if (kind == "start04") {
    w.speed = [](double t) { return smoothSteps(t, {{0, 0.4}, {12, kCruiseMps}, {90, kCruiseMps}}); };
    w.seed = 14;
  } else if (kind == "stop_and_go") {  // stands from 5.5 to 6.5 s of every 7 s
    std::vector<std::pair<double, double>> knots = {{0, kCruiseMps}};
    for (int k = 0; k < 13; ++k) {
      knots.emplace_back(7 * k + 5.5, 0.0);
      knots.emplace_back(7 * k + 8.0, kCruiseMps);
    }
    w.speed = [knots](double t) { return smoothSteps(t, knots); };
    w.seed = 11;
  } else if (kind == "small_room") {
    w.speed = constant(1.0);
    w.path = blockPath(6.0, 4.0, 0.8);
    w.seed = 12;
  } else if (kind == "there_and_back") {  // 40 m down a corridor and back, to 1 m before its end
    w.path = thereAndBackPath(40.0, 0.8);
    w.speed = constant(kCruiseMps);
    w.duration_s = (ArcLengthPath(w.path).length() - 1.0) / kCruiseMps;
    w.seed = 21;
  } else if (kind == "laps") {  // twice round the block (81 m a lap)
    w.speed = constant(kCruiseMps);
    w.duration_s = 130.0;
    w.seed = 22;
  } else if (kind == "steady") {  // 0.3 m/s down a straight, no bounce or sway: the scale is unobservable
    w.path = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(30.0, 0.0)};
    w.speed = constant(0.3);
    w.gait_translation = false;
    w.duration_s = 60.0;
    w.seed = 16;
  } else if (kind == "run") {
    w.speed = constant(3.5);
    w.duration_s = 60.0;
    w.seed = 15;
  } else {
    throw std::invalid_argument("unknown walk '" + kind + "'");
  }
  return w;
}

}  // namespace

std::vector<std::string> generatedWalkKinds(bool suite_only) {
  std::vector<std::string> kinds = {"slow_start", "crawl", "stops", "stairs", "fast", "stairwell"};
  if (!suite_only) {
    for (const char* k :
         {"slow_walk", "start04", "stop_and_go", "small_room", "run", "there_and_back", "laps", "steady"}) {
      kinds.push_back(k);
    }
  }
  return kinds;
}

std::vector<io::StampedPose> generatedWalk(const std::string& kind) { return sample(spec(kind)); }

}  // namespace vi_ekf_slam::sim
