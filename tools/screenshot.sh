#!/usr/bin/env bash
# make screenshot: replays BAG with rviz (the demo's view, rviz/hallway_demo.rviz) under Xvfb and saves a picture
# AT seconds into the replay, then checks it shows the path, the landmark cloud and the tracks.
#   tools/screenshot.sh [BAG] [OUT.png] [AT_SECONDS]
set -euo pipefail
export PATH=/usr/bin:/bin:$PATH
BAG=$(realpath "${1:-results/bags/hallway.bag}")
OUT=$(realpath -m "${2:-results/demo/rviz.png}")
AT=${3:-25}
mkdir -p "$(dirname "$OUT")"
scratch=$(mktemp -d)
export HOME=$scratch              # rviz aborts without a HOME
disp=":$((90 + RANDOM % 9))"
Xvfb "$disp" -screen 0 1280x800x24 -nolisten tcp > "$scratch/xvfb.log" 2>&1 &
xvfb=$!
export DISPLAY=$disp
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("",0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://localhost:$port
cleanup() { kill -INT "${launch:-0}" 2>/dev/null || true; wait "${launch:-0}" 2>/dev/null || true; kill "$xvfb" 2>/dev/null || true; }
trap cleanup EXIT
stdbuf -oL roslaunch -p "$port" vi_ekf_slam replay.launch bag:="$BAG" rviz:=true rviz_config:=hallway_demo.rviz follow:=false delay:=5 keep_alive:=true \
  config:="$(rospack find vi_ekf_slam)/config/sim_hallway.yaml" > "$scratch/roslaunch.log" 2>&1 &
launch=$!
sleep $((5 + 4 + AT))             # delay + startup + replay time
import -window root "$OUT"
# rviz must go before Xvfb, or it aborts.
kill -INT "$launch"; wait "$launch" || true
kill "$xvfb"; wait "$xvfb" 2>/dev/null || true
trap - EXIT
echo "rviz screenshot: $OUT"
python3 "$(dirname "$0")/check_screenshot.py" "$OUT"
