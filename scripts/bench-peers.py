#!/usr/bin/env python3
"""Open3D's side of `scripts/bench-peers.sh`, and the table.

    python scripts/bench-peers.py --arps arps.json [--threads N] [--json out.json] SET=DIR ...

For every pair of every set (DIR/pairs.tsv, the format of fixtures/pairs/pairs.tsv) it times, from
clouds already in memory (reading excluded, as for arps):

* "O3D ICP": Open3D's point-to-plane ICP from the identity, on the clouds voxelised as arps
  voxelises them for ICP (voxel d/2), target normals from 20 nearest neighbours (arps's count),
  coarse to fine at 4d, 2d, d (arps's schedule), 30 iterations per stage, relative fitness and
  RMSE 1e-6. d = 0.025 x the pair's scale (arps's default final distance).
* "O3D RANSAC": Open3D's global registration tutorial pipeline: voxel_down_sample(v), normals
  (radius 2v, 30 neighbours), FPFH (radius 5v, 100 neighbours), RANSAC on mutual feature matches
  (distance 1.5v, 3 points, edge-length 0.9 and distance checkers, 100,000 iterations at
  confidence 0.999), then the ICP above from RANSAC's answer. v is the feature voxel arps picks
  (0.08 x the scale, grown by 1.25x until both voxelised clouds have at most 1,500 points),
  computed outside the timed region, as a caller who knows the data would fix it.

The scale is arps's: the largest bounding-box half-extent of the two clouds. Recall is the
repository's (`arps eval`): rotation error < 15 degrees and translation error < 0.2, the
translation error divided by the scale unless DIR/pairs.json says the set is in normalised units.
The arps figures come from scripts/bench-peers.mjs's JSON (--arps). Prints per set the median
ms/pair, the recall and the ratios arps / Open3D.
"""
import argparse
import json
import math
import os
import statistics
import sys
import time

import numpy as np

o3d = None  # imported in main(), once OMP_NUM_THREADS is set
REG = None
ROT_THRESHOLD_DEG = 15.0
TRANS_THRESHOLD = 0.2
D_FRACTION = 0.025  # arps's default final ICP distance, fraction of the scale
SCHEDULE = (4.0, 2.0, 1.0)  # arps's coarse-to-fine ICP stages, multiples of d
FEATURE_VOXEL_FRACTION = 0.08  # arps's global::VOXEL_FRACTION
MAX_FEATURE_POINTS = 1500  # arps's global::MAX_FEATURE_POINTS


def read_pairs(directory):
    pairs = []
    with open(os.path.join(directory, "pairs.tsv")) as f:
        for k, line in enumerate(f):
            line = line.rstrip("\n\r")
            if not line.strip() or line.startswith("#") or (k == 0 and line.startswith("name\t")):
                continue
            c = line.split("\t")
            gt = np.array([float(x) for x in c[5].split()]).reshape(4, 4)
            pairs.append({"name": c[0], "source": os.path.join(directory, c[1]),
                          "target": os.path.join(directory, c[2]), "gt": gt})
    normalized = False
    sidecar = os.path.join(directory, "pairs.json")
    if os.path.exists(sidecar):
        with open(sidecar) as f:
            normalized = json.load(f).get("units") == "normalized"
    return pairs, normalized


def half_extent(pcd):
    lo, hi = pcd.get_min_bound(), pcd.get_max_bound()
    return float(np.max((hi - lo) * 0.5))


def rotation_error_deg(a, b):
    r = a[:3, :3].T @ b[:3, :3]
    return math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(r) - 1.0) / 2.0))))


def recalled(t, gt, scale):
    if not np.all(np.isfinite(t)):
        return False
    te = float(np.linalg.norm(t[:3, 3] - gt[:3, 3])) / scale
    return rotation_error_deg(t, gt) < ROT_THRESHOLD_DEG and te < TRANS_THRESHOLD


def feature_voxel(source, target, scale):
    v = FEATURE_VOXEL_FRACTION * scale
    for _ in range(60):
        fits = all(len(c.points) <= MAX_FEATURE_POINTS or len(c.voxel_down_sample(v).points) <= MAX_FEATURE_POINTS
                   for c in (source, target))
        if fits:
            break
        v *= 1.25
    return v


def icp(source, target, init, d):
    """Point-to-plane ICP, coarse to fine, on clouds voxelised at d/2 (target normals: 20-NN)."""
    s = source.voxel_down_sample(d / 2)
    t = target.voxel_down_sample(d / 2)
    t.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(20))
    crit = REG.ICPConvergenceCriteria(relative_fitness=1e-6, relative_rmse=1e-6, max_iteration=30)
    T = init
    for factor in SCHEDULE:
        T = REG.registration_icp(s, t, factor * d, T, REG.TransformationEstimationPointToPlane(), crit).transformation
    return T


