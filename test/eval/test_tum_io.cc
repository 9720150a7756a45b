// Trajectory files as users have them: the suite runs on any TUM file dropped into
// DATA_DIR/trajectories, so the reader takes the common variants and names what it refuses.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

#include "vi_ekf_slam/eval/tum_io.h"

using namespace vi_ekf_slam;

namespace {

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = "/tmp/vi_ekf_slam_tum_io_" + name + ".txt";
  std::ofstream(path) << text;
  return path;
}

std::string errorOf(const std::string& path) {
  try {
    eval::readTum(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(TumIo, CommasAndARepeatedLineReadAsTheSpaceSeparatedFile) {
  const std::string plain =
      "# timestamp tx ty tz qx qy qz qw\n"
      "10.0 1 2 3 0 0 0 1\n"
      "10.1 1.1 2 3 0 0 0.0499792 0.9987503\n"
      "10.2 1.2 2 3 0 0 0.0998334 0.9950042\n";
  const auto a = eval::readTum(writeFile("plain", plain));
  ASSERT_EQ(a.size(), 3u);
  const auto b = eval::readTum(writeFile("comma",
                                         "10.0,1,2,3,0,0,0,1\n"
                                         "10.1,1.1,2,3,0,0,0.0499792,0.9987503\n"
                                         "10.1,1.1,2,3,0,0,0.0499792,0.9987503\n"  // written twice
                                         "10.2, 1.2, 2, 3, 0, 0, 0.0998334, 0.9950042\n"));
  ASSERT_EQ(b.size(), a.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t, b[i].t);
    EXPECT_EQ((a[i].p - b[i].p).norm(), 0.0);
    EXPECT_NEAR(a[i].q.angularDistance(b[i].q), 0.0, 1e-12);
  }
}

TEST(TumIo, ContradictionsAreRefusedWithTheirLine) {
  const std::string other_pose_same_time = errorOf(writeFile("same_time",
                                                             "10.0 1 2 3 0 0 0 1\n"
                                                             "10.0 1.5 2 3 0 0 0 1\n"));
  EXPECT_NE(other_pose_same_time.find(":2: another pose at the time"), std::string::npos) << other_pose_same_time;
  const std::string backwards = errorOf(writeFile("backwards",
                                                  "10.0 1 2 3 0 0 0 1\n"
                                                  "10.2 1 2 3 0 0 0 1\n"
                                                  "10.1 1 2 3 0 0 0 1\n"));
  EXPECT_NE(backwards.find(":3: time does not increase"), std::string::npos) << backwards;
  const std::string columns = errorOf(writeFile("columns", "10.0 1 2 3 0 0 1\n"));
  EXPECT_NE(columns.find(":1: 7 columns"), std::string::npos) << columns;
  const std::string nanoseconds = errorOf(writeFile("ns", "1550864017670950000 1 2 3 0 0 0 1\n"));
  EXPECT_NE(nanoseconds.find(":1: the time looks like nanoseconds"), std::string::npos) << nanoseconds;
  const std::string word = errorOf(writeFile("word", "10.0 1 2 3 0 0 zero 1\n"));
  EXPECT_NE(word.find("'zero' is not a number"), std::string::npos) << word;
}
