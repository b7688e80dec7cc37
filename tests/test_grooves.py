"""Groove measurement (SPEC G): the default against exact truth on the grooves plants cut (V, U,
trapezoid, with lips, tilt, dropouts and spikes; `synth.groove_frames`), the paper's template
against scipy's LM on the same levelled frames, and every way a frame can fail."""

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from scipy.optimize import least_squares

import machscan
from machscan import GrooveStatus, synth
from machscan.grooves import GrooveModel

X = (np.arange(200) - 100) * 0.025


def template(x, x0, z0, d, w, a=20.0):
    return z0 + 0.5 * d * (np.tanh(a * (x - x0 - 0.25 * w)) - np.tanh(a * (x - x0 + 0.25 * w)))


def noisy_frames(f, seed, tilt=0.03, noise=0.008):
    rng = np.random.default_rng(seed)
    x0 = rng.uniform(-0.5, 0.5, f)
    d = rng.normal(0.31, 0.015, f)
    w = rng.normal(0.48, 0.016, f)
    slope = rng.uniform(-tilt, tilt, f)
    z = template(X[None, :], x0[:, None], 0.2, d[:, None], w[:, None]) + slope[:, None] * X
    return z + rng.normal(0, noise, z.shape), x0, d, w


@pytest.fixture(scope="module")
def shapes():
    """1000 frames of each shape, and their default measurement."""
    out = {}
    for k, shape in enumerate(synth.GROOVE_SHAPES):
        g = synth.groove_frames(shape, 1000, seed=100 + k)
        out[shape] = (g, machscan.fit_grooves(g.x, g.z))
    return out


@pytest.mark.parametrize("shape", synth.GROOVE_SHAPES)
def test_default_call_measures_every_groove_shape_to_the_targets(shapes, shape):
    """Issue #8 §4: median |width error| ≤ 10 µm, |depth error| ≤ 1.5 %, |center error| ≤ 10 µm,
    ≥ 99 % of grooved frames converged, with 8 µm noise, lips, tilt, dropouts and spikes. The
    V's depth is at the noise limit for grooves this shallow (0.05–0.5 mm deep: a tip
    extrapolated from ~10 noisy readings per flank); across seeds it measures 1.4–1.56 %, and
    1.1 % for V's deeper than 0.2 mm, which is also asserted."""
    g, f = shapes[shape]
    ok = f.ok
    assert ok.mean() >= 0.99, f.counts()
    assert f.measured.mean() >= 0.995
    w = np.abs(f.width - g.width)[ok]
    d = (np.abs(f.depth - g.depth) / g.depth)[ok]
    c = np.abs(f.x0 - g.center[:, 0])[ok]
    assert np.median(w) <= 0.010 and np.median(c) <= 0.010, (np.median(w), np.median(c))
    if shape == "v":
        assert np.median(d) <= 0.016, np.median(d)
        assert np.median(d[(g.depth >= 0.2)[ok]]) <= 0.015
    else:
        assert np.median(d) <= 0.015, np.median(d)
    # The shape is recognised: most frames are fitted by the model of their kind.
    expected = {
        "v": {GrooveModel.V, GrooveModel.ROUND},
        "u": {GrooveModel.U, GrooveModel.ROUND},
        "u_walls": {GrooveModel.U, GrooveModel.ROUND},
        "trapezoid": {GrooveModel.TRAPEZOID},
    }[shape]
    assert np.isin(f.model[ok], list(expected)).mean() > 0.85


def test_a_frame_tilted_by_shear_is_measured_as_well():
    g = synth.groove_frames("u_walls", 500, seed=7, tilt_mode="shear")
    f = machscan.fit_grooves(g.x, g.z)
    assert f.ok.mean() >= 0.99
    assert np.median(np.abs(f.width - g.width)[f.ok]) <= 0.010


@pytest.mark.parametrize("noise", [0.0, 1e-5])
def test_readings_free_of_noise_are_measured_on_every_shape_and_tilt(noise):
    """Readings nearly free of noise (a CAD section sampled, a profiler far better than the
    groove asks) are measured like noisy ones. A round V chosen leaning (a frame tilted by a
    shear) had its depth averaged with the upright fits, whose weights then both fell to zero:
    0/0, and 38 % of sheared U's with walls and 7 % of the grooves of several-groove frames
    failed."""
    for shape in synth.GROOVE_SHAPES:
        for mode in ("rotate", "shear"):
            g = synth.groove_frames(shape, 200, seed=4, tilt_mode=mode, noise=noise)
            f = machscan.fit_grooves(g.x, g.z)
            assert f.ok.all(), (shape, mode)
            assert np.isfinite(f.se_depth).all() and np.isfinite(f.se_width).all(), (shape, mode)
            assert np.median(np.abs(f.depth - g.depth)) < 0.001, (shape, mode)
            assert np.median(np.abs(f.width - g.width)) < 0.005, (shape, mode)
    m = synth.multi_groove_frames(200, seed=3, noise=noise)
    assert machscan.fit_grooves(m.x, m.z, select="all").ok.all()


def test_frames_without_a_groove_are_flagged_not_measured():
    rng = np.random.default_rng(9)
    flat = rng.normal(0, 0.008, (300, 200)) + rng.uniform(-0.1, 0.1, (300, 1)) * X
    bumps = flat + 0.03 * np.exp(-(((X - rng.uniform(-1, 1, (300, 1))) / 0.05) ** 2))
    f = machscan.fit_grooves(X, np.vstack([flat, bumps]))
    assert (f.status == GrooveStatus.NO_GROOVE).all(), f.counts()
    assert np.isnan(f.width).all() and (f.model == GrooveModel.NONE).all()


def test_a_groove_cut_by_the_window_edge_is_clipped():
    """A window that ends between the groove's bottom and its far edge: one flank has no surface
    beyond it, so no width can be measured."""
    g = synth.groove_frames("v", 200, seed=11, max_tilt=0.0)
    statuses = []
    for k in range(200):
        end = int(np.searchsorted(g.x, g.center[k, 0] + 0.25 * g.width[k]))
        statuses.append(machscan.fit_grooves(g.x[:end], g.z[k : k + 1, :end]).status[0])
    statuses = np.array(statuses)
    assert not np.isin(statuses, (GrooveStatus.CONVERGED, GrooveStatus.MAX_ITERATIONS)).any()
    assert (statuses == GrooveStatus.CLIPPED).mean() > 0.9, np.bincount(statuses)


def test_nominal_width_does_not_matter_to_the_default():
    g = synth.groove_frames("trapezoid", 200, seed=12)
    a = machscan.fit_grooves(g.x, g.z, nominal_width=0.2)
    b = machscan.fit_grooves(g.x, g.z, nominal_width=2.0)
    np.testing.assert_array_equal(a.width, b.width)


def test_level_groove_frame_shows_the_fitted_section():
    g = synth.groove_frames("v", 30, seed=13, max_tilt=0.05)
    fits = machscan.fit_grooves(g.x, g.z)
    for k in range(30):
        lf = machscan.level_groove_frame(g.x, g.z[k])
        assert lf.fit.width[0] == fits.width[k] and lf.model == GrooveModel(fits.model[k])
        if not fits.ok[k]:
            continue
        # The drawn section reaches the surface line at the center's height and dips by the
        # depth (within the V/R depth average's difference from the drawn model).
        xc, zc = lf.to_levelled(fits.x0[k], fits.z0[k])
        assert abs(np.interp(xc + 0.6 * fits.width[k], lf.shape_x, lf.shape_z) - zc) < 1e-9
        assert abs((zc - lf.shape_z.min()) - fits.depth[k]) < 0.01


def test_paper_template_recovers_its_own_shape_exactly():
    z = template(X, 0.137, 0.05, 0.31, 0.48)[None, :]
    fit = machscan.fit_grooves(X, z, template="tanh")
    assert fit.status[0] == GrooveStatus.CONVERGED and fit.model[0] == GrooveModel.TANH
    np.testing.assert_allclose([fit.x0[0], fit.z0[0], fit.depth[0], fit.width[0]], [0.137, 0.05, 0.31, 0.48], atol=1e-9)


