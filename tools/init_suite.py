#!/usr/bin/env python3
"""Starting mid-walk (docs/initialization.md): on each trajectory, the study from N random start
times (RUNS runs in all, the same seeds) three times with the node's default configuration: started
as the node starts (`--init dynamic`: a recent interval at rest, else the dynamic initializer), from
the true state (`--init truth`), and from an error drawn from the filter's prior (`--init prior`,
the same biased IMU as the first: a start that knows the state to the prior's sigmas, but not the
IMU's biases). One table: initialized within 1.5 s, pose NEES over the first 10 s after the
initialization against its 95% band, and the ATE of the rest of the run against the other starts.

The dynamic start knows neither position nor yaw (they are registered to the truth with an error
drawn from the prior), so the ATE compared is the posyaw one (4-DoF aligned), which the
registration does not enter.

  init_suite.py --study BIN [--data DIR] [--out results/init_suite] [--runs 20] [--starts 5]
                [--window 20] [--seed 1] [--threads N]
"""
import argparse
import os
import subprocess
import sys

from study_cli import add_study_options, resolve_tools
import report
from suite import trajectory_files, walk_files, write_walks

# The built-in walk, every TUM file in DATA_DIR/trajectories (a file added there joins; short names
# for the known ones) and the suite's generated walks.
SHORT_NAMES = {"tum_corridor1_512_16_okvis": "tum_corridor", "euroc_V1_01_easy": "euroc_V1_01",
               "udel_arl_short": "udel_arl"}
MIN_FRACTION_WITHIN = 0.95  # of the runs initialized within INIT_WITHIN_S
INIT_WITHIN_S = 1.5


def study(a, traj, init, out):
    cmd = [a.study, "--trajectory", traj, "--runs", str(a.runs), "--seed", str(a.seed), "--configs", "default",
           "--threads", str(a.threads), "--random-starts", str(a.starts), "--max-duration", str(a.window),
           "--init", init, "--out", out]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout + proc.stderr)
        sys.exit("init_suite: the study failed: " + " ".join(cmd))
    return report.load(os.path.join(out, "summary.json"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_study_options(ap, out="results/init_suite", runs=20)
    ap.add_argument("--starts", type=int, default=5)
    ap.add_argument("--window", type=float, default=20.0, help="seconds from each start")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    a = resolve_tools(ap.parse_args())

    rows = []
    trajectories = [("builtin", "builtin")]
    files = trajectory_files(a.data)
    if not files:
        print("  no trajectory files in %s: the built-in walk only" % os.path.join(a.data, "trajectories"))
    for path in files:
        stem = os.path.splitext(os.path.basename(path))[0]
        trajectories.append((SHORT_NAMES.get(stem, stem), path))
    # The suite's generated walks (sim/generated_walks.h): a slow start, a crawl, stops, stairs, a fast walk, a stairwell.
    trajectories += walk_files(write_walks(a.make_walks, a.out))
    for name, traj in trajectories:
        dyn = study(a, traj, "dynamic", os.path.join(a.out, name, "dynamic"))
        ref = study(a, traj, "truth", os.path.join(a.out, name, "truth"))
        pri = study(a, traj, "prior", os.path.join(a.out, name, "prior"))
        d, r, p = dyn["runs"]["default"], ref["runs"]["default"], pri["runs"]["default"]
        delays = [x for x in d["init_delay_s"] if x is not None]
        fast = sum(1 for x in delays if x <= INIT_WITHIN_S)
        band = dyn["config"]["pose_nees_band"]
        rows.append({
            "trajectory": name, "starts_s": ", ".join("%g" % s for s in dyn["config"]["start_offsets_s"]),
            "runs": d["runs_started"],
            "initialized": len(delays), "initialized_within_1_5_s": fast,
            "init_delay_max_s": max(delays) if delays else None,
            "nees_pose_first_10s": d["nees_pose_first_10s"], "nees_band": band,
            "ate_posyaw_m": d["ate_posyaw_m"], "truth_ate_posyaw_m": r["ate_posyaw_m"],
            "ate_m": d["ate_position_m"], "truth_ate_m": r["ate_position_m"],
            "prior_ate_posyaw_m": p["ate_posyaw_m"],
        })
        print("  %s done" % name, flush=True)
    for row in rows:
        lo, hi = row["nees_band"]
        row["nees_inside_band"] = row["nees_pose_first_10s"] is not None and lo <= row["nees_pose_first_10s"] <= hi
        row["ate_posyaw_over_truth_start"] = (row["ate_posyaw_m"] / row["truth_ate_posyaw_m"]
                                              if row["truth_ate_posyaw_m"] else None)
    within, runs = sum(r["initialized_within_1_5_s"] for r in rows), sum(r["runs"] for r in rows)
    notes = []
    if runs:
        notes.append("All trajectories: %d/%d runs initialized within %g s (%.1f%%; at least %g%% asked)%s" % (
            within, runs, INIT_WITHIN_S, 100.0 * within / runs, 100.0 * MIN_FRACTION_WITHIN,
            "" if within >= MIN_FRACTION_WITHIN * runs else " (!)"))
    r = report.report("init_suite", "Starting mid-walk: %d runs from %d random starts per trajectory, %g s each, "
                      "seed %d" % (a.runs, a.starts, a.window, a.seed),
                      {"runs": a.runs, "starts": a.starts, "window_s": a.window, "seed": a.seed},
                      {row["trajectory"]: row for row in rows})
    columns = [("starts_s", "starts [s]", 0), ("initialized_within_1_5_s", "initialized within 1.5 s", 0),
               ("runs", "runs", 0), ("init_delay_max_s", "max delay [s]", 2),
               ("nees_pose_first_10s", "NEES pose, first 10 s", 2), ("nees_inside_band", "inside band", 0),
               ("ate_posyaw_m", "ATE posyaw, dynamic start [m]", 3),
               ("truth_ate_posyaw_m", "ATE posyaw, truth start [m]", 3),
               ("ate_posyaw_over_truth_start", "ratio", 2), ("ate_m", "ATE, dynamic start [m]", 3),
               ("truth_ate_m", "ATE, truth start [m]", 3), ("prior_ate_posyaw_m", "ATE posyaw, prior start [m]", 3)]
    text = report.write_report(a.out, "init_suite", r, columns=columns, notes=notes)
    print(text)


if __name__ == "__main__":
    main()
