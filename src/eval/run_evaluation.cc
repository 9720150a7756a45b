#include "vi_ekf_slam/eval/run_evaluation.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>

#include "vi_ekf_slam/core/chi_squared.h"
#include "vi_ekf_slam/eval/report.h"
#include "vi_ekf_slam/eval/report_columns.h"
#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam::eval {

namespace {

/// The truth at time t (interpolated within 0.2 s): the estimates are stamped at the state's time
/// (image stamp + estimated time offset), which need not be a truth stamp.
std::optional<io::StampedPose> truthAt(const std::vector<io::StampedPose>& truth, double t) {
  return io::interpolatePose(truth, t, 0.2);
}

}  // namespace

RunMetrics evaluateRun(const std::vector<EstimatedPose>& est, const std::vector<io::StampedPose>& truth,
                       const std::vector<EstimatedLandmark>& landmarks, const LandmarkTruth& landmark_truth) {
  RunMetrics m;
  // Registration at the first estimate with a truth pose.
  size_t first = 0;
  while (first < est.size() && !truthAt(truth, est[first].t)) ++first;
  if (first == est.size()) return m;
  const std::optional<io::StampedPose> g0 = truthAt(truth, est[first].t);
  const Eigen::Isometry3d T_true_est = registrationAtFirstPose(est[first].p, est[first].q, g0->p, g0->q);
  const Quat R(T_true_est.linear());
  Eigen::Matrix<double, 6, 6> G = Eigen::Matrix<double, 6, 6>::Zero();
  G.topLeftCorner<3, 3>() = T_true_est.linear();
  G.bottomRightCorner<3, 3>() = T_true_est.linear();
  const double lo = chiSquaredQuantile(0.025, 6), hi = chiSquaredQuantile(0.975, 6);
  std::vector<Vec3> e_all, p_true, p_est;
  std::vector<double> q_deg, np, nq, npose, ms, tracker_ms;
  int inside = 0;
  for (size_t i = first; i < est.size(); ++i) {
    const std::optional<io::StampedPose> g = truthAt(truth, est[i].t);
    if (!g) continue;
    RunFrame f;
    f.t = est[i].t;
    f.p_true = g->p;
    f.p_est = T_true_est * est[i].p;
    const Quat q_est = R * est[i].q;
    f.e_p = g->p - f.p_est;
    f.e_q = orientationError(g->q, q_est);
    const Eigen::Matrix<double, 6, 6> C = G * est[i].cov * G.transpose();
    f.s_p = C.topLeftCorner<3, 3>().diagonal().cwiseMax(0).cwiseSqrt();
    f.s_q = C.bottomRightCorner<3, 3>().diagonal().cwiseMax(0).cwiseSqrt();
    Eigen::Matrix<double, 6, 1> e;
    e << f.e_p, f.e_q;
    f.nees_pose = nees(e, C);
    np.push_back(nees(f.e_p, C.topLeftCorner<3, 3>()));
    nq.push_back(nees(f.e_q, C.bottomRightCorner<3, 3>()));
    npose.push_back(f.nees_pose);
    inside += f.nees_pose >= lo && f.nees_pose <= hi;
    e_all.push_back(f.e_p);
    p_true.push_back(f.p_true);
    p_est.push_back(f.p_est);
    q_deg.push_back(f.e_q.norm() * 180.0 / M_PI);
    ms.push_back(est[i].processing_ms);
    tracker_ms.push_back(est[i].tracker_ms);
    m.series.push_back(f);
  }
  if (m.series.empty()) return m;
  const auto mean = meanOfFinite;
  m.frames = static_cast<int>(m.series.size());
  m.duration_s = m.series.back().t - m.series.front().t;
  m.distance_m = pathLength(p_true);
  m.ate_position_m = rms(e_all);
  const YawTranslation fit = alignPosYaw(p_est, p_true);
  std::vector<Vec3> e_fit;
  for (size_t i = 0; i < p_est.size(); ++i) e_fit.push_back(p_true[i] - fit.apply(p_est[i]));
  m.ate_posyaw_m = rms(e_fit);
  m.ate_orientation_deg = rms(q_deg);
  m.final_position_error_m = e_all.back().norm();
  m.final_position_error_pct = 100.0 * m.final_position_error_m / std::max(1e-9, m.distance_m);
  m.nees_position = mean(np);
  m.nees_orientation = mean(nq);
  m.nees_pose = mean(npose);
  m.consistent_fraction = static_cast<double>(inside) / m.frames;
  m.processing_ms_mean = mean(ms);
  m.tracker_ms_mean = mean(tracker_ms);  // NaN unless the front end was timed
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  m.processing_ms_p95 = sorted[static_cast<size_t>(0.95 * (sorted.size() - 1))];
  double total = 0.0;
  for (double x : ms) total += x;
  m.real_time_factor = total > 0.0 ? 1000.0 * m.duration_s / total : std::nan("");
  m.final_scale_ratio = std::nan("");
  if (landmark_truth) {
    std::vector<Vec3> le, lt;
    std::vector<double> err;
    for (const auto& l : landmarks) {
      if (auto p = landmark_truth(l)) {
        le.push_back(l.p);
        lt.push_back(*p);
        err.push_back((T_true_est * l.p - *p).norm());
      }
    }
    m.map_landmarks = static_cast<int>(le.size());
    if (le.size() >= 2) {
      m.final_scale_ratio = scaleRatio(le, lt);
      std::sort(err.begin(), err.end());
      m.map_error_median_m = err[err.size() / 2];
      m.map_error_p90_m = err[err.size() * 9 / 10];
    }
  }
  return m;
}

