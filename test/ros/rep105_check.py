#!/usr/bin/python3
"""rostest: the node in a robot's TF tree (REP-105). A URDF-like base_link -> imu0 (rotated: the
IMU on its side, away from the base origin), the driver's imu0 -> cam0, the node's odom ->
base_link and map -> odom. Checks: every frame has one parent; the odometry is the base in odom
and equals the TF at its stamp; the IMU pose it implies (odom -> base_link -> imu0) follows the
simulated IMU (/ground_truth/pose) after registering the first pose (yaw and position).

Private parameters:
  listen_s          the stream's nominal length [s] (the check waits for /stream/end and the node)
  max_final_error_m final position error of the IMU implied by odom -> base_link [m]
  max_attitude_error_rad largest attitude error of that IMU after the registration [rad]
"""
import math
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from std_msgs.msg import Time
from tf2_msgs.msg import TFMessage

from quaternions import qconj, qmul, rotate, yaw_between

PKG = "vi_ekf_slam"


def pose(msg_pose):
    p, o = msg_pose.position, msg_pose.orientation
    return (p.x, p.y, p.z), (o.w, o.x, o.y, o.z)


def transform(t):
    p, o = t.transform.translation, t.transform.rotation
    return (p.x, p.y, p.z), (o.w, o.x, o.y, o.z)


def compose(a, b):
    """(p, q) of b in a's parent: a * b."""
    pa, qa = a
    pb, qb = b
    r = rotate(qa, pb)
    return (pa[0] + r[0], pa[1] + r[1], pa[2] + r[2]), qmul(qa, qb)


def angle_of(q):
    return 2.0 * math.acos(min(1.0, abs(q[0])))


class Rep105Check(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.parents, self.odom, self.truth, self.end = {}, [], {}, None
        self.buffer = tf2_ros.Buffer(cache_time=rospy.Duration(120.0))
        self.listener = tf2_ros.TransformListener(self.buffer)
        for topic in ("/tf", "/tf_static"):
            rospy.Subscriber(topic, TFMessage, self.on_tf, queue_size=1000)
        rospy.Subscriber("/vi_ekf_slam/odom", Odometry, self.on_odom, queue_size=1000)
        rospy.Subscriber("/ground_truth/pose", PoseStamped, self.on_truth, queue_size=1000)
        rospy.Subscriber("/stream/end", Time, self.on_end, queue_size=1)

    def on_tf(self, m):
        with self.lock:
            for t in m.transforms:
                self.parents.setdefault(t.child_frame_id, set()).add(t.header.frame_id)

    def on_odom(self, m):
        with self.lock:
            self.odom.append(m)

    def on_truth(self, m):
        with self.lock:
            self.truth[round(m.header.stamp.to_sec(), 3)] = m.pose

    def on_end(self, m):
        with self.lock:
            self.end = m.data.to_sec()

    def wait_for_stream(self):
        """Until the stream is over and the node caught up with it (not a wall-clock window)."""
        limit = time.time() + rospy.get_param("~listen_s", 10.0) + 60.0
        end_seen = None
        while time.time() < limit and not rospy.is_shutdown():
            time.sleep(0.05)
            with self.lock:
                end, last = self.end, (self.odom[-1].header.stamp.to_sec() if self.odom else 0.0)
            if end is None:
                continue
            end_seen = end_seen or time.time()
            if last >= end - 1.0 / 28.0 - 0.2 or time.time() - end_seen > 10.0:
                return

    def test_rep105_tree_and_base_pose(self):
        self.wait_for_stream()
        time.sleep(0.5)  # the last TF
        with self.lock:
            parents, odom, truth = dict(self.parents), list(self.odom), dict(self.truth)
        self.assertGreater(len(odom), 50, "no odometry")
        for child, ps in parents.items():
            self.assertEqual(len(ps), 1, "%s has %d parents: %s" % (child, len(ps), sorted(ps)))
        self.assertEqual(parents.get("base_link"), {"odom"})
        self.assertEqual(parents.get("imu0"), {"base_link"})
        self.assertEqual(parents.get("cam0"), {"imu0"})
        self.assertEqual(parents.get("odom"), {"map"})
        for o in odom:
            self.assertEqual((o.header.frame_id, o.child_frame_id), ("odom", "base_link"))

        # The TF at an odometry stamp is the odometry.
        for o in odom[::10]:
            t = self.buffer.lookup_transform("odom", "base_link", o.header.stamp)
            (p, q), (tp, tq) = pose(o.pose.pose), transform(t)
            self.assertLess(max(abs(a - b) for a, b in zip(p, tp)), 1e-6)
            self.assertLess(angle_of(qmul(qconj(q), tq)), 1e-6)

        # The IMU implied by odom -> base_link -> imu0 against the simulated IMU.
        T_base_imu = transform(self.buffer.lookup_transform("base_link", "imu0", rospy.Time(0)))
        pairs = [(compose(pose(o.pose.pose), T_base_imu), truth.get(round(o.header.stamp.to_sec(), 3)))
                 for o in odom]
        pairs = [(e, pose(g)) for e, g in pairs if g is not None]
        self.assertGreater(len(pairs), 50, "no ground truth at the odometry stamps")
        (e0p, e0q), (g0p, g0q) = pairs[0]
        d = yaw_between(e0q, g0q)
        q_reg = (math.cos(d / 2), 0.0, 0.0, math.sin(d / 2))
        r0 = rotate(q_reg, e0p)
        shift = tuple(g - r for g, r in zip(g0p, r0))
        worst_att = 0.0
        for (ep, eq), (gp, gq) in pairs:
            worst_att = max(worst_att, angle_of(qmul(qconj(gq), qmul(q_reg, eq))))
        (ep, eq), (gp, gq) = pairs[-1]
        final = math.dist(tuple(r + s for r, s in zip(rotate(q_reg, ep), shift)), gp)
        print("REP-105: %d poses, IMU via odom -> base_link: final error %.3f m, worst attitude error %.3f rad"
              % (len(pairs), final, worst_att))
        self.assertLess(final, rospy.get_param("~max_final_error_m", 0.5))
        self.assertLess(worst_att, rospy.get_param("~max_attitude_error_rad", 0.1))


if __name__ == "__main__":
    rospy.init_node("rep105_check")
    rostest.rosrun(PKG, "rep105_check", Rep105Check)
