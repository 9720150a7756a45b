#include "synthetic_rig.h"

#include <cv_bridge/cv_bridge.h>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>

#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/ros/bag_faults.h"
#include "vi_ekf_slam/sim/renderer.h"
#include "vi_ekf_slam/sim/scenarios.h"

namespace vi_ekf_slam::test {
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

sensor_msgs::Image encode(const cv::Mat& mono, const std::string& enc, const std_msgs::Header& h) {
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
  return *cv_bridge::CvImage(h, enc, img).toImageMsg();
}

ros::Time stampOf(double t0, double t) {
  ros::Time s;
  s.fromSec(t0 + t);
  return s;
}

}  // namespace

RigStream makeRigStream(const RigOptions& o, double t0) {
  sim::HallwayParams hp;
  hp.standing_s = o.standing_s;
  hp.duration_s = o.duration_s + 1.0;
  hp.turn_time_s = 100.0;  // a straight walk
  sim::Scenario sc = sim::hallwayScenario(hp, 1.0, static_cast<std::uint64_t>(o.seed));
  std::mt19937_64 rng(static_cast<std::uint64_t>(o.seed));
  sc.imu.initial_accel_bias_sigma_mps2 = 0.02;
  sc.imu.initial_gyro_bias_sigma_radps = 0.001;
  if (o.camera) sc.camera = CameraModel(*o.camera);
  if (o.T_b_c) sc.T_b_c = *o.T_b_c;
  const sim::ImuSequence imu = sim::simulateImu(*sc.trajectory, sc.imu, rng);
  sim::Renderer renderer(sim::hallwayGeometry(hp), sc.camera, sc.T_b_c, sim::RenderParams());
  std::vector<double> frame_t;
  std::vector<cv::Mat> frames;
  for (double t = 0.0; t <= o.duration_s; t += 1.0 / sc.cam.rate_hz) {
    frame_t.push_back(t);
    frames.push_back(renderer.render(*sc.trajectory, t, rng));
  }

  RigStream out;
  out.imu_camera.header.frame_id = o.imu_frame;
  out.imu_camera.child_frame_id = o.camera_frame;
  tf2::toMsg(sc.T_b_c.p_b_c, out.imu_camera.transform.translation);
  out.imu_camera.transform.rotation = tf2::toMsg(Quat(sc.T_b_c.R_b_c));

  const std::string& fault = o.fault;
  // Bag-restart fault: after 5 s the stream starts over from t = 0 with its original stamps.
  const double restart_at = fault == "time_jump" ? 5.0 : std::numeric_limits<double>::infinity();
  size_t k_imu = 0, k_img = 0;
  double offset = 0.0;  // seconds already played before a restart
  const char* cycle[] = {"mono8", "mono16", "bgr8", "rgb8", "bgra8"};
  sensor_msgs::Imu last_imu;
  std::optional<sensor_msgs::Image> last_img;
  auto add = [&](double t, auto msg) { out.messages.push_back({t + offset, std::move(msg)}); };
  while (true) {
    const double t_imu = k_imu < imu.samples.size() ? imu.samples[k_imu].timestamp : 1e9;
    const double t_img = k_img < frames.size() ? frame_t[k_img] : 1e9;
    const double t = std::min(t_imu, t_img);
    if (t > o.duration_s) break;
    if (offset == 0.0 && t >= restart_at) {
      offset = restart_at;
      k_imu = k_img = 0;
      continue;
    }
    const ros::Time stamp = stampOf(t0, t);
    if (t_imu <= t_img) {
      const ImuData& d = imu.samples[k_imu++];
      if (fault == "imu_gap" && t >= 4.0 && t < 4.5) continue;
      if (fault == "image_before_imu" && t < 1.5) continue;
      sensor_msgs::Imu m;
      m.header.stamp = stamp;
      m.header.frame_id = o.imu_frame;
      m.orientation_covariance[0] = -1;  // no orientation (REP-145)
      tf2::toMsg(d.wm, m.angular_velocity);
      tf2::toMsg(d.am, m.linear_acceleration);
      if (fault == "nan_imu" && t >= 3.0 && t < 3.1) m.linear_acceleration.y = std::nan("");
      if (fault == "imu_repeat" && t >= 3.0 && t < 3.2 && k_imu % 7 == 0) {
        add(t, last_imu);  // a repeated stamp
        sensor_msgs::Imu older = last_imu;
        older.header.stamp -= ros::Duration(0.02);
        add(t, older);  // a small step back
      }
      add(t, m);
      last_imu = m;
    } else {
      const size_t k = k_img++;
      if (fault == "image_dropout" && t >= 4.0 && t < 6.0) continue;
      std_msgs::Header h;
      h.stamp = stamp;
      h.frame_id = o.camera_frame;
      std::string enc = "mono8";
      if (fault == "encoding_cycle") enc = cycle[k % 5];
      if (fault.rfind("encoding:", 0) == 0) enc = fault.substr(9);
      cv::Mat frame = frames[k];
      if (fault == "camera_covered" && t >= 3.0 && t < 8.0) frame = cv::Mat(frames[k].size(), CV_8UC1, cv::Scalar(12));
      if (fault == "camera_dark" && t >= 3.0 && t < 8.0) {
        // A twentieth of the light at a high gain: the sensor's noise (8 grey levels) over a faint scene.
        cv::RNG rng(static_cast<std::uint64_t>(k) + 1);
        frame = glue::dimmed(frames[k], 0.05, 8.0, rng);
      }
      const size_t stale = static_cast<size_t>(1.5 * sc.cam.rate_hz);
      if (fault == "outlier_burst" && t >= 4.0 && t < 4.5 && k >= stale) frame = frames[k - stale];
      const sensor_msgs::Image img = encode(frame, enc, h);
      if (fault != "camera_info_missing") add(t, cameraInfo(sc.camera, h, fault == "camera_info_zero"));
      if (fault == "image_repeat" && t >= 3.0 && t < 3.5 && last_img && k % 3 == 0) add(t, *last_img);
      if (fault == "compressed") {
        sensor_msgs::CompressedImage c;
        c.header = h;
        c.format = "mono8; png compressed ";
        cv::imencode(".png", frame, c.data);
        add(t, c);
      } else {
        add(t, img);
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
      add(t, gt);
    }
  }
  return out;
}

}  // namespace vi_ekf_slam::test
