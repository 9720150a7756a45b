#!/usr/bin/env python3
"""Pedestrian walks the shared recordings lack, as TUM trajectories for the study and the suite.

Each walk goes round a rectangular block of corridors (rounded corners) with a torso-worn rig's
gait (bounce at the step frequency, lateral sway and yaw at the stride frequency, scaled with the
speed) and a small postural sway when standing:

  slow_start  starts at a slow walk (0.5 m/s) and reaches 1.3 m/s only after 20 s;
  crawl       starts at a crawl (0.3 m/s: feeling the way in smoke or the dark) for 10 s, then
              1.3 m/s from 12 s (the gait's bounce, what tells the scale, at a quarter of a walk's);
  stops       1.3 m/s with stands of 5, 12 and 20 s (about a third of the time standing);
  stairs      walks, climbs a flight of stairs (2.8 m up over 5 m), walks on, comes back down;
  fast        a brisk walk at 2.4 m/s from the start (a hurried responder; the gait at its largest);
  stairwell   from a stand, within a second up a stairwell that turns all the time (a helix of
              1.6 m radius, 0.75 rad/s, 0.24 m up per second) for 34 s, then the block (the start
              of OpenVINS's udel_gore trajectory, docs/evaluation.md).

Not in the suite's default (`--kinds all` adds them; `make suite SUITE_WALKS=all`), probes of walks
the suite does not have (docs/evaluation.md):

  slow_walk    0.6 m/s throughout (a careful walker: the gait's bounce at half a walk's);
  start04      0.4 m/s for 10 s, then 1.3 m/s from 12 s (between the crawl and the slow start);
  stop_and_go  1.3 m/s with a 1 s stop every 7 s (checking doors);
  small_room   1.0 m/s round a 6 m x 4 m room (a turn every 3-5 s);
  run          3.5 m/s from the first sample (the gait at its cap).

The files are made by a formula, not recorded: they exercise the starts, stands and climbs that
held-out recordings have, and the suite runs them next to the recorded trajectories.

  make_walks.py OUT_DIR [--kinds K1,K2,..|all]
      writes OUT_DIR/<kind>.txt (100 Hz, z up); by default the suite's six kinds above
"""
import argparse
import math
import os
import sys

import numpy as np

RATE_HZ = 100.0
STEP_HZ = 1.9
CRUISE_MPS = 1.3


def block_path(length=30.0, width=12.0, radius=1.5, ds=0.01):
    """Centreline of a rectangular loop with rounded corners: (x, y) every ds metres, closed."""
    pts = []
    corners = [(length, 0.0), (length, width), (0.0, width), (0.0, 0.0)]
    start = np.array([0.0, 0.0])
    heading = 0.0
    pos = start.copy()
    for k, _ in enumerate(corners):
        side = length if k % 2 == 0 else width
        straight = side - 2 * radius
        d = np.array([math.cos(heading), math.sin(heading)])
        for s in np.arange(0.0, straight, ds):
            pts.append(pos + s * d)
        pos = pos + straight * d
        # quarter circle to the left
        centre = pos + radius * np.array([-d[1], d[0]])
        for a in np.arange(0.0, math.pi / 2, ds / radius):
            ang = heading - math.pi / 2 + a
            pts.append(centre + radius * np.array([math.cos(ang), math.sin(ang)]))
        heading += math.pi / 2
        pos = centre + radius * np.array([math.cos(heading - math.pi / 2), math.sin(heading - math.pi / 2)])
    return np.array(pts)


def stairwell_path(radius, turns, ds=0.01):
    """A helix's ground track (a circle of `radius`, `turns` times round, turning left), then the
    block loop from the circle's exit: (x, y) every ds metres."""
    pts = []
    for a in np.arange(0.0, 2 * math.pi * turns, ds / radius):
        pts.append(np.array([radius * math.sin(a), radius * (1.0 - math.cos(a))]))
    pts.extend(block_path(ds=ds)[1:])
    return np.array(pts)