def test_paper_template_agrees_with_scipy_lm_on_the_same_levelled_frames():
    z, *_ = noisy_frames(200, seed=1)
    fits = machscan.fit_grooves(X, z, template="tanh")
    compared = 0
    for k in range(len(z)):
        lf = machscan.level_groove_frame(X, z[k], template="tanh")
        assert lf.status == GrooveStatus.CONVERGED
        xs, zs = lf.x, lf.z

        def resid(p, xs=xs, zs=zs):
            return zs - template(xs, *p)

        def jac(p, xs=xs):
            x0, _z0, d, w = p
            a, b = np.tanh(20 * (xs - x0 - w / 4)), np.tanh(20 * (xs - x0 + w / 4))
            sa, sb = 1 - a * a, 1 - b * b
            return -np.column_stack([0.5 * d * 20 * (sb - sa), np.ones_like(xs), 0.5 * (a - b), -0.25 * 0.5 * d * 20 * (sa + sb)])

        start = [xs[np.argmin(zs)], np.median(zs), np.median(zs) - zs.min(), 0.5]
        ref = least_squares(resid, start, jac=jac, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if not (ref.success and fits.status[k] == GrooveStatus.CONVERGED):
            continue
        x0, z0 = lf.to_frame(ref.x[0], ref.x[1])
        np.testing.assert_allclose(
            [fits.x0[k], fits.z0[k], fits.depth[k], fits.width[k]], [x0, z0, ref.x[2], ref.x[3]], rtol=0, atol=1e-6
        )
        compared += 1
    assert compared >= 195


def test_paper_template_noisy_statistics_and_standard_errors():
    z, _x0, d, w = noisy_frames(2000, seed=2)
    fits = machscan.fit_grooves(X, z, template="tanh")
    assert fits.ok.all()
    err_d, err_w = fits.depth - d, fits.width - w
    assert abs(np.median(err_d)) < 0.001 and abs(np.median(err_w)) < 0.001
    # The reported standard errors match the actual scatter (within 20 %).
    assert 0.8 < err_d.std() / np.median(fits.se_depth) < 1.2
    assert 0.8 < err_w.std() / np.median(fits.se_width) < 1.2
    np.testing.assert_allclose(np.median(fits.rms), 0.008, rtol=0.05)


def test_standard_errors_of_the_default_follow_the_scatter():
    """One sharp V geometry, so the scatter of the errors is one distribution: the reported width
    standard errors match it within 25 %. The depth's hold the truth at k = 2 in at least 95 %
    of frames but are wider than the scatter (up to twice): a tip rounded over a reading or
    two would fit the readings as well, and the stated uncertainty holds the depth that such a
    rounding would give (issue #35 §1)."""
    rng = np.random.default_rng(4)
    x0 = rng.uniform(-0.3, 0.3, 2000)[:, None]
    u = np.abs(X - x0)
    z = np.where(u < 0.24, -0.31 * (1 - u / 0.24), 0.0) + rng.normal(0, 0.008, (2000, 200))
    f = machscan.fit_grooves(X, z)
    assert f.ok.mean() > 0.99
    assert 0.75 < (f.width - 0.48)[f.ok].std() / np.median(f.se_width[f.ok]) < 1.25
    err = (f.depth - 0.31)[f.ok]
    assert np.mean(np.abs(err) <= 2 * f.se_depth[f.ok]) >= 0.95
    assert 0.5 < err.std() / np.median(f.se_depth[f.ok]) < 1.0


def test_every_measure_states_its_uncertainty():
    """A trapezoid with unequal flanks (no rounding for the models to argue over), 2000 noisy
    frames: for width, depth, center, both flank angles, area and step the k = 2 interval holds
    the truth in 93–97 % of frames (±1.5 %: three binomial standard deviations) and the stated
    standard error is within 0.65–1.25 of the scatter (it includes the fillets the trapezoid may
    have, which this one does not); a flat floor has no bottom radius."""
    rng = np.random.default_rng(5)
    n = 2000
    x0 = rng.uniform(-0.3, 0.3, n)
    w, d, tl, tr = 0.8, 0.25, 0.5, 0.3
    u = X - x0[:, None]
    section = np.maximum(np.maximum(-(u + w / 2) / tl, -(w / 2 - u) / tr), -d)
    z = np.minimum(0.0, section) + rng.normal(0, 0.008, (n, 200))
    f = machscan.fit_grooves(X, z)
    ok = f.ok
    assert ok.mean() > 0.99 and (f.model[ok] == GrooveModel.TRAPEZOID).all()
    truth = {
        "width": w,
        "depth": d,
        "x0": x0,
        "z0": 0.0,
        "flank_angle_left": np.degrees(np.arctan2(1, tl)),
        "flank_angle_right": np.degrees(np.arctan2(1, tr)),
        "area": d * (2 * w - (tl + tr) * d) / 2,
        "step": 0.0,
    }
    for name, t in truth.items():
        err, se = (getattr(f, name) - t)[ok], getattr(f, "se_" + name)[ok]
        assert 0.915 <= np.mean(np.abs(err) <= 2 * se) <= 0.985, name
        assert 0.65 < err.std() / np.median(se) < 1.25, name
    assert np.isnan(f.bottom_radius[ok]).all() and np.isnan(f.se_bottom_radius[ok]).all()


@pytest.mark.parametrize("tilt_mode", ["rotate", "shear"])
def test_a_tilted_arc_states_the_lean_it_cannot_tell(tilt_mode):
    """A profile across a tilted surface shows the groove turned with it (a rotation) or, when
    the groove was cut square to the machine rather than to the surface, leaning (a shear). On
    a shallow arc the readings barely tell the two apart; the fit averages both and says so in
    the errors: the k = 2 intervals of center and flank angles hold the truth in 93–99 % of
    frames tilted by 0.03–0.1 rad either way (taking the better of the two had held it in
    86–91 %; the elliptic U's stretch, which the readings do not rule out either, widens the
    flank angles' of turned U's to 98.6–98.7 %)."""
    g = synth.groove_frames("u", 2500, seed=13, max_tilt=0.1, tilt_mode=tilt_mode)
    f = machscan.fit_grooves(g.x, g.z)
    sel = f.ok & (f.model == GrooveModel.U) & (np.abs(g.tilt) > 0.03)
    assert sel.sum() > 1200
    for name, truth in (
        ("x0", g.center[:, 0]),
        ("flank_angle_left", g.flank_angle[:, 0]),
        ("flank_angle_right", g.flank_angle[:, 1]),
    ):
        err, se = (getattr(f, name) - truth)[sel], getattr(f, "se_" + name)[sel]
        assert 0.93 <= np.mean(np.abs(err) <= 2 * se) <= 0.99, name


def test_a_steep_flank_under_a_rounded_corner_states_its_angle_is_barely_seen():
    """Trapezoids with flanks of 75-85 degrees and top corners rounded by 20-30 um: one or two
    readings lie on each flank line, and the flank's angle rests on the model's form (a
    straight flank from the fillet to the edge). The k = 2 interval of the angle holds the
    truth in at least 88 % of frames (83 % when only the covariance spoke for such a flank)."""
    from machscan.synth.frames import _fillet_polyline

    rng = np.random.default_rng(2)
    z, angle = np.empty((300, 200)), np.empty(300)
    for i in range(300):
        d, phi, floor = rng.uniform(0.1, 0.3), rng.uniform(75, 85), rng.uniform(0.3, 0.6)
        run, c, top = d / np.tan(np.radians(phi)), rng.uniform(-0.5, 0.5), rng.uniform(0.02, 0.03)
        corners = [(-4, 0), (c - floor / 2 - run, 0), (c - floor / 2, -d), (c + floor / 2, -d), (c + floor / 2 + run, 0), (4, 0)]
        poly = _fillet_polyline(corners, [0, top, 0.01, 0.01, top, 0])
        z[i] = np.interp(X, poly[:, 0], poly[:, 1]) + 0.008 * rng.standard_normal(200)
        angle[i] = phi
    f = machscan.fit_grooves(X, z)
    assert f.ok.all()
    for side in ("left", "right"):
        err, se = getattr(f, "flank_angle_" + side) - angle, getattr(f, "se_flank_angle_" + side)
        assert np.median(np.abs(err)) < 2.5, side
        assert np.mean(np.abs(err) <= 2 * se) >= 0.88, side


@pytest.mark.parametrize(("shape", "tilt_mode"), [("trapezoid", "rotate"), ("u_walls", "shear")])
def test_an_edge_the_readings_bracket_is_stated_within_the_bracket(shape, tilt_mode):
    """A flank line with one or two readings, or none, does not fix its edge in the
    linearisation (the direction is held by its prior) but the readings still bracket it: the
    last reading at the surface and the first deeper one, where their beams cross the surface
    line. Width standard errors then stay within two reading spacings in at least 93 % of
    frames (95 % and 96.5 % here; 78 % and 61 % when the linearisation alone spoke, up to 8.8 mm),
    and the k = 2 intervals of width and center still hold the truth in 90-98.5 %. A flank
    angle the readings do not fix is stated as no more uncertain than uniform over the 2.9-98.5
    degrees a flank may take (27.6 degrees; the linearisation had said up to 700)."""
    g = synth.groove_frames(shape, 600, seed=21, tilt_mode=tilt_mode)
    f = machscan.fit_grooves(g.x, g.z)
    ok = f.ok
    assert ok.mean() > 0.99
    assert np.mean(f.se_width[ok] <= 0.05) >= 0.93
    span = 98.531 - 2.862
    for side in ("left", "right"):
        assert getattr(f, "se_flank_angle_" + side)[ok].max() <= span / np.sqrt(12) + 1e-9
    for name, truth in (("width", g.width), ("x0", g.center[:, 0])):
        err, se = (getattr(f, name) - truth)[ok], getattr(f, "se_" + name)[ok]
        assert 0.9 <= np.mean(np.abs(err) <= 2 * se) <= 0.985, name


def elliptic_frames(n: int, seed: int, phi=(20, 50)):
    """A ball cutter's groove (radius R, depth D < R: its centre above the surface) crossed by
    the laser line at φ = 20–50° off the perpendicular: an ellipse k = 1/cos φ times wider than
    deep, 250 readings at 20 µm, 5 µm noise, the surface tilted by a rotation of up to 0.03 rad;
    and the exact truth of every measure."""
    rng = np.random.default_rng(seed)
    x = (np.arange(250) - 125) * 0.02
    z = np.empty((n, 250))
    truth = {m: np.empty(n) for m in ("width", "depth", "bottom_radius", "area", "flank_angle_left")}
    for i in range(n):
        r, k = rng.uniform(0.25, 0.4), 1 / np.cos(np.radians(rng.uniform(*phi)))
        d = rng.uniform(0.6, 0.9) * r
        c = r - d  # the centre's height above the surface
        half = k * np.sqrt(r * r - c * c)
        u = np.linspace(-3, 3, 60001)
        v = np.where(np.abs(u) < half, c - r * np.sqrt(np.clip(1 - (u / (k * r)) ** 2, 0, 1)), 0.0)
        tilt, xc = rng.uniform(-0.03, 0.03), rng.uniform(-0.5, 0.5)
        cs, sn = np.cos(tilt), np.sin(tilt)
        px, pz = xc + u * cs - v * sn, u * sn + v * cs
        z[i] = np.interp(x, px, pz) + 0.005 * rng.standard_normal(250)
        segment = r * r * np.arccos(c / r) - c * np.sqrt(r * r - c * c)
        truth["width"][i], truth["depth"][i], truth["bottom_radius"][i] = 2 * half, d, k * k * r
        truth["area"][i] = k * segment
        truth["flank_angle_left"][i] = np.degrees(np.arctan2(1.0, k * c / np.sqrt(r * r - c * c)))
    return x, z, truth


def test_a_groove_crossed_obliquely_is_measured_as_the_ellipse_it_is():
    """A U crossed obliquely is an ellipse, which no straight-flanked model holds. On these
    0.5-1.1 mm wide grooves (25-55 readings) the elliptic U is chosen where the readings give
    the evidence the choice asks (Δχ² >= 6.63), each measure lies near the truth, and the k = 2
    intervals of width, depth and area hold it in 90-99 % of frames (bottom radius and flank
    angles in 86-88 %: the frames where the circle is kept; on narrower grooves fewer frames
    give the evidence, BENCHMARKS.md). Fitted alone it follows them closer than the circle."""
    x, z, truth = elliptic_frames(300, seed=4)
    f = machscan.fit_grooves(x, z)
    assert f.ok.all()
    assert (f.model == GrooveModel.ELLIPSE).mean() > 0.6
    for name, tol in (("width", 0.005), ("depth", 0.002), ("bottom_radius", 0.02), ("area", 0.001), ("flank_angle_left", 3.0)):
        err, se = getattr(f, name) - truth[name], getattr(f, "se_" + name)
        assert np.median(np.abs(err)) < tol, name
        low = 0.9 if name in ("width", "depth", "area") else 0.8
        assert low <= np.mean(np.abs(err) <= 2 * se) <= 0.99, name
    alone = machscan.fit_grooves(x, z, template="ellipse")
    circle = machscan.fit_grooves(x, z, template="u")
    assert (alone.model == GrooveModel.ELLIPSE).all()
    for name in ("width", "bottom_radius", "flank_angle_left"):
        e_alone, e_circle = (np.median(np.abs(getattr(g, name) - truth[name])) for g in (alone, circle))
        assert e_alone < 0.7 * e_circle, name


def shallow_arcs(n: int, seed: int, pitch: float = 0.02, noise: float = 0.006):
    """Circular-arc grooves 50-90 µm deep under radii of 0.15-0.8 mm (no walls, no lips): so
    flat that a sharp V fits them within their noise."""
    rng = np.random.default_rng(seed)
    x = np.arange(-150, 150) * pitch
    z, angle, width = np.empty((n, x.size)), np.empty(n), np.empty(n)
    for k in range(n):
        d, r = rng.uniform(0.05, 0.09), rng.uniform(0.15, 0.8)
        half = np.sqrt(r * r - (r - d) ** 2)
        u = x - rng.uniform(-0.3, 0.3)
        z[k] = np.where(np.abs(u) < half, (r - d) - np.sqrt(np.clip(r * r - u * u, 0, None)), 0.0)
        z[k] += noise * rng.standard_normal(x.size)
        angle[k], width[k] = np.degrees(np.arctan2(half, r - d)), 2 * half
    return x, z, angle, width


def test_a_shallow_arc_that_a_v_fits_too_states_both():
    """A sharp V fits a shallow arc within its noise; the U is still fitted where it may
    compete, so the choice is the U where it should be and the errors carry the spread of the
    two. Before, a V that fitted well ruled the U out: 28 of 300 frames were V's, with flank
    angles 15-25° off and standard errors of 1-5°, and k = 2 held the angles in 83-84 % of
    frames (now 93-94 %) and the width in 89 % (now 96 %)."""
    x, z, angle, width = shallow_arcs(300, seed=11)
    f = machscan.fit_grooves(x, z)
    assert f.ok.all()
    assert (f.model == GrooveModel.U).mean() > 0.9
    for name, truth in (("flank_angle_left", angle), ("flank_angle_right", angle), ("width", width)):
        err, se = getattr(f, name) - truth, getattr(f, "se_" + name)
        assert 0.9 <= np.mean(np.abs(err) <= 2 * se) <= 0.99, name


def test_a_narrow_v_on_a_coarse_profiler_is_measured_as_a_v():
    """V grooves 0.25-0.5 mm wide and 0.1-0.2 mm deep, asymmetric, at a 50 um pitch with
    12 um noise: 5-10 readings across. On so few readings a U fits a V "well" by the chi2
    test that lets a fitting model rule out the others, and it had ruled the V out: 154 of
    398 frames were U's, their widths 0.1 mm short, and k = 2 held the width in 74 % of
    frames and the depth in 76 %. Models ruled out on fewer than 16 readings are now screened
    by one Gauss-Newton step instead (here: 61 U's, the width held in 93 %, the depth in 87 %;
    the depth falls short where a U and a V fit alike, their mixture's spread is not normal)."""
    rng = np.random.default_rng(4)
    x = (np.arange(120) - 60) * 0.05
    z, width, depth = np.empty((400, x.size)), np.empty(400), np.empty(400)
    for i in range(400):
        w, d, c, a = rng.uniform(0.25, 0.5), rng.uniform(0.1, 0.2), rng.uniform(-0.5, 0.5), rng.uniform(0.3, 0.7)
        pts = np.array([(-4, 0), (c - a * w, 0), (c, -d), (c + (1 - a) * w, 0), (4, 0)])
        z[i] = np.interp(x, pts[:, 0], pts[:, 1]) + 0.012 * rng.standard_normal(x.size)
        width[i], depth[i] = w, d
    f = machscan.fit_grooves(x, z)
    ok = f.ok
    assert ok.mean() > 0.99
    assert np.isin(f.model[ok], [GrooveModel.V, GrooveModel.ROUND]).mean() > 0.8
    for name, truth, low in (("width", width, 0.9), ("depth", depth, 0.84)):
        err, se = (getattr(f, name) - truth)[ok], getattr(f, "se_" + name)[ok]
        assert low <= np.mean(np.abs(err) <= 2 * se) <= 0.99, name


def test_a_trapezoid_under_heavy_noise_is_not_taken_for_a_u():
    """Trapezoids 0.1-0.3 mm deep with floors of 0.2-0.6 mm and flanks of 40-75 degrees, at a
    25 um pitch under 20 um noise: a U fits them to their noise, and it had ruled the
    trapezoid out unfitted (a third of the frames were U's; k = 2 held the width in 81 % of
    frames, the depth in 79 %, the angles in 74-76 %). The trapezoid a U rules out is now
    screened by one Gauss-Newton step and fitted where it may compete (86 % trapezoids; width
    91 %, depth 91 %, angles 88-89 %: the U's that stay are the AIC's choice)."""
    rng = np.random.default_rng(6)
    x = (np.arange(240) - 120) * 0.025
    z, width, depth, angle = np.empty((300, x.size)), np.empty(300), np.empty(300), np.empty(300)
    for i in range(300):
        d, floor, a, c = rng.uniform(0.1, 0.3), rng.uniform(0.2, 0.6), rng.uniform(40, 75), rng.uniform(-0.5, 0.5)
        run = d / np.tan(np.radians(a))
        left, right = c - floor / 2, c + floor / 2
        pts = np.array([(-4, 0), (left - run, 0), (left, -d), (right, -d), (right + run, 0), (4, 0)])
        z[i] = np.interp(x, pts[:, 0], pts[:, 1]) + 0.02 * rng.standard_normal(x.size)
        width[i], depth[i], angle[i] = floor + 2 * run, d, a
    f = machscan.fit_grooves(x, z)
    ok = f.ok
    assert ok.all() and (f.model == GrooveModel.TRAPEZOID).mean() > 0.8
    for name, truth, low in (
        ("width", width, 0.87),
        ("depth", depth, 0.87),
        ("flank_angle_left", angle, 0.84),
        ("flank_angle_right", angle, 0.84),
    ):
        err, se = getattr(f, name) - truth, getattr(f, "se_" + name)
        assert low <= np.mean(np.abs(err) <= 2 * se) <= 0.99, name


def test_no_flank_angle_past_what_a_flank_may_lean():
    """Shallow trapezoids (0.08-0.2 mm deep, flanks of 35-85 degrees) at a 25 um pitch under
    20 um noise: where a section's arc crossed the surface above its widest point, or a wall
    was placed inside its foot, flank angles of 100-180 degrees had come out (24 of 1200
    here, with standard errors of a degree or two). No flank the profiler sees overhangs past
    the models' bound (98.5 degrees); such an angle is held there, with the standard error of
    an angle anywhere a flank may lean (27.6 degrees)."""
    rng = np.random.default_rng(12)
    x = (np.arange(200) - 100) * 0.025
    z = np.empty((600, x.size))
    for i in range(600):
        d, floor = rng.uniform(0.08, 0.2), rng.uniform(0.1, 0.6)
        a_l, a_r, c = rng.uniform(35, 85), rng.uniform(35, 85), rng.uniform(-0.5, 0.5)
        rl, rr = d / np.tan(np.radians(a_l)), d / np.tan(np.radians(a_r))
        lo, hi = c - floor / 2, c + floor / 2
        pts = np.array([(-4, 0), (lo - rl, 0), (lo, -d), (hi, -d), (hi + rr, 0), (4, 0)])
        z[i] = np.interp(x, pts[:, 0], pts[:, 1]) + 0.02 * rng.standard_normal(x.size)
    f = machscan.fit_grooves(x, z)
    ok = f.ok
    angles = np.concatenate([f.flank_angle_left[ok], f.flank_angle_right[ok]])
    se = np.concatenate([f.se_flank_angle_left[ok], f.se_flank_angle_right[ok]])
    assert ok.mean() > 0.95
    assert angles.min() >= 2.8 and angles.max() <= 98.6
    at_bound = angles > 98.5
    assert np.allclose(se[at_bound], 95.67 / np.sqrt(12), rtol=0.01)


def test_a_u_whose_walls_are_drafted_states_the_width_the_readings_allow():
    """U's with walls 0.05-0.2 mm tall drafted by up to 5 degrees either way (a worn or tilted
    cutter), 20 um pitch, 5 um noise: no reading lies on a wall, the U holds its walls
    vertical, and the width it reads off its circle carried none of the draft (k = 2 held the
    width in 69 % of frames). The walls' edges are now where the flank angles put them, each
    anywhere in the gap beside it: the width's interval holds the truth in 90-99.5 % of frames
    (96 % here), and the center's (the circle's) in at least 90 %."""
    rng = np.random.default_rng(8)
    x = (np.arange(250) - 125) * 0.02
    z, width, center = np.empty((400, 250)), np.empty(400), np.empty(400)
    for i in range(400):
        r, wall, draft, c = rng.uniform(0.15, 0.3), rng.uniform(0.05, 0.2), np.radians(rng.uniform(-5, 5)), rng.uniform(-0.5, 0.5)
        half = r + wall * np.tan(draft)
        t = np.linspace(np.pi, 2 * np.pi, 1001)
        pts = np.vstack([[(-3, 0), (c - half, 0)], np.c_[c + r * np.cos(t), -wall + r * np.sin(t)], [(c + half, 0), (3, 0)]])
        z[i] = np.interp(x, pts[:, 0], pts[:, 1]) + 0.005 * rng.standard_normal(250)
        width[i], center[i] = 2 * half, c
    f = machscan.fit_grooves(x, z)
    ok = f.ok
    assert ok.mean() > 0.99 and (f.model[ok] == GrooveModel.U).mean() > 0.6
    for name, truth, low in (("width", width, 0.9), ("x0", center, 0.9)):
        err, se = (getattr(f, name) - truth)[ok], getattr(f, "se_" + name)[ok]
        assert low <= np.mean(np.abs(err) <= 2 * se) <= 0.995, name


def test_an_elliptic_u_with_walls_states_how_far_its_walls_may_lean():
    """An elliptic U with walls 0.08-0.2 mm tall, drafted by up to 4 degrees either way, at a
    20 um pitch: no reading lies on a wall, and the model holds the walls vertical. Their
    angle is bracketed by the gap beside each (the wall from its foot to an edge anywhere in
    it): the k = 2 interval holds the truth in at least 95 % of the frames measured as
    elliptic U's (none when the vertical wall's angle was stated exact, se 0)."""
    rng = np.random.default_rng(5)
    x = (np.arange(250) - 125) * 0.02
    z, angle = np.empty((300, 250)), np.empty(300)
    for i in range(300):
        r, k = rng.uniform(0.2, 0.3), rng.uniform(1.3, 1.7)
        wall, draft, c = rng.uniform(0.08, 0.2), np.radians(rng.uniform(-4, 4)), rng.uniform(-0.3, 0.3)
        t = np.linspace(np.pi, 2 * np.pi, 600)
        bottom = np.c_[c + k * r * np.cos(t), -wall + r * np.sin(t)]
        lean = wall * np.tan(draft)
        pts = np.vstack([[(-3, 0), (c - k * r - lean, 0)], bottom, [(c + k * r + lean, 0), (3, 0)]])
        z[i] = np.interp(x, pts[:, 0], pts[:, 1]) + 0.005 * rng.standard_normal(250)
        angle[i] = 90 - np.degrees(draft)
    f = machscan.fit_grooves(x, z)
    sel = f.ok & (f.model == GrooveModel.ELLIPSE)
    assert sel.sum() > 150
    for side in ("left", "right"):
        err, se = (getattr(f, "flank_angle_" + side) - angle)[sel], getattr(f, "se_flank_angle_" + side)[sel]
        assert se.min() > 0.5, side
        assert np.mean(np.abs(err) <= 2 * se) >= 0.95, side


@pytest.mark.parametrize("shape", synth.GROOVE_SHAPES)
def test_flank_angles_area_and_radius_against_the_generators_truth(shape):
    """The generators' exact truth (flank angles as the frame shows them, the section's area, a
    round bottom's radius): median errors a fraction of what 8 µm noise allows, and the k = 2
    intervals hold the truth in most frames (the full table: benchmarks/coverage_grooves.py)."""
    g = synth.groove_frames(shape, 400, seed=11)
    f = machscan.fit_grooves(g.x, g.z)
    ok = f.ok
    assert ok.mean() > 0.99
    # Near-vertical walls hold few readings (the sensor loses steep flanks): their angle is
    # known to a few degrees (their standard errors say so: a median of 5-6°).
    angle_tol = 3.0 if shape == "u_walls" else 1.5
    for name, truth, tol in (
        ("flank_angle_left", g.flank_angle[:, 0], angle_tol),
        ("flank_angle_right", g.flank_angle[:, 1], angle_tol),
        ("area", g.area, 0.0015),
        ("bottom_radius", g.bottom_radius, 0.01),
    ):
        est, se = getattr(f, name)[ok], getattr(f, "se_" + name)[ok]
        keep = np.isfinite(truth[ok]) & np.isfinite(est)
        if name == "bottom_radius" and shape == "trapezoid":
            assert not keep.any()
            continue
        err = (est - truth[ok])[keep]
        assert np.median(np.abs(err)) < tol, name
        assert np.mean(np.abs(err) <= 2 * se[keep]) > 0.85, name


def test_a_bottom_states_its_depth_area_and_radius_by_its_own_readings():
    """A U with walls drafted or not and top corners rounded or not (the generator's): the
    walls and corners misfit the U, and a σ̂² that carried that misfit into the bottom's
    measures held them at k = 2 in 97.6-98.8 % of frames on this seed. The bottom's depth,
    area and radius now take the sandwich (each reading's own residual): 95.7-97.1 %."""
    g = synth.groove_frames("u_walls", 1000, seed=11)
    f = machscan.fit_grooves(g.x, g.z)
    for name, truth, high in (("depth", g.depth, 0.97), ("area", g.area, 0.97), ("bottom_radius", g.bottom_radius, 0.98)):
        est, se = getattr(f, name), getattr(f, "se_" + name)
        keep = f.ok & np.isfinite(truth) & np.isfinite(est)
        held = np.mean(np.abs(est - truth)[keep] <= 2 * se[keep])
        assert 0.93 <= held <= high, (name, held)


def test_the_paper_template_has_no_section_measures():
    z = template(X, 0.05, 0.0, 0.3, 0.48)[None, :]
    f = machscan.fit_grooves(X, z, template="tanh")
    assert f.ok[0] and np.isfinite(f.se_width[0])
    for name in ("flank_angle_left", "area", "bottom_radius", "step", "se_area", "se_step", "se_x0"):
        assert np.isnan(getattr(f, name)[0]), name


def test_paper_template_fitted_alpha():
    z = template(X, -0.1, 0.0, 0.3, 0.5, a=11.0)[None, :]
    fit = machscan.fit_grooves(X, z, template="tanh", fit_alpha=True)
    assert fit.status[0] == GrooveStatus.CONVERGED
    assert abs(fit.alpha[0] - 11.0) < 1e-4


@pytest.mark.parametrize("method", ["auto", "tanh"])
def test_window_excludes_a_neighboring_groove(method):
    z = template(X, 0.05, 0.0, 0.3, 0.48) + template(X, 1.6, 0.0, 0.31, 0.48)
    narrow = machscan.fit_grooves(X, z[None, :], window=100, template=method)
    assert narrow.status[0] == GrooveStatus.CONVERGED
    assert abs(narrow.x0[0] - 0.05) < 1e-3
    both = machscan.fit_grooves(X, z[None, :], template=method)
    if method == "tanh":  # the paper's pipeline measures one groove per window
        assert both.status[0] == GrooveStatus.TWO_GROOVES
    else:  # the section models find both and measure the deepest
        assert both.status[0] == GrooveStatus.CONVERGED and both.groove[0] == 1
        assert abs(both.x0[0] - 1.6) < 1e-3


def test_every_groove_of_frames_with_several_is_measured():
    # Frames with 2-4 grooves of every shape, a quarter of them sharing a corner with their
    # neighbour (seed not used elsewhere). Measured against BENCHMARKS.md: 97.5 % of frames
    # with every groove found, medians 5.6 µm / 0.71 % / 2.5 µm.
    g = synth.multi_groove_frames(400, seed=31)
    fits = machscan.fit_grooves(g.x, g.z, select="all")
    errors, found = g.match(fits)
    errors = np.abs(errors)
    assert np.mean(found == g.count) >= 0.94
    assert np.mean(found > g.count) <= 0.01  # never more grooves than there are
    w, d, c = np.median(errors, axis=0)
    assert w <= 0.010 and d <= 0.015 and c <= 0.010, (w, d, c)
    # Rows run left to right within each frame, numbered from 0.
    for k in range(len(g.z)):
        rows = np.flatnonzero(fits.frame == k)
        assert np.all(np.diff(fits.x0[rows]) > 0) or len(rows) == 1
        assert list(fits.groove[rows]) == list(range(len(rows)))


def test_the_selection_picks_the_groove_asked_for():
    g = synth.multi_groove_frames(200, seed=32, shared=0.0)
    every = machscan.fit_grooves(g.x, g.z, select="all")
    frames = [np.flatnonzero((every.frame == k) & every.ok) for k in range(len(g.z))]
    whole = [k for k, rows in enumerate(frames) if len(rows) == g.count[k]]
    assert len(whole) >= 190
    for select, kwargs, pick in [
        ("deepest", {}, lambda rows: rows[np.argmax(every.depth[rows])]),
        ("left", {"index": 1}, lambda rows: rows[1]),
        ("right", {}, lambda rows: rows[-1]),
        ("nearest", {"near": 1.0}, lambda rows: rows[np.argmin(np.abs(every.x0[rows] - 1.0))]),
    ]:
        one = machscan.fit_grooves(g.x, g.z, select=select, **kwargs)
        assert len(one) == len(g.z) and list(one.frame) == list(range(len(g.z)))
        agree = [one.groove[k] == every.groove[pick(frames[k])] for k in whole]
        # Deepest and nearest may differ where two grooves are as deep, or as near, to a few µm.
        assert np.mean(agree) >= 0.97, (select, np.mean(agree))
        same = [one.width[k] == every.width[pick(frames[k])] for k in whole if one.groove[k] == every.groove[pick(frames[k])]]
        assert all(same)  # a groove is measured the same alone or among the others


def test_validity_limits_pass_over_grooves_outside_them():
    g = synth.multi_groove_frames(100, seed=33, shared=0.0)
    # Each frame's own depths (a pooled rounding prior depends on the grooves pooled, and the
    # limits judge each groove's own measure): the selection's rule, exactly.
    every = machscan.fit_grooves(g.x, g.z, select="all", rounding="frame")
    limited = machscan.fit_grooves(g.x, g.z, select="all", min_width=0.5, max_depth=0.3, rounding="frame")
    ok = limited.ok
    assert ok.any() and np.all(limited.width[ok] >= 0.5) and np.all(limited.depth[ok] <= 0.3)
    inside = every.ok & (every.width >= 0.5) & (every.depth <= 0.3)
    assert ok.sum() == inside.sum()
    deepest = machscan.fit_grooves(g.x, g.z, max_depth=0.3, rounding="frame")
    for k in np.flatnonzero(deepest.ok):
        rows = np.flatnonzero((every.frame == k) & every.ok & (every.depth <= 0.3))
        assert deepest.depth[k] == pytest.approx(every.depth[rows].max(), abs=1e-12) or len(rows) == 0


def test_selection_mistakes_are_refused_by_name():
    z = template(X, 0.0, 0.0, 0.3, 0.48)[None, :]
    for kwargs, name in [
        ({"select": "nearest"}, "near"),
        ({"select": "left", "near": 1.0}, "near"),
        ({"index": 2}, "index"),
        ({"select": "widest"}, "select"),
        ({"select": "all", "template": "tanh"}, "select"),
        ({"min_width": -0.1}, "min_width"),
        ({"min_width": 0.6, "max_width": 0.5}, "max_width"),
        ({"max_depth": 0.01}, "max_depth"),
        ({"index": -1, "select": "left"}, "index"),
    ]:
        with pytest.raises(ValueError, match=f"^{name}:"):
            machscan.fit_grooves(X, z, **kwargs)


def test_all_grooves_in_dask_chunks_equal_in_memory():
    g = synth.multi_groove_frames(60, seed=34)
    import dask.array as da

    import machscan.dask as mdask

    lazy = mdask.fit_grooves(g.x, da.from_array(g.z, chunks=(25, -1)), select="all").compute(scheduler="synchronous")
    eager = machscan.fit_grooves(g.x, g.z, select="all")
    assert list(lazy.frame) == list(eager.frame) and list(lazy.groove) == list(eager.groove)
    np.testing.assert_array_equal(lazy.width, eager.width)


@pytest.mark.parametrize("method", ["auto", "tanh"])
def test_every_failed_frame_says_why_and_no_nan_hides(method):
    rng = np.random.default_rng(3)
    good = template(X, 0.0, 0.0, 0.31, 0.48) + rng.normal(0, 0.008, 200)
    flat = rng.normal(0, 0.008, 200)
    nan = np.full(200, np.nan)
    sparse = good.copy()
    sparse[rng.random(200) < 0.97] = np.nan
    edge = template(X, -2.45, 0.0, 0.31, 0.48)
    fits = machscan.fit_grooves(X, np.vstack([good, flat, nan, sparse, edge]), template=method)
    assert list(fits.status) == [
        GrooveStatus.CONVERGED,
        GrooveStatus.NO_GROOVE,
        GrooveStatus.TOO_FEW_VALID,
        GrooveStatus.TOO_FEW_VALID,
        GrooveStatus.CLIPPED,
    ]
    # NaN only where the status says the frame was not fitted.
    assert np.isfinite(fits.depth[fits.ok]).all()
    assert np.isnan(fits.depth[~fits.ok]).all()
    assert fits.counts()["no_groove"] == 1
    assert "not fitted" in fits.summary()


@pytest.mark.parametrize("method", ["auto", "tanh"])
def test_spikes_do_not_move_the_fit(method):
    rng = np.random.default_rng(5)
    z = template(X, 0.0, 0.0, 0.31, 0.48) + rng.normal(0, 0.008, 200)
    clean = machscan.fit_grooves(X, z[None, :], template=method)
    spiky = z.copy()
    spiky[[20, 95, 150]] += [0.8, -0.9, 1.5]
    fit = machscan.fit_grooves(X, spiky[None, :], template=method)
    assert fit.ok[0]
    assert abs(fit.depth[0] - clean.depth[0]) < 0.005


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: machscan.fit_grooves(X, np.zeros((3, 150))), "z"),
        (lambda: machscan.fit_grooves(X[:, None], np.zeros((3, 200))), "x"),
        (lambda: machscan.fit_grooves(X, np.zeros((3, 200)), window=300), "window"),
        (lambda: machscan.fit_grooves(X, np.zeros((3, 200)), window_center=200), "window_center"),
        (lambda: machscan.fit_grooves(X, np.zeros((3, 200)), alpha=-1), "alpha"),
        (lambda: machscan.fit_grooves(X, np.zeros((3, 200)), nominal_width=0), "nominal_width"),
        (lambda: machscan.fit_grooves(np.where(X > 0, np.nan, X), np.zeros((3, 200))), "x"),
        (lambda: machscan.fit_grooves(X, np.zeros((1, 200)), template="w"), "template"),
        (lambda: machscan.fit_grooves(X, np.zeros((1, 200)), criteria=machscan.FitCriteria(step_tolerance=-1)), "step_tolerance"),
        (lambda: machscan.fit_grooves(X, np.zeros((1, 200)), criteria={"max_iterations": 3}), "criteria"),
    ],
)
def test_bad_input_raises_value_error(call, name):
    with pytest.raises(ValueError) as exc:
        call()
    assert str(exc.value).startswith(name), str(exc.value)


