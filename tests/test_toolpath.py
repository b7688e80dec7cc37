"""Toolpath compensation (issue #10 §4–5; SPEC S5): against the closed-form truth of a skin bent onto a cylinder
(machscan.synth.BentSkin, an isometry), with the true matching points, so that these figures are the
compensation's own; tests/test_matching.py runs the whole chain."""

import numpy as np
import pytest

import machscan
from machscan.synth import BentSkin, misplacement


def angles(a, b):
    return np.degrees(np.arccos(np.clip((a * b).sum(axis=1), -1.0, 1.0)))


@pytest.fixture(scope="module")
def skin():
    # The issue's part: 300 × 200 mm bent to R = 1000 mm, misplaced by 1 mm / 0.5°, scanned at 1.3 mm with
    # 5 µm noise; an 8 × 8 grid of matching points.
    s = BentSkin(pose=misplacement(3, translation=1.0, rotation=np.deg2rad(0.5)))
    tm = s.matching_grid()
    return s, s.scan(1.3, 0.005, seed=1), tm, s.actual(tm)[0]


@pytest.mark.parametrize("depth", [0.0, -2.0])
def test_the_default_mapping_meets_the_issue_targets_on_a_bent_noisy_skin(skin, depth):
    s, scan, tm, am = skin
    tools = s.raster(depth=depth)
    truth, normals = s.actual(tools)
    r = machscan.compensate_toolpath(tools, tm, am, scan)
    assert r.inside.all()
    err = np.linalg.norm(r.points - truth, axis=1)
    before = np.linalg.norm(tools - truth, axis=1)
    # Issue: ≤ 50 µm max, axes ≤ 0.1°, ≥ 98 % less error than the uncompensated path (measured: ~5 µm, 0.05°).
    assert err.max() < 0.050
    assert angles(r.axes, normals).max() < 0.1
    assert 1 - err.max() / before.max() > 0.98
    np.testing.assert_allclose(r.offsets, depth, atol=1e-9)


def test_the_papers_variant_is_kept_and_its_triangle_normals_tilt_with_the_noise(skin):
    s, scan, tm, am = skin
    tools = s.raster(depth=-2.0)
    truth, normals = s.actual(tools)
    paper = machscan.compensate_toolpath(tools, tm, am, scan, interpolation="linear", normals="triangle")
    smooth = machscan.compensate_toolpath(tools, tm, am, scan)
    # 5 µm of noise at 1.3 mm spacing tilts triangle normals by tenths of a degree (the issue's point), and a
    # 2 mm deep pocket floor moves by depth × tilt.
    tilt = angles(paper.axes, normals)
    assert tilt.max() > 0.3 and np.median(tilt) > 0.1
    assert angles(smooth.axes, normals).max() < 0.1
    assert np.linalg.norm(paper.points - truth, axis=1).max() > np.linalg.norm(smooth.points - truth, axis=1).max()


def test_given_tool_axes_turn_with_the_surface(skin):
    s, scan, tm, am = skin
    tools = s.raster(step=40.0, spacing=20.0)
    # A lead angle of 10° in x on the theoretical (flat) skin.
    axis = np.array([np.sin(np.deg2rad(10)), 0.0, np.cos(np.deg2rad(10))])
    r = machscan.compensate_toolpath(np.hstack([tools, np.tile(axis, (len(tools), 1))]), tm, am, scan)
    # The truth: the axis as a point offset 1 mm along it, carried by the bend, minus the carried foot (the
    # bend is a rotation of the normal; its differential maps the lead direction to the tangent).
    _foot, n = s.actual(tools)
    u = tools[:, 0] / s.radius
    tangent = np.column_stack([np.cos(u), np.zeros_like(u), np.sin(u)]) @ s.pose[:3, :3].T
    want = axis[0] * tangent + axis[2] * n
    assert angles(r.axes, want).max() < 0.1


def test_points_outside_the_matching_hull_are_flagged_not_dropped(skin):
    _s, scan, tm, am = skin
    tools = np.array([[0.0, 0.0, 0.0], [145.0, 0.0, 0.0], [0.0, -95.0, 0.0], [139.0, 89.0, 0.0]])
    r = machscan.compensate_toolpath(tools, tm, am, scan)
    np.testing.assert_array_equal(r.inside, [True, False, False, True])
    assert np.isfinite(r.points).all() and np.isfinite(r.axes).all()
    assert "2 outside" in repr(r)


