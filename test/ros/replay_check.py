#!/usr/bin/python3
"""rostest: replays a bag with `rosbag play --clock` into the running filter and checks the result.

Private parameters:
  source            euroc_micro (real EuRoC frames, ASL -> bag) | euroc_micro_driver (the same on the
                    EuRoC driver's topics /imu0, /cam0/...) | rendered (a simulated walk)
  outputs           the namespace of the node's outputs (default /vi_ekf_slam)
  duration_s        rendered: seconds of walking after the 2 s standing start
  max_final_error_m final position error after registering the first pose [m]
  min_tracks        minimum mean number of tracks per frame
  compare_offline   also run vi_ekf_slam_run_bag on the bag and compare the trajectories
  max_offline_diff_m largest position difference live vs offline [m]
"""
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import rosbag
import rosgraph
import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from vi_ekf_slam.msg import FilterStatus

from quaternions import from_msg, yaw_between

PKG = "vi_ekf_slam"


def register(est0, gt0):
    """Yaw + translation taking the first estimate onto the truth (both unobservable)."""
    d = yaw_between(from_msg(est0.orientation), from_msg(gt0.orientation))
    c, s = math.cos(d), math.sin(d)

    def apply(p):
        x = c * p.x - s * p.y
        y = s * p.x + c * p.y
        return (x + gt0.position.x - (c * est0.position.x - s * est0.position.y),
                y + gt0.position.y - (s * est0.position.x + c * est0.position.y),
                p.z + gt0.position.z - est0.position.z)
    return apply


class ReplayCheck(unittest.TestCase):
    def setUp(self):
        self.odom, self.truth, self.status = [], {}, []
        ns = rospy.get_param("~outputs", "/vi_ekf_slam").rstrip("/")
        rospy.Subscriber(ns + "/odom", Odometry, lambda m: self.odom.append(m), queue_size=1000)
        rospy.Subscriber(ns + "/status", FilterStatus, lambda m: self.status.append(m), queue_size=1000)
        rospy.Subscriber("/ground_truth/pose", PoseStamped,
                         lambda m: self.truth.__setitem__(round(m.header.stamp.to_sec(), 3), m.pose), queue_size=1000)

    def make_bag(self, source, path):
        if source.startswith("euroc_micro"):
            data = os.environ.get("DATA_DIR", "")
            asl = os.path.join(data, "euroc_v1_01_micro", "mav0")
            if not data or not os.path.isdir(asl):
                self.skipTest("DATA_DIR with euroc_v1_01_micro not available")
            cmd = ["rosrun", PKG, "vi_ekf_slam_asl_to_bag", "--asl", asl, "--out", path]
            if source == "euroc_micro_driver":
                cmd.append("--euroc-topics")
        else:
            duration = str(rospy.get_param("~duration_s", 8.0))
            cmd = ["rosrun", PKG, "vi_ekf_slam_make_bag", "--out", path, "--duration", duration]
        subprocess.run(cmd, check=True, stdout=subprocess.PIPE)

    def test_replay(self):
        source = rospy.get_param("~source")
        # Removed when the check passes, kept for inspection when it fails.
        tmp = tempfile.mkdtemp(prefix="vi_ekf_slam_replay_")
        print("replay_check: working in %s" % tmp)
        bag = os.path.join(tmp, "input.bag")
        self.make_bag(source, bag)
        # The first messages must reach the node whatever the machine's load (a publish before the
        # node's connection is lost, and a later start is a different run): wait until the node has
        # subscribed to the bag's IMU and images, then let rosbag play wait for a connection on
        # every topic it plays (those someone subscribes to).
        with rosbag.Bag(bag) as b:
            topics = b.get_type_and_topic_info().topics
            images = [t for t, info in topics.items() if info.msg_type == "sensor_msgs/Image"]
            last_image_t = max(m.header.stamp.to_sec() for _, m, _ in b.read_messages(topics=images))
        sensors = {t for t, info in topics.items() if info.msg_type in ("sensor_msgs/Imu", "sensor_msgs/Image")}
        master = rosgraph.Master(rospy.get_name())
        while True:
            subscribed = {t for t, _ in master.getSystemState()[1]}
            if sensors <= subscribed:
                break
            time.sleep(0.1)
        play = sorted(t for t in topics if t in subscribed)
        subprocess.run(["rosbag", "play", "--clock", "--quiet", "--wait-for-subscribers", bag, "--topics"] + play,
                       check=True)
        # The node may lag behind the bag on a busy machine: wait for the status of its last images
        # (stamped on the IMU clock: within the 0.1 s any time offset estimate stays in).
        while not any(st.header.stamp.to_sec() >= last_image_t - 0.1 for st in self.status[-5:]):
            time.sleep(0.05)
        self.assertGreater(len(self.odom), 20, "no odometry from the replay")
        for o in self.odom:
            p = o.pose.pose.position
            self.assertTrue(all(math.isfinite(v) for v in (p.x, p.y, p.z)), "non-finite odometry")
        # Final error after registering the first pose that has ground truth.
        pairs = [(o, self.truth.get(round(o.header.stamp.to_sec(), 3))) for o in self.odom]
        pairs = [(o, g) for o, g in pairs if g is not None]
        self.assertGreater(len(pairs), 10, "odometry stamps do not match the ground truth")
        apply = register(pairs[0][0].pose.pose, pairs[0][1])
        x, y, z = apply(pairs[-1][0].pose.pose.position)
        g = pairs[-1][1].position
        err = math.sqrt((x - g.x) ** 2 + (y - g.y) ** 2 + (z - g.z) ** 2)
        tracks = sum(s.tracks for s in self.status) / max(1, len(self.status))
        print("%s: %d poses, final position error %.4f m, %.1f tracks per frame" % (source, len(pairs), err, tracks))
        self.assertLess(err, rospy.get_param("~max_final_error_m"))
        self.assertGreaterEqual(tracks, rospy.get_param("~min_tracks", 0))
        if rospy.get_param("~compare_offline", False):
            out = os.path.join(tmp, "offline")
            cfg = rospy.get_param("~offline_args", "").split()
            subprocess.run(["rosrun", PKG, "vi_ekf_slam_run_bag", "--bag", bag, "--out", out, "--no-plots"] + cfg,
                           check=True, stdout=subprocess.PIPE)
            tum = [f for f in os.listdir(out) if f.endswith(".tum")][0]
            offline = {}
            with open(os.path.join(out, tum)) as f:
                for line in f:
                    if line.startswith("#"):
                        continue
                    v = [float(x) for x in line.split()]
                    offline[round(v[0], 3)] = v[1:4]
            diffs = []
            for o in self.odom:
                q = offline.get(round(o.header.stamp.to_sec(), 3))
                if q is not None:
                    p = o.pose.pose.position
                    diffs.append(math.sqrt((p.x - q[0]) ** 2 + (p.y - q[1]) ** 2 + (p.z - q[2]) ** 2))
            self.assertGreater(len(diffs), 0.9 * len(self.odom), "offline and live stamps do not match")
            print("live vs offline: %d common poses, largest difference %.6f m" % (len(diffs), max(diffs)))
            self.assertLess(max(diffs), rospy.get_param("~max_offline_diff_m"))
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    rospy.init_node("replay_check")
    rostest.rosrun(PKG, "replay_check", ReplayCheck, sys.argv)
