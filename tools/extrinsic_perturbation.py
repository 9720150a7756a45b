#!/usr/bin/env python3
"""The online camera-IMU extrinsic (estimate_extrinsic) against a wrong calibration.

On a real recording: the rig file's extrinsic, and four copies of it turned by DEG degrees and moved
by M metres (about and along four different axes), each run through the node's processor offline
(vi_ekf_slam_run_bag, the rig file on the default configuration) with the extrinsic fixed and with
it estimated: resets, the error against the reference (Sim(3) RMSE of the camera poses) and, when
estimated, how far the final extrinsic is from the rig file's.

With --study, also the study on the built-in walk (8 runs, the default configuration) from each
start (the dynamic initializer, the filter's prior, the truth), the extrinsic true or DEG / M off,
fixed or estimated: ATE, run-averaged pose NEES and its band.

Writes OUT/extrinsic.json and OUT/extrinsic.md (the report schema of eval/report.h).

usage: extrinsic_perturbation.py --bin DIR --bag BAG --rig RIG.yaml --reference CAMERA_POSES.tum [--out DIR]
                                 [--deg 3] [--m 0.03] [--study]
"""
import argparse
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import report

MECH = "sensor_centric_composition"
# The perturbations' axes: each turns about one and moves along another (run_bag --extrinsic-error).
TURN_AXES = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)]
MOVE_AXES = [(0, 1, 0), (0, 0, 1), (1, 0, 0), (1, -1, 1)]


def run_bag(a, name, k, estimate):
    """Run k of the real recording (k < 0: the rig file's extrinsic, else perturbation k)."""
    out = os.path.join(a.out, "real", name)
    cmd = [os.path.join(a.bin, "vi_ekf_slam_run_bag"), "--bag", a.bag, "--out", out, "--mechanization", MECH,
           "--no-plots", "--rig", a.rig, "--param", "estimate_extrinsic=%s" % ("true" if estimate else "false"),
           "--reference", a.reference, "--reference-frame", "camera", "--reference-clock", "camera"]
    if k >= 0:
        cmd += ["--extrinsic-error", ",".join("%g" % v for v in [a.deg, a.m] + list(TURN_AXES[k]) + list(MOVE_AXES[k]))]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if proc.returncode != 0:
        sys.exit("extrinsic_perturbation: run_bag failed:\n%s" % proc.stdout[-3000:])
    h = report.load(os.path.join(out, "health.json"))["runs"][MECH]
    e = h.get("extrinsic_error", {"given": {"deg": 0.0, "m": 0.0}})
    row = {"given": name.split(" ")[0], "extrinsic": "estimated" if estimate else "fixed", "resets": h["resets"],
           "rmse_m": h["references"][0]["position_rmse_m"], "rotation_deg": h["references"][0]["rotation_rmse_deg"],
           "given_off_deg": e["given"]["deg"], "given_off_cm": 100.0 * e["given"]["m"]}
    if estimate:
        # How far the estimate ended from the rig file's (run_bag: "final", or with the rig's
        # extrinsic given, how far it moved).
        final = e.get("final") or {"deg": h["extrinsic"]["moved_deg"], "m": h["extrinsic"]["moved_m"]}
        row["final_off_deg"] = final["deg"]
        row["final_off_cm"] = 100.0 * final["m"]
    return name, row


def study_rows(a):
    rows = {}
    for start in ("dynamic", "prior", "truth"):
        for off in (False, True):
            for estimate in (False, True):
                name = "%s / %s / %s" % (start, "%g deg, %g m off" % (a.deg, a.m) if off else "true",
                                         "estimated" if estimate else "fixed")
                o = os.path.join(a.out, "study", name.replace(" / ", "_").replace(" ", "").replace(",", "_"))
                cmd = [os.path.join(a.bin, "vi_ekf_slam_study"), "--trajectory", "builtin", "--runs", "8", "--seed",
                       "1", "--configs", "default", "--init", start, "--threads", "2", "--out", o]
                cmd += ["--extrinsic-error", "%g,%g" % (a.deg, a.m)] if off else []
                cmd += ["--estimate-extrinsic"] if estimate else []
                subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                r = report.load(os.path.join(o, "summary.json"))
                d, band = r["runs"]["default"], r["config"]["pose_nees_band"]
                rows[name] = {"start": start, "given": "off" if off else "true",
                              "extrinsic": "estimated" if estimate else "fixed", "ate_position_m": d["ate_position_m"],
                              "nees_pose": d["nees_pose"], "inside_band": band[0] <= d["nees_pose"] <= band[1],
                              "consistent_fraction": d["consistent_fraction"], "band_lo": band[0],
                              "band_hi": band[1]}
                print("study / %-40s ATE %.3f m, NEES pose %.2f (band [%.2f, %.2f])" % (
                    name, d["ate_position_m"], d["nees_pose"], band[0], band[1]), flush=True)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", required=True, help="the folder of the vi_ekf_slam programs")
    ap.add_argument("--bag", required=True, help="a real recording (vi_ekf_slam_asl_to_bag)")
    ap.add_argument("--rig", required=True, help="its rig file (extrinsic_source: parameters, a T_b_c line)")
    ap.add_argument("--reference", required=True, help="camera poses on the camera clock (TUM)")
    ap.add_argument("--out", default="results/extrinsic")
    ap.add_argument("--deg", type=float, default=3.0, help="the perturbations' rotation [deg]")
    ap.add_argument("--m", type=float, default=0.03, help="the perturbations' translation [m]")
    ap.add_argument("--study", action="store_true", help="also the study on the built-in walk")
    a = ap.parse_args()
    jobs = []
    for k in range(-1, len(TURN_AXES)):
        name = "rig" if k < 0 else "perturbed%d" % (k + 1)
        jobs += [(name + " fixed", k, False), (name + " estimated", k, True)]
    rows = {}
    with ThreadPoolExecutor(2) as pool:
        for name, row in pool.map(lambda j: run_bag(a, j[0], j[1], j[2]), jobs):
            rows[name] = row
            print("%-24s resets %d, RMSE %.3f m, rotation %.2f deg%s" % (
                name, row["resets"], row["rmse_m"], row["rotation_deg"],
                ", final extrinsic %.2f deg / %.1f cm off the rig file's" % (row["final_off_deg"], row["final_off_cm"])
                if "final_off_deg" in row else ""), flush=True)
    tables = {"study": study_rows(a)} if a.study else None
    r = report.report("extrinsic", "The online camera-IMU extrinsic against a wrong calibration (%s)" % MECH,
                      {"bag": a.bag, "rig": a.rig, "deg": a.deg, "m": a.m}, rows, tables)
    text = report.write_report(a.out, "extrinsic", r, columns=[
        ("given_off_deg", "given off [deg]", 2), ("given_off_cm", "given off [cm]", 1), ("resets", "resets", 0),
        ("rmse_m", "RMSE [m]", 3), ("rotation_deg", "rotation [deg]", 2), ("final_off_deg", "final off [deg]", 2),
        ("final_off_cm", "final off [cm]", 1)],
        table_columns={"study": report.STUDY_COLUMNS},
        headings={"study": "The study on the built-in walk (8 runs, default configuration), per start"},
        notes=["RMSE, rotation: Sim(3) against the reference camera poses over the whole run; off: from the rig "
               "file's extrinsic (the calibration)."])
    print()
    print(text)


if __name__ == "__main__":
    main()
