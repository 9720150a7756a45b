#!/usr/bin/python3
"""The package's declared dependencies (package.xml) are exactly what it uses: the ROS packages of
CMakeLists.txt's find_package, of the C++ includes (src, include, tools, test, bench), of the
Python imports (tools, bench, test) and of the launch files (pkg="..."), and the system libraries
and Python modules behind them. Prints what is missing and what is declared for nothing; exits 1
on either.

usage: check_package_xml.py [SOURCE_DIR]
"""
import ast
import glob
import os
import re
import sys
import xml.etree.ElementTree as ET

# System dependencies by how the code uses them, as rosdep keys.
CMAKE_PACKAGES = {"Eigen3": "eigen", "Boost": "boost", "yaml-cpp": "yaml-cpp", "OpenCV": "libopencv-dev",
                  "benchmark": "benchmark", "rostest": "rostest", "roslaunch": "roslaunch", "catkin": "catkin"}
HEADERS = {"nlohmann": "nlohmann-json-dev", "gtest": "gtest", "benchmark": "benchmark", "yaml-cpp": "yaml-cpp",
           "Eigen": "eigen", "opencv2": "libopencv-dev", "boost": "boost"}
PYTHON_MODULES = {"numpy": "python3-numpy", "matplotlib": "python3-matplotlib", "cv2": "python3-opencv",
                  "yaml": "python3-yaml"}
# Packages catkin's message generation brings in (package.xml format 3 names them explicitly).
IMPLIED = {"message_generation", "message_runtime"}
ROS_SHARE = "/usr/share"


def is_ros_package(name):
    return os.path.exists(os.path.join(ROS_SHARE, name, "package.xml"))


def declared(root):
    tree = ET.parse(os.path.join(root, "package.xml"))
    tags = ("depend", "build_depend", "exec_depend", "test_depend", "buildtool_depend", "build_export_depend")
    return {e.text.strip() for t in tags for e in tree.getroot().findall(t)}


def from_cmake(root):
    text = open(os.path.join(root, "CMakeLists.txt")).read()
    used = set()
    for name, rest in re.findall(r"find_package\((\S+)([^)]*)\)", text):
        if name in CMAKE_PACKAGES:
            used.add(CMAKE_PACKAGES[name])
    components = re.search(r"set\(ROS_COMPONENTS(.*?)\)", text, re.S)
    used |= set(components.group(1).split()) if components else set()
    used |= {p for p in re.findall(r"COMPONENTS \$\{ROS_COMPONENTS\} (\w+)", text)}
    return used


def from_includes(root):
    used = set()
    for path in glob.glob(os.path.join(root, "**", "*.[ch]*"), recursive=True):
        if "/.catkin_ws/" in path or "/results/" in path:
            continue
        for top in re.findall(r'#include [<"]([\w\-]+)/', open(path, errors="replace").read()):
            if top == "vi_ekf_slam":
                continue
            if top in HEADERS:
                used.add(HEADERS[top])
            elif is_ros_package(top):
                used.add(top)
    return used


def from_python(root):
    used, local = set(), set()
    files = [f for d in ("tools", "bench", "test") for f in glob.glob(os.path.join(root, d, "**", "*.py"), recursive=True)]
    local = {os.path.splitext(os.path.basename(f))[0] for f in files} | {"vi_ekf_slam"}
    for path in files:
        for node in ast.walk(ast.parse(open(path).read())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            for n in names:
                top = n.split(".")[0]
                if top in local or top in sys.stdlib_module_names:
                    continue
                used.add(PYTHON_MODULES.get(top, top))
    return used


def from_launch(root):
    used = set()
    for path in glob.glob(os.path.join(root, "launch", "*.launch")) + glob.glob(os.path.join(root, "test", "**", "*.launch"),
                                                                                  recursive=True) + glob.glob(
            os.path.join(root, "test", "**", "*.test"), recursive=True):
        used |= {p for p in re.findall(r'pkg="([\w]+)"', open(path).read()) if p != "vi_ekf_slam"}
        if re.search(r"<test ", open(path).read()):
            used.add("rostest")
    if glob.glob(os.path.join(root, "rviz", "*.rviz")):
        used.add("rviz")  # the shipped views, started by replay.launch
    return used


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")
    have = declared(root)
    sources = {"CMakeLists.txt": from_cmake(root), "C++ includes": from_includes(root),
               "Python imports": from_python(root), "launch files": from_launch(root)}
    used = set().union(*sources.values()) | IMPLIED
    missing = sorted(used - have)
    unused = sorted(have - used)
    for name in missing:
        where = [k for k, v in sources.items() if name in v]
        print("package.xml lacks %s (used by %s)" % (name, ", ".join(where)))
    for name in unused:
        print("package.xml declares %s, which nothing uses" % name)
    if missing or unused:
        return 1
    print("package.xml: %d dependencies, each used, none missing" % len(have))
    return 0


if __name__ == "__main__":
    sys.exit(main())
