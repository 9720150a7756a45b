// What a run says about itself without ground truth: path length, speed, tracks, observations,
// NIS, time offset, resets and time per image (health.json / health.md and the per-image trace of
// the offline bag runner). ROS-free: the runner converts its status messages to StatusSample.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/eval/report.h"

namespace vi_ekf_slam::eval {

/// The filter's status after one processed image (the FilterStatus message's figures).
struct StatusSample {
  double t = 0.0;         ///< [s] IMU clock
  Vec3 p = Vec3::Zero();  ///< [m] body position in the output frame
  int tracks = 0;
  int accepted = 0, rejected = 0;  ///< observations of the update
  double nis_per_dof = 0.0;
  double time_offset_s = 0.0, time_offset_sigma_s = 0.0;
  int resets = 0;  ///< since the start
  double processing_ms = 0.0, tracker_ms = 0.0;
  int landmarks = 0, new_landmarks = 0, deferred = 0, removed = 0;
  int dormant = 0, revisits = 0;  ///< keep_map: dormant landmarks, and those observed again in this image
  bool stationary = false;
  double speed_mps = 0.0;           ///< [m/s] the body's estimated speed
  double velocity_sigma_mps = 0.0;  ///< [m/s] its std-dev per axis (root of the mean of the three variances)
  double blind_s = 0.0;             ///< [s] since the first image without a usable feature; 0 while the camera sees
};

/// The health of one run: samples of every processed image (across resets), the resets, the
/// input's duration and the wall time it took [s].
nlohmann::ordered_json runHealth(const std::vector<StatusSample>& samples, int resets, double input_s, double wall_s);
/// One run's health as two lines of text.
std::string healthLine(const std::string& name, const nlohmann::ordered_json& h);
/// The health report's Markdown columns (with the first reference comparison's figures).
std::vector<ReportColumn> healthColumns();
/// Every sample as CSV.
void writeTrace(const std::string& path, const std::vector<StatusSample>& samples);

}  // namespace vi_ekf_slam::eval
