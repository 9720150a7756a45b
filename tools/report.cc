// The scripts' reports through the one implementation of the schema (eval/report.h): a report
// object and how to show it, as JSON on standard input, written as OUT/STEM.json and OUT/STEM.md,
// the Markdown printed. tools/report.py builds the object and calls this.
//
//   {"out": DIR, "stem": NAME,
//    "report": {"tool": ..., "title": ..., "config": {...}, "runs": {...}, "tables": {name: {...}}},
//    "columns": COLUMNS, "table_columns": {table: COLUMNS}, "headings": {table: "..."}, "notes": ["..."]}
//   COLUMNS: null (every key of the rows) or a list of metric keys (their one header and precision,
//   eval/report_columns.h) and [key, header, digits] for a column of the script's own.
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "vi_ekf_slam/eval/report.h"
#include "vi_ekf_slam/eval/report_columns.h"

using namespace vi_ekf_slam;
using nlohmann::ordered_json;

namespace {

std::vector<eval::ReportColumn> columnsOf(const ordered_json& spec) {
  std::vector<eval::ReportColumn> out;
  if (spec.is_null()) return out;
  for (const ordered_json& c : spec) {
    if (c.is_string()) {
      out.push_back(eval::metricColumn(c.get<std::string>()));
    } else {
      out.push_back({c.at(0).get<std::string>(), c.at(1).get<std::string>(), c.at(2).get<int>()});
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string usage = "vi_ekf_slam_report < SPEC.json";
  cli::parse(argc, argv, usage, "Writes a script's report (JSON and Markdown) from a specification on standard input.",
             cli::po::options_description("options"));
  try {
    const ordered_json spec = ordered_json::parse(std::cin);
    const ordered_json& r = spec.at("report");
    eval::Report report;
    report.tool = r.value("tool", std::string());
    report.title = r.value("title", std::string());
    report.config = r.value("config", ordered_json::object());
    report.runs.rows = r.value("runs", ordered_json::object());
    report.runs.columns = columnsOf(spec.value("columns", ordered_json()));
    const ordered_json table_columns = spec.value("table_columns", ordered_json::object());
    const ordered_json headings = spec.value("headings", ordered_json::object());
    const ordered_json tables = r.value("tables", ordered_json::object());
    for (const auto& t : tables.items()) {
      eval::ReportTable table;
      table.rows = t.value();
      table.columns = columnsOf(table_columns.value(t.key(), ordered_json()));
      table.heading = headings.value(t.key(), std::string());
      report.tables.emplace_back(t.key(), table);
    }
    const ordered_json notes = spec.value("notes", ordered_json::array());
    for (const auto& n : notes) report.notes.push_back(n.get<std::string>());
    eval::writeReport(spec.at("out").get<std::string>(), spec.at("stem").get<std::string>(), report);
    std::cout << eval::reportMarkdown(report);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
