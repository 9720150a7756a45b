#include "vi_ekf_slam/ros/conversions.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cv_bridge/cv_bridge.h>
#include <opencv2/imgproc.hpp>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <sstream>
#include <tf2_eigen/tf2_eigen.h>

#include "vi_ekf_slam/core/frames.h"
#include "vi_ekf_slam/ros/ekf_slam_processor.h"

namespace vi_ekf_slam::glue {

namespace enc = sensor_msgs::image_encodings;

std::optional<ImuData> fromImuMsg(const sensor_msgs::Imu& m) {
  ImuData d;
  d.timestamp = m.header.stamp.toSec();
  d.wm = Eigen::Vector3d(m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z);
  d.am = Eigen::Vector3d(m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z);
  if (!isFinite(d)) return std::nullopt;
  return d;
}

sensor_msgs::CameraInfo toCameraInfo(const CameraIntrinsics& k, const std_msgs::Header& header) {
  sensor_msgs::CameraInfo ci;
  ci.header = header;
  ci.width = static_cast<uint32_t>(k.width);
  ci.height = static_cast<uint32_t>(k.height);
  ci.distortion_model = k.model == DistortionModel::kEquidistant ? "equidistant" : "plumb_bob";
  ci.D = k.distortion;
  ci.K = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
  ci.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  ci.P = {k.fx, 0, k.cx, 0, 0, k.fy, k.cy, 0, 0, 0, 1, 0};
  return ci;
}

std::string intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& m, CameraIntrinsics* out) {
  CameraIntrinsics c;
  c.width = static_cast<int>(m.width);
  c.height = static_cast<int>(m.height);
  c.fx = m.K[0];
  c.fy = m.K[4];
  c.cx = m.K[2];
  c.cy = m.K[5];
  c.distortion.assign(m.D.begin(), m.D.end());
  if (m.distortion_model == "plumb_bob" || m.distortion_model == "rational_polynomial") {
    c.model = DistortionModel::kRadTan;
    if (c.distortion.size() > 5) {
      for (size_t i = 5; i < c.distortion.size(); ++i) {
        if (c.distortion[i] != 0.0) return "rational_polynomial with non-zero k4..k6 is not supported";
      }
      c.distortion.resize(5);
    }
    bool all_zero = true;
    for (double d : c.distortion) all_zero = all_zero && d == 0.0;
    if (all_zero) {
      c.model = DistortionModel::kNone;
      c.distortion.clear();
    }
  } else if (m.distortion_model == "equidistant") {
    c.model = DistortionModel::kEquidistant;
  } else if (m.distortion_model.empty() && m.D.empty()) {
    c.model = DistortionModel::kNone;
  } else {
    return "unsupported distortion model '" + m.distortion_model + "' (plumb_bob, equidistant)";
  }
  const std::string err = c.validate();
  if (!err.empty()) return "camera_info: " + err;
  *out = c;
  return "";
}

std::string toMono8(const sensor_msgs::Image& msg, cv::Mat* out) {
  cv_bridge::CvImageConstPtr cv;
  try {
    // Share the buffer; the conversions below copy.
    cv = cv_bridge::toCvCopy(msg);
  } catch (const cv_bridge::Exception& e) {
    return std::string("cv_bridge: ") + e.what();
  }
  const std::string& e = msg.encoding;
  if (cv->image.empty()) return "empty image";
  if (e == enc::MONO8 || e == enc::TYPE_8UC1) {
    *out = cv->image;
  } else if (e == enc::MONO16 || e == enc::TYPE_16UC1) {
    cv->image.convertTo(*out, CV_8U, 1.0 / 256.0);
  } else if (e == enc::BGR8) {
    cv::cvtColor(cv->image, *out, cv::COLOR_BGR2GRAY);
  } else if (e == enc::RGB8) {
    cv::cvtColor(cv->image, *out, cv::COLOR_RGB2GRAY);
  } else if (e == enc::BGRA8) {
    cv::cvtColor(cv->image, *out, cv::COLOR_BGRA2GRAY);
  } else if (e == enc::RGBA8) {
    cv::cvtColor(cv->image, *out, cv::COLOR_RGBA2GRAY);
  } else {
    return "unsupported image encoding '" + e + "' (mono8, mono16, bgr8, rgb8, bgra8, rgba8)";
  }
  return "";
}

