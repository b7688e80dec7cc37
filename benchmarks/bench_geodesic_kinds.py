"""Geodesic distances on meshes of other kinds than the bunny, side by side with the reference libraries
(issue #10 §2): a closed sphere (icosphere, 40,962 vertices) smooth and with 1 % radial bumps (saddles
everywhere), a torus, a rough open terrain meshed by delaunay_xy, and the issue's bent-skin scan at 1.3 mm
(36,000 points, open). One source per mesh (a third of the way through the vertex list), best of
--repeat runs for every library, one thread unless RAYON_NUM_THREADS says otherwise (pygeodesic and
potpourri3d have no parallel path; with one source only machscan's per-call set-up runs in parallel).
For each: exact vs pygeodesic (time and largest difference), fast marching vs potpourri3d (time, mean
relative error against the exact distances), the heat method vs potpourri3d (mean relative error).

    python benchmarks/bench_geodesic_kinds.py [--repeat 3]
"""

import argparse
import os

os.environ.setdefault("RAYON_NUM_THREADS", "1")

import numpy as np
import potpourri3d
import pygeodesic.geodesic as pygeodesic
import trimesh
from timing import best_time

import machscan
from machscan.synth import BentSkin


def kinds():
    rng = np.random.default_rng(0)
    sphere = trimesh.creation.icosphere(6, radius=50.0)
    torus = trimesh.creation.torus(60.0, 20.0, major_sections=320, minor_sections=120)
    xy = rng.uniform(0, 100, (40_000, 2))
    terrain = np.c_[xy, 3 * np.sin(xy[:, 0] / 7) * np.cos(xy[:, 1] / 5) + 0.3 * rng.standard_normal(len(xy))]
    scan = BentSkin().scan(1.3, 0.005, seed=0)
    yield "sphere, smooth", sphere.vertices, sphere.faces
    yield "sphere, 1 % bumps", sphere.vertices * (1 + 0.01 * rng.standard_normal((len(sphere.vertices), 1))), sphere.faces
    yield "torus", torus.vertices, torus.faces
    yield "rough terrain (open)", terrain, machscan.delaunay_xy(terrain)
    yield "bent skin scan 1.3 mm", scan, machscan.delaunay_xy(scan)


def compare(name, v, f, repeat):
    v, f = np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64)
    src = len(v) // 3
    exact = pygeodesic.PyGeodesicAlgorithmExact(v, f)
    reference = exact.geodesicDistances(np.array([src]), None)[0]
    ours = machscan.geodesic_distances(v, f, [src])[0]
    t_ours = best_time(lambda: machscan.geodesic_distances(v, f, [src]), repeat)
    t_ref = best_time(lambda: exact.geodesicDistances(np.array([src]), None), repeat)

    def error(d):
        return np.mean(np.abs(d - reference)) / np.mean(reference)

    f0 = int(np.flatnonzero((f == src).any(axis=1))[0])
    bary = [float(f[f0][k] == src) for k in range(3)]
    marching = potpourri3d.MeshFastMarchingDistanceSolver(v, f)
    fmm_ours = machscan.geodesic_distances(v, f, [src], method="fmm")[0]
    fmm_ref = np.asarray(marching.compute_distance([[(f0, bary)]], [[0.0]], False)).ravel()
    t_fmm = best_time(lambda: machscan.geodesic_distances(v, f, [src], method="fmm"), repeat)
    t_fmm_ref = best_time(lambda: marching.compute_distance([[(f0, bary)]], [[0.0]], False), repeat)
    heat_ours = machscan.geodesic_distances(v, f, [src], method="heat")[0]
    heat_ref = potpourri3d.MeshHeatMethodDistanceSolver(v, f).compute_distance(src)
    print(
        f"{name} ({len(v)} vertices): exact {t_ours * 1e3:.0f} ms, pygeodesic {t_ref * 1e3:.0f} ms -> "
        f"{t_ref / t_ours:.1f}x, largest difference {np.abs(ours - reference).max():.1e}; "
        f"fmm {t_fmm * 1e3:.1f} ms vs {t_fmm_ref * 1e3:.1f} ms -> {t_fmm_ref / t_fmm:.1f}x, error "
        f"{100 * error(fmm_ours):.3f} % vs {100 * error(fmm_ref):.3f} %; heat error {100 * error(heat_ours):.3f} % "
        f"vs {100 * error(heat_ref):.3f} %"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"RAYON_NUM_THREADS={os.environ['RAYON_NUM_THREADS']}")
    for name, v, f in kinds():
        compare(name, v, f, args.repeat)


if __name__ == "__main__":
    main()
