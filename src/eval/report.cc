#include "vi_ekf_slam/eval/report.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vi_ekf_slam::eval {

namespace {

std::string cell(const nlohmann::ordered_json& v, int digits) {
  if (v.is_null()) return "-";
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number_float()) {
    const double x = v.get<double>();
    if (!std::isfinite(x)) return "-";
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.*f", digits, x);
    return buf;
  }
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

std::vector<ReportColumn> columnsOf(const ReportTable& t) {
  if (!t.columns.empty()) return t.columns;
  std::vector<ReportColumn> cols;
  for (const auto& [name, row] : t.rows.items()) {
    for (const auto& [key, value] : row.items()) {
      bool known = false;
      for (const auto& c : cols) known = known || c.key == key;
      if (!known) cols.push_back({key, key, 3});
    }
  }
  return cols;
}

void writeTable(std::ostream& md, const ReportTable& t) {
  if (!t.heading.empty()) md << "## " << t.heading << "\n\n";
  const std::vector<ReportColumn> cols = columnsOf(t);
  md << "| |";
  for (const auto& c : cols) md << " " << c.header << " |";
  md << "\n|---|";
  for (size_t i = 0; i < cols.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& [name, row] : t.rows.items()) {
    md << "| " << name << " |";
    for (const auto& c : cols) {
      // A key starting with '/' is a JSON pointer into the row (a nested figure).
      const bool pointer = !c.key.empty() && c.key[0] == '/';
      const nlohmann::ordered_json::json_pointer ptr(pointer ? c.key : "");
      const bool has = pointer ? row.contains(ptr) : row.contains(c.key);
      md << " " << (has ? cell(pointer ? row.at(ptr) : row[c.key], c.digits) : "-") << " |";
    }
    md << "\n";
  }
  md << "\n";
}

}  // namespace

nlohmann::ordered_json reportJson(const Report& r) {
  nlohmann::ordered_json js;
  js["schema"] = kReportSchema;
  js["tool"] = r.tool;
  // The commit the numbers were measured on (make exports it; "+changes": with uncommitted ones).
  if (const char* commit = std::getenv("VI_EKF_SLAM_COMMIT"); commit && *commit) js["commit"] = commit;
  js["title"] = r.title;
  js["config"] = r.config;
  js["runs"] = r.runs.rows;
  if (!r.tables.empty()) {
    js["tables"] = nlohmann::ordered_json::object();
    for (const auto& [name, t] : r.tables) js["tables"][name] = t.rows;
  }
  return js;
}

std::string reportMarkdown(const Report& r) {
  std::ostringstream md;
  md << "# " << r.title << "\n\n";
  std::string settings;
  for (const auto& [key, value] : r.config.items()) {
    settings +=
        (settings.empty() ? "" : ", ") + key + " " + (value.is_string() ? value.get<std::string>() : value.dump());
  }
  if (!settings.empty()) md << "Settings: " << settings << ".\n\n";
  writeTable(md, r.runs);
  for (const auto& [name, t] : r.tables) writeTable(md, t);
  for (const auto& n : r.notes) md << n << "\n\n";
  return md.str();
}

void writeReport(const std::string& dir, const std::string& stem, const Report& r) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/" + stem + ".json") << reportJson(r).dump(2) << "\n";
  std::ofstream(dir + "/" + stem + ".md") << reportMarkdown(r);
}

}  // namespace vi_ekf_slam::eval
