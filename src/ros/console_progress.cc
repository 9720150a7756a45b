#include "vi_ekf_slam/ros/console_progress.h"

#include <cstdio>
#include <iostream>
#include <ros/console.h>
#include <ros/console_backend.h>

namespace vi_ekf_slam::glue {

namespace {

using PrintFunction = void (*)(void*, ros::console::Level, const char*, const char*, const char*, int);
// rosconsole's backend prints through one function pointer (ros/console_backend.h): the hook
// wraps it. One hook at a time (the program's progress line).
PrintFunction g_backend_print = nullptr;
eval::Progress* g_progress = nullptr;

void printBesideProgress(void* logger, ros::console::Level level, const char* text, const char* file,
                         const char* function, int line) {
  if (g_progress) g_progress->finish();
  std::cout.flush();
  std::fflush(stdout);
  g_backend_print(logger, level, text, file, function, line);
  std::fflush(nullptr);
}

}  // namespace

ConsoleBesideProgress::ConsoleBesideProgress() {
  // The backend sets its print function when rosconsole initializes: initialize first.
  ros::console::initialize();
  if (!g_backend_print) {
    g_backend_print = ros::console::backend::function_print;
    ros::console::backend::function_print = &printBesideProgress;
  }
}

void ConsoleBesideProgress::follow(eval::Progress* progress) { g_progress = progress; }

ConsoleBesideProgress::~ConsoleBesideProgress() {
  g_progress = nullptr;
  if (g_backend_print) {
    ros::console::backend::function_print = g_backend_print;
    g_backend_print = nullptr;
  }
}

}  // namespace vi_ekf_slam::glue
