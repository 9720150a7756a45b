#include "vi_ekf_slam/eval/monte_carlo.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vi_ekf_slam::eval {

using namespace sim;  // the simulator it runs

namespace {

Vec3 sigmas(const Eigen::MatrixXd& P, int i) { return P.block<3, 3>(i, i).diagonal().cwiseMax(0.0).cwiseSqrt(); }

Vec3 gaussian3(std::mt19937_64& rng, const Vec3& sigma) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double x = n(rng), y = n(rng), z = n(rng);
  return sigma.cwiseProduct(Vec3(x, y, z));
}

}  // namespace

NavState drawInitialEstimate(const NavState& truth, const InitialUncertainty& u, std::mt19937_64& rng) {
  NavState est = truth;
  est.p_n_b -= gaussian3(rng, Vec3::Constant(u.position_m));
  est.v_n_b -= gaussian3(rng, Vec3::Constant(u.velocity_mps));
  // R_true = Exp(psi) R_est  ->  R_est = Exp(-psi) R_true
  const Vec3 psi = gaussian3(rng, Vec3(u.roll_pitch_rad, u.roll_pitch_rad, u.yaw_rad));
  est.q_n_b = (expQuat(-psi) * truth.q_n_b).normalized();
  est.b_a.setZero();
  est.b_g.setZero();
  return est;
}

namespace {

/// The filter's start: drawn from its prior around the truth (the truth itself when the run starts
/// there); with a recorded IMU, its true biases minus an error drawn from the prior.
NavState drawnStart(const Scenario& sc, const EkfSlamConfig& config, const NavState& truth0, std::mt19937_64& rng) {
  NavState init = drawInitialEstimate(truth0, config.initial, rng);
  if (sc.start_at_truth) init = truth0;
  if (sc.recorded_imu) {
    // A real IMU has the biases it has: start from the true ones (when the ground truth knows
    // them) minus an error drawn from the filter's prior, as the simulated runs do.
    const Vec3 b_a0 = sc.recorded_imu->true_accel_bias.front();
    const Vec3 b_g0 = sc.recorded_imu->true_gyro_bias.front();
    const Vec3 e_a = gaussian3(rng, Vec3::Constant(config.initial.accel_bias_mps2));
    const Vec3 e_g = gaussian3(rng, Vec3::Constant(config.initial.gyro_bias_radps));
    if (b_a0.allFinite()) init.b_a = b_a0 - e_a;
    if (b_g0.allFinite()) init.b_g = b_g0 - e_g;
  }
  return init;
}

/// The sensor-centric state's own errors: the body in the strapdown frame {s} and {s} in {n},
/// against the true {s} (p_n_s_true, q_n_s_true).
void strapdownFrameErrors(const FilterState& s, const TrajectorySample& tr, const Vec3& p_n_s_true,
                          const Quat& q_n_s_true, FrameMetrics* m) {
  m->has_s = true;
  const Eigen::MatrixXd Ps = s.motionCovariance();
  const Vec3 p_s_b_true = q_n_s_true.conjugate() * (tr.p_n_b - p_n_s_true);
  const Quat q_s_b_true = q_n_s_true.conjugate() * tr.q_n_b;
  m->e_p_sb = p_s_b_true - s.x.p_s_b;
  m->e_q_sb = orientationError(q_s_b_true, s.x.q_s_b);
  m->e_p_ns = p_n_s_true - s.x.p_n_s;
  m->e_q_ns = orientationError(q_n_s_true, s.x.q_n_s);
  m->s_p_sb = sigmas(Ps, idx::kP);
  m->s_q_sb = sigmas(Ps, idx::kPsi);
  m->s_p_ns = sigmas(Ps, idx::kPns);
  m->s_q_ns = sigmas(Ps, idx::kPsiNs);
}

/// The run's whole-trajectory figures from its per-frame positions and orientation errors.
void trajectoryMetrics(const std::vector<Vec3>& p_true, const std::vector<Vec3>& p_est,
                       const std::vector<double>& q_err_deg, RunResult* out) {
  std::vector<Vec3> e;
  for (size_t i = 0; i < p_true.size(); ++i) e.push_back(p_true[i] - p_est[i]);
  out->ate_position_m = rms(e);
  const YawTranslation T = alignPosYaw(p_est, p_true);
  std::vector<Vec3> e_aligned;
  double filter_s = 0.0;
  for (size_t i = 0; i < p_true.size(); ++i) e_aligned.push_back(p_true[i] - T.apply(p_est[i]));
  for (const auto& f : out->frames) filter_s += f.update_ms * 1e-3;
  out->ate_posyaw_m = rms(e_aligned);
  if (out->frames.size() > 1 && filter_s > 0.0) {
    out->real_time_factor = (out->frames.back().t - out->frames.front().t) / filter_s;
  }
  out->ate_orientation_deg = rms(q_err_deg);
  out->final_position_error_m = e.empty() ? 0.0 : e.back().norm();
  out->distance_m = pathLength(p_true);
  std::vector<double> t;
  for (const auto& f : out->frames) t.push_back(f.t);
  out->revisits = revisitErrors(t, p_true, p_est);
}

}  // namespace

