"""Signed distances to a CAD mesh against Open3D's raycasting scene, side by side in one run
(issue #34 §4).

A closed, asymmetric, partly concave body of about 100,000 triangles (a sphere of 99,224
triangles stretched and dented) and 1,000,000 measured points near its surface (sampled on it,
moved ±0.5 mm along the normal), in two orders: as a scanner delivers them (along scan lines)
and shuffled. machscan: ``signed_distances`` (float64, the sign from pseudo-normals, the tree
built in the call). Open3D: ``RaycastingScene.compute_signed_distance`` (float32, Embree, the
sign from ray parity, nsamples=1, its default), the scene built outside the timing. Both on
every core. Target: >= 1.2x Open3D. Best of --repeats runs.

    python benchmarks/bench_deviation.py [--points 1000000] [--repeats 3]
"""

from __future__ import annotations

import argparse

import numpy as np
import open3d as o3d
from timing import best_time

import machscan


def body() -> tuple[np.ndarray, np.ndarray]:
    m = o3d.geometry.TriangleMesh.create_sphere(radius=40.0, resolution=158)
    v = np.asarray(m.vertices) * [1.5, 1.0, 0.7]
    v = v * (1 + 0.15 * np.sin(3 * v[:, :1] / 40) * np.cos(2 * v[:, 1:2] / 40))
    return v, np.asarray(m.triangles, dtype=np.int64)


def scan_points(v: np.ndarray, f: np.ndarray, n: int, seed: int) -> np.ndarray:
    """Points on the surface moved along its normal, ordered along lines of constant y (as a
    line scanner sweeps)."""
    rng = np.random.default_rng(seed)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    normal = np.cross(b - a, c - a)
    area = 0.5 * np.linalg.norm(normal, axis=1)
    pick = rng.choice(len(f), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    flip = r1 + r2 > 1
    r1[flip], r2[flip] = 1 - r1[flip], 1 - r2[flip]
    p = a[pick] + r1[:, None] * (b - a)[pick] + r2[:, None] * (c - a)[pick]
    p += rng.uniform(-0.5, 0.5, size=(n, 1)) * normal[pick] / (2 * area[pick, None])
    line = np.round(p[:, 1] / 0.2)
    return p[np.lexsort((p[:, 0], line))]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    v, f = body()
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(f.astype(np.uint32)))
    ordered = scan_points(v, f, args.points, 1)
    shuffled = ordered[np.random.default_rng(2).permutation(len(ordered))]
    print(f"signed distances, {args.points:,} points -> {len(f):,} triangles, best of {args.repeats}")
    print("  order       machscan     Open3D  vs Open3D   max |Δd| where the signs agree  sign disagreements (|d| > 1 µm)")
    for name, q in (("scan lines", ordered), ("shuffled", shuffled)):
        q32 = o3d.core.Tensor(q.astype(np.float32))
        ours = best_time(lambda q=q: machscan.signed_distances(q, v, f), args.repeats)
        ref = best_time(lambda q32=q32: scene.compute_signed_distance(q32), args.repeats)
        d = machscan.signed_distances(q, v, f).distances
        r = scene.compute_signed_distance(q32).numpy()
        agree = np.sign(d) == np.sign(r)
        flips = int(np.sum(~agree & (np.abs(d) > 1e-3)))
        print(
            f"  {name:<10} {ours * 1e3:8.0f} ms {ref * 1e3:8.0f} ms   {ref / ours:6.2f}x   "
            f"{np.abs(d - r)[agree].max():.1e} mm (float32)              {flips}"
        )


if __name__ == "__main__":
    main()
