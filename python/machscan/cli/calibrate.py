"""The ``machscan calibrate`` command: the sensor mount from a scan of a reference sphere."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from machscan.cli._shared import _load_scan, _scan_arguments, _warn

__all__ = ["add_parser", "run"]


def run(args: argparse.Namespace) -> int:
    from machscan.kinematics import calibrate_mount_sphere

    if args.simulate:
        from machscan.synth import sphere_scan

        scan, truth = sphere_scan(args.sim_poses, seed=args.seed)
        radius = truth.radius
        print(f"simulated : a sphere of {radius} mm from {args.sim_poses} head orientations, 8 µm noise")
    else:
        if args.scan is None or args.radius is None:
            raise ValueError("scan, --radius: give the sphere's scan and its radius (or --simulate)")
        scan, radius = _load_scan(args), args.radius
    cal = calibrate_mount_sphere(scan, radius)
    print(cal.summary())
    if args.simulate:
        err = cal.params - truth.mount
        print(
            f"truth     : mount angles within {np.abs(err[:3]).max() * 1e3:.4f} mrad, shifts within "
            f"{np.abs(err[3:]).max() * 1e3:.2f} µm, centre within {np.abs(cal.sphere_center - truth.center).max() * 1e3:.2f} µm"
        )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(
        out,
        cal.params[None],
        fmt="%.12g",
        header="sensor mount: theta psi phi (rad) dx dy dz (mm); machscan points --mount takes these six",
    )
    print(f"written   : {out} (the mount: theta, psi, phi in rad; dx, dy, dz in mm)")
    if not cal.converged:
        _warn("the calibration did not converge: check the radius and the start mount")
        return 3
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    ca = sub.add_parser("calibrate", help="the sensor mount from a scan of a reference sphere")
    _scan_arguments(ca, optional=True)
    ca.add_argument("--radius", type=float, help="the sphere's calibrated radius, mm")
    ca.add_argument("--out", type=Path, default=Path("mount.txt"), help="where the mount is written (default: %(default)s)")
    ca.add_argument("--simulate", action="store_true", help="calibrate on the built-in sphere scan and compare with its truth")
    ca.add_argument("--sim-poses", type=int, default=5, help="with --simulate: head orientations, 1-8 (default: %(default)s)")
    ca.add_argument("--seed", type=int, default=0, help=argparse.SUPPRESS)
    ca.set_defaults(run=run)
