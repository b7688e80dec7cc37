"""Groove inspection end to end (paper 000): from a raw line-laser scan of an engraved,
film-coated skin and the CAD contours to the paper's tables.

Steps (SPEC G and C): per-frame groove fit → groove centers in the WCS → Euclidean clustering
into engraved contours → matching to the CAD contours (one to one, by centroid) → contour error
per contour → decomposition of the error into offset, bending and local parts.

The formulas and their papers: ``docs/contours.md`` (and ``docs/grooves.md`` for the groove fit).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan._core import euclidean_clusters, match_contours, nearest_neighbors
from machscan._options import changed
from machscan.contours import ACTUAL_SPACING, CAD_SPACING, ContourErrorResult, contour_error, resample_cad
from machscan.grooves import GrooveFits, GrooveOptions, fit_grooves
from machscan.scan import Scan

__all__ = [
    "INSPECTION_GROOVE",
    "ContourResult",
    "Decomposition",
    "GrooveReport",
    "InspectionOptions",
    "Tolerance",
    "inspect_grooves",
]


@dataclass(frozen=True, eq=False, repr=False)
class ContourResult:
    """One engraved contour matched to its CAD contour.

    Attributes
    ----------
    cad_index : int
        Index of the CAD contour (as given).
    cluster : int
        Label of the cluster of groove centers.
    frames : ndarray of int64
        Frames whose groove center belongs to this contour (rows of ``fits`` with
        ``select="all"``, in their order along the contour).
    theoretical : ndarray (a, 3)
        CAD contour points P (resampled), mm.
    actual : ndarray (b, 3)
        Measured groove centers (WCS) of the contour's frames, mm; the errors use them joined
        in scan order and resampled (see :func:`inspect_grooves`).
    width, depth : ndarray (b,)
        Groove width and depth of those frames, mm.
    error : ContourErrorResult
        The contour error of paper 000 eq (21)–(23).
    offset_error : float
        |E| after the bending is taken out, mm (decomposition).
    bending : ndarray (a,)
        Bending error at each theoretical point: |B(x, y) − z_CAD|, mm.
    local : ndarray (a,)
        Local error at each theoretical point: what is left after bending and offset, mm.
    """

    cad_index: int
    cluster: int
    frames: NDArray[np.int64]
    theoretical: NDArray[np.float64]
    actual: NDArray[np.float64]
    width: NDArray[np.float64]
    depth: NDArray[np.float64]
    error: ContourErrorResult
    offset_error: float
    bending: NDArray[np.float64]
    local: NDArray[np.float64]

    def __repr__(self) -> str:
        return (
            f"ContourResult(CAD {self.cad_index}: {len(self.frames)} frames, width "
            f"{self.width.mean():.4f} mm, depth {self.depth.mean():.4f} mm, error {self.error.mean:.4f} mm)"
        )


@dataclass(frozen=True, eq=False)
class Decomposition:
    """Shares of the contour error (paper 000 §3: offset 17.16 %, bending 74.56 %, local 8.28 %).

    Each part is a mean magnitude over all theoretical points of all matched contours (mm); the
    shares are each part over their sum. ``bending_surface`` holds the polynomial B(x, y) fitted
    to the measured surface heights (coefficients over ``exponents``, in coordinates centered on
    ``center`` and scaled by ``scale``)."""

    offset: float
    bending: float
    local: float
    offset_share: float
    bending_share: float
    local_share: float
    bending_degree: int
    bending_rms_residual: float
    exponents: NDArray[np.int64] = field(repr=False)
    coefficients: NDArray[np.float64] = field(repr=False)
    center: NDArray[np.float64] = field(repr=False)
    scale: float = field(repr=False)

    def bending_at(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """The fitted bending surface B(x, y) minus the CAD height, mm."""
        return _poly_eval(self.exponents, self.coefficients, np.asarray(x, float), np.asarray(y, float), self.center, self.scale)


@dataclass(frozen=True)
class Tolerance:
    """A groove dimension's specification: its lower and upper limits, mm, and its nominal
    (default their middle).

    Examples
    --------
    >>> report = machscan.inspect_grooves(scan, cad, width_tolerance=machscan.Tolerance(0.45, 0.51))
    """

    lower: float
    upper: float
    nominal: float | None = None

    def __post_init__(self) -> None:
        lo, hi = float(self.lower), float(self.upper)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ValueError(f"tolerance: expected finite limits with lower < upper, mm, got ({self.lower}, {self.upper})")
        nominal = 0.5 * (lo + hi) if self.nominal is None else float(self.nominal)
        if not lo <= nominal <= hi:
            raise ValueError(f"tolerance: nominal {nominal} mm lies outside its limits ({lo}, {hi}) mm")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "nominal", nominal)

    def holds(self, values: ArrayLike) -> NDArray[np.bool_]:
        """Whether each value lies within the limits (NaN: False)."""
        v = np.asarray(values, dtype=np.float64)
        return (v >= self.lower) & (v <= self.upper)

    def capability(self, values: ArrayLike) -> dict[str, float]:
        """Process capability of a sample: ``cp`` = (upper − lower) / 6s, ``cpk`` =
        min(upper − mean, mean − lower) / 3s (s the sample standard deviation, ddof 1; NaN with
        fewer than two values or s = 0) and ``in_tolerance`` the share within the limits."""
        v = np.asarray(values, dtype=np.float64)
        v = v[np.isfinite(v)]
        share = float(self.holds(v).mean()) if len(v) else float("nan")
        if len(v) < 2 or not v.std(ddof=1) > 0:
            return {"cp": float("nan"), "cpk": float("nan"), "in_tolerance": share}
        mean, sd = float(v.mean()), float(v.std(ddof=1))
        return {
            "cp": (self.upper - self.lower) / (6 * sd),
            "cpk": min(self.upper - mean, mean - self.lower) / (3 * sd),
            "in_tolerance": share,
        }


@dataclass(frozen=True, eq=False, repr=False)
class GrooveReport:
    """Everything :func:`inspect_grooves` measured.

    Attributes
    ----------
    fits : GrooveFits
        Per-frame groove fits in the SCS (with ``select="all"`` per groove: every per-frame
        array below then has a row per groove, ``fits.frame`` and ``fits.groove`` saying whose).
    suspect : ndarray of bool (F,)
        Converged fits left out because their standard error of width or depth is more than
        ``max_se_ratio`` times the median (all False unless ``max_se_ratio`` is given).
    center_wcs : ndarray (F, 3)
        Groove center (x0, 0, z0) of every frame in the WCS, mm; NaN where the frame was not
        fitted (its status in ``fits.status`` says why).
    cluster : ndarray of int64 (F,)
        Cluster of every fitted center; −1 for frames not fitted or in clusters smaller than
        ``min_cluster_frames``.
    contour : ndarray of int64 (F,)
        Matched CAD contour of every frame, −1 when none.
    contours : tuple of ContourResult
        One per matched contour, in CAD order.
    unmatched_clusters : tuple of int
        Clusters no CAD contour was matched to (e.g. a stray engraving, or a CAD contour
        missing from the drawing).
    unmatched_cad : tuple of int
        CAD contours no cluster was matched to (not engraved, or not scanned).
    decomposition : Decomposition or None
        None when no contour was matched.
    nearest_cad_distance : ndarray (n_clusters,)
        Distance from each cluster's centroid to the nearest CAD contour centroid, mm: when
        nothing matched, it says how far off the CAD is (another unit, another origin).
    max_match_distance : float
        The matching limit used, mm.
    width_tolerance, depth_tolerance : Tolerance or None
        The specifications the frames and contours are judged against (:attr:`width_ok`,
        :attr:`depth_ok`; Cp, Cpk and the share in tolerance per contour in the tables).
    """

    fits: GrooveFits
    suspect: NDArray[np.bool_]
    center_wcs: NDArray[np.float64]
    cluster: NDArray[np.int64]
    contour: NDArray[np.int64]
    contours: tuple[ContourResult, ...]
    unmatched_clusters: tuple[int, ...]
    unmatched_cad: tuple[int, ...]
    decomposition: Decomposition | None
    nearest_cad_distance: NDArray[np.float64]
    max_match_distance: float
    width_tolerance: Tolerance | None = None
    depth_tolerance: Tolerance | None = None

    @property
    def width_ok(self) -> NDArray[np.bool_]:
        """Per frame (row): measured, and its width within ``width_tolerance`` when there is
        one."""
        return self._within(self.width_tolerance, self.fits.width)

    @property
    def depth_ok(self) -> NDArray[np.bool_]:
        """Per frame (row): the depth within ``depth_tolerance`` (as :attr:`width_ok`)."""
        return self._within(self.depth_tolerance, self.fits.depth)

    def _within(self, tolerance: Tolerance | None, values: NDArray[np.float64]) -> NDArray[np.bool_]:
        if tolerance is None:
            return self.fits.ok.copy()
        return self.fits.ok & tolerance.holds(values)

    def matching_problem(self) -> str | None:
        """Why no contour was matched, in words, or None when some were (or nothing was
        fitted to match)."""
        if self.contours or len(self.nearest_cad_distance) == 0:
            return None
        near = float(self.nearest_cad_distance.min())
        return (
            f"no CAD contour within max_match_distance = {self.max_match_distance:g} mm of the "
            f"{len(self.nearest_cad_distance)} scanned contours: the nearest CAD contour centroid is "
            f"{near:.4g} mm away. Are the CAD contours in mm and in the workpiece coordinate system?"
        )

    @property
    def used(self) -> NDArray[np.bool_]:
        """Frames whose groove center went into the contours: converged and not suspect."""
        return self.fits.ok & ~self.suspect

    # ---- the paper's tables ---------------------------------------------------------------

    def width_depth_rows(self) -> list[dict[str, float | int]]:
        """Paper 000 table 1: groove width and depth per contour (mean, std), mm; with a
        tolerance, the share of frames within it and Cp, Cpk of the contour
        (:meth:`Tolerance.capability`). The last row (contour −1) is overall."""
        rows: list[dict[str, float | int]] = []

        def row(contour: int, w: NDArray[np.float64], d: NDArray[np.float64]) -> dict[str, float | int]:
            r: dict[str, float | int] = {
                "contour": contour,
                "frames": len(w),
                "width_mean": float(w.mean()),
                "width_std": float(w.std()),
                "depth_mean": float(d.mean()),
                "depth_std": float(d.std()),
            }
            for name, tol, v in (("width", self.width_tolerance, w), ("depth", self.depth_tolerance, d)):
                if tol is not None:
                    cap = tol.capability(v)
                    r |= {f"{name}_in_tolerance": cap["in_tolerance"], f"{name}_cp": cap["cp"], f"{name}_cpk": cap["cpk"]}
            return r

        for c in self.contours:
            rows.append(row(c.cad_index, c.width, c.depth))
        if self.contours:
            w, d = (np.concatenate([getattr(c, n) for c in self.contours]) for n in ("width", "depth"))
            rows.append(row(-1, w, d))
        return rows

    def contour_error_rows(self) -> list[dict[str, float | int]]:
        """Paper 000 table 2 and the decomposition: contour error per contour (mean, std, max)
        and its offset, bending and local parts, mm. The last row (contour −1) is overall."""
        rows: list[dict[str, float | int]] = []
        for c in self.contours:
            rows.append(
                {
                    "contour": c.cad_index,
                    "points": len(c.error.errors),
                    "error_mean": c.error.mean,
                    "error_std": c.error.std,
                    "error_max": c.error.max,
                    "offset": c.offset_error,
                    "bending_mean": float(c.bending.mean()),
                    "bending_std": float(c.bending.std()),
                    "local_mean": float(c.local.mean()),
                    "local_std": float(c.local.std()),
                }
            )
        if self.contours:
            e = np.concatenate([c.error.errors for c in self.contours])
            b = np.concatenate([c.bending for c in self.contours])
            lo = np.concatenate([c.local for c in self.contours])
            off = np.concatenate([np.full(len(c.error.errors), c.offset_error) for c in self.contours])
            rows.append(
                {
                    "contour": -1,
                    "points": len(e),
                    "error_mean": float(e.mean()),
                    "error_std": float(e.std()),
                    "error_max": float(e.max()),
                    "offset": float(off.mean()),
                    "bending_mean": float(b.mean()),
                    "bending_std": float(b.std()),
                    "local_mean": float(lo.mean()),
                    "local_std": float(lo.std()),
                }
            )
        return rows

    def width_depth_table(self) -> str:
        """Table 1 as text."""
        tols = [(n, t) for n, t in (("width", self.width_tolerance), ("depth", self.depth_tolerance)) if t is not None]
        head = "contour  frames   width (mm)          depth (mm)       "
        rule = "-------  ------   -----------------   -----------------"
        for n, t in tols:
            head += f"  {n} {t.lower:g}–{t.upper:g} mm: in %, Cp, Cpk"
            rule += "  " + "-" * (len(n) + 32)
        lines = [head.rstrip(), rule]
        for r in self.width_depth_rows():
            name = "all" if r["contour"] == -1 else str(r["contour"])
            line = (
                f"{name:>7}  {r['frames']:>6}   {r['width_mean']:.4f} ± {r['width_std']:.4f}   "
                f"{r['depth_mean']:.4f} ± {r['depth_std']:.4f}"
            )
            for n, _ in tols:
                line += f"  {100 * r[f'{n}_in_tolerance']:>{len(n) + 12}.1f}  {r[f'{n}_cp']:>6.2f}  {r[f'{n}_cpk']:>6.2f}"
            lines.append(line)
        return "\n".join(lines)

    def contour_error_table(self) -> str:
        """Table 2 with the decomposition, as text."""
        lines = [
            "contour  error (mm)          max (mm)  offset   bending             local",
            "-------  -----------------   --------  ------   -----------------   -----------------",
        ]
        for r in self.contour_error_rows():
            name = "all" if r["contour"] == -1 else str(r["contour"])
            lines.append(
                f"{name:>7}  {r['error_mean']:.4f} ± {r['error_std']:.4f}   {r['error_max']:.4f}    "
                f"{r['offset']:.4f}   {r['bending_mean']:.4f} ± {r['bending_std']:.4f}   "
                f"{r['local_mean']:.4f} ± {r['local_std']:.4f}"
            )
        d = self.decomposition
        if d is not None:
            lines.append(
                f"shares of the error: offset {100 * d.offset_share:.2f} %, bending {100 * d.bending_share:.2f} %, "
                f"local {100 * d.local_share:.2f} %"
            )
        return "\n".join(lines)

    def summary(self) -> str:
        """Frames, fits, contours and both tables."""
        f = self.fits
        lines = [f"groove inspection: {len(f)} frames, {int(f.ok.sum())} fitted; {len(self.contours)} contours matched"]
        bad = {k: v for k, v in f.counts().items() if v and k != "converged"}
        if bad:
            lines.append("  frames not fitted: " + ", ".join(f"{k} {v}" for k, v in bad.items()))
        lines += ["  " + line for line in f.pooled_lines()]
        if self.suspect.any():
            lines.append(f"  fits left out as suspect (standard error far above the median): {int(self.suspect.sum())}")
        problem = self.matching_problem()
        if problem:
            lines.append("  " + problem)
        elif self.unmatched_clusters:
            lines.append(f"  clusters with no CAD contour: {list(self.unmatched_clusters)}")
        if self.unmatched_cad:
            lines.append(f"  CAD contours not found in the scan: {list(self.unmatched_cad)}")
        lines += ["", self.width_depth_table(), "", self.contour_error_table()]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"GrooveReport({len(self.fits)} frames, {int(self.fits.ok.sum())} fitted, {len(self.contours)} contours)"

    def to_csv(self, directory: str | os.PathLike[str]) -> list[Path]:
        """Write ``frames.csv`` (per frame, or per groove with ``select="all"``; ``frame`` and
        ``groove`` say which), ``widths.csv`` (table 1) and ``contour_errors.csv``
        (table 2 with the decomposition) into ``directory``; returns the paths. Every column of a
        length names its unit (``width_mm``, ``error_mean_mm``; angles ``_deg``, areas ``_mm2``); in ``frames.csv`` ``status`` and
        ``model`` are the :class:`GrooveStatus` and :class:`GrooveModel` codes, empty cells are NaN."""
        out = Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        paths = []
        f = self.fits
        frame_cols = {
            "frame": f.frame,
            "groove": f.groove,
            "status": f.status,
            "model": f.model,
            "suspect": self.suspect.astype(np.int64),
            "x0_scs_mm": f.x0,
            "z0_scs_mm": f.z0,
            "x_wcs_mm": self.center_wcs[:, 0],
            "y_wcs_mm": self.center_wcs[:, 1],
            "z_wcs_mm": self.center_wcs[:, 2],
            "width_mm": f.width,
            "depth_mm": f.depth,
            "se_width_mm": f.se_width,
            "se_depth_mm": f.se_depth,
            "se_x0_mm": f.se_x0,
            "se_z0_mm": f.se_z0,
            "flank_angle_left_deg": f.flank_angle_left,
            "flank_angle_right_deg": f.flank_angle_right,
            "se_flank_angle_left_deg": f.se_flank_angle_left,
            "se_flank_angle_right_deg": f.se_flank_angle_right,
            "area_mm2": f.area,
            "se_area_mm2": f.se_area,
            "bottom_radius_mm": f.bottom_radius,
            "se_bottom_radius_mm": f.se_bottom_radius,
            "step_mm": f.step,
            "se_step_mm": f.se_step,
            "rms_mm": f.rms,
            "cluster": self.cluster,
            "contour": self.contour,
        }
        for name, tol, ok in (("width", self.width_tolerance, self.width_ok), ("depth", self.depth_tolerance, self.depth_ok)):
            if tol is not None:
                frame_cols[f"{name}_ok"] = ok.astype(np.int64)
        path = out / "frames.csv"
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(frame_cols)
            for row in zip(*frame_cols.values()):
                w.writerow([_cell(v) for v in row])
        paths.append(path)
        for name, rows in (("widths.csv", self.width_depth_rows()), ("contour_errors.csv", self.contour_error_rows())):
            path = out / name
            with open(path, "w", newline="") as fh:
                if rows:
                    # Counts, shares (0–1) and Cp/Cpk have no unit; every other column is a length
                    # in mm, and says so.
                    names = {k: k if k in _COUNTS else f"{k}_mm" for k in rows[0]}
                    table = csv.DictWriter(fh, fieldnames=list(names.values()))
                    table.writeheader()
                    table.writerows({names[k]: v for k, v in r.items()} for r in rows)
            paths.append(path)
        return paths


#: Columns of the tables that are counts, labels, shares or indices, not lengths.
_COUNTS = (
    "contour",
    "frames",
    "points",
    "width_in_tolerance",
    "width_cp",
    "width_cpk",
    "depth_in_tolerance",
    "depth_cp",
    "depth_cpk",
)


def _cell(v: object) -> str | int:
    """A CSV cell: empty for NaN, 10 significant digits for floats, integers as they are."""
    if isinstance(v, (float, np.floating)):
        return "" if np.isnan(v) else f"{v:.10g}"
    return int(v)  # type: ignore[call-overload]


# ---- the bending surface ------------------------------------------------------------------


def _poly_eval(exponents, coefficients, x, y, center, scale):
    """B(x, y) of the bending surface, from the core (any matching shapes of x and y)."""
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    return _core.bending_surface_at(exponents, coefficients, center, scale, x.ravel(), y.ravel()).reshape(x.shape)


#: The groove fit of an inspection: paper 000's t = 200 readings around the line center.
INSPECTION_GROOVE = GrooveOptions(window=200)


@dataclass(frozen=True)
class InspectionOptions:
    """How :func:`inspect_grooves` (and ``machscan grooves``, ``machscan batch``) measures: the
    groove fit of every frame, the clustering of the centers into contours, the matching to
    the CAD and the error decomposition.

    Attributes
    ----------
    groove : GrooveOptions
        The groove fit (see :func:`machscan.fit_grooves`); by default paper 000's window of
        t = 200 readings around the line center (:data:`INSPECTION_GROOVE`).
    cluster_radius : float
        Euclidean clustering radius of the centers, mm (paper: 5 mm; see
        :func:`machscan.euclidean_clusters`).
    cluster_k : int or None
        Nearest neighbours each center links to (paper: 5; None: all within the radius).
    min_cluster_frames : int
        Clusters of fewer centers are dropped as strays.
    cad_spacing, actual_spacing : float
        The CAD contours and the joined centers resampled every so many mm (step 5 of
        :func:`inspect_grooves`).
    max_match_distance : float
        No cluster is matched to a CAD contour whose centroid is farther, mm.
    bending_degree : int
        Total degree of the bending surface B(x, y).
    max_se_ratio : float, optional
        Converged fits whose standard error of width or depth exceeds this many times the
        median are left out as suspect (see ``GrooveReport.suspect``). Off by default: with the
        section models a large standard error rarely marks a wrong fit (on the demo scan a ratio
        of 5 left out 43 frames of which 5 were off by more than 25 µm); it guards the tanh
        template, whose fit converges to a width the data do not fix when a groove lost its
        flank readings (5 is then a good value).
    width_tolerance, depth_tolerance : Tolerance or (lower, upper), optional
        Specifications the report judges frames (pass / fail) and contours (share in
        tolerance, Cp, Cpk) against.

    Examples
    --------
    >>> options = machscan.InspectionOptions(cluster_radius=3.0, groove=machscan.GrooveOptions(window=150))
    >>> report = machscan.inspect_grooves(scan, cad, options=options)
    """

    groove: GrooveOptions = INSPECTION_GROOVE
    cluster_radius: float = 5.0
    cluster_k: int | None = 5
    min_cluster_frames: int = 20
    cad_spacing: float = CAD_SPACING
    actual_spacing: float = ACTUAL_SPACING
    max_match_distance: float = 10.0
    bending_degree: int = 4
    max_se_ratio: float | None = None
    width_tolerance: Tolerance | None = None
    depth_tolerance: Tolerance | None = None

    def __post_init__(self) -> None:
        for name in ("width_tolerance", "depth_tolerance"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, Tolerance):
                if isinstance(value, (tuple, list)) and len(value) in (2, 3):
                    object.__setattr__(self, name, Tolerance(*value))
                else:
                    raise ValueError(f"{name}: expected a machscan.Tolerance or (lower, upper) mm, got {value!r}")
        if not isinstance(self.groove, GrooveOptions):
            raise ValueError(f"groove: expected a machscan.GrooveOptions, got {type(self.groove).__name__}")

    def with_changes(self, changes: Mapping[str, Any], where: str = "options") -> InspectionOptions:
        """These options with ``changes`` made: names of this class's fields, or of
        :class:`GrooveOptions` fields, which change ``groove``."""
        groove_names = {f.name for f in fields(GrooveOptions)}
        groove = {k: v for k, v in changes.items() if k in groove_names}
        mine = {k: v for k, v in changes.items() if k not in groove_names}
        options = changed(self, mine, where)
        return replace(options, groove=options.groove.with_changes(groove, where)) if groove else options


# ---- the workflow -------------------------------------------------------------------------


def _as_polylines(cad_contours: Sequence[ArrayLike] | NDArray[np.float64]) -> list[NDArray[np.float64]]:
    out = []
    for k, c in enumerate(cad_contours):
        a = np.asarray(c, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] not in (2, 3):
            raise ValueError(f"cad_contours: contour {k}: expected shape (n, 3) or (n, 2), got {a.shape}")
        if a.shape[1] == 2:
            a = np.column_stack([a, np.zeros(len(a))])
        if len(a) < 3:
            raise ValueError(f"cad_contours: contour {k}: a closed contour needs at least 3 points, got {len(a)}")
        if not np.isfinite(a).all():
            raise ValueError(f"cad_contours: contour {k}: must be finite")
        out.append(a)
    if not out:
        raise ValueError("cad_contours: expected at least one contour, got none")
    return out


def inspect_grooves(
    scan: Scan,
    cad_contours: Sequence[ArrayLike],
    *,
    options: InspectionOptions | None = None,
    progress: bool | None = False,
    **changes: Any,
) -> GrooveReport:
    """Measure engraved grooves and their contour error from a raw scan (paper 000).

    1. Every frame: the groove fit of :func:`machscan.fit_grooves` (the section models by
       default, the paper's tanh template with ``template="tanh"``) on the ``window`` readings
       around the line center (the scan path keeps the groove there).
    2. Groove centers (x0, 0, z0) to the WCS with the frame's machine pose.
    3. Euclidean clustering of the centers (``cluster_radius``, paper: 5 mm with ``cluster_k``
       = 5 nearest); clusters smaller than ``min_cluster_frames`` are dropped as strays.
    4. CAD contours resampled every ``cad_spacing`` mm; clusters matched to them one to one by
       centroid (no match beyond ``max_match_distance``).
    5. Contour error per contour, paper eq (21)–(23), against the centers joined in scan order
       and resampled every ``actual_spacing`` mm. The paper's frames lie microns apart; a
       decimated scan's do not, and bare centers would add the gaps between frames to the
       nearest-point distances. Both spacings must be small against the errors measured: the
       nearest-point matching adds up to about half of the coarser one (the defaults, 5 µm and
       2 µm, add about 1 µm; 0.2 mm would add about 0.1 mm).
    6. Decomposition: a polynomial B(x, y) of degree ``bending_degree`` is fitted to the
       measured surface heights minus the CAD heights over the whole part (the smooth
       deformation of the clamped skin). Bending error = |B| at the CAD points; offset error
       = |E| of the contour once the bending is taken out; local error = what is left,
       |P_i − Q'| after both. Shares are the mean parts over their sum.

    Parameters
    ----------
    scan : Scan
        Raw scan: frames, poses, profiler, machine (AC head with C2 and mount).
    cad_contours : sequence of array_like, each (n, 3) or (n, 2); or one (n, 3) array
        Closed CAD polylines in the WCS, mm (z = 0 when only x, y are given), resampled every
        ``cad_spacing`` mm. Or the points of the whole drawing as one array: its contours are
        then found by the same Euclidean clustering as the groove centers and its points are
        used as they are (they should be dense: see step 5).
    options : InspectionOptions, optional
        How it measures (default :class:`InspectionOptions()`; every field is described there).
    **changes
        Fields of :class:`InspectionOptions`, or of its ``groove`` (:class:`GrooveOptions`),
        changed for this call: ``inspect_grooves(scan, cad, window=150, max_se_ratio=5.0)``.
    progress : bool or None
        A progress bar of the groove fits on stderr (:func:`machscan.fit_grooves`); None: when
        stderr is a terminal.

    Returns
    -------
    GrooveReport
        Per-frame arrays, per-contour results, tables (``summary()``, ``to_csv()``) and plots
        (:mod:`machscan.plot`).

    Examples
    --------
    >>> scan, truth = machscan.synth.groove_scan(seed=0)
    >>> report = machscan.inspect_grooves(scan, truth.nominal_polylines)
    >>> print(report.summary())
    """
    if options is None:
        options = InspectionOptions()
    if not isinstance(options, InspectionOptions):
        raise ValueError(f"options: expected a machscan.InspectionOptions, got {type(options).__name__}")
    options = options.with_changes(changes, "inspect_grooves")
    groove = options.groove
    cluster_radius, cluster_k, min_cluster_frames = options.cluster_radius, options.cluster_k, options.min_cluster_frames
    cad_spacing, actual_spacing = options.cad_spacing, options.actual_spacing
    max_match_distance, bending_degree, max_se_ratio = options.max_match_distance, options.bending_degree, options.max_se_ratio
    if not isinstance(scan, Scan):
        raise ValueError(f"scan: expected a machscan.Scan, got {type(scan).__name__}")
    cad_cloud = isinstance(cad_contours, np.ndarray) and cad_contours.ndim == 2
    if cad_cloud:
        # One point set for the whole drawing: its contours are found by the same Euclidean
        # clustering as the groove centers (SPEC C1); the points are used as they are.
        cad_points = np.asarray(cad_contours, dtype=np.float64)
        if cad_points.shape[1] == 2:
            cad_points = np.column_stack([cad_points, np.zeros(len(cad_points))])
        if cad_points.shape[1] != 3 or len(cad_points) < 3 or not np.isfinite(cad_points).all():
            raise ValueError(f"cad_contours: expected finite (n, 3) points with n >= 3, got {cad_points.shape}")
        cad_labels = euclidean_clusters(cad_points, cluster_radius, k=_cluster_k(cluster_k, len(cad_points)))
        polylines = [cad_points[cad_labels == c] for c in range(int(cad_labels.max()) + 1)]
    else:
        polylines = _as_polylines(cad_contours)
    if groove.window is not None and groove.window > scan.n_readings:
        raise ValueError(f"window: {groove.window} readings, but the frames have only {scan.n_readings}")
    if min_cluster_frames < 1:
        raise ValueError(f"min_cluster_frames: must be at least 1, got {min_cluster_frames}")
    if bending_degree < 0:
        raise ValueError(f"bending_degree: must be >= 0, got {bending_degree}")
    prof = scan.profiler
    x = (np.arange(scan.n_readings) - prof.i0) * prof.pitch
    z = np.where(scan.valid_mask(), scan.frames, np.nan)
    fits = fit_grooves(x, z, options=groove, progress=progress)
    if max_se_ratio is not None and not max_se_ratio > 0:
        raise ValueError(f"max_se_ratio: must be positive or None, got {max_se_ratio}")
    converged = fits.ok
    suspect = np.zeros(len(fits), dtype=bool)
    if converged.any() and max_se_ratio is not None:
        for se in (fits.se_width, fits.se_depth):
            suspect |= converged & (se > max_se_ratio * np.median(se[converged]))
    ok = converged & ~suspect

    # Centers to the WCS with each frame's pose (with select="all", a row per groove: its frame's).
    t = scan.transforms()[fits.frame]
    local = np.column_stack([fits.x0, np.zeros(len(fits)), fits.z0])
    center = np.full((len(fits), 3), np.nan)
    center[ok] = np.einsum("fij,fj->fi", t[ok, :3, :3], local[ok]) + t[ok, :3, 3]

    # Contours from the center cloud.
    cluster = np.full(len(fits), -1, dtype=np.int64)
    idx_ok = np.nonzero(ok)[0]
    if len(idx_ok):
        labels = euclidean_clusters(center[idx_ok], cluster_radius, k=_cluster_k(cluster_k, len(idx_ok)))
        sizes = np.bincount(labels)
        keep = sizes[labels] >= min_cluster_frames
        # Renumber the kept clusters 0.. in order of first frame.
        kept_labels = np.unique(labels[keep])
        renum = np.full(len(sizes), -1, dtype=np.int64)
        renum[kept_labels] = np.arange(len(kept_labels))
        cluster[idx_ok] = renum[labels]
    n_clusters = int(cluster.max()) + 1
    theoretical = polylines if cad_cloud else [resample_cad(p, spacing=cad_spacing) for p in polylines]
    cad_centroids = np.array([p.mean(0) for p in theoretical])
    cl_centroids = np.array([center[cluster == c].mean(0) for c in range(n_clusters)]).reshape(-1, 3)
    match = match_contours(cl_centroids, cad_centroids, max_distance=max_match_distance)
    nearest_cad = (
        np.linalg.norm(cl_centroids[:, None, :] - cad_centroids[None, :, :], axis=2).min(axis=1) if n_clusters else np.zeros(0)
    )
    contour = np.full(len(fits), -1, dtype=np.int64)
    for c, m in enumerate(match):
        if m >= 0:
            contour[cluster == c] = m

    # Bending surface over the whole part: measured heights minus CAD heights at the centers.
    pairs = [(int(m), c) for c, m in enumerate(match) if m >= 0]
    decomposition = None
    results = []
    if pairs:
        dz_parts, xs, ys = [], [], []
        for m, c in pairs:
            q = center[cluster == c]
            p = theoretical[m]
            # CAD height under each center: the nearest CAD point's z (the CAD skin is smooth).
            near, _ = nearest_neighbors(p * [1.0, 1.0, 0.0], q * [1.0, 1.0, 0.0])
            dz_parts.append(q[:, 2] - p[near, 2])
            xs.append(q[:, 0])
            ys.append(q[:, 1])
        xs_a, ys_a, dz = np.concatenate(xs), np.concatenate(ys), np.concatenate(dz_parts)
        surface = _core.fit_bending_surface(xs_a, ys_a, dz, degree=int(bending_degree))
        ex, coef, bend_center = surface["exponents"], surface["coefficients"], surface["center"]
        degree, scale, resid = surface["degree"], surface["scale"], surface["rms_residual"]
        totals = np.zeros(3)
        count = 0
        for m, c in sorted(pairs):
            frames = np.nonzero(cluster == c)[0]
            if groove.select == "all":
                # Several lines per profile: a contour's centers come from the passes along
                # it and from those crossing it, so scan order is not its order; they are put
                # in the order of their nearest CAD points along the contour.
                along, _ = nearest_neighbors(theoretical[m], center[frames])
                frames = frames[np.argsort(along, kind="stable")]
            q = center[frames]
            p = theoretical[m]
            # The building block on the same inputs gives the same figure: machscan.contour_error(c.theoretical,
            # the contour's centers) with these spacings.
            err = contour_error(p, q, cad_spacing=None if cad_cloud else cad_spacing, actual_spacing=actual_spacing)
            dense = err.actual
            bend_q = _poly_eval(ex, coef, dense[:, 0], dense[:, 1], bend_center, scale)
            flat = dense - np.column_stack([np.zeros((len(dense), 2)), bend_q])
            bend_p = np.abs(_poly_eval(ex, coef, p[:, 0], p[:, 1], bend_center, scale))
            flat_err = contour_error(p, flat, cad_spacing=None, actual_spacing=None)
            offset_error = float(np.linalg.norm(flat_err.offset))
            results.append(
                ContourResult(
                    cad_index=m,
                    cluster=c,
                    frames=frames,
                    theoretical=p,
                    actual=q,
                    width=fits.width[frames],
                    depth=fits.depth[frames],
                    error=err,
                    offset_error=offset_error,
                    bending=bend_p,
                    local=flat_err.deviations,
                )
            )
            totals += [offset_error * len(p), bend_p.sum(), flat_err.deviations.sum()]
            count += len(p)
        parts = totals / count
        shares = parts / parts.sum() if parts.sum() > 0 else np.zeros(3)
        decomposition = Decomposition(
            offset=float(parts[0]),
            bending=float(parts[1]),
            local=float(parts[2]),
            offset_share=float(shares[0]),
            bending_share=float(shares[1]),
            local_share=float(shares[2]),
            bending_degree=degree,
            bending_rms_residual=resid,
            exponents=ex,
            coefficients=coef,
            center=bend_center,
            scale=scale,
        )
    matched_cad = {m for m, _ in pairs}
    return GrooveReport(
        fits=fits,
        suspect=suspect,
        center_wcs=center,
        cluster=cluster,
        contour=contour,
        contours=tuple(results),
        unmatched_clusters=tuple(c for c, m in enumerate(match) if m < 0),
        unmatched_cad=tuple(k for k in range(len(polylines)) if k not in matched_cad),
        decomposition=decomposition,
        nearest_cad_distance=nearest_cad,
        max_match_distance=float(max_match_distance),
        width_tolerance=options.width_tolerance,
        depth_tolerance=options.depth_tolerance,
    )


def _cluster_k(k: int | None, n: int) -> int | None:
    """The paper's k nearest, for a cloud of n points: every other point when there are fewer
    than k (the same partition as k = n − 1)."""
    if k is None or n < 2:
        return None if n < 2 else k
    return min(k, n - 1)
