#include "vi_ekf_slam/eval/progress.h"

#include <unistd.h>
#include <algorithm>
#include <cmath>

namespace vi_ekf_slam::eval {

std::string progressText(double done_s, double total_s, double wall_s) {
  const double fraction = total_s > 0.0 ? std::clamp(done_s / total_s, 0.0, 1.0) : 0.0;
  char buf[160];
  if (wall_s <= 0.0 || done_s <= 0.0) {
    std::snprintf(buf, sizeof(buf), "%3.0f%% of %.1f s", 100.0 * fraction, total_s);
  } else {
    const double rate = done_s / wall_s;  // data seconds per wall second
    const double left = std::max(0.0, total_s - done_s) / rate;
    std::snprintf(buf, sizeof(buf), "%3.0f%% of %.1f s, %.1fx real time, %.0f s left", 100.0 * fraction, total_s, rate,
                  std::ceil(left));
  }
  return buf;
}

Progress::Progress(std::string what, double total_s, std::FILE* out)
    : Progress(std::move(what), total_s, out, isatty(fileno(out)) != 0) {}

Progress::Progress(std::string what, double total_s, std::FILE* out, bool enabled)
    : what_(std::move(what)), total_s_(total_s), out_(out), enabled_(enabled) {}

void Progress::update(double done_s) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (shown_ && now - last_ < std::chrono::milliseconds(250)) return;
  last_ = now;
  shown_ = true;
  const double wall = std::chrono::duration<double>(now - start_).count();
  std::fprintf(out_, "\r\033[K%s: %s", what_.c_str(), progressText(done_s, total_s_, wall).c_str());
  std::fflush(out_);
}

void Progress::finish() {
  if (!shown_) return;
  std::fprintf(out_, "\r\033[K");
  std::fflush(out_);
  shown_ = false;
}

}  // namespace vi_ekf_slam::eval
