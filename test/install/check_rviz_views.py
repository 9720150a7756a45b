#!/usr/bin/python3
"""The shipped rviz views: the default one (rviz/vi_ekf_slam.rviz) is at a pedestrian's scale and
follows the rig once tools/rviz_follow.py sets its target frame; the demo's view
(rviz/hallway_demo.rviz) keeps the rendered hallway in sight. Exits 1 with what is wrong.

usage: check_rviz_views.py [SOURCE_DIR]
"""
import os
import sys

import yaml

ROOT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tools"))
from rviz_follow import followed_view  # noqa: E402


def view(text):
    return yaml.safe_load(text)["Visualization Manager"]["Views"]["Current"]


def main():
    problems = []
    default = open(os.path.join(ROOT, "rviz", "vi_ekf_slam.rviz")).read()
    demo = open(os.path.join(ROOT, "rviz", "hallway_demo.rviz")).read()
    v = view(default)
    if v["Distance"] > 15.0:
        problems.append("the default view is %g m away: not a pedestrian's scale" % v["Distance"])
    followed = yaml.safe_load(followed_view(default, "camera_link"))
    if followed["Visualization Manager"]["Views"]["Current"]["Target Frame"] != "camera_link":
        problems.append("rviz_follow does not set the view's target frame")
    grid = [d for d in followed["Visualization Manager"]["Displays"] if d.get("Class") == "rviz/Grid"]
    if grid and grid[0]["Reference Frame"] != "<Fixed Frame>":
        problems.append("rviz_follow moved the grid off the fixed frame")
    if followed["Visualization Manager"]["Global Options"]["Fixed Frame"] != "odom":
        problems.append("the fixed frame is not odom")
    d = view(demo)
    if d["Distance"] < 30.0:
        problems.append("the demo's view no longer shows the whole hallway")
    for p in problems:
        print("rviz views: " + p)
    if not problems:
        print("rviz views: the default follows the rig at %g m, the demo's shows the hallway at %g m"
              % (v["Distance"], d["Distance"]))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
