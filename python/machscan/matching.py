"""Isometric matching (SPEC S4; paper 002 §3.3): where each theoretical matching point of a thin skin went
on the scanned, bent skin, from geodesic distances that bending keeps.

A skin clamped on a mirror-milling machine bends without stretching, so the geodesic distance along it
between any two of its points stays what the design says. :func:`isometric_match` moves the actual matching
points over the scanned surface until their geodesic distances to two locating points and to one another equal
the theoretical ones (the paper's Levenberg–Marquardt, eq 10–16). :func:`machscan.compensate_toolpath` then
carries the toolpath along.

The assumption is the method's limit: where the skin stretches (a doubly curved part pressed onto a fixture,
heat), geodesic distances change and the matched points are off by about the stretch.

The formulas and their papers: ``docs/matching.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan.mesh import GeodesicMethod, _surface

__all__ = ["MATCH_JACOBIAN", "MATCH_METHOD", "MATCH_SPACING", "IsometricMatch", "Jacobian", "MatchStop", "isometric_match"]

#: The Jacobian of the distances: ``"quadratic"``, the paper's (eq 12–13: a quadratic of x, y fitted to a
#: point's distances to all matching points, differentiated); ``"gradient"``, the gradient of the point's
#: distance field at each matching point (SPEC S4 Beyond).
Jacobian = Literal["quadratic", "gradient"]

#: Why the iterations stopped: ``"tolerance"`` (E ≤ tolerance), ``"step"`` (the last step moved no point by
#: more than a hundredth of the tolerance), ``"stalled"`` (T stopped falling: by less than 0.1 % in each of two
#: steps, or not at all; the scan's noise floor), ``"max_iterations"``.
MatchStop = Literal["tolerance", "step", "stalled", "max_iterations"]


@dataclass(frozen=True, eq=False)
class IsometricMatch:
    """Result of :func:`isometric_match`.

    Attributes
    ----------
    points : ndarray, shape (n, 3)
        The matched actual points, on the actual surface, mm; row i belongs to theoretical matching point i.
    locating : ndarray, shape (2, 3)
        The actual locating points, put on the actual surface.
    objective : ndarray, shape (iterations + 1,)
        T = ‖V₂ − V₁‖ (eq 14) at the start, then after each iteration (unchanged after a rejected step), mm.
    max_error : ndarray, shape (iterations + 1,)
        E = max |V₂ − V₁| (eq 15), mm.
    residuals : ndarray, shape (2n + n(n−1)/2,)
        The final V₂ − V₁, mm: d(r₁, pⱼ), d(r₂, pⱼ), then d(pᵢ, pⱼ) for i < j.
    iterations : int
    stop : str
        See :data:`MatchStop`.
    converged : bool
        False only when the iteration limit stopped it. True also when T stopped falling (``"stalled"``), which is
        where a noisy scan ends, but also where a method too coarse for the job ends: check ``max_error[-1]``
        against what the match must reach (``machscan compensate`` warns and exits 3 above ``--max-error``).
    """

    points: NDArray[np.float64]
    locating: NDArray[np.float64]
    objective: NDArray[np.float64]
    max_error: NDArray[np.float64]
    residuals: NDArray[np.float64]
    iterations: int
    stop: MatchStop
    converged: bool

    def __repr__(self) -> str:
        return (
            f"IsometricMatch({len(self.points)} points, T {self.objective[-1]:.4g} mm, "
            f"E {self.max_error[-1]:.4g} mm, {self.iterations} iterations, stop {self.stop!r})"
        )


#: Defaults of :func:`isometric_match`, which its signature and ``machscan compensate`` read.
MATCH_JACOBIAN: Jacobian = "quadratic"
MATCH_METHOD: GeodesicMethod = "exact"
MATCH_SPACING: float | Literal["auto"] | None = "auto"


def isometric_match(
    theoretical_points: ArrayLike | tuple[ArrayLike, ArrayLike],
    actual_points: ArrayLike | tuple[ArrayLike, ArrayLike],
    theoretical_locating: ArrayLike,
    actual_locating: ArrayLike,
    theoretical_matching: ArrayLike,
    actual_initial: ArrayLike | None = None,
    *,
    jacobian: Jacobian = MATCH_JACOBIAN,
    method: GeodesicMethod = MATCH_METHOD,
    spacing: float | Literal["auto"] | None = MATCH_SPACING,
    max_edge: float | None = None,
    max_iterations: int = 50,
    tolerance: float = 1e-3,
) -> IsometricMatch:
    """Match theoretical points onto the scanned, bent surface by their geodesic distances (SPEC S4; paper
    002 §3.3, eq 10–16).

    Both surfaces are meshed (points by :func:`machscan.delaunay_xy`, thinned as ``spacing`` says; a
    ``(vertices, faces)`` pair or a :class:`machscan.io.TriangleMesh` as given) and the locating and matching
    points inserted as vertices (:func:`machscan.insert_points`). V₁ holds the theoretical geodesic distances
    from each matching point pᵢ to r₁, r₂ and to every other pⱼ (``2n + n(n−1)/2`` of them); V₂ the same on
    the actual surface. Each iteration solves ``(JᵀJ + u·I) δ = −Jᵀ(V₂ − V₁)`` for the x, y moves of the
    actual matching points, puts them back on the actual surface at their new x, y (the surfaces are height
    fields over xy), and keeps the step when T fell (u ÷ 5, else u × 5; u starts at 0.001).

    Parameters
    ----------
    theoretical_points, actual_points : array_like (N, 3), or (vertices, faces)
        The theoretical surface (e.g. sampled from CAD) and the scan of the clamped part, mm.
    theoretical_locating, actual_locating : array_like, shape (2, 3)
        r₁, r₂ on the theoretical surface and as measured on the machine; apart in x, y.
    theoretical_matching : array_like, shape (n, 3)
        p₁ … pₙ, e.g. a grid over the part (n ≥ 7 for the quadratic Jacobian, ≥ 3 otherwise). The quadratic
        Jacobian fits a quadratic in x, y to the points other than each one, so those must not lie on one line
        or conic (a ValueError says so; the gradient Jacobian has no such need).
    actual_initial : array_like, shape (n, 3), optional
        Where the actual matching points start (their x, y); by default the theoretical ones moved by the x, y
        rigid motion that takes r₁, r₂ to r′₁, r′₂ (a point that this puts outside the actual surface's xy
        outline, as on a strongly bent part, starts just inside the nearest triangle).
    jacobian : {"quadratic", "gradient"}
        See :data:`Jacobian`. Both end at the same points; the gradient needs fewer iterations.
    method : {"exact", "fmm", "heat"}
        How geodesic distances are measured (:func:`machscan.geodesic_distances`). The approximate methods'
        ~0.2–0.5 % is a millimetre over a 300 mm skin: matching needs the exact one.
    spacing : float, "auto" or None
        How finely surfaces given as points are meshed for the geodesics: about one vertex per ``spacing`` ×
        ``spacing`` mm of the xy plane, the points' outline kept (each boundary loop to ``spacing / 20``, so
        locating points near the edge stay on the mesh); ``"auto"`` thins to about 2,000 vertices when the
        points are denser; ``None`` meshes every point. Exact geodesics cost far more than linearly in the
        vertices, and the distances matched run tens of millimetres over radii of hundreds: on the 300 × 200 mm
        skin (R 1000 mm, 1.3 mm scan, 5 µm noise) the default matches to a few µm in seconds where every
        point takes minutes. Give a smaller spacing for strongly curved parts: a chord of a triangle of side h
        on a radius R shortens a path by a relative (h/R)²/24. :func:`machscan.compensate_toolpath` uses the
        full scan either way.
    max_edge : float, optional
        Long-edge trim when meshing point surfaces, mm: every triangle with a longer edge is left out
        (:func:`machscan.delaunay_xy`). By default only triangles with an outline edge beyond 4 × the median edge
        are peeled off, from the outline inwards: the long triangles Delaunay adds across an inward-bowing
        stretch of the outline (the edge of a bent, tilted part bows by tens of µm in xy) are shortcuts for
        geodesics between points near the edge, while a gap inside the scan (a clamp's shadow) stays bridged, as
        the part is there. ``float("inf")`` keeps every triangle. A thinned surface's triangles are those over
        this mesh, so a concave outline stays concave.
    max_iterations : int
        Each try of a step counts, accepted or not.
    tolerance : float
        Stop when E ≤ tolerance, mm.

    Returns
    -------
    IsometricMatch
        ``.points``, ``.objective`` and ``.max_error`` per iteration, ``.iterations``, ``.stop``.

    Raises
    ------
    ValueError
        An argument of the wrong shape, not finite, an ``actual_initial`` point outside the actual surface's xy
        outline, a locating or matching point farther from its surface than two median edges of the surface as given
        (at least 1 mm: a wrong point, its units, a typo), points the surface does not join, a bad option.

    Examples
    --------
    >>> skin = machscan.synth.BentSkin()
    >>> match = machscan.isometric_match(skin.grid(2.0), skin.scan(), skin.locating(),
    ...                                  skin.actual(skin.locating())[0], skin.matching_grid())
    >>> match.points  # where the 8 × 8 theoretical matching points went
    """
    tp, tf = _surface(theoretical_points, "theoretical_points")
    ap, af = _surface(actual_points, "actual_points")
    out = _core.isometric_match(
        tp,
        tf,
        ap,
        af,
        theoretical_locating,
        actual_locating,
        theoretical_matching,
        actual_initial,
        jacobian=jacobian,
        method=method,
        spacing=spacing,
        max_edge=max_edge,
        max_iterations=max_iterations,
        tolerance=tolerance,
    )
    return IsometricMatch(**out)
