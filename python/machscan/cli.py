"""The ``machscan`` command (also ``python -m machscan``).

    machscan demo [--out DIR] [--seed 0]            synthetic engraved plate → groove tables
    machscan grooves SCAN CAD [CAD ...] [--out DIR] raw scan + CAD contours → groove tables (CSV);
                                                    exit status 3 when no contour matched
    machscan points SCAN [--out cloud.ply]          raw scan → workpiece point cloud (PLY)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import get_args

import numpy as np


def _write_cloud(path: Path, points: np.ndarray, frame_index: np.ndarray, binary: bool) -> None:
    from machscan.io import write_points

    path.parent.mkdir(parents=True, exist_ok=True)
    write_points(path, points, scalars={"frame": frame_index}, binary=binary)


def _warn(text: str) -> None:
    print(f"machscan: warning: {text}", file=sys.stderr)


def _check_readings(scan) -> None:
    """Warn when one exact value makes up a large share of the valid readings: a "no reading"
    code the profiler is not told about (its default sentinel is −99999) turns into points."""
    valid = scan.frames[scan.valid_mask()]
    if valid.size == 0:
        _warn("the scan holds no valid readings (all NaN, sentinel or out of range)")
        return
    sample = valid[:: max(1, valid.size // 1_000_000)]
    values, counts = np.unique(sample, return_counts=True)
    k = int(np.argmax(counts))
    share = counts[k] / sample.size
    if share >= 0.05:
        _warn(f"{100 * share:.0f} % of the valid readings are exactly {values[k]!r}: if that is the profiler's "
              f"no-reading code, pass --sentinel {values[k]!r} (or --valid-range) so they are dropped")


def _scan_summary(scan, points: np.ndarray, seconds: float) -> list[str]:
    readings = scan.frames.size
    dropped = readings - len(points)
    return [
        f"scan      : {scan.n_frames} frames x {scan.n_readings} readings "
        f"({scan.profiler.name}, pitch {scan.profiler.pitch} mm), {scan.duration:.3f} s of scanning",
        f"points    : {len(points):,} workpiece points in {seconds * 1e3:.0f} ms",
        f"dropped   : {dropped:,} invalid readings ({100.0 * dropped / readings:.2f} %: dropouts, sentinel, out of range)",
    ]


def _load_scan(args: argparse.Namespace):
    from machscan.scan import Profiler, Scan, read_scan_csv

    path = Path(args.scan)
    if path.suffix.lower() == ".npz":
        return Scan.load(path)
    missing = [n for n in ("poses", "pitch", "c2_offset", "mount") if getattr(args, n, None) is None]
    if missing:
        raise ValueError(f"scan: {path} is a CSV export; give --{' --'.join(m.replace('_', '-') for m in missing)} too")
    readings = args.readings or _csv_readings(path)
    profiler = Profiler(readings=readings, pitch=args.pitch, valid_range=tuple(args.valid_range) if args.valid_range else None,
                        sentinel=args.sentinel, name="profiler")
    return read_scan_csv(path, args.poses, profiler, args.c2_offset, args.mount)


def _csv_readings(path: Path) -> int:
    """Readings per frame of a frames CSV: the width of its first data row, less a leading
    time column when the header names one."""
    header: list[str] = []
    with open(path) as fh:
        for line in fh:
            cells = [c.strip() for c in line.split(",")]
            try:
                float(cells[0])
            except ValueError:
                header = header or cells
                continue
            timed = bool(header) and header[0].lower() in ("t", "time", "timestamp")
            return len(cells) - (1 if timed else 0)
    raise ValueError(f"scan: {path}: no frames")


def _demo(args: argparse.Namespace) -> int:
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
        f"(profiler noise {scan.profiler.noise * 1e3:.1f} µm), {err.n_outliers} spikes beyond "
        f"{err.outlier_threshold * 1e3:.0f} µm"
    )
    t0 = time.perf_counter()
    report = inspect_grooves(scan, truth.nominal_polylines)
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


def _grooves(args: argparse.Namespace) -> int:
    from machscan.cad import read_contours
    from machscan.inspection import inspect_grooves

    scan = _load_scan(args)
    _check_readings(scan)
    cad = read_contours(args.cad)
    report = inspect_grooves(scan, cad, window=args.window, template=args.template, alpha=args.alpha,
                             nominal_width=args.nominal_width, cluster_radius=args.cluster_radius,
                             max_match_distance=args.max_match_distance, max_se_ratio=args.max_se_ratio)
    print(report.summary())
    paths = report.to_csv(args.out)
    print(f"\nwritten   : {', '.join(str(p) for p in paths)}")
    fitted = int(report.fits.ok.sum())
    if fitted < 0.5 * len(report.fits):
        _warn(f"only {fitted} of {len(report.fits)} frames have a fitted groove: check --window, --template "
              f"and the invalid readings (--sentinel, --valid-range)")
    problem = report.matching_problem()
    if problem:
        _warn(problem)
        return 3
    if not report.contours:
        _warn("no contour was matched")
        return 3
    return 0


def _points(args: argparse.Namespace) -> int:
    scan = _load_scan(args)
    _check_readings(scan)
    t0 = time.perf_counter()
    points, frame_index = scan.wcs_points()
    seconds = time.perf_counter() - t0
    _write_cloud(args.out, points, frame_index, binary=not args.ascii)
    for line in _scan_summary(scan, points, seconds):
        print(line)
    print(f"written   : {args.out}")
    return 0


def _scan_arguments(p: argparse.ArgumentParser) -> None:
    from machscan.scan import SENTINEL

    p.add_argument("scan", type=Path, help="raw scan: .npz saved by Scan.save, or a CSV export (one frame per row)")
    g = p.add_argument_group("for a CSV scan")
    g.add_argument("--poses", type=Path, help="poses CSV (X, Y, Z, A, C, C2 per frame, optional leading t)")
    g.add_argument("--pitch", type=float, help="reading spacing, mm")
    g.add_argument("--readings", type=int, help="readings per frame (default: the file's)")
    g.add_argument("--c2-offset", type=float, nargs=3, metavar=("LX", "LY", "LZ"), help="C2 axis offset, mm")
    g.add_argument("--mount", type=float, nargs=6, metavar=("THETA", "PSI", "PHI", "DX", "DY", "DZ"),
                   help="sensor mount, rad and mm")
    g.add_argument("--valid-range", type=float, nargs=2, metavar=("LO", "HI"), help="measuring range, mm")
    g.add_argument("--sentinel", type=float, default=SENTINEL,
                   help="value the profiler returns for no reading (default: %(default)s)")


def build_parser() -> argparse.ArgumentParser:
    from machscan import __version__
    from machscan.grooves import DEFAULTS as GROOVE_DEFAULTS
    from machscan.grooves import Template

    parser = argparse.ArgumentParser(
        prog="machscan",
        description="On-machine measurement for five-axis machining: line-laser frames and axis "
        "positions to workpiece points and answers.",
    )
    parser.add_argument("--version", action="version", version=f"machscan {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    demo = sub.add_parser("demo", help="run the groove inspection on a built-in synthetic scan")
    demo.add_argument("--out", type=Path, default=Path("machscan-demo"), help="output folder (default: %(default)s)")
    demo.add_argument("--seed", type=int, default=0, help="seed of the synthetic scan (default: %(default)s)")
    demo.add_argument("--cloud-every", type=int, default=10,
                      help="write the workpiece points of every Nth frame (default: %(default)s)")
    demo.set_defaults(run=_demo)

    gr = sub.add_parser("grooves", help="groove width, depth and contour error from a raw scan and CAD contours")
    _scan_arguments(gr)
    gr.add_argument("cad", nargs="+", type=Path, help="CAD contours: CSV (contour, x, y, z) or APT/CL files (GOTO points)")
    gr.add_argument("--out", type=Path, default=Path("grooves"), help="output folder for the CSV tables (default: %(default)s)")
    gr.add_argument("--window", type=int, default=200,
                    help="readings around the line center fitted per frame (default: %(default)s)")
    gr.add_argument("--template", choices=get_args(Template), default=GROOVE_DEFAULTS["template"],
                    help="groove shape fitted: the best of the four section models (auto), one of them, or the "
                         "paper's tanh template (default: %(default)s)")
    gr.add_argument("--alpha", type=float, default=GROOVE_DEFAULTS["alpha"],
                    help="tanh template only: shape coefficient, 1/mm (default: %(default)s)")
    gr.add_argument("--nominal-width", type=float, default=GROOVE_DEFAULTS["nominal_width"],
                    help="tanh template only: starting groove width, mm (default: %(default)s)")
    gr.add_argument("--max-se-ratio", type=float, default=None,
                    help="leave out frames whose width or depth standard error exceeds this many times the "
                         "median (default: keep all; 5 suits the tanh template)")
    gr.add_argument("--cluster-radius", type=float, default=5.0, help="contour segmentation distance, mm (default: %(default)s)")
    gr.add_argument("--max-match-distance", type=float, default=10.0,
                    help="largest distance between a scanned contour and its CAD contour, mm (default: %(default)s)")
    gr.set_defaults(run=_grooves)

    pts = sub.add_parser("points", help="turn a raw scan into a workpiece point cloud (PLY)")
    _scan_arguments(pts)
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
    if getattr(args, "cloud_every", 1) < 1:
        parser.error("--cloud-every must be at least 1")
    try:
        return int(args.run(args))
    except (ValueError, OSError) as e:
        print(f"machscan: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
