"""Blade positioning by touch-probe rounds and the envelope fit of a blank (issue #9 §3 and §4),
against exact ground truth: the synthetic blade and probe simulator of ``machscan.synth``, and
SciPy's SLSQP on the same allowance."""

import numpy as np
import pytest

import machscan
from machscan.synth import Blade, TouchProbe, misplacement


@pytest.fixture(scope="module")
def blade():
    b = Blade()
    points, normals = b.sample(200, 100)
    return b, points, normals


def moved(p, m):
    return p @ m[:3, :3].T + m[:3, 3]


def pose_error(blade, found, truth):
    """RMS over the whole model of the pose error along the true normals, and of the full
    displacement, mm."""
    _, points, normals = blade
    p, n = points.reshape(-1, 3), normals.reshape(-1, 3)
    d = moved(p, found) - moved(p, truth)
    along = np.einsum("ij,ij->i", d, n @ truth[:3, :3].T)
    return np.sqrt(np.mean(along**2)), np.sqrt(np.mean(np.sum(d**2, axis=1)))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("n_points", [160, 400])
def test_probe_rounds_locate_a_misplaced_blade_to_2_um_along_the_normals(blade, seed, n_points):
    # Issue #9 §3: 0.5 mm / 0.5° misplacement, 2 µm probe noise, ≤ 4 rounds of ≤ 400 points;
    # the pose error along the surface normals, over the whole model, ≤ 2 µm RMS.
    b, points, normals = blade
    truth = misplacement(seed, center=points.reshape(-1, 3).mean(axis=0))
    radius = 1.0 if seed % 2 else 0.0
    probe = TouchProbe(b, truth, radius=radius, noise=0.002, seed=seed)
    r = machscan.position_workpiece(points, normals, probe, n_points=n_points, probe_radius=radius, max_rounds=4)
    along, full = pose_error(blade, r.transformation, truth)
    assert len(r.rounds) <= 4 and r.converged
    assert along < 0.002, f"along the normals {along * 1e3:.2f} µm (full displacement {full * 1e3:.1f} µm)"
    # The residuals are the probe noise once the pose is right.
    assert 0.0015 < r.history[-1] < 0.0025


def test_noise_free_probing_converges_to_the_exact_pose(blade):
    # The rounds converge quadratically: what the tangent plane misses (κ s² / 2) shrinks with
    # the square of how far the probe landed from where it was sent.
    b, points, normals = blade
    truth = misplacement(3, center=points.reshape(-1, 3).mean(axis=0))
    probe = TouchProbe(b, truth, radius=3.0)
    r = machscan.position_workpiece(points, normals, probe, probe_radius=3.0, tolerance=1e-9, max_rounds=5)
    assert np.abs(r.transformation - truth).max() < 1e-8
    corrections = [x.correction for x in r.rounds]
    assert corrections[1] < 0.02 * corrections[0] and corrections[2] < 0.02 * corrections[1]
    # The surface points are the ball centres compensated by the radius: on the model surface.
    last = r.rounds[-1]
    assert np.abs(last.errors.e_total).max() < 1e-6
    assert last.surface.shape == last.commanded.shape
    assert "round" in r.summary() and len(r.summary().splitlines()) == len(r.rounds) + 1


def test_the_designed_pattern_fixes_the_pose_better_than_a_random_draw(blade):
    # The pose error that probe noise leaves along the normals over the model, predicted from the
    # linearised fit (σ² trace((JᵀJ)⁻¹ W)): the designed pattern lowers it, here by half or more.
    _, points, normals = blade
    p, n = points.reshape(-1, 3), normals.reshape(-1, 3)
    c = p.mean(axis=0)
    g = np.hstack([np.cross(p - c, n), n])
    w = g.T @ g / len(p)

    def predicted(idx):
        return np.sqrt(np.trace(np.linalg.inv(g[idx].T @ g[idx]) @ w))

    designed = machscan.locating_points(points, m=160, keep=0.5, normals=normals, pattern="optimal")
    random = [predicted(machscan.locating_points(points, m=160, keep=0.5, seed=s)) for s in range(5)]
    assert len(np.unique(designed)) == 160
    assert predicted(designed) < 0.7 * min(random)
    # From the flattest half, a spacing away from each other and from the blade's root and tip.
    v = (designed % 100) / 99
    assert v.min() > 0.01 and v.max() < 0.99
    gaps = np.linalg.norm(p[designed][:, None] - p[designed][None], axis=2) + np.eye(160) * 1e9
    assert gaps.min() > 1.0


def test_a_probe_that_finds_nothing_is_reported_not_raised(blade):
    b, points, normals = blade
    far = np.eye(4)
    far[:3, 3] = [0, 0, 400.0]  # the part is not where the probe goes
    r = machscan.position_workpiece(points, normals, TouchProbe(b, far), max_rounds=3)
    assert not r.converged and len(r.rounds) == 1 and r.rounds[0].hits == 0
    np.testing.assert_array_equal(r.transformation, np.eye(4))
    assert np.isnan(r.history[0])


