"""The ``machscan grooves`` command: groove width, depth and contour error from a raw scan and CAD contours."""

from __future__ import annotations

import argparse
from pathlib import Path

from machscan.cli._shared import (
    _check_readings,
    _groove_arguments,
    _groove_options,
    _load_scan,
    _progress_argument,
    _scan_arguments,
    _warn,
)

__all__ = ["add_parser", "run"]

def run(args: argparse.Namespace) -> int:
    from machscan.cad import read_contours
    from machscan.inspection import inspect_grooves

    scan = _load_scan(args)
    _check_readings(scan)
    cad = read_contours(args.cad)
    report = inspect_grooves(scan, cad, options=_groove_options(args), progress=args.progress)
    print(report.summary())
    paths = report.to_csv(args.out)
    print(f"\nwritten   : {', '.join(str(p) for p in paths)}")
    fitted = int(report.fits.ok.sum())
    if fitted < 0.5 * len(report.fits):
        _warn(
            f"only {fitted} of {len(report.fits)} frames have a fitted groove: check --window, --template "
            f"and the invalid readings (--sentinel, --valid-range)"
        )
    problem = report.matching_problem()
    if problem:
        _warn(problem)
        return 3
    if not report.contours:
        _warn("no contour was matched")
        return 3
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    gr = sub.add_parser("grooves", help="groove width, depth and contour error from a raw scan and CAD contours")
    _scan_arguments(gr)
    gr.add_argument("cad", nargs="+", type=Path, help="CAD contours: CSV (contour, x, y, z) or APT/CL files (GOTO points)")
    gr.add_argument("--out", type=Path, default=Path("grooves"), help="output folder for the CSV tables (default: %(default)s)")
    _groove_arguments(gr)
    _progress_argument(gr)
    gr.set_defaults(run=run)
