// The one report schema of the tools (run_bag's summary and health, the study, the suite, the
// benchmarks; tools/report.py writes the same from Python). JSON:
//   {"schema": "vi_ekf_slam.report/1", "tool": ..., ["commit": ...,] "title": ..., "config": {settings},
//    "runs": {name: {metric: value}}, "tables": {name: {row: {column: value}}}}
// ("tables" only when there are more tables than the runs; "commit" the environment's
// VI_EKF_SLAM_COMMIT, the commit `make` measures on), non-finite numbers as null; and the
// same as Markdown: the title, the settings, one table per table (a column per metric), notes.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace vi_ekf_slam::eval {

inline constexpr const char* kReportSchema = "vi_ekf_slam.report/1";

struct ReportColumn {
  std::string key;  ///< the row's key, or a JSON pointer into the row ("/references/0/...")
  std::string header;
  int digits = 3;  ///< decimals of a number
};

struct ReportTable {
  std::string heading;                                             ///< Markdown heading ("": none)
  std::vector<ReportColumn> columns;                               ///< empty: every key of the rows, in their order
  nlohmann::ordered_json rows = nlohmann::ordered_json::object();  ///< name -> {key: value}
};

struct Report {
  std::string tool, title;
  nlohmann::ordered_json config = nlohmann::ordered_json::object();
  ReportTable runs;
  std::vector<std::pair<std::string, ReportTable>> tables;  ///< more tables, by name
  std::vector<std::string> notes;                           ///< Markdown paragraphs at the end
};

nlohmann::ordered_json reportJson(const Report& r);
std::string reportMarkdown(const Report& r);
/// dir/stem.json and dir/stem.md (dir created).
void writeReport(const std::string& dir, const std::string& stem, const Report& r);

}  // namespace vi_ekf_slam::eval
