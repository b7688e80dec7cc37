"""The ``machscan compare`` command: the signed deviation of a scan from the CAD model, per point
and per CAD face, after an optional best fit."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from machscan.cli._shared import _floats, _read_pose, _warn, _write_table

__all__ = ["add_parser", "run"]

#: CAD files read through the B-rep (``machscan[cad]``); every other model is read as a mesh.
_BREP = (".step", ".stp", ".iges", ".igs")


def _read_cad_mesh(path: Path, chordal: float) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, str]:
    """The model's mesh, its CAD face per triangle (None for a mesh file) and what was read."""
    from machscan.io import read_cad, read_mesh

    if path.suffix.lower() in _BREP:
        cad = read_cad(path, tolerance=chordal)
        faces = int(cad.cad_faces.max()) + 1 if len(cad.cad_faces) else 0
        what = (
            f"{len(cad.triangles):,} triangles on {faces} CAD faces "
            f"(chordal deviation {cad.chordal_deviation * 1e3:.1f} µm, file unit {cad.unit})"
        )
        return cad.vertices, cad.triangles, cad.cad_faces, what
    mesh = read_mesh(path)
    if len(mesh.triangles) == 0:
        raise ValueError(f"cad: {path} holds no triangles (a point file?): give a mesh (STL, OBJ, PLY) or STEP/IGES")
    return mesh.vertices, mesh.triangles, None, f"{len(mesh.triangles):,} triangles (a mesh: no CAD faces)"


