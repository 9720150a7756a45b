// The REP-105 outputs: the odometry of a base rigidly attached to the IMU (pose, twist and both
// covariances against numerical derivatives), and odom's continuity across the filter's restarts.
#include <gtest/gtest.h>
#include <tf2_eigen/tf2_eigen.h>

#include <random>

#include "vi_ekf_slam/ros/output_frames.h"

namespace vi_ekf_slam::glue {
namespace {

using Iso = Eigen::Isometry3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;

Iso makePose(const Vec3& rotation_vector, const Vec3& p) {
  Iso T = Iso::Identity();
  if (rotation_vector.norm() > 0)
    T.linear() = Eigen::AngleAxisd(rotation_vector.norm(), rotation_vector.normalized()).toRotationMatrix();
  T.translation() = p;
  return T;
}

Iso poseOf(const nav_msgs::Odometry& o) {
  Iso T;
  tf2::fromMsg(o.pose.pose, T);
  return T;
}

Mat6 covOf(const boost::array<double, 36>& c) {
  Mat6 M;
  for (int i = 0; i < 36; ++i) M(i / 6, i % 6) = c[static_cast<size_t>(i)];
  return M;
}

Vec3 rotationVector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd a(R);
  return a.angle() * a.axis();
}

Mat6 randomCovariance(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Mat6 A;
  for (int i = 0; i < 36; ++i) A(i / 6, i % 6) = n(rng);
  return A * A.transpose() + 0.1 * Mat6::Identity();
}

nav_msgs::Odometry imuOdometry(std::mt19937_64& rng) {
  nav_msgs::Odometry o;
  o.header.frame_id = "world";
  o.child_frame_id = "imu0";
  o.pose.pose = tf2::toMsg(makePose(Vec3(0.3, -0.2, 1.1), Vec3(1.0, 2.0, 0.5)));
  tf2::toMsg(Vec3(1.2, -0.3, 0.1), o.twist.twist.linear);
  tf2::toMsg(Vec3(0.2, 0.5, -0.4), o.twist.twist.angular);
  const Mat6 P = randomCovariance(rng), Q = randomCovariance(rng);
  for (int i = 0; i < 36; ++i) {
    o.pose.covariance[static_cast<size_t>(i)] = P(i / 6, i % 6);
    o.twist.covariance[static_cast<size_t>(i)] = Q(i / 6, i % 6);
  }
  return o;
}

const Iso kBaseImu = makePose(Vec3(M_PI / 2, 0.0, 0.2), Vec3(0.2, -0.1, 0.3));  // IMU on its side

}  // namespace

TEST(OutputFrames, TheBaseCovariancesAreTheImuCovariancesThroughNumericalJacobians) {
  std::mt19937_64 rng(7);
  const nav_msgs::Odometry imu = imuOdometry(rng);
  const nav_msgs::Odometry base = attachedFrameOdometry(imu, kBaseImu, "base_link");
  EXPECT_EQ(base.child_frame_id, "base_link");
  EXPECT_EQ(base.header.frame_id, "world");
  const Iso T_w_i = poseOf(imu);
  EXPECT_TRUE(poseOf(base).isApprox(T_w_i * kBaseImu.inverse(), 1e-12));

  // Pose error [dp, dtheta (global)] of the IMU -> of the base, column by column.
  const double h = 1e-6;
  Mat6 J;
  for (int k = 0; k < 6; ++k) {
    Vec6 d = Vec6::Zero();
    d(k) = h;
    Iso T = T_w_i;
    T.translation() += d.head<3>();
    T.linear() = makePose(d.tail<3>(), Vec3::Zero()).linear() * T_w_i.linear();
    nav_msgs::Odometry moved = imu;
    moved.pose.pose = tf2::toMsg(T);
    const Iso b0 = poseOf(base), b1 = poseOf(attachedFrameOdometry(moved, kBaseImu, "base_link"));
    J.col(k) << (b1.translation() - b0.translation()) / h, rotationVector(b1.linear() * b0.linear().transpose()) / h;
  }
  const Mat6 expected = J * covOf(imu.pose.covariance) * J.transpose();
  EXPECT_LT((covOf(base.pose.covariance) - expected).norm(), 1e-5 * expected.norm());

  // Twist [v, w] of the IMU (IMU frame) -> of the base (base frame): linear, so a difference is exact.
  auto twistOf = [](const nav_msgs::Odometry& o) {
    Vec3 v, w;
    tf2::fromMsg(o.twist.twist.linear, v);
    tf2::fromMsg(o.twist.twist.angular, w);
    return (Vec6() << v, w).finished();
  };
  Mat6 Jt;
  for (int k = 0; k < 6; ++k) {
    nav_msgs::Odometry moved = imu;
    Vec6 t = twistOf(imu);
    t(k) += 1.0;
    tf2::toMsg(Vec3(t.head<3>()), moved.twist.twist.linear);
    tf2::toMsg(Vec3(t.tail<3>()), moved.twist.twist.angular);
    Jt.col(k) = twistOf(attachedFrameOdometry(moved, kBaseImu, "base_link")) - twistOf(base);
  }
  const Mat6 expected_t = Jt * covOf(imu.twist.covariance) * Jt.transpose();
  EXPECT_LT((covOf(base.twist.covariance) - expected_t).norm(), 1e-9 * expected_t.norm());
}

