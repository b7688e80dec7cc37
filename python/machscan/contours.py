"""Contours (SPEC C, paper 000 §2.2): CAD polylines resampled, actual contours matched to
theoretical ones, and the contour error (eq 21–23) as a result object.

Contours are segmented from a cloud of groove centers by :func:`machscan.euclidean_clusters`
(re-exported here).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan._core import euclidean_clusters, match_contours, resample_polyline

__all__ = ["ContourErrorResult", "contour_error", "euclidean_clusters", "match_contours", "resample_polyline"]


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
    """

    offset: NDArray[np.float64]
    errors: NDArray[np.float64]
    deviations: NDArray[np.float64]
    matched: NDArray[np.int64]
    cases: NDArray[np.uint8]
    mean: float
    std: float
    max: float

    def __repr__(self) -> str:
        return (
            f"ContourErrorResult({len(self.errors)} points: {self.mean:.4f} ± {self.std:.4f} mm, "
            f"max {self.max:.4f} mm, |E| = {np.linalg.norm(self.offset):.4f} mm)"
        )


def contour_error(theoretical: ArrayLike, actual: ArrayLike, delta1: float = 1.0, delta2: float = 1.0) -> ContourErrorResult:
    """Contour error of one contour (SPEC C3–C5, paper 000 eq 21–23).

    The actual points are first moved by the offset E = mean(P) − mean(Q). Each theoretical
    point P_i is paired with its nearest compensated actual point; where actual points have
    P_i as *their* nearest theoretical point, the farthest of them competes and the farther of
    the two is kept (eq 22), so a point straying from a corner counts with its real deviation.

    Parameters
    ----------
    theoretical : array_like, shape (a, 3)
        CAD contour points P, mm (e.g. from :func:`resample_polyline`).
    actual : array_like, shape (b, 3)
        Measured groove centers Q of the same contour, mm.
    delta1, delta2 : float
        Weights of the offset and of the compensated deviation (paper: 1 and 1).

    Returns
    -------
    ContourErrorResult
        ``.offset`` (E), ``.errors`` (e_i), ``.mean``, ``.std``, ``.max``, ...

    Examples
    --------
    >>> r = machscan.contour_error(cad_points, groove_centers)
    >>> r.mean, r.max
    """
    return ContourErrorResult(**_core.contour_error(theoretical, actual, delta1=delta1, delta2=delta2))
