"""Surface meshes (issue #10 §1): the Delaunay triangulation of the xy projection against
SciPy's on the same points, and its rules for degenerate input."""

import numpy as np
import pytest

import machscan


def triangles(faces):
    return {tuple(sorted(t)) for t in np.asarray(faces).tolist()}


@pytest.mark.parametrize("seed", range(3))
def test_delaunay_xy_equals_scipy_on_points_in_general_position(seed):
    spatial = pytest.importorskip("scipy.spatial")
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 300, (5000, 2))
    pts = np.column_stack([xy, 0.001 * (xy[:, 0] - 150) ** 2])  # a skin bent over x
    faces = machscan.delaunay_xy(pts)
    assert faces.dtype == np.int64 and faces.shape[1] == 3
    assert triangles(faces) == triangles(spatial.Delaunay(xy).simplices)
    # Counter-clockwise seen from +z: the lifted normals point up.
    a, b, c = (pts[faces[:, k]] for k in range(3))
    assert (np.cross(b - a, c - a)[:, 2] > 0).all()


def test_max_edge_trims_the_hull_triangles_of_a_concave_outline():
    # An L-shaped grid: the hull closes the notch with long triangles; max_edge removes them.
    gx, gy = np.meshgrid(np.arange(0, 100.5, 2.0), np.arange(0, 100.5, 2.0))
    keep = ~((gx > 50) & (gy > 50))
    pts = np.column_stack([gx[keep], gy[keep], np.zeros(keep.sum())])
    every = machscan.delaunay_xy(pts)
    trimmed = machscan.delaunay_xy(pts, max_edge=3.0)
    a, b, c = (pts[trimmed[:, k]] for k in range(3))
    area = 0.5 * np.abs(np.cross(b - a, c - a)[:, 2]).sum()
    # The L, not its hull: plus the one triangle at the inner corner whose edges (2, 2, 2.8 mm) are
    # all shorter than max_edge.
    assert area == pytest.approx(100 * 100 - 50 * 50 + 2)
    assert len(trimmed) < len(every)


def test_duplicates_are_left_out_and_degenerate_input_raises_naming_points():
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 3], [1, 1, 1.0]])
    faces = machscan.delaunay_xy(pts)
    assert 3 not in faces  # the second point at (1, 0): the first is kept
    assert len(faces) == 2
    with pytest.raises(ValueError, match="points.*one line"):
        machscan.delaunay_xy(np.array([[0, 0, 0], [1, 1, 0], [2, 2, 0.0]]))
    with pytest.raises(ValueError, match="points"):
        machscan.delaunay_xy(np.array([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]]))
    with pytest.raises(ValueError, match="max_edge"):
        machscan.delaunay_xy(pts, max_edge=-1.0)
    with pytest.raises(ValueError, match="points"):
        machscan.delaunay_xy(np.zeros((4, 2)))
