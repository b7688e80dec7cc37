"""Isometric matching (issue #10 §3, §5; SPEC S4): against the closed-form truth of a skin bent onto a cylinder
(machscan.synth.BentSkin: bending onto a cylinder is an isometry, so geodesic distances are kept and the true
place of every matching point is known), then the whole chain, match + compensate, against the issue's targets."""

import numpy as np
import pytest

import machscan
from machscan.synth import BentSkin, misplacement


@pytest.fixture(scope="module")
def part():
    # The issue's part: 300 × 200 mm bent to R = 1000 mm, misplaced rigidly (1 mm / 0.5°), scanned at 1.3 mm
    # with 5 µm noise, two locating points and an 8 × 8 grid of matching points. The default call thins both
    # surfaces to about 2,000 vertices for the geodesics (spacing="auto").
    skin = BentSkin(pose=misplacement(5, translation=1.0, rotation=np.deg2rad(0.5)))
    theoretical, scan = skin.grid(1.3), skin.scan(1.3, 0.005, seed=2)
    r, grid = skin.locating(), skin.matching_grid()
    return skin, theoretical, scan, r, skin.actual(r)[0], grid


@pytest.fixture(scope="module")
def matched(part):
    _skin, theoretical, scan, r, r_actual, grid = part
    # The paper's quadratic Jacobian creeps (measured: 16–17 iterations to E ≤ 1 µm where the gradient takes
    # 2–3); 20 iterations are enough to meet the target.
    return {
        "quadratic": machscan.isometric_match(theoretical, scan, r, r_actual, grid, max_iterations=20),
        "gradient": machscan.isometric_match(theoretical, scan, r, r_actual, grid, jacobian="gradient"),
    }


def rms(d):
    return float(np.sqrt(np.mean(np.sum(d**2, axis=1))))


def test_matched_points_meet_the_issue_target_with_either_jacobian(part, matched):
    skin, *_, grid = part
    truth = skin.actual(grid)[0]
    assert matched["gradient"].converged
    for jac, m in matched.items():
        # Issue: within 20 µm RMS of the truth.
        assert rms(m.points - truth) < 0.020, (jac, rms(m.points - truth))
        assert len(m.objective) == len(m.max_error) == m.iterations + 1
        assert m.objective[-1] < m.objective[0] / 100
        assert len(m.residuals) == 2 * 64 + 64 * 63 // 2
        np.testing.assert_allclose(np.abs(m.residuals).max(), m.max_error[-1])
    # Both Jacobians only steer the steps: they end at the same points, to within the noise floor.
    assert rms(matched["quadratic"].points - matched["gradient"].points) < 0.010


def test_match_and_compensate_meet_the_issue_targets_end_to_end(part, matched):
    skin, _theoretical, scan, _r, _r_actual, grid = part
    tools = np.vstack([skin.raster(depth=0.0), skin.raster(step=25.0, depth=-2.0)])
    truth, normals = skin.actual(tools)
    path = machscan.compensate_toolpath(tools, grid, matched["quadratic"].points, scan)
    assert path.inside.all()
    err = np.linalg.norm(path.points - truth, axis=1)
    before = np.linalg.norm(tools - truth, axis=1)
    tilt = np.degrees(np.arccos(np.clip(np.sum(path.axes * normals, axis=1), -1, 1)))
    # Issue: ≤ 50 µm max inside the hull, axes ≤ 0.1°, ≥ 98 % less error than uncompensated.
    assert err.max() < 0.050, err.max()
    assert tilt.max() < 0.1
    assert 1 - err.max() / before.max() > 0.98


def test_a_rigidly_moved_flat_plate_is_matched_exactly():
    # No bend and no noise: exact geodesics on a flat mesh are Euclidean, so the match is the rigid motion.
    flat = BentSkin(length=120.0, width=80.0, radius=np.inf, pose=misplacement(1, translation=3.0, rotation=0.1))
    theoretical, scan = flat.grid(2.0), flat.scan(2.0, 0.0)
    r, grid = flat.locating(), flat.matching_grid(4, 4)
    m = machscan.isometric_match(theoretical, scan, r, flat.actual(r)[0], grid, jacobian="gradient", tolerance=1e-7)
    assert np.abs(m.points - flat.actual(grid)[0]).max() < 1e-5


def test_a_stretched_skin_breaks_the_assumption_and_the_residual_shows_it(part, matched):
    skin, theoretical, _, r, _, grid = part
    dome = BentSkin(radius=1000.0, second_radius=1500.0, pose=skin.pose)
    m = machscan.isometric_match(theoretical, dome.scan(6.0, 0.005), r, dome.actual(r)[0], grid, jacobian="gradient")
    # The stretch (up to ~0.2 mm over the skin) stays in V₂ − V₁: no isometric match exists.
    assert m.max_error[-1] > 10 * matched["gradient"].max_error[-1]
    assert rms(m.points - dome.actual(grid)[0]) > 0.020


