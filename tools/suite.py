#!/usr/bin/env python3
"""The suite: the study (same seeds) over every pedestrian trajectory we have, in windows, and one
table per trajectory and configuration, with a worst-case row per configuration.

Cases: the built-in hallway walk; the TUM corridor, UDel ARL and EuRoC V1_01 (the non-pedestrian
check) from DATA_DIR/trajectories, each in 120 s windows; and the walks of tools/make_walks.py
(a slow start, long stands, stairs). Any other *.txt in DATA_DIR/trajectories joins the suite
with one window from its start, so the command runs unchanged on trajectories added there.

  suite.py --study BIN [--data DIR] [--out results/suite] [--runs 8] [--seed 1]
           [--configs NAME,...] [--threads N] [-- extra study options]

Writes OUT/<case>/ (the study's files), OUT/suite.json and OUT/suite.md, and prints the table.
"""
import argparse
import glob
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
PAPER = ["world_centric", "sensor_centric", "sensor_centric_composition"]
DEFAULT_CONFIGS = PAPER + [
    "sensor_centric_composition+inverse_depth+every_update",
    "sensor_centric_composition+inverse_depth+every_update+zero_velocity",
    "default",
]
WINDOW_S = 120.0
# (file in DATA_DIR/trajectories, window starts [s]); pedestrian unless said otherwise.
KNOWN = {
    "tum_corridor1_512_16_okvis.txt": [0.0, 150.0],
    "udel_arl_short.txt": [0.0, 300.0, 600.0],
    "euroc_V1_01_easy.txt": [0.0],
}


def cases(data_dir, walks_dir):
    out = [("builtin", "builtin", 0.0, 0.0)]
    traj_dir = os.path.join(data_dir, "trajectories")
    for path in sorted(glob.glob(os.path.join(traj_dir, "*.txt"))):
        name = os.path.splitext(os.path.basename(path))[0]
        for start in KNOWN.get(os.path.basename(path), [0.0]):
            out.append(("%s@%d" % (name, start), path, start, WINDOW_S))
    for path in sorted(glob.glob(os.path.join(walks_dir, "*.txt"))):
        out.append(("walk_" + os.path.splitext(os.path.basename(path))[0], path, 0.0, 0.0))
    return out


def fmt(v, digits=3):
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else ("%.*f" % (digits, v))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--study", required=True, help="the vi_ekf_slam_study binary")
    ap.add_argument("--data", default=os.environ.get("DATA_DIR", "../shared/data"))
    ap.add_argument("--out", default="results/suite")
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--configs", default=",".join(DEFAULT_CONFIGS))
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    ap.add_argument("extra", nargs="*", help="more options for every study call (after --)")
    a = ap.parse_args()

    walks = os.path.join(a.out, "walks")
    subprocess.run([sys.executable, os.path.join(HERE, "make_walks.py"), walks], check=True, stdout=subprocess.DEVNULL)
    configs = a.configs.split(",")
    results = {}
    t_start = time.time()
    for name, traj, start, window in cases(a.data, walks):
        out = os.path.join(a.out, name)
        cmd = [a.study, "--trajectory", traj, "--runs", str(a.runs), "--seed", str(a.seed), "--configs", a.configs,
               "--threads", str(a.threads), "--out", out]
        if start > 0:
            cmd += ["--start-offset", str(start)]
        if window > 0:
            cmd += ["--max-duration", str(window)]
        cmd += a.extra
        t0 = time.time()
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if proc.returncode != 0:
            sys.stderr.write(proc.stdout + proc.stderr)
            sys.exit("suite: the study failed on %s" % name)
        with open(os.path.join(out, "summary.json")) as f:
            results[name] = json.load(f)
        print("  %-34s %5.0f s" % (name, time.time() - t0), flush=True)

    # Per case: each configuration's metrics and its ATE over the best of the paper's three.
    rows, worst = [], {c: {"nees_pose": 0.0, "consistent_fraction": 1.0, "ate_ratio": 0.0, "outside_band": 0}
                       for c in configs}
    band = None
    for name, s in results.items():
        band = s["config"]["pose_nees_band"]
        paper_ate = [s[c]["ate_position_m"] for c in PAPER if c in s and s[c]["ate_position_m"] is not None]
        best_paper = min(paper_ate) if paper_ate else None
        for c in configs:
            m = s[c]
            ratio = m["ate_position_m"] / best_paper if best_paper else None
            inside = m["nees_pose"] is not None and band[0] <= m["nees_pose"] <= band[1]
            rows.append({"case": name, "config": c, "ate_m": m["ate_position_m"], "ate_posyaw_m": m["ate_posyaw_m"],
                         "nees_pose": m["nees_pose"], "consistent_fraction": m["consistent_fraction"],
                         "ate_over_best_paper": ratio, "nees_inside_band": inside})
            w = worst[c]
            nees = m["nees_pose"] if m["nees_pose"] is not None else float("inf")
            w["nees_pose"] = max(w["nees_pose"], nees)
            w["consistent_fraction"] = min(w["consistent_fraction"], m["consistent_fraction"] or 0.0)
            if ratio is not None:
                w["ate_ratio"] = max(w["ate_ratio"], ratio)
            w["outside_band"] += 0 if inside else 1
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "suite.json"), "w") as f:
        json.dump({"runs": a.runs, "seed": a.seed, "pose_nees_band": band, "rows": rows, "worst": worst,
                   "minutes": (time.time() - t_start) / 60}, f, indent=1)

    lines = ["# Suite: %d cases, %d runs each, seed %d (pose NEES 95%% band [%.2f, %.2f])" %
             (len(results), a.runs, a.seed, band[0], band[1]), "",
             "| case | configuration | ATE [m] | ATE posyaw [m] | NEES pose | consistent | ATE / best paper |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %s | %s | %s | %s | %s%s | %s | %s |" % (
            r["case"], r["config"], fmt(r["ate_m"]), fmt(r["ate_posyaw_m"]), fmt(r["nees_pose"], 2),
            "" if r["nees_inside_band"] else " (!)", fmt(r["consistent_fraction"], 2),
            fmt(r["ate_over_best_paper"], 2)))
    lines += ["", "Worst case over the %d cases:" % len(results), "",
              "| configuration | max NEES pose | cases outside the band | min consistent | max ATE / best paper |",
              "|---|---|---|---|---|"]
    for c in configs:
        w = worst[c]
        lines.append("| %s | %s | %d | %s | %s |" % (c, fmt(w["nees_pose"], 2), w["outside_band"],
                                                     fmt(w["consistent_fraction"], 2), fmt(w["ate_ratio"], 2)))
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "suite.md"), "w") as f:
        f.write(text)
    print(text)
    print("suite: %.1f min, written to %s" % ((time.time() - t_start) / 60, a.out))


if __name__ == "__main__":
    main()
