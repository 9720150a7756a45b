// Progress of long offline work on a terminal: percent, real-time factor and time left on one
// line rewritten in place, at most a few times a second. Quiet when the output is not a terminal
// (a log file, a pipe, CI), so that logs hold results only.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace vi_ekf_slam::eval {

/// "42% of 52.0 s, 5.3x real time, 6 s left" for `done_s` of `total_s` of data after `wall_s`.
std::string progressText(double done_s, double total_s, double wall_s);

class Progress {
 public:
  /// `what` starts the line; enabled when `out` is a terminal.
  Progress(std::string what, double total_s, std::FILE* out = stderr);
  Progress(std::string what, double total_s, std::FILE* out, bool enabled);
  ~Progress() { finish(); }
  /// `done_s` of the total are done (data time, not wall time).
  void update(double done_s);
  /// Clears the line (once).
  void finish();
  bool enabled() const { return enabled_; }

 private:
  std::string what_;
  double total_s_;
  std::FILE* out_;
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_ = start_;
};

}  // namespace vi_ekf_slam::eval
