"""Surface meshes (SPEC S1–S3; paper 002 §3): the triangulated theoretical and scanned surfaces
that mirror-milling compensation works on. :func:`delaunay_xy` meshes a height-field surface by
the Delaunay triangulation of its xy projection; :func:`closest_points` finds the nearest point
of a mesh to each query; :func:`insert_points` makes points of the surface vertices of its mesh;
:func:`geodesic_distances` measures along the surface, and :class:`GeodesicSolver` does so again and again on
one mesh prepared once; :func:`sample_surface` spreads points with normals evenly over a mesh. The formulas and
their papers: ``docs/mesh.md``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan._core import delaunay_xy

__all__ = [
    "FEATURE_ANGLE",
    "ClosestPoints",
    "GeodesicMethod",
    "GeodesicSolver",
    "InsertedPoints",
    "Landing",
    "closest_points",
    "corner_normals",
    "delaunay_xy",
    "geodesic_distances",
    "insert_points",
    "sample_surface",
]

#: How :func:`geodesic_distances` measures: ``"exact"``, the exact polyhedral geodesic (window propagation of
#: the MMP family; equals pygeodesic's MMP to 1e-9); ``"fmm"``, fast marching (first order; ~0.2 % on a
#: scanned mesh, the fastest for one source); ``"heat"``, the heat method (two prefactored sparse solves per
#: source; ~0.5 %, the fastest for many sources on one mesh).
GeodesicMethod = Literal["exact", "fmm", "heat"]

#: Where an inserted point landed: on a vertex, on an edge (its triangles split in two each),
#: or inside a triangle (split in three).
Landing = Literal["vertex", "edge", "face"]


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


@dataclass(frozen=True, eq=False)
class InsertedPoints:
    """Result of :func:`insert_points`: the mesh with the points as vertices.

    Attributes
    ----------
    vertices : ndarray, shape (V + k, 3)
        The mesh's vertices, then one per point that did not land on a vertex.
    faces : ndarray of int64, shape (M', 3)
        The triangles, split where the points landed (the first M keep their places).
    indices : ndarray of int64, shape (N,)
        The vertex of each point.
    landings : list of str
        ``"vertex"``, ``"edge"`` or ``"face"`` per point.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    indices: NDArray[np.int64]
    landings: list[Landing]


def insert_points(vertices: ArrayLike, faces: ArrayLike, points: ArrayLike, *, tolerance: float = 1e-6) -> InsertedPoints:
    """Points of the surface as vertices of its mesh (SPEC S2; paper 002 §3.2, fig. 6), so that
    geodesic distances start and end exactly there. Each point, in order, goes to its closest
    point of the mesh: within ``tolerance`` of a vertex it is that vertex; within ``tolerance``
    of an edge the edge's triangles are split in two each; otherwise its triangle is split in
    three. Triangles are only split, never flipped: the surface and its area stay as they were.

    Parameters
    ----------
    vertices : array_like, shape (V, 3)
    faces : array_like of int, shape (M, 3)
    points : array_like, shape (N, 3)
        On or near the surface, mm (a point off it is inserted at its closest point).
    tolerance : float
        Snapping distance to a vertex or an edge, mm.

    Returns
    -------
    InsertedPoints
        ``.vertices``, ``.faces``, ``.indices`` (the vertex of each point), ``.landings``.

    Examples
    --------
    >>> mesh = machscan.insert_points(scan, machscan.delaunay_xy(scan), matching_points)
    >>> mesh.indices  # sources of geodesic distances
    """
    out = _core.insert_points(vertices, faces, points, tolerance=tolerance)
    return InsertedPoints(out["vertices"], out["faces"], out["indices"], list(out["landings"]))


def _surface(value: object, name: str) -> tuple[ArrayLike, ArrayLike | None]:
    """A surface argument as (points, faces or None): scan points (meshed in the core), a ``(vertices,
    faces)`` pair, or a mesh with ``.vertices`` and ``.triangles`` (:class:`machscan.io.TriangleMesh`)."""
    if isinstance(value, tuple):
        if len(value) != 2:
            raise ValueError(f"{name}: expected points (N, 3) or a (vertices, faces) pair, got a tuple of {len(value)}")
        return value[0], value[1]
    if hasattr(value, "vertices") and hasattr(value, "triangles"):
        return value.vertices, value.triangles
    return value, None  # type: ignore[return-value]


def geodesic_distances(
    vertices: ArrayLike, faces: ArrayLike, sources: ArrayLike, *, method: GeodesicMethod = "exact"
) -> NDArray[np.float64]:
    """Geodesic distances along a triangle mesh from each source vertex to every vertex (SPEC
    S3; paper 002 §3.2), sources in parallel with the GIL released.

    ``method="exact"`` (default): the length of the shortest path along the polyhedral surface, by window
    propagation (Mitchell–Mount–Papadimitriou, with the Chen–Han / Xin–Wang pruning): straight inside every
    face, bending only at saddle and boundary vertices. Equals pygeodesic (Kirsanov's MMP) to 1e-9. One
    source alone is propagated in two halves of the mesh on two threads (1.6–1.8× faster on the bunny; on
    meshes of 2,048 faces and more, and back on one thread when another program keeps the second core
    busy); its row equals the same source's row in a call with several up to rounding (~1e-15 of the
    distances). The propagation's buffers (about 300 bytes per face) are kept for the next call, up to
    256 MB in all.

    ``method="fmm"``: fast marching with the virtual-source update (the point in the triangle's
    plane at the two known distances; exact where that point is seen through the triangle, so a
    regular flat grid measures Euclidean distances to 1e-9), the edge update where that point's
    line misses the triangle (a flat plate of random points meshed by :func:`delaunay_xy`: 0.1–0.4 %
    mean, up to a few % at single vertices).

    ``method="heat"``: the heat method (Crane, Weischedel & Wardetzky): heat flowed from the source
    for a short time t = h² (h the mean edge), its normalised gradient, and the Poisson equation whose
    solution has that gradient; on the intrinsic Delaunay triangulation of the mesh (edges flipped
    along the surface, so that obtuse triangles do not spoil the Laplacian; on an open mesh that of
    its tufted cover, so that boundary edges are flipped too, as potpourri3d does). Mean errors seen:
    0.45–0.85 % on the bunny, 1–2 % on a random flat plate. Both sparse systems are
    factored once (faer's Cholesky) and serve every source, which makes it the fastest for many
    sources on one mesh. Beyond ~700 mean edges from a source the heat underflows and distances there
    are not reliable.

    Parameters
    ----------
    vertices : array_like, shape (V, 3)
    faces : array_like of int, shape (M, 3)
    sources : array_like of int, shape (S,)
        Source vertices, e.g. ``insert_points(...).indices``.
    method : {"exact", "fmm", "heat"}

    Returns
    -------
    ndarray, shape (S, V)
        mm; ``inf`` at vertices no face uses or no face path reaches.

    Examples
    --------
    >>> d = machscan.geodesic_distances(mesh.vertices, mesh.faces, mesh.indices)
    """
    return _core.geodesic_distances(vertices, faces, _source_indices(sources), method=method)


def _source_indices(sources: ArrayLike) -> list[int]:
    """``sources`` as a list of vertex indices; a clear error for anything else."""
    src = np.atleast_1d(np.asarray(sources))
    if src.ndim != 1 or (src.size and not np.issubdtype(src.dtype, np.integer)):
        raise ValueError(f"sources: expected vertex indices (S,), got {src.dtype} of shape {src.shape}")
    if src.size and (int(src.min()) < 0 or int(src.max()) > np.iinfo(np.int64).max):
        bad = int(src.min()) if int(src.min()) < 0 else int(src.max())
        raise ValueError(f"sources: {bad} is not a vertex index")
    return [int(s) for s in src]


class GeodesicSolver:
    """A mesh prepared once for :func:`geodesic_distances` by one method, for any number of calls: what
    pygeodesic's ``PyGeodesicAlgorithmExact`` and potpourri3d's distance solvers are. ``method="exact"``
    keeps the mesh's layout for the window propagation (edges, unfolded faces, which vertices are
    saddles) and the propagation's buffers; ``"fmm"`` the faces around each vertex and the face lengths;
    ``"heat"`` the factored heat and Poisson operators (the costly part: ~0.1 s on the 35,947-vertex
    bunny, then 2–9 ms per source). Each call of :meth:`distances` gives the same rows as
    :func:`geodesic_distances` on the same mesh and sources (for ``"heat"``, the same sources in the same
    order). Calls release the GIL and may come from several threads.

    Parameters
    ----------
    vertices : array_like, shape (V, 3)
        mm.
    faces : array_like of int, shape (M, 3)
    method : {"exact", "fmm", "heat"}
        As in :func:`geodesic_distances`.

    Raises
    ------
    ValueError
        Naming ``vertices`` (shape, not finite), ``faces`` (shape, beyond the vertices) or ``method``.

    Examples
    --------
    >>> solver = machscan.GeodesicSolver(mesh.vertices, mesh.faces)
    >>> d = solver.distances([0, 17])      # (2, V), mm
    """

    def __init__(self, vertices: ArrayLike, faces: ArrayLike, *, method: GeodesicMethod = "exact") -> None:
        self._solver = _core.GeodesicSolver(vertices, faces, method=method)

    @property
    def method(self) -> GeodesicMethod:
        """The method the mesh was prepared for."""
        return self._solver.method  # type: ignore[return-value]

    @property
    def vertex_count(self) -> int:
        """The number of vertices V, the length of each row of :meth:`distances`."""
        return self._solver.vertex_count

    def distances(self, sources: ArrayLike) -> NDArray[np.float64]:
        """Distances from each source vertex to every vertex, sources in parallel.

        Parameters
        ----------
        sources : array_like of int, shape (S,)

        Returns
        -------
        ndarray, shape (S, V)
            mm; ``inf`` at vertices no face uses or no face path reaches.

        Raises
        ------
        ValueError
            Naming ``sources`` (not integer vertex indices, or beyond the vertices).
        """
        return self._solver.distances(_source_indices(sources))

    def __repr__(self) -> str:
        return f"GeodesicSolver(method={self.method!r}, vertex_count={self.vertex_count})"


#: Default feature angle of :func:`corner_normals`, degrees: faces meeting at a vertex more steeply than this are
#: on two sides of an edge of the part, whose normals are not averaged.
FEATURE_ANGLE = 30.0


def corner_normals(vertices: ArrayLike, triangles: ArrayLike, *, feature_angle: float = FEATURE_ANGLE) -> NDArray[np.float64]:
    """Unit normals at each triangle's corners, shape (T, 3, 3): the area-weighted mean of the normals of the faces
    round the corner's vertex that turn by less than ``feature_angle`` degrees from the triangle's own. A smooth
    stretch (a fillet tessellated in facets) gets normals that turn with it; a face beside an edge of the part (a box's
    side) keeps its own normal up to the edge, where one averaged over both sides would lean 45° out of it.

    Raises
    ------
    ValueError
        ``vertices`` not (N, 3) finite, ``triangles`` not (T, 3) indices into them, or a triangle of zero area.

    Examples
    --------
    >>> mesh = machscan.io.read_mesh("part.stl")
    >>> corners = machscan.mesh.corner_normals(mesh.vertices, mesh.triangles)  # (T, 3, 3), unit
    """
    v, t = _mesh_arrays(vertices, triangles)
    if not (np.isfinite(feature_angle) and 0 < feature_angle < 180):
        raise ValueError(f"feature_angle: must be between 0 and 180 degrees, got {feature_angle}")
    face = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])  # twice the area along the unit normal
    length = np.linalg.norm(face, axis=1)
    if np.any(length == 0):
        raise ValueError(f"triangles: triangle {int(np.argmin(length))} has zero area (no normal)")
    unit = face / length[:, None]
    # Every pair (corner, face round the corner's vertex), by grouping the corners by vertex.
    corner_vertex = t.ravel()
    corner_face = np.repeat(np.arange(len(t)), 3)
    order = np.argsort(corner_vertex, kind="stable")
    by_vertex = corner_vertex[order]
    first = np.searchsorted(by_vertex, by_vertex, "left")
    count = np.searchsorted(by_vertex, by_vertex, "right") - first
    owner = np.repeat(np.arange(len(order)), count)
    within = np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count)
    other = first[owner] + within
    own_face, other_face = corner_face[order[owner]], corner_face[order[other]]
    smooth = np.einsum("ij,ij->i", unit[own_face], unit[other_face]) >= np.cos(np.radians(feature_angle))
    total = np.zeros((len(order), 3))
    np.add.at(total, owner[smooth], face[other_face[smooth]])
    normals = np.empty_like(total)
    normals[order] = total / np.linalg.norm(total, axis=1, keepdims=True)
    return normals.reshape(len(t), 3, 3)


