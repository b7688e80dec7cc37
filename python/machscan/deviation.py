"""Deviation from the CAD model: the signed distance of every measured point to the model's
mesh, and its statistics per CAD face — the figures an inspection report is built on (what
PolyWorks, ZEISS Inspect and Geomagic Control X call a deviation map and a face report).

:func:`signed_distances` measures; :meth:`SignedDistances.statistics` tabulates per face;
:func:`machscan.fit_to_mesh` finds the best-fit pose first; :func:`machscan.plot.deviation_map`
draws it; ``machscan compare`` does all of it from files. The formulas: ``docs/deviation.md``.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core

__all__ = ["FaceStatistics", "SignedDistances", "Tolerance", "signed_distances", "tolerance_band"]

#: A tolerance: ``t`` for the band ``[-t, +t]``, or ``(lower, upper)``, mm.
Tolerance = float | tuple[float, float]


def tolerance_band(tolerance: Tolerance) -> tuple[float, float]:
    """``(lower, upper)`` of a tolerance given as ``t`` (``±t``) or as the pair, mm; checked."""
    if isinstance(tolerance, tuple | list):
        if len(tolerance) != 2:
            raise ValueError(f"tolerance: expected t or (lower, upper), got {len(tolerance)} values")
        lower, upper = (float(v) for v in tolerance)
    else:
        t = float(tolerance)
        if not t >= 0:
            raise ValueError(f"tolerance: a symmetric tolerance must be >= 0 mm, got {t}")
        lower, upper = -t, t
    if not (np.isfinite(lower) and np.isfinite(upper) and lower <= upper):
        raise ValueError(f"tolerance: needs finite lower <= upper, got ({lower}, {upper})")
    return lower, upper


@dataclass(frozen=True, eq=False)
class FaceStatistics:
    """Signed distances per CAD face (one row per face some point lands on, in face order), mm.

    Attributes
    ----------
    face : ndarray of int64
        The CAD face (0 for every point of a mesh without CAD faces: the whole mesh).
    count : ndarray of int64
        Points landing on it.
    min, max, mean, std : ndarray
        Of their signed distances, mm (std with n − 1; 0 for one point).
    out_of_tolerance : ndarray
        Share of them outside ``[lower, upper]``, 0–1.
    lower, upper : float
        The tolerance band, mm.
    """

    face: NDArray[np.int64]
    count: NDArray[np.int64]
    min: NDArray[np.float64]
    max: NDArray[np.float64]
    mean: NDArray[np.float64]
    std: NDArray[np.float64]
    out_of_tolerance: NDArray[np.float64]
    lower: float
    upper: float

    def __len__(self) -> int:
        return len(self.face)

    def to_csv(self, path: str | os.PathLike[str]) -> None:
        """One row per face; the header names each column's unit."""
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(
                [
                    "face",
                    "points",
                    "min_mm",
                    "max_mm",
                    "mean_mm",
                    "std_mm",
                    f"out_of_tolerance_percent[{self.lower:g};{self.upper:g} mm]",
                ]
            )
            for i in range(len(self)):
                w.writerow(
                    [
                        int(self.face[i]),
                        int(self.count[i]),
                        f"{self.min[i]:.6f}",
                        f"{self.max[i]:.6f}",
                        f"{self.mean[i]:.6f}",
                        f"{self.std[i]:.6f}",
                        f"{100 * self.out_of_tolerance[i]:.3f}",
                    ]
                )