def test_mesh_input_and_a_given_start_give_the_same_match(part):
    skin, *_ = part
    # At 6 mm, where "auto" does not thin: points, the same points with every one kept, and their mesh given.
    theoretical, scan = skin.grid(6.0), skin.scan(6.0, 0.005, seed=2)
    r, grid = skin.locating(), skin.matching_grid()
    r_actual = skin.actual(r)[0]
    auto = machscan.isometric_match(theoretical, scan, r, r_actual, grid, jacobian="gradient")
    every = machscan.isometric_match(theoretical, scan, r, r_actual, grid, jacobian="gradient", spacing=None)
    np.testing.assert_array_equal(auto.points, every.points)
    m = machscan.isometric_match(
        theoretical,
        (scan, machscan.delaunay_xy(scan)),
        r,
        r_actual,
        grid,
        actual_initial=skin.actual(grid)[0] + [0.3, -0.2, 0.0],
        jacobian="gradient",
    )
    assert rms(m.points - auto.points) < 0.005
    assert rms(m.points - skin.actual(grid)[0]) < 0.020


def test_points_near_the_edge_of_a_tilted_bent_skin_are_matched():
    # Locating and matching points 1 mm inside the edge of a 1 mm scan, thinned to a 2.2 mm spacing: still on the
    # mesh, still right. The tilt makes the outline bow inward by tens of µm in xy; Delaunay's hull triangles
    # across it were shortcuts for the geodesics (0.15 mm between the corner points) until the default long-edge
    # trim: with every triangle kept the match stalls.
    skin = BentSkin(length=120.0, width=80.0, radius=400.0, pose=misplacement(2, translation=1.0, rotation=0.01))
    theoretical, scan = skin.grid(1.0), skin.scan(1.0, 0.002, seed=1)
    r, grid = skin.locating(margin=1.0), skin.matching_grid(4, 4, margin=1.0)
    truth = skin.actual(grid)[0]
    for spacing in ("auto", None):
        m = machscan.isometric_match(theoretical, scan, r, skin.actual(r)[0], grid, jacobian="gradient", spacing=spacing)
        assert m.converged and m.max_error[-1] < 0.002, (spacing, m)
        assert rms(m.points - truth) < 0.005, (spacing, rms(m.points - truth))
    untrimmed = machscan.isometric_match(
        theoretical, scan, r, skin.actual(r)[0], grid, jacobian="gradient", spacing=None, max_edge=float("inf")
    )
    assert untrimmed.max_error[-1] > 0.05


def test_a_strongly_bent_part_starts_inside_its_outline():
    # Bent to R = 100 mm, the 120 mm plate is 7 mm shorter in xy than flat: the rigid motion of the locating points
    # carries the far matching points past the scan's outline. They start just inside it (this raised before).
    skin = BentSkin(length=120.0, width=80.0, radius=100.0, pose=misplacement(3, translation=1.0, rotation=0.01))
    theoretical, scan = skin.grid(1.5), skin.scan(1.5, 0.002, seed=1)
    r, grid = skin.locating(), skin.matching_grid(4, 4, margin=2.0)
    r_actual = skin.actual(r)[0]
    # The rigid xy motion of r1, r2 (the default start), to show the case is the one meant.
    a, b = r_actual[1, :2] - r_actual[0, :2], r[1, :2] - r[0, :2]
    turn = np.arctan2(a[1], a[0]) - np.arctan2(b[1], b[0])
    rot = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    start = (grid[:, :2] - r[0, :2]) @ rot.T + r_actual[0, :2]
    along = (start - r_actual[0, :2]) @ (a / np.linalg.norm(a))
    assert along.max() > ((scan[:, :2] - r_actual[0, :2]) @ (a / np.linalg.norm(a))).max() + 2.0
    m = machscan.isometric_match(theoretical, scan, r, r_actual, grid, jacobian="gradient")
    assert m.converged
    assert rms(m.points - skin.actual(grid)[0]) < 0.010


def test_the_noise_floor_stops_the_match_not_the_iteration_limit():
    # 10 µm noise and a tolerance no match reaches (1 nm): T falls to the noise floor in a few steps, then by
    # nothing. The match stops there ("stalled", converged) instead of trying up to max_iterations (which took
    # 21 and 32 iterations for the same points before).
    skin = BentSkin(length=120.0, width=80.0, radius=400.0, pose=misplacement(2, translation=1.0, rotation=0.01))
    theoretical, scan = skin.grid(1.5), skin.scan(1.5, 0.010, seed=1)
    r, grid = skin.locating(), skin.matching_grid(4, 4)
    for jacobian in ("gradient", "quadratic"):
        m = machscan.isometric_match(theoretical, scan, r, skin.actual(r)[0], grid, jacobian=jacobian, tolerance=1e-6)
        assert (m.stop, m.converged) == ("stalled", True), (jacobian, m)
        assert m.iterations <= 10, (jacobian, m)
        assert m.objective[-1] < m.objective[0] / 100
        assert rms(m.points - skin.actual(grid)[0]) < 0.015, jacobian