def sample_surface(
    vertices: ArrayLike,
    triangles: ArrayLike,
    spacing: float,
    *,
    normals: ArrayLike | None = None,
    feature_angle: float = FEATURE_ANGLE,
    seed: int = 0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Points with normals spread evenly over a triangle mesh, about ``spacing`` mm apart (Poisson-disk by
    elimination: a dense random sample, area-weighted, thinned so that no two kept points are closer than
    ``spacing``): a model for :func:`machscan.allowance` and grinding from a mesh whose vertices are where a mesher
    put them (a flat one triangle across has none inside it). Points lie on the triangles; normals are interpolated
    over each triangle from its corners and normalised — ``normals`` per vertex (N, 3) when given (a CAD mesh's
    exact ones), else :func:`corner_normals` with ``feature_angle``.

    Returns
    -------
    points, normals : ndarray, shape (K, 3)

    Raises
    ------
    ValueError
        ``spacing`` not a positive distance or too fine for the mesh's area (over 50 M candidates), bad arrays.

    Examples
    --------
    >>> mesh = machscan.io.read_mesh("part.stl")
    >>> model, normals = machscan.sample_surface(mesh.vertices, mesh.triangles, 0.15)  # points 0.15 mm apart
    >>> allowance = machscan.allowance(model, normals, blank)
    """
    from machscan.cloud import remove_duplicates

    v, t = _mesh_arrays(vertices, triangles)
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing: must be a positive distance, got {spacing}")
    if normals is None:
        corners = corner_normals(v, t, feature_angle=feature_angle)
    else:
        vn = np.asarray(normals, dtype=np.float64)
        if vn.shape != v.shape or not np.isfinite(vn).all():
            raise ValueError(f"normals: must be finite, one per vertex {v.shape}, got shape {vn.shape}")
        corners = vn[t]
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    total = float(area.sum())
    # Ten candidates per disk of the spacing: enough that the thinned set covers evenly.
    n = int(np.ceil(10 * total / (np.pi * (spacing / 2) ** 2)))
    if n > 50_000_000:
        raise ValueError(f"spacing: {spacing} mm over {total:.0f} mm² would need {n:,} candidates; sample coarser")
    rng = np.random.default_rng(seed)
    pick = rng.choice(len(t), size=n, p=area / total)
    r1, r2 = rng.random(n), rng.random(n)
    flip = r1 + r2 > 1
    r1[flip], r2[flip] = 1 - r1[flip], 1 - r2[flip]
    w = np.column_stack([1 - r1 - r2, r1, r2])
    points = np.einsum("nk,nkj->nj", w, v[t[pick]])
    keep = remove_duplicates(points, spacing)
    # Normals only for the points kept: the candidates are ten per disc, and their (n, 3, 3) corner normals had
    # taken 1.3 GB for a blade sampled every 0.15 mm.
    sampled = np.einsum("nk,nkj->nj", w[keep], corners[pick[keep]])
    sampled /= np.linalg.norm(sampled, axis=1, keepdims=True)
    return points[keep], sampled


def _mesh_arrays(vertices: ArrayLike, triangles: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles)
    if v.ndim != 2 or v.shape[1] != 3 or not np.isfinite(v).all():
        raise ValueError(f"vertices: must be finite (N, 3) points in mm, got shape {v.shape}")
    if t.ndim != 2 or t.shape[1] != 3 or not np.issubdtype(t.dtype, np.integer) or len(t) == 0:
        raise ValueError(f"triangles: must be (T, 3) integer vertex indices, at least one, got {t.dtype} {t.shape}")
    if t.min() < 0 or t.max() >= len(v):
        raise ValueError(f"triangles: indices must lie in 0 … {len(v) - 1}, found {t.min()} … {t.max()}")
    return v, t.astype(np.int64)
