#!/usr/bin/env python3
"""Fits the confidence model (src/confidence.rs: WEIGHTS) to `arps eval --json` outputs.

usage: scripts/fit-confidence.py [--fit-methods A,B] [--weights W0,W1,...] EVAL.json [EVAL.json ...]

Every answer of every method in the files is one sample: its evidence (the features of
`confidence::features`, kept in sync by hand in `features` below) and whether it was recalled
(RE < rot threshold, TE < trans threshold). Only the answers of the methods named by
`--fit-methods` (default: all) are fitted; every method is reported.

The model is fitted without the cap that `confidence::confidence` puts on it (at most
1 / (1 + alternatives)); the reports apply it.

Cross-validation: the pairs of each file are split by index parity; the model fitted on one half
scores the other, so every answer gets a confidence from a model that never saw its pair. The
script prints, per file and method, the share of wrong answers with that confidence < 0.5 and
the share of right answers with it < 0.5, then refits on everything and prints the weights as a
Rust array. With `--weights` it fits nothing and reports those weights (in-sample) instead.

Pure Python (no numpy): a few thousand samples and a handful of features.
"""
import json
import math
import sys

# The names of `confidence::features`, in order (the bias is the last weight).
NAMES = ["fitness", "fitness_tight", "fitness_loose", "fitness_coarse", "overlap_reverse", "rmse_ratio", "rise",
         "ambiguity", "alternatives", "slide"]


def features(e):
    """`confidence::features` of one evidence object (camelCase JSON)."""
    rise = e["fitnessTight"] / e["fitnessCoarse"] if e["fitnessCoarse"] > 0 else 0.0
    return [e["fitness"], e["fitnessTight"], e["fitnessLoose"], e["fitnessCoarse"], e["overlapReverse"],
            e["rmseRatio"], rise, e["ambiguity"], e["alternatives"], e["slide"]]


def load(paths):
    """Samples: (file, pair index, method, features, recalled)."""
    out = []
    for path in paths:
        d = json.load(open(path))
        rt, tt = d["rot_threshold_deg"], d["trans_threshold"]
        for k, p in enumerate(d["per_pair"]):
            for r in p["results"]:
                if r.get("evidence") is None:
                    continue
                ok = 1.0 if (r["rot_deg"] < rt and r["trans"] < tt) else 0.0
                out.append((path, k, r["method"], features(r["evidence"]), ok))
    return out


def solve(a, b):
    """Solves a x = b (Gaussian elimination with partial pivoting)."""
    n = len(b)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        m[c], m[p] = m[p], m[c]
        for r in range(c + 1, n):
            f = m[r][c] / m[c][c]
            for j in range(c, n + 1):
                m[r][j] -= f * m[c][j]
    x = [0.0] * n
    for r in range(n - 1, -1, -1):
        x[r] = (m[r][n] - sum(m[r][j] * x[j] for j in range(r + 1, n))) / m[r][r]
    return x


def sigmoid(z):
    return 1 / (1 + math.exp(-z)) if z > -700 else 0.0


def predict(w, x):
    """`confidence::confidence`: the logistic model, capped at 1 / (1 + alternatives)."""
    return min(sigmoid(sum(a * b for a, b in zip(w, x)) + w[-1]), 1 / (1 + max(x[NAMES.index("alternatives")], 0)))


def fit(xs, ys, l2=1e-3, iters=50):
    """L2-regularised logistic regression (bias unregularised) by Newton's method."""
    n = len(xs[0]) + 1
    w = [0.0] * n
    rows = [x + [1.0] for x in xs]
    for _ in range(iters):
        g = [0.0] * n
        h = [[0.0] * n for _ in range(n)]
        for x, y in zip(rows, ys):
            p = sigmoid(sum(a * b for a, b in zip(w, x)))
            s = p * (1 - p)
            for i in range(n):
                g[i] += (p - y) * x[i]
                for j in range(i + 1):
                    h[i][j] += s * x[i] * x[j]
        for i in range(n):
            g[i] = g[i] / len(ys) + (l2 * w[i] if i < n - 1 else 0.0)
            for j in range(i + 1):
                h[i][j] = h[i][j] / len(ys) + (l2 if i == j and i < n - 1 else 0.0)
                h[j][i] = h[i][j]
        step = solve(h, g)
        w = [a - b for a, b in zip(w, step)]
        if max(abs(v) for v in step) < 1e-9:
            break
    return w


def report(samples, conf, title):
    """Prints wrong<0.5 and right<0.5 per file and method for the confidences `conf`."""
    print(title)
    groups = {}
    for s, c in zip(samples, conf):
        groups.setdefault((s[0], s[2]), []).append((s[4], c))
    for (path, method), g in sorted(groups.items()):
        wrong = [c for y, c in g if y == 0]
        right = [c for y, c in g if y == 1]
        wl = sum(c < 0.5 for c in wrong) / len(wrong) if wrong else float("nan")
        rl = sum(c < 0.5 for c in right) / len(right) if right else float("nan")
        print(f"  {path} | {method}: wrong<0.5 {wl:.3f} of {len(wrong)}, right<0.5 {rl:.3f} of {len(right)}")


def main():
    args = sys.argv[1:]
    fit_methods, given = None, None
    while args and args[0].startswith("--"):
        if args[0] == "--fit-methods":
            fit_methods = set(args[1].split(","))
        elif args[0] == "--weights":
            given = [float(v) for v in args[1].split(",")]
        else:
            sys.exit(__doc__)
        args = args[2:]
    if not args:
        sys.exit(__doc__)
    samples = load(args)
    used = [s for s in samples if fit_methods is None or s[2] in fit_methods]
    print(f"{len(samples)} answers, {int(sum(s[4] for s in samples))} right; fitted on {len(used)}")
    if given is not None:
        report(samples, [predict(given, s[3]) for s in samples], "given weights (in-sample):")
        return
    conf = [0.0] * len(samples)
    for held in (0, 1):
        train = [s for s in used if s[1] % 2 != held]
        w = fit([s[3] for s in train], [s[4] for s in train])
        for i, s in enumerate(samples):
            if s[1] % 2 == held:
                conf[i] = predict(w, s[3])
    report(samples, conf, "cross-validated (fitted on the other parity of pairs):")
    w = fit([s[3] for s in used], [s[4] for s in used])
    report(samples, [predict(w, s[3]) for s in samples], "refitted on all (in-sample):")
    print("  " + ", ".join(f"{n} {v:.3}" for n, v in zip(NAMES + ["bias"], w)))
    print("const WEIGHTS: [f64; %d] = [%s];" % (len(w), ", ".join(f"{v:.4}" for v in w)))


if __name__ == "__main__":
    main()
