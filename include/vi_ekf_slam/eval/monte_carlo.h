// Monte-Carlo consistency runs of the simulator (paper Sec. IV-A, repeated M times): each run draws its own
// sensor noise, initial biases and initial state error from the filter's own initial
// covariance, so the NEES measures consistency honestly. Per camera time it records errors in
// {n} (and, for sensor-centric filters, in {s} and of p_n_s, q_n_s) with the filter's sigmas,
// NEES, the scale ratio gamma and the events (new landmarks, compositions).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "vi_ekf_slam/eval/metrics.h"
#include "vi_ekf_slam/sim/sim_runner.h"

namespace vi_ekf_slam::eval {

struct FrameMetrics {
  double t = 0.0;
  Vec3 p_true = Vec3::Zero(), p_est = Vec3::Zero();
  // Errors (true - estimate) in {n} and the filter's 1-sigma (square roots of the diagonal).
  Vec3 e_p, e_q, e_v, e_ba, e_bg;
  Vec3 s_p, s_q, s_v, s_ba, s_bg;
  double nees_p = 0.0, nees_q = 0.0, nees_pose = 0.0;
  // Sensor-centric only: body pose in {s} and the pose of {s} in {n}.
  bool has_s = false;
  Vec3 e_p_sb, e_q_sb, e_p_ns, e_q_ns;
  Vec3 s_p_sb, s_q_sb, s_p_ns, s_q_ns;
  double gamma = 0.0;  ///< eq. (34) over the landmarks in the map
  int landmarks = 0;
  int new_landmarks = 0;
  int new_triangulated = 0;  ///< of those, entered at the depth their baseline gave
  int rejected = 0;
  bool composed = false;
  bool stationary = false;   ///< the filter detected standing (zero-velocity update applied)
  double parallax_px = 0.0;  ///< the standing test's median de-rotated parallax
  double update_ms = 0.0;    ///< filter time for this frame (propagation + update + init + composition)
  double e_td = 0.0;         ///< camera-IMU time offset error (true - estimate) [s]
  double s_td = 0.0;         ///< its 1-sigma [s]
  /// Keeping the map: dormant landmarks observed again through a new track (accepted by the
  /// update), those of them that were another point (the simulator knows), and matches refused.
  int revisits = 0;
  int false_revisits = 0;
  int revisits_refused = 0;
  int dormant = 0;  ///< dormant landmarks after the frame
};

struct RunResult {
  std::vector<FrameMetrics> frames;
  std::map<std::int64_t, Vec3> landmark_estimates;  ///< last estimate of every landmark in {n}
  double ate_position_m = 0.0;
  double ate_posyaw_m = 0.0;  ///< after the 4-DoF (yaw + translation) alignment
  double ate_orientation_deg = 0.0;
  double final_position_error_m = 0.0;
  double distance_m = 0.0;
  double real_time_factor = 0.0;  ///< data duration / filter time (propagation, update, init)
  /// From the start of the run to the filter's initialization (0 when started from the truth or
  /// the prior; NaN when a dynamic start never initialized) [s]. The frames start there.
  double init_delay_s = 0.0;
  /// Coming back to places seen more than 20 s before (within 0.5 m): the errors then and again.
  RevisitErrors revisits;
};

/// Draws the initial estimate: truth minus an error ~ N(0, P0) of the world-centric prior
/// (position, velocity, roll/pitch and yaw), i.e. the registration error of the paper.
NavState drawInitialEstimate(const NavState& truth, const InitialUncertainty& u, std::mt19937_64& rng);

/// One run with its own seed; the initial biases of the simulated IMU are drawn with the
/// filter's prior sigmas.
RunResult runMonteCarloRun(const sim::Scenario& scenario, const EkfSlamConfig& config, std::uint64_t seed);

/// The first seconds after the initialization, whose NEES says whether a start is honest [s].
constexpr double kEarlyWindowS = 10.0;

/// Over the runs that initialized (all but a dynamic start that kept waiting), frame by frame
/// from their initialization on, over the number of frames every one of them has.
struct ConsistencySummary {
  std::string name;
  int runs = 0;                           ///< runs that initialized
  int runs_started = 0;                   ///< runs in all
  std::vector<double> init_delay_s;       ///< every run's RunResult::init_delay_s
  std::vector<double> ate_posyaw_runs_m;  ///< every initialized run's RunResult::ate_posyaw_m [m]
  double ate_position_m = 0.0;            ///< mean over runs of the per-run position RMSE
  double ate_posyaw_m = 0.0;              ///< the same after posyaw alignment
  /// Over the runs that came back to places: the mean of their error on return over their error
  /// when the place was first seen (RevisitErrors::ratio; NaN when no run came back).
  double revisit_error_ratio = std::nan("");
  /// Keeping the map: accepted re-observations of dormant landmarks per run, and how many of all
  /// the runs' were of another point (a false closure the filter believed).
  double revisits_per_run = 0.0;
  int false_revisits = 0;
  double real_time_factor = 0.0;     ///< mean over runs
  double ate_orientation_deg = 0.0;  ///< mean over runs of the per-run orientation RMSE
  double final_position_error_m = 0.0;
  double final_position_error_pct = 0.0;  ///< of the distance walked
  double distance_m = 0.0;
  double nees_position = 0.0;  ///< time average of the run-averaged NEES
  double nees_orientation = 0.0;
  double nees_pose = 0.0;
  double nees_pose_early = 0.0;      ///< the same over the first kEarlyWindowS after the initialization
  double consistent_fraction = 0.0;  ///< share of camera times with the run-averaged pose NEES in its 95% band
  double final_scale_ratio = 0.0;
  double mean_update_ms = 0.0;
  double p95_update_ms = 0.0;
  NeesBand pose_band;
  // Run-averaged time series (same length as the runs' frames); gamma as the run median, since
  // the landmarks initialized in a frame make single runs spike (as the paper notes).
  std::vector<double> t, avg_nees_p, avg_nees_q, avg_nees_pose, median_gamma, rms_p;
  /// Per axis, run-averaged (e_i / sigma_i)^2 of position, velocity and orientation in {n}: 1 when
  /// that axis is consistent; shows which direction an inconsistency lives in. The same for the
  /// accelerometer and gyro biases (an overconfident gyro bias z is what drifts yaw unnoticed).
  std::vector<Vec3> axis_p, axis_v, axis_q, axis_ba, axis_bg;
};

ConsistencySummary summarize(const std::string& name, const std::vector<RunResult>& runs);

}  // namespace vi_ekf_slam::eval
