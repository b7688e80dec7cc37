"""What the subcommands share: reading scans and tables, the scan and groove options, summaries."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, get_args

import numpy as np

if TYPE_CHECKING:
    from machscan.inspection import InspectionOptions


#: Point files that hold x, y, z per line and nothing else (what Open3D and PCL read as such).
_TEXT_POINTS = (".xyz", ".csv", ".txt", ".pts", ".asc")


def _write_cloud(path: Path, points: np.ndarray, frame_index: np.ndarray, binary: bool) -> str:
    """Writes the workpiece points; PLY and PCD keep each point's frame as a scalar field, text files hold x, y, z
    only. Returns what the file holds, for the console."""
    from machscan.io import write_points

    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix.lower() in _TEXT_POINTS:
        write_points(path, points)
        return "x, y, z in mm (a text point file keeps no frame index: write .ply or .pcd for it)"
    write_points(path, points, scalars={"frame": frame_index}, binary=binary)
    return "x, y, z in mm and the frame of each point"


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
        _warn(
            f"{100 * share:.0f} % of the valid readings are exactly {values[k]!r}: if that is the profiler's "
            f"no-reading code, pass --sentinel {values[k]!r} (or --valid-range) so they are dropped"
        )


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
    if getattr(args, "poses", None) is None and _is_gocator_export(path):
        from machscan.scan import read_profiles

        return read_profiles(path)
    missing = [n for n in ("poses", "pitch", "c2_offset", "mount") if getattr(args, n, None) is None]
    if missing:
        raise ValueError(f"scan: {path} is a CSV export; give --{' --'.join(m.replace('_', '-') for m in missing)} too")
    readings = args.readings or _csv_readings(path)
    profiler = Profiler(
        readings=readings,
        pitch=args.pitch,
        valid_range=tuple(args.valid_range) if args.valid_range else None,
        sentinel=args.sentinel,
        name="profiler",
    )
    return read_scan_csv(path, args.poses, profiler, args.c2_offset, args.mount)


def _is_gocator_export(path: Path) -> bool:
    """A Gocator CSV export starts with a section name (``Info``, ``Profile``, ``Part``, ...)
    alone on its line; a frames CSV with numbers or a header of several cells."""
    try:
        with open(path, "rb") as f:
            head = f.read(256)
    except OSError:
        return False
    first = next((line.strip() for line in head.decode("latin-1").splitlines() if line.strip()), "")
    return first.isalpha()


def _csv_readings(path: Path) -> int:
    """Readings per frame of a frames CSV: the width of its first data row, less a leading
    time column when the header names one."""
    from machscan.io import read_table

    # The header and the first data row tell the width; the scan itself is read once, after.
    table = read_table(path, delimiter=",", max_rows=1, name="scan")
    if table.values.shape[0] == 0:
        raise ValueError(f"scan: {path}: no frames")
    timed = table.header is not None and table.header[0].lower() in ("t", "time", "timestamp")
    return table.values.shape[1] - (1 if timed else 0)


def _csv_text(text: str | None) -> str:
    return "" if text is None else '"' + text.replace('"', "'").replace("\n", " ") + '"'


#: A mesh given as the model of an allowance is sampled every half blank spacing, at most every 0.15 mm: the stock
#: field reads the model's shape between its points (docs/registration.md R7), and the shape it cannot see is a
#: curvature jump between neighbours, set by their distance, not by the blank's. Poisson-disk models no closer than
#: 0.16 mm held 4.9 µm where a 1.5 mm edge meets a flat at 0.5–1 mm blank spacing, 0.24 mm up to 10.8 µm at 1 mm
#: (five draws, benchmarks/accuracy_allowance_sampling.py).
MESH_SAMPLING = (0.5, 0.15)


def mesh_spacing(blank_spacing: float) -> float:
    """Where a mesh model is sampled for an allowance over a blank of this point spacing, mm (:data:`MESH_SAMPLING`)."""
    share, finest = MESH_SAMPLING
    return min(share * blank_spacing, finest)


def _read_model(path: Path, *, spacing: Callable[[], float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Model points and outward normals from a file: its points and normals, or for a mesh (STL/OBJ/PLY with faces
    and no normals) points spread evenly over its surface every ``spacing()`` mm (asked only of a mesh) with
    normals interpolated from its corners (:func:`machscan.mesh.sample_surface`) — or, without ``spacing``, its
    vertices with their area-weighted normals (outward for a consistently wound mesh). A mesh's vertices are where
    its mesher put them (a flat one triangle across has none inside it): the allowance and grinding want the
    surface."""
    from machscan.io import read
    from machscan.mesh import sample_surface

    f = read(path)
    if f.normals is not None:
        return f.points, f.normals
    if len(f.triangles):
        if spacing is not None:
            every = spacing()
            points, normals = sample_surface(f.points, f.triangles, every)
            print(f"model     : {path} is a mesh: {len(points):,} points with normals spread over it every {every:.3g} mm")
            return points, normals
        t = f.triangles
        face = np.cross(f.points[t[:, 1]] - f.points[t[:, 0]], f.points[t[:, 2]] - f.points[t[:, 0]])
        normals = np.zeros_like(f.points)
        for k in range(3):
            np.add.at(normals, t[:, k], face)
        used = np.linalg.norm(normals, axis=1) > 0
        return f.points[used], normals[used]
    raise ValueError(
        f"model: {path} has no normals (nx, ny, nz) and no triangles: the allowance and the probe "
        "directions need the model's outward normals"
    )


