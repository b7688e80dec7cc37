"""Signed distances to a mesh, per-face statistics, the fit to a mesh and ``machscan compare``.

References: an exhaustive search over every triangle (NumPy) for the distance and closest point;
Open3D's ``RaycastingScene.compute_signed_distance`` (sign by ray parity, float32) on closed
meshes; exact geometry (a sphere) for the sign on open patches; NumPy for the statistics; a
known pose for the fit.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

import machscan
from machscan.cli import main

trimesh = pytest.importorskip("trimesh")


def exhaustive(points: np.ndarray, v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance to, and closest point on, the nearest triangle, over every triangle (Ericson's
    Voronoi regions, vectorised over triangles for each point)."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    ab, ac = b - a, c - a
    best_d = np.empty(len(points))
    best_p = np.empty_like(points)
    for i, p in enumerate(points):
        ap, bp, cp = p - a, p - b, p - c
        d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
        d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
        d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
        va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
        with np.errstate(divide="ignore", invalid="ignore"):
            denom = va + vb + vc
            q = a + ab * (vb / denom)[:, None] + ac * (vc / denom)[:, None]
            e_ab = a + ab * np.clip(d1 / (d1 - d3), 0, 1)[:, None]
            e_ac = a + ac * np.clip(d2 / (d2 - d6), 0, 1)[:, None]
            e_bc = b + (c - b) * np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)[:, None]
        inside = (va > 0) & (vb > 0) & (vc > 0)
        cands = np.stack([np.where(inside[:, None], q, a), a, b, c, e_ab, e_ac, e_bc])
        cands = np.nan_to_num(cands, nan=np.inf)
        dist = np.linalg.norm(cands - p, axis=2)
        k = np.unravel_index(np.argmin(dist), dist.shape)
        best_d[i], best_p[i] = dist[k], cands[k]
    return best_d, best_p


def lumpy_body(subdivisions: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A closed, asymmetric, partly concave body: an icosphere stretched and dented."""
    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=20.0)
    v = s.vertices * [1.5, 1.0, 0.7]
    v = v * (1 + 0.15 * np.sin(3 * v[:, :1] / 20) * np.cos(2 * v[:, 1:2] / 20) - 0.1 * (v[:, 2:] > 8))
    return np.asarray(v, dtype=np.float64), np.asarray(s.faces, dtype=np.int64)


def test_distances_and_closest_points_equal_an_exhaustive_search():
    v, f = lumpy_body(2)
    rng = np.random.default_rng(1)
    q = rng.uniform(-40, 40, size=(600, 3)) * [1.0, 0.8, 0.6]
    d = machscan.signed_distances(q, v, f)
    ref_d, ref_p = exhaustive(q, v, f)
    np.testing.assert_allclose(np.abs(d.distances), ref_d, rtol=0, atol=1e-11)
    np.testing.assert_allclose(d.points, ref_p, rtol=0, atol=1e-9)
    # The triangle named holds the closest point.
    a, b, c = (v[f[d.triangles, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    assert np.all(np.abs(np.einsum("ij,ij->i", d.points - a, n)) <= 1e-9 * np.linalg.norm(n, axis=1))


def test_signs_match_open3d_on_closed_meshes_convex_or_not():
    o3d = pytest.importorskip("open3d")
    rng = np.random.default_rng(2)
    for v, f in (lumpy_body(3), _annulus()):
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(f.astype(np.uint32)))
        lo, hi = v.min(axis=0) - 3, v.max(axis=0) + 3
        q = rng.uniform(lo, hi, size=(20000, 3))
        ours = machscan.signed_distances(q, v, f).distances
        # Five rays per point and a majority: a single ray through an edge flips Open3D's sign.
        ref = scene.compute_signed_distance(o3d.core.Tensor(q.astype(np.float32)), nsamples=5).numpy()
        # float32 coordinates: 1e-4 mm on parts of 60 mm is a few of its rounding steps.
        np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-4)
        clear = np.abs(ref) > 1e-4
        assert np.array_equal(np.sign(ours[clear]), np.sign(ref[clear]))
        assert (ours < 0).sum() > 1000 and (ours > 0).sum() > 1000


def _annulus() -> tuple[np.ndarray, np.ndarray]:
    m = trimesh.creation.annulus(r_min=8.0, r_max=20.0, height=10.0, sections=48)
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)


def test_an_open_patch_is_signed_by_its_winding_near_its_surface():
    # The upper half of a sphere of radius 20, open at the equator: outside is away from the centre.
    s = trimesh.creation.icosphere(subdivisions=4, radius=20.0)
    keep = s.vertices[s.faces].min(axis=1)[:, 2] > 0.5
    v, f = np.asarray(s.vertices), np.asarray(s.faces[keep])
    rng = np.random.default_rng(3)
    u = rng.normal(size=(5000, 3))
    u[:, 2] = np.abs(u[:, 2]) + 0.5
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    radius = 20 + rng.uniform(-2, 2, size=5000)
    q = u * radius[:, None]
    d = machscan.signed_distances(q, v, f).distances
    # The mesh lies within 0.05 mm inside the sphere; points farther than that off it sign by the sphere.
    clear = np.abs(radius - 20) > 0.1
    assert np.array_equal(np.sign(d[clear]), np.sign(radius[clear] - 20))


