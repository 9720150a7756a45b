#!/usr/bin/python3
"""Checks an rviz screenshot of vi_ekf_slam: the estimated path (red-orange 255,25,0), the
landmark cloud (cyan 0,255,255) and the track image (green track marks 0,255,0 on a grey image)
must all be visible. With --pose (the default view, rviz/vi_ekf_slam.rviz), also the current pose
(the yellow arrow) and its position covariance (a purple ellipsoid) in the 3D view, the ellipsoid
small enough to hide nothing (at most --max-covariance-share of the view). Exits non-zero with the
counts otherwise.

usage: check_screenshot.py PNG [--min-pixels N] [--pose] [--max-covariance-share F]
"""
import argparse
import sys

import cv2
import numpy as np

BACKGROUND = 48  # the views' background colour (48,48,48)


def count(img, rgb, tol=40):
    bgr = np.array(rgb[::-1], dtype=np.int32)
    return int(np.sum(np.all(np.abs(img.astype(np.int32) - bgr) <= tol, axis=2)))


def view_3d(img):
    """The 3D view: the rows and columns that are mostly its background colour (the panels are
    light, the camera image varied)."""
    bg = np.all(np.abs(img.astype(np.int32) - BACKGROUND) <= 4, axis=2)
    cols = np.where(bg.mean(axis=0) > 0.5)[0]
    if cols.size == 0:
        return img[:0, :0]
    bg = bg[:, cols.min():cols.max() + 1]
    rows = np.where(bg.mean(axis=1) > 0.5)[0]
    return img[rows.min():rows.max() + 1, cols.min():cols.max() + 1]


def purple(img):
    """The covariance ellipsoid's pixels: purple hue (its colour 170,85,255 shaded and blended)."""
    hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV).astype(np.int32)
    return int(np.sum((hsv[..., 0] > 125) & (hsv[..., 0] < 150) & (hsv[..., 1] > 80) & (hsv[..., 2] > 60)))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("png", help="the screenshot")
    p.add_argument("--min-pixels", type=int, default=50, help="pixels of each colour it must show")
    p.add_argument("--pose", action="store_true", help="also the current pose and its covariance")
    p.add_argument("--max-covariance-share", type=float, default=0.02,
                   help="largest share of the 3D view the covariance may cover")
    a = p.parse_args()
    img = cv2.imread(a.png)
    if img is None:
        print("cannot read", a.png)
        return 1
    min_px = a.min_pixels
    counts = {"path (255,25,0)": count(img, (255, 25, 0)), "landmarks (0,255,255)": count(img, (0, 255, 255)),
              "tracks (0,255,0)": count(img, (0, 255, 0), tol=30)}
    ok = all(c >= min_px for c in counts.values())
    extra = ""
    if a.pose:
        view = view_3d(img)
        pose, cov = count(view, (255, 255, 0), tol=60), purple(view)
        share = cov / max(1, view.shape[0] * view.shape[1])
        counts["pose (255,255,0)"] = pose
        counts["covariance (purple)"] = cov
        # The arrow may point at the viewer: its head's disc is then all there is of it.
        ok = ok and pose >= min_px // 5 and cov >= min_px // 4 and share <= a.max_covariance_share
        extra = " (3D view %dx%d, covariance %.2f%% of it)" % (view.shape[1], view.shape[0], 100 * share)
    print("screenshot %s %dx%d: %s%s -> %s" % (a.png, img.shape[1], img.shape[0],
                                               ", ".join("%s %d px" % kv for kv in counts.items()), extra,
                                               "ok" if ok else "MISSING"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
