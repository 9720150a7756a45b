#!/usr/bin/env python3
"""Plots of a vi_ekf_slam study (what the paper's Figs. 2-4 show, plus run-averaged NEES).

For each configuration folder in OUT (written by vi_ekf_slam_study):
  <cfg>/topview.png      true and estimated trajectory and landmarks (run 0)
  <cfg>/errors.png       errors in {n} with +-3 sigma, red bars where landmarks were added (run 0)
  <cfg>/errors_s.png     sensor-centric only: body pose in {s} and pose of {s} in {n} (run 0)
  <cfg>/gamma.png        scale ratio gamma (eq. 34), run 0 and run average
  <cfg>/nees.png         run-averaged NEES with its 95% chi-square band
and OUT/nees_comparison.png over all configurations.

usage: plot_study.py OUT [--docs DIR --prefix NAME]   (copies the README's plots to DIR)
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


def read_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    d = {k: np.array([float(r[k]) if r[k] not in ("", "nan") else np.nan for r in rows]) for k in rows[0]}
    if "t" in d and len(d["t"]) and d["t"][0] > 1e6:
        d["t"] = d["t"] - d["t"][0]  # recorded data: absolute stamps -> seconds since the first frame
    return d


def vec(d, name):
    return np.stack([d[name + "_x"], d[name + "_y"], d[name + "_z"]], axis=1)


def mark_events(ax, d):
    t = d["t"]
    for tt in t[d["new_landmarks"] > 0]:
        ax.axvline(tt, color="red", alpha=0.12, lw=0.6)


def error_grid(d, rows, title, path):
    fig, axes = plt.subplots(len(rows), 3, figsize=(12, 2.1 * len(rows)), sharex=True)
    t = d["t"]
    for r, (name, label, scale) in enumerate(rows):
        e, s = vec(d, "e_" + name) * scale, vec(d, "s_" + name) * scale
        for c, axis in enumerate("xyz"):
            ax = axes[r][c]
            mark_events(ax, d)
            ax.plot(t, e[:, c], color="tab:blue", lw=0.9)
            ax.plot(t, 3 * s[:, c], color="tab:green", lw=0.9)
            ax.plot(t, -3 * s[:, c], color="tab:green", lw=0.9)
            ax.set_ylabel(f"{label} {axis}", fontsize=8)
            ax.tick_params(labelsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(title + "  (blue: error, green: +-3 sigma, red: new landmarks)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=72)
    plt.close(fig)


def plot_config(out, cfg, world):
    d = read_csv(os.path.join(out, cfg, "run0.csv"))
    ts = read_csv(os.path.join(out, cfg, "timeseries.csv"))
    lm = read_csv(os.path.join(out, cfg, "landmarks_run0.csv"))
    # Top view ({n}: x along the hallway, y to the right; plotted with y down like a map).
    fig, ax = plt.subplots(figsize=(8, 6))
    ax.scatter(world["y"], world["x"], s=3, color="tab:blue", label="landmarks (true)")
    ax.scatter(lm["est_y"], lm["est_x"], s=4, color="tab:orange", label="landmarks (estimated, run 0)")
    ax.plot(d["ty"], d["tx"], color="red", lw=1.5, label="true trajectory")
    ax.plot(d["ey"], d["ex"], color="green", lw=1.5, label="estimated trajectory")
    ax.set_xlabel("y [m] (right)")
    ax.set_ylabel("x [m] (forward)")
    # Frame the true world: unconverged inverse-depth points far away would shrink it to a dot.
    m = 3.0
    ax.set_xlim(np.nanmin(world["y"]) - m, np.nanmax(world["y"]) + m)
    ax.set_ylim(np.nanmin(world["x"]) - m, np.nanmax(world["x"]) + m)
    ax.set_aspect("equal", adjustable="box")
    ax.legend(fontsize=8, loc="best")
    ax.set_title(f"{cfg}: top view")
    fig.tight_layout()
    fig.savefig(os.path.join(out, cfg, "topview.png"), dpi=72)
    plt.close(fig)
    deg = 180.0 / np.pi
    error_grid(d, [("p", "pos [m]", 1.0), ("q", "rot [deg]", deg), ("v", "vel [m/s]", 1.0),
                   ("ba", "b_a [m/s2]", 1.0), ("bg", "b_g [deg/s]", deg)],
               f"{cfg}: errors in {{n}} (run 0)", os.path.join(out, cfg, "errors.png"))
    if d["has_s"].max() > 0:
        error_grid(d, [("p_sb", "p_s_b [m]", 1.0), ("q_sb", "psi_s_b [deg]", deg),
                       ("p_ns", "p_n_s [m]", 1.0), ("q_ns", "psi_n_s [deg]", deg)],
                   f"{cfg}: body pose in {{s}} and pose of {{s}} in {{n}} (run 0)",
                   os.path.join(out, cfg, "errors_s.png"))
    fig, ax = plt.subplots(figsize=(8, 3))
    mark_events(ax, d)
    ax.plot(d["t"], d["gamma"], label="run 0")
    ax.plot(ts["t"], ts["median_gamma"], label="run median")
    ax.axhline(1.0, color="k", lw=0.6)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("scale ratio gamma")
    ax.legend(fontsize=8)
    ax.set_title(f"{cfg}: scale ratio (eq. 34)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, cfg, "gamma.png"), dpi=90)
    plt.close(fig)
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.2))
    for ax, key, band, label in ((axes[0], "avg_nees_p", "band3", "position (3 dof)"),
                                 (axes[1], "avg_nees_q", "band3", "orientation (3 dof)"),
                                 (axes[2], "avg_nees_pose", "band6", "pose (6 dof)")):
        ax.semilogy(ts["t"], ts[key], lw=0.9)
        ax.fill_between(ts["t"], ts[band + "_lo"], ts[band + "_hi"], color="tab:green", alpha=0.25,
                        label="95% band")
        ax.set_title(f"average NEES, {label}", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=7)
    fig.suptitle(cfg, fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out, cfg, "nees.png"), dpi=90)
    plt.close(fig)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out", help="a folder written by vi_ekf_slam_study")
    p.add_argument("--docs", help="also copy the plots into this folder")
    p.add_argument("--prefix", default="study", help="file name prefix of the copies in --docs")
    a = p.parse_args()
    out, docs, prefix = a.out, a.docs, a.prefix if a.docs else None
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    configs = list(summary["runs"])
    world = read_csv(os.path.join(out, "world.csv"))
    for cfg in configs:
        plot_config(out, cfg, world)
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for cfg in configs:
        ts = read_csv(os.path.join(out, cfg, "timeseries.csv"))
        ax.semilogy(ts["t"], ts["avg_nees_pose"], lw=1.0, label=cfg)
    ax.fill_between(ts["t"], ts["band6_lo"], ts["band6_hi"], color="k", alpha=0.15, label="95% band")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("run-averaged pose NEES")
    ax.legend(fontsize=7)
    ax.set_title(f"{summary['config']['trajectory']}: pose NEES, {summary['config']['runs']} runs")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "nees_comparison.png"), dpi=90)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for cfg in configs:
        ts = read_csv(os.path.join(out, cfg, "timeseries.csv"))
        ax.plot(ts["t"], ts["median_gamma"], lw=1.0, label=cfg)
    ax.axhline(1.0, color="k", lw=0.6)
    ax.set_ylim(0.8, 1.6)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("run-median gamma (eq. 34)")
    ax.legend(fontsize=7)
    ax.set_title(f"{summary['config']['trajectory']}: scale ratio, {summary['config']['runs']} runs")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "gamma_comparison.png"), dpi=90)
    plt.close(fig)
    if docs:
        # Only the plots the README shows: the comparisons, and per-run plots of the paper's three
        # configurations and of the best one.
        os.makedirs(docs, exist_ok=True)
        for name in ("nees_comparison", "gamma_comparison"):
            shutil.copy(os.path.join(out, name + ".png"), os.path.join(docs, f"{prefix}_{name}.png"))
        best = "sensor_centric_composition+inverse_depth+every_update"
        wanted = {"world_centric": ("topview", "errors"), "sensor_centric": ("errors",),
                  "sensor_centric_composition": ("errors", "errors_s"), best: ("topview", "errors", "errors_s")}
        for cfg, names in wanted.items():
            for name in names:
                src = os.path.join(out, cfg, name + ".png")
                if os.path.exists(src):
                    shutil.copy(src, os.path.join(docs, f"{prefix}_{cfg}_{name}.png"))
    print(f"plots written to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
