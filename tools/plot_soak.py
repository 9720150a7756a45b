#!/usr/bin/python3
"""Plot of the endurance run (vi_ekf_slam_soak): position error with its 3-sigma and resident
memory over time, one line per mechanization.

usage: plot_soak.py DIR [--docs DOCS_DIR]   (writes DIR/soak.png, copies it to DOCS_DIR/soak.png)
"""
import csv
import os
import argparse
import shutil

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out", help="a folder written by vi_ekf_slam_soak")
    p.add_argument("--docs", help="also copy the plot into this folder")
    a = p.parse_args()
    out = a.out
    fig, (ax_e, ax_m) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for name in ("world_centric", "sensor_centric", "sensor_centric_composition"):
        path = os.path.join(out, name + ".csv")
        if not os.path.exists(path):
            continue
        with open(path) as f:
            rows = list(csv.DictReader(f))
        t0 = float(rows[0]["t"])
        t = [(float(r["t"]) - t0) / 60.0 for r in rows]
        line, = ax_e.plot(t, [float(r["position_error_m"]) for r in rows], lw=1, label=name)
        ax_e.plot(t, [float(r["sigma3_m"]) for r in rows], lw=0.8, ls="--", color=line.get_color())
        ax_m.plot(t, [float(r["rss_mb"]) for r in rows], lw=1, color=line.get_color(), label=name)
    ax_e.set_ylabel("position error [m] (dashed: 3 sigma)")
    ax_e.set_yscale("log")
    ax_e.legend(loc="upper left", fontsize=8)
    ax_m.set_ylabel("resident memory [MB]")
    ax_m.set_xlabel("time [min]")
    ax_e.set_title("30 min walk, laps around a corridor block (no loop closure)")
    fig.tight_layout()
    png = os.path.join(out, "soak.png")
    fig.savefig(png, dpi=90)
    if a.docs:
        docs = a.docs
        os.makedirs(docs, exist_ok=True)
        shutil.copy(png, os.path.join(docs, "soak.png"))
    print("plot written to", png)


if __name__ == "__main__":
    main()
