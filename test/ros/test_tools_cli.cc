// Every tool answers --help with its usage (exit 0) and refuses a bad value with one error line
// (exit 2), instead of starting a long run or ending in an uncaught std::stod.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace {

struct Outcome {
  int code = -1;
  std::string output;  ///< stdout and stderr
};

Outcome run(const std::string& command) {
  Outcome o;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return o;
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), p)) o.output += buf.data();
  const int status = pclose(p);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

struct Tool {
  const char* path;
  const char* bad_value;  ///< arguments with a value that is not a number
};

const Tool kTools[] = {
    {VI_TOOL_MAKE_BAG, "--out /tmp/x.bag --duration abc"},
    {VI_TOOL_ASL_TO_BAG, "--asl /tmp --out /tmp/x.bag --imu-margin 1s"},
    {VI_TOOL_SIMULATE_SHORT, "thirty"},
    {VI_TOOL_RUN_FEATURES, "--gate high"},
    {VI_TOOL_STUDY, "--runs many"},
    {VI_TOOL_SOAK, "--minutes half"},
};

}  // namespace

TEST(ToolsCli, HelpPrintsUsageAndBadNumbersAreRefused) {
  for (const Tool& t : kTools) {
    const Outcome help = run(std::string(t.path) + " --help");
    EXPECT_EQ(help.code, 0) << t.path << "\n" << help.output;
    EXPECT_NE(help.output.find("usage:"), std::string::npos) << t.path;
    const Outcome bad = run(std::string(t.path) + " " + t.bad_value);
    EXPECT_EQ(bad.code, 2) << t.path << " " << t.bad_value << "\n" << bad.output;
    EXPECT_NE(bad.output.find("error:"), std::string::npos) << t.path;
  }
  const Outcome unknown = run(std::string(VI_TOOL_SOAK) + " --minute 1");  // not taken for --minutes
  EXPECT_EQ(unknown.code, 2) << unknown.output;
}
