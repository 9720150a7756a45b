#!/usr/bin/env python3
"""docs/results.md from the result files of `make demo`, `make realdata`, `make suite` and
`make bench` (results/*/summary.json and friends), and the README's copy of its first section.

Every current number of the project lives in docs/results.md; the README quotes its first
section ("At a glance") between the markers below, and `--check` fails while the quote differs.

usage: results_page.py [--results results] [--out docs/results.md] [--readme README.md]
       results_page.py --check [--out docs/results.md] [--readme README.md]
"""
import argparse
import datetime
import os
import sys

import report

BEGIN = "<!-- results: the first section of docs/results.md (make results); do not edit here -->"
END = "<!-- /results -->"
GLANCE = "## At a glance"
MECHANIZATIONS = ["world_centric", "sensor_centric", "sensor_centric_composition"]


def load(path):
    return report.load(path)


def stamp(path):
    """When and on which commit the file's numbers were measured."""
    when = datetime.datetime.fromtimestamp(os.path.getmtime(path)).strftime("%Y-%m-%d %H:%M")
    commit = load(path).get("commit") if path.endswith(".json") else None
    return "%s, commit %s" % (when, commit) if commit else "%s (no commit recorded)" % when


def f(v, digits=3):
    return "-" if v is None else "%.*f" % (digits, v)


def demo_section(results):
    path = os.path.join(results, "demo", "summary.json")
    s = load(path)["runs"]
    rows = [(m, s[m]) for m in MECHANIZATIONS if m in s]
    glance = ["| run | ATE [m] | final error [m] | NEES pose (dim 6) | ms per image (p95) |",
              "|---|---|---|---|---|"]
    full = ["| run | ATE [m] | ATE posyaw [m] | ATE rot [deg] | final error [m] | NEES pos | NEES rot | NEES pose "
            "| gamma | map error median [m] | ms per image (p95) |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for m, r in rows:
        ms = "%.1f (%.1f)" % (r["processing_ms_mean"], r["processing_ms_p95"])
        glance.append("| %s | %s | %s | %s | %s |" % (m, f(r["ate_position_m"]), f(r["final_position_error_m"]),
                                                      f(r["nees_pose"], 2), ms))
        full.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            m, f(r["ate_position_m"]), f(r["ate_posyaw_m"]), f(r["ate_orientation_deg"]),
            f(r["final_position_error_m"]), f(r["nees_position"], 2), f(r["nees_orientation"], 2),
            f(r["nees_pose"], 2), f(r.get("final_scale_ratio")), f(r.get("map_error_median_m")), ms))
    distance = rows[0][1]["distance_m"] if rows else 0.0
    text = ["## The demo (`make demo`)", "",
            "The rendered hallway walk (%.0f m) played live through the nodelet, once per mechanization; "
            "`results/demo/summary.json`, %s. The world-centric filter diverges: its row changes from replay "
            "to replay." % (distance, stamp(path)), ""] + full
    return glance, text


REALDATA_RUNS = [("defaults", "defaults"), ("rig", "rig file"), ("defaults_keep_map", "defaults, map kept"),
                 ("rig_keep_map", "rig file, map kept"),
                 ("defaults_keep_map_reset_30s", "defaults, map kept, reset at 30 s")]


