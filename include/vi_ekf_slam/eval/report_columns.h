// The one header and precision of every metric the tools report (run_bag, the study, the suite,
// the scripts through vi_ekf_slam_report), by the metric's key: the same metric reads the same in
// every table.
#pragma once

#include <string>
#include <vector>

#include "vi_ekf_slam/eval/report.h"

namespace vi_ekf_slam::eval {

/// The column of a metric key; throws std::invalid_argument for a key without one.
ReportColumn metricColumn(const std::string& key);
std::vector<ReportColumn> metricColumns(const std::vector<std::string>& keys);

}  // namespace vi_ekf_slam::eval
