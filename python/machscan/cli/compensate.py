"""The ``machscan compensate`` command: mirror milling, a toolpath carried onto the scanned, bent skin."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import get_args

import numpy as np

from machscan.cli._shared import (
    _check_positive_mm,
    _read_rows,
    _warn,
    _write_table,
)

__all__ = ["add_parser", "run"]

def run(args: argparse.Namespace) -> int:
    from machscan.io import read_points, read_toolpath

    _check_positive_mm("--max-error", args.max_error)
    if args.simulate:
        return _compensate_simulated(args)
    if args.theoretical is None or args.scan is None or args.toolpath is None or args.locating is None or args.matching is None:
        raise ValueError("compensate: give THEORETICAL SCAN TOOLPATH --locating and --matching (or --simulate)")
    theoretical, scan = read_points(args.theoretical), read_points(args.scan)
    from machscan.scan import _check_finite_rows

    _check_finite_rows(theoretical, "THEORETICAL", f"x, y, z in mm, as read from {args.theoretical}")
    _check_finite_rows(scan, "SCAN", f"x, y, z in mm, as read from {args.scan}")
    locating = _read_rows(args.locating, "--locating", (6,))
    if len(locating) != 2:
        raise ValueError(f"--locating: {args.locating} has {len(locating)} rows, expected the 2 locating points")
    matching = _read_rows(args.matching, "--matching", (3, 6))
    toolpath = read_toolpath(args.toolpath)
    return _run_compensation(args, theoretical, scan, locating, matching, toolpath)


def _run_compensation(args, theoretical, scan, locating, matching, toolpath, truth=None) -> int:
    """Match, compensate, write the CL file and the tables, print the report; compare with ``truth`` (points
    and normals) when the part is simulated."""
    from machscan.io import write_toolpath
    from machscan.matching import isometric_match
    from machscan.toolpath import compensate_toolpath

    t0 = time.perf_counter()
    initial = matching[:, 3:6] if matching.shape[1] == 6 else None
    match = isometric_match(
        theoretical,
        scan,
        locating[:, :3],
        locating[:, 3:],
        matching[:, :3],
        initial,
        jacobian=args.jacobian,
        method=args.method,
        spacing=args.mesh_spacing,
        max_edge=args.max_edge,
    )
    t1 = time.perf_counter()
    path = compensate_toolpath(
        toolpath,
        matching[:, :3],
        match.points,
        scan,
        interpolation=args.interpolation,
        normals=args.normals,
        max_edge=args.max_edge,
    )
    t2 = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_toolpath(out / "compensated.cl", path.points, axes=path.axes, feeds=toolpath.feeds, segments=toolpath.segments)
    _write_table(
        out / "matched.csv",
        "x_mm,y_mm,z_mm,actual_x_mm,actual_y_mm,actual_z_mm",
        np.column_stack([matching[:, :3], match.points]),
    )
    moved = np.linalg.norm(path.points - toolpath.points, axis=1)
    _write_table(
        out / "report.csv",
        "index,x_mm,y_mm,z_mm,compensated_x_mm,compensated_y_mm,compensated_z_mm,i,j,k,moved_mm,inside,on_scan",
        np.column_stack([np.arange(len(moved)), toolpath.points, path.points, path.axes, moved, path.inside, path.on_scan]),
    )
    print(
        f"matching  : {len(match.points)} points, T {match.objective[-1] * 1e3:.2f} µm, E {match.max_error[-1] * 1e3:.2f} "
        f"µm after {match.iterations} iterations (stop: {match.stop}, {args.jacobian} Jacobian, {args.method} "
        f"geodesics), {t1 - t0:.1f} s"
    )
    print(
        f"toolpath  : {len(moved)} points moved by {moved.min():.3f} … {moved.max():.3f} mm, "
        f"{int((~path.inside).sum())} outside the matching hull, {int((~path.on_scan).sum())} beyond the scan, "
        f"{t2 - t1:.2f} s"
    )
    if truth is not None:
        want, normals = truth
        err = np.linalg.norm(path.points - want, axis=1)[path.inside]
        before = np.linalg.norm(toolpath.points - want, axis=1)[path.inside]
        tilt = np.degrees(np.arccos(np.clip(np.sum(path.axes * normals, axis=1), -1, 1)))[path.inside]
        print(
            f"truth     : compensated path within {err.max() * 1e3:.1f} µm (max; {np.sqrt(np.mean(err**2)) * 1e3:.1f} "
            f"µm RMS), axes within {tilt.max():.3f}°; uncompensated {before.max():.3f} mm "
            f"({100 * (1 - err.max() / before.max()):.2f} % less)"
        )
    print(f"written   : {out / 'compensated.cl'}, {out / 'matched.csv'}, {out / 'report.csv'}")
    problems = []
    if not match.converged:
        problems.append("the match did not converge")
    elif match.max_error[-1] > args.max_error:
        problems.append(
            f"the match ended with E {match.max_error[-1] * 1e3:.1f} µm, above --max-error {args.max_error * 1e3:g} µm: "
            "the matched points are not where the part is"
        )
    if not path.inside.all():
        problems.append("tool points outside the matching hull were extrapolated (report.csv, inside = 0)")
    if not path.on_scan.all():
        problems.append("tool points map beyond the scan and were put on its edge (report.csv, on_scan = 0)")
    for problem in problems:
        _warn(problem)
    return 3 if problems else 0


def _mesh_spacing(text: str) -> float | str | None:
    """``--mesh-spacing``: "auto", "all" (every point) or a spacing in mm."""
    if text in ("auto", "all"):
        return None if text == "all" else text
    try:
        mm = float(text)
    except ValueError:
        mm = float("nan")
    if not (np.isfinite(mm) and mm > 0):
        raise argparse.ArgumentTypeError(f"expected auto, all or a positive spacing in mm, got {text!r}")
    return mm


def _compensate_simulated(args: argparse.Namespace) -> int:
    from machscan.io import Toolpath, write_points, write_toolpath
    from machscan.synth import BentSkin, misplacement

    _check_positive_mm("--scan-spacing", args.scan_spacing)
    skin = BentSkin(pose=misplacement(args.seed, translation=1.0, rotation=np.deg2rad(0.5)))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    theoretical, scan = skin.grid(args.scan_spacing), skin.scan(args.scan_spacing, 0.005, seed=args.seed)
    r = skin.locating()
    locating = np.column_stack([r, skin.actual(r)[0]])
    matching = skin.matching_grid()
    tools = np.vstack([skin.raster(depth=0.0), skin.raster(step=25.0, depth=-2.0)])
    up = np.tile([0.0, 0.0, 1.0], (len(tools), 1))
    toolpath = Toolpath(
        tools, up, np.full(len(tools), 1200.0), np.repeat([0, 1], [len(skin.raster()), len(tools) - len(skin.raster())])
    )
    write_points(out / "theoretical.ply", theoretical)
    write_points(out / "scan.ply", scan)
    _write_table(out / "locating.csv", "x_mm,y_mm,z_mm,actual_x_mm,actual_y_mm,actual_z_mm", locating)
    _write_table(out / "matching.csv", "x_mm,y_mm,z_mm", matching)
    write_toolpath(out / "theoretical.cl", tools, axes=up, feeds=toolpath.feeds, segments=toolpath.segments)
    print(
        f"synthetic skin: 300 × 200 mm bent to R = 1000 mm, misplaced 1 mm / 0.5°, scanned at {args.scan_spacing:g} mm "
        f"with 5 µm noise; inputs in {out}\n"
    )
    return _run_compensation(args, theoretical, scan, locating, matching, toolpath, truth=skin.actual(tools))


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    from machscan.matching import MATCH_JACOBIAN, MATCH_METHOD, MATCH_SPACING, Jacobian
    from machscan.mesh import GeodesicMethod
    from machscan.toolpath import COMPENSATE_INTERPOLATION, COMPENSATE_NORMALS, Interpolation, SurfaceNormals

    co = sub.add_parser("compensate", help="mirror milling: carry a toolpath onto the scanned, bent skin")
    co.add_argument("theoretical", nargs="?", type=Path, help="theoretical surface points (PLY/PCD/XYZ/CSV)")
    co.add_argument("scan", nargs="?", type=Path, help="scan of the clamped skin (PLY/PCD/XYZ/CSV)")
    co.add_argument("toolpath", nargs="?", type=Path, help="toolpath programmed on the theoretical surface (APT/CL)")
    co.add_argument(
        "--locating",
        type=Path,
        help="CSV, 2 rows: theoretical x, y, z and measured actual x, y, z of the locating points (a first line that is "
        "not numbers is a header)",
    )
    co.add_argument(
        "--matching",
        type=Path,
        help="CSV: theoretical matching points x, y, z (and optionally starting actual x, y, z; a first line that is not "
        "numbers is a header)",
    )
    co.add_argument(
        "--out",
        type=Path,
        default=Path("compensation"),
        help="output folder: compensated.cl, matched.csv, report.csv (default: %(default)s)",
    )
    co.add_argument(
        "--jacobian", choices=get_args(Jacobian), default=MATCH_JACOBIAN, help="matching Jacobian (default: %(default)s)"
    )
    co.add_argument(
        "--method", choices=get_args(GeodesicMethod), default=MATCH_METHOD, help="geodesic distances (default: %(default)s)"
    )
    co.add_argument(
        "--interpolation",
        choices=get_args(Interpolation),
        default=COMPENSATE_INTERPOLATION,
        help="mapping between the matching points (default: %(default)s)",
    )
    co.add_argument(
        "--normals",
        choices=get_args(SurfaceNormals),
        default=COMPENSATE_NORMALS,
        help="actual surface point and normal (default: %(default)s)",
    )
    co.add_argument("--max-edge", type=float, default=None, help="trim mesh edges longer than this, mm")
    co.add_argument(
        "--max-error",
        type=float,
        default=0.05,
        help="largest geodesic distance mismatch E the match may end with, mm; above it the run warns and exits 3 "
        "(default: %(default)s, the 50 µm a compensated path must meet)",
    )
    co.add_argument("--simulate", action="store_true", help="run on the built-in bent skin and compare with its truth")
    co.add_argument(
        "--mesh-spacing",
        type=_mesh_spacing,
        default=MATCH_SPACING,
        help="surfaces thinned to this xy spacing for the matching's geodesics, mm; auto (about 2,000 vertices) or all "
        "(default: %(default)s)",
    )
    co.add_argument(
        "--scan-spacing",
        type=float,
        default=1.3,
        help="scan spacing of the simulated skin, mm (default: %(default)s)",
    )
    co.add_argument("--seed", type=int, default=0, help="seed of the simulated misplacement and noise (default: %(default)s)")
    co.set_defaults(run=run)
