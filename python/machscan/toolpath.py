"""Toolpaths: compensation for mirror milling, and the row spacing of grinding paths.

Toolpath compensation for mirror milling (SPEC S5; paper 002 §4): the toolpath programmed on the theoretical
skin, carried onto the skin as it lies bent on the machine, so that pockets and wall thickness land where the
design wants them.

:func:`compensate_toolpath` takes the matching pairs (theoretical points and where :func:`machscan.isometric_match`
found them) and the scan. Each tool point is split into its foot on the theoretical surface and its offset
along the theoretical normal (0 for a contact point, −h for a pocket floor h deep); the foot is mapped onto the
actual surface and the offset put back along the actual normal; a tool axis turns with the normal.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan.io import Toolpath
from machscan.mesh import _surface

__all__ = [
    "BeadChain",
    "ChainMethod",
    "CompensatedToolpath",
    "Interpolation",
    "SurfaceNormals",
    "bead_chain",
    "compensate_toolpath",
    "scallop_height",
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
    offsets : ndarray, shape (M,)
        Each tool point's offset from the theoretical surface along its normal, mm (negative below it).
    """

    points: NDArray[np.float64]
    axes: NDArray[np.float64]
    inside: NDArray[np.bool_]
    offsets: NDArray[np.float64]

    def __repr__(self) -> str:
        out = int((~self.inside).sum())
        return f"CompensatedToolpath({len(self.points)} points, {out} outside the matching hull)"


def compensate_toolpath(
    tool_points: ArrayLike | Toolpath,
    theoretical_matching: ArrayLike,
    actual_matching: ArrayLike,
    actual_surface: ArrayLike | tuple[ArrayLike, ArrayLike],
    *,
    interpolation: Interpolation = "cubic",
    normals: SurfaceNormals = "smooth",
    radius: float | None = None,
    max_edge: float | None = None,
) -> CompensatedToolpath:
    """Carry a toolpath from the theoretical skin onto the scanned one (SPEC S5–S6; paper 002 §4).

    Parameters
    ----------
    tool_points : array_like, shape (M, 3) or (M, 6), or :class:`machscan.io.Toolpath`
        Tool points on or off the theoretical surface, mm, with unit tool axes in columns 3–5 if given (a
        Toolpath's axes are used when it has them all).
    theoretical_matching, actual_matching : array_like, shape (n, 3)
        The matching pairs: theoretical points (n ≥ 6, not all on one line or conic in xy) and their actual
        places, e.g. :func:`machscan.isometric_match`'s ``.points``.
    actual_surface : array_like (N, 3), or (vertices, faces)
        The scan of the clamped part (meshed by :func:`machscan.delaunay_xy`), or its mesh.
    interpolation : {"cubic", "linear"}
        See :data:`Interpolation`.
    normals : {"smooth", "triangle"}
        See :data:`SurfaceNormals`.
    radius : float, optional
        Radius of the scan patch of the smooth surface, mm; by default 5 median edge lengths of the scan mesh.
    max_edge : float, optional
        Long-edge trim when meshing a point scan, mm.

    Returns
    -------
    CompensatedToolpath
        ``.points``, ``.axes``, ``.inside``, ``.offsets``.

    Examples
    --------
    >>> match = machscan.isometric_match(theoretical, scan, r, r_measured, grid)
    >>> path = machscan.compensate_toolpath(tool_points, grid, match.points, scan)
    >>> machscan.io.write_toolpath("compensated.cl", path.points, axes=path.axes)
    """
    if isinstance(tool_points, Toolpath):
        axes = tool_points.axes
        tool_points = np.hstack([tool_points.points, axes]) if np.isfinite(axes).all() else tool_points.points
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
    start: ArrayLike | None = None,
    direction: ArrayLike | None = None,
    *,
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
