#!/usr/bin/python3
"""Checks an rviz screenshot of vi_ekf_slam: the estimated path (red-orange 255,25,0), the
landmark cloud (cyan 0,255,255) and the track image (green track marks 0,255,0 on a grey image)
must all be visible. Exits non-zero with the counts otherwise.

usage: check_screenshot.py PNG [--min-pixels N]
"""
import sys

import cv2
import numpy as np


def count(img, rgb, tol=40):
    bgr = np.array(rgb[::-1], dtype=np.int32)
    return int(np.sum(np.all(np.abs(img.astype(np.int32) - bgr) <= tol, axis=2)))


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    img = cv2.imread(sys.argv[1])
    if img is None:
        print("cannot read", sys.argv[1])
        return 1
    min_px = int(sys.argv[sys.argv.index("--min-pixels") + 1]) if "--min-pixels" in sys.argv else 50
    counts = {"path (255,25,0)": count(img, (255, 25, 0)), "landmarks (0,255,255)": count(img, (0, 255, 255)),
              "tracks (0,255,0)": count(img, (0, 255, 0), tol=30)}
    ok = all(c >= min_px for c in counts.values())
    print("screenshot %s %dx%d: %s -> %s" % (sys.argv[1], img.shape[1], img.shape[0],
                                             ", ".join("%s %d px" % kv for kv in counts.items()), "ok" if ok else "MISSING"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
