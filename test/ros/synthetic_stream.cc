// Test fixture: publishes a simulated pedestrian rig in real time, like its drivers would:
// /imu (sensor_msgs/Imu, 200 Hz, frame ~imu_frame, default imu), /camera/image_raw (rendered
// hallway, 28 Hz, frame ~camera_frame, default camera), /camera/camera_info, /tf_static (imu <-
// camera) and /ground_truth/pose (the IMU in the z-up world). ~fault injects one kind of bad input:
//   none | nan_imu | imu_repeat | image_repeat | time_jump | imu_gap | image_before_imu |
//   encoding_cycle | encoding:<enc> | camera_info_missing | camera_info_zero |
//   compressed (PNG on /camera/image_raw/compressed instead of raw images) |
//   image_dropout (no images for 2 s from t = 4 s) | camera_covered (uniform dark images for
//   5 s from t = 3 s) | outlier_burst (for 0.5 s from t = 4 s the images are those of 1.5 s
//   earlier: every track is wrong, consistently)
#include <geometry_msgs/PoseStamped.h>
#include <opencv2/imgproc.hpp>
#include <ros/ros.h>
#include <opencv2/imgcodecs.hpp>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <std_msgs/Time.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cv_bridge/cv_bridge.h>
#include <limits>

#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/sim/renderer.h"
#include "vi_ekf_slam/sim/scenarios.h"

using namespace vi_ekf_slam;

namespace {

sensor_msgs::CameraInfo cameraInfo(const CameraModel& cam, const std_msgs::Header& header, bool zero) {
  sensor_msgs::CameraInfo ci;
  ci.header = header;
  ci.width = static_cast<uint32_t>(cam.width());
  ci.height = static_cast<uint32_t>(cam.height());
  if (zero) return ci;  // all-zero K, as some drivers publish before calibration
  const auto& k = cam.intrinsics();
  ci.distortion_model = "plumb_bob";
  ci.D = k.distortion;
  ci.K = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
  ci.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  ci.P = {k.fx, 0, k.cx, 0, 0, k.fy, k.cy, 0, 0, 0, 1, 0};
  return ci;
}

sensor_msgs::ImagePtr encode(const cv::Mat& mono, const std::string& enc, const std_msgs::Header& h) {
  namespace e = sensor_msgs::image_encodings;
  cv::Mat img;
  if (enc == e::MONO8)
    img = mono;
  else if (enc == e::MONO16)
    mono.convertTo(img, CV_16U, 256.0);
  else if (enc == e::BGR8)
    cv::cvtColor(mono, img, cv::COLOR_GRAY2BGR);
  else if (enc == e::RGB8)
    cv::cvtColor(mono, img, cv::COLOR_GRAY2RGB);
  else if (enc == e::BGRA8)
    cv::cvtColor(mono, img, cv::COLOR_GRAY2BGRA);
  else
    mono.convertTo(img, CV_32F, 1.0 / 255.0);  // e.g. 32FC1: not supported by the filter
  return cv_bridge::CvImage(h, enc, img).toImageMsg();
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "synthetic_stream");
  ros::NodeHandle nh, pnh("~");
  double duration = 8.0, standing = 2.0;
  std::string fault = "none", imu_frame = "imu", camera_frame = "camera";
  int seed = 1;
  pnh.param("imu_frame", imu_frame, imu_frame);
  pnh.param("camera_frame", camera_frame, camera_frame);
  pnh.param("duration_s", duration, duration);
  pnh.param("standing_s", standing, standing);
  pnh.param("fault", fault, fault);
  pnh.param("seed", seed, seed);

  sim::HallwayParams hp;
  hp.standing_s = standing;
  hp.duration_s = duration + 1.0;
  hp.turn_time_s = 100.0;  // a straight walk
  sim::Scenario sc = sim::hallwayScenario(hp, 1.0, static_cast<std::uint64_t>(seed));
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
  sc.imu.initial_accel_bias_sigma_mps2 = 0.02;
  sc.imu.initial_gyro_bias_sigma_radps = 0.001;
  const sim::ImuSequence imu = sim::simulateImu(*sc.trajectory, sc.imu, rng);
  sim::Renderer renderer(sim::hallwayGeometry(hp), sc.camera, sc.T_b_c, sim::RenderParams());
  std::vector<double> frame_t;
  std::vector<cv::Mat> frames;
  for (double t = 0.0; t <= duration; t += 1.0 / sc.cam.rate_hz) {
    frame_t.push_back(t);
    frames.push_back(renderer.render(*sc.trajectory, t, rng));
  }
  ROS_INFO("synthetic_stream: %zu frames rendered, fault '%s'", frames.size(), fault.c_str());

