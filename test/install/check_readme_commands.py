#!/usr/bin/python3
"""The roslaunch commands of the README and docs/ name only arguments their launch files declare:
roslaunch ignores an unknown argument without a word, so a misspelled or invented one (an
`emitter_enabled:=0` the driver's launch file does not have) silently does nothing. This
package's launch files are read from launch/; the RealSense driver's rs_camera.launch (not
installed here) from the list below. Exits 1 with each unknown argument.

usage: check_readme_commands.py [SOURCE_DIR]
"""
import glob
import os
import re
import shlex
import sys
import xml.etree.ElementTree as ET

# The arguments of realsense2_camera/launch/rs_camera.launch, realsense-ros 2.3 (ROS 1, the
# ros1-legacy branch), the driver the RealSense presets and launch/realsense.launch are for.
RS_CAMERA_ARGS = {
    "serial_no", "usb_port_id", "device_type", "json_file_path", "camera", "tf_prefix", "external_manager", "manager",
    "output", "respawn", "fisheye_width", "fisheye_height", "enable_fisheye", "depth_width", "depth_height",
    "enable_depth", "confidence_width", "confidence_height", "enable_confidence", "confidence_fps", "infra_width",
    "infra_height", "enable_infra", "enable_infra1", "enable_infra2", "infra_rgb", "color_width", "color_height",
    "enable_color", "fisheye_fps", "depth_fps", "infra_fps", "color_fps", "gyro_fps", "accel_fps", "enable_gyro",
    "enable_accel", "enable_pointcloud", "pointcloud_texture_stream", "pointcloud_texture_index",
    "allow_no_texture_points", "ordered_pc", "enable_sync", "align_depth", "publish_tf", "tf_publish_rate", "filters",
    "clip_distance", "linear_accel_cov", "initial_reset", "reconnect_timeout", "unite_imu_method", "topic_odom_in",
    "calib_odom_file", "publish_odom_tf", "stereo_module/exposure/1", "stereo_module/gain/1",
    "stereo_module/exposure/2", "stereo_module/gain/2"}


def commands(markdown):
    """The shell commands of the markdown's code blocks, continuation lines joined, comments cut."""
    out = []
    for block in re.findall(r"```(?:bash|sh)?\n(.*?)```", markdown, re.S):
        for line in block.replace("\\\n", " ").splitlines():
            try:
                words = shlex.split(line, comments=True)
            except ValueError:
                continue
            if words:
                out.append(words)
    return out


def own_launch_args(root, name):
    path = os.path.join(root, "launch", name)
    if not os.path.exists(path):
        return None
    return {a.get("name") for a in ET.parse(path).getroot().findall("arg")}


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")
    problems, checked = [], 0
    for md in [os.path.join(root, "README.md")] + sorted(glob.glob(os.path.join(root, "docs", "*.md"))):
        for words in commands(open(md).read()):
            if len(words) < 3 or words[0] != "roslaunch":
                continue
            pkg, launch = words[1], words[2]
            declared = (own_launch_args(root, launch) if pkg == "vi_ekf_slam" else
                        RS_CAMERA_ARGS if (pkg, launch) == ("realsense2_camera", "rs_camera.launch") else None)
            where = "%s: roslaunch %s %s" % (os.path.relpath(md, root), pkg, launch)
            if declared is None:
                problems.append("%s: a launch file this check does not know" % where)
                continue
            checked += 1
            for w in words[3:]:
                if ":=" in w and w.split(":=", 1)[0] not in declared:
                    problems.append("%s: no argument '%s'" % (where, w.split(":=", 1)[0]))
    for p in problems:
        print("readme commands: " + p)
    if not problems:
        print("readme commands: the %d roslaunch commands name only declared arguments" % checked)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