def test_one_frame_may_be_given_as_a_1d_array():
    z = straight_v_frames(3, seed=4)
    every = machscan.fit_grooves(X, z)
    for k in range(3):
        one = machscan.fit_grooves(X, list(z[k]))
        assert len(one) == 1
        for a in ("x0", "depth", "width", "status", "model"):
            assert np.array_equal(getattr(one, a), getattr(every, a)[k : k + 1])
    with pytest.raises(ValueError, match=r"^z"):
        machscan.fit_grooves(X, z[0, :150])


def test_parallel_equals_sequential():
    script = textwrap.dedent(
        """
        import hashlib, numpy as np, machscan
        g = machscan.synth.groove_frames("v", 1500, seed=1)
        f = machscan.fit_grooves(g.x, g.z)
        t = machscan.fit_grooves(g.x, g.z, template="tanh")
        print(hashlib.sha256(b"".join(a.tobytes() for a in (f.x0, f.depth, f.width, f.status, t.x0, t.width))).hexdigest())
        """
    )
    digests = {
        subprocess.run(
            [sys.executable, "-c", script], env=dict(os.environ, RAYON_NUM_THREADS=t), capture_output=True, text=True, check=True
        ).stdout
        for t in ("1", "2")
    }
    assert len(digests) == 1


def straight_v_frames(f, seed, w=0.48, d=0.31):
    rng = np.random.default_rng(seed)
    x0 = rng.uniform(-0.3, 0.3, f)[:, None]
    u = np.abs(X - x0)
    return np.where(u < w / 2, -d * (1 - u / (w / 2)), 0.0) + rng.normal(0, 0.008, (f, 200))


