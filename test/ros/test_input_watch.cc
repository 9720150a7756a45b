// InputWatch names the input the node waits on, by its resolved topic, on the caller's clock.
#include <gtest/gtest.h>

#include "vi_ekf_slam/ros/input_watch.h"

namespace vi_ekf_slam::glue {
namespace {

InputWatch threeInputs(double start_s) {
  return InputWatch({{"imu", "/imu0", "remap imu:="},
                     {"image", "/vi_ekf_slam/image", "remap image:="},
                     {"camera_info", "/vi_ekf_slam/camera_info", "remap camera_info:="}},
                    5.0, start_s);
}

TEST(InputWatch, NamesTheSilentImageTopicWhileTheImuArrives) {
  InputWatch w = threeInputs(100.0);
  w.setNeeded(2, false);  // intrinsics from a file
  for (double t = 100.0; t < 104.0; t += 0.005) w.arrived(0, t);
  EXPECT_EQ(w.waitingOn(104.0), "") << "not before the silence has lasted";
  for (double t = 104.0; t < 106.0; t += 0.005) w.arrived(0, t);
  const std::string s = w.waitingOn(106.0);
  EXPECT_NE(s.find("image on /vi_ekf_slam/image"), std::string::npos) << s;
  EXPECT_NE(s.find("nothing received in 6 s"), std::string::npos) << s;
  EXPECT_NE(s.find("while imu arrives"), std::string::npos) << s;
  EXPECT_EQ(s.find("camera_info"), std::string::npos) << "not needed, not named: " << s;
}

TEST(InputWatch, NamesEveryTopicWhenNothingArrives) {
  InputWatch w = threeInputs(0.0);
  const std::string s = w.waitingOn(7.0);
  for (const char* topic : {"imu on /imu0", "image on /vi_ekf_slam/image", "camera_info on /vi_ekf_slam/camera_info"})
    EXPECT_NE(s.find(topic), std::string::npos) << s;
  EXPECT_EQ(s.find("while"), std::string::npos) << s;
}

TEST(InputWatch, AnInputThatStopsIsNamedAsSilentAndQuietOnceItIsBack) {
  InputWatch w = threeInputs(0.0);
  for (double t = 0.0; t < 20.0; t += 0.1) {
    w.arrived(0, t);
    w.arrived(2, t);
    if (t < 3.0) w.arrived(1, t);
  }
  const std::string s = w.waitingOn(20.0);
  EXPECT_NE(s.find("image on /vi_ekf_slam/image (silent for 17 s"), std::string::npos) << s;
  EXPECT_NE(s.find("while imu, camera_info arrive"), std::string::npos) << s;
  w.arrived(1, 20.0);
  EXPECT_EQ(w.waitingOn(20.1), "");
}

}  // namespace
}  // namespace vi_ekf_slam::glue
