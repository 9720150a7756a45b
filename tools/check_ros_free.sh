#!/usr/bin/env bash
# Fails if a binary links any ROS library: the core/sim/eval layers must stay ROS-free.
set -euo pipefail
bin="$1"
if ! out=$(ldd "$bin"); then echo "check_ros_free: cannot ldd $bin" >&2; exit 2; fi
ros=$(grep -Ei 'lib(roscpp|rosconsole|rostime|cpp_common|rosbag|roslib|xmlrpcpp|nodelet|tf2|cv_bridge|image_transport|message_filters|dynamic_reconfigure|diagnostic_updater|catkin)' <<<"$out" || true)
if [[ -n "$ros" ]]; then
  echo "check_ros_free: $bin links ROS libraries:" >&2
  echo "$ros" >&2
  exit 1
fi