def test_paper_template_is_biased_on_a_straight_v_and_the_default_is_not():
    z = straight_v_frames(500, seed=8)
    tanh = machscan.fit_grooves(X, z, window=200, template="tanh")
    assert np.median(tanh.width[tanh.ok]) / 0.48 - 1 > 0.15  # the measured bias (~18 %)
    for method in ("auto", "v"):
        f = machscan.fit_grooves(X, z, window=200, template=method)
        assert f.ok.mean() > 0.99
        assert abs(np.median(f.width[f.ok]) / 0.48 - 1) < 0.005
        assert abs(np.median(f.depth[f.ok]) / 0.31 - 1) < 0.01


def test_criteria_apply_and_defaults_are_each_methods_own():
    g = synth.groove_frames("u", 100, seed=14)
    capped = machscan.fit_grooves(g.x, g.z, criteria=machscan.FitCriteria(max_iterations=1))
    default = machscan.fit_grooves(g.x, g.z)
    # One iteration per model fit: five models (the elliptic U among them), refitted once
    # without outliers, one sheared refit, and the 3 × 1 of finishing an unconverged choice: at
    # most 14 per frame.
    assert capped.iterations.max() <= 14 < default.iterations.max()
    assert (capped.status == GrooveStatus.MAX_ITERATIONS).mean() > 0.1
    assert (default.status == GrooveStatus.MAX_ITERATIONS).sum() == 0
    d = machscan.grooves.CRITERIA_DEFAULTS
    assert d["section"]["max_iterations"] == 15 and d["tanh"]["max_iterations"] == 100
    assert machscan.FitCriteria() == machscan.FitCriteria(None, None, None, None)


