// rostest checker for the vi_ekf_slam node/nodelet. Parameters (private):
//   listen_s            the stream's nominal length [s]: the checker listens until the stream's end
//                       (/stream/end) and the node caught up, at most listen_s + 60 s
//   expect_odom         odometry must be published (default true)
//   min_odom_hz         minimum odometry rate while running [Hz]
//   max_final_error_m   final position error against /ground_truth/pose after aligning the
//                       first pose (position and yaw: both unobservable) [m]; 0: not checked
//   diag_nonzero        comma-separated keys of the "inputs" diagnostics that must end > 0
//   diag_zero           comma-separated keys of the "inputs" diagnostics that must stay 0
//   min_diag_level      the inputs diagnostics must reach this level once (0 OK, 1 WARN, 2 ERROR)
//   expect_inputs_summary a substring the inputs diagnostics' summary must show once
//   expect_event        a substring that must appear on the events topic
//   min_resets          minimum "resets" reported by the status
//   call_reset_at_s     call the reset service this long after the first odometry [s]; <0: never
//   max_reinit_s        after that reset, odometry must be back within this much stream time [s]; 0: not checked
//   max_reset_step_m    largest position step between consecutive odometry messages from just before
//                       that reset on: odom stays continuous (REP-105) [m]; 0: not checked
//   switch_at_s         switch the mechanization this long after the first odometry [s]; <0: never
//   switch_to           the mechanization to switch to
#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/client.h>
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>

#include <optional>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/String.h>
#include <std_msgs/Time.h>
#include <std_srvs/Trigger.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <mutex>
#include <sstream>

#include "vi_ekf_slam/EkfSlamReconfigureConfig.h"
#include "msg_eigen.h"
#include "vi_ekf_slam/core/so3.h"
#include "vi_ekf_slam/FilterStatus.h"
#include "vi_ekf_slam/ros/conversions.h"

namespace {

using vi_ekf_slam::test::pos;
using vi_ekf_slam::test::quat;

struct Recorder {
  std::mutex m;
  std::vector<nav_msgs::Odometry> odom;
  std::map<double, geometry_msgs::PoseStamped> truth;
  std::vector<vi_ekf_slam::FilterStatus> status;
  int clouds = 0;
  std::vector<std::string> events;
  std::map<std::string, double> inputs;  // last values of the "inputs" diagnostics
  int max_inputs_level = 0;
  std::vector<std::string> inputs_summaries;  // every distinct summary of the "inputs" diagnostics
  ros::Time last_diag;
};

}  // namespace

