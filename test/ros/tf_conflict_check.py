#!/usr/bin/python3
"""rostest: the frame the node would move (the IMU frame, base_frame empty) already has a parent on
TF. Checks: the node still publishes odometry, never broadcasts a second parent for that frame, and
its "tf" diagnostic is an error that names the existing parent.

Private parameters:
  listen_s  the stream's nominal length [s] (the check waits for /stream/end and the node)
"""
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from nav_msgs.msg import Odometry
from std_msgs.msg import Time
from tf2_msgs.msg import TFMessage

PKG = "vi_ekf_slam"


class TfConflictCheck(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.parents, self.odom, self.tf_status, self.end = {}, 0, None, None
        for topic in ("/tf", "/tf_static"):
            rospy.Subscriber(topic, TFMessage, self.on_tf, queue_size=1000)
        rospy.Subscriber("/vi_ekf_slam/odom", Odometry, self.on_odom, queue_size=1000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag, queue_size=100)
        rospy.Subscriber("/stream/end", Time, self.on_end, queue_size=1)

    def on_tf(self, m):
        with self.lock:
            for t in m.transforms:
                self.parents.setdefault(t.child_frame_id, set()).add(t.header.frame_id)

    def on_odom(self, _):
        with self.lock:
            self.odom += 1

    def on_diag(self, m):
        with self.lock:
            for s in m.status:
                if s.name.endswith(": tf"):
                    self.tf_status = s

    def on_end(self, m):
        with self.lock:
            self.end = m.data.to_sec()

    def test_no_second_parent_and_said_on_diagnostics(self):
        limit = time.time() + rospy.get_param("~listen_s", 8.0) + 60.0
        while time.time() < limit and not rospy.is_shutdown():
            time.sleep(0.1)
            with self.lock:
                if self.end is not None and self.odom > 50 and self.tf_status is not None:
                    break
        time.sleep(1.0)  # the last TF and diagnostics
        with self.lock:
            parents, odom, status = dict(self.parents), self.odom, self.tf_status
        self.assertGreater(odom, 50, "no odometry")
        self.assertEqual(parents.get("imu0"), {"base_link"})
        self.assertIsNotNone(status, "no tf diagnostic")
        self.assertEqual(status.level, DiagnosticStatus.ERROR, status.message)
        self.assertIn("already has the parent 'base_link'", status.message)
        print("tf diagnostic: %s" % status.message)


if __name__ == "__main__":
    rospy.init_node("tf_conflict_check")
    rostest.rosrun(PKG, "tf_conflict_check", TfConflictCheck)