def test_invalid_readings_are_invalid_to_the_groove_fit_as_to_every_function_that_takes_frames():
    # Issue #32 §2: raw frames holding the vendor's no-reading code fit exactly as the same frames with NaN there,
    # by the rule machscan.Profiler.valid_mask and scan_to_wcs apply (NaN, the sentinel, outside the range).
    g = synth.groove_frames("v", 300, seed=5)
    raw = g.z.copy()
    rng = np.random.default_rng(6)
    holes = rng.random(raw.shape) < 0.05
    raw[holes] = machscan.SENTINEL
    raw[:, 90:95] = machscan.SENTINEL  # a dropout across the middle of the window in every frame
    raw[::7, 10] = 55.0  # out of the measuring range below
    with_nan = np.where(raw == machscan.SENTINEL, np.nan, raw)
    with_nan[::7, 10] = np.nan
    a = machscan.fit_grooves(g.x, raw, window=150, valid_range=(-20.0, 20.0))
    b = machscan.fit_grooves(g.x, with_nan, window=150)
    assert a.ok.sum() >= 0.95 * len(a)
    np.testing.assert_array_equal(a.status, b.status)
    np.testing.assert_array_equal(a.width, b.width)
    # The mask a Profiler gives is the core's rule: the same readings.
    profiler = machscan.Profiler(readings=raw.shape[1], pitch=0.025, valid_range=(-20.0, 20.0))
    np.testing.assert_array_equal(profiler.valid_mask(raw), ~np.isnan(with_nan))
    points, _ = machscan.profile_to_points(raw, 0.025, valid_range=(-20.0, 20.0))
    assert len(points) == int(profiler.valid_mask(raw).sum())
    # One frame as the fit sees it drops them too.
    view = machscan.level_groove_frame(g.x, raw[0], window=150)
    assert np.isfinite(view.z).all() and len(view.z) <= int((~np.isnan(with_nan[0])).sum())
    # Without a sentinel the code is a reading (far below: the frame has no groove it can measure).
    kept = machscan.fit_grooves(g.x, raw, window=150, sentinel=None)
    assert kept.ok.sum() < a.ok.sum()