@pytest.mark.parametrize(
    ("kwargs", "error", "name"),
    [
        (dict(measure=lambda p, d: p[:5]), ValueError, "measure"),
        (dict(measure=3), TypeError, "measure"),
        (dict(probe_radius=-1.0), ValueError, "probe_radius"),
        (dict(max_rounds=0), ValueError, "max_rounds"),
        (dict(pattern="best"), ValueError, "pattern"),
        (dict(init=np.eye(3)), ValueError, "init"),
    ],
)
def test_bad_positioning_arguments_raise_naming_them(blade, kwargs, error, name):
    _, points, normals = blade
    args = dict(measure=lambda p, d: p) | kwargs
    with pytest.raises(error, match=name):
        machscan.position_workpiece(points, normals, **args)


# ---- envelope fit --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def notched_blank():
    """The blade's faces as the model (the edges left out: a plane through 8 blank points is
    biased by the curvature there, 35 µm at the 3.6 mm leading edge) and a blank built as the
    blade offset along its normals by 0.3 mm of stock, with a notch on the pressure side down to
    0.08 mm below the model, sampled at about 0.25 mm and misplaced by 0.2 mm / 0.2°."""
    b = Blade()
    model, normals = b.sample(120, 40)
    u = np.arange(120) / 120
    faces = (np.abs(u - 0.5) > 0.06) & (np.abs(u - 0.5) < 0.44)
    model, normals = model[faces, 2:-2].reshape(-1, 3), normals[faces, 2:-2].reshape(-1, 3)
    u, v = np.meshgrid(np.arange(900) / 900, np.linspace(0, 1, 500), indexing="ij")
    s, n = b.surface(u, v)
    notch = 0.38 * np.exp(-(((u - 0.75) / 0.03) ** 2) - ((v - 0.5) / 0.08) ** 2)
    blank = (s + (0.3 - notch)[..., None] * n).reshape(-1, 3)
    displaced = misplacement(4, translation=0.2, rotation=np.deg2rad(0.2), center=model.mean(axis=0))
    return model, normals, moved(blank, displaced)


def test_envelope_fit_finds_the_pose_a_plain_best_fit_misses(notched_blank):
    model, normals, blank = notched_blank
    plain = machscan.envelope_fit(model, normals, blank, min_allowance=-1e6)  # evenness alone
    assert np.nanmin(plain.allowance) < -0.01  # the notch is left short
    fit = machscan.envelope_fit(model, normals, blank, min_allowance=0.0)
    assert fit.feasible and fit.converged
    assert np.nanmin(fit.allowance) >= -1e-9
    # The allowance reported is the allowance of the blank moved by the returned transform.
    again = machscan.allowance(model, normals, moved(blank, fit.transformation))
    np.testing.assert_allclose(again, fit.allowance, atol=1e-9)
    # A minimum of 0.25 mm cannot hold (the notch takes 0.38 mm from 0.3 mm on one face, so no
    # move leaves 0.25 mm on both): infeasible, reported, and the smallest stock raised anyway.
    high = machscan.envelope_fit(model, normals, blank, min_allowance=0.25)
    assert not high.feasible
    assert np.nanmin(high.allowance) > np.nanmin(fit.allowance)
    assert "does NOT hold" in high.summary() and "holds" in fit.summary()


def test_slsqp_finds_no_more_even_pose_than_the_envelope_fit(notched_blank):
    # SciPy's SLSQP on the same problem (six pose parameters, the allowance of
    # machscan.allowance, one constraint per model point), started at the envelope fit's pose:
    # no feasible pose it reaches is more even, so the fit is a constrained optimum. (From the
    # misplaced start SLSQP needs ~200 iterations and minutes to reach the same variance.)
    scipy_optimize = pytest.importorskip("scipy.optimize")
    from scipy.spatial.transform import Rotation

    model, normals, blank = notched_blank
    model, normals = model[::2], normals[::2]
    ours = machscan.envelope_fit(model, normals, blank, min_allowance=0.0)
    start = moved(blank, ours.transformation)
    centre = model.mean(axis=0)

    def allowance(x):
        m = np.eye(4)
        m[:3, :3] = Rotation.from_rotvec(x[:3] / 50.0).as_matrix()
        m[:3, 3] = centre - m[:3, :3] @ centre + x[3:]
        a = machscan.allowance(model, normals, moved(start, m))
        return a[np.isfinite(a)]

    ref = scipy_optimize.minimize(
        lambda x: np.var(allowance(x)),
        np.zeros(6),
        method="SLSQP",
        constraints=[{"type": "ineq", "fun": allowance}],
        options=dict(eps=1e-4, maxiter=20, ftol=1e-12),
    )
    a_ref, a = allowance(ref.x), ours.allowance[np.isfinite(ours.allowance)]
    assert a.min() >= -1e-9
    assert a_ref.min() < -1e-6 or np.var(a_ref) >= 0.99 * np.var(a), (np.var(a_ref), np.var(a), a_ref.min())


def test_envelope_fit_refuses_bad_input_by_name(notched_blank):
    model, normals, blank = notched_blank
    with pytest.raises(ValueError, match="min_allowance"):
        machscan.envelope_fit(model, normals, blank, min_allowance=float("nan"))
    with pytest.raises(ValueError, match="model_normals"):
        machscan.envelope_fit(model, normals[:-1], blank)
    with pytest.raises(ValueError, match="k"):
        machscan.envelope_fit(model, normals, blank, k=2)
    with pytest.raises(ValueError, match="blank_points"):
        machscan.envelope_fit(model, normals, np.vstack([blank, [np.nan, 0, 0]]))
