#!/usr/bin/env python3
"""The fault matrix: faulty copies of a bag, one fault class at a time (vi_ekf_slam_perturb_bag),
each run through the node's processor offline (vi_ekf_slam_run_bag, the default configuration),
against the clean run: resets, the seconds of the input the output trajectory covers, and the error
against the reference (Sim(3) RMSE against a TUM reference, or the ATE against the bag's ground
truth), with its ratio to the clean run's. Writes OUT/faults.json and OUT/faults.md (the report
schema of tools/report.py) and prints the table.

usage: fault_matrix.py --bin DIR --bag NAME=BAG[:REFERENCE.tum] [--bag ...] [--out DIR] [--classes a,b|all]
"""
import argparse
import json
import os
import subprocess
import sys

import report

MECH = "sensor_centric_composition"
CLASSES = ["clipped_imu", "sensor_gaps", "covered_lens", "nan_imu", "dim_images", "lossy_link"]


def run(bin_dir, bag, ref, out):
    """run_bag over BAG into OUT; (health row, error [m]) of the default mechanization."""
    cmd = [os.path.join(bin_dir, "vi_ekf_slam_run_bag"), "--bag", bag, "--out", out, "--mechanization", MECH,
           "--no-plots"]
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
    a = ap.parse_args()
    classes = CLASSES if a.classes == "all" else a.classes.split(",")
    rows = {}
    for spec in a.bag:
        name, _, rest = spec.partition("=")
        bag, _, ref = rest.partition(":")
        clean_health, clean_error = run(a.bin, bag, ref, os.path.join(a.out, name, "clean"))
        for fault in ["clean"] + classes:
            if fault == "clean":
                health, error = clean_health, clean_error
            else:
                faulty = os.path.join(a.out, name, fault + ".bag")
                subprocess.run([os.path.join(a.bin, "vi_ekf_slam_perturb_bag"), "--bag", bag, "--out", faulty,
                                "--fault", fault], check=True, stdout=subprocess.DEVNULL)
                health, error = run(a.bin, faulty, ref, os.path.join(a.out, name, fault))
                if not a.keep_bags:
                    os.remove(faulty)
            inputs = health.get("inputs", {})
            rows["%s / %s" % (name, fault)] = {
                "bag": name, "fault": fault, "resets": health["resets"],
                "output_s": health["output_s"], "input_s": health["input_s"],
                "error_m": error, "error_over_clean": error / clean_error if error and clean_error else None,
                "imu_bridged": inputs.get("imu_clipped", 0) + inputs.get("imu_implausible", 0),
                "imu_dropped_nonfinite": inputs.get("imu_nonfinite", 0), "imu_gaps": inputs.get("imu_gaps", 0),
                "image_gaps": inputs.get("image_gaps", 0),
                "images_without_features": inputs.get("images_without_features", 0),
                "divergences": inputs.get("divergences", 0),
            }
            r = rows["%s / %s" % (name, fault)]
            print("%-28s resets %d, output %.1f of %.1f s, error %s m" % (
                name + " / " + fault, r["resets"], r["output_s"], r["input_s"],
                "%.3f" % error if error is not None else "-"), flush=True)
    r = report.report("faults", "Faults: one class at a time through the node's processor (%s)" % MECH,
                      {"mechanization": MECH, "classes": ",".join(classes)}, rows)
    text = report.write_report(a.out, "faults", r, columns=[
        ("resets", "resets", 0), ("output_s", "output [s]", 1), ("input_s", "input [s]", 1),
        ("error_m", "error [m]", 3), ("error_over_clean", "x clean", 2), ("imu_bridged", "IMU bridged", 0),
        ("imu_dropped_nonfinite", "IMU non-finite", 0), ("imu_gaps", "IMU gaps", 0), ("image_gaps", "image gaps", 0),
        ("images_without_features", "images w/o features", 0)],
        notes=["error: Sim(3) RMSE against the reference, or the ATE against the bag's ground truth; the whole run "
               "in the continuous odom frame."])
    print()
    print(text)
    with open(os.path.join(a.out, "faults_rows.json"), "w") as f:
        json.dump(rows, f)


if __name__ == "__main__":
    main()