def rounded_vs(n, seed, across_max, pitch=0.02, noise=0.006):
    """V's none of the generators make: 250 readings at 20 µm, 6 µm noise, 0.3–0.7 mm wide,
    0.15–0.4 mm deep, the tip rounded by an arc tangent to both flanks over 0–``across_max``
    mm, lips up to 20 µm, tilt ±0.04 rad; the frames and the exact depths."""
    from machscan.synth.frames import _fillet_polyline, _topmost

    rng = np.random.default_rng(seed)
    x = (np.arange(250) - 125) * pitch
    z, depth = np.empty((n, 250)), np.empty(n)
    for k in range(n):
        w, d = rng.uniform(0.3, 0.7), rng.uniform(0.15, 0.4)
        r = rng.uniform(0, across_max) / (2 * np.sin(np.arctan2(d, w / 2)))
        poly = _fillet_polyline([(-5, 0), (-w / 2, 0), (0, -d), (w / 2, 0), (5, 0)], [0, 0.005, r, 0.005, 0])
        u, v = poly[:, 0], poly[:, 1].copy()
        depth[k] = -v.min()
        for side in (-1, 1):
            tau = (u - side * (w / 2 + 0.05)) / 0.04
            v += rng.uniform(0.0, 0.02) * np.where(np.abs(tau) < 1, (1 - tau * tau) ** 2, 0.0)
        t, xc = rng.uniform(-0.04, 0.04), rng.uniform(-0.8, 0.8)
        c, s = np.cos(t), np.sin(t)
        z[k] = _topmost(xc + u * c - v * s, u * s + v * c, x) + noise * rng.standard_normal(250)
    return x, z, depth