def realdata_section(results):
    runs = []
    for sub, _ in REALDATA_RUNS:
        path = os.path.join(results, "realdata", sub, "health.json")
        if os.path.exists(path):
            for name, r in load(path)["runs"].items():
                runs.append((sub, name, r, path))
    if not runs:
        raise FileNotFoundError("results/realdata/*/health.json (make realdata)")
    text = ["## The real hand-held recording (`make realdata`)", "",
            "50 s of the DM-VIO hand-held recording through the node's processor (`run_bag`), against the SfM "
            "reference (camera poses) and OpenVINS tuned for the recording (IMU poses), Sim(3)-aligned; "
            "RMSE in the estimate's metres; `results/realdata/*/health.json`, %s. OpenVINS against the SfM "
            "reference: 0.073 m (the data set's README). First 10 s scale: the first 10 s window's scale against "
            "the SfM reference over the later windows' median, each window aligned on its own (1: the start is "
            "at the rest's scale)." % stamp(runs[0][3]), "",
            "| configuration | run | resets | SfM RMSE [m] | SfM from 15 s [m] | SfM from 20 s [m] | OpenVINS RMSE [m] "
            "| rotation vs SfM [deg] | first 10 s scale | time offset [s] | relocalizations | real-time factor |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    headline = None
    for sub, name, r, _ in runs:
        refs = r.get("references", [])

        def ref(word, from_s=None):
            for x in refs:
                if word in os.path.basename(x["file"]) and x.get("from_s") == from_s and "position_rmse_m" in x:
                    return x
            return None
        sfm, sfm15, sfm20, ov = ref("sfm"), ref("sfm", 15.0), ref("sfm", 20.0), ref("openvins")
        text.append("| %s | %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %.1f |" % (
            dict(REALDATA_RUNS)[sub], name, r["resets"], f(sfm and sfm["position_rmse_m"]),
            f(sfm15 and sfm15["position_rmse_m"]), f(sfm20 and sfm20["position_rmse_m"]),
            f(ov and ov["position_rmse_m"]), f(sfm and sfm["rotation_rmse_deg"], 2),
            f(sfm and sfm.get("first_window_scale_ratio"), 2), f(r["time_offset_s"], 4),
            r.get("relocalizations", "-"), r["real_time_factor"]))
        if sub == "defaults" and name == "sensor_centric_composition" and sfm:
            headline = (sfm["position_rmse_m"], r["time_offset_s"], r["resets"])
    return headline, text


def suite_section(results):
    path = os.path.join(results, "suite", "suite.json")
    r = load(path)
    s = {"rows": list(r["runs"].values()), "worst": r["tables"]["worst"]}
    band = r["config"]["pose_nees_band"]
    configs = list(s["worst"].keys())
    text = ["## The suite (`make suite`)", "",
            "The study on every walk we have, %d runs per case, seed %d; pose NEES band [%.2f, %.2f]; "
            "`results/suite/suite.json`, %s." % (r["config"]["runs"], r["config"]["seed"], band[0], band[1],
                                                stamp(path)), "",
            "| case | configuration | ATE [m] | ATE posyaw [m] | NEES pose | consistent | ATE / best of the paper's |",
            "|---|---|---|---|---|---|---|"]
    for r in s["rows"]:
        if r.get("failed"):
            text.append("| %s | %s | failed: %s | | | | |" % (r["case"], r["config"], r["failed"]))
            continue
        text.append("| %s | %s | %s | %s | %s | %s | %s |" % (
            r["case"], r["config"], f(r["ate_position_m"]), f(r["ate_posyaw_m"]), f(r["nees_pose"], 2),
            f(r["consistent_fraction"], 2), f(r["ate_over_best_paper"], 2)))
    cases = len({r["case"] for r in s["rows"]})
    text += ["", "Worst case over the %d cases:" % cases, "",
             "| configuration | max NEES pose | cases outside the band | min consistent | max ATE / best of the paper's |",
             "|---|---|---|---|---|"]
    for c in configs:
        w = s["worst"][c]
        text.append("| %s | %s | %d | %s | %s |" % (c, f(w["nees_pose"], 2), w["outside_band"],
                                                   f(w["consistent_fraction"], 2), f(w["ate_ratio"], 2)))
    d = s["worst"].get("default")
    headline = None
    if d:
        headline = (cases - d["outside_band"] - d["failed"], cases, d["nees_pose"], band)
    return headline, text


def bench_section(results):
    path = os.path.join(results, "bench", "summary.json")
    r = load(path)
    text = ["## Speed (`make bench`)", "",
            "One core (`taskset -c 0`), median CPU time; `results/bench/summary.json`, %s, %s." % (
                stamp(path), r["config"].get("cpu_model") or "this machine"), "",
            "| benchmark | median [us] |", "|---|---|"]
    for b in r["runs"].values():
        text.append("| %s | %.1f |" % (b["name"], b["median_us"]))
    exponents = r.get("tables", {}).get("exponents", {})
    if exponents:
        text += ["", "| growth with the map size N | exponent |", "|---|---|"]
        for fam, e in exponents.items():
            text.append("| %s | %s |" % (fam, f(e["exponent"], 2)))
    p = r.get("tables", {}).get("pipeline", {}).get("pipeline") or {}
    if p:
        text += ["", "| the whole pipeline (bench/pipeline.py) | value |", "|---|---|"]
        for k in sorted(p):
            text.append("| %s | %s |" % (k, p[k]))
    return text


def faults_section(results):
    """The fault matrix (make faults), if it was run: (worst resets and error ratio, text)."""
    path = os.path.join(results, "faults", "faults.json")
    if not os.path.exists(path):
        return None, []
    r = load(path)
    text = ["## Faults (`make faults`)", "",
            "Faulty copies of the real recording and of the rendered walk, one fault class at a time, through the "
            "node's processor (%s); error: Sim(3) RMSE against the SfM reference (real) or ATE against the ground "
            "truth (rendered), the whole run in the continuous odom frame; `results/faults/faults.json`, %s." % (
                r["config"]["mechanization"], stamp(path)), "",
            "| bag / fault | resets | output [s] of input [s] | error [m] | x clean | IMU bridged | IMU non-finite "
            "| IMU gaps | image gaps | images without features |", "|---|---|---|---|---|---|---|---|---|---|"]
    for name, x in r["runs"].items():
        text.append("| %s | %d | %.1f of %.1f | %s | %s | %d | %d | %d | %d | %d |" % (
            name, x["resets"], x["output_s"], x["input_s"], f(x["error_m"]), f(x["error_over_clean"], 2),
            x["imu_bridged"], x["imu_dropped_nonfinite"], x["imu_gaps"], x["image_gaps"],
            x["images_without_features"]))
    study = r.get("tables", {}).get("study", {})
    if study:
        text += ["", "The study on the built-in walk (8 runs, seed 1, default configuration) with the simulator's "
                 "faults (NEES after: the run-averaged pose NEES over the 5 s after a covered camera):", "",
                 "| fault | ATE [m] | NEES pose | NEES after | band | consistent |", "|---|---|---|---|---|---|"]
        for x in study.values():
            text.append("| %s | %s | %s | %s | [%.2f, %.2f] | %s |" % (
                x["fault"], f(x["ate_position_m"]), f(x["nees_pose"], 2), f(x.get("nees_pose_after_outage"), 2),
                x["band_lo"], x["band_hi"], f(x["consistent_fraction"], 2)))
    faulty = [(name, x) for name, x in r["runs"].items() if x["fault"] != "clean" and "worst of" not in x["fault"]]
    worst_name, _ = max(faulty, key=lambda nx: (nx[1]["resets"], nx[1]["error_over_clean"] or 0.0))
    head = (max(x["resets"] for _, x in faulty), max(x["error_over_clean"] or 0.0 for _, x in faulty), len(faulty),
            worst_name)
    return head, text


def table_section(path, heading, about, columns):
    """A generated section of a report's runs table (None when the file is not there): columns
    [(key, header, digits)]."""
    if not os.path.exists(path):
        return []
    r = load(path)
    text = [heading, "", "%s `%s`, %s." % (about, os.path.relpath(path), stamp(path)), "",
            "| | " + " | ".join(c[1] for c in columns) + " |", "|---|" + "---|" * len(columns)]
    for name, row in r["runs"].items():
        cells = []
        for key, _, digits in columns:
            v = row.get(key)
            cells.append("-" if v is None else ("yes" if v is True else "no" if v is False else
                                                ("%.*f" % (digits, v) if isinstance(v, float) else str(v))))
        text.append("| %s | %s |" % (name, " | ".join(cells)))
    for name, rows in r.get("tables", {}).items():
        keys = [k for k in next(iter(rows.values()), {}).keys()]
        text += ["", "| %s | %s |" % (name, " | ".join(keys)), "|---|" + "---|" * len(keys)]
        for row_name, row in rows.items():
            text.append("| %s | %s |" % (row_name, " | ".join(
                "-" if row.get(k) is None else ("%.3f" % row[k] if isinstance(row[k], float) else str(row[k]))
                for k in keys)))
    return text


def extra_sections(results):
    """The map's walks, the online extrinsic and the soaks, where they were run."""
    out = []
    out += table_section(os.path.join(results, "suite", "map", "suite_map.json"), "## The map's walks (`make suite`)",
                         "The study on walks that come back, every landmark unlike the others and on a tiled floor, the "
                         "map kept and forgotten (the node's defaults otherwise);",
                         [("ate_posyaw_keep_m", "ATE posyaw kept [m]", 3), ("ate_posyaw_forget_m", "forgotten [m]", 3),
                          ("ate_keep_over_forget", "kept / forgotten", 2),
                          ("return_keep", "error on return / first, kept", 2), ("return_forget", "forgotten", 2),
                          ("revisits_per_run", "revisits / run", 1), ("false_revisits", "false revisits", 0),
                          ("nees_pose_keep", "NEES pose kept", 2), ("consistent_keep", "consistent kept", 2),
                          ("filter_ms_keep", "filter kept [ms]", 2), ("filter_ms_forget", "forgotten [ms]", 2)])
    ext = table_section(os.path.join(results, "extrinsic", "extrinsic.json"),
                        "## The online camera-IMU extrinsic (`make extrinsic`)",
                        "The real recording from the rig file's extrinsic and four copies of it 3 deg / 3 cm off, fixed "
                        "and estimated (Sim(3) against the SfM reference), and the study per start;",
                        [("resets", "resets", 0), ("rmse_m", "RMSE [m]", 3), ("rotation_deg", "rotation [deg]", 2),
                         ("given_off_deg", "given off [deg]", 2), ("given_off_cm", "given off [cm]", 1),
                         ("final_off_deg", "final off [deg]", 2), ("final_off_cm", "final off [cm]", 1)])
    out += ([""] if out and ext else []) + ext
    for mode in ("forget", "keep"):
        soak = table_section(os.path.join(results, "soak_" + mode, "summary.json"),
                             "## Soak, the map %s (`make soak%s`)" % ("forgotten" if mode == "forget" else "kept",
                                                                       "" if mode == "forget" else " SOAK_MAP=keep"),
                             "Laps of the simulated walk for half an hour with the soak's faults, per mechanization;",
                             [("distance_m", "distance [m]", 0), ("final_error_m", "final error [m]", 3),
                              ("max_landmarks", "max landmarks", 0), ("rss_start_mb", "RSS start [MB]", 1),
                              ("rss_end_mb", "RSS end [MB]", 1), ("nonfinite", "non-finite", 0),
                              ("wall_s", "wall [s]", 0)])
        out += ([""] if out and soak else []) + soak
    return out


def generate(results):
    demo_glance, demo = demo_section(results)
    real, realdata = realdata_section(results)
    suite_head, suite = suite_section(results)
    bench = bench_section(results)
    faults_head, faults = faults_section(results)
    glance = [GLANCE, "", "`make demo`: the rendered 37 s hallway walk (2 s standing, 45 m) played with "
              "`rosbag play --clock` into the nodelet, once per mechanization (times per image on 2 cores):", ""]
    glance += demo_glance
    if real:
        glance += ["", "On the real hand-held recording (50 s, 1280x720, `make realdata`) the defaults, given nothing "
                   "but the recording's calibration, track to %.3f m RMSE against the SfM reference (OpenVINS tuned "
                   "for it: 0.073 m) with %d resets, and find the camera-IMU time offset online (%.3f s)." % (
                       real[0], real[2], real[1])]
    if suite_head:
        inside, cases, worst, band = suite_head
        glance += ["", "Over the suite's %d cases (simulated walks and windows of recorded trajectories; `make suite`, seed 1) the default is inside the pose NEES "
                   "band [%.2f, %.2f] on %d; its worst case is %.2f." % (cases, band[0], band[1], inside, worst)]
    if faults_head:
        glance += ["", "With a fault injected (`make faults`: clipped IMU samples, sensor gaps, NaN IMU samples, a "
                   "lossy link, and a covered lens, dim images and darkness each at several moments, the lens for several "
                   "lengths; %d runs on the real recording and the rendered walk) the filter resets at most %d time%s "
                   "and its error is at most %.2fx the clean run's (the worst row: %s; the known limits are in "
                   "docs/evaluation.md)." % (faults_head[2], faults_head[0], "" if faults_head[0] == 1 else "s",
                                             faults_head[1], faults_head[3])]
    page = ["# Results", "",
            "Generated by `make results` (tools/results_page.py) from the result files named in each section; "
            "do not edit. Every current number of the project is here.", ""]
    page += glance + [""] + demo + [""] + realdata + [""] + suite + [""] + bench + ([""] + faults if faults else [])
    extra = extra_sections(results)
    page += [""] + extra if extra else []
    return "\n".join(page) + "\n"


def glance_of(page):
    start = page.index(GLANCE)
    end = page.index("\n## ", start + len(GLANCE))
    return page[start + len(GLANCE):end].strip("\n")


def quote(readme, glance):
    start, end = readme.index(BEGIN), readme.index(END)
    return readme[:start + len(BEGIN)] + "\n" + glance + "\n" + readme[end:]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--results", default="results")
    ap.add_argument("--out", default="docs/results.md")
    ap.add_argument("--readme", default="README.md")
    ap.add_argument("--check", action="store_true", help="only check that the README quotes the page")
    a = ap.parse_args()
    with open(a.readme) as fh:
        readme = fh.read()
    if BEGIN not in readme or END not in readme:
        sys.exit("results_page: %s has no results markers" % a.readme)
    if a.check:
        with open(a.out) as fh:
            page = fh.read()
        if quote(readme, glance_of(page)) != readme:
            sys.exit("results_page: %s does not quote the first section of %s (run make results)" % (a.readme, a.out))
        print("results_page: %s quotes %s" % (a.readme, a.out))
        return 0
    try:
        page = generate(a.results)
    except (FileNotFoundError, KeyError) as e:
        sys.exit("results_page: missing result: %s (run make demo, make realdata, make suite, make bench)" % e)
    with open(a.out, "w") as fh:
        fh.write(page)
    with open(a.readme, "w") as fh:
        fh.write(quote(readme, glance_of(page)))
    print("results_page: wrote %s and the README's quote" % a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
