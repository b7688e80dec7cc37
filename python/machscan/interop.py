"""Conversions to and from Open3D and trimesh geometry (issue #34 §5).

machscan takes and returns NumPy arrays; these turn the geometry objects of the two libraries a
plant's scripts most often hold into machscan's :class:`~machscan.io.CloudFile` and
:class:`~machscan.io.TriangleMesh` and back. Neither library is imported until a conversion
asks for it. Passing such an object where machscan takes an array raises a ``ValueError``
naming the argument and the conversion to use.

- :func:`from_open3d` — ``open3d.geometry.PointCloud`` / ``TriangleMesh`` (legacy) or
  ``open3d.t.geometry.PointCloud`` / ``TriangleMesh`` (tensor) → ``CloudFile`` /
  ``TriangleMesh``; normals kept; a tensor cloud's other per-point attributes become scalars.
- :func:`to_open3d` — a ``CloudFile``, a ``TriangleMesh`` or an ``(N, 3)`` array → the legacy
  geometry (``tensor=True``: the tensor one, float64, with scalars as point attributes).
- :func:`from_trimesh` — ``trimesh.Trimesh`` → ``TriangleMesh`` (vertex normals only when the
  mesh carries them, not computed); ``trimesh.PointCloud`` → ``CloudFile``.
- :func:`to_trimesh` — a ``TriangleMesh`` → ``trimesh.Trimesh`` (``process=False``: vertices
  and faces as given); a ``CloudFile`` or an array → ``trimesh.PointCloud``.

Coordinates are taken as they are (machscan's unit is the mm).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from machscan.io import CloudFile, TriangleMesh

__all__ = ["from_open3d", "from_trimesh", "to_open3d", "to_trimesh"]


def _copy(values: ArrayLike, dtype: Any) -> np.ndarray:
    """A C-ordered copy: Open3D refuses read-only buffers, and trimesh marks what it is given
    read-only, which must not happen to the caller's arrays."""
    return np.array(values, dtype=dtype, order="C", copy=True)


def _import(name: str) -> Any:
    try:
        return __import__(name)
    except ImportError:
        raise ImportError(f"this conversion needs {name}: pip install {name}") from None


def _kind(obj: object) -> tuple[str, str]:
    t = type(obj)
    return t.__module__ or "", t.__name__


def from_open3d(geometry: Any) -> CloudFile | TriangleMesh:
    """An Open3D point cloud or triangle mesh (legacy or tensor) as machscan data.

    Examples
    --------
    >>> cloud = machscan.interop.from_open3d(open3d.io.read_point_cloud("scan.ply"))
    >>> machscan.estimate_normals(cloud.points, k=20)
    """
    module, name = _kind(geometry)
    if not module.startswith("open3d"):
        raise ValueError(f"geometry: expected an Open3D PointCloud or TriangleMesh, got {module}.{name}")
    tensor = ".t." in module + "." or module.endswith(".t")
    if name == "PointCloud":
        if tensor:
            attrs = {k: geometry.point[k].numpy() for k in geometry.point}
            points = np.asarray(attrs.pop("positions"), dtype=np.float64)
            normals = attrs.pop("normals", None)
            scalars = {k: np.asarray(v, dtype=np.float64).reshape(len(points), -1) for k, v in attrs.items()}
            flat = {}
            for k, v in scalars.items():
                if v.shape[1] == 1:
                    flat[k] = v[:, 0]
                else:
                    flat.update({f"{k}_{j}": v[:, j] for j in range(v.shape[1])})
            return CloudFile(
                points=points,
                normals=None if normals is None else np.asarray(normals, dtype=np.float64),
                scalars=flat,
            )
        points = np.asarray(geometry.points, dtype=np.float64)
        normals = np.asarray(geometry.normals, dtype=np.float64) if geometry.has_normals() else None
        scalars = {}
        if geometry.has_colors():
            colours = np.asarray(geometry.colors, dtype=np.float64)
            scalars = {"red": colours[:, 0], "green": colours[:, 1], "blue": colours[:, 2]}
        return CloudFile(points=points, normals=normals, scalars=scalars)
    if name == "TriangleMesh":
        if tensor:
            vertices = np.asarray(geometry.vertex["positions"].numpy(), dtype=np.float64)
            triangles = np.asarray(geometry.triangle["indices"].numpy(), dtype=np.int64)
            normals = geometry.vertex["normals"].numpy() if "normals" in geometry.vertex else None
        else:
            vertices = np.asarray(geometry.vertices, dtype=np.float64)
            triangles = np.asarray(geometry.triangles, dtype=np.int64)
            normals = np.asarray(geometry.vertex_normals) if geometry.has_vertex_normals() else None
        return TriangleMesh(
            vertices=vertices,
            triangles=triangles.reshape(-1, 3),
            normals=None if normals is None else np.asarray(normals, dtype=np.float64),
        )
    raise ValueError(f"geometry: expected an Open3D PointCloud or TriangleMesh, got {module}.{name}")