def walk(speed_of_t, duration, height_of_s=None, seed=0, path=None):
    """Samples a path (default: the block loop) at RATE_HZ for the given speed profile [m/s] over
    time [s]."""
    rng = np.random.default_rng(seed)
    path = block_path() if path is None else path
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    arclen = np.concatenate([[0.0], np.cumsum(seg)])
    loop = arclen[-1]
    t = np.arange(0.0, duration, 1.0 / RATE_HZ)
    v = np.array([speed_of_t(x) for x in t])
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) / RATE_HZ)])
    sl = np.mod(s, loop)
    x = np.interp(sl, arclen, path[:, 0])
    y = np.interp(sl, arclen, path[:, 1])
    # Heading from the path tangent (smooth), unwrapped over laps.
    tx = np.interp(sl + 0.3, arclen, path[:, 0], period=loop) - np.interp(sl - 0.3, arclen, path[:, 0], period=loop)
    ty = np.interp(sl + 0.3, arclen, path[:, 1], period=loop) - np.interp(sl - 0.3, arclen, path[:, 1], period=loop)
    yaw = np.unwrap(np.arctan2(ty, tx))
    z = np.full_like(t, 1.3) + (height_of_s(s) if height_of_s else 0.0)
    # Gait: cadence falls with the square root of the speed (1.9 steps/s at 1.3 m/s, 1.2 at
    # 0.5 m/s), the step length with the rest; the bounce scales with the speed.
    cadence = STEP_HZ * np.sqrt(np.clip(v, 0.0, None) / CRUISE_MPS)
    phase = 2 * math.pi * np.concatenate([[0.0], np.cumsum(0.5 * (cadence[1:] + cadence[:-1]) / RATE_HZ)])
    amp = np.clip(v / CRUISE_MPS, 0.0, 1.2)
    z = z + 0.025 * amp * np.sin(phase)
    lateral = 0.03 * amp * np.sin(phase / 2)
    yaw = yaw + 0.035 * amp * np.sin(phase / 2 + 0.5)
    roll = 0.026 * amp * np.sin(phase / 2)
    pitch = 0.017 * amp * np.sin(phase + 0.3)
    # Standing: postural sway (a few mm, a fraction of a degree) at 0.2-0.5 Hz.
    still = 1.0 - np.clip(v / 0.3, 0.0, 1.0)
    f1, f2 = rng.uniform(0.2, 0.5, 2)
    lateral = lateral + still * 0.004 * np.sin(2 * math.pi * f1 * t)
    pitch = pitch + still * 0.004 * np.sin(2 * math.pi * f2 * t + 1.0)
    x = x - lateral * np.sin(yaw)
    y = y + lateral * np.cos(yaw)
    return t, np.stack([x, y, z], axis=1), yaw, pitch, roll


def quaternion(yaw, pitch, roll):
    """Hamilton (x, y, z, w) of R = Rz(yaw) Ry(pitch) Rx(roll): body x forward, z up."""
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    w = cr * cp * cy + sr * sp * sy
    x = sr * cp * cy - cr * sp * sy
    y = cr * sp * cy + sr * cp * sy
    z = cr * cp * sy - sr * sp * cy
    return np.stack([x, y, z, w], axis=1)


def smooth_steps(t, knots):
    """Piecewise-constant speed [(t_start, speed), ...] with 1.5 s cosine ramps between levels."""
    ramp = 1.5
    v = knots[0][1]
    for (t0, v0), (t1, v1) in zip(knots[:-1], knots[1:]):
        if t >= t1:
            v = v1
        elif t >= t1 - ramp:
            a = (t - (t1 - ramp)) / ramp
            v = v0 + (v1 - v0) * 0.5 * (1 - math.cos(math.pi * a))
    return v


WALKS = {}  # kind -> function returning (t, positions, yaw, pitch, roll), in the order written
SUITE_KINDS = []  # the kinds the suite runs by default; the others are probes


def walk_kind(suite):
    """Registers the function as the walk of the kind it is named after (in the suite's default or not)."""
    def register(fn):
        WALKS[fn.__name__] = fn
        if suite:
            SUITE_KINDS.append(fn.__name__)
        return fn

    return register


@walk_kind(suite=True)
def slow_start():
    # 0.5 m/s for 8 s, then a slow ramp to cruise speed by 20 s.
    def speed(t):
        if t < 8.0:
            return 0.5
        a = min(1.0, (t - 8.0) / 12.0)
        return 0.5 + (CRUISE_MPS - 0.5) * 0.5 * (1 - math.cos(math.pi * a))
    return walk(speed, 90.0, seed=1)


@walk_kind(suite=True)
def crawl():
    return walk(lambda t: smooth_steps(t, [(0, 0.3), (12, CRUISE_MPS), (90, CRUISE_MPS)]), 90.0, seed=5)


@walk_kind(suite=True)
def stops():
    knots = [(0, 1.3), (15, 0.0), (20, 1.3), (40, 0.0), (52, 1.3), (75, 0.0), (95, 1.3), (120, 1.3)]
    return walk(lambda t: smooth_steps(t, knots), 120.0, seed=2)


