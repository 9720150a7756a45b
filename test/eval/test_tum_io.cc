// Trajectory files as users have them: the suite runs on any TUM file dropped into
// DATA_DIR/trajectories, so the reader takes the common variants and names what it refuses.
#include <gtest/gtest.h>

#include "scratch_dir.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>
#include <fstream>
#include <stdexcept>
#include <string>

#include "../evo_tum_rules.h"
#include "vi_ekf_slam/io/tum_io.h"

using namespace vi_ekf_slam;

namespace {

std::string writeFile(const std::string& name, const std::string& text) {
  const std::string path = vi_ekf_slam::test::programScratch() / ("tum_io_" + name + ".txt");
  std::ofstream(path) << text;
  return path;
}

std::string errorOf(const std::string& path) {
  try {
    io::readTum(path);
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
  const auto a = io::readTum(writeFile("plain", plain));
  ASSERT_EQ(a.size(), 3u);
  const auto b = io::readTum(writeFile("comma",
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

namespace {

std::vector<io::StampedPose> someTrajectoryWithCovariances() {
  std::vector<io::StampedPose> poses;
  for (int i = 0; i < 5; ++i) {
    io::StampedPose p;
    p.t = 1650458716.848713 + 0.05 * i;
    p.p = Vec3(0.1 * i, -0.2 * i, 1e-7 * i);
    p.q = Quat(Eigen::AngleAxisd(0.3 * i, Vec3(1, 2, 3).normalized()));
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random();
    p.cov = A * A.transpose() * 1e-4 + Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
    poses.push_back(p);
  }
  return poses;
}

}  // namespace

// The trajectories we write are read by evo (and ov_eval, rpg_trajectory_evaluation): 8 columns;
// the covariances travel in their own file and come back as written.
TEST(TumIo, WrittenTrajectoriesPassEvosRulesAndTheCovariancesComeBack) {
  const std::vector<io::StampedPose> poses = someTrajectoryWithCovariances();
  const std::string tum = vi_ekf_slam::test::programScratch() / "tum_io_written.tum";
  const std::string cov = vi_ekf_slam::test::programScratch() / "tum_io_written_covariance.txt";
  io::writeTum(tum, poses, "t x y z qx qy qz qw (a header)");
  io::writePoseCovariances(cov, poses);
  EXPECT_EQ(test::evoStrictTumProblem(tum), "");
  std::vector<io::StampedPose> back = io::readTum(tum);
  ASSERT_EQ(back.size(), poses.size());
  EXPECT_EQ(io::readPoseCovariances(cov, &back), static_cast<int>(poses.size()));
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_NEAR(back[i].t, poses[i].t, 1e-9);
    EXPECT_LT((back[i].p - poses[i].p).norm(), 1e-8);
    ASSERT_TRUE(back[i].cov);
    EXPECT_LT(((*back[i].cov) - (*poses[i].cov)).norm(), 1e-9 * poses[i].cov->norm());
  }
  // The strict reader is strict: a trailing space, a 29-column line, two spaces.
  EXPECT_NE(test::evoStrictTumProblem(writeFile("trailing", "10.0 1 2 3 0 0 0 1 \n")), "");
  EXPECT_NE(test::evoStrictTumProblem(writeFile("double_space", "10.0  1 2 3 0 0 0 1\n")), "");
  std::string wide = "10.0 1 2 3 0 0 0 1";
  for (int i = 0; i < 21; ++i) wide += " 0.1";
  EXPECT_NE(test::evoStrictTumProblem(writeFile("wide", wide + "\n")), "");
  // ... and so is ours: a 29-column line is not a trajectory.
  EXPECT_NE(errorOf(writeFile("wide", wide + "\n")).find("29 columns"), std::string::npos);
}
