#!/usr/bin/env python3
"""The fault matrix: faulty copies of a bag, one fault class at a time (vi_ekf_slam_perturb_bag),
each run through the node's processor offline (vi_ekf_slam_run_bag, the default configuration),
against the clean run: resets, the seconds of the input the output trajectory covers, and the error
against the reference (Sim(3) RMSE against a TUM reference, or the ATE against the bag's ground
truth), with its ratio to the clean run's. Writes OUT/faults.json and OUT/faults.md (the report
schema of tools/report.py) and prints the table.

With --study, also the study on the built-in walk (8 runs, the default configuration) clean and with
each of the simulator's faults: ATE, run-averaged pose NEES and its band.

A fault of one moment (a covered lens, dim images, darkness) met at one moment is one sample: it is placed at
each of --moments (fractions of the bag), one row per moment and a row with the worst of them
(most resets, then the largest error). --sizes adds sizes of a class (covered_lens=4,6,10).

usage: fault_matrix.py --bin DIR --bag NAME=BAG[:REFERENCE.tum] [--bag ...] [--out DIR] [--classes a,b|all]
                       [--moments 0.2,0.4,0.6,0.8] [--sizes CLASS=S,S ...] [--study]
"""
import argparse
import os
import subprocess
import sys

import report

MECH = "sensor_centric_composition"
# The simulator's faults in the study (KIND:START_S:DURATION_S on the 37 s built-in walk).
STUDY_FAULTS = {"clean": [], "imu_clipped": ["imu_clipped:8:8"], "imu_gap": ["imu_gap:12:0.5"],
                "image_dropout": ["image_dropout:12:2"], "camera_covered": ["camera_covered:12:3"],
                "camera_covered_4s": ["camera_covered:12:4"], "camera_covered_10s": ["camera_covered:12:10"],
                "outlier_burst": ["outlier_burst:12:1"]}


def study_rows(bin_dir, out):
    """The study clean and with each simulated fault: {name: row}."""
    rows = {}
    for name, faults in STUDY_FAULTS.items():
        o = os.path.join(out, "study", name)
        cmd = [os.path.join(bin_dir, "vi_ekf_slam_study"), "--trajectory", "builtin", "--runs", "8", "--seed", "1",
               "--configs", "default", "--out", o] + [x for f in faults for x in ("--fault", f)]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        r = report.load(os.path.join(o, "summary.json"))
        d, band = r["runs"]["default"], r["config"]["pose_nees_band"]
        rows["study / " + name] = {"fault": name, "ate_position_m": d["ate_position_m"], "nees_pose": d["nees_pose"],
                                   "band_lo": band[0], "band_hi": band[1],
                                   "inside_band": band[0] <= d["nees_pose"] <= band[1],
                                   "consistent_fraction": d["consistent_fraction"],
                                   "nees_pose_after_outage": d.get("nees_pose_after_outage")}
        print("study / %-20s ATE %.3f m, NEES pose %.2f (band [%.2f, %.2f])" % (
            name, d["ate_position_m"], d["nees_pose"], band[0], band[1]), flush=True)
    return rows


