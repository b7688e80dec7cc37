"""Surface meshes (SPEC S1–S3; paper 002 §3): the triangulated theoretical and scanned surfaces
that mirror-milling compensation works on. :func:`delaunay_xy` meshes a height-field surface by
the Delaunay triangulation of its xy projection; :func:`closest_points` finds the nearest point
of a mesh to each query."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan._core import delaunay_xy

__all__ = ["ClosestPoints", "closest_points", "delaunay_xy"]


@dataclass(frozen=True, eq=False)
class ClosestPoints:
    """Result of :func:`closest_points`, one row per query.

    Attributes
    ----------
    points : ndarray, shape (N, 3)
        The closest point of the mesh, mm.
    distances : ndarray, shape (N,)
        Its distance from the query, mm.
    triangles : ndarray of int64, shape (N,)
        The triangle it lies on (the lowest index where two are equally close, on their shared
        edge or vertex).
    barycentric : ndarray, shape (N, 3)
        Its weights on that triangle's three vertices (each in [0, 1], sum 1).
    """

    points: NDArray[np.float64]
    distances: NDArray[np.float64]
    triangles: NDArray[np.int64]
    barycentric: NDArray[np.float64]


def closest_points(vertices: ArrayLike, faces: ArrayLike, queries: ArrayLike) -> ClosestPoints:
    """The closest point of a triangle mesh to each query (SPEC S2): how a tool point is carried
    onto a scanned surface, or how far a point is from a model. A bounding-volume hierarchy over
    the triangles is built once per call and searched in parallel (GIL released); the results
    equal ``trimesh.proximity.closest_point``'s and do not depend on the thread count.

    Parameters
    ----------
    vertices : array_like, shape (V, 3)
        mm.
    faces : array_like of int, shape (M, 3)
        Vertex indices of the triangles, e.g. from :func:`delaunay_xy`.
    queries : array_like, shape (N, 3)

    Returns
    -------
    ClosestPoints
        ``.points``, ``.distances``, ``.triangles``, ``.barycentric``.

    Examples
    --------
    >>> faces = machscan.delaunay_xy(scan)
    >>> on = machscan.closest_points(scan, faces, tool_points)
    >>> on.points, on.distances
    """
    out = _core.closest_points(vertices, faces, queries)
    return ClosestPoints(out["points"], out["distances"], out["triangles"], out["barycentric"])