def test_points_that_map_beyond_the_scan_are_flagged(skin):
    # Review (session 15): with a scan of half the part, the tool points over the other half were put on the
    # scan's edge, up to 143 mm from the truth, and nothing said so. Matching points off the scan are refused.
    s, scan, tm, am = skin
    tools = s.raster(step=5.0, spacing=1.0)
    with pytest.raises(ValueError, match=r"^actual_matching: point \d+ .* from the surface"):
        machscan.compensate_toolpath(tools, tm, am, scan[scan[:, 0] < 0.0])
    # A hole 30 mm across in the scan, inside the matching hull (a clamp's shadow left open by max_edge): the
    # points over it are flagged, the others, up to its rim (rows 5 mm apart, points 1 mm apart), are placed
    # as the issue asks.
    hole = np.hypot(scan[:, 0], scan[:, 1]) < 15.0
    r = machscan.compensate_toolpath(tools, tm, am, scan[~hole], max_edge=5.0)
    truth = s.actual(tools)[0]
    err = np.linalg.norm(r.points - truth, axis=1)
    centre = np.hypot(truth[:, 0], truth[:, 1])
    assert r.inside[centre < 40.0].all()
    assert not r.on_scan[centre < 14.0].any()
    assert r.on_scan[centre > 16.0].all()
    assert err[r.on_scan & r.inside].max() < 0.050
    assert f"{int((~r.on_scan).sum())} beyond the scan" in repr(r)
    # The paper's linear mapping is off the surface by up to tenths of a millimetre between matching points;
    # that does not take a point off the scan.
    assert machscan.compensate_toolpath(tools, tm, am, scan, interpolation="linear").on_scan.all()


def test_a_point_without_a_tool_axis_takes_the_normal_and_keeps_the_others_axes(skin, tmp_path):
    # Review (session 15): one GOTO/x,y,z among five-axis GOTOs made every programmed axis be dropped.
    s, scan, tm, am = skin
    tools = s.raster(step=50.0, spacing=50.0)
    lead = np.array([0.0, 0.6, 0.8])
    axes = np.tile(lead, (len(tools), 1))
    axes[0] = np.nan
    path = tmp_path / "mixed.cl"
    machscan.io.write_toolpath(path, tools, axes=axes)
    mixed = machscan.compensate_toolpath(machscan.io.read_toolpath(path), tm, am, scan)
    given = machscan.compensate_toolpath(np.hstack([tools, np.tile(lead, (len(tools), 1))]), tm, am, scan)
    normal = machscan.compensate_toolpath(tools, tm, am, scan)
    np.testing.assert_allclose(mixed.axes[1:], given.axes[1:], atol=1e-12)
    np.testing.assert_allclose(mixed.axes[0], normal.axes[0], atol=1e-12)
    assert angles(mixed.axes[1:], normal.axes[1:]).min() > 30.0
    # CL files print axes to a few decimals: 0.70711, 0.70711 (length 1 + 4.6e-6) is an axis, normalised.
    short = np.hstack([tools, np.tile([0.0, 0.70711, 0.70711], (len(tools), 1))])
    exact = np.hstack([tools, np.tile([0.0, np.sqrt(0.5), np.sqrt(0.5)], (len(tools), 1))])
    np.testing.assert_allclose(
        machscan.compensate_toolpath(short, tm, am, scan).axes, machscan.compensate_toolpath(exact, tm, am, scan).axes, atol=1e-9
    )
    half_given = np.hstack([tools, axes])
    half_given[0, 3] = 0.0  # one NaN left in the row: neither an axis nor none
    with pytest.raises(ValueError, match=r"^tool_points: must be finite, found NaN at row 0, column 4"):
        machscan.compensate_toolpath(half_given, tm, am, scan)
    with pytest.raises(ValueError, match=r"^tool_points: the tool axis of point 1 .* length is 1.01"):
        machscan.compensate_toolpath(np.hstack([tools, 1.01 * axes]), tm, am, scan)


