#!/usr/bin/env bash
# Installs every Debian package vi_ekf_slam needs (build, tests, demo, plots, screenshots).
# Idempotent: only packages that are not installed yet are fetched, and `apt-get update`
# runs only when something is missing. Needs root (or sudo).
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
export DEBIAN_FRONTEND=noninteractive

PKGS=(
  # toolchain and ROS-free core
  build-essential cmake pkg-config libeigen3-dev libopencv-dev libgtest-dev libbenchmark-dev
  # ROS 1 from Debian (see ../shared/PLATFORM.md)
  ros-base-dev catkin python3-catkin python3-catkin-pkg python3-empy
  libnodeletlib-dev libnodelet-dev libnodeletlib-tools
  libtf2-ros-dev libtf2-eigen-dev libtf2-msgs-dev tf2-tools libcamera-calibration-parsers-dev
  libcv-bridge-dev libimage-transport-dev librosbag-dev libroslib-dev python3-rosbag
  librostest-dev python3-rostest python3-roslaunch rosbash
  python3-dynamic-reconfigure libdynamic-reconfigure-config-init-mutex-dev
  libstd-srvs-dev libdiagnostic-updater-dev nlohmann-json3-dev libboost-dev libboost-program-options-dev libyaml-cpp-dev
  ros-sensor-msgs ros-nav-msgs ros-geometry-msgs ros-std-srvs
  python3-sensor-msgs python3-nav-msgs python3-geometry-msgs python3-std-msgs python3-tf2-msgs python3-tf2-ros
  python3-diagnostic-msgs python3-rospy python3-rosgraph python3-rospkg
  # tools, plots (python3-yaml: dynamic_reconfigure's dynparam, used by the demo), screenshots, lint
  python3-opencv python3-numpy python3-matplotlib python3-yaml
  rviz xvfb imagemagick catkin-lint clang-format clang-tidy pyflakes3 strace
)

missing=()
for p in "${PKGS[@]}"; do
  [[ "$p" == \#* ]] && continue
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install_deps: all ${#PKGS[@]} packages present"
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO=sudo; fi
echo "install_deps: installing ${#missing[@]} missing packages: ${missing[*]}"
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
