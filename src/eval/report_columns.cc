#include "vi_ekf_slam/eval/report_columns.h"

#include <map>
#include <stdexcept>

namespace vi_ekf_slam::eval {

namespace {

const std::map<std::string, ReportColumn>& table() {
  static const std::map<std::string, ReportColumn> columns = [] {
    std::map<std::string, ReportColumn> t;
    for (const ReportColumn& c : std::vector<ReportColumn>{
             {"ate_position_m", "ATE [m]", 3},
             {"ate_posyaw_m", "ATE posyaw [m]", 3},
             {"ate_orientation_deg", "ATE rot [deg]", 3},
             {"final_position_error_m", "final err [m]", 3},
             {"final_position_error_pct", "final err [% of dist]", 2},
             {"nees_position", "NEES pos", 2},
             {"nees_orientation", "NEES rot", 2},
             {"nees_pose", "NEES pose", 2},
             {"nees_pose_after_outage", "NEES pose after outage", 2},
             {"consistent_fraction", "consistent", 2},
             {"final_scale_ratio", "final gamma", 3},
             {"map_error_median_m", "map err median [m]", 3},
             {"revisit_error_ratio", "error on return / first", 2},
             {"revisits_per_run", "revisits / run", 1},
             {"false_revisits", "false revisits", 0},
             {"processing_ms_mean", "ms/frame", 1},
             {"processing_ms_p95", "ms/frame p95", 1},
             {"filter_ms_mean", "filter [ms]", 2},
             {"filter_ms_p95", "filter p95 [ms]", 2},
             {"real_time_factor", "real-time factor", 1},
             {"resets", "resets", 0},
             {"band_lo", "band from", 2},
             {"band_hi", "to", 2},
             {"inside_band", "inside", 0},
         })
      t[c.key] = c;
    return t;
  }();
  return columns;
}

}  // namespace

ReportColumn metricColumn(const std::string& key) {
  const auto it = table().find(key);
  if (it == table().end()) throw std::invalid_argument("no report column for the metric '" + key + "'");
  return it->second;
}

std::vector<ReportColumn> metricColumns(const std::vector<std::string>& keys) {
  std::vector<ReportColumn> out;
  out.reserve(keys.size());
  for (const std::string& k : keys) out.push_back(metricColumn(k));
  return out;
}

}  // namespace vi_ekf_slam::eval
