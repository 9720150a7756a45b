#!/usr/bin/python3
"""Checks an rviz screenshot of vi_ekf_slam: the estimated path (red-orange 255,25,0), the
landmark cloud (cyan 0,255,255) and the track image (green track marks 0,255,0 on a grey image)
must all be visible. Exits non-zero with the counts otherwise.

usage: check_screenshot.py PNG [--min-pixels N]
"""
import argparse
import sys

import cv2
import numpy as np


def count(img, rgb, tol=40):
    bgr = np.array(rgb[::-1], dtype=np.int32)
    return int(np.sum(np.all(np.abs(img.astype(np.int32) - bgr) <= tol, axis=2)))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("png", help="the screenshot")
    p.add_argument("--min-pixels", type=int, default=50, help="pixels of each colour it must show")
    a = p.parse_args()
    img = cv2.imread(a.png)
    if img is None:
        print("cannot read", a.png)
        return 1
    min_px = a.min_pixels
    counts = {"path (255,25,0)": count(img, (255, 25, 0)), "landmarks (0,255,255)": count(img, (0, 255, 255)),
              "tracks (0,255,0)": count(img, (0, 255, 0), tol=30)}
    ok = all(c >= min_px for c in counts.values())
    print("screenshot %s %dx%d: %s -> %s" % (a.png, img.shape[1], img.shape[0],
                                             ", ".join("%s %d px" % kv for kv in counts.items()), "ok" if ok else "MISSING"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
