"""The plant's routes end to end (issue #32 §7): each CLI route chained exactly as the README shows it, every file a
step writes read back by the next and by the tests, the figures checked against exact truth — on parts no generator
in machscan makes (tests/analytic_blades.py: twisted elliptic blades with exact normals and offsets), and the units
every file carries checked on reading back (feeds in mm/min, lengths in mm)."""

from __future__ import annotations

import numpy as np
import pytest

import analytic_blades as parts
import machscan
from machscan import synth
from machscan.cli import main

REMOVAL = "0.05,0.6,-0.7,0.8,20,15,0.5,200"  # C, exponents, belt 20 m/s, force 15 N, feeds 0.5–200 mm/s
MODEL = machscan.RemovalModel(C=0.05, exponents=(0.6, -0.7, 0.8), belt_speed=20.0, force=15.0, feed_limits=(0.5, 200.0))


def twisted_blade() -> parts.Blade:
    """A twisted blade of elliptic sections with 2 mm edges (40 mm chord, 60 mm span): no generator makes it."""
    return parts.Blade(parts.EllipseSection.with_edge_radius(20, 2.0), 60, twist_deg=30, lean=(0.05, 0.02), bow=(5e-4, 0))


@pytest.fixture(scope="module")
def blade_files(tmp_path_factory):
    """model.ply (points and normals every 0.5 mm, a band of the span) and blank.ply (a smooth 0.1–0.5 mm offset,
    measured every 0.5 mm on its own jittered grid, 3 mm longer at both ends), with the exact allowance."""
    d = tmp_path_factory.mktemp("routes")
    blade = twisted_blade()
    u, z = blade.model_grid(0.5, (20, 40), stagger=0.37)
    p, v = blade.point(u, z), blade.normal(u, z)
    offset = parts.smooth_offset(blade)
    blank = blade.sample_blank(0.5, (17, 43), offset, np.random.default_rng(11), jitter=0.3)["points"]
    machscan.write_points(d / "model.ply", p, v, dtype="float64")
    machscan.write_points(d / "blank.ply", blank, dtype="float64")
    return d, blade, p, v, blade.truth(u, z, offset), blank


