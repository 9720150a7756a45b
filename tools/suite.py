#!/usr/bin/env python3
"""The suite: the study (same seeds) over every pedestrian trajectory we have, in windows, and one
table per trajectory and configuration, with a worst-case row per configuration.

Cases: the built-in hallway walk; the TUM corridor, UDel ARL and EuRoC V1_01 (the non-pedestrian
check) from DATA_DIR/trajectories, each in 120 s windows; and the simulator's generated walks
(a slow start, a crawl, stands, stairs, a fast walk, a stairwell; --walks chooses others, or all of
its kinds). Then the map's walks (there and back, laps; every landmark unlike the others, and a
tiled floor), each with the map kept and forgotten: OUT/map/suite_map.md (--no-map skips them,
--map-only runs only them). Any other *.txt in DATA_DIR/trajectories joins the suite with one window from its
start, so the command runs unchanged on trajectories added there.

  suite.py --study BIN [--data DIR] [--out results/suite] [--runs 8] [--seed 1 | --seed 1,2,3]
           [--configs NAME,...] [--walks KIND,...|all] [--threads N] [-- extra study options]

Writes OUT/<case>/ (the study's files), OUT/suite.json and OUT/suite.md, and prints the table.
With several seeds: OUT/seed_N/ as above for each, and OUT/suite_seeds.{md,json}: every case's
pose NEES and consistent fraction per seed, and the worst case over all cases and seeds.
"""
import argparse
import glob
import os
import subprocess
import sys
import time

import report
from study_cli import add_study_options, resolve_tools

HERE = os.path.dirname(os.path.abspath(__file__))


def study_configs(study):
    """{configuration name: its sets} as the study lists them (`--list-configs`): the names are
    written once, in the study."""
    out = subprocess.run([study, "--list-configs"], capture_output=True, text=True, check=True).stdout
    return {name: sets.split(",") for name, sets in (line.split() for line in out.splitlines() if line.strip())}


def configs_in(study, the_set):
    return [n for n, sets in study_configs(study).items() if the_set in sets]

WINDOW_S = 120.0
# (file in DATA_DIR/trajectories, window starts [s]); pedestrian unless said otherwise.
KNOWN = {
    "tum_corridor1_512_16_okvis.txt": [0.0, 150.0],
    "udel_arl_short.txt": [0.0, 300.0, 600.0],
    "euroc_V1_01_easy.txt": [0.0],
}


def trajectory_files(data_dir):
    """Every TUM file in DATA_DIR/trajectories, sorted."""
    return sorted(glob.glob(os.path.join(data_dir, "trajectories", "*.txt")))


def write_walks(tool, out_dir, kinds=""):
    """The simulator's generated walks (TOOL: vi_ekf_slam_make_walks; the suite's kinds, or KINDS)
    written into OUT_DIR/walks, and no others; returns that folder."""
    walks = os.path.join(out_dir, "walks")
    for old in glob.glob(os.path.join(walks, "*.txt")):
        os.remove(old)  # a walk of an earlier call with other kinds is not one of this suite's
    cmd = [tool, "--out", walks, "--kinds", kinds or "suite"]
    if subprocess.run(cmd, stdout=subprocess.DEVNULL).returncode != 0:
        sys.exit("suite: %s could not write the walks (above)" % tool)
    return walks


def walk_files(walks_dir):
    """(name, path) of every walk in WALKS_DIR, sorted."""
    return [("walk_" + os.path.splitext(os.path.basename(p))[0], p)
            for p in sorted(glob.glob(os.path.join(walks_dir, "*.txt")))]


def cases(data_dir, walks_dir):
    out = [("builtin", "builtin", 0.0, 0.0)]
    for path in trajectory_files(data_dir):
        name = os.path.splitext(os.path.basename(path))[0]
        for start in KNOWN.get(os.path.basename(path), [0.0]):
            out.append(("%s@%d" % (name, start), path, start, WINDOW_S))
    out += [(name, path, 0.0, 0.0) for name, path in walk_files(walks_dir)]
    return out