def test_statistics_per_cad_face_equal_numpy_and_follow_the_tolerance():
    v, f = lumpy_body(2)
    cad = (np.arange(len(f)) % 7).astype(np.int64)
    rng = np.random.default_rng(4)
    q = rng.uniform(-35, 35, size=(3000, 3)) * [1.0, 0.7, 0.5]
    d = machscan.signed_distances(q, v, f, cad_faces=cad)
    np.testing.assert_array_equal(d.cad_faces, cad[d.triangles])
    s = d.statistics((-0.5, 1.0))
    for i, face in enumerate(s.face):
        x = d.distances[d.cad_faces == face]
        assert s.count[i] == len(x)
        got = [s.min[i], s.max[i], s.mean[i], s.std[i]]
        np.testing.assert_allclose(got, [x.min(), x.max(), x.mean(), x.std(ddof=1)], atol=1e-12)
        assert s.out_of_tolerance[i] == pytest.approx(np.mean((x < -0.5) | (x > 1.0)))
    whole = machscan.signed_distances(q, v, f).statistics(0.5)
    assert list(whole.face) == [0] and whole.count[0] == len(q)
    assert np.array_equal(d.out_of_tolerance(0.5), np.abs(d.distances) > 0.5)


def test_bad_meshes_and_arguments_are_refused_by_name():
    v, f = lumpy_body(1)
    q = np.zeros((1, 3))
    g = f.copy()
    g[0] = g[0, ::-1]
    with pytest.raises(ValueError, match=r"triangles: .*wound consistently"):
        machscan.signed_distances(q, v, g)
    with pytest.raises(ValueError, match="triangles: the closed mesh is wound inside out"):
        machscan.signed_distances(q, v, f[:, ::-1])
    with pytest.raises(ValueError, match="cad_faces: expected integers of shape"):
        machscan.signed_distances(q, v, f, cad_faces=np.zeros(3, dtype=int))
    with pytest.raises(ValueError, match="points"):
        machscan.signed_distances([[np.nan, 0, 0]], v, f)
    with pytest.raises(ValueError, match="tolerance"):
        machscan.signed_distances(q, v, f).statistics((1.0, -1.0))


def _pose(angles_deg: tuple[float, float, float], shift: tuple[float, float, float]) -> np.ndarray:
    a, b, c = np.radians(angles_deg)
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    t = np.eye(4)
    t[:3, :3] = rz @ ry @ rx
    t[:3, 3] = shift
    return t


def _surface_points(v: np.ndarray, f: np.ndarray, n: int, seed: int) -> np.ndarray:
    mesh = trimesh.Trimesh(v, f, process=False)
    points, _ = trimesh.sample.sample_surface(mesh, n, seed=seed)
    return np.asarray(points)


def test_the_fit_to_a_mesh_recovers_a_pose_to_1e_9_mm():
    v, f = lumpy_body(3)
    on = _surface_points(v, f, 4000, 5)
    truth = _pose((1.5, -2.0, 2.5), (0.6, -0.4, 0.3))
    scan = (on - truth[:3, 3]) @ truth[:3, :3]  # the inverse of truth applied
    fit = machscan.fit_to_mesh(scan, v, f, 3.0, max_iterations=100, relative_fitness=0, relative_rmse=0)
    assert np.abs(fit.transformation - truth).max() < 1e-9
    assert fit.rmse < 1e-9 and fit.fitness == 1.0 and fit.converged and fit.undetermined == ""
    for k, want in zip("xyzabc", (0.6, -0.4, 0.3, 1.5, -2.0, 2.5), strict=True):
        assert fit.motion[k] == pytest.approx(want, abs=1e-8)


def test_held_motions_are_exactly_zero_and_c_turns_about_the_rotary_axis():
    v, f = lumpy_body(3)
    on = _surface_points(v, f, 4000, 6)
    point, direction = np.array([4.0, -3.0, 0.0]), np.array([0.0, 0.0, 1.0])
    # The part turned 3° about the table axis and shifted in x, y.
    turn = _pose((0, 0, 3.0), (0, 0, 0))
    about = np.eye(4)
    about[:3, 3] = point
    truth = _pose((0, 0, 0), (0.25, -0.15, 0)) @ about @ turn @ np.linalg.inv(about)
    scan = (on - truth[:3, 3]) @ truth[:3, :3]
    fit = machscan.fit_to_mesh(
        scan, v, f, 3.0, dof="xyc", axis=(point, direction), max_iterations=100, relative_fitness=0, relative_rmse=0
    )
    assert (fit.motion["z"], fit.motion["a"], fit.motion["b"]) == (0.0, 0.0, 0.0)
    assert fit.dof == "xyc"
    # Z held and only C turned: the pose's z row is exactly (0, 0, 1, 0).
    assert list(fit.transformation[2]) == [0.0, 0.0, 1.0, 0.0]
    assert np.abs(fit.transformation - truth).max() < 1e-9
    assert fit.motion["c"] == pytest.approx(3.0, abs=1e-8)