def test_allowance_then_grind_as_the_readme_chains_them(blade_files, capsys):
    d, blade, p, _v, truth, _ = blade_files
    # machscan allowance model.ply blank.ply --out allowance.ply
    assert main(["allowance", str(d / "model.ply"), str(d / "blank.ply"), "--out", str(d / "allowance.ply")]) == 0
    stored = machscan.io.read(d / "allowance.ply")
    a = stored.scalars["allowance"]  # mm, float32 on disk
    np.testing.assert_allclose(stored.points, p, atol=1e-5)
    assert np.abs(a - truth).max() < 0.003  # 2 mm edges every 0.5 mm: µm-exact, float32 rounding included
    # machscan grind allowance.ply --tool-radius 10 --scallop-height 0.01 --removal ... --out grinding/
    out = d / "grinding"
    args = ["grind", str(d / "allowance.ply"), "--tool-radius", "10", "--scallop-height", "0.01", "--removal", REMOVAL]
    assert main([*args, "--section-normal", "0,0,1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "mm/min" in text and "points outside ±0.08 mm" in text
    path = machscan.io.read_toolpath(out / "grind.cl")
    table = np.genfromtxt(out / "path.csv", delimiter=",", names=True)
    # Feeds: the CL file's are mm/min, 60 × the removal model's mm/s for the path point's allowance (held within 3 %).
    wanted = MODEL.feed(table["allowance_mm"])
    assert np.all(np.abs(60.0 * wanted - path.feeds) <= 0.03 * path.feeds + 1e-6)
    np.testing.assert_allclose(path.feeds, table["feed_mm_per_min"], rtol=1e-6)
    assert "FEDRAT/MMPM," in (out / "grind.cl").read_text()
    # The path lies on the blade and carries its allowance.
    assert np.abs(blade.height(path.points)).max() < 0.005
    # Every row crosses the span band once: sections every ~0.8 mm, none cut, none duplicated.
    report = np.genfromtxt(out / "report.csv", delimiter=",", names=True)
    offsets = report["offset_mm"]
    assert len(np.unique(offsets)) == len(offsets) and 15 <= len(offsets) <= 30
    assert np.nanmax(np.abs(np.column_stack([report["deviation_min_mm"], report["deviation_max_mm"]]))) <= 0.08


def test_model_and_blank_to_grind_in_one_step_gives_the_same_path(blade_files):
    d, *_ = blade_files
    if not (d / "grinding" / "grind.cl").exists():
        pytest.skip("needs the allowance → grind route's path")
    out = d / "direct"
    args = ["grind", str(d / "model.ply"), "--blank", str(d / "blank.ply"), "--section-normal", "0,0,1"]
    assert main([*args, "--removal", REMOVAL, "--out", str(out)]) == 0
    one, two = machscan.io.read_toolpath(out / "grind.cl"), machscan.io.read_toolpath(d / "grinding" / "grind.cl")
    # The allowance file holds float32: the two paths agree to its rounding.
    assert one.points.shape == two.points.shape
    assert np.abs(one.points - two.points).max() < 1e-3


def test_allowance_fit_finds_a_clamped_blank_and_writes_its_pose(blade_files, capsys):
    d, _blade, p, v, truth, blank = blade_files
    rng = np.random.default_rng(4)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    r = np.eye(3) + np.sin(np.radians(2.0)) * k + (1 - np.cos(np.radians(2.0))) * k @ k
    c = p.mean(axis=0)
    clamped = (blank - c) @ r.T + c + [1.5, -1.0, 0.8]
    machscan.write_points(d / "clamped.ply", clamped, dtype="float64")
    # machscan allowance model.ply blank.ply --fit --min-allowance 0.1 --out allowance.ply
    out = d / "fit" / "allowance.ply"
    assert main(["allowance", str(d / "model.ply"), str(d / "clamped.ply"), "--fit", "--min-allowance", "0.1",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "coarse" in text and "icp" in text and "envelope" in text and "moved" in text
    pose = np.loadtxt(out.with_name("allowance.pose.txt"))
    a = machscan.io.read(out).scalars["allowance"]
    # The fit's allowance is the allowance of the blank moved by the pose written (translation in mm).
    moved = clamped @ pose[:3, :3].T + pose[:3, 3]
    np.testing.assert_allclose(a, machscan.allowance(p, v, moved), atol=1e-6, equal_nan=True)
    # The blank is only 3 mm longer than the band of the part: the fit may slide it until points of an end row are
    # uncovered (counted by the allowance extrapolated from where they were measured; measured: 42 of 7257), never
    # more than a row (1.2 %).
    assert np.isfinite(a).mean() > 0.988 and np.nanmin(a) >= 0.1 - 1e-6
    # As even as the blank allows: no more uneven than where the blank was made.
    assert np.nanstd(a) <= truth.std() + 0.002


def test_points_route_writes_what_open3d_and_our_reader_read_in_mm(tmp_path):
    scan, _ = synth.groove_scan(seed=3, readings=400, keep_every=400)
    scan.save(tmp_path / "scan.npz")
    points, frame = scan.wcs_points()
    for name in ("cloud.ply", "cloud.xyz", "cloud.csv"):
        assert main(["points", str(tmp_path / "scan.npz"), "--out", str(tmp_path / name)]) == 0
        back = machscan.read_points(tmp_path / name)
        np.testing.assert_allclose(back, points, atol=1e-4 if name.endswith("ply") else 1e-12)
    cloud = machscan.io.read(tmp_path / "cloud.ply")
    np.testing.assert_array_equal(cloud.scalars["frame"], frame)


@pytest.fixture(scope="module")
def own_contours(tmp_path_factory):
    """A scan of an engraving no built-in layout has (three contours, a rotated slot among them), its CAD file."""
    d = tmp_path_factory.mktemp("grooves")
    shapes = [
        synth.ContourShape("circle", (60.0, 70.0), (14.0, 14.0), 14.0),
        synth.ContourShape("slot", (120.0, 60.0), (30.0, 9.0), 9.0, angle=0.6),
        synth.ContourShape("rounded_rectangle", (90.0, 140.0), (35.0, 18.0), 6.0, angle=-0.3),
    ]
    scan, truth = synth.groove_scan(seed=21, readings=800, keep_every=100, contours=shapes, bend=0.2)
    scan.save(d / "scan.npz")
    from machscan.cad import write_contours_csv

    write_contours_csv(d / "cad.csv", truth.nominal_polylines)
    return d, scan, truth


def test_grooves_route_measures_the_truth(own_contours):
    d, scan, truth = own_contours
    # machscan grooves scan.npz cad.csv --out tables/
    assert main(["grooves", str(d / "scan.npz"), str(d / "cad.csv"), "--out", str(d / "tables")]) == 0
    frames = np.genfromtxt(d / "tables" / "frames.csv", delimiter=",", names=True)
    ok = frames["status"] == 0
    assert ok.mean() > 0.95
    assert np.median(np.abs(frames["width_mm"][ok] - truth.width[ok])) < 0.010
    errors = np.genfromtxt(d / "tables" / "contour_errors.csv", delimiter=",", names=True)
    assert len(errors) == 4  # three contours and the overall row
    # The building block on the report's inputs gives the table's figure.
    report = machscan.inspect_grooves(scan, truth.nominal_polylines)
    for row, c in zip(errors[:-1], report.contours):
        centers = report.center_wcs[report.contour == c.cad_index]
        assert machscan.contour_error(c.theoretical, centers).mean == pytest.approx(row["error_mean_mm"], rel=1e-9)


def test_batch_route_gives_each_scans_tables(own_contours, tmp_path):
    pytest.importorskip("distributed")
    d, scan, _ = own_contours
    import machscan.dask

    scans = tmp_path / "scans"
    scans.mkdir()
    machscan.dask.save_scan(scan, scans / "a.zarr")
    machscan.dask.save_scan(scan.select(slice(0, len(scan.frames) // 2)), scans / "b.zarr")
    # machscan batch grooves scans/*.zarr --cad cad.csv --workers 2 --out batch/
    args = ["batch", "grooves", str(scans / "a.zarr"), str(scans / "b.zarr"), "--cad", str(d / "cad.csv")]
    code = main([*args, "--workers", "2", "--out", str(tmp_path / "batch"), "--no-progress"])
    assert code in (0, 3)
    table = np.genfromtxt(tmp_path / "batch" / "batch.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert len(table) == 2
    single = np.genfromtxt(d / "tables" / "contour_errors.csv", delimiter=",", names=True) if (
        d / "tables" / "contour_errors.csv"
    ).exists() else None
    mine = np.genfromtxt(tmp_path / "batch" / "a" / "contour_errors.csv", delimiter=",", names=True)
    if single is not None:
        np.testing.assert_allclose(mine["error_mean_mm"], single["error_mean_mm"], rtol=1e-12)


def test_compensate_route_from_the_files_its_simulation_writes(tmp_path):
    # machscan compensate theoretical.ply scan.ply path.cl --locating loc.csv --matching match.csv --out comp/
    sim = tmp_path / "sim"
    assert main(["compensate", "--simulate", "--out", str(sim), "--scan-spacing", "6", "--jacobian", "gradient"]) == 0
    args = [str(sim / "theoretical.ply"), str(sim / "scan.ply"), str(sim / "theoretical.cl")]
    args += ["--locating", str(sim / "locating.csv"), "--matching", str(sim / "matching.csv")]
    assert main(["compensate", *args, "--out", str(tmp_path / "comp"), "--jacobian", "gradient"]) == 0
    before = machscan.io.read_toolpath(sim / "theoretical.cl")
    after = machscan.io.read_toolpath(tmp_path / "comp" / "compensated.cl")
    # Feeds and segments carried over in mm/min; the report's lengths in mm match the CL files.
    np.testing.assert_array_equal(after.feeds, before.feeds)
    report = np.genfromtxt(tmp_path / "comp" / "report.csv", delimiter=",", names=True)
    np.testing.assert_allclose(report["moved_mm"], np.linalg.norm(after.points - before.points, axis=1), atol=1e-6)


def test_points_without_stock_pass_from_allowance_to_grind_and_are_counted(tmp_path, capsys):
    # Issue #32 §2: `machscan allowance` leaves NaN where the blank does not cover the model; `machscan grind` reads
    # it (PLY and CSV alike), leaves those points out, says how many, and counts them per row in report.csv.
    cloud = synth.WavyPanel(width=20.0, length=30.0).sample(0.5, seed=5)
    a = cloud.allowance.copy()
    hole = np.linalg.norm(cloud.points[:, :2] - [10.0, 15.0], axis=1) < 2.0
    a[hole] = np.nan
    for name in ("allowance.ply", "allowance.csv"):
        src = tmp_path / name
        if name.endswith(".ply"):
            machscan.write_points(src, cloud.points, cloud.normals, scalars={"allowance": a}, dtype="float64")
        else:
            np.savetxt(src, np.column_stack([cloud.points, cloud.normals, a]), delimiter=",",
                       header="x_mm,y_mm,z_mm,nx,ny,nz,allowance_mm", comments="")
        out = tmp_path / name.replace(".", "_")
        code = main(["grind", str(src), "--section-normal", "0,1,0", "--tool-radius", "8", "--out", str(out)])
        assert code in (0, 3)
        assert f"{int(hole.sum())} model points have no allowance" in capsys.readouterr().out
        report = np.genfromtxt(out / "report.csv", delimiter=",", names=True)
        assert int(report["no_stock_points"].sum()) == int(hole.sum())


def test_a_cad_meshs_stl_as_the_model_is_sampled_and_its_allowance_feeds_grind(tmp_path, capsys):
    # The model as a CAD mesher writes it: the stadium prism (flats one triangle across, half circles of 1.5 mm cut
    # every 10°). Its vertices alone leave the flats without a point (the allowance there unknown, the grinding rows
    # nothing to follow); the surface is sampled every 0.15 mm instead (half the blank's spacing, at most 0.15 mm),
    # with normals interpolated from the corners. Blank every 1 mm (edges of 1.5 spacings: the hardest),
    # offset 0.3 mm.
    vertices, triangles = parts.stadium_mesh()
    machscan.io.write_mesh(tmp_path / "model.stl", vertices, triangles)
    rng = np.random.default_rng(4)
    perimeter = 4 * 5.0 + 2 * np.pi * 1.5
    s, z = np.meshgrid(np.arange(0, perimeter, 1.0), np.arange(-3, 23, 1.0))
    s, z = s + rng.uniform(-0.3, 0.3, s.shape), z + rng.uniform(-0.3, 0.3, z.shape)
    surface, normal = parts.stadium(s.ravel(), z.ravel())
    machscan.write_points(tmp_path / "blank.ply", surface + 0.3 * normal, dtype="float64")
    # machscan allowance model.stl blank.ply --out allowance.ply
    assert main(["allowance", str(tmp_path / "model.stl"), str(tmp_path / "blank.ply"), "--out", str(tmp_path / "a.ply")]) == 0
    assert "is a mesh" in capsys.readouterr().out
    stored = machscan.io.read(tmp_path / "a.ply")
    p, v, a = stored.points, stored.normals, stored.scalars["allowance"]
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    on_flats = (np.abs(p[:, 0]) < 4.5) & (p[:, 2] > 1) & (p[:, 2] < 19)
    assert on_flats.sum() > 500  # the flats have points now (the mesh's vertices put none inside them)
    np.testing.assert_allclose(machscan.mesh.closest_points(vertices, triangles, p).distances, 0.0, atol=1e-5)
    inner = (p[:, 2] > 2) & (p[:, 2] < 18)
    truth = parts.stadium_offset_distance(p, v, 0.3)
    # Measured: 6.5 µm (the chords lie up to 5.7 µm inside the arcs, the normals are the arc's); float32 on disk.
    assert not np.isnan(a[inner]).any() and np.abs(a - truth)[inner].max() < 0.010
    # machscan grind allowance.ply --tool-radius 10 --scallop-height 0.01 --removal ... --out grinding/
    out = tmp_path / "grinding"
    args = ["grind", str(tmp_path / "a.ply"), "--tool-radius", "10", "--scallop-height", "0.01", "--removal", REMOVAL]
    assert main([*args, "--out", str(out)]) == 0
    report = np.genfromtxt(out / "report.csv", delimiter=",", names=True)
    offsets = report["offset_mm"]
    assert len(np.unique(offsets)) == len(offsets) and report["closed"].all()  # whole rows round the prism
    assert np.nanmax(np.abs(np.column_stack([report["deviation_min_mm"], report["deviation_max_mm"]]))) <= 0.03
