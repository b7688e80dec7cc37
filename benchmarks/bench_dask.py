"""Scaling of machscan.dask on this machine (issue #12 §3): the groove fit over 200 000 frames read from Zarr,
and a batch of scans, on a LocalCluster of 1 and 2 worker processes (one thread each, one kernel thread per
task) against the in-memory call on all cores. Side by side in one run; best of --repeat.

    python benchmarks/bench_dask.py [--frames 200000] [--chunk 10000] [--scans 8] [--repeat 3]

Targets: 1 → 2 workers ≥ 1.7×; 2 workers within 1.5× of the in-memory call.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile

import numpy as np
from distributed import Client, LocalCluster
from timing import best_time

import machscan
import machscan.dask as md
from machscan.synth.frames import groove_frames


def fits_of_scan(path: str) -> int:
    """One batch task: the groove fit of a whole scan file (frames read on the worker)."""
    scan = md.open_scan(path)
    return int(machscan.fit_grooves(scan.profiler.x, scan.frames.compute()).ok.sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=200_000)
    ap.add_argument("--chunk", type=int, default=10_000)
    ap.add_argument("--scans", type=int, default=8)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    # 20 000 distinct V/U/trapezoid frames of 200 readings, repeated up to the frame count (a fit's cost does
    # not depend on having seen the frame before).
    parts = [groove_frames(shape, 20_000 // 3 + 1, seed=k) for k, shape in enumerate(("v", "u", "trapezoid"))]
    x = parts[0].x
    z = np.concatenate([p.z for p in parts])
    z = np.tile(z, (math.ceil(args.frames / len(z)), 1))[: args.frames]
    with tempfile.TemporaryDirectory(prefix="bench_dask_") as tmp:
        run(args, x, z, tmp)


def run(args, x, z, tmp) -> None:
    profiler = machscan.Profiler(readings=len(x), pitch=float(x[1] - x[0]))
    scan = machscan.Scan(z, np.zeros((len(z), 6)), np.arange(len(z)) * 1e-4, profiler, (0.0, 0.0, 100.0), np.zeros(6))
    md.save_scan(scan, os.path.join(tmp, "long.zarr"), chunk_frames=args.chunk)
    frames = md.open_scan(os.path.join(tmp, "long.zarr")).frames
    print(f"{args.frames:,} frames x {len(x)} readings in Zarr chunks of {args.chunk:,} frames ({frames.numblocks[0]} chunks)")

    # A batch: scans of 25 000 frames each.
    paths = []
    for k in range(args.scans):
        path = os.path.join(tmp, f"scan{k}.zarr")
        md.save_scan(scan.select(slice(k * 5_000, k * 5_000 + 25_000)), path, chunk_frames=args.chunk)
        paths.append(path)

    ref = machscan.fit_grooves(x, z)
    t_memory = best_time(lambda: machscan.fit_grooves(x, z), args.repeat)
    t_batch_memory = best_time(lambda: [fits_of_scan(p) for p in paths], args.repeat)
    rows = [("in memory, all cores", t_memory, t_batch_memory)]
    for workers in (1, 2):
        with (
            LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster,
            Client(cluster) as client,
        ):
            lazy = md.fit_grooves(x, frames)
            got = lazy.compute()
            assert np.array_equal(got.width, ref.width, equal_nan=True)
            client.run(lambda: machscan.fit_grooves(x, z[:100]))  # warm the workers' imports
            t = best_time(lambda: md.fit_grooves(x, frames).compute(), args.repeat)
            tb = best_time(lambda: md.map_files(fits_of_scan, paths, client=client, progress=False), args.repeat)
            rows.append((f"LocalCluster, {workers} worker{'s' if workers > 1 else ''}", t, tb))
            if workers == 2:
                # What a real cluster changes: the cost per task (chunk size) and where the data starts.
                sweep = []
                for chunk in (1_000, 5_000, 40_000):
                    path = os.path.join(tmp, f"long{chunk}.zarr")
                    md.save_scan(scan, path, chunk_frames=chunk)
                    f = md.open_scan(path).frames
                    sweep.append((chunk, best_time(lambda f=f: md.fit_grooves(x, f).compute(), args.repeat)))
                shipped = best_time(lambda: md.fit_grooves(x, z).compute(), args.repeat)
    print("2 workers, by chunk size (Zarr chunks read on the workers):")
    for chunk, t in sweep:
        print(f"  {chunk:>6,} frames per chunk: {t:6.2f} s, {args.frames / chunk:5.0f} tasks, {args.frames / t:8,.0f} frames/s")
    print(f"  frames in the client's memory, sent to the workers ({z.nbytes / 1e6:.0f} MB): {shipped:.2f} s")
    print(f"{'':28s} {'fit_grooves':>12s} {'frames/s':>10s} {'batch':>9s}")
    for name, t, tb in rows:
        print(f"{name:28s} {t:10.2f} s {args.frames / t:10,.0f} {tb:7.2f} s")
    (_, t1, b1), (_, t2, b2) = rows[1], rows[2]
    print(f"1 → 2 workers: fit_grooves {t1 / t2:.2f}x, batch {b1 / b2:.2f}x (target >= 1.7x)")
    print(f"2 workers / in memory: fit_grooves {t2 / t_memory:.2f}, batch {b2 / t_batch_memory:.2f} (target <= 1.5)")


if __name__ == "__main__":
    main()
