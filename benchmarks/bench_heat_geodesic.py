"""Heat-method geodesic distances on the Stanford bunny against potpourri3d's
MeshHeatMethodDistanceSolver (defaults: t_coef=1, robust intrinsic Delaunay / mollified Laplacian),
side by side in one run (issue #10 §2; targets: no less accurate, ≥ 1.5× faster over 20 sources
with the factorization included in both).

The Python binding of the heat method is not wired yet, so the Rust side runs as the ignored cargo
test ``mesh::geodesic_heat::tests::bunny_report`` of a release test binary, fed a dump of the mesh;
it times ``geodesic_heat`` (build and factor once, then 20 sources) best of 3 in-process and writes
each variant's distances for the first three sources. Build the binary first:

    CARGO_TARGET_DIR=target cargo test --release --lib mesh::geodesic_heat
    python benchmarks/bench_heat_geodesic.py [--target target] [--exact /tmp/bunny_exact.npy]

Accuracy: mean |error| / mean distance against exact polyhedral distances (pygeodesic, Kirsanov's
MMP; computed and cached at --exact when missing, ~2 s per source) for sources 14029, 0 and 5000 of
the compacted mesh (unreferenced vertices dropped: potpourri3d needs that).
"""

from __future__ import annotations

import argparse
import glob
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import potpourri3d as pp3d
import trimesh

BUNNY = "/work/shared/data/stanford-bunny-mesh/stanford_bunny.ply"
ACCURACY_SOURCES = [14029, 0, 5000]
VARIANTS = ["cotan", "cotan_avg", "idt", "idt_avg"]


def bunny(path):
    m = trimesh.load(path, process=False)
    v, f = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
    used = np.unique(f)
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


def exact(v, f, path):
    if Path(path).exists():
        return np.load(path)
    import pygeodesic.geodesic as geodesic

    geo = geodesic.PyGeodesicAlgorithmExact(v, f)
    rows = np.array([geo.geodesicDistances(np.array([s]), None)[0] for s in ACCURACY_SOURCES])
    np.save(path, rows)
    return rows


def test_binary(target):
    bins = [p for p in glob.glob(f"{target}/release/deps/machscan-*") if "." not in os.path.basename(p)]
    return max(bins, key=os.path.getmtime)


def rust(exe, work, timing_only, threads=None):
    env = dict(os.environ, HEAT_DUMP=f"{work}/mesh.bin", HEAT_OUT=work)
    if timing_only:
        env["HEAT_TIMING_ONLY"] = "1"
    if threads:
        env["RAYON_NUM_THREADS"] = str(threads)
    args = [exe, "mesh::geodesic_heat::tests::bunny_report", "--exact", "--ignored", "--nocapture", "--test-threads=1"]
    return subprocess.run(args, env=env, capture_output=True, text=True, check=True).stdout


def relative(h, d):
    ok = np.isfinite(d) & (d < 1e10)
    return np.abs(h[ok] - d[ok]).mean() / d[ok].mean()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--target", default=os.environ.get("CARGO_TARGET_DIR", "target"))
    ap.add_argument("--bunny", default=BUNNY)
    ap.add_argument("--exact", default="/tmp/bunny_exact.npy")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    v, f = bunny(a.bunny)
    n = len(v)
    rng = np.random.default_rng(0)
    sources = ACCURACY_SOURCES + [int(x) for x in rng.choice(np.setdiff1d(np.arange(n), ACCURACY_SOURCES), 17, replace=False)]
    exe = test_binary(a.target)
    with tempfile.TemporaryDirectory() as work:
        with open(f"{work}/mesh.bin", "wb") as fh:
            fh.write(np.array([n, len(f)], "<u8").tobytes())
            fh.write(v.astype("<f8").tobytes())
            fh.write(f.astype("<u4").tobytes())
            fh.write(np.array([len(sources)], "<u8").tobytes())
            fh.write(np.array(sources, "<u8").tobytes())
        rust(exe, work, timing_only=False)
        ex = exact(v, f, a.exact)
        solver = pp3d.MeshHeatMethodDistanceSolver(v, f)
        print(f"bunny: {n} vertices, {len(f)} faces; mean |error| / mean distance vs exact, sources {ACCURACY_SOURCES}")
        theirs = [relative(solver.compute_distance(s), ex[i]) for i, s in enumerate(ACCURACY_SOURCES)]
        print(f"  {'potpourri3d':12}" + "".join(f"{100 * r:8.3f} %" for r in theirs))
        for name in VARIANTS:
            rows = np.fromfile(f"{work}/{name}.bin", "<f8").reshape(3, n)
            print(f"  {name:12}" + "".join(f"{100 * relative(rows[i], ex[i]):8.3f} %" for i in range(3)))
        theirs = np.inf
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            s = pp3d.MeshHeatMethodDistanceSolver(v, f)
            for x in sources:
                s.compute_distance(x)
            theirs = min(theirs, time.perf_counter() - t0)
        ours = float(rust(exe, work, timing_only=True).split("HEAT_TIME")[1].split()[0])
        ours1 = float(rust(exe, work, timing_only=True, threads=1).split("HEAT_TIME")[1].split()[0])
    print(f"{len(sources)} sources, factorization included, best of {a.repeat}:")
    print(f"  potpourri3d {1e3 * theirs:.1f} ms; machscan heat {1e3 * ours:.1f} ms ({theirs / ours:.2f}x)")
    print(f"  machscan heat on 1 thread {1e3 * ours1:.1f} ms ({theirs / ours1:.2f}x)")


if __name__ == "__main__":
    main()