def run_cases(a, seed, out_dir, walks, configs):
    """The study on every case with one seed: OUT_DIR/<case>/, suite.json and suite.md; returns the
    rows (case x configuration) and the pose NEES band."""
    results = {}
    t_start = time.time()
    for name, traj, start, window in cases(a.data, walks):
        out = os.path.join(out_dir, name)
        cmd = [a.study, "--trajectory", traj, "--runs", str(a.runs), "--seed", str(seed), "--configs", ",".join(configs),
               "--threads", str(a.threads), "--out", out]
        if start > 0:
            cmd += ["--start-offset", str(start)]
        if window > 0:
            cmd += ["--max-duration", str(window)]
        cmd += a.extra
        t0 = time.time()
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if proc.returncode != 0:
            # One case the study cannot run (a malformed file among the trajectories) is a row of
            # the table, not the end of the suite; main() ends non-zero after the tables.
            sys.stderr.write(proc.stdout[-2000:] + proc.stderr[-2000:])
            lines = [l for l in (proc.stderr + proc.stdout).splitlines() if l.strip()]
            results[name] = {"failed": lines[-1] if lines else "exit status %d" % proc.returncode}
            print("  %-34s FAILED: %s" % (name, results[name]["failed"]), flush=True)
            continue
        results[name] = report.load(os.path.join(out, "summary.json"))
        print("  %-34s %5.0f s" % (name, time.time() - t0), flush=True)

    # Per case: each configuration's metrics and its ATE over the best of the paper's three.
    rows, worst = [], {c: new_worst() for c in configs}
    band = None
    paper = configs_in(a.study, "paper")
    for name, s in results.items():
        if "failed" in s:
            for c in configs:
                row = {"case": name, "config": c, "failed": s["failed"], "ate_position_m": None, "ate_posyaw_m": None,
                       "nees_pose": None, "consistent_fraction": None, "ate_over_best_paper": None,
                       "nees_inside_band": False}
                rows.append(row)
                add_to_worst(worst[c], row)
            continue
        band = s["config"]["pose_nees_band"]
        study = s["runs"]
        paper_ate = [study[c]["ate_position_m"] for c in paper if c in study and study[c]["ate_position_m"] is not None]
        best_paper = min(paper_ate) if paper_ate else None
        for c in configs:
            m = study[c]
            ratio = m["ate_position_m"] / best_paper if best_paper else None
            inside = m["nees_pose"] is not None and band[0] <= m["nees_pose"] <= band[1]
            row = {"case": name, "config": c, "ate_position_m": m["ate_position_m"], "ate_posyaw_m": m["ate_posyaw_m"],
                   "nees_pose": m["nees_pose"], "consistent_fraction": m["consistent_fraction"],
                   "ate_over_best_paper": ratio, "nees_inside_band": inside}
            rows.append(row)
            add_to_worst(worst[c], row)
    if band is None:
        sys.exit("suite: the study failed on every case")
    r = report.report(
        "suite", "Suite: %d cases, %d runs each, seed %d" % (len(results), a.runs, seed),
        {"runs": a.runs, "seed": seed, "pose_nees_band": band, "minutes": (time.time() - t_start) / 60},
        {"%s / %s" % (row["case"], row["config"]): row for row in rows}, {"worst": worst})
    text = report.write_report(out_dir, "suite", r, columns=row_columns(rows),
                               table_columns={"worst": WORST_COLUMNS + ([("failed", "cases failed", 0)]
                                                                        if any_failed(rows) else [])},
                               headings={"worst": "Worst case over the %d cases" % len(results)})
    print(text)
    return rows, band


# The map's walks (issue "keep the map", docs/evaluation.md): walks that come back to where they
# have been, with every landmark looking different and with a tiled floor (one pattern for all),
# each with the map kept and forgotten (the node's default configuration otherwise).
MAP_WALKS = ["there_and_back", "laps"]
MAP_TEXTURES = [("unique", 0), ("tiled", 1)]
MAP_COLUMNS = [("ate_posyaw_keep_m", "ATE posyaw kept [m]", 3), ("ate_posyaw_forget_m", "forgotten [m]", 3),
               ("ate_keep_over_forget", "kept / forgotten", 2), ("return_keep", "error on return / first, kept", 2),
               ("return_forget", "forgotten", 2), ("revisits_per_run", "revisits / run", 1),
               ("false_revisits", "false revisits", 0), ("nees_pose_keep", "NEES pose kept", 2),
               ("nees_inside_band", "inside band", 0), ("consistent_keep", "consistent kept", 2),
               ("filter_ms_keep", "filter kept [ms]", 2), ("filter_ms_forget", "forgotten [ms]", 2)]