def run(args: argparse.Namespace) -> int:
    from machscan.deviation import signed_distances, tolerance_band
    from machscan.io import read_points, write_points
    from machscan.registration import fit_to_mesh

    if len(args.tolerance) not in (1, 2):
        raise ValueError(f"--tolerance: T for ±T, or LOWER UPPER; got {len(args.tolerance)} values")
    lower, upper = tolerance_band(tuple(args.tolerance) if len(args.tolerance) == 2 else args.tolerance[0])
    scan = read_points(args.scan)
    vertices, triangles, cad_faces, what = _read_cad_mesh(args.cad, args.chordal)
    print(f"scan      : {len(scan):,} points from {args.scan}")
    print(f"CAD       : {what}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = _read_pose(args.start, "--start") if args.start else None
    if args.axis is not None and not args.fit:
        raise ValueError("--axis: is an option of --fit")
    if args.fit:
        axis = None
        if args.axis is not None:
            v = _floats(args.axis, 6, "--axis")
            axis = (v[:3], v[3:])
        fit = fit_to_mesh(scan, vertices, triangles, args.max_distance, start, dof=args.dof, axis=axis)
        m = fit.motion
        print(
            f"best fit  : dof {fit.dof}; x {m['x']:+.4f} y {m['y']:+.4f} z {m['z']:+.4f} mm, "
            f"a {m['a']:+.4f} b {m['b']:+.4f} c {m['c']:+.4f} deg; rmse {fit.rmse * 1e3:.1f} µm, "
            f"fitness {fit.fitness:.3f}, {fit.iterations} iterations, converged {fit.converged}"
        )
        if fit.undetermined:
            _warn(f"the scan does not fix the motions {fit.undetermined!r}: they were held at 0")
        pose = fit.transformation
        np.savetxt(out / "pose.txt", pose, fmt="%.12g", header="scan pose: 4 x 4, scan -> CAD frame; translation in mm")
        print(f"written   : {out / 'pose.txt'} (the scan pose, scan -> CAD, mm)")
        if not fit.converged:
            _warn("the best fit did not converge: the deviations are at its last pose")
    elif start is not None:
        pose = start
    else:
        pose = np.eye(4)
    moved = scan @ pose[:3, :3].T + pose[:3, 3]
    d = signed_distances(moved, vertices, triangles, cad_faces=cad_faces)
    outside = d.out_of_tolerance((lower, upper))
    n_out = int(outside.sum())
    dist = d.distances
    print(
        f"deviation : min {dist.min():+.4f}  mean {dist.mean():+.4f}  max {dist.max():+.4f}  std {dist.std():.4f} mm "
        f"(+ outside the material)"
    )
    print(f"tolerance : [{lower:g}, {upper:g}] mm; {n_out:,} of {len(dist):,} points outside ({100 * n_out / len(dist):.2f} %)")
    faces = d.statistics((lower, upper))
    face_ids = d.cad_faces if d.cad_faces is not None else np.zeros(len(dist), dtype=np.int64)
    cloud = out / f"deviation{args.format}"
    write_points(cloud, moved, scalars={"deviation_mm": dist, "cad_face": face_ids.astype(np.float64)})
    _write_table(
        out / "deviation.csv", "x_mm,y_mm,z_mm,deviation_mm,cad_face", np.column_stack([moved, dist, face_ids])
    )
    faces.to_csv(out / "faces.csv")
    print(f"written   : {cloud} (scan points in the CAD frame; scalars deviation_mm, cad_face)")
    print(f"written   : {out / 'deviation.csv'} (the same as a table, mm)")
    print(f"written   : {out / 'faces.csv'} ({len(faces)} faces: min, max, mean, std in mm, share out of tolerance)")
    worst = np.argsort(-faces.out_of_tolerance, kind="stable")[:10]
    print("face  points   min mm    max mm   mean mm    std mm  out %")
    for i in worst:
        print(
            f"{faces.face[i]:4d} {faces.count[i]:7d} {faces.min[i]:+9.4f} {faces.max[i]:+9.4f} {faces.mean[i]:+9.4f} "
            f"{faces.std[i]:9.4f} {100 * faces.out_of_tolerance[i]:6.2f}"
        )
    try:
        from machscan.plot import deviation_map
    except ImportError:  # pragma: no cover - plot needs matplotlib
        _warn("no figure: machscan.plot needs matplotlib (pip install machscan[plot])")
    else:
        import matplotlib

        matplotlib.use("Agg")
        try:
            fig = deviation_map(moved, dist, tolerance=(lower, upper), vertices=vertices, triangles=triangles)
        except ImportError:
            _warn("no figure: machscan.plot needs matplotlib (pip install machscan[plot])")
        else:
            fig.savefig(out / "deviation.png", dpi=150)
            print(f"written   : {out / 'deviation.png'} (the deviation map, colour bar in mm)")
    if n_out:
        _warn(f"{n_out:,} points are outside the tolerance [{lower:g}, {upper:g}] mm")
        return 3
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """The subcommand's arguments."""
    cp = sub.add_parser("compare", help="signed deviation of a scan from the CAD model, per point and per CAD face")
    cp.add_argument("scan", type=Path, help="measured points (PLY, PCD, XYZ/CSV, LAS/LAZ, E57), mm")
    cp.add_argument("cad", type=Path, help="the CAD model: STEP or IGES (machscan[cad]), or a mesh (STL, OBJ, PLY)")
    cp.add_argument(
        "--tolerance",
        type=float,
        nargs="+",
        required=True,
        metavar="T",
        help="the band, mm: T for ±T, or LOWER UPPER",
    )
    cp.add_argument("--out", type=Path, default=Path("compare"), help="output directory (default: %(default)s)")
    cp.add_argument(
        "--format", choices=(".ply", ".pcd"), default=".ply", help="the per-point file's format (default: %(default)s)"
    )
    cp.add_argument("--fit", action="store_true", help="first the best fit of the scan to the CAD mesh (fit_to_mesh)")
    cp.add_argument("--dof", default="xyzabc", help="with --fit: the free motions, x y z a b c (default: %(default)s)")
    cp.add_argument("--axis", help="with --fit: C turns about this line: px,py,pz,dx,dy,dz (mm)")
    cp.add_argument(
        "--max-distance",
        type=float,
        default=1.0,
        help="with --fit: largest correspondence distance, mm (default: %(default)s)",
    )
    cp.add_argument("--start", type=Path, help="start pose of the scan, 4 × 4 text (scan → CAD frame; default identity)")
    cp.add_argument(
        "--chordal",
        type=float,
        default=0.01,
        help="STEP/IGES: largest distance of the tessellation from the B-rep, mm (default: %(default)s)",
    )
    cp.set_defaults(run=run)
