#!/usr/bin/python3
"""Independent ATE reference (Horn/Umeyama with numpy's SVD), written apart from the C++
code, in the manner of the TUM RGB-D benchmark's evaluate_ate.py. Prints one JSON object.

usage: ate_reference.py GT EST [--sim3] [--max-diff S]
"""
import json
import sys

import numpy as np


def read(path):
    rows = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            rows.append([float(v) for v in line.replace(",", " ").split()])
    return np.array(rows)


def associate(a, b, max_diff):
    cands = sorted(
        (abs(ta - tb), i, j)
        for i, ta in enumerate(a)
        for j, tb in enumerate(b)
        if abs(ta - tb) <= max_diff
    )
    used_a, used_b, pairs = set(), set(), []
    for _, i, j in cands:
        if i in used_a or j in used_b:
            continue
        used_a.add(i)
        used_b.add(j)
        pairs.append((i, j))
    return sorted(pairs)


def main():
    args = sys.argv[1:]
    sim3 = "--sim3" in args
    max_diff = 0.02
    if "--max-diff" in args:
        max_diff = float(args[args.index("--max-diff") + 1])
    gt, est = read(args[0]), read(args[1])
    pairs = associate(gt[:, 0], est[:, 0], max_diff)
    X = np.array([est[j, 1:4] for _, j in pairs]).T  # 3 x n, model
    Y = np.array([gt[i, 1:4] for i, _ in pairs]).T   # 3 x n, data
    mx, my = X.mean(axis=1, keepdims=True), Y.mean(axis=1, keepdims=True)
    Xc, Yc = X - mx, Y - my
    U, d, Vt = np.linalg.svd(Yc @ Xc.T)
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[2, 2] = -1
    R = U @ S @ Vt
    s = np.trace(np.diag(d) @ S) / (Xc ** 2).sum() if sim3 else 1.0
    t = my - s * R @ mx
    err = np.linalg.norm(Y - (s * R @ X + t), axis=0)
    print(json.dumps({"rmse": float(np.sqrt((err ** 2).mean())), "mean": float(err.mean()),
                      "median": float(np.median(err)), "max": float(err.max()), "pairs": len(pairs),
                      "scale": float(s)}))


if __name__ == "__main__":
    main()
