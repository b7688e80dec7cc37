"""The ``machscan position`` command: touch-probe plans and the part's pose from probe rounds."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from machscan.cli._shared import (
    _read_model,
    _warn,
    _write_table,
)
from machscan.registration import (
    PROBE_KEEP,
    PROBE_PATTERN,
    PROBE_POINTS,
    PROBE_RADIUS,
    PROBE_SEED,
)

__all__ = ["add_parser", "run"]

def run(args: argparse.Namespace) -> int:
    from machscan import registration

    if args.simulate:
        return _position_simulated(args)
    if args.model is None or args.plan is None:
        raise ValueError("position: give MODEL and --plan (or --simulate)")
    points, normals = _read_model(args.model)
    pose = np.loadtxt(args.pose).reshape(4, 4) if args.pose else np.eye(4)
    if args.measured is None:
        idx = registration.locating_points(
            points, m=args.n_points, keep=args.keep, seed=args.seed, normals=normals, pattern=args.pattern
        )
        _write_plan(args.plan, points, normals, idx, pose)
        print(f"plan      : {len(idx)} probe points of {len(points):,} ({args.pattern}, flattest {args.keep:.0%})")
        print(f"written   : {args.plan} (index, x, y, z, dx, dy, dz: contact points and approach directions, mm)")
        return 0
    plan = np.loadtxt(args.plan, delimiter=",", skiprows=1, ndmin=2)
    measured = np.genfromtxt(args.measured, delimiter=",", skip_header=1, usecols=(0, 1, 2), ndmin=2)
    r = registration.probe_round(points, normals, plan[:, 0].astype(np.int64), pose, measured, probe_radius=args.probe_radius)
    result = registration.PositioningResult(r.transformation, (r,), plan[:, 0].astype(np.int64), converged=False)
    print(result.summary())
    if r.hits < 6:
        _warn(f"only {r.hits} probe points found the part: no pose fitted")
        return 3
    args.out.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(args.out, r.transformation, fmt="%.12g", header="pose: 4 x 4, model -> machine; rotation, translation in mm")
    print(f"\npose      : model → machine, written to {args.out}")
    print(
        f"correction: {r.correction * 1e3:.2f} µm RMS along the normals; probe again at the new pose while it "
        "is above the probe noise"
    )
    if args.next_plan:
        _write_plan(args.next_plan, points, normals, plan[:, 0].astype(np.int64), r.transformation)
        print(f"written   : {args.next_plan} (the same points at the new pose)")
    return 0


def _write_plan(path: Path, points: np.ndarray, normals: np.ndarray, idx: np.ndarray, pose: np.ndarray) -> None:
    from machscan.registration import probe_plan

    p, d = probe_plan(points, normals, idx, pose)
    _write_table(path, "index,x_mm,y_mm,z_mm,dx,dy,dz", np.column_stack([idx, p, d]))


def _position_simulated(args: argparse.Namespace) -> int:
    from machscan.registration import position_workpiece
    from machscan.synth import Blade, TouchProbe, misplacement

    blade = Blade()
    points, normals = blade.sample(200, 100)
    truth = misplacement(args.seed, center=points.reshape(-1, 3).mean(axis=0))
    probe = TouchProbe(blade, truth, radius=args.probe_radius, noise=0.002, seed=args.seed)
    r = position_workpiece(
        points,
        normals,
        probe,
        n_points=args.n_points,
        seed=args.seed,
        probe_radius=args.probe_radius,
        keep=args.keep,
        pattern=args.pattern,
    )
    p, n = points.reshape(-1, 3), normals.reshape(-1, 3)
    d = (p @ r.transformation[:3, :3].T + r.transformation[:3, 3]) - (p @ truth[:3, :3].T + truth[:3, 3])
    along = np.einsum("ij,ij->i", d, n @ truth[:3, :3].T)
    print("synthetic blade, 0.5 mm / 0.5° misplaced, probe noise 2 µm\n")
    print(r.summary())
    print(
        f"\npose error over the whole blade: {np.sqrt(np.mean(along**2)) * 1e3:.2f} µm RMS along the normals, "
        f"{np.sqrt(np.mean(np.sum(d**2, axis=1))) * 1e3:.1f} µm RMS displacement (sliding along the faces)"
    )
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    pos = sub.add_parser("position", help="where the part sits: touch-probe plan, or the pose from one probe round")
    pos.add_argument("model", nargs="?", type=Path, help="model points with normals (PLY/PCD/XYZ/CSV) or a mesh (STL)")
    pos.add_argument("--plan", type=Path, help="probe plan CSV: written without --measured, read with it")
    pos.add_argument("--measured", type=Path, help="probe readings CSV (x, y, z per plan row; empty: missed)")
    pos.add_argument("--pose", type=Path, help="4×4 pose (model → machine) the plan was made at (default: identity)")
    pos.add_argument("--out", type=Path, default=Path("pose.txt"), help="fitted pose (default: %(default)s)")
    pos.add_argument("--next-plan", type=Path, help="write the plan at the fitted pose for the next round")
    pos.add_argument("--n-points", type=int, default=PROBE_POINTS, help="probe points (default: %(default)s)")
    pos.add_argument(
        "--keep", type=float, default=PROBE_KEEP, help="flattest share to choose from (default: %(default)s)"
    )
    pos.add_argument(
        "--pattern",
        choices=("optimal", "random"),
        default=PROBE_PATTERN,
        help="designed points or the paper's random draw (default: %(default)s)",
    )
    pos.add_argument("--seed", type=int, default=PROBE_SEED, help="seed of a random draw (default: %(default)s)")
    pos.add_argument(
        "--probe-radius", type=float, default=PROBE_RADIUS, help="probe ball radius, mm (default: %(default)s)"
    )
    pos.add_argument("--simulate", action="store_true", help="run the rounds on the built-in synthetic blade")
    pos.set_defaults(run=run)
