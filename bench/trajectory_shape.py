#!/usr/bin/env python3
"""Takes a SLAM trajectory's error apart against the ground truth of a generated world (z up).

    bench/trajectory_shape.py GROUNDTRUTH.txt ESTIMATE.txt [--every N] [--smooth K]

Both files in TUM format (timestamp tx ty tz qx qy qz qw), poses paired by timestamp.
Prints: the ATE RMSE after an se3 and after a sim3 fit (with the scale), the horizontal and
height parts of the se3 error, the error left after smoothing it over K frames (what is not
frame-to-frame jitter), and every N frames the error along the path, across it (positive to
the left of the motion) and in height. docs/slam.md, "What is left of the corridor's error".
Needs numpy (python3-numpy, installed by scripts/setup).
"""
import argparse
import sys

import numpy as np


def load(path):
    poses = {}
    with open(path) as f:
        for n, line in enumerate(f, 1):
            if line.startswith("#") or not line.strip():
                continue
            v = line.split()
            if len(v) < 4:
                sys.exit(f"{path}:{n}: expected 'timestamp tx ty tz ...'")
            try:
                poses[round(float(v[0]), 4)] = np.array([float(x) for x in v[1:4]])
            except ValueError:
                sys.exit(f"{path}:{n}: not a number")
    return poses


def fit(est, gt, with_scale):
    """Umeyama: s, R, t minimizing |s R est + t - gt|."""
    me, mg = est.mean(0), gt.mean(0)
    a, b = est - me, gt - mg
    U, S, Vt = np.linalg.svd(b.T @ a)
    D = np.eye(3)
    D[2, 2] = np.sign(np.linalg.det(U @ Vt))
    R = U @ D @ Vt
    s = (S * np.diag(D)).sum() / (a ** 2).sum() if with_scale else 1.0
    return s, R, mg - s * R @ me


def rms(x):
    return float(np.sqrt((x ** 2).sum(axis=-1).mean()))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("groundtruth")
    ap.add_argument("estimate")
    ap.add_argument("--every", type=int, default=150)
    ap.add_argument("--smooth", type=int, default=15)
    o = ap.parse_args()
    gt, est = load(o.groundtruth), load(o.estimate)
    keys = sorted(set(gt) & set(est))
    if len(keys) < 3:
        sys.exit(f"{o.estimate}: fewer than 3 poses share a timestamp with {o.groundtruth}")
    G = np.array([gt[k] for k in keys])
    E = np.array([est[k] for k in keys])
    for name, with_scale in (("se3", False), ("sim3", True)):
        s, R, t = fit(E, G, with_scale)
        print(f"{name}: ATE RMSE {rms((s * (R @ E.T)).T + t - G):.4f} m, scale {s:.5f}")
    s, R, t = fit(E, G, False)
    d = (R @ E.T).T + t - G
    print(f"se3 parts: horizontal {rms(d[:, :2]):.4f} m, height {rms(d[:, 2:]):.4f} m")
    k = max(1, o.smooth)
    smooth = np.stack([np.convolve(d[:, i], np.ones(k) / k, mode="same") for i in range(3)], axis=1)
    print(f"smoothed over {k} frames: {rms(smooth):.4f} m; the rest (jitter) {rms(d - smooth):.4f} m")
    print("frame      x      y   along  across  height")
    for i in range(0, len(keys), max(1, o.every)):
        v = G[min(i + 10, len(keys) - 1)] - G[max(i - 10, 0)]
        v[2] = 0
        n = np.linalg.norm(v)
        if n < 1e-6:
            continue
        v /= n
        left = np.array([-v[1], v[0], 0.0])
        print(f"{i:5d} {G[i, 0]:6.2f} {G[i, 1]:6.2f}  {d[i] @ v:+.3f}  {d[i] @ left:+.3f}  {d[i, 2]:+.3f}")


if __name__ == "__main__":
    main()
