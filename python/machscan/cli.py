"""The ``machscan`` command (also ``python -m machscan``).

machscan demo [--out DIR] [--seed 0]            synthetic engraved plate → groove tables
machscan grooves SCAN CAD [CAD ...] [--out DIR] raw scan + CAD contours → groove tables (CSV);
                                                exit status 3 when no contour matched
machscan points SCAN [--out cloud.ply]          raw scan → workpiece point cloud (PLY)
machscan position MODEL --plan plan.csv         model → probe points and approach directions
machscan position MODEL --plan plan.csv --measured probed.csv [--out pose.txt]
                                                one probe round → part pose, error table
machscan position --simulate                    the probe rounds on the built-in blade
machscan allowance MODEL BLANK [--out a.ply]    stock per model point (PLY/PCD/XYZ/CSV);
                                                exit status 3 when the minimum does not hold
machscan allowance MODEL BLANK --fit [--start pose.txt] [--local]
                                                the blank's pose first: coarse alignment, ICP, the
                                                envelope fit (--local: the envelope fit alone)
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
import time
from dataclasses import dataclass
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


def _csv_readings(path: Path) -> int:
    """Readings per frame of a frames CSV: the width of its first data row, less a leading
    time column when the header names one."""
    from machscan.io import read_table

    table = read_table(path, delimiter=",", name="scan")
    if table.values.shape[0] == 0:
        raise ValueError(f"scan: {path}: no frames")
    timed = table.header is not None and table.header[0].lower() in ("t", "time", "timestamp")
    return table.values.shape[1] - (1 if timed else 0)


def _demo(args: argparse.Namespace) -> int:
    from machscan import synth
    from machscan.inspection import inspect_grooves

    t0 = time.perf_counter()
    scan, truth = synth.groove_scan(seed=args.seed)
    t_synth = time.perf_counter() - t0
    print(f"machscan demo: synthetic engraved plate, 11 contours (seed {args.seed}), generated in {t_synth:.1f} s")
    t0 = time.perf_counter()
    points, frame_index = scan.wcs_points()
    t_points = time.perf_counter() - t0
    for line in _scan_summary(scan, points, t_points):
        print(line)
    err = synth.surface_error(points, frame_index, truth)
    print(
        f"round trip: workpiece points vs the true bent surface, away from the grooves ({err.n:,} points): "
        f"mean {err.mean * 1e3:+.2f} µm, robust sigma {err.robust_sigma * 1e3:.1f} µm "
        f"(profiler noise {(scan.profiler.noise or 0.0) * 1e3:.1f} µm), {err.n_outliers} spikes beyond "
        f"{err.outlier_threshold * 1e3:.0f} µm"
    )
    t0 = time.perf_counter()
    report = inspect_grooves(scan, truth.nominal_polylines, progress=None)
    t_inspect = time.perf_counter() - t0
    print(f"inspection: {t_inspect:.2f} s\n")
    print(report.summary())
    ok = report.used
    print(
        f"\nagainst the truth: width |error| median {np.median(np.abs(report.fits.width[ok] - truth.width[ok])) * 1e3:.1f} µm, "
        f"depth |error| median {100 * np.median(np.abs(report.fits.depth[ok] - truth.depth[ok]) / truth.depth[ok]):.2f} %, "
        f"center rms {np.sqrt(np.mean(np.sum((report.center_wcs[ok] - truth.center_wcs[ok]) ** 2, axis=1))) * 1e3:.1f} µm"
    )
    out = Path(args.out)
    paths = report.to_csv(out)
    keep = frame_index % args.cloud_every == 0
    cloud = out / "cloud.ply"
    _write_cloud(cloud, points[keep], frame_index[keep], binary=True)
    print(f"\nwritten   : {', '.join(str(p) for p in paths)}")
    print(f"            {cloud} (workpiece points of every {args.cloud_every}th frame; --cloud-every 1 for all)")
    return 0


def _grooves(args: argparse.Namespace) -> int:
    from machscan.cad import read_contours
    from machscan.inspection import inspect_grooves

    scan = _load_scan(args)
    _check_readings(scan)
    cad = read_contours(args.cad)
    report = inspect_grooves(scan, cad, _groove_options(args), progress=args.progress)
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
    report = inspect_grooves(scan, cad, options)
    folder = Path(out) / p.stem
    report.to_csv(folder)
    problem = report.matching_problem() or (None if report.contours else "no contour was matched")
    return BatchGrooves(len(report.fits), int(report.fits.ok.sum()), len(report.contours), problem, str(folder))


def _batch_grooves(args: argparse.Namespace) -> int:
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


def _csv_text(text: str | None) -> str:
    return "" if text is None else '"' + text.replace('"', "'").replace("\n", " ") + '"'


def _points(args: argparse.Namespace) -> int:
    scan = _load_scan(args)
    _check_readings(scan)
    t0 = time.perf_counter()
    points, frame_index = scan.wcs_points()
    seconds = time.perf_counter() - t0
    holds = _write_cloud(args.out, points, frame_index, binary=not args.ascii)
    for line in _scan_summary(scan, points, seconds):
        print(line)
    print(f"written   : {args.out} ({holds})")
    return 0


def _read_model(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Model points and outward normals from a file: its normals, or for a mesh (STL/OBJ/PLY
    with faces) the area-weighted normals of its vertices (outward for a consistently wound
    mesh)."""
    from machscan.io import read

    f = read(path)
    if f.normals is not None:
        return f.points, f.normals
    if len(f.triangles):
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