TEST(FilterNode, BehavesOnThisInputStream) {
  ros::NodeHandle nh, pnh("~");
  double listen_s = 15, min_hz = 15, max_err = 0, reset_at = -1, switch_at = -1, max_reinit = 0;
  bool expect_odom = true;
  int min_level = 0, min_resets = 0;
  std::string diag_nonzero, diag_zero, expect_event, switch_to = "world_centric", expect_summary;
  pnh.param("expect_inputs_summary", expect_summary, expect_summary);
  pnh.param("listen_s", listen_s, listen_s);
  pnh.param("expect_odom", expect_odom, expect_odom);
  pnh.param("min_odom_hz", min_hz, min_hz);
  pnh.param("max_final_error_m", max_err, max_err);
  pnh.param("diag_nonzero", diag_nonzero, diag_nonzero);
  pnh.param("diag_zero", diag_zero, diag_zero);
  pnh.param("min_diag_level", min_level, min_level);
  pnh.param("expect_event", expect_event, expect_event);
  pnh.param("min_resets", min_resets, min_resets);
  pnh.param("call_reset_at_s", reset_at, reset_at);
  pnh.param("max_reinit_s", max_reinit, max_reinit);
  double max_reset_step = 0.0;
  pnh.param("max_reset_step_m", max_reset_step, max_reset_step);
  pnh.param("switch_at_s", switch_at, switch_at);
  pnh.param("switch_to", switch_to, switch_to);

  Recorder rec;
  auto s1 = nh.subscribe<nav_msgs::Odometry>("/vi_ekf_slam/odom", 1000, [&](const nav_msgs::OdometryConstPtr& m) {
    std::lock_guard<std::mutex> l(rec.m);
    rec.odom.push_back(*m);
  });
  auto s2 = nh.subscribe<geometry_msgs::PoseStamped>("/ground_truth/pose", 1000,
                                                     [&](const geometry_msgs::PoseStampedConstPtr& m) {
                                                       std::lock_guard<std::mutex> l(rec.m);
                                                       rec.truth[m->header.stamp.toSec()] = *m;
                                                     });
  auto s3 = nh.subscribe<vi_ekf_slam::FilterStatus>("/vi_ekf_slam/status", 1000,
                                                    [&](const vi_ekf_slam::FilterStatusConstPtr& m) {
                                                      std::lock_guard<std::mutex> l(rec.m);
                                                      rec.status.push_back(*m);
                                                    });
  auto s4 = nh.subscribe<sensor_msgs::PointCloud2>("/vi_ekf_slam/landmarks", 10,
                                                   [&](const sensor_msgs::PointCloud2ConstPtr&) {
                                                     std::lock_guard<std::mutex> l(rec.m);
                                                     ++rec.clouds;
                                                   });
  auto s5 = nh.subscribe<std_msgs::String>("/vi_ekf_slam/events", 100, [&](const std_msgs::StringConstPtr& m) {
    std::lock_guard<std::mutex> l(rec.m);
    rec.events.push_back(m->data);
  });
  auto s6 = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
        std::lock_guard<std::mutex> l(rec.m);
        for (const auto& st : m->status) {
          if (st.name.find("inputs") == std::string::npos) continue;
          rec.max_inputs_level = std::max<int>(rec.max_inputs_level, st.level);
          if (std::find(rec.inputs_summaries.begin(), rec.inputs_summaries.end(), st.message) ==
              rec.inputs_summaries.end())
            rec.inputs_summaries.push_back(st.message);
          rec.last_diag = ros::Time::now();
          for (const auto& kv : st.values) {
            try {
              rec.inputs[kv.key] = std::stod(kv.value);
            } catch (const std::exception&) {
            }
          }
        }
      });

  double stream_end = 0.0;  // stamp of the stream's last IMU sample, once it is over
  auto s7 = nh.subscribe<std_msgs::Time>("/stream/end", 1, [&](const std_msgs::TimeConstPtr& m) {
    std::lock_guard<std::mutex> l(rec.m);
    stream_end = m->data.toSec();
  });

  ros::AsyncSpinner spinner(2);
  spinner.start();
  // Listen until the stream is over and the node has caught up with it (its odometry reaches the
  // stream's last image), not for a fixed wall-clock window: a loaded machine renders and streams
  // slower. listen_s (the stream's nominal length) + kMaxDelayS only bounds a node that never
  // catches up; after the end, a node that does not catch up gets kCatchUpS, and a test without
  // odometry drains kDrainS.
  constexpr double kMaxDelayS = 60.0, kCatchUpS = 10.0, kDrainS = 2.0, kCaughtUpS = 0.2;
  const ros::WallTime start = ros::WallTime::now();
  ros::WallTime first_odom, end_seen;
  bool reset_done = false, switch_done = false;
  double switch_stamp = 0.0, reset_stamp = 0.0;
  while (ros::ok() && (ros::WallTime::now() - start).toSec() < listen_s + kMaxDelayS) {
    ros::WallDuration(0.05).sleep();
    double last_stamp = 0.0, end = 0.0;
    {
      // Never call services while holding the lock: the spinner threads need it.
      std::lock_guard<std::mutex> l(rec.m);
      end = stream_end;
      if (!rec.odom.empty()) last_stamp = rec.odom.back().header.stamp.toSec();
    }
    if (end > 0.0) {
      if (end_seen.isZero()) end_seen = ros::WallTime::now();
      const bool caught_up = expect_odom && last_stamp >= end - 1.0 / 28.0 - kCaughtUpS;
      if (caught_up || (ros::WallTime::now() - end_seen).toSec() > (expect_odom ? kCatchUpS : kDrainS)) break;
    }
    if (last_stamp == 0.0) continue;
    if (first_odom.isZero()) first_odom = ros::WallTime::now();
    const double since = (ros::WallTime::now() - first_odom).toSec();
    if (reset_at >= 0 && !reset_done && since > reset_at) {
      std_srvs::Trigger srv;
      EXPECT_TRUE(ros::service::call("/vi_ekf_slam/filter/reset", srv));
      EXPECT_TRUE(srv.response.success);
      reset_done = true;
      reset_stamp = last_stamp;
    }
    if (switch_at >= 0 && !switch_done && since > switch_at) {
      dynamic_reconfigure::Client<vi_ekf_slam::EkfSlamReconfigureConfig> client("/vi_ekf_slam/filter");
      vi_ekf_slam::EkfSlamReconfigureConfig cfg;
      ASSERT_TRUE(client.getCurrentConfiguration(cfg, ros::Duration(5.0))) << "no reconfigure server";
      cfg.mechanization = switch_to;
      switch_stamp = last_stamp;
      ASSERT_TRUE(client.setConfiguration(cfg)) << "reconfigure refused";
      switch_done = true;
    }
  }
  spinner.stop();
  std::lock_guard<std::mutex> l(rec.m);

  // Never a NaN.
  for (const auto& o : rec.odom) ASSERT_TRUE(vi_ekf_slam::glue::allFinite(o)) << "non-finite odometry";
  // The node stays up: its diagnostics keep coming until the end.
  EXPECT_GT(rec.last_diag.toSec(), 0.0) << "no diagnostics at all";
  EXPECT_LT((ros::Time::now() - rec.last_diag).toSec(), 3.0) << "diagnostics stopped: node down?";

  if (expect_odom) {
    ASSERT_GT(rec.odom.size(), 20u);
    const double span = rec.odom.back().header.stamp.toSec() - rec.odom.front().header.stamp.toSec();
    const double hz = (rec.odom.size() - 1) / std::max(1e-6, span);
    EXPECT_GE(hz, min_hz) << "odometry rate";
    ::testing::Test::RecordProperty("odom_rate_centihz", static_cast<int>(100 * hz));
    EXPECT_GT(rec.clouds, 5) << "landmark clouds";
    EXPECT_GT(rec.status.size(), 20u) << "status messages";
    if (!rec.status.empty()) {
      EXPECT_GT(rec.status.back().landmarks_in_state, 0);
      for (const auto& st : rec.status) {  // the front end's time is a part of the image's time
        EXPECT_TRUE(st.tracker_time_ms >= 0.0 && st.tracker_time_ms <= st.update_time_ms)
            << st.tracker_time_ms << " of " << st.update_time_ms << " ms";
      }
    }
  } else {
    EXPECT_TRUE(rec.odom.empty()) << "odometry published although it should not";
  }

  if (max_err > 0 && !rec.odom.empty()) {
    // The truth at an odometry stamp (the state's time: image stamp + estimated time offset),
    // position interpolated between the truth poses around it, orientation of the nearer one.
    auto truthAt = [&](double t) -> std::optional<geometry_msgs::PoseStamped> {
      if (rec.truth.empty()) return std::nullopt;
      auto b = rec.truth.lower_bound(t);
      if (b != rec.truth.end() && b->first - t < 1e-6) return b->second;
      // Just outside the truth's span (the offset estimate moved the stamp past an end): the end.
      if (b == rec.truth.begin()) return b->first - t < 0.1 ? std::optional(b->second) : std::nullopt;
      if (b == rec.truth.end()) {
        const auto& last = *rec.truth.rbegin();
        return t - last.first < 0.1 ? std::optional(last.second) : std::nullopt;
      }
      auto a = std::prev(b);
      if (b->first - a->first > 0.5) return std::nullopt;
      const double alpha = (t - a->first) / (b->first - a->first);
      geometry_msgs::PoseStamped p = alpha < 0.5 ? a->second : b->second;
      p.pose.position.x = (1 - alpha) * a->second.pose.position.x + alpha * b->second.pose.position.x;
      p.pose.position.y = (1 - alpha) * a->second.pose.position.y + alpha * b->second.pose.position.y;
      p.pose.position.z = (1 - alpha) * a->second.pose.position.z + alpha * b->second.pose.position.z;
      return p;
    };
    // Align at the first odometry after the last reset (resets restart the world frame).
    size_t first = 0;
    for (size_t i = 1; i < rec.odom.size(); ++i) {
      if (rec.odom[i].header.stamp < rec.odom[i - 1].header.stamp) first = i;
    }
    const auto g0 = truthAt(rec.odom[first].header.stamp.toSec());
    const auto g1 = truthAt(rec.odom.back().header.stamp.toSec());
    ASSERT_TRUE(g0 && g1) << "no ground truth at the odometry stamps";
    const Eigen::Isometry3d T_true_est = vi_ekf_slam::registrationAtFirstPose(
        pos(rec.odom[first].pose.pose.position), quat(rec.odom[first].pose.pose.orientation), pos(g0->pose.position),
        quat(g0->pose.orientation));
    const Eigen::Vector3d e = T_true_est * pos(rec.odom.back().pose.pose.position) - pos(g1->pose.position);
    const double dist = (pos(g1->pose.position) - pos(g0->pose.position)).norm();
    std::printf("final position error %.3f m over %.1f m walked\n", e.norm(), dist);
    ::testing::Test::RecordProperty("final_position_error_mm", static_cast<int>(1000 * e.norm()));
    ::testing::Test::RecordProperty("distance_mm", static_cast<int>(1000 * dist));
    EXPECT_LT(e.norm(), max_err);
  }
  std::stringstream keys(diag_nonzero);
  std::string key;
  while (std::getline(keys, key, ',')) {
    if (key.empty()) continue;
    EXPECT_GT(rec.inputs[key], 0.0) << "diagnostics '" << key << "' stayed 0";
  }
  std::stringstream zero_keys(diag_zero);
  while (std::getline(zero_keys, key, ',')) {
    if (key.empty()) continue;
    EXPECT_TRUE(rec.inputs.count(key)) << "diagnostics '" << key << "' never reported";
    EXPECT_EQ(rec.inputs[key], 0.0) << "diagnostics '" << key << "' should have stayed 0";
  }
  EXPECT_GE(rec.max_inputs_level, min_level) << "inputs diagnostics never reached level " << min_level;
  if (!expect_summary.empty()) {
    std::string seen;
    for (const auto& s : rec.inputs_summaries) seen += "\n  " + s;
    EXPECT_TRUE(std::any_of(rec.inputs_summaries.begin(), rec.inputs_summaries.end(),
                            [&](const std::string& s) { return s.find(expect_summary) != std::string::npos; }))
        << "the inputs diagnostics never said '" << expect_summary << "'; they said:" << seen;
  }
  if (!expect_event.empty()) {
    bool seen = false;
    for (const auto& e : rec.events) seen = seen || e.find(expect_event) != std::string::npos;
    EXPECT_TRUE(seen) << "no event containing '" << expect_event << "'";
  }
  if (min_resets > 0) {
    ASSERT_FALSE(rec.status.empty());
    EXPECT_GE(rec.status.back().resets, min_resets);
  }
  if (reset_at >= 0) {
    EXPECT_TRUE(reset_done);
    // After the reset the filter re-initialized and published again.
    int inits = 0;
    for (const auto& e : rec.events) inits += e.rfind("initialized", 0) == 0;
    EXPECT_GE(inits, 2) << "the filter did not initialize again after the reset";
    if (max_reinit > 0.0) {
      // The longest silence of the odometry from just before the reset on (stream time).
      double gap = 0.0, prev = reset_stamp - 0.5;
      for (const auto& o : rec.odom) {
        const double t = o.header.stamp.toSec();
        if (t < prev) continue;
        gap = std::max(gap, t - prev);
        prev = t;
      }
      std::printf("odometry back %.2f s after the reset\n", gap);
      ::testing::Test::RecordProperty("reinit_ms", static_cast<int>(1e3 * gap));
      EXPECT_LT(gap, max_reinit) << "no odometry for " << gap << " s after the reset";
    }
    if (max_reset_step > 0.0) {
      // The filter starts over in a new world; odom places it where the last pose was.
      double step = 0.0;
      for (size_t i = 1; i < rec.odom.size(); ++i) {
        if (rec.odom[i].header.stamp.toSec() < reset_stamp - 0.5) continue;
        step = std::max(step, (pos(rec.odom[i].pose.pose.position) - pos(rec.odom[i - 1].pose.pose.position)).norm());
      }
      std::printf("largest odometry step across the reset %.3f m\n", step);
      EXPECT_LT(step, max_reset_step) << "odom jumped at the reset";
    }
  }
  if (switch_at >= 0) {
    ASSERT_TRUE(switch_done);
    ASSERT_FALSE(rec.status.empty());
    EXPECT_EQ(rec.status.back().mechanization, switch_to);
    // The pose stays continuous across the switch: consecutive poses move only as the
    // velocity says (walking 1.3 m/s moves ~5 cm per image).
    double worst = 0.0;
    for (size_t i = 1; i < rec.odom.size(); ++i) {
      const double t0 = rec.odom[i - 1].header.stamp.toSec(), t1 = rec.odom[i].header.stamp.toSec();
      if (std::abs(t0 - switch_stamp) > 0.5) continue;
      const Eigen::Quaterniond q(rec.odom[i - 1].pose.pose.orientation.w, rec.odom[i - 1].pose.pose.orientation.x,
                                 rec.odom[i - 1].pose.pose.orientation.y, rec.odom[i - 1].pose.pose.orientation.z);
      const Eigen::Vector3d v_w =
          q * Eigen::Vector3d(rec.odom[i - 1].twist.twist.linear.x, rec.odom[i - 1].twist.twist.linear.y,
                              rec.odom[i - 1].twist.twist.linear.z);
      const Eigen::Vector3d jump =
          pos(rec.odom[i].pose.pose.position) - pos(rec.odom[i - 1].pose.pose.position) - v_w * (t1 - t0);
      worst = std::max(worst, jump.norm());
    }
    std::printf("largest pose jump around the switch: %.4f m\n", worst);
    ::testing::Test::RecordProperty("switch_jump_um", static_cast<int>(1e6 * worst));
    EXPECT_LT(worst, 0.03);
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_filter_outputs");
  return RUN_ALL_TESTS();
}