@walk_kind(suite=True)
def stairs():
    # A flight from 20 m to 25 m of the walk (2.8 m up), back down from 78 m to 83 m along the
    # path; slower on the stairs.
    up0, up1, down0, down1, rise = 20.0, 25.0, 78.0, 83.0, 2.8

    def height(s):
        return rise * np.clip((s - up0) / (up1 - up0), 0, 1) - rise * np.clip((s - down0) / (down1 - down0), 0, 1)

    # 0.5 m/s on the flights: the speed is a function of the distance, integrated in time
    # and smoothed over 1 s.
    def speed_at_s(s):
        return 0.5 if (up0 <= s <= up1 or down0 <= s <= down1) else CRUISE_MPS

    ts = np.arange(0.0, 90.0, 1.0 / RATE_HZ)
    s = 0.0
    profile = []
    for _ in ts:
        v = speed_at_s(s)
        profile.append(v)
        s += v / RATE_HZ
    profile = np.convolve(profile, np.ones(100) / 100, mode="same")
    return walk(lambda t: float(np.interp(t, ts, profile)), 90.0, height_of_s=height, seed=3)


@walk_kind(suite=True)
def fast():
    # 2.4 m/s from the first sample: cadence 2.6 steps/s, the bounce and sway at their cap.
    return walk(lambda t: 2.4, 60.0, seed=4)


@walk_kind(suite=True)
def stairwell():
    # Stands 0.2 s, walks off to 1.2 m/s within 0.8 s, round the helix (0.75 rad/s) while
    # climbing 0.2 m per metre of path (0.24 m/s) for 34 s, then the block.
    radius, turns, climb_per_m = 1.6, 4.0, 0.2
    path = stairwell_path(radius, turns)
    helix_len = 2 * math.pi * radius * turns

    def height(s):
        return climb_per_m * np.clip(s, 0.0, helix_len)

    def speed(t):
        a = np.clip((t - 0.2) / 0.8, 0.0, 1.0)
        return 1.2 * 0.5 * (1 - math.cos(math.pi * a))

    return walk(speed, 90.0, height_of_s=height, seed=6, path=path)


@walk_kind(suite=False)
def slow_walk():
    return walk(lambda t: 0.6, 90.0, seed=13)


@walk_kind(suite=False)
def start04():
    return walk(lambda t: smooth_steps(t, [(0, 0.4), (12, CRUISE_MPS), (90, CRUISE_MPS)]), 90.0, seed=14)


@walk_kind(suite=False)
def stop_and_go():
    # Each knot is reached at its time after a 1.5 s ramp: stands from 5.5 to 6.5 s of every 7 s.
    knots = [(0, CRUISE_MPS)]
    for k in range(13):
        knots += [(7 * k + 5.5, 0.0), (7 * k + 8.0, CRUISE_MPS)]
    return walk(lambda t: smooth_steps(t, knots), 90.0, seed=11)


@walk_kind(suite=False)
def small_room():
    return walk(lambda t: 1.0, 90.0, seed=12, path=block_path(length=6.0, width=4.0, radius=0.8))


@walk_kind(suite=False)
def run():
    return walk(lambda t: 3.5, 60.0, seed=15)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out_dir")
    ap.add_argument("--kinds", default=",".join(SUITE_KINDS), help="comma-separated, or all")
    a = ap.parse_args()
    kinds = list(WALKS) if a.kinds == "all" else [k.strip() for k in a.kinds.split(",") if k.strip()]
    unknown = [k for k in kinds if k not in WALKS]
    if unknown:
        sys.exit("make_walks: unknown kind(s) %s; known: %s" % (",".join(unknown), ",".join(WALKS)))
    os.makedirs(a.out_dir, exist_ok=True)
    for kind in kinds:
        t, p, yaw, pitch, roll = WALKS[kind]()
        q = quaternion(yaw, pitch, roll)
        path = os.path.join(a.out_dir, kind + ".txt")
        with open(path, "w") as f:
            f.write("# t x y z qx qy qz qw (tools/make_walks.py %s; z up, body x forward)\n" % kind)
            for i in range(len(t)):
                f.write("%.3f %.5f %.5f %.5f %.7f %.7f %.7f %.7f\n" % (t[i], *p[i], *q[i]))
        dist = np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))
        print("%s: %.0f s, %.0f m -> %s" % (kind, t[-1], dist, path))


if __name__ == "__main__":
    main()