def _points_of(data: CloudFile | TriangleMesh | ArrayLike) -> tuple[np.ndarray, np.ndarray | None, dict[str, Any]]:
    if isinstance(data, CloudFile):
        return data.points, data.normals, data.scalars
    if isinstance(data, TriangleMesh):
        return data.vertices, data.normals, {}
    points = np.asarray(data, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"data: expected a CloudFile, a TriangleMesh or points of shape (N, 3), got {points.shape}")
    return points, None, {}


def to_open3d(data: CloudFile | TriangleMesh | ArrayLike, *, tensor: bool = False) -> Any:
    """machscan data as Open3D geometry: a ``TriangleMesh`` for a mesh, a ``PointCloud``
    otherwise (legacy by default; ``tensor=True`` for ``open3d.t.geometry``, float64, which
    also keeps the scalars as point attributes).

    Examples
    --------
    >>> pcd = machscan.interop.to_open3d(machscan.io.read("scan.las"))
    >>> open3d.visualization.draw_geometries([pcd])
    """
    o3d = _import("open3d")
    if isinstance(data, TriangleMesh):
        if tensor:
            mesh = o3d.t.geometry.TriangleMesh()
            mesh.vertex["positions"] = o3d.core.Tensor(_copy(data.vertices, dtype=np.float64))
            mesh.triangle["indices"] = o3d.core.Tensor(_copy(data.triangles, dtype=np.int64))
            if data.normals is not None:
                mesh.vertex["normals"] = o3d.core.Tensor(_copy(data.normals, dtype=np.float64))
            return mesh
        mesh = o3d.geometry.TriangleMesh(
            o3d.utility.Vector3dVector(_copy(data.vertices, dtype=np.float64)),
            o3d.utility.Vector3iVector(_copy(data.triangles, dtype=np.int32)),
        )
        if data.normals is not None:
            mesh.vertex_normals = o3d.utility.Vector3dVector(_copy(data.normals, dtype=np.float64))
        return mesh
    points, normals, scalars = _points_of(data)
    if tensor:
        cloud = o3d.t.geometry.PointCloud(o3d.core.Tensor(_copy(points, dtype=np.float64)))
        if normals is not None:
            cloud.point["normals"] = o3d.core.Tensor(_copy(normals, dtype=np.float64))
        for name, values in scalars.items():
            cloud.point[name] = o3d.core.Tensor(_copy(values, dtype=np.float64).reshape(-1, 1))
        return cloud
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(_copy(points, dtype=np.float64)))
    if normals is not None:
        cloud.normals = o3d.utility.Vector3dVector(_copy(normals, dtype=np.float64))
    return cloud


def from_trimesh(geometry: Any) -> CloudFile | TriangleMesh:
    """A trimesh ``Trimesh`` (→ ``TriangleMesh``) or ``PointCloud`` (→ ``CloudFile``).

    Vertex normals are kept only where the mesh already holds them (trimesh computes them on
    first access; machscan does not ask it to).

    Examples
    --------
    >>> mesh = machscan.interop.from_trimesh(trimesh.load("blade.stl"))
    """
    module, name = _kind(geometry)
    if not module.startswith("trimesh"):
        raise ValueError(f"geometry: expected a trimesh Trimesh or PointCloud, got {module}.{name}")
    if name == "Trimesh":
        cached = "vertex_normals" in geometry._cache
        return TriangleMesh(
            vertices=np.asarray(geometry.vertices, dtype=np.float64),
            triangles=np.asarray(geometry.faces, dtype=np.int64).reshape(-1, 3),
            normals=np.asarray(geometry.vertex_normals, dtype=np.float64) if cached else None,
        )
    if name == "PointCloud":
        return CloudFile(points=np.asarray(geometry.vertices, dtype=np.float64), normals=None, scalars={})
    raise ValueError(f"geometry: expected a trimesh Trimesh or PointCloud, got {module}.{name}")


def to_trimesh(data: CloudFile | TriangleMesh | ArrayLike) -> Any:
    """machscan data as trimesh geometry: ``Trimesh`` for a mesh (``process=False``: vertices
    and faces exactly as given), ``PointCloud`` otherwise.

    Examples
    --------
    >>> tm = machscan.interop.to_trimesh(machscan.read_mesh("blade.stl"))
    >>> tm.is_watertight
    """
    trimesh = _import("trimesh")
    if isinstance(data, TriangleMesh):
        kwargs: dict[str, Any] = {}
        if data.normals is not None:
            kwargs["vertex_normals"] = _copy(data.normals, dtype=np.float64)
        return trimesh.Trimesh(
            vertices=_copy(data.vertices, dtype=np.float64),
            faces=_copy(data.triangles, dtype=np.int64),
            process=False,
            **kwargs,
        )
    points, _, _ = _points_of(data)
    return trimesh.PointCloud(_copy(points, dtype=np.float64))
