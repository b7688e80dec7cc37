"""The ``machscan grind`` command: belt-grinding paths from an allowance cloud."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from machscan.cli._shared import (
    _check_positive_mm,
    _floats,
    _read_model,
    _read_rows,
    _warn,
    _write_table,
    mesh_spacing,
)

__all__ = ["add_parser", "run"]

def _read_allowance(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Model points, normals and allowance as ``machscan allowance`` writes them: a point file with normals and an
    ``allowance`` scalar, or a CSV table x, y, z, nx, ny, nz, allowance."""
    from machscan.io import read

    if path.suffix.lower() in (".csv", ".txt"):
        # NaN in the allowance column: no stock measured there (as `machscan allowance` writes it).
        rows = _read_rows(path, "ALLOWANCE", (7,), nan_columns=(6,))
        return rows[:, :3], rows[:, 3:6], rows[:, 6]
    f = read(path)
    if f.normals is None or "allowance" not in f.scalars:
        raise ValueError(f"ALLOWANCE: {path} holds no normals and 'allowance' field (write it with `machscan allowance`)")
    return f.points, f.normals, f.scalars["allowance"]


def run(args: argparse.Namespace) -> int:
    from machscan.cloud import point_spacing
    from machscan.io import read_points
    from machscan.registration import allowance
    from machscan.synth import blade_allowance
    from machscan.toolpath import RemovalModel, grinding_paths

    _check_positive_mm("--band", args.band)
    if args.simulate:
        cloud = blade_allowance(spacing=args.spacing, seed=args.seed)
        points, normals, stock = cloud.points, cloud.normals, cloud.allowance
        print(f"simulated blade: {len(points):,} model points every ~{args.spacing:g} mm, allowance "
              f"{stock.min():.3f} … {stock.max():.3f} mm")
    elif args.source is None:
        raise ValueError("grind: give ALLOWANCE (or MODEL --blank BLANK, or --simulate)")
    elif args.blank is not None:
        blank = read_points(args.blank)
        points, normals = _read_model(args.source, spacing=lambda: mesh_spacing(point_spacing(blank)))
        stock = allowance(points, normals, blank)
    else:
        points, normals, stock = _read_allowance(args.source)
    model = None
    if args.removal is not None:
        c, e1, e2, e3, vb, force, lo, hi = _floats(args.removal, 8, "--removal")
        model = RemovalModel(C=c, exponents=(e1, e2, e3), belt_speed=vb, force=force, feed_limits=(lo, hi), feed_unit="mm/s")
    section = _floats(args.section_normal, 3, "--section-normal")
    paths = grinding_paths(
        points,
        normals,
        stock,
        args.tool_radius,
        args.scallop_height,
        section,
        removal_model=model,
        spacing=args.path_spacing,
        feed_step=args.feed_step,
        band=args.band,
    )
    check = paths.check
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    _write_table(
        out / "path.csv",
        "x_mm,y_mm,z_mm,nx,ny,nz,row,curvature_per_mm,allowance_mm,feed_mm_per_min",
        np.column_stack([paths.points, paths.normals, paths.row, paths.curvature, paths.allowance, paths.feed_per_minute()]),
    )
    pieces = len(paths.row_offsets)
    count = np.bincount(paths.row, minlength=pieces)
    # Cloud points without stock measured (NaN allowance) nearest each row: left out, counted.
    no_stock = np.bincount(check.section[np.isnan(check.deviation)], minlength=pieces)
    _write_table(
        out / "report.csv",
        "row,offset_mm,points,closed,deviation_min_mm,deviation_mean_mm,deviation_max_mm,no_stock_points",
        np.column_stack(
            [np.arange(pieces), paths.row_offsets, count, paths.row_closed, check.minimum, check.mean, check.maximum, no_stock]
        ),
    )
    sections = np.unique(paths.row_offsets)
    steps = np.diff(sections)
    cut = f", {pieces} pieces where a row is cut" if pieces > len(sections) else ""
    spacing = f", spacing {steps.min():.3f} … {steps.max():.3f} mm" if len(sections) > 1 else ""
    print(f"rows      : {len(sections)}{cut}{spacing}")
    print(f"points    : {len(paths.points):,}")
    if paths.without_stock:
        print(f"no stock  : {paths.without_stock:,} model points have no allowance (the blank does not cover them): left out")
    if model is not None:
        clamped = int(np.sum((paths.feed <= model.feed_limits[0]) | (paths.feed >= model.feed_limits[1])))
        per_minute = paths.feed_per_minute()
        changes = 1 + int(np.count_nonzero(np.diff(paths.feed)))
        print(
            f"feed      : {per_minute.min():.4g} … {per_minute.max():.4g} mm/min ({paths.feed.min():.4g} … "
            f"{paths.feed.max():.4g} {model.feed_unit}), {changes:,} FEDRAT (a new feed where it changes by more than "
            f"{100 * args.feed_step:g} %), {clamped} points at a limit"
        )
    print(
        f"simulated : stock left over the model {np.nanmin(check.deviation):+.4f} … {np.nanmax(check.deviation):+.4f} mm, "
        f"{int(check.outside.sum()):,} points outside ±{args.band:g} mm"
    )
    written = [out / "path.csv", out / "report.csv"]
    problem = check.problem()
    if problem is None or args.force:
        paths.to_apt(out / "grind.cl", force=args.force)
        written.insert(0, out / "grind.cl")
    elif (out / "grind.cl").exists():
        # An earlier run's path beside this run's refusal would be taken for this one.
        (out / "grind.cl").unlink()
        print(f"removed   : the grind.cl of an earlier run in {out}")
    print(f"written   : {', '.join(str(w) for w in written)}")
    holds = True
    if not paths.tool_fits.all():
        _warn(f"{int((~paths.tool_fits).sum())} path points lie on concave stretches tighter than the tool")
        holds = False
    if problem is not None:
        if args.force:
            _warn(f"{out / 'grind.cl'} written by --force although {problem}")
        else:
            print(
                f"machscan: refused: {out / 'grind.cl'} not written: {problem}. report.csv has the stock left per row; "
                "--force writes the path anyway",
                file=sys.stderr,
            )
        holds = False
    return 0 if holds else 3


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    from machscan.toolpath import BAND, FEED_STEP

    gr = sub.add_parser("grind", help="belt-grinding paths from an allowance cloud, spaced by the scallop height")
    gr.add_argument(
        "source",
        nargs="?",
        type=Path,
        help="allowance file from `machscan allowance` (points, normals, allowance), or the model with --blank",
    )
    gr.add_argument("--blank", type=Path, help="measured blank points: SOURCE is then the model and the allowance is computed")
    gr.add_argument("--tool-radius", type=float, default=10.0, help="contact radius across the rows, mm (default: %(default)s)")
    gr.add_argument("--scallop-height", type=float, default=0.01, help="allowed cusp height, mm (default: %(default)s)")
    gr.add_argument(
        "--section-normal", default="0,0,1", help="normal of the section planes, x,y,z (default: %(default)s, a blade's span)"
    )
    gr.add_argument(
        "--removal",
        metavar="C,E_BELT,E_FEED,E_FORCE,BELT_SPEED,FORCE,FEED_LO,FEED_HI",
        help="removal model r = C·Vb^e1·Vw^e2·F^e3 in the paper's units (r mm, belt speed Vb m/s, feed Vw mm/s, "
        "force F N) and the feed limits in mm/s; grind.cl gets the feeds in mm/min (FEDRAT/MMPM); without it no "
        "feeds are written",
    )
    gr.add_argument(
        "--feed-step",
        type=float,
        default=FEED_STEP,
        help="program a new feed where the wanted one changes by more than this share (default: %(default)s)",
    )
    gr.add_argument("--path-spacing", type=float, default=None, help="path point spacing along a row, mm (default: the cloud's)")
    gr.add_argument(
        "--band",
        type=float,
        default=BAND,
        help="allowed deviation after the simulated pass, ±mm; a path that leaves it is not written (default: %(default)s)",
    )
    gr.add_argument(
        "--force", action="store_true", help="write grind.cl even when the simulated pass leaves points outside --band"
    )
    gr.add_argument(
        "--out", type=Path, default=Path("grinding"), help="output folder: grind.cl, path.csv, report.csv (default: %(default)s)"
    )
    gr.add_argument("--simulate", action="store_true", help="run on the built-in synthetic blade")
    gr.add_argument("--spacing", type=float, default=0.5, help="point spacing of the simulated blade, mm (default: %(default)s)")
    gr.add_argument("--seed", type=int, default=0, help="seed of the simulated allowance (default: %(default)s)")
    gr.set_defaults(run=run)
