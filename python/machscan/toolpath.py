"""Toolpaths: compensation for mirror milling, and the row spacing of grinding paths.

Toolpath compensation for mirror milling (SPEC S5; paper 002 §4): the toolpath programmed on the theoretical
skin, carried onto the skin as it lies bent on the machine, so that pockets and wall thickness land where the
design wants them.

:func:`compensate_toolpath` takes the matching pairs (theoretical points and where :func:`machscan.isometric_match`
found them) and the scan. Each tool point is split into its foot on the theoretical surface and its offset
along the theoretical normal (0 for a contact point, −h for a pocket floor h deep); the foot is mapped onto the
actual surface and the offset put back along the actual normal; a tool axis turns with the normal.

The formulas and their papers: ``docs/matching.md`` (compensation) and ``docs/grinding.md`` (grinding paths).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan.io import Toolpath, write_toolpath
from machscan.mesh import _surface

__all__ = [
    "COMPENSATE_INTERPOLATION",
    "COMPENSATE_NORMALS",
    "FEED_STEP",
    "BeadChain",
    "ChainMethod",
    "CompensatedToolpath",
    "FeedUnit",
    "GrindingPaths",
    "Interpolation",
    "RemovalCheck",
    "RemovalModel",
    "SurfaceNormals",
    "UnsafePathError",
    "bead_chain",
    "compensate_toolpath",
    "grinding_paths",
    "scallop_height",
    "simulate_removal",
    "step_over",
]

#: How theoretical x, y map to the actual surface: ``"cubic"`` (default), polyharmonic splines through the
#: matching pairs (cubic fields reproduced exactly); ``"linear"``, the paper's eq 17, the barycentric
#: coordinates of the point in the theoretical matching triangle applied to the actual one (one shared
#: connectivity).
Interpolation = Literal["cubic", "linear"]

#: The actual surface point and normal: ``"smooth"`` (default), a local quadric fitted to the scan points within
#: ``radius``; ``"triangle"``, the paper's closest point on the scan mesh and its triangle's normal (which tilts
#: with the scan's noise: ~0.2° at 5 µm noise and 1.3 mm spacing).
SurfaceNormals = Literal["smooth", "triangle"]


#: Default share of the feed by which the wanted feed must change before :func:`grinding_paths` programs a new one
#: (the core's ``DEFAULT_FEED_STEP``).
FEED_STEP: float = _core.GRINDING_FEED_STEP

#: The band a ground section must end within, mm: paper 004 measures its ground sections within ±0.08 mm of the model.
BAND: float = 0.08


class UnsafePathError(ValueError):
    """A grinding path whose simulated pass leaves points outside the band (an over-cut scraps the part): it is not
    written as a usable path. The message names the points and rows; ``force=True`` writes it anyway."""


#: How :func:`bead_chain` orders a section: ``"tree"`` (default) along the diameter of the points' minimum
#: spanning tree; ``"nearest"``, the paper's rule, always to the nearest unvisited point.
ChainMethod = Literal["tree", "nearest"]


@dataclass(frozen=True, eq=False)
class CompensatedToolpath:
    """Result of :func:`compensate_toolpath`, one row per tool point.

    Attributes
    ----------
    points : ndarray, shape (M, 3)
        The compensated tool points, mm.
    axes : ndarray, shape (M, 3)
        Unit tool axes: the given axes turned as the surface normal turned, or the actual surface normal (+z
        side) when none were given.
    inside : ndarray of bool, shape (M,)
        False where the point's foot lies outside the xy hull of the theoretical matching points: it was
        extrapolated, and is only as good as the mapping beyond the last matching points.
    on_scan : ndarray of bool, shape (M,)
        False where the point maps to where the scan has no surface: its x, y outside the scan mesh (beyond its
        outline, or over a hole the mesh leaves open). It was put on the scan's nearest edge, which is not where
        the part is: rescan there, or leave the point out. Use ``inside & on_scan`` for the points to trust.
    offsets : ndarray, shape (M,)
        Each tool point's offset from the theoretical surface along its normal, mm (negative below it).
    """

    points: NDArray[np.float64]
    axes: NDArray[np.float64]
    inside: NDArray[np.bool_]
    on_scan: NDArray[np.bool_]
    offsets: NDArray[np.float64]

    def __repr__(self) -> str:
        out, off = int((~self.inside).sum()), int((~self.on_scan).sum())
        return f"CompensatedToolpath({len(self.points)} points, {out} outside the matching hull, {off} beyond the scan)"


#: Defaults of :func:`compensate_toolpath`, which its signature and ``machscan compensate`` read.
COMPENSATE_INTERPOLATION: Interpolation = "cubic"
COMPENSATE_NORMALS: SurfaceNormals = "smooth"


def compensate_toolpath(
    tool_points: ArrayLike | Toolpath,
    theoretical_matching: ArrayLike,
    actual_matching: ArrayLike,
    actual_surface: ArrayLike | tuple[ArrayLike, ArrayLike],
    *,
    interpolation: Interpolation = COMPENSATE_INTERPOLATION,
    normals: SurfaceNormals = COMPENSATE_NORMALS,
    radius: float | None = None,
    max_edge: float | None = None,
) -> CompensatedToolpath:
    """Carry a toolpath from the theoretical skin onto the scanned one (SPEC S5–S6; paper 002 §4).

    Parameters
    ----------
    tool_points : array_like, shape (M, 3) or (M, 6), or :class:`machscan.io.Toolpath`
        Tool points on or off the theoretical surface, mm, with unit tool axes in columns 3–5 if given (normalised;
        a length more than 1e-3 from 1 is refused). A point whose axis columns are all NaN has no axis of its own,
        as a Toolpath's ``GOTO/x,y,z`` among five-axis GOTOs: it takes the actual surface normal.
    theoretical_matching, actual_matching : array_like, shape (n, 3)
        The matching pairs: theoretical points (n ≥ 6, not all on one line or conic in xy) and their actual
        places, e.g. :func:`machscan.isometric_match`'s ``.points``. An actual point farther from the scan than two
        median edges of its mesh (at least 1 mm) is refused: it is not on the part.
    actual_surface : array_like (N, 3), or (vertices, faces)
        The scan of the clamped part (meshed by :func:`machscan.delaunay_xy`, the long triangles across a concave
        outline peeled off as :func:`machscan.isometric_match` does), or its mesh.
    interpolation : {"cubic", "linear"}
        See :data:`Interpolation`.
    normals : {"smooth", "triangle"}
        See :data:`SurfaceNormals`.
    radius : float, optional
        Radius of the scan patch of the smooth surface, mm; by default 5 median edge lengths of the scan mesh.
        The axes' tilt from the scan's noise σ at spacing h goes as σ·h / radius²: at the default about
        0.011° per µm of noise per mm of spacing, measured on the bent skin (0.040° at 5 µm and 1.3 mm, 0.08°
        at 10 µm, 0.115° at 10 µm and 1.0 mm); a larger radius lowers it, at the cost of the surface's
        features smaller than the patch.
    max_edge : float, optional
        Long-edge trim when meshing a point scan, mm.

    Returns
    -------
    CompensatedToolpath
        ``.points``, ``.axes``, ``.inside``, ``.on_scan``, ``.offsets``.

    Examples
    --------
    >>> match = machscan.isometric_match(theoretical, scan, r, r_measured, grid)
    >>> path = machscan.compensate_toolpath(tool_points, grid, match.points, scan)
    >>> machscan.io.write_toolpath("compensated.cl", path.points, axes=path.axes)
    """
    if isinstance(tool_points, Toolpath):
        axes = tool_points.axes
        tool_points = np.hstack([tool_points.points, axes]) if np.isfinite(axes).any() else tool_points.points
    vertices, faces = _surface(actual_surface, "actual_surface")
    out = _core.compensate_toolpath(
        tool_points,
        theoretical_matching,
        actual_matching,
        vertices,
        faces,
        interpolation=interpolation,
        normals=normals,
        radius=radius,
        max_edge=max_edge,
    )
    return CompensatedToolpath(**out)


def _elementwise(kernel, names: tuple[str, str, str], a: ArrayLike, b: ArrayLike, c: ArrayLike) -> float | NDArray[np.float64]:
    arrays = [np.asarray(x, dtype=np.float64) for x in (a, b, c)]
    try:
        shaped = np.broadcast_arrays(*arrays)
    except ValueError:
        shapes = ", ".join(f"{n} {x.shape}" for n, x in zip(names, arrays))
        raise ValueError(f"{names[2]}: the shapes do not broadcast: {shapes}") from None
    out = kernel(*(np.ascontiguousarray(x).ravel() for x in shaped)).reshape(shaped[0].shape)
    return float(out) if out.ndim == 0 else out


def scallop_height(tool_radius: ArrayLike, curvature_radius: ArrayLike, step: ArrayLike) -> float | NDArray[np.float64]:
    """The cusp height left between two tool rows an arc ``step`` apart (SPEC P3; paper 004 §3), by exact circle
    geometry in the plane across the rows: the surface a circle of radius ``curvature_radius``, the contact wheel a
    circle of radius ``tool_radius`` touching it at each row. Vectorised (arguments broadcast); no digits lost on
    nearly flat surfaces.

    Parameters
    ----------
    tool_radius : float or array_like
        Contact radius R, mm.
    curvature_radius : float or array_like
        Surface radius ρ across the rows, mm: > 0 convex, < 0 concave (|ρ| > R, or the tool does not fit), ``inf``
        flat.
    step : float or array_like
        Row spacing, arc length on the surface, mm.

    Returns
    -------
    float or ndarray
        Scallop height, mm.

    Raises
    ------
    ValueError
        A radius ≤ 0 or NaN, a concave radius the tool does not fit, a step so wide that the rows leave a strip
        unground; the message names the argument (and the element of an array).

    Examples
    --------
    >>> machscan.scallop_height(10.0, float("inf"), 2.0)   # R − √(R² − 1)
    0.050125628933...
    """
    return _elementwise(_core.scallop_heights, ("tool_radius", "curvature_radius", "step"), tool_radius, curvature_radius, step)


def step_over(tool_radius: ArrayLike, curvature_radius: ArrayLike, scallop_height: ArrayLike) -> float | NDArray[np.float64]:
    """The widest row spacing (arc length on the surface, mm) that leaves cusps no higher than ``scallop_height``:
    the inverse of :func:`scallop_height`, in closed form (SPEC P3). Vectorised (arguments broadcast).

    Parameters
    ----------
    tool_radius : float or array_like
        Contact radius R, mm.
    curvature_radius : float or array_like
        Surface radius across the rows, mm: > 0 convex, < 0 concave, ``inf`` flat.
    scallop_height : float or array_like
        Allowed cusp height, 0 ≤ h < R, mm.

    Returns
    -------
    float or ndarray
        Step-over, mm.

    Examples
    --------
    >>> machscan.step_over(10.0, [50.0, float("inf"), -50.0], 0.01)   # convex, flat, concave
    array([0.8162..., 0.8942..., 0.9998...])
    """
    return _elementwise(
        _core.step_overs, ("tool_radius", "curvature_radius", "scallop_height"), tool_radius, curvature_radius, scallop_height
    )


@dataclass(frozen=True, eq=False)
class BeadChain:
    """Result of :func:`bead_chain`.

    Attributes
    ----------
    order : ndarray of int64, shape (N,)
        Every point once, in path order: ``points[order]`` is the polyline.
    closed : bool
        Whether the section closes up (the last point lies next to the first).
    """

    order: NDArray[np.int64]
    closed: bool

    def __repr__(self) -> str:
        return f"BeadChain({len(self.order)} points, {'closed' if self.closed else 'open'})"


def bead_chain(
    points: ArrayLike,
    *,
    start: ArrayLike | None = None,
    direction: ArrayLike | None = None,
    method: ChainMethod = "tree",
) -> BeadChain:
    """Order the points of one section into a continuous polyline (SPEC P2; paper 004 §2.1, the "bead chain").

    A section of a scan is a band of scattered points, not a thin curve, and a blade's trailing edge brings its
    other side within tenths of a millimetre. The paper's rule (``method="nearest"``: step to the nearest unvisited
    point) skips points on such a band and comes back for them by long jumps. The default orders the points along
    the diameter of their minimum spanning tree: the tree follows the band, the two sides of a thin edge meet only
    round its tip, and every point's place along the curve is where its branch meets the diameter plus its offset
    along the tangent there.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        The points of one section, mm (e.g. those within ±h/2 of a plane).
    start : array_like, shape (3,), optional
        An open section starts at the end nearest to it; a closed one at the point nearest to it. By default the
        point (end) lowest along the section's main axis.
    direction : array_like, shape (3,), optional
        The way a closed section is run (by default counter-clockwise seen from the +z side of its plane), or
        which end an open one starts from when no ``start`` is given.
    method : {"tree", "nearest"}
        See :data:`ChainMethod`.

    Returns
    -------
    BeadChain
        ``.order`` and ``.closed``.

    Examples
    --------
    >>> chain = machscan.bead_chain(section)
    >>> polyline = section[chain.order]
    """
    out = _core.bead_chain(points, start, direction, method=method)
    return BeadChain(out["order"], bool(out["closed"]))


#: The feed unit of a :class:`RemovalModel`: the unit its calibration data gives the feed in.
FeedUnit = Literal["mm/s", "mm/min"]

#: Minutes per feed unit's time: what a feed is multiplied by to give mm/min (the CL file's unit).
_PER_MINUTE = {"mm/s": 60.0, "mm/min": 1.0}


@dataclass(frozen=True)
class RemovalModel:
    """The removal model of belt grinding (SPEC P4; paper 004 eq 11): the depth removed is
    ``r = C · Vb^e₁ · Vw^e₂ · F^e₃`` for belt speed ``Vb``, feed ``Vw`` and contact force ``F``.

    The model stays in the units its calibration data comes in. Those of the paper, and the defaults
    here: ``r`` in mm, ``Vb`` in m/s, ``Vw`` in mm/s, ``F`` in N — so ``C`` carries whatever units make
    that product mm. The feeds it gives (:meth:`feed`, :attr:`GrindingPaths.feed`) and its
    ``feed_limits`` are in ``feed_unit``; CL files are written in mm/min (``FEDRAT/MMPM,f``, 60 × a
    feed in mm/s), which is what :func:`machscan.io.read_toolpath` reads back.

    Attributes
    ----------
    C : float
        Coefficient, > 0.
    exponents : (float, float, float)
        ``(e_belt, e_feed, e_force)``; ``e_feed`` ≠ 0 (negative: a faster feed removes less).
    belt_speed : float
        The belt speed the path is ground at, m/s (the calibration's unit), > 0.
    force : float
        The contact force, N (the calibration's unit), > 0.
    feed_limits : (float, float)
        The machine's lowest and highest feed, ``0 < low ≤ high``, in ``feed_unit``.
    feed_unit : {"mm/s", "mm/min"}
        The unit of the feed in the calibration (the paper's: mm/s).

    Examples
    --------
    >>> model = machscan.RemovalModel(C=0.3, exponents=(0.6, -0.7, 0.8), belt_speed=20.0, force=15.0,
    ...                               feed_limits=(1.0, 50.0))
    >>> feed = model.feed([0.10, 0.25])          # mm/s that remove 0.10 and 0.25 mm
    >>> model.removal(feed)
    array([0.1 , 0.25])
    >>> model.per_minute(feed)                   # the same feeds in mm/min, as a CL file has them
    """

    C: float
    exponents: tuple[float, float, float]
    belt_speed: float
    force: float
    feed_limits: tuple[float, float]
    feed_unit: FeedUnit = "mm/s"

    @classmethod
    def of(cls, model: RemovalModel | Mapping[str, object]) -> RemovalModel:
        """A RemovalModel, or one built from a mapping with the same keys (the issue's ``dict(C=..., ...)``)."""
        if isinstance(model, RemovalModel):
            return model
        if not isinstance(model, Mapping):
            raise TypeError(f"removal_model: expected a RemovalModel or a dict of its fields, got {type(model).__name__}")
        fields = {"C", "exponents", "belt_speed", "force", "feed_limits", "feed_unit"}
        missing, extra = fields - set(model) - {"feed_unit"}, set(model) - fields
        if missing or extra:
            raise ValueError(f"removal_model: missing keys {sorted(missing)}, unknown keys {sorted(extra)}")
        return cls(**model)  # type: ignore[arg-type]

    def per_minute(self, feed: ArrayLike) -> NDArray[np.float64]:
        """Feeds of this model (in :attr:`feed_unit`) in mm/min, the unit of CL files."""
        if self.feed_unit not in _PER_MINUTE:
            raise ValueError(f"removal_model.feed_unit: expected one of {sorted(_PER_MINUTE)}, got {self.feed_unit!r}")
        return _PER_MINUTE[self.feed_unit] * np.asarray(feed, dtype=np.float64)

    def _args(self) -> tuple[float, tuple[float, float, float], float, float, tuple[float, float]]:
        if self.feed_unit not in _PER_MINUTE:
            raise ValueError(f"removal_model.feed_unit: expected one of {sorted(_PER_MINUTE)}, got {self.feed_unit!r}")
        e = tuple(float(x) for x in self.exponents)
        lim = tuple(float(x) for x in self.feed_limits)
        if len(e) != 3 or len(lim) != 2:
            raise ValueError("removal_model: expected three exponents (belt, feed, force) and two feed limits (low, high)")
        return (float(self.C), (e[0], e[1], e[2]), float(self.belt_speed), float(self.force), (lim[0], lim[1]))

    def feed(self, allowance: ArrayLike) -> NDArray[np.float64]:
        """The feed that removes ``allowance`` (mm) at each point, clamped to the limits; where there is nothing to
        remove (≤ 0), the limit that removes least."""
        a = np.asarray(allowance, dtype=np.float64)
        return _core.removal_feeds(np.ravel(a), self._args()).reshape(a.shape)

    def removal(self, feed: ArrayLike) -> NDArray[np.float64]:
        """The depth (mm) removed at each ``feed``."""
        f = np.asarray(feed, dtype=np.float64)
        return _core.removal_depths(np.ravel(f), self._args()).reshape(f.shape)


@dataclass(frozen=True, eq=False)
class GrindingPaths:
    """Result of :func:`grinding_paths`: one path, row after row, one entry per path point (paper 004 table 4).

    Attributes
    ----------
    points : ndarray, shape (M, 3)
        Contact points on the surface, each on its row's section plane, mm.
    normals : ndarray, shape (M, 3)
        Unit outward surface normals there (the tool axis of a contact-wheel program).
    row : ndarray of int64, shape (M,)
        Row of each point, 0 at the lowest section offset.
    curvature : ndarray, shape (M,)
        Normal curvature of the surface across the rows, 1/mm: > 0 convex, < 0 concave.
    allowance : ndarray, shape (M,)
        The allowance field at each point, mm.
    feed : ndarray, shape (M,)
        The feed programmed at each point, in the removal model's ``feed_unit`` (mm/s for the paper's
        calibration): the feed removing the point's allowance, clamped to the limits, and held along the path
        while that stays within ``feed_step`` of the feed in force (so a CL file gets a FEDRAT per real change).
        NaN without a model. :meth:`feed_per_minute` gives it in mm/min, as :meth:`to_apt` writes it.
    tool_fits : ndarray of bool, shape (M,)
        False where the surface is concave with a radius no larger than the tool's: the tool cannot reach there.
    row_offsets : ndarray, shape (rows,)
        Each row's plane: offset along the unit section normal, mm (non-decreasing; the pieces of a cut row share it).
    row_closed : ndarray of bool, shape (rows,)
        Whether the row closes round the part (a blade section) or runs edge to edge.
    without_stock : int
        Cloud points left out because their allowance is NaN: no stock was measured there (the blank does not
        cover them). The rows do not cross them; grind them once the blank is measured there.
    tool_radius, scallop_height : float
        As requested.
    section_normal : ndarray, shape (3,)
        The unit section normal.
    removal_model : RemovalModel or None
    check : RemovalCheck
        The pass simulated over the cloud the path was made from (:func:`simulate_removal` with the path's own
        feeds): ``check.within_band`` says whether every point ends within ±``band`` of the model; where it does
        not, :meth:`to_apt` refuses to write the path.
    """

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    row: NDArray[np.int64]
    curvature: NDArray[np.float64]
    allowance: NDArray[np.float64]
    feed: NDArray[np.float64]
    tool_fits: NDArray[np.bool_]
    row_offsets: NDArray[np.float64]
    row_closed: NDArray[np.bool_]
    without_stock: int
    tool_radius: float
    scallop_height: float
    section_normal: NDArray[np.float64]
    removal_model: RemovalModel | None
    check: RemovalCheck

    def __repr__(self) -> str:
        left_out = f", {self.without_stock} cloud points without stock left out" if self.without_stock else ""
        return (
            f"GrindingPaths({len(self.points)} points in {len(self.row_offsets)} rows, tool radius {self.tool_radius} mm"
            f"{left_out})"
        )

    def removal(self) -> NDArray[np.float64]:
        """The depth removed at each path point: the removal model at the point's feed, or its allowance when the
        path has no model (an ideal tool that removes what it is asked to)."""
        if self.removal_model is None:
            return self.allowance.copy()
        return self.removal_model.removal(self.feed)

    def feed_per_minute(self) -> NDArray[np.float64]:
        """The programmed feed at each path point in mm/min (the unit of CL files); NaN without a removal model."""
        if self.removal_model is None:
            return self.feed.copy()
        return self.removal_model.per_minute(self.feed)

    def to_apt(self, path: str | os.PathLike[str], *, force: bool = False) -> None:
        """Write the path as APT/CL: ``UNITS/MM``, ``GOTO/x,y,z,i,j,k`` per point (contact point and outward
        normal), ``FEDRAT/MMPM,f`` in mm/min where the programmed feed changes (none without a removal model).
        :func:`machscan.io.read_toolpath` reads it back with ``feeds`` equal to :meth:`feed_per_minute`.

        A path whose simulated pass (:attr:`check`) leaves any point outside the band is refused: an over-cut
        scraps the part, and a path is not written as usable that the simulation says is not. ``force=True``
        writes it anyway (e.g. to inspect it in a CAM viewer).

        Raises
        ------
        UnsafePathError
            The simulated pass leaves points outside the band; the message names how many, how far, the rows
            and the worst point.
        """
        problem = self.check.problem()
        if problem and not force:
            raise UnsafePathError(f"{os.fspath(path)} not written: {problem} (force=True writes it anyway)")
        feeds = self.feed_per_minute() if np.isfinite(self.feed).all() else None
        write_toolpath(path, self.points, axes=self.normals, feeds=feeds)


def grinding_paths(
    points: ArrayLike,
    normals: ArrayLike,
    allowance: ArrayLike,
    tool_radius: float,
    scallop_height: float,
    section_normal: ArrayLike,
    *,
    removal_model: RemovalModel | Mapping[str, object] | None = None,
    thickness: float | None = None,
    spacing: float | None = None,
    tolerance: float | None = None,
    fit_radius: float | None = None,
    feed_step: float = FEED_STEP,
    band: float = BAND,
) -> GrindingPaths:
    """Belt-grinding paths over an allowance cloud, rows spaced by the scallop height (SPEC P1–P5; paper 004 §2–3).

    Rows are sections of the surface by planes of normal ``section_normal``. Between two rows the surface's
    curvature across them sets the spacing: the widest that keeps the cusp at ``scallop_height``
    (:func:`step_over`), so rows close up on convex stretches and open out on concave ones. Curvature comes from how
    the given normals turn across the rows over ``fit_radius`` (the scale of a step, so scan noise does not turn into
    curvature; docs/grinding.md step 1). Each row's
    points are put in order by :func:`bead_chain`, resampled every ``spacing`` and put back on the surface within
    their plane — round an edge of a few point spacings' radius by a fit of the edge's cross-sections, which follows it
    between scan lines. Open rows alternate direction, closed rows (blade sections) run the same way. Where the wheel
    could not move straight from one path point to the next without cutting into the part (a plane that runs off the
    cloud round a thin edge, or grazes the surface), the row is cut there: its pieces are consecutive rows with the same
    offset. Rows are meant to cross the surface; planes that graze it (along a blade's span) leave it unground there.
    The feed at each point removes its allowance under ``removal_model``.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        The surface the allowance was measured on (e.g. the model points of a registered scan), mm.
    normals : array_like, shape (N, 3)
        Outward normals there, pointing to the tool side (need not be unit).
    allowance : array_like, shape (N,)
        Stock above the model at each point, mm; NaN where none was measured (as :func:`machscan.allowance` gives
        where the blank does not cover the model): those points are left out and counted in ``without_stock``.
    tool_radius : float
        Contact radius R of the wheel across the rows, mm.
    scallop_height : float
        Allowed cusp height between rows, mm (0 < h < R).
    section_normal : array_like, shape (3,)
        Normal of the section planes (e.g. the span axis of a blade).
    removal_model : RemovalModel or dict, optional
        The removal model; without one ``.feed`` is NaN and the APT file has no FEDRAT.
    thickness : float, optional
        Slab of cloud points that traces a row, mm; default twice the cloud's median point spacing, or 1.5 times
        the gap between its lines across the planes where that is more (a model sampled in sections, a line scan),
        so that every slab holds a line.
    spacing : float, optional
        Path point spacing along a row, mm; default the cloud's median point spacing.
    tolerance : float, optional
        Largest deviation of the tool centre (``tool_radius`` out along the normal) between two path points from
        the straight line joining them, mm; default a quarter of ``scallop_height``. Rows take extra points where
        the normal turns fast (round a blade's edges), so that a machine moving in straight lines does not cut
        the edge.
    fit_radius : float, optional
        Radius of the curvature fits, mm; default the flat step-over, at least four point spacings.
    feed_step : float
        A new feed is programmed where the feed that removes the allowance departs from the one in force by
        more than this share of it (default 0.03: at the paper's feed exponent −0.7 the removal then differs
        from the wanted by at most 2.1 %); 0 programs every change.
    band : float
        The band the simulated pass must end within, ±mm (paper 004: 0.08): the path's :attr:`GrindingPaths.check`
        is the pass over this cloud, and :meth:`GrindingPaths.to_apt` refuses a path that leaves the band.

    Returns
    -------
    GrindingPaths

    Examples
    --------
    >>> paths = machscan.grinding_paths(points, normals, allowance, tool_radius=10.0, scallop_height=0.01,
    ...                                 section_normal=(0, 0, 1), removal_model=model)
    >>> paths.to_apt("grind.cl")
    """
    model = None if removal_model is None else RemovalModel.of(removal_model)
    normal = np.asarray(section_normal, dtype=np.float64)
    out = _core.grinding_paths(
        points,
        normals,
        allowance,
        tool_radius=tool_radius,
        scallop_height=scallop_height,
        section_normal=normal,
        thickness=thickness,
        spacing=spacing,
        tolerance=tolerance,
        fit_radius=fit_radius,
        removal=None if model is None else model._args(),
        feed_step=feed_step,
    )
    depths = out["allowance"].copy() if model is None else model.removal(out["feed"])
    check = _removal_check(
        out["points"],
        out["normals"],
        out["allowance"],
        out["row"],
        depths,
        float(tool_radius),
        len(out["row_offsets"]),
        points,
        normals,
        allowance,
        band,
    )
    return GrindingPaths(
        **out,
        tool_radius=float(tool_radius),
        scallop_height=float(scallop_height),
        section_normal=normal / np.linalg.norm(normal),
        removal_model=model,
        check=check,
    )


@dataclass(frozen=True, eq=False)
class RemovalCheck:
    """Result of :func:`simulate_removal`.

    Attributes
    ----------
    deviation : ndarray, shape (N,)
        Stock left over the model at each blank point after the pass, mm (negative: ground below the model); NaN
        where the blank's allowance is NaN (no stock measured there).
    section : ndarray of int64, shape (N,)
        The row (section) each blank point belongs to: that of its nearest path point.
    minimum, maximum, mean : ndarray, shape (rows,)
        The deviation over each section's points with stock (NaN for a section with none).
    points : ndarray, shape (N, 3)
        The blank's model points the deviation is given at, mm.
    band : float
        The band the pass must end within, ±mm (:data:`BAND`).
    """

    deviation: NDArray[np.float64]
    section: NDArray[np.int64]
    minimum: NDArray[np.float64]
    maximum: NDArray[np.float64]
    mean: NDArray[np.float64]
    points: NDArray[np.float64] = field(repr=False)
    band: float = BAND

    @property
    def outside(self) -> NDArray[np.bool_]:
        """Points whose stock left is more than ``band`` off the model (NaN, no stock measured, is not)."""
        with np.errstate(invalid="ignore"):
            return np.abs(self.deviation) > self.band

    @property
    def within_band(self) -> bool:
        """Every point with stock ends within ±``band`` of the model."""
        return not bool(self.outside.any())

    def problem(self) -> str | None:
        """What leaves the band, in words (points, how far, rows, where), or None when every point is within it."""
        out = self.outside
        if not out.any():
            return None
        dev = self.deviation
        over = out & (dev < 0)
        under = out & (dev > 0)
        parts = []
        if over.any():
            parts.append(f"{int(over.sum()):,} points ground below the model by more than {self.band:g} mm (over-cut, "
                         f"down to {dev[over].min():+.4f} mm)")
        if under.any():
            parts.append(f"{int(under.sum()):,} points left with more than {self.band:g} mm of stock (up to "
                         f"{dev[under].max():+.4f} mm)")
        rows = np.unique(self.section[out])
        shown = ", ".join(str(r) for r in rows[:12]) + (f" … ({len(rows)} rows)" if len(rows) > 12 else "")
        worst = int(np.nanargmax(np.where(out, np.abs(dev), -np.inf)))
        x, y, z = self.points[worst]
        return (
            f"the simulated pass leaves {' and '.join(parts)}; rows {shown}; the worst at ({x:.3f}, {y:.3f}, {z:.3f}) mm "
            f"(point {worst}, row {int(self.section[worst])})"
        )

    def __repr__(self) -> str:
        outside = int(self.outside.sum())
        return (
            f"RemovalCheck({len(self.deviation)} points in {len(self.mean)} sections, deviation "
            f"{np.nanmin(self.minimum):+.4f} … {np.nanmax(self.maximum):+.4f} mm, {outside} outside ±{self.band:g} mm)"
        )


def simulate_removal(
    paths: GrindingPaths, points: ArrayLike, normals: ArrayLike, allowance: ArrayLike, *, band: float = BAND
) -> RemovalCheck:
    """Sweep the contact wheel along a grinding path over the blank and report the stock left over the model
    (SPEC P5 beyond; paper 004 measures ground sections within ±0.08 mm).

    The wheel is a sphere of the path's tool radius at every path point, its lowest point sunk below the blank
    (model + allowance) by the depth the point's feed removes (:meth:`GrindingPaths.removal`); every blank point
    keeps the lower of its stock and the depth any wheel position reaches along its normal. What remains is the
    scallop between rows, plus whatever the feed limits kept the model from removing.

    Parameters
    ----------
    paths : GrindingPaths
    points, normals, allowance : array_like
        The blank as model points, their outward normals and the stock above them (e.g. the cloud the path was
        made from, or a denser one); an allowance of NaN (no stock measured) gives a deviation of NaN.
    band : float
        The band the pass must end within, ±mm (paper 004: 0.08); ``.outside`` and ``.problem()`` use it.

    Returns
    -------
    RemovalCheck

    Examples
    --------
    >>> check = machscan.simulate_removal(paths, cloud.points, cloud.normals, cloud.allowance)
    >>> bool((np.abs(check.deviation) <= 0.08).all())   # the paper's band for ground sections
    True
    """
    return _removal_check(
        paths.points,
        paths.normals,
        paths.allowance,
        paths.row,
        paths.removal(),
        paths.tool_radius,
        len(paths.row_offsets),
        points,
        normals,
        allowance,
        band,
    )


def _removal_check(
    path_points, path_normals, path_allowance, row, depths, tool_radius, rows, points, normals, allowance, band
) -> RemovalCheck:
    if not (np.isfinite(band) and band > 0):
        raise ValueError(f"band: must be a positive number of mm, got {band!r}")
    out = _core.simulate_removal(
        points, normals, allowance, path_points, path_normals, path_allowance, row, depths, tool_radius=tool_radius
    )
    section = row[out["nearest"]]
    dev = out["deviation"]
    measured = ~np.isnan(dev)
    count = np.bincount(section[measured], minlength=rows)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.bincount(section[measured], weights=dev[measured], minlength=rows) / count
    minimum = np.full(rows, np.inf)
    maximum = np.full(rows, -np.inf)
    np.minimum.at(minimum, section[measured], dev[measured])
    np.maximum.at(maximum, section[measured], dev[measured])
    empty = count == 0
    minimum[empty] = maximum[empty] = np.nan
    return RemovalCheck(
        deviation=dev,
        section=section,
        minimum=minimum,
        maximum=maximum,
        mean=mean,
        points=np.asarray(points, dtype=np.float64),
        band=float(band),
    )