def _write_table(path: Path, header: str, rows: np.ndarray) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(path, rows, delimiter=",", header=header, comments="", fmt="%.9g")


def out_pose_path(out: Path) -> Path:
    """Where ``machscan allowance --fit`` writes the blank pose by default: beside the allowance file."""
    out = Path(out)
    return out.with_name(out.stem + ".pose.txt")


def _read_pose(path: Path, name: str) -> np.ndarray:
    """A 4 × 4 rigid pose from a text file (as machscan writes them; ``#`` comments)."""
    try:
        pose = np.loadtxt(path, ndmin=2)
    except ValueError as e:
        raise ValueError(f"{name}: {path} is not a 4 x 4 matrix of numbers ({e})") from None
    if pose.size != 16 or not np.isfinite(pose).all():
        raise ValueError(f"{name}: {path} holds {pose.size} values, expected a finite 4 x 4 pose")
    return pose.reshape(4, 4)


def _floats(text: str, count: int, name: str) -> tuple[float, ...]:
    """``count`` comma-separated numbers."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"{name}: expected {count} comma-separated numbers, got {text!r}") from None
    if len(values) != count:
        raise ValueError(f"{name}: expected {count} comma-separated numbers, got {text!r}")
    return values


def _check_positive_mm(option: str, value: float) -> None:
    """Refuses an option's length in mm that is not a positive number (nan, inf, 0 and below)."""
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{option}: must be a positive number of mm, got {value:g}")


def _read_rows(path: Path, name: str, widths: tuple[int, ...], nan_columns: tuple[int, ...] = ()) -> np.ndarray:
    """A comma-separated table of numbers of one of ``widths`` columns (machscan.io.read_table's rules)."""
    from machscan.io import read_table

    rows = read_table(path, delimiter=",", widths=widths, nan_columns=nan_columns, name=name).values
    if rows.size == 0:
        raise ValueError(f"{name}: {path} holds no rows of numbers")
    return rows


def _scan_arguments(p: argparse.ArgumentParser, *, optional: bool = False) -> None:
    """The scan argument (optional for a command that can simulate one) and a CSV scan's options."""
    from machscan.scan import SENTINEL

    p.add_argument(
        "scan",
        type=Path,
        nargs="?" if optional else None,
        help="raw scan: .npz saved by Scan.save, a Gocator CSV export, or a CSV export (one frame per row)",
    )
    g = p.add_argument_group("for a CSV scan")
    g.add_argument("--poses", type=Path, help="poses CSV (X, Y, Z, A, C, C2 per frame, optional leading t)")
    g.add_argument("--pitch", type=float, help="reading spacing, mm")
    g.add_argument("--readings", type=int, help="readings per frame (default: the file's)")
    g.add_argument("--c2-offset", type=float, nargs=3, metavar=("LX", "LY", "LZ"), help="C2 axis offset, mm")
    g.add_argument(
        "--mount", type=float, nargs=6, metavar=("THETA", "PSI", "PHI", "DX", "DY", "DZ"), help="sensor mount, rad and mm"
    )
    g.add_argument("--valid-range", type=float, nargs=2, metavar=("LO", "HI"), help="measuring range, mm")
    g.add_argument(
        "--sentinel", type=float, default=SENTINEL, help="value the profiler returns for no reading (default: %(default)s)"
    )