def run_map_cases(a, seed, out_dir):
    """The map's walks with one seed, the map kept and forgotten: OUT_DIR/map/<walk>_<texture>_<keep|forget>/,
    OUT_DIR/map/suite_map.{json,md}; returns the rows (None for a case the study could not run)."""
    root = os.path.join(out_dir, "map")
    walks = os.path.join(root, "walks")
    if subprocess.run([a.make_walks, "--out", walks, "--kinds", ",".join(MAP_WALKS)], stdout=subprocess.DEVNULL).returncode:
        sys.exit("suite: %s could not write the map's walks (above)" % a.make_walks)
    rows, band, failed = {}, None, []
    for walk in MAP_WALKS:
        for texture, patterns in MAP_TEXTURES:
            m = {}
            for mode in ("keep", "forget"):
                out = os.path.join(root, "%s_%s_%s" % (walk, texture, mode))
                cmd = [a.study, "--trajectory", os.path.join(walks, walk + ".txt"), "--runs", str(a.runs), "--seed",
                       str(seed), "--configs", "default", "--threads", str(a.threads), "--map", mode,
                       "--texture-patterns", str(patterns), "--out", out] + a.extra
                proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                if proc.returncode != 0:
                    sys.stderr.write(proc.stdout[-2000:] + proc.stderr[-2000:])
                    m = None
                    break
                r = report.load(os.path.join(out, "summary.json"))
                band = r["config"]["pose_nees_band"]
                m[mode] = r["runs"]["default"]
            name = "%s, %s" % (walk, texture)
            if m is None:
                failed.append(name)
                print("  %-34s FAILED" % name, flush=True)
                continue
            k, f = m["keep"], m["forget"]
            rows[name] = {
                "ate_posyaw_keep_m": k["ate_posyaw_m"], "ate_posyaw_forget_m": f["ate_posyaw_m"],
                "ate_keep_over_forget": k["ate_posyaw_m"] / f["ate_posyaw_m"] if f["ate_posyaw_m"] else None,
                "return_keep": k["revisit_error_ratio"], "return_forget": f["revisit_error_ratio"],
                "revisits_per_run": k["revisits_per_run"], "false_revisits": k["false_revisits"],
                "nees_pose_keep": k["nees_pose"],
                "nees_inside_band": k["nees_pose"] is not None and band[0] <= k["nees_pose"] <= band[1],
                "consistent_keep": k["consistent_fraction"], "filter_ms_keep": k["filter_ms_mean"],
                "filter_ms_forget": f["filter_ms_mean"]}
            print("  %-34s done" % name, flush=True)
    r = report.report("suite_map", "The map's walks: %d runs each, seed %d, the map kept and forgotten" % (a.runs, seed),
                      {"runs": a.runs, "seed": seed, "pose_nees_band": band, "failed": failed}, rows)
    print(report.write_report(root, "suite_map", r, columns=MAP_COLUMNS))
    return rows, failed


def row_columns(rows):
    """The suite table's columns (with the reason of a case the study could not run, if any)."""
    cols = ["ate_position_m", "ate_posyaw_m", "nees_pose", ("nees_inside_band", "inside band", 0), "consistent_fraction",
            ("ate_over_best_paper", "ATE / best paper", 2)]
    return cols + ([("failed", "failed", 0)] if any_failed(rows) else [])


WORST_COLUMNS = [("nees_pose", "max NEES pose", 2), ("outside_band", "cases outside the band", 0),
                 ("consistent_fraction", "min consistent", 2), ("ate_ratio", "max ATE / best paper", 2)]


def new_worst():
    return {"nees_pose": 0.0, "consistent_fraction": 1.0, "ate_ratio": None, "outside_band": 0, "failed": 0}


def add_to_worst(w, row):
    if "failed" in row:
        w["failed"] += 1
        return
    nees = row["nees_pose"] if row["nees_pose"] is not None else float("inf")
    w["nees_pose"] = max(w["nees_pose"], nees)
    w["consistent_fraction"] = min(w["consistent_fraction"], row["consistent_fraction"] or 0.0)
    if row["ate_over_best_paper"] is not None:  # (none without the paper's configurations)
        w["ate_ratio"] = max(w["ate_ratio"] or 0.0, row["ate_over_best_paper"])
    w["outside_band"] += 0 if row["nees_inside_band"] else 1


