"""The ``machscan`` command (also ``python -m machscan``).

    machscan demo [--out scan.ply] [--seed 0]      synthetic groove scan → workpiece point cloud
    machscan points SCAN.npz [--out cloud.ply]     a saved raw scan → workpiece point cloud
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np


def _write_cloud(path: Path, points: np.ndarray, frame_index: np.ndarray, binary: bool) -> None:
    from machscan._core import write_points

    path.parent.mkdir(parents=True, exist_ok=True)
    write_points(path, points, scalars={"frame": frame_index}, binary=binary)


def _scan_summary(scan, points: np.ndarray, seconds: float) -> list[str]:
    readings = scan.frames.size
    dropped = readings - len(points)
    return [
        f"scan      : {scan.n_frames} frames x {scan.n_readings} readings "
        f"({scan.profiler.name}, pitch {scan.profiler.pitch} mm), {scan.duration:.3f} s of scanning",
        f"points    : {len(points):,} workpiece points in {seconds * 1e3:.0f} ms",
        f"dropped   : {dropped:,} invalid readings ({100.0 * dropped / readings:.2f} %: dropouts, sentinel, out of range)",
    ]


def _demo(args: argparse.Namespace) -> int:
    from machscan import synth

    t0 = time.perf_counter()
    scan, truth = synth.groove_scan(seed=args.seed)
    t_synth = time.perf_counter() - t0
    t0 = time.perf_counter()
    points, frame_index = scan.wcs_points()
    t_points = time.perf_counter() - t0
    _write_cloud(args.out, points, frame_index, binary=not args.ascii)
    print(f"machscan demo: synthetic engraved plate (seed {args.seed}), generated in {t_synth:.1f} s")
    for line in _scan_summary(scan, points, t_points):
        print(line)
    err = synth.surface_error(points, frame_index, truth)
    print(
        f"round trip: workpiece points vs the true bent surface, away from the grooves ({err.n:,} points): "
        f"mean {err.mean * 1e3:+.2f} µm, robust sigma {err.robust_sigma * 1e3:.1f} µm "
        f"(profiler noise {scan.profiler.noise * 1e3:.1f} µm), {err.n_outliers} spikes beyond "
        f"{err.outlier_threshold * 1e3:.0f} µm"
    )
    print(f"written   : {args.out}")
    return 0


def _points(args: argparse.Namespace) -> int:
    from machscan.scan import Scan

    scan = Scan.load(args.scan)
    t0 = time.perf_counter()
    points, frame_index = scan.wcs_points()
    seconds = time.perf_counter() - t0
    _write_cloud(args.out, points, frame_index, binary=not args.ascii)
    for line in _scan_summary(scan, points, seconds):
        print(line)
    print(f"written   : {args.out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    from machscan import __version__

    parser = argparse.ArgumentParser(
        prog="machscan",
        description="On-machine measurement for five-axis machining: line-laser frames and axis "
        "positions to workpiece points and answers.",
    )
    parser.add_argument("--version", action="version", version=f"machscan {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    demo = sub.add_parser("demo", help="run the main job on a built-in synthetic scan")
    demo.add_argument("--out", type=Path, default=Path("machscan-demo.ply"), help="output PLY (default: %(default)s)")
    demo.add_argument("--seed", type=int, default=0, help="seed of the synthetic scan (default: %(default)s)")
    demo.add_argument("--ascii", action="store_true", help="write ASCII PLY instead of binary")
    demo.set_defaults(run=_demo)

    pts = sub.add_parser("points", help="turn a saved raw scan (.npz) into a workpiece point cloud")
    pts.add_argument("scan", type=Path, help="raw scan saved with Scan.save (.npz)")
    pts.add_argument("--out", type=Path, default=Path("cloud.ply"), help="output PLY (default: %(default)s)")
    pts.add_argument("--ascii", action="store_true", help="write ASCII PLY instead of binary")
    pts.set_defaults(run=_points)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 0
    try:
        return int(args.run(args))
    except (ValueError, OSError) as e:
        print(f"machscan: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
