// The tools' one report schema (eval/report.h): the JSON carries the schema, tool, config, runs and
// more tables, non-finite numbers as null; the Markdown shows the same rows with the chosen columns,
// nested figures through a JSON pointer.
#include <gtest/gtest.h>

#include <cmath>

#include "vi_ekf_slam/eval/report.h"

namespace vi_ekf_slam::eval {
namespace {

Report sample() {
  Report r;
  r.tool = "study";
  r.title = "A study";
  r.config = {{"seed", 1}, {"trajectory", "builtin"}};
  r.runs.rows["default"] = {{"ate_m", 0.12345}, {"nees", std::nan("")}, {"refs", {{{"rmse", 0.5}}}}};
  r.runs.rows["other"] = {{"ate_m", 2.0}, {"nees", 6.5}};
  r.runs.columns = {{"ate_m", "ATE [m]", 3}, {"nees", "NEES", 2}, {"/refs/0/rmse", "ref [m]", 1}};
  ReportTable worst;
  worst.heading = "Worst";
  worst.rows["default"] = {{"count", 3}, {"inside", true}};
  r.tables.emplace_back("worst", worst);
  r.notes.push_back("A note.");
  return r;
}

TEST(Report, TheJsonCarriesTheSchemaToolConfigRunsAndTables) {
  const nlohmann::ordered_json j = reportJson(sample());
  EXPECT_EQ(j["schema"], kReportSchema);
  EXPECT_EQ(j["tool"], "study");
  EXPECT_EQ(j["config"]["seed"], 1);
  EXPECT_DOUBLE_EQ(j["runs"]["default"]["ate_m"].get<double>(), 0.12345);
  EXPECT_EQ(j["tables"]["worst"]["default"]["count"], 3);
  // Non-finite numbers become null in the text (nlohmann's rule), which every reader takes.
  EXPECT_TRUE(nlohmann::json::parse(j.dump())["runs"]["default"]["nees"].is_null());
  // Without more tables there is no "tables".
  Report plain = sample();
  plain.tables.clear();
  EXPECT_FALSE(reportJson(plain).contains("tables"));
}

TEST(Report, TheMarkdownShowsTheSameRowsWithTheChosenColumns) {
  const std::string md = reportMarkdown(sample());
  EXPECT_NE(md.find("# A study"), std::string::npos) << md;
  EXPECT_NE(md.find("Settings: seed 1, trajectory builtin."), std::string::npos) << md;
  EXPECT_NE(md.find("| | ATE [m] | NEES | ref [m] |"), std::string::npos) << md;
  EXPECT_NE(md.find("| default | 0.123 | - | 0.5 |"), std::string::npos) << md;  // NaN as "-", pointer
  EXPECT_NE(md.find("| other | 2.000 | 6.50 | - |"), std::string::npos) << md;   // no such figure: "-"
  EXPECT_NE(md.find("## Worst"), std::string::npos) << md;
  EXPECT_NE(md.find("| default | 3 | yes |"), std::string::npos) << md;  // columns from the rows
  EXPECT_NE(md.find("A note."), std::string::npos) << md;
}

}  // namespace
}  // namespace vi_ekf_slam::eval