def _position(args: argparse.Namespace) -> int:
    from machscan import registration

    if args.simulate:
        return _position_simulated(args)
    if args.model is None or args.plan is None:
        raise ValueError("position: give MODEL and --plan (or --simulate)")
    points, normals = _read_model(args.model)
    pose = np.loadtxt(args.pose).reshape(4, 4) if args.pose else np.eye(4)
    if args.measured is None:
        idx = registration.locating_points(
            points, args.n_points, keep=args.keep, seed=args.seed, normals=normals, pattern=args.pattern
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


def _allowance(args: argparse.Namespace) -> int:
    from machscan.io import read_points, write_points
    from machscan.registration import align_blank, allowance, envelope_fit

    model, normals = _read_model(args.model)
    blank = read_points(args.blank)
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


def _grind(args: argparse.Namespace) -> int:
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
        points, normals = _read_model(args.source)
        stock = allowance(points, normals, read_points(args.blank))
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
        model,
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


def _compensate(args: argparse.Namespace) -> int:
    from machscan.io import read_points, read_toolpath

    _check_positive_mm("--max-error", args.max_error)
    if args.simulate:
        return _compensate_simulated(args)
    if args.theoretical is None or args.scan is None or args.toolpath is None or args.locating is None or args.matching is None:
        raise ValueError("compensate: give THEORETICAL SCAN TOOLPATH --locating and --matching (or --simulate)")
    theoretical, scan = read_points(args.theoretical), read_points(args.scan)
    from machscan.scan import _check_finite_rows

    _check_finite_rows(theoretical, f"THEORETICAL {args.theoretical}", "x, y, z in mm")
    _check_finite_rows(scan, f"SCAN {args.scan}", "x, y, z in mm")
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


def _scan_arguments(p: argparse.ArgumentParser) -> None:
    from machscan.scan import SENTINEL

    p.add_argument("scan", type=Path, help="raw scan: .npz saved by Scan.save, or a CSV export (one frame per row)")
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
    from machscan.grooves import Template
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
        help="groove shape fitted: the best of the four section models (auto), one of them, or the "
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
            cluster_radius=args.cluster_radius,
            max_match_distance=args.max_match_distance,
            max_se_ratio=args.max_se_ratio,
        )
    )


def _progress_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--progress", action=argparse.BooleanOptionalAction, default=None, help="progress bar on stderr (default: on a terminal)"
    )