RunResult runMonteCarloRun(const Scenario& scenario_in, const EkfSlamConfig& config, std::uint64_t seed) {
  Scenario sc = scenario_in;
  // The IMU's turn-on biases are drawn from the filter's prior, unless the run starts at the true
  // state (zero biases) or is told to have none.
  const bool draw_biases = sc.draw_imu_biases && !sc.start_at_truth;
  sc.imu.initial_accel_bias_sigma_mps2 = draw_biases ? config.initial.accel_bias_mps2 : 0.0;
  sc.imu.initial_gyro_bias_sigma_radps = draw_biases ? config.initial.gyro_bias_radps : 0.0;
  if (sc.dynamic_init) {
    // The initializer does not estimate the gyro bias: its prior is the one the biases are drawn with.
    sc.dynamic_init = withFilterSettings(*sc.dynamic_init, config);
    sc.dynamic_init->gyro_bias_sigma_radps = config.initial.gyro_bias_radps;
  }
  std::mt19937_64 rng(seed);
  const double t0 = std::max(0.0, sc.trajectory->startTime());
  const NavState truth0 = trueNavState(*sc.trajectory, t0);
  const NavState init = drawnStart(sc, config, truth0, rng);

  RunResult out;
  // True pose of the strapdown frame {s}: the true body pose at the start and at every
  // composition (the filter defines {s} as the true body frame at those instants).
  Vec3 p_n_s_true = truth0.p_n_b;
  Quat q_n_s_true = truth0.q_n_b;
  std::vector<Vec3> p_true, p_est;
  std::vector<double> q_err_deg;
  // A start of the node's (and a start over after the filter was lost) defines {s} anew.
  double started_t = sc.dynamic_init ? std::nan("") : t0;
  const FrameCallback cb = [&](EkfSlam& f, FrameRecord& rec) {
    if (rec.initialized_t != started_t) {
      const TrajectorySample at_init = sc.trajectory->sample(rec.initialized_t);
      p_n_s_true = at_init.p_n_b;
      q_n_s_true = at_init.q_n_b;
      started_t = rec.initialized_t;
    }
    FrameMetrics m;
    m.update_ms = rec.filter_ms;
    m.t = rec.t;
    const NavState& n = rec.estimate;
    const TrajectorySample& tr = rec.truth;
    m.p_true = tr.p_n_b;
    m.p_est = n.p_n_b;
    m.e_p = tr.p_n_b - n.p_n_b;
    m.e_q = orientationError(tr.q_n_b, n.q_n_b);
    m.e_v = tr.v_n_b - n.v_n_b;
    m.e_ba = rec.true_accel_bias - n.b_a;
    m.e_bg = rec.true_gyro_bias - n.b_g;
    const Eigen::MatrixXd C = n.cov;
    m.s_p = sigmas(C, idx::kP);
    m.s_q = sigmas(C, idx::kPsi);
    m.s_v = sigmas(C, idx::kV);
    m.s_ba = sigmas(C, idx::kBa);
    m.s_bg = sigmas(C, idx::kBg);
    Eigen::Matrix<double, 6, 1> e6;
    e6 << m.e_p, m.e_q;
    m.nees_pose = nees(e6, n.poseCovariance());
    m.nees_p = nees(m.e_p, C.block<3, 3>(idx::kP, idx::kP));
    m.nees_q = nees(m.e_q, C.block<3, 3>(idx::kPsi, idx::kPsi));
    const FilterState& s = f.state();
    // A composition in this frame already moved the filter's {s} to the current body frame.
    if (rec.result.composed) {
      p_n_s_true = tr.p_n_b;
      q_n_s_true = tr.q_n_b;
    }
    if (isSensorCentric(s.mechanization())) strapdownFrameErrors(s, tr, p_n_s_true, q_n_s_true, &m);
    std::vector<Vec3> est, truth;
    for (const auto& l : f.landmarks()) {
      est.push_back(l.p_n_l);
      truth.push_back(landmarkOfTrack(l.id, sc.world).p_n);
      out.landmark_estimates[l.id] = l.p_n_l;
    }
    m.gamma = scaleRatio(est, truth);
    m.landmarks = s.numLandmarks();
    m.new_landmarks = static_cast<int>(rec.result.new_ids.size());
    m.new_triangulated = rec.result.new_triangulated;
    m.rejected = static_cast<int>(rec.result.update.rejected_ids.size());
    m.composed = rec.result.composed;
    m.stationary = rec.result.zero_velocity_applied;
    m.parallax_px = rec.result.stationary.parallax_px;
    for (const auto& v : rec.result.revisits) {
      ++m.revisits;
      if (&landmarkOfTrack(v.track_id, sc.world) != &landmarkOfTrack(v.landmark_id, sc.world)) ++m.false_revisits;
    }
    m.revisits_refused = rec.result.revisits_rejected;
    m.dormant = rec.result.dormant_landmarks;
    m.e_td = sc.cam.time_offset_s - s.x.t_d;
    m.s_td = std::sqrt(std::max(0.0, s.covariance()(idx::kTd, idx::kTd)));
    p_true.push_back(m.p_true);
    p_est.push_back(m.p_est);
    q_err_deg.push_back(m.e_q.norm() * 180.0 / M_PI);
    out.frames.push_back(m);
  };
  const SimRun run = runSimulation(sc, config, init, rng, cb, false);
  out.init_delay_s = run.initialized_t - t0;
  trajectoryMetrics(p_true, p_est, q_err_deg, &out);
  return out;
}

