// Evaluation of one run (a bag replayed live or offline) against its ground truth: the estimate
// starts in its own frame (static initialization: position 0, yaw 0), so it is registered to the
// truth at the first estimate (translation and yaw, both unobservable; roll and pitch are
// physical). Covariances rotate with that registration, which keeps NEES meaningful.
#pragma once

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/core/measurement_model.h"
#include "vi_ekf_slam/eval/metrics.h"
#include "vi_ekf_slam/io/tum_io.h"

namespace vi_ekf_slam::eval {

struct EstimatedPose {
  double t = 0.0;
  Vec3 p = Vec3::Zero();
  Quat q = Quat::Identity();
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();  ///< [position, orientation (global)]
  double processing_ms = 0.0;
  double tracker_ms = std::nan("");  ///< the front end's part of processing_ms, if known
};

struct EstimatedLandmark {
  std::int64_t id = 0;
  Vec3 p = Vec3::Zero();  ///< in the estimate's world frame
  double birth_time = 0.0;
  Eigen::Vector2d birth_uv = Eigen::Vector2d::Zero();
};

/// Finds the true position of a landmark from where its track started (e.g. a ray cast into a
/// simulated world from the true camera pose). nullopt if unknown.
using LandmarkTruth = std::function<std::optional<Vec3>(const EstimatedLandmark&)>;

struct RunFrame {
  double t = 0.0;
  Vec3 p_true, p_est;  ///< estimate registered to the truth frame
  Vec3 e_p, e_q, s_p, s_q;
  double nees_pose = 0.0;
};

struct RunMetrics {
  int frames = 0;
  double duration_s = 0.0;
  double distance_m = 0.0;
  double ate_position_m = 0.0;  ///< registered at the first pose, no fit
  double ate_posyaw_m = 0.0;    ///< after a least-squares position + yaw fit
  double ate_orientation_deg = 0.0;
  double final_position_error_m = 0.0;
  double final_position_error_pct = 0.0;
  double nees_position = 0.0, nees_orientation = 0.0, nees_pose = 0.0;  ///< time averages
  double consistent_fraction = 0.0;  ///< frames with pose NEES inside its 95% chi^2(6) interval
  double final_scale_ratio = 0.0;    ///< eq. (34) over the final map (NaN if no landmark truth)
  double map_error_median_m = 0.0;   ///< |landmark - truth| over the final map, registered
  double map_error_p90_m = 0.0;
  int map_landmarks = 0;  ///< landmarks of the final map with a known truth
  double processing_ms_mean = 0.0, processing_ms_p95 = 0.0;
  double tracker_ms_mean = std::nan("");  ///< of processing_ms_mean: the front end (NaN: not measured)
  double real_time_factor = 0.0;          ///< duration / total processing time
  std::vector<RunFrame> series;
};

/// truth must be sorted by time; estimates are matched to truth stamps within 1 ms.
RunMetrics evaluateRun(const std::vector<EstimatedPose>& estimates, const std::vector<io::StampedPose>& truth,
                       const std::vector<EstimatedLandmark>& landmarks = {}, const LandmarkTruth& landmark_truth = {});

/// summary.json / summary.md / timeseries.csv for runs keyed by name (e.g. per mechanization).
void writeRunReport(const std::string& dir, const std::vector<std::pair<std::string, RunMetrics>>& runs,
                    const nlohmann::ordered_json& config);

}  // namespace vi_ekf_slam::eval
