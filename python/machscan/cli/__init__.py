"""The ``machscan`` command (also ``python -m machscan``).

machscan demo [--out DIR] [--seed 0]            synthetic engraved plate → groove tables
machscan grooves SCAN CAD [CAD ...] [--out DIR] raw scan + CAD contours → groove tables (CSV);
                                                exit status 3 when no contour matched
machscan points SCAN [--out cloud.ply]          raw scan → workpiece point cloud (PLY)
machscan calibrate SCAN --radius R [--out mount.txt]
                                                the sensor mount from a scan of a reference sphere
                                                (--simulate: the built-in sphere and its truth)
machscan position MODEL --plan plan.csv         model → probe points and approach directions
machscan position MODEL --plan plan.csv --measured probed.csv [--out pose.txt]
                                                one probe round → part pose, error table
machscan position --simulate                    the probe rounds on the built-in blade
machscan allowance MODEL BLANK [--out a.ply]    stock per model point (PLY/PCD/XYZ/CSV);
                                                exit status 3 when the minimum does not hold
machscan allowance MODEL BLANK --fit [--start pose.txt] [--local]
                                                the blank's pose first: coarse alignment, ICP, the
                                                envelope fit (--local: the envelope fit alone)
machscan compare SCAN CAD --tolerance T [--fit] [--dof xyc] [--out DIR]
                                                signed deviation from the CAD (STEP/IGES or a mesh),
                                                per point and per CAD face, with a figure; exit
                                                status 3 when points are out of tolerance
machscan compensate THEORETICAL SCAN TOOLPATH --locating loc.csv --matching match.csv [--out DIR]
                                                mirror milling: toolpath onto the bent skin (CL)
                                                and a report; exit status 3 when the match did
                                                not converge or ended above --max-error, or tool
                                                points lie outside the hull or beyond the scan
machscan compensate --simulate [--out DIR]      the same on the built-in bent skin, with its truth
machscan grind ALLOWANCE [--removal ...] [--out DIR]
                                                belt-grinding paths (CL, feeds in mm/min) from an
                                                allowance file, or MODEL --blank BLANK; a path whose
                                                simulated pass leaves --band is not written (exit 3)
machscan batch grooves SCAN... --cad CAD... [--workers N | --scheduler ADDR] [--out DIR]
                                                the groove inspection over many scans on a Dask
                                                cluster; exit status 3 when a scan failed
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from typing import TextIO

from machscan.cli import allowance, batch, calibrate, compare, compensate, demo, grind, grooves, points, position

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    from machscan import __version__

    parser = argparse.ArgumentParser(
        prog="machscan",
        description="On-machine measurement for five-axis machining: line-laser frames and axis "
        "positions to workpiece points and answers.",
    )
    parser.add_argument("--version", action="version", version=f"machscan {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    for command in (demo, grooves, points, calibrate, position, allowance, compare, compensate, grind, batch):
        command.add_parser(sub)
    return parser


class _UntilClosed:
    """Standard output that drops what is printed once its reader has gone (``machscan allowance ... | head``): the
    command still writes its files and exits with its own status, where a broken pipe would have stopped it between
    its table and its output file."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream
        self._gone = False

    def _guard(self, action: Callable[[], object]) -> None:
        if self._gone:
            return
        try:
            action()
        except BrokenPipeError:
            self._gone = True
            # The interpreter flushes the real stream at exit: point it where a write cannot fail.
            try:
                os.dup2(os.open(os.devnull, os.O_WRONLY), self._stream.fileno())
            except (OSError, ValueError):
                pass

    def write(self, text: str) -> int:
        self._guard(lambda: self._stream.write(text))
        return len(text)

    def flush(self) -> None:
        self._guard(self._stream.flush)

    def __getattr__(self, name: str) -> object:
        return getattr(self._stream, name)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 0
    if getattr(args, "cloud_every", 1) < 1:
        parser.error("--cloud-every must be at least 1")
    stdout = sys.stdout
    sys.stdout = _UntilClosed(stdout)  # type: ignore[assignment]
    try:
        return int(args.run(args))
    except (ValueError, OSError) as e:
        print(f"machscan: error: {e}", file=sys.stderr)
        return 2
    finally:
        sys.stdout = stdout


if __name__ == "__main__":
    sys.exit(main())