@dataclass(frozen=True, eq=False)
class SignedDistances:
    """Result of :func:`signed_distances`, one row per measured point.

    Attributes
    ----------
    distances : ndarray, shape (N,)
        Signed distance to the mesh, mm: + outside the material, − inside.
    points : ndarray, shape (N, 3)
        The closest point of the mesh, mm.
    triangles : ndarray of int64, shape (N,)
        Its triangle (the lowest index where two are equally close).
    cad_faces : ndarray of int64, shape (N,), or None
        The CAD face of that triangle, when the mesh came with them (:func:`machscan.io.read_cad`).
    """

    distances: NDArray[np.float64]
    points: NDArray[np.float64]
    triangles: NDArray[np.int64]
    cad_faces: NDArray[np.int64] | None

    def out_of_tolerance(self, tolerance: Tolerance) -> NDArray[np.bool_]:
        """The points whose signed distance is outside the band (``t`` for ±t, or ``(lower, upper)``, mm)."""
        lower, upper = tolerance_band(tolerance)
        return (self.distances < lower) | (self.distances > upper)

    def statistics(self, tolerance: Tolerance) -> FaceStatistics:
        """Min, max, mean, std and the share out of tolerance per CAD face (the whole mesh as
        face 0 when it has no CAD faces); computed in the core, in point order."""
        lower, upper = tolerance_band(tolerance)
        if self.cad_faces is None:
            faces = np.zeros(len(self.distances), dtype=np.int64)
        else:
            faces = self.cad_faces
        count = int(faces.max()) + 1 if len(faces) else 0
        s = _core.face_statistics(self.distances, faces, count=count, lower=lower, upper=upper)
        return FaceStatistics(**s, lower=lower, upper=upper)


def signed_distances(
    points: ArrayLike,
    vertices: ArrayLike,
    triangles: ArrayLike,
    *,
    cad_faces: ArrayLike | None = None,
) -> SignedDistances:
    """The signed distance of every measured point to a triangle mesh (the CAD model).

    The distance is to the closest point of the triangles (exact, float64); the sign is that of
    the offset along the angle-weighted pseudo-normal of the feature — face, edge or corner — the
    closest point lies on (Bærentzen & Aanæs 2005): + outside, − inside. That sign needs no
    closed mesh: it is right wherever the closest feature's triangles are wound consistently,
    so an open CAD patch or a mesh with holes elsewhere still signs the points near it. The
    search is a bounding-volume hierarchy, queries in Morton order, in parallel with the GIL
    released; results do not depend on the thread count.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Measured points, in the model's frame (e.g. after :func:`machscan.fit_to_mesh`), mm.
    vertices : array_like, shape (V, 3)
        mm.
    triangles : array_like of int, shape (M, 3)
        Vertex indices, counter-clockwise seen from outside the material.
    cad_faces : array_like of int, shape (M,), optional
        The CAD face of each triangle (``CadMesh.cad_faces``), carried to every point.

    Returns
    -------
    SignedDistances
        ``.distances``, ``.points``, ``.triangles``, ``.cad_faces``; ``.statistics(tol)`` per face.

    Raises
    ------
    ValueError
        Points or vertices not finite; a triangle naming a missing vertex; triangles whose
        winding disagrees across a shared edge, or a closed mesh wound inside out (the sign
        would be meaningless: it is refused, naming ``triangles``).

    Examples
    --------
    >>> cad = machscan.io.read_cad("blade.step")
    >>> d = machscan.signed_distances(scan, cad.vertices, cad.triangles, cad_faces=cad.cad_faces)
    >>> d.statistics(0.05).out_of_tolerance  # share per CAD face outside ±0.05 mm
    """
    out = _core.signed_distances(points, vertices, triangles)
    faces = None
    if cad_faces is not None:
        per_triangle = np.asarray(cad_faces)
        m = len(np.asarray(triangles))
        if per_triangle.shape != (m,) or per_triangle.dtype.kind not in "iu":
            raise ValueError(
                f"cad_faces: expected integers of shape ({m},), one per triangle, "
                f"got {per_triangle.dtype} of shape {per_triangle.shape}"
            )
        if m and per_triangle.min() < 0:
            raise ValueError(f"cad_faces: must be >= 0, found {per_triangle.min()}")
        faces = per_triangle.astype(np.int64)[out["triangles"]]
    return SignedDistances(
        distances=out["distances"], points=out["points"], triangles=out["triangles"], cad_faces=faces
    )
