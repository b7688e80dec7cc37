"""The ``machscan batch`` command: an analysis over many scans on a Dask cluster."""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from machscan.cli._shared import (
    _csv_text,
    _groove_arguments,
    _groove_options,
    _progress_argument,
    _warn,
)

if TYPE_CHECKING:
    from machscan.inspection import InspectionOptions


__all__ = ["BatchGrooves", "add_parser", "inspect_groove_file", "run"]

@dataclass(frozen=True)
class BatchGrooves:
    """What one scan of `machscan batch grooves` gave (its tables are in its folder)."""

    frames: int
    fitted: int
    contours: int
    problem: str | None
    folder: str


def inspect_groove_file(path: str, cad: list, options: InspectionOptions, out: str) -> BatchGrooves:
    """One task of `machscan batch grooves`: the scan at `path` inspected, its tables written to
    `out`/<scan name>/."""
    from machscan.inspection import inspect_grooves
    from machscan.scan import Scan

    p = Path(path)
    if p.suffix.lower() == ".zarr" or p.is_dir():
        from machscan.dask import open_scan

        scan = open_scan(p).compute()
    else:
        scan = Scan.load(p)
    report = inspect_grooves(scan, cad, options=options)
    folder = Path(out) / p.stem
    report.to_csv(folder)
    problem = report.matching_problem() or (None if report.contours else "no contour was matched")
    return BatchGrooves(len(report.fits), int(report.fits.ok.sum()), len(report.contours), problem, str(folder))


def run(args: argparse.Namespace) -> int:
    import functools

    from machscan.cad import read_contours

    try:
        from distributed import Client, LocalCluster

        from machscan.dask import map_files
    except ImportError:
        raise ValueError("batch: needs Dask: pip install 'machscan[dask]'") from None
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers: must be at least 1, got {args.workers}")
    if args.threads < 1:
        raise ValueError(f"--threads: must be at least 1, got {args.threads}")
    cad = read_contours(args.cad)
    task = functools.partial(inspect_groove_file, cad=cad, options=_groove_options(args), out=str(args.out))
    args.out.mkdir(parents=True, exist_ok=True)
    if args.scheduler:
        with Client(args.scheduler) as client:
            outcomes = map_files(task, args.scans, client=client, threads=args.threads, progress=args.progress)
    else:
        workers = args.workers or os.cpu_count() or 1
        with (
            LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster,
            Client(cluster) as client,
        ):
            outcomes = map_files(task, args.scans, client=client, threads=args.threads, progress=args.progress)
    rows = ["scan,ok,frames,fitted,contours,folder,problem"]
    failed = 0
    for o in outcomes:
        r = o.result
        if o.ok:
            note = f"; {r.problem}" if r.problem else ""
            print(f"{o.path}: {r.fitted} of {r.frames} frames fitted, {r.contours} contours{note}")
            rows.append(f"{o.path},{r.problem is None},{r.frames},{r.fitted},{r.contours},{r.folder},{_csv_text(r.problem)}")
            failed += r.problem is not None
        else:
            _warn(f"{o.path}: {o.error}")
            rows.append(f"{o.path},False,,,,,{_csv_text(o.error)}")
            failed += 1
    table = args.out / "batch.csv"
    table.write_text("\n".join(rows) + "\n")
    print(f"\n{len(outcomes) - failed} of {len(outcomes)} scans done without a problem; written {table}")
    return 3 if failed else 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    batch = sub.add_parser("batch", help="run an analysis over many scans on a Dask cluster (needs machscan[dask])")
    jobs = batch.add_subparsers(dest="job", metavar="JOB", required=True)
    bg = jobs.add_parser("grooves", help="the groove inspection of `machscan grooves` on every scan, one task per file")
    bg.add_argument("scans", nargs="+", type=Path, help="scans: .zarr folders (machscan.dask.save_scan) or .npz (Scan.save)")
    bg.add_argument("--cad", nargs="+", type=Path, required=True, help="CAD contours, as for `machscan grooves`")
    _groove_arguments(bg)
    bg.add_argument(
        "--out",
        type=Path,
        default=Path("batch"),
        help="output folder: one folder of tables per scan, batch.csv (default: %(default)s)",
    )
    bg.add_argument(
        "--workers", type=int, default=None, help="worker processes of the local cluster (default: one per core)"
    )
    bg.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786) to use instead of a local cluster")
    bg.add_argument("--threads", type=int, default=1, help="threads each task's kernels use (default: %(default)s)")
    _progress_argument(bg)
    bg.set_defaults(run=run)
