// A log line never runs into the progress line: the line is cleared before rosconsole prints.
#include <gtest/gtest.h>

#include <cstdio>
#include <ros/console.h>
#include <string>

#include "vi_ekf_slam/ros/console_progress.h"

namespace vi_ekf_slam::glue {
namespace {

std::string contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  for (int c; (c = std::fgetc(f)) != EOF;) s += static_cast<char>(c);
  return s;
}

TEST(ConsoleBesideProgress, ALogLineFirstClearsTheProgressLineWhichIsDrawnAgainAfterIt) {
  std::FILE* line = std::tmpfile();
  ASSERT_NE(line, nullptr);
  {
    eval::Progress progress("run", 10.0, line, true);
    ConsoleBesideProgress console;
    console.follow(&progress);
    progress.update(2.0);
    EXPECT_EQ(contents(line).rfind("\r\033[Krun:  20% of 10.0 s", 0), 0u) << contents(line);
    ROS_WARN("vi_ekf_slam: a log line");
    // Cleared: the log line starts on an empty line.
    const std::string after_log = contents(line);
    EXPECT_EQ(after_log.substr(after_log.size() - 4), "\r\033[K") << after_log;
    std::fseek(line, 0, SEEK_END);
    progress.update(3.0);  // at once, not 250 ms later: the line was taken
    EXPECT_NE(contents(line).find("30% of 10.0 s"), std::string::npos) << contents(line);
    console.follow(nullptr);
    std::fseek(line, 0, SEEK_END);
    const size_t before = contents(line).size();
    ROS_WARN("vi_ekf_slam: a log line without a progress line");
    EXPECT_EQ(contents(line).size(), before) << "nothing followed, nothing cleared";
    std::fseek(line, 0, SEEK_END);
  }  // (the progress line clears itself here: the file must still be open)
  std::fclose(line);
}

}  // namespace
}  // namespace vi_ekf_slam::glue
