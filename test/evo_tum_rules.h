// evo's reading rules for a TUM trajectory, for tests of the files we write.
#pragma once

#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

namespace vi_ekf_slam::test {

/// evo's rules for a TUM file (file_interface.read_tum_trajectory_file): '#' lines are comments;
/// every other line is exactly 8 numbers separated by single spaces (csv with delimiter " ", so
/// two spaces or a trailing space make an empty field), finite; stamps increasing; unit
/// quaternions. Returns "" or the first broken rule.
inline std::string evoStrictTumProblem(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  double last_t = -std::numeric_limits<double>::infinity();
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line[0] == '#') continue;
    std::vector<std::string> fields;
    size_t start = 0;
    while (true) {
      const size_t sp = line.find(' ', start);
      fields.push_back(line.substr(start, sp == std::string::npos ? std::string::npos : sp - start));
      if (sp == std::string::npos) break;
      start = sp + 1;
    }
    if (fields.size() != 8) return "line " + std::to_string(n) + ": " + std::to_string(fields.size()) + " fields";
    std::vector<double> v;
    for (const std::string& f : fields) {
      size_t used = 0;
      try {
        v.push_back(std::stod(f, &used));
      } catch (const std::exception&) {
        return "line " + std::to_string(n) + ": '" + f + "' is not a number";
      }
      if (used != f.size() || !std::isfinite(v.back())) return "line " + std::to_string(n) + ": '" + f + "'";
    }
    if (!(v[0] > last_t)) return "line " + std::to_string(n) + ": stamps do not increase";
    last_t = v[0];
    const double qn = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
    if (std::abs(qn - 1.0) > 1e-6) return "line " + std::to_string(n) + ": quaternion norm " + std::to_string(qn);
  }
  return n > 0 ? "" : "empty";
}

}  // namespace vi_ekf_slam::test