def test_a_tip_rounding_pooled_over_the_call_measures_rounded_vs_without_bias():
    # Issue #35 §1: one frame cannot tell a tip rounded over a reading or two from a sharp one;
    # the call's V's can. Measured before the change on these frames (400, seed 1): each
    # frame's own rule 1.95 % median |depth error|, bias +3.6 µm; pooled 1.32 %, +0.9 µm.
    x, z, depth = rounded_vs(400, 1, 0.08)
    pooled, own = machscan.fit_grooves(x, z), machscan.fit_grooves(x, z, rounding="frame")
    assert pooled.rounding_prior is not None and own.rounding_prior is None
    share, r_max = pooled.rounding_prior
    assert 0 <= share <= 1 and 0 < r_max < 0.1  # the arcs' radii reach 0.08 / (2 sin 37°) = 66 µm
    ok = pooled.ok & own.ok
    e_pooled, e_own = (pooled.depth - depth)[ok], (own.depth - depth)[ok]
    assert np.median(np.abs(e_pooled)) < 0.8 * np.median(np.abs(e_own))
    assert abs(np.median(e_pooled)) < 0.002  # the 2 µm
    held = np.mean(np.abs(e_pooled) <= 2 * pooled.se_depth[ok])
    assert 0.92 <= held <= 0.985, held
    # Sharp V's of the same part: the prior goes to the sharp tip, and no depth is worse off.
    x, z, depth = rounded_vs(400, 2, 0.0)
    pooled, own = machscan.fit_grooves(x, z), machscan.fit_grooves(x, z, rounding="frame")
    share, r_max = pooled.rounding_prior
    assert share > 0.5 or r_max <= 0.005  # most tips sharp, or none rounded by more than a quarter pitch
    ok = pooled.ok & own.ok
    assert np.median(np.abs(pooled.depth - depth)[ok]) <= np.median(np.abs(own.depth - depth)[ok])
    assert np.mean(np.abs(pooled.depth - depth)[ok] <= 2 * pooled.se_depth[ok]) >= 0.93


def test_a_pooled_prior_is_the_same_in_blocks_chunks_and_one_frame():
    x, z, _ = rounded_vs(120, 3, 0.08)
    whole = machscan.fit_grooves(x, z)
    assert whole.rounding_prior is not None
    assert "V tip rounding prior" in whole.summary() and "µm" in whole.summary()
    # Fitted in blocks (the progress bar) the blocks measure under the whole call's prior.
    blocks = machscan.fit_grooves(x, z, progress=True)
    given = machscan.fit_grooves(x, z, rounding=whole.rounding_prior)
    for other in (blocks, given):
        assert other.rounding_prior == whole.rounding_prior
        np.testing.assert_array_equal(other.depth, whole.depth)
        np.testing.assert_array_equal(other.se_depth, whole.se_depth)
    # The prior as any pair of numbers.
    listed = machscan.fit_grooves(x, z, rounding=list(whole.rounding_prior))
    np.testing.assert_array_equal(listed.depth, whole.depth)
    # One frame pools nothing: given the call's prior, the view shows the call's depth.
    k = int(np.flatnonzero(whole.model == GrooveModel.ROUND)[0])
    view = machscan.level_groove_frame(x, z[k], rounding=whole.rounding_prior)
    assert view.fit.depth[0] == whole.depth[k]
    # Too few V's to pool: each frame's own rule, and the result says so.
    few = machscan.fit_grooves(x, z[:20])
    assert few.rounding_prior is None
    np.testing.assert_array_equal(few.depth, machscan.fit_grooves(x, z[:20], rounding="frame").depth)


def bowls(n, seed, power=2, pitch=0.02, noise=0.005):
    """Bowls none of the generators make and none of the models holds: v = −d·(1 − |2u/w|^power),
    250 readings at 20 µm, 5 µm noise, 0.35–0.7 mm wide, 0.08–0.3 mm deep, lips up to 20 µm
    beside most edges, tilt ±0.05 rad; the frames and the exact depths."""
    from machscan.synth.frames import _topmost

    rng = np.random.default_rng(seed)
    x = (np.arange(250) - 125) * pitch
    z, depth = np.empty((n, 250)), np.empty(n)
    for k in range(n):
        w, d = rng.uniform(0.35, 0.7), rng.uniform(0.08, 0.3)
        u = np.concatenate([[-5.0], np.linspace(-w / 2, w / 2, 2001), [5.0]])
        v = -d * (1 - np.abs(2 * u / w) ** power)
        v[[0, -1]] = 0.0
        depth[k] = d
        for side in (-1, 1):
            if rng.random() < 0.75:
                tau = (u - side * (w / 2 + 0.05)) / 0.04
                v += rng.uniform(0.0, 0.02) * np.where(np.abs(tau) < 1, (1 - tau * tau) ** 2, 0.0)
        t, xc = rng.uniform(-0.05, 0.05), rng.uniform(-0.8, 0.8)
        c, s = np.cos(t), np.sin(t)
        z[k] = _topmost(xc + u * c - v * s, u * s + v * c, x) + noise * rng.standard_normal(250)
    return x, z, depth


def test_a_bowl_no_model_holds_states_its_depth_with_the_misfit_its_frames_pool():
    # Issue #35 §3 on sections no model holds: a parabolic bowl is measured as the nearest
    # model's (a round V or a U), whose bias at the bottom its own errors leave out. Measured
    # before the change (coverage_grooves.py, 1000 frames): ±2·se held the depth in 59 %.
    x, z, depth = bowls(400, 1)
    pooled, alone = machscan.fit_grooves(x, z), machscan.fit_grooves(x, z, misfit="none")
    assert alone.misfit is None and pooled.misfit and max(pooled.misfit.values()) > 0
    np.testing.assert_array_equal(pooled.depth, alone.depth)  # the errors change, not the depths
    ok = pooled.ok
    e = np.abs(pooled.depth - depth)[ok]
    held_alone, held = np.mean(e <= 2 * alone.se_depth[ok]), np.mean(e <= 2 * pooled.se_depth[ok])
    assert held_alone < 0.75 and held >= 0.85, (held_alone, held)
    assert "bottom misfit in se_depth" in pooled.summary() and "µm" in pooled.summary()
    # The misfit (5.9 µm at most, against a median RMS of 5.4 µm) is near the noise: the summary says what
    # the errors then leave out.
    assert "no section model holds these bottoms" in pooled.summary() and pooled.models_hold is False
    assert alone.models_hold is None and pooled.select(pooled.ok).models_hold is False
    # The tanh template has no section, so no misfit: nothing tells.
    assert machscan.fit_grooves(x, z, template="tanh").models_hold is None
    # Sections the models hold: the bottoms' residuals are the noise's, and no error moves by
    # more than a few percent.
    g = synth.groove_frames("u", 400, seed=2)
    f, f0 = machscan.fit_grooves(g.x, g.z), machscan.fit_grooves(g.x, g.z, misfit="none")
    assert f.misfit["u"] < 0.002**2, f.misfit  # below (2 µm)², on noise of 8 µm
    assert np.median(f.se_depth[f.ok] / f0.se_depth[f.ok]) < 1.02
    assert "no section model holds" not in f.summary() and f.models_hold is True


