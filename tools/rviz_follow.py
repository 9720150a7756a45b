#!/usr/bin/python3
"""Starts rviz with a view that follows the rig: the shipped view (rviz/vi_ekf_slam.rviz, a
pedestrian's scale) with its orbit centred on the frame the filter moves, the child frame of its
first odometry (base_frame, or the IMU frame), or on --frame.

usage: rviz_follow.py --config FILE.rviz [--frame NAME|(odometry)] [--odom-topic TOPIC]
"""
import argparse
import os
import signal
import subprocess
import sys
import tempfile

import rospy
from nav_msgs.msg import Odometry


def followed_view(text, frame):
    """The config with the view's target frame set (the displays keep the fixed frame)."""
    views = text.index("  Views:")
    return text[:views] + text[views:].replace("Target Frame: <Fixed Frame>", "Target Frame: %s" % frame, 1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--config", required=True, help="the rviz configuration")
    ap.add_argument("--frame", default="(odometry)",
                    help="the frame to follow (default, (odometry): the odometry's child frame)")
    ap.add_argument("--odom-topic", default="/vi_ekf_slam/odom")
    a = ap.parse_args(rospy.myargv()[1:])
    frame = "" if a.frame == "(odometry)" else a.frame
    if not frame:
        rospy.init_node("rviz_follow", anonymous=True, disable_signals=True)
        rospy.loginfo("rviz_follow: waiting for the first odometry on %s to follow its frame", a.odom_topic)
        frame = rospy.wait_for_message(a.odom_topic, Odometry).child_frame_id
        rospy.signal_shutdown("the frame to follow is known")
    # The view lives as long as rviz, then goes (rviz reads it at its start and on "Save").
    with tempfile.TemporaryDirectory(prefix="vi_ekf_slam_follow_") as tmp:
        path = os.path.join(tmp, "view.rviz")
        with open(path, "w") as f:
            f.write(followed_view(open(a.config).read(), frame))
        rviz = subprocess.Popen(["rviz", "-d", path])
        signal.signal(signal.SIGINT, lambda *_: rviz.send_signal(signal.SIGINT))
        signal.signal(signal.SIGTERM, lambda *_: rviz.send_signal(signal.SIGTERM))
        return rviz.wait()


if __name__ == "__main__":
    sys.exit(main())
