#!/usr/bin/python3
"""rostest: every launch file of the package, with every rig preset, gives the filter the preset's
values (roslaunch --dump-params): a launch argument left at its default never overrides the rig
file. An argument given explicitly wins over the rig; a rig file is found by preset name, by
absolute path and by a path relative to the working directory; `roslaunch --ros-args` marks as
required only the arguments that are.
"""
import glob
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rostest
import yaml

PKG = "vi_ekf_slam"
FILTER = "/vi_ekf_slam/filter/"
# Each launch file with the arguments it needs to load at all.
LAUNCH_FILES = {"vi_ekf_slam.launch": [], "pedestrian_rig.launch": [], "realsense.launch": ["rviz:=true"],
                "replay.launch": ["bag:=/tmp/none.bag", "rviz:=true", "record:=/tmp/none_out.bag"]}
REQUIRED = {"replay.launch": {"bag"}}


def dump(launch, args, cwd=None):
    out = subprocess.run(["roslaunch", "--dump-params", PKG, launch] + LAUNCH_FILES[launch] + args, cwd=cwd,
                         env=dict(os.environ, PWD=cwd or os.getcwd()), check=True, capture_output=True, text=True)
    return yaml.safe_load(out.stdout)


class LaunchParams(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.share = rospkg.RosPack().get_path(PKG)
        cls.presets = {os.path.splitext(os.path.basename(f))[0]: yaml.safe_load(open(f))
                       for f in sorted(glob.glob(os.path.join(cls.share, "config", "rigs", "*.yaml")))}

    def assertRigApplied(self, params, rig, what):
        for key, value in rig.items():
            self.assertIn(FILTER + key, params, "%s: %s not set" % (what, key))
            got = params[FILTER + key]
            if isinstance(value, float) or (isinstance(value, list) and value and isinstance(value[0], float)):
                self.assertEqual(list(map(float, got)) if isinstance(got, list) else float(got), value,
                                 "%s: %s" % (what, key))
            else:
                self.assertEqual(got, value, "%s: %s is %r, the rig says %r" % (what, key, got, value))

    def test_every_launch_file_takes_every_presets_values(self):
        self.assertGreaterEqual(len(self.presets), 5)
        for launch in LAUNCH_FILES:
            for name, rig in self.presets.items():
                self.assertRigApplied(dump(launch, ["rig:=" + name]), rig, "%s rig:=%s" % (launch, name))

    def test_an_argument_given_wins_over_the_rig(self):
        for launch in LAUNCH_FILES:
            p = dump(launch, ["rig:=d435i", "imu_topic:=/my/imu", "image_topic:=/my/image"]
                     if launch != "realsense.launch" else ["rig:=d435i"])
            if launch != "realsense.launch":
                self.assertEqual(p[FILTER + "imu_topic"], "/my/imu", launch)
                self.assertEqual(p[FILTER + "image_topic"], "/my/image", launch)
                self.assertEqual(p[FILTER + "camera_info_topic"], "/camera/infra1/camera_info", launch)

    def test_without_a_rig_the_inputs_are_relative_names(self):
        # Relative: resolved in the launch file's namespace, remappable.
        p = dump("vi_ekf_slam.launch", [])
        self.assertEqual((p[FILTER + "imu_topic"], p[FILTER + "image_topic"], p[FILTER + "camera_info_topic"]),
                         ("imu", "image", "camera_info"))

    def test_a_driver_started_by_pedestrian_rig_is_listened_to(self):
        p = dump("pedestrian_rig.launch", ["imu_node_pkg:=some_driver", "imu_node_type:=node.py"])
        self.assertEqual(p[FILTER + "imu_topic"], "/imu")
        self.assertEqual(p[FILTER + "body_frame"], "imu")
        self.assertEqual(p[FILTER + "image_topic"], "image", "no camera driver started: the default")

    def test_a_rig_file_by_absolute_and_by_relative_path(self):
        tmp = tempfile.mkdtemp(prefix="vi_ekf_slam_launch_")
        try:
            os.makedirs(os.path.join(tmp, "rigs"))
            rig = {"imu_topic": "/mine/imu", "image_topic": "/mine/image", "gyro_noise_density": 3.0e-4}
            with open(os.path.join(tmp, "rigs", "my_rig.yaml"), "w") as f:
                yaml.safe_dump(rig, f)
            for launch in LAUNCH_FILES:
                self.assertRigApplied(dump(launch, ["rig:=" + os.path.join(tmp, "rigs", "my_rig.yaml")]), rig,
                                      launch + " absolute")
                self.assertRigApplied(dump(launch, ["rig:=rigs/my_rig.yaml"], cwd=tmp), rig, launch + " relative")
                self.assertRigApplied(dump(launch, ["rig:=./my_rig.yaml"], cwd=os.path.join(tmp, "rigs")), rig,
                                      launch + " ./relative")
        finally:
            shutil.rmtree(tmp, ignore_errors=True)

    def test_only_required_arguments_are_marked_required(self):
        for launch in LAUNCH_FILES:
            out = subprocess.run(["roslaunch", "--ros-args", PKG, launch], check=True, capture_output=True,
                                 text=True).stdout
            required, section = set(), None
            for line in out.splitlines():
                if not line.startswith(" "):
                    section = line
                elif section == "Required Arguments:":
                    required.add(line.split(":")[0].strip())
                self.assertNotIn("undocumented", line, "%s: an argument without doc: %s" % (launch, line))
            self.assertEqual(required, REQUIRED.get(launch, set()), launch)


if __name__ == "__main__":
    rostest.rosrun(PKG, "launch_params", LaunchParams, sys.argv)
