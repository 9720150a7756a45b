// Continuous body motion for the simulator, in the navigation frame {n} (z down, gravity +z).
// A trajectory gives pose, velocity, acceleration and body angular rate at any time, so the
// synthesized IMU is consistent with the poses.
#pragma once

#include <algorithm>
#include <memory>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam::sim {

struct TrajectorySample {
  double t = 0.0;
  Vec3 p_n_b = Vec3::Zero();  ///< [m]
  Vec3 v_n_b = Vec3::Zero();  ///< [m/s]
  Vec3 a_n_b = Vec3::Zero();  ///< kinematic acceleration in {n} [m/s^2]
  Quat q_n_b = Quat::Identity();
  Vec3 w_b = Vec3::Zero();  ///< angular rate of {b} w.r.t. {n}, in {b} [rad/s]
};

class Trajectory {
 public:
  virtual ~Trajectory() = default;
  virtual double startTime() const = 0;
  virtual double endTime() const = 0;
  virtual TrajectorySample sample(double t) const = 0;
};

/// Level circle with a vertical oscillation; heading follows the tangent (body x forward,
/// y right, z down). Starts at the origin heading along {n}'s x axis.
class CircleTrajectory : public Trajectory {
 public:
  CircleTrajectory(double radius_m, double yaw_rate_radps, double bounce_m, double duration_s);
  double startTime() const override { return 0.0; }
  double endTime() const override { return duration_; }
  TrajectorySample sample(double t) const override;

 private:
  double r_, w_, h_, duration_;
};

/// Small excited motion around a point: position p0 + A sin(w t + phase) per axis and attitude
/// Exp(B sin(u t)) per axis (about a level body facing {n}'s x axis). Every axis is excited, so
/// scale, gravity direction and biases are observable.
class LissajousTrajectory : public Trajectory {
 public:
  LissajousTrajectory(const Vec3& p0, const Vec3& amplitude_m, const Vec3& freq_radps, const Vec3& angle_amp_rad,
                      const Vec3& angle_freq_radps, double duration_s);
  double startTime() const override { return 0.0; }
  double endTime() const override { return duration_; }
  TrajectorySample sample(double t) const override;

 private:
  Vec3 p0_, A_, w_, B_, u_;
  double duration_;
};

/// The part of another trajectory between `start_time` and `end_time` (e.g. the first minute of a
/// long file, or a start while already walking).
class TruncatedTrajectory : public Trajectory {
 public:
  TruncatedTrajectory(std::shared_ptr<const Trajectory> base, double end_time)
      : TruncatedTrajectory(base, base->startTime(), end_time) {}
  TruncatedTrajectory(std::shared_ptr<const Trajectory> base, double start_time, double end_time)
      : base_(std::move(base)),
        start_(std::clamp(start_time, base_->startTime(), base_->endTime())),
        end_(std::clamp(end_time, start_, base_->endTime())) {}
  double startTime() const override { return start_; }
  double endTime() const override { return end_; }
  TrajectorySample sample(double t) const override { return base_->sample(std::clamp(t, start_, end_)); }

 private:
  std::shared_ptr<const Trajectory> base_;
  double start_;
  double end_;
};

}  // namespace vi_ekf_slam::sim