CameraExtrinsics extrinsicsFromTransform(const geometry_msgs::Transform& t) {
  CameraExtrinsics T;
  Quat q;
  tf2::fromMsg(t.rotation, q);
  T.R_b_c = q.normalized().toRotationMatrix();
  tf2::fromMsg(t.translation, T.p_b_c);
  return T;
}

nav_msgs::Odometry toOdometry(const NavState& nav, const Eigen::Vector3d& w_b, double w_var, const ros::Time& stamp,
                              const std::string& world_frame, const std::string& body_frame) {
  nav_msgs::Odometry o;
  o.header.stamp = stamp;
  o.header.frame_id = world_frame;
  o.child_frame_id = body_frame;
  Vec3 p_w;
  Quat q_w_b;
  navToZUpWorld(nav.p_n_b, nav.q_n_b, &p_w, &q_w_b);
  o.pose.pose.position = tf2::toMsg(p_w);
  o.pose.pose.orientation = tf2::toMsg(q_w_b);
  // Pose covariance [position, orientation] in the world frame: both blocks rotate with R_w_n
  // (the orientation error is a global rotation vector).
  const Mat3 R_w_n = zUpWorldFromNav().toRotationMatrix();
  Eigen::Matrix<double, 6, 6> G = Eigen::Matrix<double, 6, 6>::Zero();
  G.topLeftCorner<3, 3>() = R_w_n;
  G.bottomRightCorner<3, 3>() = R_w_n;
  const Eigen::Matrix<double, 6, 6> Pw = G * nav.poseCovariance() * G.transpose();
  // Twist in the body frame: v_b = R_n_b^T v_n.
  const Mat3 R_b_n = nav.q_n_b.conjugate().toRotationMatrix();
  const Vec3 v_b = R_b_n * nav.v_n_b;
  tf2::toMsg(v_b, o.twist.twist.linear);
  tf2::toMsg(w_b, o.twist.twist.angular);
  Eigen::Matrix<double, 6, 6> Tw = Eigen::Matrix<double, 6, 6>::Zero();
  // v_b = R^T v_n -> cov R^T P_v R (+ the attitude term, small at walking speed; omitted).
  Tw.topLeftCorner<3, 3>() = R_b_n * nav.cov.block<3, 3>(idx::kV, idx::kV) * R_b_n.transpose();
  Tw.bottomRightCorner<3, 3>() = nav.cov.block<3, 3>(idx::kBg, idx::kBg) + w_var * Mat3::Identity();
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      o.pose.covariance[static_cast<size_t>(6 * i + j)] = Pw(i, j);
      o.twist.covariance[static_cast<size_t>(6 * i + j)] = Tw(i, j);
    }
  }
  return o;
}