ConsistencySummary summarize(const std::string& name, const std::vector<RunResult>& all_runs) {
  ConsistencySummary s;
  s.name = name;
  s.runs_started = static_cast<int>(all_runs.size());
  // Runs that never initialized (a dynamic start that kept waiting) have no estimate to judge;
  // the others are compared frame by frame from their initialization on, over the frames all have.
  std::vector<RunResult> runs;
  for (const auto& r : all_runs) {
    s.init_delay_s.push_back(r.init_delay_s);
    if (std::isfinite(r.init_delay_s) && !r.frames.empty()) runs.push_back(r);
  }
  s.runs = static_cast<int>(runs.size());
  if (runs.empty()) return s;
  size_t T = runs.front().frames.size();
  for (const auto& r : runs) T = std::min(T, r.frames.size());
  for (auto& r : runs) r.frames.resize(T);
  const double M = static_cast<double>(runs.size());
  s.pose_band = neesBand(6, s.runs);
  int inside = 0, counted = 0;
  std::vector<double> times;
  for (size_t k = 0; k < T; ++k) {
    double np = 0, nq = 0, npose = 0, e2 = 0;
    Vec3 ap = Vec3::Zero(), av = Vec3::Zero(), aq = Vec3::Zero(), aba = Vec3::Zero(), abg = Vec3::Zero();
    std::vector<double> g;
    for (const auto& r : runs) {
      const FrameMetrics& f = r.frames[k];
      np += f.nees_p / M;
      nq += f.nees_q / M;
      npose += f.nees_pose / M;
      e2 += f.e_p.squaredNorm() / M;
      ap += f.e_p.cwiseQuotient(f.s_p).cwiseAbs2() / M;
      av += f.e_v.cwiseQuotient(f.s_v).cwiseAbs2() / M;
      aq += f.e_q.cwiseQuotient(f.s_q).cwiseAbs2() / M;
      aba += f.e_ba.cwiseQuotient(f.s_ba).cwiseAbs2() / M;
      abg += f.e_bg.cwiseQuotient(f.s_bg).cwiseAbs2() / M;
      if (std::isfinite(f.gamma)) g.push_back(f.gamma);
      times.push_back(f.update_ms);
    }
    s.t.push_back(runs.front().frames[k].t);
    s.avg_nees_p.push_back(np);
    s.avg_nees_q.push_back(nq);
    s.avg_nees_pose.push_back(npose);
    std::sort(g.begin(), g.end());
    s.median_gamma.push_back(g.empty() ? std::nan("") : g[g.size() / 2]);
    s.rms_p.push_back(std::sqrt(e2));
    s.axis_p.push_back(ap);
    s.axis_v.push_back(av);
    s.axis_q.push_back(aq);
    s.axis_ba.push_back(aba);
    s.axis_bg.push_back(abg);
    if (std::isfinite(npose)) {
      ++counted;
      if (s.pose_band.contains(npose)) ++inside;
    }
  }
  const auto mean = meanOfFinite;
  s.nees_position = mean(s.avg_nees_p);
  s.nees_orientation = mean(s.avg_nees_q);
  s.nees_pose = mean(s.avg_nees_pose);
  std::vector<double> early;
  for (size_t k = 0; k < T && s.t[k] - s.t.front() < kEarlyWindowS; ++k) early.push_back(s.avg_nees_pose[k]);
  s.nees_pose_early = mean(early);
  s.consistent_fraction = counted ? static_cast<double>(inside) / counted : 0.0;
  std::vector<double> ate, ateq, fin, gam, rtf, revisit;
  for (const auto& r : runs) {
    if (r.revisits.pairs > 0) revisit.push_back(r.revisits.ratio());
    for (const auto& f : r.frames) {
      s.revisits_per_run += f.revisits / static_cast<double>(runs.size());
      s.false_revisits += f.false_revisits;
    }
    s.ate_posyaw_runs_m.push_back(r.ate_posyaw_m);
    rtf.push_back(r.real_time_factor);
    ate.push_back(r.ate_position_m);
    ateq.push_back(r.ate_orientation_deg);
    fin.push_back(r.final_position_error_m);
    gam.push_back(r.frames.back().gamma);
  }
  s.revisit_error_ratio = revisit.empty() ? std::nan("") : mean(revisit);
  s.ate_position_m = mean(ate);
  s.ate_posyaw_m = mean(s.ate_posyaw_runs_m);
  s.real_time_factor = mean(rtf);
  s.ate_orientation_deg = mean(ateq);
  s.final_position_error_m = mean(fin);
  s.distance_m = runs.front().distance_m;
  s.final_position_error_pct = 100.0 * s.final_position_error_m / std::max(1e-9, s.distance_m);
  s.final_scale_ratio = mean(gam);
  s.mean_update_ms = mean(times);
  std::sort(times.begin(), times.end());
  s.p95_update_ms = times[static_cast<size_t>(0.95 * (times.size() - 1))];
  return s;
}

}  // namespace vi_ekf_slam::eval
