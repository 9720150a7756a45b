#!/usr/bin/env python3
"""Summarizes a Google Benchmark JSON run of vi_ekf_slam_bench (and the pipeline numbers).

usage: summarize.py BENCH_JSON PIPELINE_JSON OUT_DIR

Writes OUT_DIR/summary.json: every benchmark with its family, N, median time [us] and the
fitted growth exponent per family (least squares of log(time) on log(N)), plus the pipeline
numbers and the machine; prints the table that bench/README.md keeps.
"""
import argparse
import json
import math
import os
import platform
import sys

# The report writer is tools/report.py (installed beside this script).
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "tools")]
import report  # noqa: E402


def fit_exponent(points):
    """Slope of log(t) over log(N)."""
    if len(points) < 2:
        return None
    xs = [math.log(n) for n, _ in points]
    ys = [math.log(t) for _, t in points]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else None


def to_us(value, unit):
    return value * {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}[unit]


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("bench_json", help="Google Benchmark's JSON output")
    p.add_argument("pipeline_json", help="bench/pipeline.py's JSON output")
    p.add_argument("out", help="the folder for summary.json and summary.md")
    a = p.parse_args()
    bench_json, pipeline_json, out = a.bench_json, a.pipeline_json, a.out
    with open(bench_json) as f:
        data = json.load(f)
    rows = []
    for b in data["benchmarks"]:
        if b.get("aggregate_name", "median") != "median" or b.get("error_occurred"):
            continue
        name = b.get("run_name", b["name"]).split("/min_time")[0]
        family, _, arg = name.partition("/")
        n = int(arg) if arg.isdigit() else None
        rows.append({"name": name, "family": family.replace("BM_", ""), "N": n,
                     "median_us": to_us(b["cpu_time"], b["time_unit"]),
                     "counters": {k: v for k, v in b.items() if k == "tracks_per_frame"}})
    families = {}
    for r in rows:
        if r["N"] is not None:
            families.setdefault(r["family"], []).append((r["N"], r["median_us"]))
    exponents = {f: fit_exponent(sorted(p)) for f, p in families.items()}
    pipeline = {}
    if os.path.exists(pipeline_json):
        with open(pipeline_json) as f:
            pipeline = json.load(f)
    ctx = data.get("context", {})
    machine = {"host": platform.node(), "cpus": ctx.get("num_cpus"), "mhz": ctx.get("mhz_per_cpu"),
               "cpu_model": cpu_model(), "date": ctx.get("date")}
    summary = report.report(
        "bench", "Benchmarks (one core, median CPU time)", machine, {r["name"]: r for r in rows},
        {"exponents": {f: {"exponent": e} for f, e in exponents.items()}, "pipeline": {"pipeline": pipeline}})
    report.write_report(out, "summary", summary,
                        columns=[("family", "family", 0), ("N", "N", 0), ("median_us", "median [us]", 2)],
                        headings={"exponents": "Growth exponent per family (log time on log N)",
                                  "pipeline": "The pipeline (bench/pipeline.py)"})

    sizes = sorted({r["N"] for r in rows if r["N"] is not None})
    print("| operation | " + " | ".join("N=%d" % n for n in sizes) + " | exponent |")
    print("|---|" + "---|" * (len(sizes) + 1))
    for fam in families:
        t = dict(families[fam])
        cells = [fmt(t[n]) if n in t else "" for n in sizes]
        e = exponents[fam]
        print("| %s [us] | %s | %s |" % (fam, " | ".join(cells), "%.2f" % e if e is not None else ""))
    print()
    for r in rows:
        if r["N"] is None:
            extra = ", %.0f tracks/frame" % r["counters"]["tracks_per_frame"] if r["counters"] else ""
            print("%s: %.2f ms per frame%s" % (r["family"], r["median_us"] / 1000.0, extra))
    for k, v in pipeline.items():
        print("%s: %s" % (k, v))
    print("\nwritten to %s/summary.json (machine: %s, %s CPUs)" % (out, machine["cpu_model"], machine["cpus"]))


def fmt(us):
    return "%.1f" % us if us < 100 else "%.0f" % us


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


if __name__ == "__main__":
    main()
