"""The ``machscan points`` command: a raw scan to a workpiece point cloud."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from machscan.cli._shared import (
    _check_readings,
    _load_scan,
    _scan_arguments,
    _scan_summary,
    _write_cloud,
)

__all__ = ["add_parser", "run"]

def run(args: argparse.Namespace) -> int:
    scan = _load_scan(args)
    _check_readings(scan)
    t0 = time.perf_counter()
    points, frame_index = scan.wcs_points()
    seconds = time.perf_counter() - t0
    holds = _write_cloud(args.out, points, frame_index, binary=not args.ascii)
    for line in _scan_summary(scan, points, seconds):
        print(line)
    print(f"written   : {args.out} ({holds})")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    pts = sub.add_parser("points", help="turn a raw scan into a workpiece point cloud (PLY, PCD or a text point file)")
    _scan_arguments(pts)
    pts.add_argument(
        "--out",
        type=Path,
        default=Path("cloud.ply"),
        help="output point file: .ply, .pcd (with each point's frame) or .xyz, .csv, .txt, .pts, .asc (x, y, z) "
        "(default: %(default)s)",
    )
    pts.add_argument("--ascii", action="store_true", help="write ASCII PLY or PCD instead of binary")
    pts.set_defaults(run=run)
