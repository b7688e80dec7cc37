"""How well a simplified cloud keeps the surface: the measure of issue #4 §4, shared by
tests/test_octree.py and the report it prints when run as a script.

The surface rebuilt from the kept points (xy-Delaunay, height linear in each triangle) is
compared with every original point: max and RMS of the vertical deviation, and the share of
original points outside the rebuilt surface (the boundary lost). A second, held-out reading
simplifies half of the points and measures the other half. The competitor is Open3D's
voxel grid with its voxel size chosen to keep the same number of points.

    python tests/octree_quality.py        # the table recorded in BENCHMARKS.md
"""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.tri as mtri
import numpy as np
import open3d
from scipy.spatial import Delaunay

import machscan
from machscan.synth import pocket_plate


@dataclass(frozen=True)
class Deviation:
    count: int
    max: float
    rms: float
    outside: float


def rebuilt_deviation(kept: np.ndarray, full: np.ndarray) -> Deviation:
    """Vertical deviation of `full` from the xy-Delaunay surface through `kept` (count: of
    `kept`)."""
    tri = Delaunay(kept[:, :2])
    # matplotlib's trapezoid map locates points in the same triangles; scipy's find_simplex
    # falls back to a slow scan for points on or just outside the hull.
    finder = mtri.TrapezoidMapTriFinder(mtri.Triangulation(kept[:, 0], kept[:, 1], triangles=tri.simplices))
    t = finder(full[:, 0], full[:, 1])
    inside = t >= 0
    a, b, c = (kept[tri.simplices[t[inside], i]] for i in range(3))
    q = full[inside]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    wb = ((q[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (q[:, 1] - a[:, 1])) / det
    wc = ((b[:, 0] - a[:, 0]) * (q[:, 1] - a[:, 1]) - (q[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])) / det
    dz = np.abs(a[:, 2] + wb * (b[:, 2] - a[:, 2]) + wc * (c[:, 2] - a[:, 2]) - q[:, 2])
    return Deviation(len(kept), float(dz.max()), float(np.sqrt(np.mean(dz**2))), float(1 - inside.mean()))


def voxel_at_count(points: np.ndarray, count: int, tolerance: float = 0.005) -> np.ndarray:
    """Open3D's voxel grid with the voxel size bisected until it keeps `count` points (within
    `tolerance`, relative)."""
    cloud = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(points))
    lo, hi = 1e-3, float(np.ptp(points, axis=0).max())
    best = None
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        kept = np.asarray(cloud.voxel_down_sample(mid).points)
        if best is None or abs(len(kept) - count) < abs(len(best) - count):
            best = kept
        if abs(len(kept) - count) <= tolerance * count:
            break
        lo, hi = (mid, hi) if len(kept) > count else (lo, mid)
    assert best is not None
    return best


def compare(points: np.ndarray, d_min: float, **options) -> tuple[Deviation, Deviation]:
    """(octree, voxel grid at the same count), measured at every original point — the issue's
    measure. The points the octree keeps lie on its own surface and count with deviation 0."""
    keep = machscan.octree_simplify(points, d_min, **options)
    return rebuilt_deviation(points[keep], points), rebuilt_deviation(voxel_at_count(points, len(keep)), points)


def compare_held_out(points: np.ndarray, d_min: float, seed: int = 1, **options) -> tuple[Deviation, Deviation, Deviation]:
    """(octree, voxel grid, no simplification): a random half of the points is simplified and
    the other half measured, so no measured point can have been kept. The third surface, through
    the whole simplified half, is the floor: the step between two samples is unknown to any
    method."""
    held_out = np.random.default_rng(seed).random(len(points)) < 0.5
    given, measured = points[~held_out], points[held_out]
    keep = machscan.octree_simplify(given, d_min, **options)
    return (
        rebuilt_deviation(given[keep], measured),
        rebuilt_deviation(voxel_at_count(given, len(keep)), measured),
        rebuilt_deviation(given, measured),
    )


RULES = {"paper": {}, "xy, refine 2": {"neighbors": "xy", "refine": 2}}


def main() -> None:
    parts = {wall: pocket_plate(wall_angle=wall) for wall in (90.0, 45.0)}
    print("At every original point:")
    print("part         d_min  rule            points   max octree / voxel   RMS octree / voxel   outside octree / voxel")
    for wall, points in parts.items():
        for d_min in (1.0, 2.0, 4.0):
            for name, options in RULES.items():
                o, v = compare(points, d_min, **options)
                print(
                    f"wall {wall:4.0f}°  {d_min:4.1f}   {name:<14} {o.count:7d}   {o.max:7.3f} / {v.max:.3f}"
                    f"      {o.rms:7.4f} / {v.rms:.4f}     {o.outside:6.2%} / {v.outside:.2%}"
                )
    print("Held out (half simplified, the other half measured; floor = the whole half kept):")
    print("part         d_min  rule            points   max octree / voxel / floor   RMS octree / voxel / floor")
    for wall, points in parts.items():
        for d_min in (1.0, 2.0, 4.0):
            for name, options in RULES.items():
                o, v, f = compare_held_out(points, d_min, **options)
                print(
                    f"wall {wall:4.0f}°  {d_min:4.1f}   {name:<14} {o.count:7d}   {o.max:7.3f} / {v.max:.3f} / {f.max:.3f}"
                    f"      {o.rms:7.4f} / {v.rms:.4f} / {f.rms:.4f}"
                )


if __name__ == "__main__":
    main()