TEST(OutputFrames, TheBaseTwistIsTheDerivativeOfTheBasePose) {
  // The IMU turning at w (its frame) and moving at v (its frame): the base origin's velocity,
  // differentiated from its poses, expressed in the base frame.
  const Vec3 v_i(1.0, 0.2, -0.1), w_i(0.3, -0.6, 0.9);
  const Iso T0 = makePose(Vec3(0.1, 0.2, 0.3), Vec3(1, 1, 1));
  auto imuAt = [&](double t) {
    Iso T = T0;
    T.translation() += T0.linear() * v_i * t;  // first order is enough for a central difference at t=0
    T.linear() = T0.linear() * makePose(w_i * t, Vec3::Zero()).linear();
    nav_msgs::Odometry o;
    o.pose.pose = tf2::toMsg(T);
    tf2::toMsg(v_i, o.twist.twist.linear);
    tf2::toMsg(w_i, o.twist.twist.angular);
    return o;
  };
  const double h = 1e-5;
  const Iso bp = poseOf(attachedFrameOdometry(imuAt(h), kBaseImu, "b"));
  const Iso bm = poseOf(attachedFrameOdometry(imuAt(-h), kBaseImu, "b"));
  const nav_msgs::Odometry b0 = attachedFrameOdometry(imuAt(0.0), kBaseImu, "b");
  const Eigen::Matrix3d R_w_b = poseOf(b0).linear();
  const Vec3 v_numeric = R_w_b.transpose() * (bp.translation() - bm.translation()) / (2 * h);
  const Vec3 w_numeric = rotationVector(bm.linear().transpose() * bp.linear()) / (2 * h);
  Vec3 v, w;
  tf2::fromMsg(b0.twist.twist.linear, v);
  tf2::fromMsg(b0.twist.twist.angular, w);
  EXPECT_LT((v - v_numeric).norm(), 1e-6) << v.transpose() << " vs " << v_numeric.transpose();
  EXPECT_LT((w - w_numeric).norm(), 1e-6) << w.transpose() << " vs " << w_numeric.transpose();
}

TEST(OutputFrames, OdomStaysContinuousWhenTheFilterStartsOver) {
  OutputFrames frames(TfMode::kOdom, "world", "odom", "");
  ASSERT_EQ(frames.prepare("imu0", nullptr), "");  // base = IMU: no TF needed
  std::mt19937_64 rng(3);
  nav_msgs::Odometry imu = imuOdometry(rng);
  const nav_msgs::Odometry first = frames.odometry(imu);
  EXPECT_EQ(first.header.frame_id, "odom");
  EXPECT_EQ(first.child_frame_id, "imu0");
  EXPECT_TRUE(poseOf(first).isApprox(poseOf(imu), 1e-12)) << "odom is the first world";
  // The filter starts over: its world is another one (yaw, origin) and its tilt differs slightly.
  frames.filterRestarted();
  const Iso T_new_old = makePose(Vec3(0.02, -0.01, 2.0), Vec3(-3.0, 4.0, 0.2));
  nav_msgs::Odometry restarted = imu;
  restarted.pose.pose = tf2::toMsg(Iso(T_new_old * poseOf(imu)));
  const Iso after = poseOf(frames.odometry(restarted));
  EXPECT_LT((after.translation() - poseOf(first).translation()).norm(), 1e-9) << "no jump in odom";
  EXPECT_LT(rotationVector(after.linear() * poseOf(first).linear().transpose()).norm(), 0.03)
      << "only the new tilt differs";
  // The placement holds for the next poses: a step of the filter is the same step in odom.
  nav_msgs::Odometry next = restarted;
  next.pose.pose = tf2::toMsg(Iso(poseOf(restarted) * makePose(Vec3(0, 0, 0.1), Vec3(0.5, 0, 0))));
  const Iso step = after.inverse() * poseOf(frames.odometry(next));
  EXPECT_TRUE(step.isApprox(makePose(Vec3(0, 0, 0.1), Vec3(0.5, 0, 0)), 1e-9));
  EXPECT_NEAR(frames.fixedFromWorld().linear()(2, 2), 1.0, 1e-12) << "gravity stays along z";
  // Time went back: odom starts over with the filter's world.
  frames.forget();
  EXPECT_TRUE(poseOf(frames.odometry(restarted)).isApprox(poseOf(restarted), 1e-12));
}