def test_the_iteration_limit_is_reported_not_raised(part):
    _skin, theoretical, scan, r, r_actual, grid = part
    m = machscan.isometric_match(theoretical, scan, r, r_actual, grid, max_iterations=1, method="fmm")
    assert (m.stop, m.converged, m.iterations) == ("max_iterations", False, 1)


def test_bad_arguments_are_refused_by_name(part):
    _skin, _theoretical, _scan, _r, _r_actual, _grid = part
    small = BentSkin(length=40.0, width=30.0)
    t, g = small.grid(2.0), small.matching_grid(3, 3, margin=5.0)
    loc = small.locating()
    base = dict(theoretical_points=t, actual_points=t, theoretical_locating=loc, actual_locating=loc, theoretical_matching=g)
    cases = [
        (dict(theoretical_locating=g[:3]), "theoretical_locating"),
        (dict(actual_locating=loc[:1]), "actual_locating"),
        (dict(theoretical_matching=g[:6]), "theoretical_matching"),
        (dict(actual_initial=g[:4]), "actual_initial"),
        (dict(actual_initial=g + [100.0, 0.0, 0.0]), "actual_initial"),
        (dict(actual_points=t[:, :2]), "actual_points"),
        (dict(theoretical_points=(t, [[0, 1, len(t)]])), "theoretical_points"),
        (dict(jacobian="numeric"), "jacobian"),
        (dict(method="dijkstra"), "method"),
        (dict(tolerance=0.0), "tolerance"),
        (dict(max_iterations=-1), "max_iterations"),
        (dict(spacing=0.0), "spacing"),
        (dict(spacing="fine"), "spacing"),
        (dict(spacing=float("nan")), "spacing"),
        (dict(theoretical_locating=loc[[0, 0]]), "theoretical_locating: r1 and r2 coincide"),
        (dict(actual_locating=loc[[1, 1]]), "actual_locating: r1 and r2 coincide"),
        # Review (session 15): points far off the surface were put on its edge and matched as if right; inf
        # was reported as coinciding locating points.
        (dict(theoretical_locating=loc + [1000.0, 0.0, 0.0]), r"theoretical_locating: point 0 .* lies 9\d\d\.\d+ mm from"),
        (
            dict(actual_locating=loc + [0.0, 0.0, 5.0]),
            r"actual_locating: point 0 .* lies 5\.000 mm from the surface, more than 4\.000",
        ),
        (dict(theoretical_matching=np.vstack([g, [[1000.0, 0.0, 0.0]]])), r"theoretical_matching: point 9 "),
        (dict(theoretical_locating=np.vstack([[np.inf, 0.0, 0.0], loc[1]])), "theoretical_locating: must be finite"),
        (dict(max_edge=0.1), r"max_edge: 0.1 mm left no triangle of theoretical_points \(its Delaunay edges' median is 2"),
        # The quadratic Jacobian's fit is not defined on points along one line (the gradient one is).
        (dict(theoretical_matching=np.c_[np.linspace(-15, 15, 8), np.zeros(8), np.zeros(8)]), "one line or conic"),
    ]
    for change, name in cases:
        with pytest.raises(ValueError, match=name):
            machscan.isometric_match(**(base | change))
    bad = g.copy()
    bad[2, 0] = np.nan
    with pytest.raises(ValueError, match="theoretical_matching"):
        machscan.isometric_match(t, t, loc, loc, bad)


def test_a_point_off_the_scan_is_measured_against_the_scans_spacing_not_the_thinned_mesh(part):
    # Review (session 15): the limit came from the mesh thinned for the geodesics (~5.5 mm edges on this part),
    # so a locating point 8 mm off the 1.3 mm scan passed.
    _skin, theoretical, scan, r, r_actual, grid = part
    with pytest.raises(ValueError, match=r"^actual_locating: point 1 .* lies [45]\.\d+ mm from the surface, more than [23]\."):
        machscan.isometric_match(theoretical, scan, r, r_actual + [[0.0, 0.0, 0.0], [0.0, 0.0, 5.0]], grid)


def test_bent_skin_refuses_a_spacing_that_is_not_positive():
    for spacing in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="spacing"):
            BentSkin().scan(spacing)


def test_a_gap_inside_the_scan_is_bridged_not_walked_round():
    # A clamp's 12 mm shadow in the scan, no matching point in it. Trimming every long triangle (the default
    # until review) left a hole the geodesics went round: E 1.8 mm, stalled, 0.23 mm RMS off. The default now
    # peels long triangles from the outline only.
    skin = BentSkin(length=120.0, width=80.0, radius=400.0, pose=misplacement(5, translation=1.0, rotation=np.deg2rad(0.5)))
    uv = skin.grid(1.3)
    scan = skin.scan(1.3, 0.005, seed=2)
    scan = scan[np.hypot(uv[:, 0] - 12.0, uv[:, 1] - 7.0) > 6.0]
    r, grid = skin.locating(), skin.matching_grid(5, 5)
    m = machscan.isometric_match(skin.grid(1.3), scan, r, skin.actual(r)[0], grid, jacobian="gradient")
    assert m.converged and m.max_error[-1] < 0.002, m
    assert rms(m.points - skin.actual(grid)[0]) < 0.010
