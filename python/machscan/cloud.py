"""Point clouds (SPEC F, papers 002 §2 and 004 §1.1): filters, neighbors, normals and curvature,
octree simplification, and Euclidean clustering.

Conventions every function here follows:

- the cloud ``points (N, 3)`` comes first, in mm;
- filters return the **kept indices** (ascending int64), so normals, scalars and frame numbers
  are carried along with ``array[keep]`` (or :meth:`machscan.io.CloudFile.select`);
- neighbor counts ``k``: at least 1 (3 for normals and curvature), and no more than the cloud
  holds — a point counts as its own neighbor in the filters, normals and :func:`knn_graph`
  (``k ≤ N``); the feature degree and clustering count the other points (``k ≤ N − 1``). Asking
  for more raises ``ValueError``: a smaller neighborhood than asked would change the result
  silently. An empty cloud gives an empty result.

The kernels are in Rust and run in parallel with the GIL released; results do not depend on the
number of threads.

The formulas and their papers: ``docs/clouds.md``.
"""

from machscan._core import (
    crop_box,
    estimate_normals,
    euclidean_clusters,
    knn_graph,
    nearest_neighbors,
    octree_simplify,
    point_spacing,
    principal_curvatures,
    random_downsample,
    remove_duplicates,
    remove_radius_outliers,
    remove_statistical_outliers,
    surface_variation,
    uniform_downsample,
    voxel_downsample,
)

__all__ = [
    "crop_box",
    "estimate_normals",
    "euclidean_clusters",
    "knn_graph",
    "nearest_neighbors",
    "octree_simplify",
    "point_spacing",
    "principal_curvatures",
    "random_downsample",
    "remove_duplicates",
    "remove_radius_outliers",
    "remove_statistical_outliers",
    "surface_variation",
    "uniform_downsample",
    "voxel_downsample",
]
