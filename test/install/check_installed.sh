#!/bin/bash
# The package as installed works without its source tree or devel space: catkin_make install into
# the workspace's install prefix, then, in an environment with only that prefix sourced and from
# another directory, the installed vi_ekf_slam_run_bag over a short rendered bag (its default
# configuration and plot script found through the package) and roslaunch replay.launch (which
# includes vi_ekf_slam.launch) recording the node's outputs, all under strace: no file of the
# source tree may be opened, and both runs must produce estimates.
#   check_installed.sh WORKSPACE
set -euo pipefail
ws=$(cd "$1" && pwd)
src=$(cd "$(dirname "$0")/../.." && pwd -P)
prefix=$ws/install
tmp=$(mktemp -d /tmp/vi_ekf_slam_install.XXXXXX)
trap 'rm -rf "$tmp"' EXIT

(cd "$ws" && PATH=/usr/bin:$PATH catkin_make install > "$tmp/install.log" 2>&1) || { tail -n 30 "$tmp/install.log"; exit 1; }

# A clean environment: only the install prefix (and the system's ROS) on the paths.
run_installed() {
  env -i HOME="$tmp" PATH=/usr/bin:/bin ROS_HOME="$tmp/ros" ROS_LOG_DIR="$tmp/log" \
    bash -c "source '$prefix/setup.bash' && cd '$tmp' && $1"
}
port=$((20000 + RANDOM % 20000))
bin=$prefix/lib/vi_ekf_slam
run_installed "$bin/vi_ekf_slam_make_bag --out short.bag --duration 5 --standing 1 > make_bag.log 2>&1"
run_installed "strace -f -qq -s 4096 -e trace=open,openat,execve -o run_bag.trace \
  $bin/vi_ekf_slam_run_bag --bag short.bag --out offline > run_bag.log 2>&1" || { cat "$tmp/run_bag.log"; exit 1; }
run_installed "strace -f -qq -s 4096 -e trace=open,openat,execve -o launch.trace \
  roslaunch -p $port vi_ekf_slam replay.launch bag:=$tmp/short.bag delay:=3 record:=$tmp/live.bag \
  imu_topic:=/imu image_topic:=/camera/image_raw camera_info_topic:=/camera/camera_info > launch.log 2>&1" \
  || { tail -n 40 "$tmp/launch.log"; exit 1; }

fail=0
for trace in run_bag launch; do
  # Opened or executed files of the source tree (the install prefix inside the workspace aside).
  if grep -v ENOENT "$tmp/$trace.trace" | grep -oE "\"$src/[^\"]*\"" | grep -v "^\"$prefix/" | sort -u | grep .; then
    echo "check_installed: the installed $trace read the source tree (above)"
    fail=1
  fi
done
grep -q '"config": "'"$prefix"'/share/vi_ekf_slam/config/vi_ekf_slam.yaml"' "$tmp/offline/health.json" ||
  { echo "check_installed: run_bag did not use the installed configuration"; cat "$tmp/offline/health.json"; fail=1; }
images=$(python3 -c "import json; print(json.load(open('$tmp/offline/health.json'))['runs']['sensor_centric_composition']['images'])")
[ "$images" -gt 20 ] || { echo "check_installed: run_bag processed $images images"; fail=1; }
[ -f "$tmp/offline/topview.png" ] || { echo "check_installed: run_bag wrote no plots"; cat "$tmp/run_bag.log"; fail=1; }
run_installed "rosbag info -y -k topics live.bag" > "$tmp/live_topics.txt"
grep -A2 "/vi_ekf_slam/odom" "$tmp/live_topics.txt" | grep -qE "messages: [1-9]" ||
  { echo "check_installed: the launched node published no odometry"; tail -n 40 "$tmp/launch.log"; fail=1; }
[ $fail -eq 0 ] && echo "check_installed: run_bag ($images images) and replay.launch ran from $prefix alone"
exit $fail
