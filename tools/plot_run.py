#!/usr/bin/python3
"""Plots of single runs written by vi_ekf_slam_run_bag (offline or recorded live replays).

usage: plot_run.py DIR [--docs DOCS_DIR --prefix NAME]
Writes DIR/topview.png (truth and every run, registered at the first pose), DIR/errors.png
(position errors with +-3 sigma per run) and DIR/nees.png (pose NEES with the 95% band of 6 dof).
"""
import csv
import json
import os
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    out = sys.argv[1]
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    runs = [k for k in summary if k != "config"]
    data = {r: load(os.path.join(out, r + "_timeseries.csv")) for r in runs}
    fig, ax = plt.subplots(figsize=(7, 6))
    first = data[runs[0]]
    ax.plot(first["ty"], first["tx"], "k", lw=2.5, label="ground truth")
    for r in runs:
        ax.plot(data[r]["ey"], data[r]["ex"], lw=1.2, label=r)
    ax.set_xlabel("y [m]")
    ax.set_ylabel("x [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8)
    ax.set_title("trajectories (z-up world, registered at the first pose)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "topview.png"), dpi=80)
    plt.close(fig)
    fig, axes = plt.subplots(len(runs), 3, figsize=(12, 2.2 * len(runs)), sharex=True, squeeze=False)
    for i, r in enumerate(runs):
        d = data[r]
        t = d["t"] - d["t"][0]
        for c, a in enumerate("xyz"):
            ax = axes[i][c]
            ax.plot(t, d["e_p_" + a], lw=0.9)
            ax.plot(t, 3 * d["s_p_" + a], "g", lw=0.8)
            ax.plot(t, -3 * d["s_p_" + a], "g", lw=0.8)
            ax.set_ylabel(f"{r}\n{a} [m]" if c == 0 else f"{a} [m]", fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle("position error (blue) and +-3 sigma (green)", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "errors.png"), dpi=72)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(9, 3.2))
    for r in runs:
        d = data[r]
        ax.semilogy(d["t"] - d["t"][0], d["nees_pose"], lw=0.8, label=r)
    ax.axhspan(1.237, 14.449, color="k", alpha=0.12, label="95% band, 6 dof")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("pose NEES")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "nees.png"), dpi=72)
    plt.close(fig)
    if "--docs" in sys.argv:
        docs = sys.argv[sys.argv.index("--docs") + 1]
        prefix = sys.argv[sys.argv.index("--prefix") + 1]
        os.makedirs(docs, exist_ok=True)
        for name in ("topview", "errors", "nees"):
            shutil.copy(os.path.join(out, name + ".png"), os.path.join(docs, f"{prefix}_{name}.png"))
    print("plots written to", out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