def ransac_icp(source, target, v, d):
    def prepare(c):
        down = c.voxel_down_sample(v)
        down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * v, max_nn=30))
        fpfh = REG.compute_fpfh_feature(down, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * v, max_nn=100))
        return down, fpfh

    (s, sf), (t, tf) = prepare(source), prepare(target)
    dist = 1.5 * v
    r = REG.registration_ransac_based_on_feature_matching(
        s, t, sf, tf, True, dist, REG.TransformationEstimationPointToPoint(False), 3,
        [REG.CorrespondenceCheckerBasedOnEdgeLength(0.9), REG.CorrespondenceCheckerBasedOnDistance(dist)],
        REG.RANSACConvergenceCriteria(100000, 0.999))
    return icp(source, target, r.transformation, d)


def timed(f):
    t0 = time.perf_counter()
    out = f()
    return out, (time.perf_counter() - t0) * 1000.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--arps", required=True, help="scripts/bench-peers.mjs's JSON")
    ap.add_argument("--threads", type=int, default=1, help="Open3D threads (the wasm build uses one)")
    ap.add_argument("--json", help="also write every per-pair figure here")
    ap.add_argument("sets", nargs="+", help="SET=DIR, the same as given to bench-peers.mjs")
    a = ap.parse_args()
    os.environ["OMP_NUM_THREADS"] = str(a.threads)
    global o3d, REG
    import open3d

    o3d, REG = open3d, open3d.pipelines.registration
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    o3d.utility.random.seed(0)
    with open(a.arps) as f:
        arps = json.load(f)
    table, dump = [], {"open3d": o3d.__version__, "threads": a.threads, "sets": {}}
    for spec in a.sets:
        name, directory = spec.split("=", 1)
        pairs, normalized = read_pairs(directory)
        arps_rows = {r["name"]: r for r in arps["sets"][name]}
        rows = []
        for p in pairs:
            source, target = o3d.io.read_point_cloud(p["source"]), o3d.io.read_point_cloud(p["target"])
            scale = max(half_extent(source), half_extent(target))
            te_scale = 1.0 if normalized else scale
            d = D_FRACTION * scale
            v = feature_voxel(source, target, scale)
            T_icp, ms_icp = timed(lambda: icp(source, target, np.eye(4), d))
            T_ran, ms_ran = timed(lambda: ransac_icp(source, target, v, d))
            ar = arps_rows[p["name"]]
            T_arps = np.array(ar["matrixColumnMajor"]).reshape(4, 4).T
            rows.append({
                "name": p["name"], "points": (len(source.points) + len(target.points)) / 2,
                "arps_ms": ar["ms"], "arps_ok": recalled(T_arps, p["gt"], te_scale),
                "icp_ms": ms_icp, "icp_ok": recalled(T_icp, p["gt"], te_scale),
                "ransac_ms": ms_ran, "ransac_ok": recalled(T_ran, p["gt"], te_scale),
                "arps_timings": ar.get("timingsMs"), "arps_start": ar.get("start"),
            })
            print(f"bench-peers: open3d {name} {p['name']} icp {ms_icp:.1f} ms, ransac {ms_ran:.1f} ms",
                  file=sys.stderr)
        dump["sets"][name] = rows
        med = lambda k: statistics.median(r[k] for r in rows)
        rec = lambda k: sum(r[k] for r in rows) / len(rows)
        table.append((name, len(rows), med("points"), med("arps_ms"), rec("arps_ok"), med("icp_ms"), rec("icp_ok"),
                      med("ransac_ms"), rec("ransac_ok")))
    print(f"Open3D {o3d.__version__} ({a.threads} thread{'s' if a.threads > 1 else ''}) vs {arps['engine']}, "
          f"{arps['options']} options; median ms/pair (recall: RE < {ROT_THRESHOLD_DEG:g} deg, TE < {TRANS_THRESHOLD:g})")
    print("| set | pairs | points/cloud | arps ms (recall) | O3D ICP ms (recall) | O3D RANSAC+ICP ms (recall) "
          "| arps / ICP | arps / RANSAC |")
    print("|---|---|---|---|---|---|---|---|")
    for n, k, pts, am, ar, im, ir, rm, rr in table:
        print(f"| {n} | {k} | {pts:,.0f} | {am:.1f} ({ar:.3f}) | {im:.1f} ({ir:.3f}) | {rm:.1f} ({rr:.3f}) "
              f"| {am / im:.2f} | {am / rm:.2f} |")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(dump, f, indent=1)


if __name__ == "__main__":
    main()
