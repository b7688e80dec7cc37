"""The ``machscan demo`` command: the groove inspection on a built-in synthetic scan."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from machscan.cli._shared import (
    _scan_summary,
    _write_cloud,
)

__all__ = ["add_parser", "run"]

def run(args: argparse.Namespace) -> int:
    from machscan import synth
    from machscan.inspection import inspect_grooves

    t0 = time.perf_counter()
    scan, truth = synth.groove_scan(seed=args.seed)
    t_synth = time.perf_counter() - t0
    print(f"machscan demo: synthetic engraved plate, 11 contours (seed {args.seed}), generated in {t_synth:.1f} s")
    t0 = time.perf_counter()
    points, frame_index = scan.wcs_points()
    t_points = time.perf_counter() - t0
    for line in _scan_summary(scan, points, t_points):
        print(line)
    err = synth.surface_error(points, frame_index, truth)
    print(
        f"round trip: workpiece points vs the true bent surface, away from the grooves ({err.n:,} points): "
        f"mean {err.mean * 1e3:+.2f} µm, robust sigma {err.robust_sigma * 1e3:.1f} µm "
        f"(profiler noise {(scan.profiler.noise or 0.0) * 1e3:.1f} µm), {err.n_outliers} spikes beyond "
        f"{err.outlier_threshold * 1e3:.0f} µm"
    )
    t0 = time.perf_counter()
    report = inspect_grooves(scan, truth.nominal_polylines, progress=None)
    t_inspect = time.perf_counter() - t0
    print(f"inspection: {t_inspect:.2f} s\n")
    print(report.summary())
    ok = report.used
    print(
        f"\nagainst the truth: width |error| median {np.median(np.abs(report.fits.width[ok] - truth.width[ok])) * 1e3:.1f} µm, "
        f"depth |error| median {100 * np.median(np.abs(report.fits.depth[ok] - truth.depth[ok]) / truth.depth[ok]):.2f} %, "
        f"center rms {np.sqrt(np.mean(np.sum((report.center_wcs[ok] - truth.center_wcs[ok]) ** 2, axis=1))) * 1e3:.1f} µm"
    )
    out = Path(args.out)
    paths = report.to_csv(out)
    keep = frame_index % args.cloud_every == 0
    cloud = out / "cloud.ply"
    _write_cloud(cloud, points[keep], frame_index[keep], binary=True)
    print(f"\nwritten   : {', '.join(str(p) for p in paths)}")
    print(f"            {cloud} (workpiece points of every {args.cloud_every}th frame; --cloud-every 1 for all)")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    demo = sub.add_parser("demo", help="run the groove inspection on a built-in synthetic scan")
    demo.add_argument("--out", type=Path, default=Path("machscan-demo"), help="output folder (default: %(default)s)")
    demo.add_argument("--seed", type=int, default=0, help="seed of the synthetic scan (default: %(default)s)")
    demo.add_argument(
        "--cloud-every", type=int, default=10, help="write the workpiece points of every Nth frame (default: %(default)s)"
    )
    demo.set_defaults(run=run)
