#!/usr/bin/python3
"""Whole-pipeline numbers for `make bench`:
  - offline: vi_ekf_slam_run_bag on the hallway bag pinned to one core (taskset), its real-time
    factor and filter+tracker time per frame;
  - offline on a real 1280x720 recording (--real-bag, the make realdata bag), pinned to one core:
    real-time factor, time per image and its tracking share (from health.json: no ground truth);
  - the same two with the map kept (keep_map: dormant points fill the state up to its bound): time
    per frame and what keeping the map adds to it;
  - live: one `rosbag play` replay through the nodelet (tools/demo.py's replay), and the latency
    of every published odometry message: the time the recorder received it minus its stamp (the
    image time). rosbag play drives /clock at 100 Hz, so single values are quantized to 10 ms;
    the median and 99th percentile over ~1000 frames are still meaningful.

usage: pipeline.py --bag BAG --config YAML --out DIR [--real-bag BAG]   (writes DIR/pipeline.json)
"""
import argparse
import json
import os
import subprocess
import sys

import rosbag

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools"))
from demo import replay  # noqa: E402

MECH = "sensor_centric_composition"


def percentile(sorted_values, q):
    return sorted_values[min(len(sorted_values) - 1, int(q * (len(sorted_values) - 1)))]


def odom_latency_ms(bag_path, topic="/vi_ekf_slam/odom"):
    lat = []
    with rosbag.Bag(bag_path) as bag:
        for _, msg, t in bag.read_messages(topics=[topic]):
            lat.append((t - msg.header.stamp).to_sec() * 1000.0)
    lat.sort()
    return lat


def offline(bag, out, summary_file, extra=()):
    """vi_ekf_slam_run_bag on one core; the default mechanization's entry of its summary file."""
    subprocess.run(["taskset", "-c", "0", "rosrun", "vi_ekf_slam", "vi_ekf_slam_run_bag", "--bag", bag,
                    "--mechanization", MECH, "--out", out, "--no-plots"] + list(extra),
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, summary_file)) as f:
        return json.load(f)["runs"][MECH]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bag", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--real-bag", default="")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    result = {}
    s = offline(a.bag, os.path.join(a.out, "offline"), "summary.json", ["--config", a.config])
    result["offline_real_time_factor_1core"] = round(s["real_time_factor"], 2)
    result["offline_ms_per_frame_mean"] = round(s["processing_ms_mean"], 2)
    result["offline_ms_per_frame_p95"] = round(s["processing_ms_p95"], 2)
    result["offline_tracker_ms_per_frame"] = round(s["tracker_ms_mean"], 2)
    k = offline(a.bag, os.path.join(a.out, "offline_keep_map"), "summary.json",
                ["--config", a.config, "--param", "keep_map=true"])
    result["offline_keep_map_ms_per_frame_mean"] = round(k["processing_ms_mean"], 2)
    result["offline_keep_map_extra_ms_per_frame"] = round(k["processing_ms_mean"] - s["processing_ms_mean"], 2)
    if a.real_bag:
        h = offline(a.real_bag, os.path.join(a.out, "offline_real"), "health.json")
        result["real_1280x720_real_time_factor_1core"] = round(h["real_time_factor"], 2)
        result["real_1280x720_ms_per_image_mean"] = round(h["processing_ms_mean"], 2)
        result["real_1280x720_tracker_ms_per_image"] = round(h["tracker_ms_mean"], 2)
        hk = offline(a.real_bag, os.path.join(a.out, "offline_real_keep_map"), "health.json",
                     ["--param", "keep_map=true"])
        result["real_1280x720_keep_map_ms_per_image_mean"] = round(hk["processing_ms_mean"], 2)
        result["real_1280x720_keep_map_extra_ms_per_image"] = round(hk["processing_ms_mean"] - h["processing_ms_mean"], 2)
    with open(os.path.join(a.out, "roslaunch.log"), "w") as log:
        rec = replay(os.path.abspath(a.bag), MECH, a.out, os.path.abspath(a.config), False, 1.0, log)
    lat = odom_latency_ms(rec)
    if lat:
        result["live_latency_ms_median"] = round(percentile(lat, 0.5), 1)
        result["live_latency_ms_p99"] = round(percentile(lat, 0.99), 1)
        result["live_frames"] = len(lat)
    with open(os.path.join(a.out, "pipeline.json"), "w") as f:
        json.dump(result, f, indent=1)
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