def any_failed(rows):
    return any("failed" in r for r in rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_study_options(ap, out="results/suite", runs=8)
    ap.add_argument("--seed", default="1", help="a seed, or several (1,2,3): each in OUT/seed_N, worst over all")
    ap.add_argument("--configs", default="", help="configurations (default: the study's suite set)")
    ap.add_argument("--walks", default="", help="generated walk kinds (vi_ekf_slam_make_walks), comma-separated, or all (default: the suite's)")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--no-map", action="store_true",
                    help="skip the map's walks (there and back, laps; unique and tiled texture; kept and forgotten)")
    ap.add_argument("--map-only", action="store_true", help="only the map's walks")
    ap.add_argument("extra", nargs="*", help="more options for every study call (after --)")
    a = resolve_tools(ap.parse_args())
    try:
        seeds = [int(x) for x in a.seed.split(",")]
    except ValueError:
        sys.exit("suite: --seed takes integers, comma-separated")
    t_start = time.time()

    if a.map_only:
        failed = []
        for seed in seeds:
            failed += run_map_cases(a, seed, a.out if len(seeds) == 1 else os.path.join(a.out, "seed_%d" % seed))[1]
        print("suite: the map's walks, %.1f min" % ((time.time() - t_start) / 60))
        sys.exit("suite: the study failed on some cases (the tables say which)" if failed else 0)
    walks = write_walks(a.make_walks, a.out, a.walks)
    configs = a.configs.split(",") if a.configs else configs_in(a.study, "suite")
    if len(seeds) == 1:
        rows, _ = run_cases(a, seeds[0], a.out, walks, configs)
        _, map_failed = run_map_cases(a, seeds[0], a.out) if not a.no_map else ({}, [])
        print("suite: %.1f min, written to %s" % ((time.time() - t_start) / 60, a.out))
        if any_failed(rows) or map_failed:
            sys.exit("suite: the study failed on some cases (the tables say which)")
        return

    # Several seeds: each as above in its own folder, then per case and configuration the pose NEES
    # (consistent fraction) of every seed, and the worst case over all cases and seeds.
    per_seed, map_failed = {}, []
    for seed in seeds:
        rows, band = run_cases(a, seed, os.path.join(a.out, "seed_%d" % seed), walks, configs)
        per_seed[seed] = {(r["case"], r["config"]): r for r in rows}
        if not a.no_map:
            map_failed += run_map_cases(a, seed, os.path.join(a.out, "seed_%d" % seed))[1]
    worst = {c: new_worst() for c in configs}
    runs = {}
    for key in per_seed[seeds[0]]:
        row = {"case": key[0], "config": key[1]}
        for seed in seeds:
            r = per_seed[seed][key]
            add_to_worst(worst[key[1]], r)
            row["seed_%d_nees_pose" % seed] = r["nees_pose"]
            row["seed_%d_consistent" % seed] = r["consistent_fraction"]
            row["seed_%d_failed" % seed] = r.get("failed")
        runs["%s / %s" % key] = row
    r = report.report("suite", "Suite: %d runs per case, seeds %s" % (a.runs, ", ".join(map(str, seeds))),
                      {"runs": a.runs, "seeds": seeds, "pose_nees_band": band,
                       "minutes": (time.time() - t_start) / 60}, runs, {"worst": worst})
    columns = [c for seed in seeds for c in (("seed_%d_nees_pose" % seed, "seed %d: NEES pose" % seed, 2),
                                              ("seed_%d_consistent" % seed, "consistent", 2))]
    text = report.write_report(
        a.out, "suite_seeds", r, columns=columns, table_columns={"worst": WORST_COLUMNS + [("failed", "cases failed", 0)]},
        headings={"worst": "Worst case over every case and seed (outside the band: counted once per seed)"})
    print(text)
    print("suite: %.1f min, written to %s (seed_N/ per seed, suite_seeds.md)" % ((time.time() - t_start) / 60, a.out))
    if any(any_failed(per_seed[s].values()) for s in seeds) or map_failed:
        sys.exit("suite: the study failed on some cases (the tables say which)")


if __name__ == "__main__":
    main()
