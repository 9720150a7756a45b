// What bounds the drift while blind. With no image the velocity is integrated from the IMU alone,
// and the accelerometer bias and the tilt's error (gravity leaking into the horizontal axes) make
// it run off without bound: a slow hand-held walk drifted about 1.5 m/s in 10 s. A pedestrian's
// body does not accelerate freely: how fast a person walks and moves the rig along each of its
// axes (a walker's forward pace, a hand's slow sway) changes slowly. So the filter's own velocity
// in {b} over the seconds of sight (exponentially forgotten over window_s) gives a prior for the
// blind seconds: zero mean (the direction does not carry over: a hand-held rig scanning a room
// goes back and forth), its second moment plus the filter's uncertainty of it as covariance. It is
// used as a soft measurement of the body-frame velocity (body_velocity.h) only along the
// directions where the IMU's own knowledge of the velocity has become worse than the prior's: it
// bounds the uncertainty, it does not shrink it below what the person's own motion allows, and it
// never pulls an axis the IMU still knows (a walker's forward pace) towards its zero mean. The
// body-frame velocity is R_s_b^T v_s_b: bounding it also takes back the tilt's share of the drift.
// Where the body moves unlike before (a person who stood starts walking while blind), the IMU's
// velocity disagrees with the prior and the gate refuses it.
//
// Assumptions (docs/design.md): the rig is carried by a walking person (torso-worn or hand-held)
// whose motion while blind is like their motion before; a vehicle or a drone that speeds up while
// blind violates them, and the prior is switched off there (blind_motion_prior).
#pragma once

#include <optional>

#include "vi_ekf_slam/core/body_velocity.h"
#include "vi_ekf_slam/core/types.h"

namespace vi_ekf_slam {

struct BlindMotionPriorParams {
  bool enabled = true;
  /// The seconds of sight that make the prior [s]: the time constant of the exponential forgetting
  /// of the filter's body-frame velocity. Long enough to hold a few strides and turns.
  double window_s = 10.0;
  /// Seconds of sight needed before the prior is used at all [s]: a stretch right after the start
  /// has none.
  double min_seen_s = 3.0;
  /// Added to the prior's std-dev on each axis [m/s]: the pace of the blind seconds is never known
  /// better than this (a person slows down in smoke, stops at a door).
  double min_sigma_mps = 0.05;
  /// chi^2 gate (as many dof as directions measured): a body moving unlike before (a person who
  /// walked slowly speeds up) makes the IMU's velocity disagree with the prior, which is then
  /// refused. Narrower than the images' gate: the prior is a model of a person, not a sensor, and
  /// at 0.999 a walk speeding up from 0.4 to 1.3 m/s while blind took it (the study's TUM corridor
  /// with a 10 s outage: pose NEES 38); a prior refused where it agreed costs one image's bound.
  double gate_probability = 0.95;
};

class BlindMotionPrior {
 public:
  /// The filter's velocity at an image where the camera saw (after its update).
  void seen(const FilterState& state, const BlindMotionPriorParams& params);
  /// The prior at time t: zero mean, the second moment of the body-frame velocity over the seconds
  /// of sight (exponentially weighted) plus the filter's covariance of it, min_sigma_mps added to
  /// each principal sigma; none before min_seen_s of sight or when switched off.
  std::optional<BodyVelocity> prior(double t, const BlindMotionPriorParams& params) const;
  /// While no image constrains the velocity: applies the prior along the directions where the
  /// state's own body-frame velocity covariance exceeds twice the prior's (whitened by the prior,
  /// its eigenvectors with eigenvalues above 2), gated. Not applied: result.applied false.
  KalmanUpdateResult applyIfUncertain(FilterState& state, const BlindMotionPriorParams& params) const;
  /// Seconds of sight since the start or the last reset [s] (gaps in the sight left out).
  double seenSeconds() const { return seen_s_; }
  void reset() { *this = BlindMotionPrior{}; }

 private:
  std::optional<double> last_t_;
  double seen_s_ = 0.0;          ///< unweighted seconds of sight since the start or reset
  double weight_ = 0.0;          ///< sum of the frame intervals, exponentially forgotten [s]
  Mat3 sum_vv_ = Mat3::Zero();   ///< weighted sum of v_b v_b^T
  Mat3 sum_cov_ = Mat3::Zero();  ///< weighted sum of the filter's covariance of v_b
};

}  // namespace vi_ekf_slam