def test_a_mesh_a_toolpath_object_and_apt_files_go_through_the_same_way(skin, tmp_path):
    s, scan, tm, am = skin
    tools = s.raster(step=50.0, spacing=25.0)
    faces = machscan.delaunay_xy(scan)
    a = machscan.compensate_toolpath(tools, tm, am, scan)
    b = machscan.compensate_toolpath(tools, tm, am, (scan, faces))
    np.testing.assert_array_equal(a.points, b.points)
    path = tmp_path / "theoretical.cl"
    up = np.tile([0.0, 0.0, 1.0], (len(tools), 1))
    machscan.io.write_toolpath(path, tools, axes=up, feeds=np.full(len(tools), 800.0))
    c = machscan.compensate_toolpath(machscan.io.read_toolpath(path), tm, am, scan)
    np.testing.assert_allclose(c.points, a.points, atol=1e-12)
    out = tmp_path / "compensated.cl"
    machscan.io.write_toolpath(out, c.points, axes=c.axes)
    back = machscan.io.read_toolpath(out)
    np.testing.assert_array_equal(back.points, c.points)
    np.testing.assert_array_equal(back.axes, c.axes)


def test_bad_arguments_are_refused_by_name(skin):
    s, scan, tm, am = skin
    tools = s.raster(step=50.0, spacing=25.0)
    line = np.column_stack([np.arange(64.0), np.arange(64.0), np.zeros(64)])
    cases = [
        (dict(tool_points=tools[:, :2]), "tool_points"),
        (dict(tool_points=np.hstack([tools, np.ones((len(tools), 3))])), "tool_points"),
        (dict(actual_matching=am[:-1]), "actual_matching"),
        (dict(theoretical_matching=line), "theoretical_matching"),
        (dict(actual_surface=scan[:, :2]), "actual_surface"),
        (dict(interpolation="spline"), "interpolation"),
        (dict(normals="vertex"), "normals"),
        (dict(radius=-1.0), "radius"),
    ]
    for change, name in cases:
        kw = dict(tool_points=tools, theoretical_matching=tm, actual_matching=am, actual_surface=scan) | change
        with pytest.raises(ValueError, match=name):
            machscan.compensate_toolpath(**kw)
    bad = tools.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="tool_points"):
        machscan.compensate_toolpath(bad, tm, am, scan)
    # A bad tool axis is named by its column as given, (x, y, z, i, j, k).
    with_axes = np.hstack([tools, np.tile([0.0, 0.0, 1.0], (len(tools), 1))])
    with_axes[2, 4] = np.nan
    with pytest.raises(ValueError, match=r"tool_points: .* row 2, column 4"):
        machscan.compensate_toolpath(with_axes, tm, am, scan)
    # Coordinates whose squares overflow, and a point so far out that the extrapolated (cubic) mapping
    # overflows: refused by name (the latter was an index panic).
    for x, message in [(1e200, r"tool_points: coordinates beyond ±1e150 .* row 4, column 0"), (1e150, "tool_points: point 4")]:
        far = np.r_[tools[:4], [[x, 0.0, 0.0]]]
        with pytest.raises(ValueError, match=message):
            machscan.compensate_toolpath(far, tm, am, scan)
    with pytest.raises(ValueError, match=r"actual_surface: coordinates beyond ±1e150"):
        machscan.compensate_toolpath(tools, tm, am, np.r_[scan, [[1e200, 0.0, 0.0]]])


def test_a_gap_in_the_scan_does_not_tilt_the_axes_across_it():
    # A clamp's 16 mm shadow in the scan of the issue's skin, with the true matching points (so only the
    # compensation is measured). Tool points over the gap had no scan points within the normal's default
    # radius (5 median edges) and the 12 nearest, all on one side, extrapolated their slope: 119 µm and 2.39°.
    # Widening until the points surround the tool point: 32 µm, 1.04° (radius=15 reaches 1.8 µm, 0.01°).
    s = BentSkin(pose=misplacement(5, translation=1.0, rotation=np.deg2rad(0.5)))
    uv = s.grid(1.3)
    scan = s.scan(1.3, 0.005, seed=2)
    scan = scan[np.hypot(uv[:, 0], uv[:, 1] - 30.0) > 8.0]
    grid = s.matching_grid()
    tools = s.raster(step=2.0, spacing=1.0)
    truth, normals = s.actual(tools)
    c = machscan.compensate_toolpath(tools, grid, s.actual(grid)[0], scan)
    tilt = np.degrees(np.arccos(np.clip(np.sum(c.axes * normals, axis=1), -1, 1)))
    assert np.linalg.norm(c.points - truth, axis=1).max() < 0.050 and tilt.max() < 1.5
