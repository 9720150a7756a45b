#include "vi_ekf_slam/io/tum_io.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace vi_ekf_slam::io {

std::vector<StampedPose> readTum(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open trajectory file '" + path + "'");
  std::vector<StampedPose> out;
  std::string line;
  int line_no = 0;
  auto fail = [&](const std::string& why) {
    throw std::runtime_error(path + ":" + std::to_string(line_no) + ": " + why + " (expected `t x y z qx qy qz qw`)");
  };
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');  // comma-separated exports read the same
    std::istringstream ss(line);
    std::vector<double> v;
    std::string tok;
    while (ss >> tok) {
      try {
        size_t used = 0;
        v.push_back(std::stod(tok, &used));
        if (used != tok.size()) fail("'" + tok + "' is not a number");
      } catch (const std::logic_error&) {
        fail("'" + tok + "' is not a number");
      }
    }
    if (v.size() != 8) fail(std::to_string(v.size()) + " columns");
    for (double x : v) {
      if (!std::isfinite(x)) fail("non-finite value");
    }
    // Unix time in seconds is about 1.7e9; in nanoseconds (EuRoC's CSV files) about 1.7e18.
    if (std::abs(v[0]) > 1e12) fail("the time looks like nanoseconds; TUM files give seconds");
    StampedPose p;
    p.t = v[0];
    p.p = Vec3(v[1], v[2], v[3]);
    p.q = Quat(v[7], v[4], v[5], v[6]);
    if (p.q.norm() < 1e-6) fail("zero quaternion");
    p.q.normalize();
    if (!out.empty() && p.t == out.back().t) {
      // Some exporters write a pose twice; the same pose again carries nothing, another pose at
      // the same time is a contradiction.
      if ((p.p - out.back().p).norm() < 1e-9 && std::abs(p.q.dot(out.back().q)) > 1.0 - 1e-12) continue;
      fail("another pose at the time of the line before");
    }
    if (!out.empty() && p.t < out.back().t) fail("time does not increase");
    out.push_back(p);
  }
  return out;
}

void writeTum(const std::string& path, const std::vector<StampedPose>& poses, const std::string& header) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  out << "# " << (header.empty() ? "t x y z qx qy qz qw" : header) << "\n" << std::setprecision(9) << std::fixed;
  for (const auto& p : poses) {
    out << p.t << " " << p.p.x() << " " << p.p.y() << " " << p.p.z() << " " << p.q.x() << " " << p.q.y() << " "
        << p.q.z() << " " << p.q.w() << "\n";
  }
}

void writePoseCovariances(const std::string& path, const std::vector<StampedPose>& poses) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  out << "# t, then the upper triangle of the 6x6 pose covariance row by row: [position [m], orientation [rad] "
         "(about the world axes)], 21 numbers\n";
  for (const auto& p : poses) {
    if (!p.cov) continue;
    out << std::fixed << std::setprecision(9) << p.t << std::scientific << std::setprecision(9);
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) out << " " << (*p.cov)(i, j);
    out << "\n";
  }
}

int readPoseCovariances(const std::string& path, std::vector<StampedPose>* poses) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open covariance file '" + path + "'");
  std::string line;
  int line_no = 0, matched = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    std::vector<double> v;
    double x;
    while (ss >> x) v.push_back(x);
    if (v.size() != 22 || !ss.eof()) {
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected t and 21 numbers");
    }
    Eigen::Matrix<double, 6, 6> c;
    int k = 1;
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) c(i, j) = c(j, i) = v[static_cast<size_t>(k++)];
    auto it = std::lower_bound(poses->begin(), poses->end(), v[0] - 1e-6,
                               [](const StampedPose& p, double t) { return p.t < t; });
    if (it != poses->end() && std::abs(it->t - v[0]) < 1e-6) {
      it->cov = c;
      ++matched;
    }
  }
  return matched;
}

std::optional<StampedPose> interpolatePose(const std::vector<StampedPose>& poses, double t, double max_gap_s) {
  auto it = std::lower_bound(poses.begin(), poses.end(), t, [](const StampedPose& p, double x) { return p.t < x; });
  if (it != poses.end() && it->t - t < 1e-6) return *it;
  if (it != poses.begin() && it != poses.end() && (it - 1)->t > t - 1e-6) return *(it - 1);
  if (it == poses.begin() || it == poses.end() || it->t - (it - 1)->t > max_gap_s) return std::nullopt;
  const StampedPose& a = *(it - 1);
  const StampedPose& b = *it;
  const double alpha = (t - a.t) / (b.t - a.t);
  StampedPose p;
  p.t = t;
  p.p = (1.0 - alpha) * a.p + alpha * b.p;
  p.q = a.q.slerp(alpha, b.q);
  return p;
}

}  // namespace vi_ekf_slam::io
