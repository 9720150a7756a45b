// The processor's frames come from the messages: the IMU frame is the frame_id of sensor_msgs/Imu
// (a driver publishing `imu0` with the extrinsic on /tf_static gets its camera-IMU transform
// without setting a parameter), unless ~body_frame overrides it; the camera frame is the image's.
#include <gtest/gtest.h>
#include <tf2/buffer_core.h>

#include "vi_ekf_slam/core/camera_model.h"
#include "vi_ekf_slam/ros/conversions.h"
#include "vi_ekf_slam/ros/ekf_slam_processor.h"

namespace vi_ekf_slam::glue {
namespace {

class NullSink : public OutputSink {
 public:
  void odometry(const nav_msgs::Odometry&) override {}
  bool wantsLandmarks() const override { return false; }
  void landmarks(const std::vector<LandmarkOutput>&, const ros::Time&) override {}
  void status(const vi_ekf_slam::FilterStatus&) override {}
  void event(const std::string&, double) override {}
};

sensor_msgs::Imu imuMsg(double t, const std::string& frame) {
  sensor_msgs::Imu m;
  m.header.stamp = ros::Time(t);
  m.header.frame_id = frame;
  m.linear_acceleration.z = 9.81;
  m.orientation_covariance[0] = -1.0;
  return m;
}

sensor_msgs::Image imageMsg(double t, const std::string& frame) {
  sensor_msgs::Image m;
  m.header.stamp = ros::Time(t);
  m.header.frame_id = frame;
  m.width = 64;
  m.height = 48;
  m.encoding = "mono8";
  m.step = 64;
  m.data.assign(64 * 48, 128);
  return m;
}

/// A driver's frames, imu0 -> cam0 on TF; `body_frame` the node's parameter.
struct Rig {
  tf2::BufferCore tf;
  NullSink sink;
  std::unique_ptr<EkfSlamProcessor> processor;
  explicit Rig(const std::string& body_frame) {
    ros::Time::init();
    geometry_msgs::TransformStamped T;
    T.header.frame_id = "imu0";
    T.child_frame_id = "cam0";
    T.transform.rotation.w = 1.0;
    tf.setTransform(T, "test", true);
    NodeParams params;
    params.node.tune_allocator = false;
    params.node.body_frame = body_frame;
    processor = std::make_unique<EkfSlamProcessor>(params, sink, &tf);
    std_msgs::Header h;
    h.frame_id = "cam0";
    processor->cameraInfo(toCameraInfo(pinholeIntrinsics(64, 48, 50.0), h));  // images built by hand
  }
};

}  // namespace

TEST(ProcessorFrames, TheImuFrameIsTheImuMessagesFrameId) {
  Rig rig("");
  // No IMU message yet: nothing to look the camera up against, and it says so.
  rig.processor->image(imageMsg(0.5, "cam0"));
  EXPECT_NE(rig.processor->lastProblem().find("waiting for IMU messages"), std::string::npos)
      << rig.processor->lastProblem();
  for (int k = 0; k < 100; ++k) rig.processor->imu(imuMsg(0.6 + 0.005 * k, "imu0"));
  EXPECT_EQ(rig.processor->bodyFrame(), "imu0");
  rig.processor->image(imageMsg(1.0, "cam0"));
  EXPECT_EQ(rig.processor->lastProblem().find("waiting for TF"), std::string::npos) << rig.processor->lastProblem();
  EXPECT_EQ(rig.processor->lastProblem().find("waiting for IMU messages"), std::string::npos);
}

TEST(ProcessorFrames, TheBodyFrameParameterOverridesTheMessages) {
  Rig rig("base_imu");
  EXPECT_EQ(rig.processor->bodyFrame(), "base_imu");
  for (int k = 0; k < 100; ++k) rig.processor->imu(imuMsg(0.6 + 0.005 * k, "imu0"));
  EXPECT_EQ(rig.processor->bodyFrame(), "base_imu");
  rig.processor->image(imageMsg(1.0, "cam0"));  // TF has no base_imu <- cam0
  EXPECT_NE(rig.processor->lastProblem().find("waiting for TF base_imu <- cam0"), std::string::npos)
      << rig.processor->lastProblem();
}

TEST(ProcessorFrames, ImuMessagesWithoutAFrameIdAreInTheImuFrame) {
  Rig rig("");
  rig.processor->imu(imuMsg(0.6, ""));
  EXPECT_EQ(rig.processor->bodyFrame(), "imu");
}

}  // namespace vi_ekf_slam::glue
