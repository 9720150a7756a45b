// Progress of long offline work: what the line says, and silence when nobody watches.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "vi_ekf_slam/eval/progress.h"

using namespace vi_ekf_slam;

TEST(Progress, SaysPercentRealTimeFactorAndTimeLeft) {
  // 13 s of a 52 s bag in 2.5 s: 25%, 5.2x real time, 39 s of data left at that rate: 7.5 s.
  EXPECT_EQ(eval::progressText(13.0, 52.0, 2.5), " 25% of 52.0 s, 5.2x real time, 8 s left");
  EXPECT_EQ(eval::progressText(0.0, 52.0, 0.0), "  0% of 52.0 s");
  EXPECT_EQ(eval::progressText(60.0, 52.0, 10.0), "100% of 52.0 s, 6.0x real time, 0 s left");
}

TEST(Progress, WritesOnlyWhenEnabledAndClearsItsLine) {
  std::FILE* quiet = std::tmpfile();
  {
    eval::Progress p("run", 10.0, quiet);  // a file is not a terminal
    EXPECT_FALSE(p.enabled());
    p.update(5.0);
  }
  EXPECT_EQ(std::ftell(quiet), 0L);
  std::FILE* shown = std::tmpfile();
  {
    eval::Progress p("run", 10.0, shown, true);
    p.update(5.0);
    p.update(6.0);  // within 250 ms of the first: not written again
  }
  std::rewind(shown);
  char buf[256] = {};
  const size_t n = std::fread(buf, 1, sizeof(buf) - 1, shown);
  const std::string text(buf, n);
  EXPECT_NE(text.find("run:  50% of 10.0 s"), std::string::npos) << text;
  EXPECT_EQ(text.find("60%"), std::string::npos) << text;
  EXPECT_EQ(text.substr(text.size() - 4), "\r\033[K");  // the line is cleared at the end
  std::fclose(quiet);
  std::fclose(shown);
}
