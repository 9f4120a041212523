#!/usr/bin/env python3
"""Fits the confidence model (src/confidence.rs: WEIGHTS) to `arps eval --json` outputs.

usage: scripts/fit-confidence.py EVAL.json [EVAL.json ...]

Every answer of every method in the files is one sample: its evidence (the features of
`confidence::features`, kept in sync by hand) and whether it was recalled (RE < rot threshold,
TE < trans threshold). Pairs are split by index parity: the model is fitted on the even pairs and
checked on the odd ones (and the other way round), then refitted on all; prints the weights as a
Rust array and the check figures (share of wrong answers with confidence < 0.5, share of right
answers with confidence < 0.5).
"""
import json
import sys

import numpy as np


def features(e):
    rise = e["fitnessTight"] / e["fitnessCoarse"] if e["fitnessCoarse"] > 0 else 0.0
    return [e["fitness"], e["fitnessTight"], e["fitnessLoose"], e["fitnessCoarse"], e["overlapReverse"],
            e["rmseRatio"], rise, e["ambiguity"]]


def load(paths):
    xs, ys, groups = [], [], []
    for path in paths:
        d = json.load(open(path))
        rt, tt = d["rot_threshold_deg"], d["trans_threshold"]
        for k, p in enumerate(d["per_pair"]):
            for r in p["results"]:
                if r.get("evidence") is None:
                    continue
                xs.append(features(r["evidence"]))
                ys.append(1.0 if (r["rot_deg"] < rt and r["trans"] < tt) else 0.0)
                groups.append(k % 2)
    return np.array(xs), np.array(ys), np.array(groups)


def fit(x, y, l2=1e-3, iters=200):
    xb = np.hstack([x, np.ones((len(x), 1))])
    w = np.zeros(xb.shape[1])
    for _ in range(iters):  # Newton's method on the L2-regularised log loss
        p = 1 / (1 + np.exp(-xb @ w))
        g = xb.T @ (p - y) / len(y) + l2 * np.r_[w[:-1], 0]
        h = (xb * (p * (1 - p))[:, None]).T @ xb / len(y) + l2 * np.eye(len(w))
        w -= np.linalg.solve(h, g)
    return w


def check(w, x, y):
    p = 1 / (1 + np.exp(-(np.hstack([x, np.ones((len(x), 1))]) @ w)))
    wrong, right = y == 0, y == 1
    return (np.mean(p[wrong] < 0.5) if wrong.any() else float("nan"),
            np.mean(p[right] < 0.5) if right.any() else float("nan"), int(wrong.sum()), int(right.sum()))


def main():
    x, y, g = load(sys.argv[1:])
    print(f"{len(y)} answers, {int(y.sum())} right")
    for held in (0, 1):
        w = fit(x[g != held], y[g != held])
        wl, rl, nw, nr = check(w, x[g == held], y[g == held])
        print(f"fit on parity {1 - held}, check on parity {held}: wrong<0.5 {wl:.3} of {nw}, right<0.5 {rl:.3} of {nr}")
    w = fit(x, y)
    wl, rl, nw, nr = check(w, x, y)
    print(f"all: wrong<0.5 {wl:.3} of {nw}, right<0.5 {rl:.3} of {nr}")
    print("const WEIGHTS: [f64; %d] = [%s];" % (len(w), ", ".join(f"{v:.4}" for v in w)))


if __name__ == "__main__":
    main()
