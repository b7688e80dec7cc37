"""The command line and the CAD contour readers."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import machscan
from machscan import synth
from machscan.cad import read_contours, read_contours_apt, read_contours_csv, write_contours_csv
from machscan.cli import main
from machscan.inspection import inspect_grooves

# The `machscan` command of the environment under test (the one pip installed beside this
# interpreter), not whichever one PATH finds first: on a fresh machine PATH may have none.
MACHSCAN = str(Path(sys.executable).with_name("machscan"))


def test_help_and_version():
    out = subprocess.run([sys.executable, "-m", "machscan", "--help"], capture_output=True, text=True, check=True)
    assert "demo" in out.stdout and "grooves" in out.stdout
    out = subprocess.run([MACHSCAN, "--version"], capture_output=True, text=True, check=True)
    assert machscan.__version__ in out.stdout


def test_import_loads_no_optional_dependency():
    # What makes `import machscan` slow is an optional library pulled in at import (matplotlib, Dask,
    # SciPy): they load on first use of the module that needs them. The check is of what is imported,
    # not of a time (this machine is shared).
    optional = ("matplotlib", "dask", "distributed", "zarr", "scipy", "open3d", "tqdm", "laspy", "trimesh")
    code = f"import sys, machscan; print(' '.join(m for m in {optional!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_demo_prints_both_tables(tmp_path):
    out = subprocess.run([MACHSCAN, "demo", "--out", str(tmp_path / "d")], capture_output=True, text=True, check=True)
    assert "width (mm)" in out.stdout and "error (mm)" in out.stdout and "shares of the error" in out.stdout
    assert "robust sigma" in out.stdout
    for name in ("frames.csv", "widths.csv", "contour_errors.csv", "cloud.ply"):
        assert (tmp_path / "d" / name).stat().st_size > 0
    with open(tmp_path / "d" / "cloud.ply", "rb") as fh:
        assert fh.read(60).startswith(b"ply\nformat binary_little_endian 1.0")


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    scan, truth = synth.groove_scan(seed=5, readings=800, keep_every=100)
    scan.save(d / "scan.npz")
    write_contours_csv(d / "cad.csv", truth.nominal_polylines)
    return d, scan, truth


def test_grooves_command_equals_the_library(small):
    d, scan, truth = small
    assert main(["grooves", str(d / "scan.npz"), str(d / "cad.csv"), "--out", str(d / "out")]) == 0
    ref = inspect_grooves(scan, truth.nominal_polylines)
    rows = np.genfromtxt(d / "out" / "contour_errors.csv", delimiter=",", names=True)
    np.testing.assert_allclose(rows["error_mean_mm"][:-1], [c.error.mean for c in ref.contours], rtol=1e-12)


def test_grooves_command_selects_the_groove_asked_for(small):
    d, scan, truth = small
    args = ["--select", "nearest", "--near", "0.0", "--max-width", "0.7"]
    assert main(["grooves", str(d / "scan.npz"), str(d / "cad.csv"), *args, "--out", str(d / "near")]) == 0
    ref = inspect_grooves(scan, truth.nominal_polylines, select="nearest", near=0.0, max_width=0.7)
    rows = np.genfromtxt(d / "near" / "contour_errors.csv", delimiter=",", names=True)
    np.testing.assert_allclose(rows["error_mean_mm"][:-1], [c.error.mean for c in ref.contours], rtol=1e-12)
    # Tolerances: pass / fail per frame, in tolerance, Cp and Cpk per contour.
    tol = ["--width-tolerance", "0.47", "0.49", "--depth-tolerance", "0.29", "0.33"]
    assert main(["grooves", str(d / "scan.npz"), str(d / "cad.csv"), *tol, "--out", str(d / "tol")]) == 0
    widths = np.genfromtxt(d / "tol" / "widths.csv", delimiter=",", names=True)
    ref = inspect_grooves(scan, truth.nominal_polylines, width_tolerance=(0.47, 0.49), depth_tolerance=(0.29, 0.33))
    np.testing.assert_allclose(widths["width_cpk"][:-1], [r["width_cpk"] for r in ref.width_depth_rows()[:-1]], rtol=1e-9)
    # Every groove of the window: frames.csv gets a row per groove, its frame and groove named.
    assert main(["grooves", str(d / "scan.npz"), str(d / "cad.csv"), "--select", "all", "--out", str(d / "all")]) == 0
    rows = np.genfromtxt(d / "all" / "frames.csv", delimiter=",", names=True)
    assert np.all(np.diff(rows["frame"]) >= 0) and rows["groove"].max() >= 0


def test_grooves_command_settles_the_tip_rounding_as_asked(small, capsys):
    d, scan, truth = small
    for rule in ("pooled", "frame"):
        out = d / f"rounding_{rule}"
        assert main(["grooves", str(d / "scan.npz"), str(d / "cad.csv"), "--rounding", rule, "--out", str(out)]) == 0
        ref = inspect_grooves(scan, truth.nominal_polylines, rounding=rule)
        rows = np.genfromtxt(out / "frames.csv", delimiter=",", names=True)
        np.testing.assert_allclose(rows["depth_mm"], ref.fits.depth, atol=1e-9)  # CSV: 0.1 nm
        # The prior a pooled call used is printed with its units.
        printed = capsys.readouterr().out
        assert ("V tip rounding prior" in printed) == (ref.fits.rounding_prior is not None)
    assert inspect_grooves(scan, truth.nominal_polylines).fits.rounding_prior is not None


def test_grooves_command_takes_the_misfit_rule_as_asked(small):
    d, scan, truth = small
    for rule in ("pooled", "none"):
        out = d / f"misfit_{rule}"
        assert main(["grooves", str(d / "scan.npz"), str(d / "cad.csv"), "--misfit", rule, "--out", str(out)]) == 0
        ref = inspect_grooves(scan, truth.nominal_polylines, misfit=rule)
        assert (ref.fits.misfit is None) == (rule == "none")
        rows = np.genfromtxt(out / "frames.csv", delimiter=",", names=True)
        np.testing.assert_allclose(rows["se_depth_mm"], ref.fits.se_depth, atol=1e-9)


def test_grooves_command_fits_the_template_asked_for(small):
    d, scan, truth = small
    out = d / "out_tanh"
    assert (
        main(
            [
                "grooves",
                str(d / "scan.npz"),
                str(d / "cad.csv"),
                "--template",
                "tanh",
                "--alpha",
                "25",
                "--max-se-ratio",
                "5",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    ref = inspect_grooves(scan, truth.nominal_polylines, template="tanh", alpha=25.0, max_se_ratio=5.0)
    rows = np.genfromtxt(out / "frames.csv", delimiter=",", names=True)
    np.testing.assert_array_equal(rows["model"], ref.fits.model)
    assert set(rows["model"][ref.fits.ok]) == {machscan.GrooveModel.TANH}
    np.testing.assert_array_equal(rows["suspect"], ref.suspect)
    np.testing.assert_allclose(rows["width_mm"], ref.fits.width, rtol=1e-9)
    with pytest.raises(SystemExit):
        main(["grooves", str(d / "scan.npz"), str(d / "cad.csv"), "--template", "gaussian"])


def test_grooves_command_on_a_csv_scan_and_apt_contours(small):
    d, scan, truth = small
    machscan.write_scan_csv(scan, d / "frames.csv", d / "poses.csv")
    apt = d / "cad.apt"
    with open(apt, "w") as fh:
        fh.write("PARTNO/ TEMPLATE $$ engraving program\nMULTAX\n")
        for c in truth.nominal_polylines:
            fh.write("RAPID\n")
            for x, y, z in np.asarray(c):
                fh.write(f"GOTO/{x:.6f},{y:.6f}, $\n  {z:.6f},0.0,0.0,1.0\n")
        fh.write("FINI\n")
    args = [
        "grooves",
        str(d / "frames.csv"),
        str(apt),
        "--poses",
        str(d / "poses.csv"),
        "--pitch",
        str(scan.profiler.pitch),
        "--c2-offset",
        *map(str, scan.c2_offset),
        "--mount",
        *map(str, scan.mount),
        "--sentinel",
        str(scan.profiler.sentinel),
        "--valid-range",
        *map(str, scan.profiler.valid_range),
        "--out",
        str(d / "out2"),
    ]
    assert main(args) == 0
    rows = np.genfromtxt(d / "out2" / "widths.csv", delimiter=",", names=True)
    assert len(rows) == len(truth.nominal_polylines) + 1


def test_grooves_command_reports_errors(small, capsys):
    d, _scan, _truth = small
    assert main(["grooves", str(d / "frames.csv"), str(d / "cad.csv")]) == 2
    assert "--poses" in capsys.readouterr().err


def test_cad_csv_layouts(tmp_path):
    sq = np.array([[0, 0, 0], [10, 0, 0], [10, 5, 0], [0, 5, 0.0]])
    (tmp_path / "xy.csv").write_text("x,y\n" + "\n".join(f"{x},{y}" for x, y, _ in sq))
    (tmp_path / "xyz.csv").write_text("\n".join(f"{x},{y},{z}" for x, y, z in sq))
    (tmp_path / "ids.csv").write_text("contour,x,y\n" + "\n".join(f"{k // 2},{x},{y}" for k, (x, y, _) in enumerate(sq)))
    np.testing.assert_array_equal(read_contours_csv(tmp_path / "xy.csv")[0], sq)
    np.testing.assert_array_equal(read_contours_csv(tmp_path / "xyz.csv")[0], sq)
    two = read_contours_csv(tmp_path / "ids.csv")
    assert len(two) == 2 and np.array_equal(two[1], sq[2:])
    write_contours_csv(tmp_path / "rt.csv", [sq, sq + 1])
    back = read_contours([tmp_path / "rt.csv"])
    assert len(back) == 2 and np.array_equal(back[1], sq + 1)


def test_apt_reader_splits_on_rapid_and_jumps(tmp_path):
    text = """$$ comment line
