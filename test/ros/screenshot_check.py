#!/usr/bin/python3
"""rostest: rviz under Xvfb during a replay (tools/screenshot.sh, which runs its own master): of a
short rendered walk in the demo's view, where the picture must show the path, the landmark cloud
and the track image; and of the first 25 s of the real hand-held recording in the default view,
which must also show the current pose and its covariance, small enough to hide nothing."""
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rospy
import rostest


class ScreenshotCheck(unittest.TestCase):
    def screenshot(self, make_bag, at_s, replay_args=(), check_args=""):
        """Runs screenshot.sh on the bag make_bag(path) writes; its folder is removed when it passes."""
        pkg = rospkg.RosPack().get_path("vi_ekf_slam")
        tmp = tempfile.mkdtemp(prefix="vi_ekf_slam_screenshot_")
        bag = os.path.join(tmp, "walk.bag")
        make_bag(bag)
        png = os.path.join(tmp, "rviz.png")
        env = dict(os.environ, SCREENSHOT_CHECK_ARGS=check_args)
        env.pop("ROS_MASTER_URI", None)
        r = subprocess.run([os.path.join(pkg, "tools", "screenshot.sh"), bag, png, str(at_s)] + list(replay_args),
                           env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        print(r.stdout[-2000:])
        self.assertTrue(os.path.exists(png), "no screenshot taken")
        self.assertEqual(r.returncode, 0, "the screenshot lacks something (above); kept in %s" % tmp)
        shutil.rmtree(tmp, ignore_errors=True)

    def test_rviz_shows_path_cloud_and_tracks(self):
        self.screenshot(lambda bag: subprocess.run(
            ["rosrun", "vi_ekf_slam", "vi_ekf_slam_make_bag", "--out", bag, "--duration", "10"], check=True,
            stdout=subprocess.PIPE), 13)

    def test_the_default_view_reads_on_the_real_recording(self):
        asl = os.path.join(os.environ.get("DATA_DIR", ""), "dmvio_handheld", "mav0")
        if not os.path.isdir(asl):
            self.skipTest("DATA_DIR with dmvio_handheld not available")
        self.screenshot(lambda bag: subprocess.run(
            ["rosrun", "vi_ekf_slam", "vi_ekf_slam_asl_to_bag", "--asl", asl, "--out", bag, "--duration", "25"],
            check=True, stdout=subprocess.PIPE), 20, ["rig:=dmvio_handheld"], "--pose")


if __name__ == "__main__":
    rospy.init_node("screenshot_check", anonymous=True)
    rostest.rosrun("vi_ekf_slam", "screenshot_check", ScreenshotCheck, sys.argv)