void writeRunReport(const std::string& dir, const std::vector<std::pair<std::string, RunMetrics>>& runs,
                    const nlohmann::ordered_json& config) {
  Report r;
  r.tool = "run_bag";
  r.title = "Runs against the ground truth";
  r.config = config;
  for (const auto& [name, m] : runs) {
    r.runs.rows[name] = {{"ate_position_m", m.ate_position_m},
                         {"ate_posyaw_m", m.ate_posyaw_m},
                         {"ate_orientation_deg", m.ate_orientation_deg},
                         {"final_position_error_m", m.final_position_error_m},
                         {"final_position_error_pct", m.final_position_error_pct},
                         {"distance_m", m.distance_m},
                         {"nees_position", m.nees_position},
                         {"nees_orientation", m.nees_orientation},
                         {"nees_pose", m.nees_pose},
                         {"consistent_fraction", m.consistent_fraction},
                         {"final_scale_ratio", m.final_scale_ratio},
                         {"map_landmarks", m.map_landmarks},
                         {"map_error_median_m", m.map_error_median_m},
                         {"map_error_p90_m", m.map_error_p90_m},
                         {"runs", 1},
                         {"frames", m.frames},
                         {"duration_s", m.duration_s},
                         {"processing_ms_mean", m.processing_ms_mean},
                         {"processing_ms_p95", m.processing_ms_p95},
                         {"tracker_ms_mean", m.tracker_ms_mean},
                         {"real_time_factor", m.real_time_factor}};
  }
  r.runs.columns =
      metricColumns({"ate_position_m", "ate_posyaw_m", "ate_orientation_deg", "final_position_error_m",
                     "final_position_error_pct", "nees_position", "nees_orientation", "nees_pose", "final_scale_ratio",
                     "map_error_median_m", "processing_ms_mean", "processing_ms_p95", "real_time_factor"});
  writeReport(dir, "summary", r);
  for (const auto& [name, m] : runs) {
    std::ofstream ts(dir + "/" + name + "_timeseries.csv");
    ts << "t,tx,ty,tz,ex,ey,ez,e_p_x,e_p_y,e_p_z,s_p_x,s_p_y,s_p_z,e_q_x,e_q_y,e_q_z,s_q_x,s_q_y,s_q_z,nees_pose\n"
       << std::setprecision(9);
    for (const auto& f : m.series) {
      ts << f.t;
      for (const Vec3* v : {&f.p_true, &f.p_est, &f.e_p, &f.s_p, &f.e_q, &f.s_q})
        ts << "," << v->x() << "," << v->y() << "," << v->z();
      ts << "," << f.nees_pose << "\n";
    }
  }
}

}  // namespace vi_ekf_slam::eval