  ros::Publisher imu_pub = nh.advertise<sensor_msgs::Imu>("/imu", 400);
  ros::Publisher img_pub = nh.advertise<sensor_msgs::Image>("/camera/image_raw", 10);
  ros::Publisher compressed_pub = nh.advertise<sensor_msgs::CompressedImage>("/camera/image_raw/compressed", 10);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/camera/camera_info", 10);
  ros::Publisher gt_pub = nh.advertise<geometry_msgs::PoseStamped>("/ground_truth/pose", 50);
  // Latched once the stream is over: the stamp of its last IMU sample. Checkers listen until then
  // (and until the node has caught up), not for a wall-clock window a loaded machine may cut short.
  ros::Publisher end_pub = nh.advertise<std_msgs::Time>("/stream/end", 1, true);
  tf2_ros::StaticTransformBroadcaster tf_static;
  geometry_msgs::TransformStamped T;
  T.header.stamp = ros::Time::now();
  T.header.frame_id = imu_frame;
  T.child_frame_id = camera_frame;
  tf2::toMsg(sc.T_b_c.p_b_c, T.transform.translation);
  T.transform.rotation = tf2::toMsg(Quat(sc.T_b_c.R_b_c));
  tf_static.sendTransform(T);
  ros::Duration(1.5).sleep();  // let the filter and the checker connect

  const ros::Time t0 = ros::Time::now();
  // Bag-restart fault: after 5 s the stream starts over from t = 0 with its original stamps.
  const double restart_at = fault == "time_jump" ? 5.0 : std::numeric_limits<double>::infinity();
  size_t k_imu = 0, k_img = 0;
  double offset = 0.0;  // wall-clock seconds already played before a restart
  const char* cycle[] = {"mono8", "mono16", "bgr8", "rgb8", "bgra8"};
  sensor_msgs::Imu last_imu;
  sensor_msgs::ImagePtr last_img;
  while (ros::ok()) {
    const double t_imu = k_imu < imu.samples.size() ? imu.samples[k_imu].timestamp : 1e9;
    const double t_img = k_img < frames.size() ? frame_t[k_img] : 1e9;
    const double t = std::min(t_imu, t_img);
    if (t > duration) break;
    if (offset == 0.0 && t >= restart_at) {
      offset = restart_at;
      k_imu = k_img = 0;
      continue;
    }
    ros::Time::sleepUntil(t0 + ros::Duration(t + offset));
    const ros::Time stamp = t0 + ros::Duration(t);
    if (t_imu <= t_img) {
      const ImuData& d = imu.samples[k_imu++];
      if (fault == "imu_gap" && t >= 4.0 && t < 4.5) continue;
      if (fault == "image_before_imu" && t < 1.5) continue;
      sensor_msgs::Imu m;
      m.header.stamp = stamp;
      m.header.frame_id = imu_frame;
      m.orientation_covariance[0] = -1;  // no orientation (REP-145)
      m.angular_velocity.x = d.wm.x();
      m.angular_velocity.y = d.wm.y();
      m.angular_velocity.z = d.wm.z();
      m.linear_acceleration.x = d.am.x();
      m.linear_acceleration.y = d.am.y();
      m.linear_acceleration.z = d.am.z();
      if (fault == "nan_imu" && t >= 3.0 && t < 3.1) m.linear_acceleration.y = std::nan("");
      if (fault == "imu_repeat" && t >= 3.0 && t < 3.2 && k_imu % 7 == 0) {
        imu_pub.publish(last_imu);  // a repeated stamp
        sensor_msgs::Imu older = last_imu;
        older.header.stamp -= ros::Duration(0.02);
        imu_pub.publish(older);  // a small step back
      }
      imu_pub.publish(m);
      last_imu = m;
    } else {
      const size_t k = k_img++;
      if (fault == "image_dropout" && t >= 4.0 && t < 6.0) continue;
      std_msgs::Header h;
      h.stamp = stamp;
      h.frame_id = camera_frame;
      std::string enc = "mono8";
      if (fault == "encoding_cycle") enc = cycle[k % 5];
      if (fault.rfind("encoding:", 0) == 0) enc = fault.substr(9);
      cv::Mat frame = frames[k];
      if (fault == "camera_covered" && t >= 3.0 && t < 8.0) frame = cv::Mat(frames[k].size(), CV_8UC1, cv::Scalar(12));
      const size_t stale = static_cast<size_t>(1.5 * sc.cam.rate_hz);
      if (fault == "outlier_burst" && t >= 4.0 && t < 4.5 && k >= stale) frame = frames[k - stale];
      sensor_msgs::ImagePtr img = encode(frame, enc, h);
      if (fault != "camera_info_missing") info_pub.publish(cameraInfo(sc.camera, h, fault == "camera_info_zero"));
      if (fault == "image_repeat" && t >= 3.0 && t < 3.5 && last_img && k % 3 == 0) img_pub.publish(last_img);
      if (fault == "compressed") {
        sensor_msgs::CompressedImage c;
        c.header = h;
        c.format = "mono8; png compressed ";
        cv::imencode(".png", frame, c.data);
        compressed_pub.publish(c);
      } else {
        img_pub.publish(img);
      }
      last_img = img;
      geometry_msgs::PoseStamped gt;
      gt.header = h;
      gt.header.frame_id = "world";
      Vec3 p_w;
      Quat q_w_b;
      const sim::TrajectorySample s = sc.trajectory->sample(t);
      navToZUpWorld(s.p_n_b, s.q_n_b, &p_w, &q_w_b);
      gt.pose.position = tf2::toMsg(p_w);
      gt.pose.orientation = tf2::toMsg(q_w_b);
      gt_pub.publish(gt);
    }
  }
  std_msgs::Time end;
  end.data = last_imu.header.stamp;
  end_pub.publish(end);
  ROS_INFO("synthetic_stream: done");
  ros::spin();  // stay up until the test ends
  return 0;
}