def test_results_do_not_depend_on_the_thread_count():
    v, f = lumpy_body(3)
    on = _surface_points(v, f, 3000, 9)
    scan = on @ _pose((0.5, 0, 1.0), (0.2, 0, 0))[:3, :3].T
    runs = []
    for threads in (1, 2):
        with machscan.thread_limit(threads):
            d = machscan.signed_distances(scan, v, f)
            fit = machscan.fit_to_mesh(scan, v, f, 2.0)
        runs.append((d.distances.tobytes(), d.triangles.tobytes(), fit.transformation.tobytes()))
    assert runs[0] == runs[1]


def test_fit_to_mesh_refuses_bad_options_by_name():
    v, f = lumpy_body(1)
    q = v[:10]
    with pytest.raises(ValueError, match="dof: 'q' is not a motion"):
        machscan.fit_to_mesh(q, v, f, 1.0, dof="xq")
    with pytest.raises(ValueError, match="axis"):
        machscan.fit_to_mesh(q, v, f, 1.0, dof="c", axis=((0, 0, 0), (0, 0, 0)))
    with pytest.raises(ValueError, match="max_distance"):
        machscan.fit_to_mesh(q, v, f, -1.0)
    with pytest.raises(TypeError, match="max_iteration"):
        machscan.fit_to_mesh(q, v, f, 1.0, max_iteration=3)


def test_compare_writes_the_field_the_faces_and_a_figure_and_exits_3_out_of_tolerance(tmp_path):
    pytest.importorskip("matplotlib")
    v, f = lumpy_body(3)
    machscan.write_mesh(tmp_path / "cad.stl", v, f)
    cad = machscan.read_mesh(tmp_path / "cad.stl")
    on = _surface_points(cad.vertices, cad.triangles, 3000, 7)
    normals = trimesh.Trimesh(cad.vertices, cad.triangles, process=False).face_normals
    _, _, tri = trimesh.proximity.closest_point(trimesh.Trimesh(cad.vertices, cad.triangles, process=False), on)
    lift = np.where(np.arange(len(on)) % 50 == 0, 0.2, 0.01)
    scan = on + lift[:, None] * normals[tri]
    machscan.write_points(tmp_path / "scan.ply", scan, dtype="float64")
    out = tmp_path / "out"
    code = main(["compare", str(tmp_path / "scan.ply"), str(tmp_path / "cad.stl"), "--tolerance", "0.05", "--out", str(out)])
    assert code == 3
    field = machscan.io.read(out / "deviation.ply")
    ref = machscan.signed_distances(scan, cad.vertices, cad.triangles).distances
    np.testing.assert_allclose(field.scalars["deviation_mm"], ref, atol=1e-6)  # float32 in the PLY
    assert np.sum(field.scalars["deviation_mm"] > 0.05) == np.sum(lift > 0.05)
    with open(out / "faces.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0][:3] == ["face", "points", "min_mm"] and int(rows[1][1]) == len(scan)
    assert (out / "deviation.png").stat().st_size > 10_000
    table = machscan.io.read_table(out / "deviation.csv")
    assert table.header is not None and table.header[3] == "deviation_mm"
    # Within tolerance: exit 0.
    assert main(["compare", str(tmp_path / "scan.ply"), str(tmp_path / "cad.stl"), "--tolerance", "0.3", "--out", str(out)]) == 0


def test_compare_fits_first_and_writes_the_pose(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    v, f = lumpy_body(3)
    machscan.write_mesh(tmp_path / "cad.ply", v, f, dtype="float64")
    on = _surface_points(v, f, 3000, 8)
    truth = _pose((0, 0, 1.0), (0.3, 0.2, 0))
    scan = (on - truth[:3, 3]) @ truth[:3, :3]
    machscan.write_points(tmp_path / "scan.ply", scan, dtype="float64")
    out = tmp_path / "out"
    args = ["compare", str(tmp_path / "scan.ply"), str(tmp_path / "cad.ply"), "--tolerance", "0.001", "--out", str(out)]
    assert main([*args, "--fit", "--dof", "xyc"]) == 0
    pose = np.loadtxt(out / "pose.txt")
    assert np.abs(pose - truth).max() < 1e-6
    assert "dof xyc" in capsys.readouterr().out
