"""Surface meshes against the reference libraries, side by side in one run (issue #10 §6):
Delaunay of 200 k points in xy against scipy.spatial.Delaunay (target ≥ 5×), and closest points
of 10 k queries on the Stanford bunny against trimesh.proximity.closest_point (≥ 100×; the
hierarchy is built inside each call, as trimesh builds its tree once and reuses it), and fast-
marching geodesic distances from one source on the bunny against potpourri3d's
MeshFastMarchingDistanceSolver (≥ 3×; its solver built once, outside the timing), and heat-method
distances from 20 sources against potpourri3d's MeshHeatMethodDistanceSolver (≥ 1.5×; the
factorization inside the timing for both: potpourri3d's constructor and 20 compute_distance calls),
and exact geodesic distances against pygeodesic's PyGeodesicAlgorithmExact (issue #33): one source with
both meshes prepared once outside the timing (a GeodesicSolver, a PyGeodesicAlgorithmExact), on one thread
(floor 6.0x) and on all; one call each with the setup inside; and eight sources, prepared once for both,
in one call against eight pygeodesic calls (floor 12x on two threads). Every library's time is the best of --repeat runs, except
trimesh's (one run of ~17 s) and pygeodesic's eight sources (best of half as many, at least 2).

    python benchmarks/bench_mesh.py [--repeat 5] [--bunny PATH]
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import potpourri3d
import pygeodesic.geodesic as pygeodesic
import trimesh
from scipy.spatial import Delaunay
from timing import best_time

import machscan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument(
        "--bunny", type=Path, default=Path(__file__).resolve().parents[1] / "data/stanford-bunny-mesh/stanford_bunny.ply"
    )
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 300, (200_000, 2))
    pts = np.column_stack([xy, 0.001 * (xy[:, 0] - 150) ** 2])
    ours = best_time(lambda: machscan.delaunay_xy(pts), args.repeat)
    ref = best_time(lambda: Delaunay(xy), args.repeat)
    print(f"Delaunay 200k points: machscan {ours * 1e3:.0f} ms, scipy {ref * 1e3:.0f} ms -> {ref / ours:.1f}x")
    m = machscan.read_mesh(args.bunny)
    v, f = np.asarray(m.vertices, dtype=np.float64), np.asarray(m.triangles)
    lo, hi = v.min(axis=0), v.max(axis=0)
    q = rng.uniform(lo - 0.01, hi + 0.01, (10_000, 3))
    mesh = trimesh.Trimesh(v, f, process=False)
    trimesh.proximity.closest_point(mesh, q[:10])  # trimesh's tree, built once, outside the timing
    ours = best_time(lambda: machscan.closest_points(v, f, q), args.repeat)
    ref = best_time(lambda: trimesh.proximity.closest_point(mesh, q), 1)
    print(
        f"closest points, 10k queries on the bunny: machscan {ours * 1e3:.1f} ms (tree built in the call), "
        f"trimesh {ref * 1e3:.0f} ms -> {ref / ours:.0f}x"
    )
    used = np.unique(f)
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))
    vu, fu = v[used], remap[f]
    src = int(remap[14558])
    solver = potpourri3d.MeshFastMarchingDistanceSolver(vu, fu)
    f0 = int(np.flatnonzero((fu == src).any(axis=1))[0])
    bary = [float(fu[f0][k] == src) for k in range(3)]
    ours = best_time(lambda: machscan.geodesic_distances(vu, fu, [src], method="fmm"), args.repeat)
    ref = best_time(lambda: solver.compute_distance([[(f0, bary)]], [[0.0]], False), args.repeat)
    print(
        f"fast marching, one source on the bunny: machscan {ours * 1e3:.1f} ms, potpourri3d {ref * 1e3:.1f} ms "
        f"-> {ref / ours:.1f}x"
    )
    twenty = [int(s) for s in np.linspace(0, len(vu) - 1, 20)]

    def pp3d_heat():
        solver = potpourri3d.MeshHeatMethodDistanceSolver(vu, fu)
        return [solver.compute_distance(s) for s in twenty]

    ours = best_time(lambda: machscan.geodesic_distances(vu, fu, twenty, method="heat"), args.repeat)
    ref = best_time(pp3d_heat, args.repeat)
    print(
        f"heat method, 20 sources on the bunny (factorization included): machscan {ours * 1e3:.0f} ms, "
        f"potpourri3d {ref * 1e3:.0f} ms -> {ref / ours:.1f}x"
    )
    # One source, the mesh prepared once for both (machscan.GeodesicSolver, pygeodesic's
    # PyGeodesicAlgorithmExact): on one thread (floor 6.0x, issue #33) and on all; then one call each
    # with the setup inside the timing for both.
    exact = pygeodesic.PyGeodesicAlgorithmExact(vu, fu)
    ref = best_time(lambda: exact.geodesicDistances(np.array([src]), None), args.repeat)
    prepared = machscan.GeodesicSolver(vu, fu, method="exact")
    with machscan.thread_limit(1):
        ours_1 = best_time(lambda: prepared.distances([src]), args.repeat)
    ours = best_time(lambda: prepared.distances([src]), args.repeat)
    print(
        f"exact geodesics, one source on the bunny, mesh prepared once for both: machscan {ours_1 * 1e3:.0f} ms "
        f"on 1 thread, {ours * 1e3:.0f} ms on {os.cpu_count()}; pygeodesic {ref * 1e3:.0f} ms -> "
        f"{ref / ours_1:.1f}x on 1 thread (floor 6.0x), {ref / ours:.1f}x"
    )
    ours = best_time(lambda: machscan.geodesic_distances(vu, fu, [src], method="exact"), args.repeat)
    ref_call = best_time(
        lambda: pygeodesic.PyGeodesicAlgorithmExact(vu, fu).geodesicDistances(np.array([src]), None), args.repeat
    )
    print(
        f"exact geodesics, one source on the bunny, one call each (setup included): machscan {ours * 1e3:.0f} ms, "
        f"pygeodesic {ref_call * 1e3:.0f} ms -> {ref_call / ours:.1f}x"
    )
    # Eight sources, the mesh prepared once for both (the floor, issue #33): one machscan call on the
    # prepared mesh (sources in parallel on all cores, and on one thread) against eight calls of
    # pygeodesic's prepared algorithm (it has no parallel path); then machscan's one call with the setup
    # inside, for the record.
    eight = np.array([int(s) for s in np.linspace(0, len(vu) - 1, 8)])
    ours = best_time(lambda: prepared.distances(eight), args.repeat)
    with machscan.thread_limit(1):
        ours_1 = best_time(lambda: prepared.distances(eight), args.repeat)
    ours_call = best_time(lambda: machscan.geodesic_distances(vu, fu, eight, method="exact"), args.repeat)
    ref = best_time(lambda: [exact.geodesicDistances(np.array([s]), None) for s in eight], max(2, args.repeat // 2))
    print(
        f"exact geodesics, 8 sources on the bunny, mesh prepared once for both: machscan {ours:.2f} s "
        f"({os.cpu_count()} threads), {ours_1:.2f} s (1 thread); pygeodesic {ref:.2f} s -> {ref / ours:.1f}x "
        f"(floor 12x on two threads), {ref / ours_1:.1f}x on one thread; machscan's one call with its setup "
        f"{ours_call:.2f} s -> {ref / ours_call:.1f}x"
    )

if __name__ == "__main__":
    main()
