#!/usr/bin/python3
"""rostest: rviz under Xvfb during a replay of a short rendered walk (tools/screenshot.sh, which
runs its own master); the picture must show the path, the landmark cloud and the track image."""
import os
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rospy
import rostest


class ScreenshotCheck(unittest.TestCase):
    def test_rviz_shows_path_cloud_and_tracks(self):
        pkg = rospkg.RosPack().get_path("vi_ekf_slam")
        tmp = tempfile.mkdtemp()
        bag = os.path.join(tmp, "walk.bag")
        subprocess.run(["rosrun", "vi_ekf_slam", "vi_ekf_slam_make_bag", "--out", bag, "--duration", "10"],
                       check=True, stdout=subprocess.PIPE)
        png = os.path.join(tmp, "rviz.png")
        env = dict(os.environ)
        env.pop("ROS_MASTER_URI", None)
        r = subprocess.run([os.path.join(pkg, "tools", "screenshot.sh"), bag, png, "13"], env=env,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        print(r.stdout[-2000:])
        self.assertTrue(os.path.exists(png), "no screenshot taken")
        self.assertEqual(r.returncode, 0, "the screenshot lacks the path, the cloud or the tracks")


if __name__ == "__main__":
    rospy.init_node("screenshot_check", anonymous=True)
    rostest.rosrun("vi_ekf_slam", "screenshot_check", ScreenshotCheck, sys.argv)