def _groove_arguments(p: argparse.ArgumentParser) -> None:
    """The groove inspection's options, shared by `grooves` and `batch grooves`; the defaults are
    InspectionOptions' (one source)."""
    from machscan.grooves import Misfit, Rounding, Select, Template
    from machscan.inspection import InspectionOptions

    default = InspectionOptions()
    p.add_argument(
        "--window",
        type=int,
        default=default.groove.window,
        help="readings around the line center fitted per frame (default: %(default)s)",
    )
    p.add_argument(
        "--template",
        choices=get_args(Template),
        default=default.groove.template,
        help="groove shape fitted: the best of the section models (auto), one of them, or the "
        "paper's tanh template (default: %(default)s)",
    )
    p.add_argument(
        "--alpha",
        type=float,
        default=default.groove.alpha,
        help="tanh template only: shape coefficient, 1/mm (default: %(default)s)",
    )
    p.add_argument(
        "--nominal-width",
        type=float,
        default=default.groove.nominal_width,
        help="tanh template only: starting groove width, mm (default: %(default)s)",
    )
    p.add_argument(
        "--select",
        choices=get_args(Select),
        default=default.groove.select,
        help="which grooves of a frame's window are measured: the deepest, the --index-th from the left or "
        "right, the one nearest --near, or all (several lines across the profile) (default: %(default)s)",
    )
    p.add_argument(
        "--rounding",
        choices=get_args(Rounding),
        default=default.groove.rounding,
        help="a V's tip rounding, which one frame cannot tell from a sharp tip: a prior pooled over the scan's V's, "
        "or each frame on its own (default: %(default)s)",
    )
    p.add_argument(
        "--misfit",
        choices=get_args(Misfit),
        default=default.groove.misfit,
        help="the misfit one frame cannot show, in the standard errors (the section's at the groove's bottom in the "
        "depth's, a U's against the ellipse in its measures'): pooled over the scan's frames, or none (the models' "
        "errors alone) (default: %(default)s)",
    )
    p.add_argument("--index", type=int, default=default.groove.index, help="with --select left/right: which one (0: outermost)")
    p.add_argument("--near", type=float, default=default.groove.near, help="with --select nearest: x in the line, mm")
    for name, what in (("min-width", "narrowest"), ("max-width", "widest"), ("max-depth", "deepest")):
        p.add_argument(
            f"--{name}",
            type=float,
            default=getattr(default.groove, name.replace("-", "_")),
            help=f"validity limit: the {what} groove that counts, mm (default: no limit)",
        )
    for name in ("width", "depth"):
        p.add_argument(
            f"--{name}-tolerance",
            type=float,
            nargs=2,
            metavar=("LOWER", "UPPER"),
            default=None,
            help=f"groove {name} limits, mm: pass / fail per frame, in tolerance, Cp and Cpk per contour",
        )
    p.add_argument(
        "--max-se-ratio",
        type=float,
        default=default.max_se_ratio,
        help="leave out frames whose width or depth standard error exceeds this many times the "
        "median (default: keep all; 5 suits the tanh template)",
    )
    p.add_argument(
        "--cluster-radius",
        type=float,
        default=default.cluster_radius,
        help="contour segmentation distance, mm (default: %(default)s)",
    )
    p.add_argument(
        "--max-match-distance",
        type=float,
        default=default.max_match_distance,
        help="largest distance between a scanned contour and its CAD contour, mm (default: %(default)s)",
    )


def _groove_options(args: argparse.Namespace) -> InspectionOptions:
    """The inspection's options from those of `_groove_arguments`."""
    from machscan.inspection import InspectionOptions

    return InspectionOptions().with_changes(
        dict(
            window=args.window,
            template=args.template,
            alpha=args.alpha,
            nominal_width=args.nominal_width,
            select=args.select,
            rounding=args.rounding,
            misfit=args.misfit,
            index=args.index,
            near=args.near,
            min_width=args.min_width,
            max_width=args.max_width,
            max_depth=args.max_depth,
            cluster_radius=args.cluster_radius,
            max_match_distance=args.max_match_distance,
            max_se_ratio=args.max_se_ratio,
            width_tolerance=tuple(args.width_tolerance) if args.width_tolerance else None,
            depth_tolerance=tuple(args.depth_tolerance) if args.depth_tolerance else None,
        )
    )


def _progress_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--progress", action=argparse.BooleanOptionalAction, default=None, help="progress bar on stderr (default: on a terminal)"
    )
