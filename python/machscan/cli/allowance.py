"""The ``machscan allowance`` command: the machining allowance of a measured blank over the model."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import get_args

import numpy as np

from machscan.cli._shared import (
    _read_model,
    _read_pose,
    _warn,
    _write_table,
    mesh_spacing,
    out_pose_path,
)
from machscan.registration import (
    ALLOWANCE_NEIGHBORS,
    ALLOWANCE_SURFACE,
    BlankSurface,
)

__all__ = ["add_parser", "run"]

def run(args: argparse.Namespace) -> int:
    from machscan.cloud import point_spacing
    from machscan.io import read_points, write_points
    from machscan.registration import align_blank, allowance, envelope_fit

    blank = read_points(args.blank)
    # The blank's spacing is read only for a mesh model, which is sampled by it.
    model, normals = _read_model(
        args.model,
        spacing=lambda: mesh_spacing(args.spacing if args.spacing is not None else point_spacing(blank)),
    )
    start = _read_pose(args.start, "--start") if args.start else None
    if args.local and not args.fit:
        raise ValueError("--local: is an option of --fit (the envelope fit alone, from --start)")
    surface = dict(surface=args.surface, k=args.k, spacing=args.spacing)
    if args.fit:
        if args.local:
            fit = envelope_fit(model, normals, blank, min_allowance=args.min_allowance, init=start, **surface)
            print("envelope fit from the start pose (--local)")
        else:
            found = align_blank(model, normals, blank, min_allowance=args.min_allowance, init=start, **surface)
            fit = found.fit
            print("blank found by coarse alignment, ICP and the envelope fit (each stage from the start pose):")
            print(found.summary())
        if args.local:
            print(fit.summary())
        a = fit.allowance
        pose_out = args.pose_out or out_pose_path(args.out)
        pose_out.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(pose_out, fit.transformation, fmt="%.12g", header="blank pose: 4 x 4, blank -> model frame; translation in mm")
        print("blank pose (applied to the blank; blank -> model frame, mm):")
        print(np.array2string(fit.transformation, precision=6, suppress_small=True))
        print(f"written   : {pose_out} (the blank pose)")
        holds = fit.feasible
    else:
        if start is not None:
            blank = blank @ start[:3, :3].T + start[:3, 3]
        a = allowance(model, normals, blank, **surface)
        ok = a[np.isfinite(a)]
        short = int(np.sum(ok < args.min_allowance))
        if len(ok):
            print(f"allowance (mm): min {ok.min():.4f}  mean {ok.mean():.4f}  max {ok.max():.4f}  std {ok.std():.4f}")
        print(
            f"{short} of {len(ok)} points below {args.min_allowance:g} mm; {len(a) - len(ok)} without stock measured "
            "(NaN: the blank does not cover them; grind leaves them out)"
        )
        holds = short == 0 and len(ok) > 0
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    if out.suffix.lower() in (".csv", ".xyz", ".txt"):
        # Text point files hold x, y, z only; the table keeps the normal and the allowance.
        _write_table(out, "x_mm,y_mm,z_mm,nx,ny,nz,allowance_mm", np.column_stack([model, normals, a]))
    else:
        write_points(out, model, normals=normals, scalars={"allowance": a})
    print(f"written   : {out} (model points, normals and the allowance, mm)")
    if not holds:
        _warn(f"the blank leaves less than {args.min_allowance:g} mm somewhere")
        return 3
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    al = sub.add_parser("allowance", help="machining allowance of a measured blank over the model")
    al.add_argument(
        "model",
        type=Path,
        help="model points with normals (PLY/PCD/XYZ/CSV), or a mesh (STL/OBJ/PLY with faces) whose surface is "
        "sampled every half blank spacing, at most 0.15 mm",
    )
    al.add_argument("blank", type=Path, help="measured blank points, in the model's frame")
    al.add_argument(
        "--out",
        type=Path,
        default=Path("allowance.ply"),
        help="model points with the allowance as a scalar field (.ply, .pcd) or a column (.csv) (default: %(default)s)",
    )
    al.add_argument("--min-allowance", type=float, default=0.0, help="least stock wanted, mm (default: %(default)s)")
    al.add_argument(
        "--fit",
        action="store_true",
        help="first find the blank's pose: coarse alignment, ICP, then the balanced envelope fit (every allowance ≥ the "
        "minimum, as even as possible); the pose is written beside --out",
    )
    al.add_argument("--start", type=Path, help="start pose of the blank, 4 × 4 text (blank → model frame; default identity)")
    al.add_argument("--local", action="store_true", help="with --fit: the envelope fit alone, from --start (no alignment)")
    al.add_argument("--pose-out", type=Path, help="where --fit writes the blank pose (default: OUT with .pose.txt)")
    al.add_argument(
        "--k", type=int, default=None, help=f"blank points per plane, --surface plane only (default: {ALLOWANCE_NEIGHBORS})"
    )
    al.add_argument(
        "--spacing",
        type=float,
        default=None,
        help="the blank's point spacing, mm (default: estimated from the blank; give it for a scan of far-apart lines)",
    )
    al.add_argument(
        "--surface",
        choices=get_args(BlankSurface),
        default=ALLOWANCE_SURFACE,
        help="how the blank's surface is taken: the stock field over the model, the blank's own quadric, or the "
        "paper's plane (default: %(default)s)",
    )
    al.set_defaults(run=run)