def build_parser() -> argparse.ArgumentParser:
    from machscan import __version__

    parser = argparse.ArgumentParser(
        prog="machscan",
        description="On-machine measurement for five-axis machining: line-laser frames and axis "
        "positions to workpiece points and answers.",
    )
    parser.add_argument("--version", action="version", version=f"machscan {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    demo = sub.add_parser("demo", help="run the groove inspection on a built-in synthetic scan")
    demo.add_argument("--out", type=Path, default=Path("machscan-demo"), help="output folder (default: %(default)s)")
    demo.add_argument("--seed", type=int, default=0, help="seed of the synthetic scan (default: %(default)s)")
    demo.add_argument(
        "--cloud-every", type=int, default=10, help="write the workpiece points of every Nth frame (default: %(default)s)"
    )
    demo.set_defaults(run=_demo)

    gr = sub.add_parser("grooves", help="groove width, depth and contour error from a raw scan and CAD contours")
    _scan_arguments(gr)
    gr.add_argument("cad", nargs="+", type=Path, help="CAD contours: CSV (contour, x, y, z) or APT/CL files (GOTO points)")
    gr.add_argument("--out", type=Path, default=Path("grooves"), help="output folder for the CSV tables (default: %(default)s)")
    _groove_arguments(gr)
    _progress_argument(gr)
    gr.set_defaults(run=_grooves)

    pts = sub.add_parser("points", help="turn a raw scan into a workpiece point cloud (PLY, PCD or a text point file)")
    _scan_arguments(pts)
    pts.add_argument(
        "--out",
        type=Path,
        default=Path("cloud.ply"),
        help="output point file: .ply, .pcd (with each point's frame) or .xyz, .csv, .txt, .pts, .asc (x, y, z) "
        "(default: %(default)s)",
    )
    pts.add_argument("--ascii", action="store_true", help="write ASCII PLY or PCD instead of binary")
    pts.set_defaults(run=_points)

    import inspect

    from machscan.registration import ALLOWANCE_NEIGHBORS, ALLOWANCE_SURFACE, BlankSurface, position_workpiece

    positioning = {k: v.default for k, v in inspect.signature(position_workpiece).parameters.items()}
    pos = sub.add_parser("position", help="where the part sits: touch-probe plan, or the pose from one probe round")
    pos.add_argument("model", nargs="?", type=Path, help="model points with normals (PLY/PCD/XYZ/CSV) or a mesh (STL)")
    pos.add_argument("--plan", type=Path, help="probe plan CSV: written without --measured, read with it")
    pos.add_argument("--measured", type=Path, help="probe readings CSV (x, y, z per plan row; empty: missed)")
    pos.add_argument("--pose", type=Path, help="4×4 pose (model → machine) the plan was made at (default: identity)")
    pos.add_argument("--out", type=Path, default=Path("pose.txt"), help="fitted pose (default: %(default)s)")
    pos.add_argument("--next-plan", type=Path, help="write the plan at the fitted pose for the next round")
    pos.add_argument("--n-points", type=int, default=positioning["n_points"], help="probe points (default: %(default)s)")
    pos.add_argument(
        "--keep", type=float, default=positioning["keep"], help="flattest share to choose from (default: %(default)s)"
    )
    pos.add_argument(
        "--pattern",
        choices=("optimal", "random"),
        default=positioning["pattern"],
        help="designed points or the paper's random draw (default: %(default)s)",
    )
    pos.add_argument("--seed", type=int, default=positioning["seed"], help="seed of a random draw (default: %(default)s)")
    pos.add_argument(
        "--probe-radius", type=float, default=positioning["probe_radius"], help="probe ball radius, mm (default: %(default)s)"
    )
    pos.add_argument("--simulate", action="store_true", help="run the rounds on the built-in synthetic blade")
    pos.set_defaults(run=_position)

    al = sub.add_parser("allowance", help="machining allowance of a measured blank over the model")
    al.add_argument("model", type=Path, help="model points with normals (PLY/PCD/XYZ/CSV) or a mesh (STL)")
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
        help="the blank's local surface: quadric, or the paper's plane (default: %(default)s)",
    )
    al.set_defaults(run=_allowance)

    from machscan.matching import Jacobian, isometric_match
    from machscan.mesh import GeodesicMethod
    from machscan.toolpath import Interpolation, SurfaceNormals, compensate_toolpath

    matching = {k: v.default for k, v in inspect.signature(isometric_match).parameters.items()}
    mapping = {k: v.default for k, v in inspect.signature(compensate_toolpath).parameters.items()}
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
        "--jacobian", choices=get_args(Jacobian), default=matching["jacobian"], help="matching Jacobian (default: %(default)s)"
    )
    co.add_argument(
        "--method", choices=get_args(GeodesicMethod), default=matching["method"], help="geodesic distances (default: %(default)s)"
    )
    co.add_argument(
        "--interpolation",
        choices=get_args(Interpolation),
        default=mapping["interpolation"],
        help="mapping between the matching points (default: %(default)s)",
    )
    co.add_argument(
        "--normals",
        choices=get_args(SurfaceNormals),
        default=mapping["normals"],
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
        default=matching["spacing"],
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
    co.set_defaults(run=_compensate)

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
    gr.set_defaults(run=_grind)

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
    bg.set_defaults(run=_batch_grooves)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 0
    if getattr(args, "cloud_every", 1) < 1:
        parser.error("--cloud-every must be at least 1")
    try:
        return int(args.run(args))
    except (ValueError, OSError) as e:
        print(f"machscan: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