PARTNO/ DEMO
GOTO/0,0,0
GOTO/1,0,0, $
   0,0,1
FEDRAT/ 1200
GOTO/1,1,0
RAPID
GOTO/50,50,0
GOTO/51,50,0
GOTO/100,100,0
GOTO/101,100,0
"""
    (tmp_path / "p.apt").write_text(text)
    c = read_contours_apt(tmp_path / "p.apt")
    assert [len(x) for x in c] == [3, 2, 2]
    np.testing.assert_array_equal(c[0][1], [1, 0, 0])


@pytest.mark.parametrize(
    "name, text, msg",
    [
        ("bad.csv", "x,y,z\n1,2,3\n4,five,6\n", "line 3"),
        ("ragged.csv", "1,2,3\n4,5\n", "line 2"),
        ("empty.csv", "x,y\n", "no points"),
        ("bad.apt", "GOTO/1,2\n", "line 1"),
        ("none.apt", "PARTNO/X\nFINI\n", "no GOTO"),
    ],
)
def test_malformed_cad_files_name_the_file(tmp_path, name, text, msg):
    (tmp_path / name).write_text(text)
    with pytest.raises(ValueError) as exc:
        read_contours([tmp_path / name])
    assert name in str(exc.value) and msg in str(exc.value)


def test_cad_in_the_wrong_unit_says_how_far_and_exits_non_zero(small, capsys):
    d, scan, truth = small
    write_contours_csv(d / "cad_inch.csv", [np.asarray(c) / 25.4 for c in truth.nominal_polylines])
    assert main(["grooves", str(d / "scan.npz"), str(d / "cad_inch.csv"), "--out", str(d / "inch")]) == 3
    captured = capsys.readouterr()
    assert "max_match_distance = 10 mm" in captured.out and "nearest CAD contour centroid is" in captured.err
    report = inspect_grooves(scan, [np.asarray(c) / 25.4 for c in truth.nominal_polylines])
    assert report.contours == () and report.nearest_cad_distance.min() > 10.0
    assert "nearest CAD contour centroid" in report.matching_problem()


def test_an_unknown_no_reading_code_is_warned_about(small, tmp_path, capsys):
    _d, scan, _truth = small
    frames = scan.frames.copy()
    frames[~scan.valid_mask()] = -9999.0  # another vendor's code, not the default sentinel
    other = machscan.Scan(
        frames,
        scan.poses,
        scan.frame_times,
        machscan.Profiler(readings=scan.n_readings, pitch=scan.profiler.pitch),
        scan.c2_offset,
        scan.mount,
    )
    frames[:, :100] = -9999.0  # and a stretch the sensor never saw
    other = machscan.Scan(frames, scan.poses, scan.frame_times, other.profiler, scan.c2_offset, scan.mount)
    other.save(tmp_path / "other.npz")
    assert main(["points", str(tmp_path / "other.npz"), "--out", str(tmp_path / "c.ply")]) == 0
    err = capsys.readouterr().err
    assert "-9999.0" in err and "--sentinel" in err


def test_points_drop_the_vendor_sentinel_by_default(small, tmp_path, capsys):
    _d, scan, _ = small
    bare = machscan.Scan(
        scan.frames,
        scan.poses,
        scan.frame_times,
        machscan.Profiler(readings=scan.n_readings, pitch=scan.profiler.pitch),
        scan.c2_offset,
        scan.mount,
    )
    bare.save(tmp_path / "bare.npz")
    assert main(["points", str(tmp_path / "bare.npz"), "--out", str(tmp_path / "c.ply")]) == 0
    out = capsys.readouterr().out
    n_sentinel = int((scan.frames == machscan.SENTINEL).sum())
    assert n_sentinel > 0 and f"dropped   : {int((~np.isfinite(scan.frames)).sum()) + n_sentinel:,}" in out
    assert machscan.read_points(tmp_path / "c.ply")[:, 2].min() > -1000


# ---- position and allowance (issue #9 §5) ---------------------------------------------------


def test_position_simulate_prints_the_rounds(capsys):
    assert main(["position", "--simulate"]) == 0
    out = capsys.readouterr().out
    assert "round" in out and "µm RMS along the normals" in out


def test_position_plan_then_fit_equals_the_library(tmp_path, capsys):
    # The plant's loop through files: plan → probe cycle (the simulator here) → fit → next plan.
    blade = synth.Blade()
    points, normals = blade.sample(120, 60)
    model = tmp_path / "model.ply"
    machscan.write_points(model, points.reshape(-1, 3), normals=normals.reshape(-1, 3))
    truth = synth.misplacement(1, center=points.reshape(-1, 3).mean(axis=0))
    probe = synth.TouchProbe(blade, truth, radius=1.5, noise=0.002, seed=1)
    plan = tmp_path / "plan.csv"
    assert main(["position", str(model), "--plan", str(plan)]) == 0
    rows = np.loadtxt(plan, delimiter=",", skiprows=1)
    measured = tmp_path / "probed.csv"
    np.savetxt(measured, probe(rows[:, 1:4], rows[:, 4:7]), delimiter=",", header="x,y,z", comments="")
    pose, nxt = tmp_path / "pose.txt", tmp_path / "next.csv"
    args = ["position", str(model), "--plan", str(plan), "--measured", str(measured), "--probe-radius", "1.5"]
    assert main([*args, "--out", str(pose), "--next-plan", str(nxt)]) == 0
    assert "e_total" in capsys.readouterr().out
    stored = machscan.io.read(model)  # as the command reads it (float32 in a PLY)
    expected = machscan.registration.probe_round(
        stored.points,
        stored.normals,
        rows[:, 0].astype(int),
        np.eye(4),
        np.loadtxt(measured, delimiter=",", skiprows=1),
        probe_radius=1.5,
    )
    np.testing.assert_allclose(np.loadtxt(pose), expected.transformation, atol=1e-9)
    assert np.abs(np.loadtxt(pose) - truth).max() < 0.02  # one round from 0.5 mm / 0.5° off: µm left
    assert np.loadtxt(nxt, delimiter=",", skiprows=1).shape == rows.shape


@pytest.mark.parametrize("suffix", [".ply", ".pcd", ".csv"])
def test_allowance_command_writes_a_scalar_field_open3d_reads(tmp_path, capsys, suffix):
    open3d = pytest.importorskip("open3d")
    blade = synth.Blade()
    points, normals = blade.sample(80, 20)
    u, v = np.meshgrid(np.arange(400) / 400, np.linspace(0, 1, 120), indexing="ij")
    s, n = blade.surface(u, v)
    blank = (s + 0.2 * n).reshape(-1, 3)
    model, blank_file = tmp_path / "model.ply", tmp_path / "blank.xyz"
    machscan.write_points(model, points.reshape(-1, 3), normals=normals.reshape(-1, 3))
    machscan.write_points(blank_file, blank)
    out = tmp_path / f"allowance{suffix}"
    # (-1 mm: the thin trailing edge of the coarse model has planes across both faces.)
    assert main(["allowance", str(model), str(blank_file), "--out", str(out), "--min-allowance", "-1"]) == 0
    assert "allowance (mm)" in capsys.readouterr().out
    stored = machscan.io.read(model)
    expected = machscan.allowance(stored.points, stored.normals, machscan.read_points(blank_file))
    if suffix == ".csv":
        back = np.loadtxt(out, delimiter=",", skiprows=1)[:, 6]
    else:
        cloud = open3d.t.io.read_point_cloud(str(out))
        back = cloud.point["allowance"].numpy().reshape(-1)
    np.testing.assert_allclose(back, expected, atol=1e-6, equal_nan=True)
    # Asking for more stock than there is: reported with exit status 3.
    assert main(["allowance", str(model), str(blank_file), "--out", str(out), "--min-allowance", "0.5"]) == 3


def test_an_stl_model_is_read_with_outward_vertex_normals(tmp_path, capsys):
    # A CAD model as a mesh: its surface is sampled, normals from its corners (the area-weighted normals of the
    # faces round each vertex, outward for a consistently wound mesh), so the allowance is that of the true normals.
    blade = synth.Blade()
    points, _ = blade.sample(120, 30)
    idx = np.arange(120 * 30).reshape(120, 30)
    nxt = np.roll(idx, -1, axis=0)
    tri = np.concatenate(
        [
            np.stack([idx[:, :-1], idx[:, 1:], nxt[:, :-1]], -1).reshape(-1, 3),
            np.stack([idx[:, 1:], nxt[:, 1:], nxt[:, :-1]], -1).reshape(-1, 3),
        ]
    )
    stl, blank_file, out = tmp_path / "blade.stl", tmp_path / "blank.xyz", tmp_path / "a.csv"
    machscan.write_mesh(stl, points.reshape(-1, 3), tri)
    u, v = np.meshgrid(np.arange(900) / 900, np.linspace(0, 1, 300), indexing="ij")
    s, n = blade.surface(u, v)
    machscan.write_points(blank_file, (s + 0.2 * n).reshape(-1, 3))
    assert main(["allowance", str(stl), str(blank_file), "--out", str(out), "--min-allowance", "-1"]) == 0
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    # The model is the mesh's surface sampled (half the blank's spacing, at most 0.15 mm), each point on a triangle
    # with a normal interpolated from its corners: outward, as the triangle's own.
    vertices = points.reshape(-1, 3)
    on = machscan.mesh.closest_points(vertices, tri, table[:, :3])
    assert on.distances.max() < 1e-5
    a, b, c = (vertices[tri[on.triangles, k]] for k in range(3))
    face = np.cross(b - a, c - a)
    face /= np.linalg.norm(face, axis=1, keepdims=True)
    cos = np.einsum("ij,ij->i", table[:, 3:6] / np.linalg.norm(table[:, 3:6], axis=1, keepdims=True), face)
    assert np.median(cos) > 0.999 and cos.min() > 0.85  # outward; round the edges the corners' normals turn
    # The facets lie under the blade (a 120 × 30 mesh), so the stock over a sampled point is 0.2 mm plus the facet's
    # depth there, measured on the blade's own surface (the blank's grid, triangulated).
    grid = np.arange(900 * 300).reshape(900, 300)
    after = np.roll(grid, -1, axis=0)
    dense = np.concatenate(
        [
            np.stack([grid[:, :-1], grid[:, 1:], after[:, :-1]], -1).reshape(-1, 3),
            np.stack([grid[:, 1:], after[:, 1:], after[:, :-1]], -1).reshape(-1, 3),
        ]
    )
    depth = machscan.mesh.closest_points(s.reshape(-1, 3), dense, table[:, :3]).distances
    assert np.median(depth) > 1e-3  # the facets' depth is what the figure below accounts for
    assert np.nanmedian(np.abs(table[:, 6] - (0.2 + depth))) < 1e-3
    plan = tmp_path / "plan.csv"
    assert main(["position", str(stl), "--plan", str(plan)]) == 0
    assert np.loadtxt(plan, delimiter=",", skiprows=1).shape == (160, 7)


def test_compensate_simulate_then_from_its_files_equals_the_library(tmp_path, capsys):
    # The simulated skin writes its inputs; the file-based command on them gives the same CL file, and both
    # equal the library's match and compensation of the same data.
    sim = tmp_path / "sim"
    assert main(["compensate", "--simulate", "--out", str(sim), "--scan-spacing", "6", "--jacobian", "gradient"]) == 0
    out = capsys.readouterr().out
    assert "truth" in out and "less" in out
    files = tmp_path / "files"
    args = [
        str(sim / "theoretical.ply"),
        str(sim / "scan.ply"),
        str(sim / "theoretical.cl"),
        "--locating",
        str(sim / "locating.csv"),
        "--matching",
        str(sim / "matching.csv"),
        "--out",
        str(files),
        "--jacobian",
        "gradient",
    ]
    assert main(["compensate", *args]) == 0
    a = machscan.io.read_toolpath(sim / "compensated.cl")
    b = machscan.io.read_toolpath(files / "compensated.cl")
    # The PLY files hold float32 points, so the file run sees the data rounded to ~1 µm.
    assert np.abs(a.points - b.points).max() < 0.005
    np.testing.assert_array_equal(a.segments, b.segments)
    np.testing.assert_array_equal(a.feeds, b.feeds)
    theoretical = machscan.read_points(sim / "theoretical.ply")
    scan = machscan.read_points(sim / "scan.ply")
    loc = np.loadtxt(sim / "locating.csv", delimiter=",", skiprows=1)
    grid = np.loadtxt(sim / "matching.csv", delimiter=",", skiprows=1)
    m = machscan.isometric_match(theoretical, scan, loc[:, :3], loc[:, 3:], grid, jacobian="gradient")
    tp = machscan.io.read_toolpath(sim / "theoretical.cl")
    p = machscan.compensate_toolpath(tp, grid, m.points, scan)
    np.testing.assert_allclose(b.points, p.points, atol=1e-9)
    report = np.loadtxt(files / "report.csv", delimiter=",", skiprows=1)
    assert report.shape == (len(tp.points), 13) and report[:, -2:].all()  # inside, on_scan
    # Tables without a header line read the same (review, session 15: their first point was dropped); a match
    # that ends above --max-error is warned about and exits 3.
    for name in ("locating.csv", "matching.csv"):
        lines = (sim / name).read_text().splitlines(keepends=True)
        (tmp_path / name).write_text("".join(lines[1:]))
    bare = [*args[:3], "--locating", str(tmp_path / "locating.csv"), "--matching", str(tmp_path / "matching.csv")]
    capsys.readouterr()
    assert main(["compensate", *bare, "--out", str(tmp_path / "bare"), "--jacobian", "gradient", "--max-error", "1e-9"]) == 3
    assert "above --max-error" in capsys.readouterr().err
    np.testing.assert_array_equal(machscan.io.read_toolpath(tmp_path / "bare" / "compensated.cl").points, b.points)


def test_compensate_names_a_missing_argument_and_a_bad_table(tmp_path, capsys):
    assert main(["compensate", "a.ply"]) == 2
    assert "--locating" in capsys.readouterr().err
    grid = synth.BentSkin(length=40.0, width=30.0).grid(2.0)
    machscan.write_points(tmp_path / "t.ply", grid)
    machscan.io.write_toolpath(tmp_path / "t.cl", grid[:5])
    bad = tmp_path / "loc.csv"
    bad.write_text("x,y,z\n1,2,3\n4,5,6\n")
    args = [
        str(tmp_path / "t.ply"),
        str(tmp_path / "t.ply"),
        str(tmp_path / "t.cl"),
        "--locating",
        str(bad),
        "--matching",
        str(bad),
    ]
    assert main(["compensate", *args]) == 2
    assert "--locating" in capsys.readouterr().err
    # Review (session 15): errors name the option or the file, not NumPy's or the library's argument.
    missing = f"No such file or directory: '{tmp_path / 'none.csv'}'"
    for table, says in ((tmp_path / "none.csv", missing), (tmp_path / "empty.csv", "holds no rows")):
        if table.name == "empty.csv":
            table.write_text("x,y,z,ax,ay,az\n")
        assert main(["compensate", *args[:3], "--locating", str(table), "--matching", str(bad)]) == 2
        assert says in capsys.readouterr().err
    noisy = grid.copy()
    noisy[5, 2] = np.nan
    np.savetxt(tmp_path / "nan.xyz", noisy)
    assert main(["compensate", args[0], str(tmp_path / "nan.xyz"), *args[2:]]) == 2
    assert "SCAN: " in capsys.readouterr().err
    for option in ("--scan-spacing", "--max-error"):
        assert main(["compensate", "--simulate", option, "nan", "--out", str(tmp_path / "s")]) == 2
        assert option in capsys.readouterr().err
    for spacing in ("fine", "0"):
        with pytest.raises(SystemExit) as exit_:
            main(["compensate", "--simulate", "--mesh-spacing", spacing])
        assert exit_.value.code == 2 and "--mesh-spacing" in capsys.readouterr().err


def test_grind_writes_the_path_table_and_report_from_an_allowance_file(tmp_path, capsys):
    panel = synth.WavyPanel(width=20.0, length=30.0)
    cloud = panel.sample(0.5, seed=4)
    source = tmp_path / "allowance.ply"
    machscan.io.write_points(source, cloud.points, normals=cloud.normals, scalars={"allowance": cloud.allowance})
    out = tmp_path / "grinding"
    removal = "0.05,0.6,-0.7,0.8,20,15,0.5,200"
    args = ["grind", str(source), "--section-normal", "0,1,0", "--tool-radius", "8", "--removal", removal, "--out", str(out)]
    assert main(args) == 0
    assert "rows" in capsys.readouterr().out
    path = machscan.io.read_toolpath(out / "grind.cl")
    table = np.loadtxt(out / "path.csv", delimiter=",", skiprows=1)
    assert np.abs(path.points - table[:, :3]).max() < 1e-4
    np.testing.assert_allclose(path.feeds, table[:, 9], rtol=1e-6)
    expected = machscan.grinding_paths(
        cloud.points, cloud.normals, cloud.allowance, 8.0, 0.01, (0, 1, 0), removal_model=machscan.RemovalModel.of(
            dict(C=0.05, exponents=(0.6, -0.7, 0.8), belt_speed=20.0, force=15.0, feed_limits=(0.5, 200.0))
        )
    )
    assert len(table) == len(expected.points)
    report = np.loadtxt(out / "report.csv", delimiter=",", skiprows=1)
    assert len(report) == len(expected.row_offsets) and np.abs(report[:, 4:]).max() <= 0.08
    # The CSV form of `machscan allowance` reads the same.
    csv = tmp_path / "allowance.csv"
    np.savetxt(csv, np.column_stack([cloud.points, cloud.normals, cloud.allowance]), delimiter=",", header="x,y,z,nx,ny,nz,a")
    assert main(["grind", str(csv), "--section-normal", "0,1,0", "--tool-radius", "8", "--out", str(tmp_path / "g2")]) == 0


def test_grind_refuses_a_malformed_removal_model_and_a_file_without_allowance(tmp_path, capsys):
    src = tmp_path / "bare.ply"
    machscan.io.write_points(src, np.random.default_rng(0).random((50, 3)))
    assert main(["grind", str(src), "--out", str(tmp_path / "o")]) == 2
    assert "allowance" in capsys.readouterr().err
    assert main(["grind", "--simulate", "--removal", "1,2,3", "--out", str(tmp_path / "o")]) == 2
    assert "--removal" in capsys.readouterr().err


def test_grind_simulate_runs_on_the_built_in_blade(tmp_path, capsys):
    assert main(["grind", "--simulate", "--spacing", "1.0", "--band", "0.5", "--out", str(tmp_path / "b")]) == 0
    text = capsys.readouterr().out
    assert "simulated blade" in text and "stock left" in text


def test_grind_refuses_a_path_whose_simulated_pass_leaves_the_band(tmp_path, capsys):
    # Issue #32 §5: the slowest feed allowed removes far more than the stock (0.6 mm/s removes ~3.8 mm): every
    # pass over-cuts. grind.cl is not written (and an earlier run's is removed), the report names points and rows;
    # --force writes it, still exit 3.
    cloud = synth.WavyPanel().sample(1.0, seed=4)
    source = tmp_path / "allowance.ply"
    machscan.io.write_points(source, cloud.points, cloud.normals, scalars={"allowance": cloud.allowance}, dtype="float64")
    out = tmp_path / "grinding"
    out.mkdir()
    (out / "grind.cl").write_text("GOTO/0,0,0\n")  # an earlier run's path
    args = ["grind", str(source), "--section-normal", "0,1,0", "--tool-radius", "8", "--out", str(out)]
    args += ["--removal", "0.05,0.6,-0.7,0.8,20,15,0.5,0.6"]
    assert main(args) == 3
    captured = capsys.readouterr()
    assert not (out / "grind.cl").exists()
    assert "refused" in captured.err and "over-cut" in captured.err and "rows 0, 1, 2" in captured.err
    assert (out / "report.csv").exists() and (out / "path.csv").exists()
    assert main(args + ["--force"]) == 3
    assert (out / "grind.cl").exists() and "--force" in capsys.readouterr().err


def test_a_reader_that_stops_early_does_not_stop_the_command(tmp_path):
    # `machscan allowance ... | head -1`: once the reader has gone, every print raised BrokenPipeError (an OSError),
    # and the command stopped with "machscan: error: [Errno 32] Broken pipe" between its table and its output file.
    import subprocess
    import sys

    g = np.stack(np.meshgrid(np.arange(30) * 0.5, np.arange(30) * 0.5), -1).reshape(-1, 2)
    model = np.column_stack([g, np.zeros(len(g))])
    machscan.write_points(tmp_path / "model.ply", model, np.tile([0.0, 0.0, 1.0], (len(g), 1)))
    machscan.write_points(tmp_path / "blank.ply", model + [0.0, 0.0, 0.3])
    out = tmp_path / "a.ply"
    command = [sys.executable, "-m", "machscan", "allowance", "model.ply", "blank.ply", "--out", str(out)]
    run = subprocess.Popen(command, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert run.stdout is not None and run.stderr is not None
    run.stdout.close()  # the reader is gone before the first line
    errors = run.stderr.read().decode()
    assert run.wait(timeout=120) == 0, errors
    assert errors == ""
    a = machscan.io.read(out).scalars["allowance"]  # NaN at the blank's corners, where its feet lie on one side
    assert np.isfinite(a).mean() > 0.95 and np.nanmax(np.abs(a - 0.3)) < 1e-5
