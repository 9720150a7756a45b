#!/usr/bin/env bash
# make screenshot: replays BAG with rviz under Xvfb and saves a picture AT seconds into the replay,
# then checks it shows the path, the landmark cloud and the tracks (check_screenshot.py).
#   tools/screenshot.sh [BAG] [OUT.png] [AT_SECONDS] [REPLAY_ARGS...]
# REPLAY_ARGS: arguments of replay.launch; default: the demo's (the rendered walk's configuration and
# the hallway view, rviz/hallway_demo.rviz). E.g. for a real recording in the default view, which
# follows the rig: rig:=dmvio_handheld. SCREENSHOT_CHECK_ARGS: more options of check_screenshot.py
# (--pose for the default view).
set -euo pipefail
export PATH=/usr/bin:/bin:$PATH
BAG=$(realpath "${1:-results/bags/hallway.bag}")
OUT=$(realpath -m "${2:-results/demo/rviz.png}")
AT=${3:-25}
shift $(( $# < 3 ? $# : 3 ))
if [ $# -gt 0 ]; then
  replay_args=("$@")
else
  replay_args=(rviz_config:=hallway_demo.rviz follow:=false config:="$(rospack find vi_ekf_slam)/config/sim_hallway.yaml")
fi
mkdir -p "$(dirname "$OUT")"
scratch=$(mktemp -d)
export HOME=$scratch              # rviz aborts without a HOME
export XDG_RUNTIME_DIR=$scratch   # (Qt makes /tmp/runtime-USER otherwise)
disp=":$((90 + RANDOM % 9))"
Xvfb "$disp" -screen 0 1280x800x24 -nolisten tcp > "$scratch/xvfb.log" 2>&1 &
xvfb=$!
export DISPLAY=$disp
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("",0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://localhost:$port
cleanup() { kill -INT "${launch:-0}" 2>/dev/null || true; wait "${launch:-0}" 2>/dev/null || true; kill "$xvfb" 2>/dev/null || true; }
trap cleanup EXIT
stdbuf -oL roslaunch -p "$port" vi_ekf_slam replay.launch bag:="$BAG" rviz:=true delay:=5 keep_alive:=true \
  "${replay_args[@]}" > "$scratch/roslaunch.log" 2>&1 &
launch=$!
sleep $((5 + 4 + AT))             # delay + startup + replay time
import -window root "$OUT"
# rviz must go before Xvfb, or it aborts.
kill -INT "$launch"; wait "$launch" || true
kill "$xvfb"; wait "$xvfb" 2>/dev/null || true
trap - EXIT
echo "rviz screenshot: $OUT"
# The scratch folder (logs, rviz's HOME) is kept when the picture fails the check.
# shellcheck disable=SC2086
if python3 "$(dirname "$0")/check_screenshot.py" "$OUT" ${SCREENSHOT_CHECK_ARGS:-}; then
  rm -rf "$scratch"
else
  echo "logs kept in $scratch"
  exit 1
fi