def run(bin_dir, bag, ref, out, params=()):
    """run_bag over BAG into OUT (with PARAMS, name=value); (health row, error [m]) of the default mechanization."""
    cmd = [os.path.join(bin_dir, "vi_ekf_slam_run_bag"), "--bag", bag, "--out", out, "--mechanization", MECH,
           "--no-plots"]
    for p in params:
        cmd += ["--param", p]
    if ref:
        cmd += ["--reference", ref, "--reference-frame", "camera", "--reference-clock", "camera"]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if proc.returncode != 0:
        sys.exit("fault_matrix: run_bag failed on %s:\n%s" % (bag, proc.stdout[-3000:]))
    health = report.load(os.path.join(out, "health.json"))["runs"][MECH]
    if ref:
        error = health["references"][0].get("position_rmse_m")
    else:
        error = report.load(os.path.join(out, "summary.json"))["runs"][MECH]["ate_position_m"]
    return health, error


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", required=True, help="the folder of the vi_ekf_slam programs")
    ap.add_argument("--bag", action="append", required=True,
                    help="NAME=BAG[:REFERENCE.tum] (a reference of camera poses on the camera clock; none: the "
                         "bag's ground truth)")
    ap.add_argument("--out", default="results/faults")
    ap.add_argument("--classes", default="all")
    ap.add_argument("--keep-bags", action="store_true", help="keep the faulty copies (they are as large as the bag)")
    ap.add_argument("--moments", default="0.2,0.4,0.6,0.8",
                    help="where each fault of one moment is placed, fractions of the bag")
    ap.add_argument("--sizes", action="append", default=[],
                    help="CLASS=S,S,...: also these sizes of a class (its default size is always run)")
    ap.add_argument("--study", action="store_true", help="also the study with the simulator's faults")
    ap.add_argument("--param", action="append", default=[],
                    help="NAME=VALUE: a node parameter for every run of the bags (run_bag --param)")
    a = ap.parse_args()
    tool = os.path.join(a.bin, "vi_ekf_slam_perturb_bag")

    def names(option):  # written once in C++
        return subprocess.run([tool, option], check=True, stdout=subprocess.PIPE, text=True).stdout.split()

    every, of_one_moment = names("--list-faults"), names("--list-moment-faults")
    classes = every if a.classes == "all" else a.classes.split(",")
    extra_sizes = {}
    for spec in a.sizes:
        c, _, sizes = spec.partition("=")
        extra_sizes[c] = [float(x) for x in sizes.split(",")]
    moments = [float(x) for x in a.moments.split(",")]
    # (label, class, size or None for the default, moment or None for the class's own)
    cases = []
    placed = {}  # a fault of one moment (its label without the moment): the labels of its moments
    for c in classes:
        for size in [None] + extra_sizes.get(c, []):
            label = c if size is None else "%s %gs" % (c, size)
            for m in (moments if c in of_one_moment else [None]):
                cases.append((label if m is None else "%s @%.2f" % (label, m), c, size, m))
                if m is not None:
                    placed.setdefault(label, []).append(cases[-1][0])
    rows = {}
    for spec in a.bag:
        name, _, rest = spec.partition("=")
        bag, _, ref = rest.partition(":")
        clean_health, clean_error = run(a.bin, bag, ref, os.path.join(a.out, name, "clean"), a.param)
        for label, fault, size, moment in [("clean", "clean", None, None)] + cases:
            if fault == "clean":
                health, error = clean_health, clean_error
            else:
                folder = label.replace(" ", "_").replace("@", "at")
                faulty = os.path.join(a.out, name, folder + ".bag")
                cmd = [tool, "--bag", bag, "--out", faulty, "--fault", fault]
                cmd += ["--size", str(size)] if size is not None else []
                cmd += ["--at", str(moment)] if moment is not None else []
                subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
                health, error = run(a.bin, faulty, ref, os.path.join(a.out, name, folder), a.param)
                if not a.keep_bags:
                    os.remove(faulty)
            inputs = health.get("inputs", {})
            rows["%s / %s" % (name, label)] = {
                "bag": name, "fault": label, "resets": health["resets"],
                "output_s": health["output_s"], "input_s": health["input_s"],
                "error_m": error, "error_over_clean": error / clean_error if error and clean_error else None,
                "imu_bridged": inputs.get("imu_clipped", 0) + inputs.get("imu_implausible", 0),
                "imu_dropped_nonfinite": inputs.get("imu_nonfinite", 0), "imu_gaps": inputs.get("imu_gaps", 0),
                "image_gaps": inputs.get("image_gaps", 0),
                "images_without_features": inputs.get("images_without_features", 0),
                "divergences": inputs.get("divergences", 0),
            }
            r = rows["%s / %s" % (name, label)]
            print("%-34s resets %d, output %.1f of %.1f s, error %s m" % (
                name + " / " + label, r["resets"], r["output_s"], r["input_s"],
                "%.3f" % error if error is not None else "-"), flush=True)
        # The worst moment of each fault of one moment: most resets, then the largest error.
        for label, at_labels in placed.items():
            at = [rows["%s / %s" % (name, x)] for x in at_labels]
            worst = dict(max(at, key=lambda r: (r["resets"], r["error_m"] if r["error_m"] is not None else 1e9)))
            worst["fault"] = "%s, worst of %d moments" % (label, len(at))
            rows["%s / %s" % (name, worst["fault"])] = worst
            print("%-34s resets %d, error %s m" % (name + " / " + worst["fault"], worst["resets"],
                                                   "%.3f" % worst["error_m"] if worst["error_m"] is not None else "-"))
    tables = {"study": study_rows(a.bin, a.out)} if a.study else None
    r = report.report("faults", "Faults: one class at a time through the node's processor (%s)" % MECH,
                      {"mechanization": MECH, "classes": ",".join(classes), "params": " ".join(a.param) or "defaults"},
                      rows, tables)
    text = report.write_report(a.out, "faults", r, columns=[
        ("resets", "resets", 0), ("output_s", "output [s]", 1), ("input_s", "input [s]", 1),
        ("error_m", "error [m]", 3), ("error_over_clean", "x clean", 2), ("imu_bridged", "IMU bridged", 0),
        ("imu_dropped_nonfinite", "IMU non-finite", 0), ("imu_gaps", "IMU gaps", 0), ("image_gaps", "image gaps", 0),
        ("images_without_features", "images w/o features", 0)],
        table_columns={"study": report.STUDY_COLUMNS[:2] + ["nees_pose_after_outage"] + report.STUDY_COLUMNS[2:]},
        headings={"study": "The study on the built-in walk (8 runs, default configuration) with the simulator's faults"},
        notes=["error: Sim(3) RMSE against the reference, or the ATE against the bag's ground truth; the whole run "
               "in the continuous odom frame."])
    print()
    print(text)


if __name__ == "__main__":
    main()