sensor_msgs::PointCloud2 toPointCloud(const std::vector<LandmarkOutput>& lms, const ros::Time& stamp,
                                      const std::string& frame, const Eigen::Isometry3d& T_frame_world) {
  sensor_msgs::PointCloud2 c;
  c.header.stamp = stamp;
  c.header.frame_id = frame;
  c.height = 1;
  sensor_msgs::PointCloud2Modifier mod(c);
  mod.setPointCloud2Fields(8, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32, "z",
                           1, sensor_msgs::PointField::FLOAT32, "id", 1, sensor_msgs::PointField::UINT32, "sigma", 1,
                           sensor_msgs::PointField::FLOAT32, "birth_time", 1, sensor_msgs::PointField::FLOAT64,
                           "birth_u", 1, sensor_msgs::PointField::FLOAT32, "birth_v", 1,
                           sensor_msgs::PointField::FLOAT32);
  std::vector<const LandmarkOutput*> finite;
  for (const auto& l : lms) {
    if (l.landmark.p_n_l.allFinite() && l.landmark.cov.allFinite()) finite.push_back(&l);
  }
  mod.resize(finite.size());
  sensor_msgs::PointCloud2Iterator<float> x(c, "x"), y(c, "y"), z(c, "z"), sigma(c, "sigma"), u(c, "birth_u"),
      v(c, "birth_v");
  sensor_msgs::PointCloud2Iterator<uint32_t> id(c, "id");
  sensor_msgs::PointCloud2Iterator<double> bt(c, "birth_time");
  const Quat q_w_n = zUpWorldFromNav();
  for (const LandmarkOutput* lo : finite) {
    const NavLandmark& l = lo->landmark;
    const Vec3 p = T_frame_world * (q_w_n * l.p_n_l);
    *x = static_cast<float>(p.x());
    *y = static_cast<float>(p.y());
    *z = static_cast<float>(p.z());
    *id = static_cast<uint32_t>(l.id);
    const double lmax = Eigen::SelfAdjointEigenSolver<Mat3>(l.cov, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
    *sigma = static_cast<float>(std::sqrt(std::max(0.0, lmax)));
    *bt = lo->birth_time;
    *u = static_cast<float>(lo->birth_uv.x());
    *v = static_cast<float>(lo->birth_uv.y());
    ++x, ++y, ++z, ++id, ++sigma, ++bt, ++u, ++v;
  }
  return c;
}

vi_ekf_slam::FilterStatus toFilterStatus(const EkfSlam& filter, const NavState& nav, const FrameResult& r,
                                         const StatusExtras& x) {
  vi_ekf_slam::FilterStatus s;
  s.mechanization = toString(filter.mechanization());
  s.landmark_init = toString(x.landmark_init);
  s.initialized = filter.initialized();
  s.landmarks_in_state = filter.state().numLandmarks();
  s.tracks = x.tracks;
  s.new_landmarks = static_cast<int>(r.new_ids.size());
  s.deferred_features = r.deferred_features;
  s.waiting_features = r.waiting_features;
  s.removed_landmarks = static_cast<int>(r.removed_ids.size());
  s.dormant_landmarks = r.dormant_landmarks;
  s.blind_s = r.blind_s;
  s.in_map = x.in_map;
  s.map_points = x.map_points;
  s.relocalizations = x.relocalizations;
  s.revisits = static_cast<int>(r.revisits.size());
  s.refused_revisits = r.revisits_rejected;
  s.accepted_observations = r.update.accepted;
  s.rejected_observations = static_cast<int>(r.update.rejected_ids.size());
  s.gate_probability = r.gate_probability;
  s.nis_per_dof = r.update.accepted > 0 ? r.update.nis_sum / (2.0 * r.update.accepted) : 0.0;
  s.time_offset_s = nav.t_d;
  s.time_offset_sigma_s = nav.t_d_sigma;
  const CameraExtrinsics& T = filter.extrinsics();
  tf2::toMsg(T.p_b_c, s.camera_in_imu.translation);
  s.camera_in_imu.rotation = tf2::toMsg(Quat(T.R_b_c));
  if (filter.state().estimatesExtrinsic()) {
    const int e = filter.state().extrinsicIndex();
    const MotionMatrix P = filter.state().motionCovariance();
    s.extrinsic_translation_sigma_m = std::sqrt(P.block<3, 3>(e, e).diagonal().maxCoeff());
    s.extrinsic_rotation_sigma_rad = std::sqrt(P.block<3, 3>(e + 3, e + 3).diagonal().maxCoeff());
  }
  s.compositions = filter.compositions();
  s.stationary = r.zero_velocity_applied;
  s.parallax_px = r.stationary.parallax_px;
  s.zero_velocity_updates = filter.zeroVelocityUpdates();
  s.resets = static_cast<int>(x.resets);
  s.update_time_ms = x.update_ms;
  s.tracker_time_ms = x.tracker_ms;
  const Vec3 g_b = nav.q_n_b.conjugate() * gravityInNav(x.gravity_mps2);
  tf2::toMsg(g_b, s.gravity_body);
  tf2::toMsg(nav.b_a, s.accel_bias);
  tf2::toMsg(nav.b_g, s.gyro_bias);
  return s;
}

bool allFinite(const nav_msgs::Odometry& o) {
  const auto& p = o.pose.pose;
  const auto& t = o.twist.twist;
  const double v[] = {p.position.x,    p.position.y,    p.position.z, p.orientation.w, p.orientation.x,
                      p.orientation.y, p.orientation.z, t.linear.x,   t.linear.y,      t.linear.z,
                      t.angular.x,     t.angular.y,     t.angular.z};
  for (double x : v) {
    if (!std::isfinite(x)) return false;
  }
  for (double x : o.pose.covariance) {
    if (!std::isfinite(x)) return false;
  }
  for (double x : o.twist.covariance) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

}  // namespace vi_ekf_slam::glue
