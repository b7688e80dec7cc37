"""Tests of machscan.synth.blade: the Bézier blade is a closed, G1, outward-normalled surface, the touch
probe returns the exact contact on the true (misplaced) part, and misplacement() is the asked rigid motion.

Every expected value comes from an independent route: finite differences of the points, a point-in-polygon
test of the planar sections, the surface itself at known parameters, and a foot-point projection written
here.
"""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from machscan import synth
from machscan.synth import Blade, TouchProbe, misplacement
from machscan.synth import blade as blade_module

JOINTS = (0.0, 0.25, 0.5, 0.75)


@pytest.fixture(scope="module")
def blade():
    return Blade()


@pytest.fixture(scope="module")
def pose():
    """A paper-like misplacement: 0.5 mm and 0.5° about an axis through mid-span."""
    return misplacement(seed=4, center=(0.0, 0.0, 75.0))


def _apply(pose, points):
    return points @ pose[:3, :3].T + pose[:3, 3]


def _random_uv(n, seed=0, margin=0.05):
    rng = np.random.default_rng(seed)
    return rng.random(n), rng.uniform(margin, 1.0 - margin, n)


def _angle(a, b):
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("...j,...j->...", a, b))


def _inside(polygon, xy):
    """Even-odd rule: whether each point of ``xy`` (M, 2) lies inside the closed ``polygon`` (K, 2)."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    x, y = xy[:, None, 0], xy[:, None, 1]
    crosses = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (crosses & (x < x_cross)).sum(axis=1) % 2 == 1


def _foot_point(part, q, u, v, h=1e-6):
    """Closest point of ``part`` to each ``q`` (model frame) near ``(u, v)``: a dense local search, then
    Newton on the gradient of ``|S − q|² / 2`` with finite differences (Gauss-Newton alone fails when the
    distance exceeds the radius of curvature, as with a 2 mm ball at the 0.7 mm trailing edge). An
    independent route to the distance from the true surface."""
    du, dv = np.linspace(-0.03, 0.03, 61), np.linspace(-0.05, 0.05, 11)
    uu, vv = np.broadcast_arrays(u[:, None, None] + du[:, None], v[:, None, None] + dv)
    points, _ = part.surface(uu, vv)
    rows = np.arange(len(q))
    best = np.argmin(np.linalg.norm(points - q[:, None, None], axis=-1).reshape(len(q), -1), axis=1)
    u, v = uu.reshape(len(q), -1)[rows, best], vv.reshape(len(q), -1)[rows, best]

    def gradient(u, v):
        su = (part.surface(u + h, v)[0] - part.surface(u - h, v)[0]) / (2 * h)
        sv = (part.surface(u, v + h)[0] - part.surface(u, v - h)[0]) / (2 * h)
        r = part.surface(u, v)[0] - q
        return np.stack([np.einsum("ij,ij->i", su, r), np.einsum("ij,ij->i", sv, r)], axis=-1)

    k = 1e-5
    for _ in range(20):
        hess = np.stack(
            [(gradient(u + k, v) - gradient(u - k, v)) / (2 * k), (gradient(u, v + k) - gradient(u, v - k)) / (2 * k)], axis=-1
        )
        step = np.linalg.solve(hess, -gradient(u, v)[..., None])[..., 0]
        u, v = u + step[:, 0], v + step[:, 1]
    return part.surface(u, v)


# --------------------------------------------------------------------------------------------
# package
# --------------------------------------------------------------------------------------------


def test_package_reexports_and_stays_pure_numpy():
    for name in synth.__all__:
        assert hasattr(synth, name), name
    assert synth.Blade is blade_module.Blade
    assert synth.GROOVE_SHAPES == ("v", "u", "u_walls", "trapezoid")
    # The truth must not come from the code it tests.
    for module in (blade_module, synth.grooves):
        assert "_core" not in inspect.getsource(module)


# --------------------------------------------------------------------------------------------
# the blade
# --------------------------------------------------------------------------------------------


def test_blade_dimensions_and_sample_grid(blade):
    points, normals = blade.sample(200, 100)
    assert points.shape == normals.shape == (200, 100, 3)
    np.testing.assert_allclose(points[:, :, 2], np.broadcast_to(np.linspace(0, 150, 100), (200, 100)), atol=1e-12)
    # u = 0 is the leading edge and u = 1/2 the trailing edge: their distance is the chord.
    (le, te), _ = blade.surface([[0.0], [0.5]], [0.0, 1.0])
    np.testing.assert_allclose(np.linalg.norm(te - le, axis=-1), [120.0, 90.0], rtol=1e-12)
    # Thickness ~11 % of the chord at the crest, measured across the section from suction to pressure crest.
    crests, _ = blade.surface([0.25, 0.75], 0.0)
    assert 0.10 * 120 < np.linalg.norm(crests[0] - crests[1]) < 0.12 * 120
    # Twist: the chord turns by 0.3 rad from root to tip.
    turn = _angle((te - le)[0], (te - le)[1])
    assert turn == pytest.approx(0.3, abs=1e-12)


def test_blade_normals_are_unit_and_perpendicular_to_tangents(blade):
    u, v = _random_uv(500, seed=1, margin=0.0)
    u, v = np.r_[u, 0.1, 0.9, 0.3], np.r_[v, 0.0, 1.0, 0.5]
    h = 1e-6
    _, n = blade.surface(u, v)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-14)
    su = (blade.surface(u + h, v)[0] - blade.surface(u - h, v)[0]) / (2 * h)
    sv = (blade.surface(u, v + h)[0] - blade.surface(u, v - h)[0]) / (2 * h)
    for tangent in (su, sv):
        rel = np.abs(np.einsum("ij,ij->i", n, tangent)) / np.linalg.norm(tangent, axis=1)
        assert rel.max() < 1e-9
    # At the joints the parametric speed may jump, not the direction: one-sided differences, O(h) error.
    h = 1e-8
    u, v = np.repeat(JOINTS, 3), np.tile([0.0, 0.5, 1.0], 4)
    _, n = blade.surface(u, v)
    for tangent in (blade.surface(u + h, v)[0] - blade.surface(u, v)[0], blade.surface(u, v)[0] - blade.surface(u - h, v)[0]):
        rel = np.abs(np.einsum("ij,ij->i", n, tangent)) / np.linalg.norm(tangent, axis=1)
        assert rel.max() < 1e-5


@pytest.mark.parametrize("v", [0.0, 0.37, 1.0])
def test_blade_normals_point_outward(blade, v):
    u = np.arange(4000) / 4000
    section, _ = blade.surface(u, v)
    np.testing.assert_allclose(section[:, 2], 150.0 * v, atol=1e-12)  # sections are planar
    # Probe around the whole section, concave pressure side and thin trailing edge included.
    s, n = blade.surface(np.arange(397) / 397 + 1e-4, v)
    eps = 0.05  # mm, below the trailing edge radius (~0.7 mm) and far above the polygon's chord error
    assert _inside(section[:, :2], (s - eps * n)[:, :2]).all()
    assert not _inside(section[:, :2], (s + eps * n)[:, :2]).any()
    assert np.abs(n[:, 2]).max() < 0.2  # taper, lean and sweep are small: the normals stay nearly in the section


def test_blade_normals_are_continuous_across_the_joints_and_the_section_closes(blade):
    v = np.linspace(0.0, 1.0, 7)
    for joint in JOINTS:
        before = (joint if joint > 0 else 1.0) - 1e-14
        p_before, n_before = blade.surface(before, v)
        p_after, n_after = blade.surface(joint, v)
        np.testing.assert_allclose(p_before, p_after, atol=1e-9)  # closed and G0 (u = 1 meets u = 0)
        assert _angle(n_before, n_after).max() < 1e-9  # G1: the normals do not jump
        # The tangent direction is continuous too (one-sided differences on each side).
        h = 1e-7
        t_before = p_before - blade.surface(before - h, v)[0]
        t_after = blade.surface(joint + h, v)[0] - p_after
        assert _angle(t_before, t_after).max() < 1e-5
    # Periodic in u.
    u = np.linspace(0.0, 1.0, 50, endpoint=False)
    for shift in (1.0, -2.0):
        np.testing.assert_allclose(blade.surface(u + shift, 0.4)[0], blade.surface(u, 0.4)[0], atol=1e-9)


def test_blade_rejects_bad_parameters():
    with pytest.raises(ValueError):
        Blade(span=0.0)
    with pytest.raises(ValueError):
        Blade(thickness=-0.1)


# --------------------------------------------------------------------------------------------
# the touch probe
# --------------------------------------------------------------------------------------------


def test_probe_returns_the_commanded_points_on_a_well_placed_part(blade):
    u, v = _random_uv(300, seed=2)
    s, n = blade.surface(u, v)
    measured = TouchProbe(blade)(s, -n)
    np.testing.assert_allclose(measured, s, atol=1e-9)


def test_probe_finds_the_true_points_of_a_misplaced_part(blade, pose):
    u, v = _random_uv(300, seed=3)
    s, n = blade.surface(u, v)
    true_points, true_normals = _apply(pose, s), n @ pose[:3, :3].T
    measured = TouchProbe(blade, pose)(true_points, -true_normals)
    np.testing.assert_allclose(measured, true_points, atol=1e-9)
    # The misplacement matters: the nominal points are off by about half a millimetre.
    assert np.linalg.norm(true_points - s, axis=1).min() > 0.05


def test_probe_ball_center_is_the_offset_surface(blade, pose):
    u, v = _random_uv(300, seed=5)
    u = np.r_[u, JOINTS]  # the edges: curvature up to 1 / 0.7 mm at the trailing edge
    v = np.r_[v, 0.5, 0.5, 0.5, 0.5]
    s, n = blade.surface(u, v)
    centers = _apply(pose, s + 3.0 * n)
    # Command the contact point of a 0-radius probe: the ball meets the part 3 mm before it.
    measured = TouchProbe(blade, pose, radius=3.0)(_apply(pose, s), -n @ pose[:3, :3].T)
    np.testing.assert_allclose(measured, centers, atol=1e-9)


@pytest.mark.parametrize("radius", [0.0, 2.0])
def test_probe_off_target_lands_on_the_true_surface_and_on_the_line(blade, pose, radius):
    u, v = _random_uv(200, seed=6, margin=0.1)
    s, n = blade.surface(u, v)
    su = blade.surface(u + 1e-6, v)[0] - blade.surface(u - 1e-6, v)[0]
    su /= np.linalg.norm(su, axis=1, keepdims=True)
    rng = np.random.default_rng(7)
    # Commanded at the nominal points shifted along the section, approached along a tilted nominal normal.
    commanded = s + 0.4 * su + radius * n
    d = -(n + rng.normal(scale=0.1, size=n.shape))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    measured = TouchProbe(blade, pose, radius=radius)(commanded, d)
    assert not np.isnan(measured).any()
    # On the commanded line.
    np.testing.assert_array_less(np.linalg.norm(np.cross(measured - commanded, d), axis=1), 1e-9)
    # At distance `radius` from the true surface, on its outer side.
    q = (measured - pose[:3, 3]) @ pose[:3, :3]
    foot, normal = _foot_point(blade, q, u, v)
    np.testing.assert_allclose(np.einsum("ij,ij->i", q - foot, normal), radius, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(q - foot, axis=1), radius, atol=1e-9)
    # And not simply the commanded point: the shift, tilt and misplacement all moved the contact.
    assert np.median(np.linalg.norm(measured - commanded, axis=1)) > 0.05


def test_probe_reports_the_first_contact_even_past_the_commanded_point(blade):
    u, v = _random_uv(100, seed=8)
    s, n = blade.surface(u, v)
    # Commanded 1 mm inside the part (a real cycle starts `clearance` before it): the contact is 1 mm back.
    measured = TouchProbe(blade)(s - 1.0 * n, -n)
    np.testing.assert_allclose(measured, s, atol=1e-9)


def test_probe_noise_is_gaussian_along_the_approach(blade):
    u, v = _random_uv(2000, seed=9)
    s, n = blade.surface(u, v)
    exact = TouchProbe(blade)(s, -n)
    noisy = TouchProbe(blade, noise=0.002, seed=3)(s, -n)
    dev = noisy - exact
    along = np.einsum("ij,ij->i", dev, -n)
    perp = dev - along[:, None] * -n
    assert np.abs(perp).max() < 1e-9
    assert np.std(along) == pytest.approx(0.002, rel=0.1)
    assert abs(np.mean(along)) < 4 * 0.002 / np.sqrt(len(along))


def test_probe_noise_is_reproducible_and_fresh_on_each_call(blade):
    s, n = blade.surface(np.linspace(0, 1, 20, endpoint=False), 0.5)
    a, b = TouchProbe(blade, noise=0.01, seed=1), TouchProbe(blade, noise=0.01, seed=1)
    first = a(s, -n)
    np.testing.assert_array_equal(first, b(s, -n))
    second = a(s, -n)
    assert not np.array_equal(first, second)
    np.testing.assert_array_equal(second, b(s, -n))
    assert not np.array_equal(first, TouchProbe(blade, noise=0.01, seed=2)(s, -n))


def test_probe_misses_give_nan(blade, pose):
    s, n = blade.surface([0.2, 0.2, 0.2, 0.7], [0.5, 0.5, 0.5, 0.5])
    commanded = s.copy()
    commanded[1, 2] = 150.0 + 20.0  # far beyond the tip: the line passes above the blade
    commanded[2] += 8.0 * n[2]  # 8 mm off the surface with a 5 mm travel
    measured = TouchProbe(blade, pose)(commanded, -n)
    assert np.isnan(measured[1:3]).all()
    assert not np.isnan(measured[[0, 3]]).any()
    # Reaching further finds the last one.
    assert not np.isnan(TouchProbe(blade, pose, travel=10.0)(commanded[2:3], -n[2:3])).any()
    # Lines that meet the loft only beyond the tip or below the root (no end caps: the surface formula goes
    # on there, the part does not), and a line leaving the part (approach along +normal).
    beyond, beyond_n = blade.surface([0.2, 0.6], [1.02, -0.01])
    assert np.isnan(TouchProbe(blade)(beyond, -beyond_n)).all()
    inside, inside_n = blade.surface([0.2, 0.6], [0.98, 0.01])
    assert not np.isnan(TouchProbe(blade)(inside, -inside_n)).any()
    assert np.isnan(TouchProbe(blade)(s[:1] + 1.0 * n[:1], n[:1])).all()


def test_probe_rejects_non_rigid_poses(blade):
    with pytest.raises(ValueError):
        TouchProbe(blade, np.diag([1.0, 1.0, 1.01, 1.0]))
    with pytest.raises(ValueError):
        TouchProbe(blade, np.diag([1.0, 1.0, -1.0, 1.0]))
    probe = TouchProbe(blade, misplacement(1))
    np.testing.assert_array_equal(probe.pose, misplacement(1))


# --------------------------------------------------------------------------------------------
# misplacement
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_misplacement_is_the_asked_rigid_motion(seed):
    center = np.array([10.0, -5.0, 75.0])
    pose = misplacement(seed, translation=0.5, rotation=np.deg2rad(0.5), center=center)
    rot, shift = pose[:3, :3], pose[:3, 3]
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-15)
    assert np.linalg.det(rot) == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_array_equal(pose[3], [0, 0, 0, 1])
    assert np.arccos((np.trace(rot) - 1) / 2) == pytest.approx(np.deg2rad(0.5), rel=1e-9)
    # The center only translates, by the asked length; the points of the axis through it too.
    moved = rot @ center + shift - center
    assert np.linalg.norm(moved) == pytest.approx(0.5, rel=1e-12)
    w, vecs = np.linalg.eig(rot)
    axis = np.real(vecs[:, np.argmin(np.abs(w - 1))])
    np.testing.assert_allclose(rot @ (center + 40 * axis) + shift - (center + 40 * axis), moved, atol=1e-12)
    # Without translation the center is a fixed point.
    still = misplacement(seed, translation=0.0, center=center)
    np.testing.assert_allclose(still[:3, :3] @ center + still[:3, 3], center, atol=1e-12)
    # Reproducible, and the seed matters.
    np.testing.assert_array_equal(pose, misplacement(seed, center=center))
    assert not np.allclose(pose, misplacement(seed + 10, center=center))