TEST(OutputFrames, TheBaseWaitsForItsTransformAndTheWorldModeIsTheFiltersOwn) {
  tf2::BufferCore tf;
  OutputFrames frames(TfMode::kOdom, "world", "odom", "base_link");
  EXPECT_NE(frames.prepare("imu0", &tf).find("waiting for TF base_link <- imu0"), std::string::npos);
  EXPECT_NE(frames.prepare("imu0", nullptr).find("no TF"), std::string::npos);
  geometry_msgs::TransformStamped t = tf2::eigenToTransform(kBaseImu);
  t.header.frame_id = "base_link";
  t.child_frame_id = "imu0";
  tf.setTransform(t, "urdf", true);
  ASSERT_EQ(frames.prepare("imu0", &tf), "");
  std::mt19937_64 rng(5);
  const nav_msgs::Odometry imu = imuOdometry(rng);
  const nav_msgs::Odometry out = frames.odometry(imu);
  EXPECT_EQ(out.child_frame_id, "base_link");
  EXPECT_TRUE(poseOf(out).isApprox(poseOf(imu) * kBaseImu.inverse(), 1e-12));

  OutputFrames world(TfMode::kWorld, "world", "odom", "base_link");
  ASSERT_EQ(world.prepare("imu0", nullptr), "");
  EXPECT_EQ(world.fixedFrame(), "world");
  const nav_msgs::Odometry same = world.odometry(imu);
  EXPECT_EQ(same.child_frame_id, "imu0");
  EXPECT_TRUE(poseOf(same).isApprox(poseOf(imu), 1e-15));
}

TEST(OutputFrames, ARelocalizationRejoinsTheMapInOdomOrMovesMapToOdom) {
  std::mt19937_64 rng(4);
  const nav_msgs::Odometry imu = imuOdometry(rng);
  // The map's world is the first one; the filter starts over in another world, placed in odom by
  // continuity, then is relocalized: its world moves by T_m_n back into the map's.
  const Iso T_new_old = makePose(Vec3(0.0, 0.0, 0.8), Vec3(-3.0, 4.0, 0.0));
  nav_msgs::Odometry restarted = imu;
  restarted.pose.pose = tf2::toMsg(Iso(T_new_old * poseOf(imu)));
  const Iso drift = makePose(Vec3::Zero(), Vec3(0.3, 0, 0));
  // The correction that puts the drifted pose back onto the map's: in the moved world the pose is
  // the map's again.
  const Iso T_m_n = drift.inverse() * T_new_old.inverse();
  const nav_msgs::Odometry relocalized = imu;
  for (const bool keep_odom : {false, true}) {
    OutputFrames frames(TfMode::kOdom, "world", "odom", "");
    ASSERT_EQ(frames.prepare("imu0", nullptr), "");
    frames.worldIsMap();
    const Iso first = poseOf(frames.odometry(imu));
    EXPECT_TRUE(frames.odomFromMap().isApprox(Iso::Identity(), 1e-12));
    frames.filterRestarted();
    // A drifted restart: odom continues 0.3 m off where the map says the rig is.
    nav_msgs::Odometry drifted = restarted;
    drifted.pose.pose = tf2::toMsg(Iso(T_new_old * drift * poseOf(imu)));
    const Iso continued = poseOf(frames.odometry(drifted));
    EXPECT_LT((continued.translation() - first.translation()).norm(), 1e-9);
    frames.relocalized(T_m_n, keep_odom);
    const Iso after = poseOf(frames.odometry(relocalized));
    if (keep_odom) {
      // odom stays continuous; map -> odom takes the correction and places the rig where the map has it.
      EXPECT_TRUE(after.isApprox(continued, 1e-9));
      EXPECT_TRUE(Iso(frames.odomFromMap().inverse() * after).isApprox(poseOf(imu), 1e-9));
    } else {
      // odom rejoins the map: the pose is the map's, map -> odom stays the identity.
      EXPECT_TRUE(after.isApprox(first, 1e-9));
      EXPECT_TRUE(frames.odomFromMap().isApprox(Iso::Identity(), 1e-12));
    }
  }
}

}  // namespace vi_ekf_slam::glue
