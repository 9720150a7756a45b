// The rig bag writer (make_bag, asl_to_bag) against what the readers need: the camera-IMU
// extrinsic on a latched /tf_static, the calibration on camera_info, read back unchanged.
#include <gtest/gtest.h>
#include <rosbag/view.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "../scratch_dir.h"
#include "vi_ekf_slam/ros/bag_io.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam::glue {
namespace {

/// The simulator's camera, with fy made different from fx so that a swap would show.
CameraIntrinsics testIntrinsics() {
  CameraIntrinsics in = sim::paperCamera().intrinsics();
  in.fy = in.fx + 1.0;
  return in;
}

TEST(RigBagWriter, StaticTransformIsLatchedAndReadsBack) {
  const vi_ekf_slam::test::ScratchDir dir("vi_ekf_slam_bag_io");
  const std::string path = dir / "rig.bag";
  const CameraIntrinsics in = testIntrinsics();
  CameraExtrinsics T_b_c;
  T_b_c.R_b_c = Eigen::AngleAxisd(0.3, Vec3(0.2, -1.0, 0.5).normalized()).toRotationMatrix();
  T_b_c.p_b_c = Vec3(0.05, -0.02, 0.11);
  {
    RigBagWriter writer(path, RigTopics(), CameraModel(in), T_b_c, ImuNoiseParams(), 200.0, ros::Time(100.0));
    ImuData d;
    d.timestamp = 100.0;
    d.wm = Vec3(0.01, 0.02, 0.03);
    d.am = Vec3(0.0, 0.0, 9.81);
    writer.imu(d);
    writer.image(100.01, cv::Mat(in.height, in.width, CV_8UC1, cv::Scalar(128)));
  }

  // rosbag play latches a topic only if its recorded connection says so; /tf_static is
  // published once, so without it a late subscriber never gets the extrinsic.
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery("/tf_static"));
  int messages = 0;
  for (const rosbag::MessageInstance& m : view) {
    ++messages;
    ASSERT_NE(m.getConnectionHeader(), nullptr);
    const auto latching = m.getConnectionHeader()->find("latching");
    ASSERT_NE(latching, m.getConnectionHeader()->end()) << "/tf_static has no latching field";
    EXPECT_EQ(latching->second, "1");
    auto tf = m.instantiate<tf2_msgs::TFMessage>();
    ASSERT_TRUE(tf);
    ASSERT_EQ(tf->transforms.size(), 1u);
    EXPECT_EQ(tf->transforms[0].header.frame_id, "imu");
    EXPECT_EQ(tf->transforms[0].child_frame_id, "camera");
  }
  EXPECT_EQ(messages, 1);
  bag.close();

  const InputBagInfo info = readInputBag(path);
  ASSERT_TRUE(info.T_b_c.has_value());
  EXPECT_LT((info.T_b_c->R_b_c - T_b_c.R_b_c).norm(), 1e-9);
  EXPECT_LT((info.T_b_c->p_b_c - T_b_c.p_b_c).norm(), 1e-12);
  ASSERT_TRUE(info.camera.has_value());
  EXPECT_EQ(info.camera->width, in.width);
  EXPECT_EQ(info.camera->height, in.height);
  EXPECT_DOUBLE_EQ(info.camera->fx, in.fx);
  EXPECT_DOUBLE_EQ(info.camera->fy, in.fy);
  EXPECT_DOUBLE_EQ(info.camera->cx, in.cx);
  EXPECT_DOUBLE_EQ(info.camera->cy, in.cy);
  EXPECT_EQ(info.camera->distortion, in.distortion);
  EXPECT_DOUBLE_EQ(info.start, 100.0);
}

}  // namespace
}  // namespace vi_ekf_slam::glue
