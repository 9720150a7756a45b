#include "vi_ekf_slam/ros/output_frames.h"

#include <cmath>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>

#include "vi_ekf_slam/core/so3.h"

namespace vi_ekf_slam::glue {
namespace {

using Mat3 = Eigen::Matrix3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec3 = Eigen::Vector3d;

Mat6 toMat6(const boost::array<double, 36>& c) {
  Mat6 M;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) M(i, j) = c[static_cast<size_t>(6 * i + j)];
  }
  return M;
}

void fromMat6(const Mat6& M, boost::array<double, 36>* c) {
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) (*c)[static_cast<size_t>(6 * i + j)] = M(i, j);
  }
}

Mat6 blockDiag(const Mat3& A, const Mat3& B) {
  Mat6 G = Mat6::Zero();
  G.topLeftCorner<3, 3>() = A;
  G.bottomRightCorner<3, 3>() = B;
  return G;
}

Eigen::Isometry3d poseOf(const nav_msgs::Odometry& o) {
  Eigen::Isometry3d T;
  tf2::fromMsg(o.pose.pose, T);
  return T;
}

}  // namespace

std::optional<TfMode> tfModeFromString(const std::string& s) {
  if (s == "none") return TfMode::kNone;
  if (s == "odom") return TfMode::kOdom;
  if (s == "world") return TfMode::kWorld;
  return std::nullopt;
}

std::string toString(TfMode m) {
  switch (m) {
    case TfMode::kNone:
      return "none";
    case TfMode::kOdom:
      return "odom";
    case TfMode::kWorld:
      return "world";
  }
  return "?";
}

nav_msgs::Odometry attachedFrameOdometry(const nav_msgs::Odometry& imu, const Eigen::Isometry3d& T_b_i,
                                         const std::string& base_frame) {
  nav_msgs::Odometry o = imu;
  o.child_frame_id = base_frame;
  const Eigen::Isometry3d T_w_i = poseOf(imu);
  const Eigen::Isometry3d T_i_b = T_b_i.inverse();
  o.pose.pose = tf2::toMsg(Eigen::Isometry3d(T_w_i * T_i_b));
  // A global rotation dtheta of the IMU moves the base origin by dtheta x r, r = R_w_i p_i_b.
  const Vec3 r = T_w_i.linear() * T_i_b.translation();
  Mat6 J = Mat6::Identity();
  J.topRightCorner<3, 3>() = -skew(r);
  fromMat6(J * toMat6(imu.pose.covariance) * J.transpose(), &o.pose.covariance);
  // The base origin moves with v_i + w_i x p_i_b (IMU frame), then rotated into the base frame.
  const Mat3 R_b_i = T_b_i.linear();
  const Vec3 p_i_b = T_i_b.translation();
  Vec3 v_i, w_i;
  tf2::fromMsg(imu.twist.twist.linear, v_i);
  tf2::fromMsg(imu.twist.twist.angular, w_i);
  tf2::toMsg(Vec3(R_b_i * (v_i + w_i.cross(p_i_b))), o.twist.twist.linear);
  tf2::toMsg(Vec3(R_b_i * w_i), o.twist.twist.angular);
  Mat6 Jt = blockDiag(R_b_i, R_b_i);
  Jt.topRightCorner<3, 3>() = -R_b_i * skew(p_i_b);
  fromMat6(Jt * toMat6(imu.twist.covariance) * Jt.transpose(), &o.twist.covariance);
  return o;
}

nav_msgs::Odometry reexpressed(const nav_msgs::Odometry& odom, const Eigen::Isometry3d& T_o_w,
                               const std::string& frame) {
  nav_msgs::Odometry o = odom;
  o.header.frame_id = frame;
  o.pose.pose = tf2::toMsg(Eigen::Isometry3d(T_o_w * poseOf(odom)));
  const Mat6 G = blockDiag(T_o_w.linear(), T_o_w.linear());
  fromMat6(G * toMat6(odom.pose.covariance) * G.transpose(), &o.pose.covariance);
  return o;
}

Eigen::Isometry3d gravityAlignedOffset(const Eigen::Isometry3d& T_o_b, const Eigen::Isometry3d& T_w_b) {
  const double yaw = yawBetween(Quat(T_w_b.linear()), Quat(T_o_b.linear()));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
  T.translation() = T_o_b.translation() - T.linear() * T_w_b.translation();
  return T;
}

OutputFrames::OutputFrames(TfMode mode, std::string world_frame, std::string odom_frame, std::string base_frame)
    : mode_(mode),
      world_frame_(std::move(world_frame)),
      odom_frame_(std::move(odom_frame)),
      base_frame_(std::move(base_frame)) {}

std::string OutputFrames::prepare(const std::string& imu_frame, const tf2::BufferCore* tf) {
  if (mode_ == TfMode::kWorld) return "";
  if (T_b_i_ && imu_frame_ == imu_frame) return "";
  if (base_frame_.empty() || base_frame_ == imu_frame) {
    T_b_i_ = Eigen::Isometry3d::Identity();
  } else if (!tf) {
    return "no TF to look up " + base_frame_ + " <- " + imu_frame + " (base_frame differs from the IMU frame)";
  } else {
    try {
      T_b_i_ = tf2::transformToEigen(tf->lookupTransform(base_frame_, imu_frame, ros::Time(0)));
    } catch (const tf2::TransformException& e) {
      return "waiting for TF " + base_frame_ + " <- " + imu_frame + " (base_frame): " + e.what();
    }
  }
  imu_frame_ = imu_frame;
  return "";
}

nav_msgs::Odometry OutputFrames::odometry(const nav_msgs::Odometry& imu_in_world) {
  if (mode_ == TfMode::kWorld) return imu_in_world;
  const nav_msgs::Odometry base =
      attachedFrameOdometry(imu_in_world, T_b_i_.value_or(Eigen::Isometry3d::Identity()), movedFrame(imu_frame_));
  if (!T_o_w_) {
    T_o_w_ = last_T_o_b_ ? gravityAlignedOffset(*last_T_o_b_, poseOf(base)) : Eigen::Isometry3d::Identity();
  }
  if (world_is_map_) T_o_m_ = *T_o_w_;
  nav_msgs::Odometry o = reexpressed(base, *T_o_w_, odom_frame_);
  last_T_o_b_ = poseOf(o);
  return o;
}

void OutputFrames::relocalized(const Eigen::Isometry3d& T_m_n, bool keep_odom) {
  if (mode_ == TfMode::kWorld) return;
  if (keep_odom) {
    // Unset (no pose since the restart): the next pose continues the last one, as after any restart.
    if (T_o_w_) T_o_w_ = *T_o_w_ * T_m_n.inverse();
  } else {
    T_o_w_ = T_o_m_;
  }
  world_is_map_ = true;  // from the next pose on, the map's frame in odom is the world's
}

}  // namespace vi_ekf_slam::glue
