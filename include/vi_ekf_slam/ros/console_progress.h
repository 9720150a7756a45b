// rosconsole lines and a progress line on one terminal: while a ConsoleBesideProgress lives, every
// log line first clears the progress line (it is drawn again at its next update) and flushes
// stdout, so that a log line never runs into the progress line and, in a pipe, log lines and the
// program's own output keep their order.
#pragma once

#include "vi_ekf_slam/eval/progress.h"

namespace vi_ekf_slam::glue {

class ConsoleBesideProgress {
 public:
  ConsoleBesideProgress();
  ~ConsoleBesideProgress();
  /// The progress line to keep clear of log lines from now on (null: none, only the flushing).
  void follow(eval::Progress* progress);
  ConsoleBesideProgress(const ConsoleBesideProgress&) = delete;
  ConsoleBesideProgress& operator=(const ConsoleBesideProgress&) = delete;
};

}  // namespace vi_ekf_slam::glue
