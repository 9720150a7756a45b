#!/usr/bin/python3
"""Plots of single runs written by vi_ekf_slam_run_bag (offline or recorded live replays).

usage: plot_run.py DIR [--docs DOCS_DIR --prefix NAME]
Always (from health.json and <run>_trace.csv, no ground truth needed): DIR/health.png (speed, NIS
per dof, time offset, tracks and observations over time) and, with reference:= comparisons,
DIR/reference_topview.png (each run over its aligned reference) and DIR/reference_errors.png
(distance to the aligned reference over time).
With ground truth in the bag (summary.json): DIR/topview.png (truth and every run, registered at
the first pose), DIR/errors.png (position errors with +-3 sigma per run) and DIR/nees.png (pose
NEES with the 95% band of 6 dof).
"""
import csv
import json
import os
import argparse
import sys
import shutil

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def plot_health(out):
    """What a run says about itself: no ground truth needed."""
    with open(os.path.join(out, "health.json")) as f:
        health = json.load(f)["runs"]
    runs = [k for k in health if os.path.exists(os.path.join(out, k + "_trace.csv"))]
    if not runs:
        return []
    fig, axes = plt.subplots(4, 1, figsize=(9, 9), sharex=True)
    t0 = None
    for r in runs:
        d = load(os.path.join(out, r + "_trace.csv"))
        if len(d["t"]) < 2:
            continue
        t0 = d["t"][0] if t0 is None else t0
        t = d["t"] - t0
        step = np.linalg.norm(np.diff(np.stack([d["x"], d["y"], d["z"]], 1), axis=0), axis=1)
        speed = step / np.maximum(np.diff(d["t"]), 1e-6)
        axes[0].plot(t[1:], speed, lw=0.8, label=r)
        axes[1].plot(t, d["nis_per_dof"], lw=0.6, label=r)
        axes[2].plot(t, 1000 * d["time_offset_s"], lw=0.9, label=r)
        axes[3].plot(t, d["tracks"], lw=0.6, label=r + " tracks")
        axes[3].plot(t, d["accepted"], lw=0.6, ls="--", label=r + " accepted")
        axes[3].plot(t, d["rejected"], lw=0.6, ls=":", label=r + " rejected")
    axes[0].set_ylabel("speed [m/s]")
    axes[0].set_yscale("symlog", linthresh=1.0)
    axes[1].set_ylabel("NIS / dof")
    axes[1].axhline(1.0, color="k", lw=0.6)
    axes[2].set_ylabel("time offset [ms]")
    axes[3].set_ylabel("per image")
    axes[3].set_xlabel("t [s]")
    for ax in axes:
        ax.legend(fontsize=6)
    fig.suptitle("health (no ground truth needed)", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "health.png"), dpi=72)
    plt.close(fig)
    written = ["health"]
    refs = [(r, f) for r in runs for f in sorted(os.listdir(out)) if f.startswith(r + "_reference") and f.endswith(".csv")]
    if refs:
        fig, axes = plt.subplots(1, len(refs), figsize=(5.5 * len(refs), 5), squeeze=False)
        fig2, ax2 = plt.subplots(figsize=(9, 3.2))
        for ax, (r, f) in zip(axes[0], refs):
            d = load(os.path.join(out, f))
            if len(d["t"]) < 2:
                continue
            ax.plot(d["rx"], d["ry"], "k", lw=2.0, label="reference (aligned)")
            ax.plot(d["ex"], d["ey"], lw=1.0, label=r)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(f, fontsize=8)
            ax.legend(fontsize=7)
            err = np.linalg.norm(np.stack([d["ex"] - d["rx"], d["ey"] - d["ry"], d["ez"] - d["rz"]], 1), axis=1)
            ax2.plot(d["t"] - d["t"][0], err, lw=0.8, label=f)
        ax2.set_xlabel("t [s]")
        ax2.set_ylabel("distance to the aligned reference [m]")
        ax2.legend(fontsize=6)
        fig.tight_layout()
        fig.savefig(os.path.join(out, "reference_topview.png"), dpi=72)
        fig2.tight_layout()
        fig2.savefig(os.path.join(out, "reference_errors.png"), dpi=72)
        plt.close(fig)
        plt.close(fig2)
        written += ["reference_topview", "reference_errors"]
    return written


ARGS = None


def main():
    global ARGS
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out", help="a folder written by vi_ekf_slam_run_bag")
    p.add_argument("--docs", help="also copy the plots into this folder")
    p.add_argument("--prefix", default="run", help="file name prefix of the copies in --docs")
    ARGS = p.parse_args()
    out = ARGS.out
    written = plot_health(out) if os.path.exists(os.path.join(out, "health.json")) else []
    if not os.path.exists(os.path.join(out, "summary.json")):
        copy_docs(out, written)
        print("plots written to", out, "(no ground truth: health and reference plots only)")
        return 0
    with open(os.path.join(out, "summary.json")) as f:
        runs = list(json.load(f)["runs"])
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
    copy_docs(out, written + ["topview", "errors", "nees"])
    print("plots written to", out)
    return 0


def copy_docs(out, names):
    if not ARGS.docs:
        return
    docs, prefix = ARGS.docs, ARGS.prefix
    os.makedirs(docs, exist_ok=True)
    for name in names:
        shutil.copy(os.path.join(out, name + ".png"), os.path.join(docs, f"{prefix}_{name}.png"))


if __name__ == "__main__":
    sys.exit(main())