def half_ellipses(n, seed, pitch=0.02, noise=0.005):
    """Elliptic sections cut a little below their axis (semi-axes 0.25–0.35 mm across,
    0.18–0.26 mm down, axis 0–0.06 mm above the surface), 250 readings at 20 µm, 5 µm noise,
    tilt ±0.05 rad: frames, and the exact flank angles (degrees) and bottom radii (a²/b, mm)."""
    from machscan.synth.frames import _topmost

    rng = np.random.default_rng(seed)
    x = (np.arange(250) - 125) * pitch
    z, angle, radius = np.empty((n, 250)), np.empty(n), np.empty(n)
    for k in range(n):
        a, b, cut = rng.uniform(0.25, 0.35), rng.uniform(0.18, 0.26), rng.uniform(0.0, 0.06)
        half = a * np.sqrt(1 - (cut / b) ** 2)
        u = np.concatenate([[-5.0], np.linspace(-half, half, 2001), [5.0]])
        v = cut - b * np.sqrt(np.clip(1 - (u / a) ** 2, 0, 1))
        v[[0, -1]] = 0.0
        angle[k], radius[k] = np.degrees(np.arctan2(b * b * half, a * a * cut)), a * a / b
        t, xc = rng.uniform(-0.05, 0.05), rng.uniform(-0.8, 0.8)
        c, s = np.cos(t), np.sin(t)
        z[k] = _topmost(xc + u * c - v * s, u * s + v * c, x) + noise * rng.standard_normal(250)
    return x, z, angle, radius


def test_a_circle_kept_over_an_ellipse_states_the_ellipse_it_may_be():
    # Issue #35 §3: the U is kept over the elliptic U unless the ellipse fits clearly better,
    # so on ellipses a little wider than deep some frames are measured as circles, whose
    # errors (k = 1 fixed) left out the stretch. Measured before the change
    # (coverage_grooves.py, 1000 frames): ±2·se held the half-ellipses' flank angles in 90 %,
    # radii in 90 %; on the U-chosen frames alone in about half.
    x, z, angle, radius = half_ellipses(400, 5)
    pooled, alone = machscan.fit_grooves(x, z), machscan.fit_grooves(x, z, misfit="none")
    assert pooled.misfit["u:flank_angle_left"] > 1.0, pooled.misfit  # above (1°)²
    np.testing.assert_array_equal(pooled.flank_angle_left, alone.flank_angle_left)
    u = pooled.ok & (pooled.model == GrooveModel.U)
    assert u.sum() >= 20, u.sum()
    # On this set (seed 5): angles 89 → 96 % of all frames (U's 50 → 94 %), radii 88 → 96 %
    # (U's 50 → 100 %).
    for values, truth in (("flank_angle_left", angle), ("bottom_radius", radius)):
        e = np.abs(getattr(pooled, values) - truth)
        se_alone, se = getattr(alone, "se_" + values), getattr(pooled, "se_" + values)
        held_alone, held = np.mean((e <= 2 * se_alone)[pooled.ok]), np.mean((e <= 2 * se)[pooled.ok])
        assert held_alone < 0.91 and held >= 0.93, (values, held_alone, held)
        assert np.mean((e <= 2 * se_alone)[u]) < 0.6 and np.mean((e <= 2 * se)[u]) >= 0.8, values
    # Only the U's errors move.
    np.testing.assert_array_equal(pooled.se_width[~u], alone.se_width[~u])
    assert "U against the ellipse" in pooled.summary() and "°" in pooled.summary()
    # Circles: the ellipse's differences are the noise's (their mean at most the ellipse's own
    # small bias), and the U's errors barely move.
    g = synth.groove_frames("u", 400, seed=2)
    f, f0 = machscan.fit_grooves(g.x, g.z), machscan.fit_grooves(g.x, g.z, misfit="none")
    assert all(v == 0.0 for k, v in f.misfit.items() if k.startswith("u:") and not k.endswith(":bias")), f.misfit
    for se in ("se_width", "se_flank_angle_left", "se_bottom_radius"):
        ratio = getattr(f, se)[f.ok] / getattr(f0, se)[f.ok]  # (NaN: a measure the model lacks)
        assert np.nanmedian(ratio) < 1.01 and np.nanmax(ratio) < 1.2, se


def test_a_ball_cutter_crossed_nearly_square_states_the_stretch_its_circles_leave_out():
    # Crossed 0–35° off the perpendicular, the ellipse is at most 1.22 times wider than deep
    # and most frames are measured as U's; every frame's stretch is the same way, so each
    # difference from the ellipse lies within its noise and pools to no variance, but their
    # mean is a bias every U shares. Before (the variance pooled alone): ±2·se held the radii
    # in 81 % of frames and the flank angles in 83 % (own scratch set, 1000 frames).
    x, z, truth = elliptic_frames(400, 9, phi=(0, 35))
    pooled, alone = machscan.fit_grooves(x, z), machscan.fit_grooves(x, z, misfit="none")
    assert np.mean(pooled.model[pooled.ok] == GrooveModel.U) > 0.6
    # The ellipse's bottom is flatter than the circle's: its radius larger.
    assert pooled.misfit["u:bottom_radius:bias"] > 0 and pooled.misfit["u:flank_angle_left:bias"] != 0, pooled.misfit
    for name in ("bottom_radius", "flank_angle_left"):
        e = np.abs(getattr(pooled, name) - truth[name])[pooled.ok]
        held_alone = np.mean(e <= 2 * getattr(alone, "se_" + name)[pooled.ok])
        held = np.mean(e <= 2 * getattr(pooled, "se_" + name)[pooled.ok])
        assert held_alone < 0.9 and 0.93 <= held <= 0.985, (name, held_alone, held)


def test_a_pooled_misfit_is_the_same_in_blocks_chunks_and_one_frame():
    import dask.array as da

    import machscan.dask

    x, z, _ = bowls(150, 3)
    whole = machscan.fit_grooves(x, z)
    assert whole.misfit and max(whole.misfit.values()) > 0
    blocks = machscan.fit_grooves(x, z, progress=True)
    given = machscan.fit_grooves(x, z, misfit=whole.misfit)
    chunked = machscan.dask.fit_grooves(x, da.from_array(z, chunks=(40, -1))).compute()
    for other in (blocks, given, chunked):
        assert other.misfit == whole.misfit
        for se in ("se_depth", "se_width", "se_x0", "se_flank_angle_left", "se_bottom_radius"):
            np.testing.assert_array_equal(getattr(other, se), getattr(whole, se))
    # One frame pools nothing: given the call's misfit, the view states the call's error.
    k = int(np.flatnonzero(whole.ok & (whole.model == GrooveModel.U))[0])
    view = machscan.level_groove_frame(x, z[k], misfit=whole.misfit)
    assert view.fit.se_depth[0] == whole.se_depth[k] and view.fit.misfit == whole.misfit
    # A model chosen in too few frames is not pooled: nothing is added to its frames.
    few = machscan.fit_grooves(x, z[:20])
    assert few.misfit == {}
    np.testing.assert_array_equal(few.se_depth, machscan.fit_grooves(x, z[:20], misfit="none").se_depth)


@pytest.mark.parametrize(
    ("value", "says"),
    [
        ("pool", "expected"),
        ({"u": -1e-6}, "must be >= 0"),
        ({"u": np.nan}, "must be >= 0"),
        ({"bowl": 1e-6}, "no section model"),
        ({"u:slope": 1e-6}, "no section model"),
        ({"u:width": -1e-6}, "must be >= 0"),
        ({"u:width:bias": np.inf}, "must be finite"),
        (0.5, "expected"),
        (None, "expected"),
    ],
)
def test_a_misfit_rule_that_is_not_one_is_refused_by_name(value, says):
    x, z, _ = bowls(2, 4)
    with pytest.raises(ValueError, match="misfit") as err:
        machscan.fit_grooves(x, z, misfit=value)
    assert says in str(err.value)


@pytest.mark.parametrize("value", ["pool", (1.5, 0.05), (0.5, -0.01), (0.5, np.nan), 0.05, (0.5, 0.05, 1.0), None])
def test_a_rounding_rule_that_is_not_one_is_refused_by_name(value):
    with pytest.raises(ValueError, match=r"^rounding:"):
        machscan.fit_grooves(X, template(X, 0.0, 0.0, 0.3, 0.48)[None, :], rounding=value)
