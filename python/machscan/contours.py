"""Contours (SPEC C, paper 000 §2.2): CAD polylines resampled, actual contours matched to
theoretical ones, and the contour error (eq 21–23) as a result object.

Contours are segmented from a cloud of groove centers by :func:`machscan.euclidean_clusters`
(re-exported here).

The formulas and their papers: ``docs/contours.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan._core import euclidean_clusters, match_contours, resample_polyline

__all__ = [
    "ACTUAL_SPACING",
    "CAD_SPACING",
    "ContourErrorResult",
    "contour_error",
    "euclidean_clusters",
    "join_centers",
    "match_contours",
    "resample_cad",
    "resample_polyline",
]


@dataclass(frozen=True, eq=False, repr=False)
class ContourErrorResult:
    """Error of one actual (engraved) contour against its theoretical (CAD) contour.

    Attributes
    ----------
    offset : ndarray (3,)
        E = mean(P) − mean(Q): theoretical minus actual centroid, mm (eq 21).
    errors : ndarray (a,)
        e_i = δ1·|E| + δ2·|P_i − Q'_match| for every theoretical point, mm (eq 23).
    deviations : ndarray (a,)
        |P_i − Q'_match|, the error left after offset compensation, mm.
    matched : ndarray of int64 (a,)
        Index of the actual point matched to each theoretical point.
    cases : ndarray of uint8 (a,)
        Rule of eq (22) that chose the match: 1 nearest actual point (no actual point has P_i
        as its nearest); 2 nearest kept, it is the farther; 3 the farthest actual point having
        P_i as its nearest was taken (a point straying from a corner).
    mean, std, max : float
        Statistics of ``errors``, mm (paper 000 table 2).
    theoretical, actual : ndarray (a, 3), (b, 3)
        The points the errors were measured between: the theoretical contour and the actual points as resampled
        (see :func:`contour_error`), mm.
    """

    offset: NDArray[np.float64]
    errors: NDArray[np.float64]
    deviations: NDArray[np.float64]
    matched: NDArray[np.int64]
    cases: NDArray[np.uint8]
    mean: float
    std: float
    max: float
    theoretical: NDArray[np.float64]
    actual: NDArray[np.float64]

    def __repr__(self) -> str:
        return (
            f"ContourErrorResult({len(self.errors)} points: {self.mean:.4f} ± {self.std:.4f} mm, "
            f"max {self.max:.4f} mm, |E| = {np.linalg.norm(self.offset):.4f} mm)"
        )


#: Spacing the CAD contour is resampled at before the contour error, mm (paper 000's CAD points lie microns apart).
CAD_SPACING: float = 0.005
#: Spacing the measured centers are joined and resampled at before the contour error, mm.
ACTUAL_SPACING: float = 0.002


def contour_error(
    theoretical: ArrayLike,
    actual: ArrayLike,
    *,
    delta1: float = 1.0,
    delta2: float = 1.0,
    cad_spacing: float | None = CAD_SPACING,
    actual_spacing: float | None = ACTUAL_SPACING,
) -> ContourErrorResult:
    """Contour error of one contour (SPEC C3–C5, paper 000 eq 21–23), as :func:`machscan.inspect_grooves` measures it.

    The paper's points lie microns apart on both contours; a CAD polyline's vertices and a decimated scan's groove
    centers do not, and nearest-point distances between sparse points measure the gaps between them, not the
    deviation. So first, as the inspection does:

    - the theoretical contour, a closed polyline, is resampled every ``cad_spacing`` where any of its segments is
      longer (a contour already that dense is used as it is);
    - the actual points, in scan order, are joined into a polyline and resampled every ``actual_spacing``; gaps
      longer than 5× the median step (a stretch the scan skipped) are not bridged, and the polyline closes when its
      ends meet (:func:`join_centers`).

    The errors: the actual points are moved by the offset E = mean(P) − mean(Q). Each theoretical point P_i is
    paired with its nearest compensated actual point; where actual points have P_i as *their* nearest theoretical
    point, the farthest of them competes and the farther of the two is kept (eq 22), so a point straying from a
    corner counts with its real deviation. The nearest-point matching adds up to about half of the coarser spacing
    (the defaults, 5 µm and 2 µm, add about 1 µm).

    Parameters
    ----------
    theoretical : array_like, shape (a, 3)
        CAD contour P, mm: a closed polyline (its vertices), or its points.
    actual : array_like, shape (b, 3)
        Measured groove centers Q of the same contour, in scan order, mm (``report.center_wcs[report.contour == k]``).
    delta1, delta2 : float
        Weights of the offset and of the compensated deviation (paper: 1 and 1).
    cad_spacing, actual_spacing : float or None
        Resampling of the two contours, mm (above); None uses the points as given (the paper's eq 21–23 on bare
        points).

    Returns
    -------
    ContourErrorResult
        ``.offset`` (E), ``.errors`` (e_i, one per theoretical point used: ``.theoretical``), ``.mean``, ``.std``,
        ``.max``, and ``.actual``, the points the errors were measured against.

    Examples
    --------
    >>> c = report.contours[0]
    >>> r = machscan.contour_error(c.theoretical, report.center_wcs[report.contour == c.cad_index])  # == c.error
    >>> r.mean, r.max
    """
    p = _points(theoretical, "theoretical")
    q = _points(actual, "actual")
    if cad_spacing is not None:
        p = resample_cad(p, spacing=cad_spacing)
    if actual_spacing is not None:
        _check_spacing(actual_spacing, "actual_spacing")
        q = join_centers(q, spacing=actual_spacing)
    return ContourErrorResult(**_core.contour_error(p, q, delta1=delta1, delta2=delta2), theoretical=p, actual=q)


def resample_cad(polyline: ArrayLike, *, spacing: float = CAD_SPACING) -> NDArray[np.float64]:
    """A closed CAD contour as the contour error measures it: resampled every ``spacing`` mm at equal arc-length
    steps where any of its segments is longer, as it is where it is already that dense (so resampling twice
    changes nothing). :func:`machscan.inspect_grooves` and :func:`contour_error` both use it.

    Examples
    --------
    >>> p = machscan.contours.resample_cad(cad_polyline)
    """
    p = _points(polyline, "polyline")
    _check_spacing(spacing, "spacing")
    if len(p) >= 3 and _longest_step(p, closed=True) > spacing * (1 + 1e-9):
        return resample_polyline(p, spacing, closed=True)
    return p


def join_centers(centers: ArrayLike, *, spacing: float = ACTUAL_SPACING) -> NDArray[np.float64]:
    """Groove centers of one contour, in scan order, joined into a polyline and resampled every ``spacing`` mm.

    Frames lie far apart next to the CAD points (0.4 mm at a typical decimation). Gaps longer than 5× the median
    step (a skipped stretch) are not bridged, and the contour is closed when its ends meet. Centers already that
    dense are returned as they are.

    Examples
    --------
    >>> dense = machscan.contours.join_centers(report.center_wcs[report.contour == 0])
    """
    q = _points(centers, "centers")
    _check_spacing(spacing, "spacing")
    if len(q) < 2:
        return q.copy()
    steps = np.linalg.norm(np.diff(q, axis=0), axis=1)
    if steps.max() <= spacing * (1 + 1e-9):
        return q.copy()
    limit = 5.0 * float(np.median(steps))
    close = np.linalg.norm(q[-1] - q[0]) <= limit
    pts = np.vstack([q, q[:1]]) if close else q
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    # Split at unbridged gaps; each piece is resampled at equal arc-length steps.
    cuts = np.nonzero(seg > limit)[0]
    if len(cuts) == 0 and close and len(q) >= 3:
        return resample_polyline(q, spacing, closed=True)
    out = []
    start = 0
    for end in [int(c) for c in cuts] + [len(pts) - 1]:
        piece = pts[start : end + 1]
        out.append(piece if len(piece) == 1 else resample_polyline(piece, spacing, closed=False))
        start = end + 1
    return np.vstack(out)


def _points(value: ArrayLike, name: str) -> NDArray[np.float64]:
    a = np.asarray(value, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name}: expected points of shape (n, 3), got {a.shape}")
    if len(a) == 0:
        raise ValueError(f"{name}: expected at least one point, got none")
    if not np.isfinite(a).all():
        raise ValueError(f"{name}: must be finite, found {int((~np.isfinite(a).all(axis=1)).sum())} rows with NaN or inf")
    return a


def _check_spacing(value: float, name: str) -> None:
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{name}: must be a positive number of mm or None, got {value!r}")


def _longest_step(p: NDArray[np.float64], closed: bool) -> float:
    pts = np.vstack([p, p[:1]]) if closed else p
    return float(np.linalg.norm(np.diff(pts, axis=0), axis=1).max())
