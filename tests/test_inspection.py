"""Groove inspection end to end on synthetic scans with exact truth (issue #3 §4)."""

import numpy as np
import pytest

import machscan
from machscan import synth
from machscan.inspection import inspect_grooves


@pytest.fixture(scope="module")
def run(groove_scan, groove_report):
    scan, truth = groove_scan
    return scan, truth, groove_report


def test_width_and_depth_per_frame_against_truth(run):
    _scan, truth, r = run
    ok = r.fits.ok
    assert ok.mean() > 0.99
    w_err = np.abs(r.fits.width[ok] - truth.width[ok])
    d_rel = (r.fits.depth[ok] - truth.depth[ok]) / truth.depth[ok]
    assert np.median(w_err) <= 0.010
    # The demo's V has its bottom rounded to 0.01 mm, barely visible at 8 µm noise: a sharp V
    # fitted to it reads 0.01·(sec θ − 1) ≈ 6 µm (2 %) deep; the V/R average halves that.
    assert np.median(np.abs(d_rel)) <= 0.02 and 0 < np.median(d_rel) < 0.02


def test_groove_centers_in_the_wcs(run):
    _scan, truth, r = run
    ok = r.used
    assert ok.mean() > 0.98
    err = np.linalg.norm(r.center_wcs[ok] - truth.center_wcs[ok], axis=1)
    assert np.sqrt(np.mean(err**2)) <= 0.010
    assert np.isnan(r.center_wcs[~ok]).all()


def test_every_contour_found_and_matched(run):
    _scan, truth, r = run
    assert [c.cad_index for c in r.contours] == list(range(11))
    assert r.unmatched_cad == () and r.unmatched_clusters == ()
    for c in r.contours:
        assert (truth.frame_contour[c.frames] == c.cad_index).all()


def test_contour_error_recovers_the_truth(run):
    _scan, truth, r = run
    for c in r.contours:
        true_contour = machscan.resample_polyline(np.asarray(truth.engraved_polylines[c.cad_index]), 0.002, closed=True)
        ref = machscan.contour_error(c.theoretical, true_contour)
        assert np.sqrt(np.mean((c.error.errors - ref.errors) ** 2)) <= 0.010, c.cad_index
        # The offset alone (bending taken out) against the applied offset.
        assert abs(c.offset_error - np.linalg.norm(truth.offsets[c.cad_index])) <= 0.005


def test_the_contour_error_building_block_gives_the_reports_figure(run):
    # Issue #32 §2: machscan.contour_error as the README shows it, on the report's own inputs (the contour's CAD
    # points and its groove centers), gives the report's figure; from the bare CAD polyline too (resampled alike).
    _scan, truth, r = run
    for c in r.contours:
        centers = r.center_wcs[r.contour == c.cad_index]
        err = machscan.contour_error(c.theoretical, centers)
        np.testing.assert_array_equal(err.errors, c.error.errors)
        assert err.mean == c.error.mean and err.max == c.error.max
        polyline = np.asarray(truth.nominal_polylines[c.cad_index], dtype=float)
        if polyline.shape[1] == 2:
            polyline = np.column_stack([polyline, np.zeros(len(polyline))])
        from_cad = machscan.contour_error(polyline, centers)
        assert abs(from_cad.mean - c.error.mean) < 0.001 and abs(from_cad.max - c.error.max) < 0.003
    # The paper's formula on the bare centers measures the gaps between frames as well: further off.
    c = r.contours[0]
    bare = machscan.contour_error(c.theoretical, r.center_wcs[r.contour == c.cad_index], actual_spacing=None)
    assert bare.mean > c.error.mean + 0.01


def test_decomposition_shares_within_5_points_of_truth(run):
    _scan, truth, r = run
    off = np.linalg.norm(truth.center_offset, axis=1).mean()
    bend = np.abs(truth.center_bend).mean()
    loc = np.abs(truth.center_local).mean()
    true_shares = np.array([off, bend, loc]) / (off + bend + loc)
    d = r.decomposition
    got = np.array([d.offset_share, d.bending_share, d.local_share])
    assert np.abs(got - true_shares).max() <= 0.05, (got, true_shares)
    assert abs(got.sum() - 1) < 1e-12


def test_tables_and_csv(run, tmp_path):
    scan, _truth, r = run
    text = r.summary()
    assert "shares of the error" in text and "all" in text
    paths = r.to_csv(tmp_path)
    assert [p.name for p in paths] == ["frames.csv", "widths.csv", "contour_errors.csv"]
    rows = np.genfromtxt(tmp_path / "widths.csv", delimiter=",", names=True)
    assert len(rows) == 12 and np.isfinite(rows["width_mean_mm"]).all()
    frames = np.genfromtxt(tmp_path / "frames.csv", delimiter=",", names=True)
    assert len(frames) == scan.n_frames
    # Every measure with its standard error, each column named with its unit, as the fits hold
    # them (to the CSV's printed digits).
    for column, name in (
        ("flank_angle_left_deg", "flank_angle_left"),
        ("se_flank_angle_right_deg", "se_flank_angle_right"),
        ("area_mm2", "area"),
        ("se_area_mm2", "se_area"),
        ("bottom_radius_mm", "bottom_radius"),
        ("step_mm", "step"),
        ("se_step_mm", "se_step"),
        ("se_x0_mm", "se_x0"),
        ("se_z0_mm", "se_z0"),
    ):
        np.testing.assert_allclose(frames[column], getattr(r.fits, name), rtol=1e-6, atol=1e-9, err_msg=column)
    assert "flank_angle_left" in r.fits.summary() and "°" in r.fits.summary()
    # No NaN in a table: the per-contour tables are all numbers.
    errs = np.genfromtxt(tmp_path / "contour_errors.csv", delimiter=",", names=True)
    assert all(np.isfinite(errs[n]).all() for n in errs.dtype.names)


def test_unmatched_contours_are_reported():
    scan, truth = synth.groove_scan(seed=1, readings=800, keep_every=100)
    cad = list(truth.nominal_polylines)
    extra = np.asarray(cad[0]) + [0.0, 300.0, 0.0]  # off the plate: never engraved
    r = inspect_grooves(scan, cad[1:] + [extra])
    assert r.unmatched_cad == (10,)
    assert len(r.unmatched_clusters) == 1  # contour 0 was engraved but is not in this CAD
    assert len(r.contours) == 10


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(cad_contours=[np.zeros((2, 3))]), "cad_contours"),
        (dict(cad_contours=[]), "cad_contours"),
        (dict(cad_contours=np.zeros((2, 3))), "cad_contours"),
        (dict(cad_contours=[np.full((4, 3), np.nan)]), "cad_contours"),
        (dict(window=10**6), "window"),
        (dict(min_cluster_frames=0), "min_cluster_frames"),
    ],
)
def test_bad_input(kwargs, name):
    scan, truth = synth.groove_scan(seed=2, readings=400, keep_every=400)
    args = dict(cad_contours=truth.nominal_polylines)
    args.update(kwargs)
    with pytest.raises(ValueError) as exc:
        inspect_grooves(scan, **args)
    assert str(exc.value).startswith(name)


def test_scan_without_grooves_gives_an_empty_report():
    scan, truth = synth.groove_scan(seed=3, readings=400, keep_every=400)
    flat = scan.frames.copy()
    flat[:] = 0.0
    from dataclasses import replace

    r = inspect_grooves(replace(scan, frames=flat), truth.nominal_polylines)
    assert r.contours == () and r.decomposition is None
    assert (r.fits.status == machscan.GrooveStatus.NO_GROOVE).all()
    assert r.unmatched_cad == tuple(range(11))
    assert "0 contours matched" in r.summary()


def test_suspect_fits_are_left_out_when_asked(run):
    scan, truth, r = run
    assert not r.suspect.any()
    screened = inspect_grooves(scan, truth.nominal_polylines, max_se_ratio=5.0)
    f = screened.fits
    ratio = np.maximum(f.se_width / np.median(f.se_width[f.ok]), f.se_depth / np.median(f.se_depth[f.ok]))
    np.testing.assert_array_equal(screened.suspect, f.ok & (ratio > 5.0))
    assert 0 < screened.suspect.sum() < 0.02 * len(f)
    assert not screened.used[screened.suspect].any() and np.isnan(screened.center_wcs[screened.suspect]).all()
    assert "suspect" in screened.summary()


def test_cad_as_one_point_set_is_clustered_into_contours(run):
    scan, truth, r = run
    cloud = np.vstack([machscan.resample_polyline(np.asarray(p), 0.005, closed=True) for p in truth.nominal_polylines])
    r2 = inspect_grooves(scan, cloud[np.random.default_rng(0).permutation(len(cloud))])
    assert len(r2.contours) == 11 and r2.unmatched_cad == ()
    # Same contours (in clustering order), same errors as from the polylines.
    by_centroid = {tuple(np.round(c.theoretical.mean(0), 3)): c for c in r.contours}
    for c in r2.contours:
        ref = by_centroid[tuple(np.round(c.theoretical.mean(0), 3))]
        assert abs(c.error.mean - ref.error.mean) < 1e-4


def test_the_bending_surface_is_the_least_squares_polynomial():
    # The core's fit against NumPy's least squares on the same design matrix: the same polynomial
    # to rounding, the degree lowered until three points hold each coefficient.
    from machscan import _core

    rng = np.random.default_rng(3)
    x, y = rng.uniform(-90, 90, 200), rng.uniform(-60, 60, 200)
    dz = 0.05 + 1e-3 * x - 2e-5 * x * y + 3e-7 * y**3 + rng.normal(0, 0.002, 200)
    fit = _core.fit_bending_surface(x, y, dz, degree=4)
    u, v = (x - fit["center"][0]) / fit["scale"], (y - fit["center"][1]) / fit["scale"]
    a = np.column_stack([u**i * v**j for i, j in fit["exponents"]])
    coef, *_ = np.linalg.lstsq(a, dz, rcond=None)
    assert fit["degree"] == 4 and len(coef) == 15
    assert np.abs(fit["coefficients"] - coef).max() < 1e-12
    assert fit["rms_residual"] == pytest.approx(np.sqrt(np.mean((dz - a @ coef) ** 2)), rel=1e-12)
    at = _core.bending_surface_at(fit["exponents"], fit["coefficients"], fit["center"], fit["scale"], x[:5], y[:5])
    assert np.abs(at - a[:5] @ coef).max() < 1e-12
    assert _core.fit_bending_surface(x[:20], y[:20], dz[:20], degree=4)["degree"] == 2


def test_several_lines_across_one_profile_each_matched_to_its_contour():
    # Three slots side by side, their long sides 2-4 mm apart: a 10 mm laser line scanning one
    # crosses the lines beside it too.
    rings = [synth.ContourShape("slot", (100.0, 100.0 + 6.0 * k), (25.0, 2.0), 2.0) for k in range(3)]
    scan, truth = synth.groove_scan(seed=4, contours=rings, readings=400, keep_every=60, bend=0.1)
    # One groove per frame, the nearest the line centre (the contour followed): the reference.
    one = inspect_grooves(scan, truth.nominal_polylines, window=200, select="nearest", near=0.0, cluster_radius=1.0)
    every = inspect_grooves(scan, truth.nominal_polylines, select="all", cluster_radius=1.0)
    assert [c.cad_index for c in every.contours] == [0, 1, 2] == [c.cad_index for c in one.contours]
    f = every.fits
    assert (np.bincount(f.frame[f.ok]) >= 2).mean() > 0.3  # the line sees several grooves
    for a, b in zip(every.contours, one.contours):
        # Each ring also seen from its neighbours' passes (those within half the line).
        assert len(a.frames) > 1.4 * len(b.frames)
        # Every center lies on its own ring, and the contour errors agree with the reference.
        cad = machscan.resample_polyline(np.asarray(truth.nominal_polylines[a.cad_index]), 0.01, closed=True)
        _, gap = machscan.nearest_neighbors(cad * [1, 1, 0], a.actual * [1, 1, 0])
        assert gap.max() < 0.2
        assert a.error.mean == pytest.approx(b.error.mean, abs=0.005)
        np.testing.assert_allclose(np.median(a.width), np.median(b.width), atol=0.005)
    # Every row says its frame and groove.
    rows = every.width_depth_rows()
    assert sum(r["frames"] for r in rows[:-1]) == sum(len(c.frames) for c in every.contours)


def test_tolerance_capability_is_the_textbook_formula():
    rng = np.random.default_rng(5)
    v = rng.normal(0.48, 0.01, 500)
    tol = machscan.Tolerance(0.45, 0.52)
    cap = tol.capability(v)
    s = v.std(ddof=1)
    assert cap["cp"] == pytest.approx(0.07 / (6 * s), rel=1e-12)
    assert cap["cpk"] == pytest.approx(min(0.52 - v.mean(), v.mean() - 0.45) / (3 * s), rel=1e-12)
    assert cap["in_tolerance"] == np.mean((v >= 0.45) & (v <= 0.52))
    assert tol.nominal == pytest.approx(0.485)
    assert np.isnan(tol.capability([0.5])["cp"])
    for bad in [(0.5, 0.4), (0.4, np.nan), (0.4, 0.5, 0.6)]:
        with pytest.raises(ValueError, match="tolerance"):
            machscan.Tolerance(*bad)


def test_tolerances_judge_frames_and_contours(run, tmp_path):
    scan, truth, _ = run
    depth = machscan.Tolerance(0.29, 0.33)
    r = inspect_grooves(scan, truth.nominal_polylines, width_tolerance=(0.47, 0.49), depth_tolerance=depth)
    assert isinstance(r.width_tolerance, machscan.Tolerance)
    ok = r.fits.ok
    np.testing.assert_array_equal(r.width_ok, ok & (r.fits.width >= 0.47) & (r.fits.width <= 0.49))
    assert 0 < r.width_ok[ok].mean() < 1  # the limits cut into the measured spread
    rows = r.width_depth_rows()
    for row, c in zip(rows, r.contours):
        ref = r.width_tolerance.capability(c.width)
        assert row["width_cpk"] == ref["cpk"] and row["width_in_tolerance"] == ref["in_tolerance"]
    assert "Cpk" in r.summary()
    r.to_csv(tmp_path)
    widths = np.genfromtxt(tmp_path / "widths.csv", delimiter=",", names=True)
    assert {"width_cp", "width_cpk", "width_in_tolerance", "depth_cpk"} <= set(widths.dtype.names)
    frames = np.genfromtxt(tmp_path / "frames.csv", delimiter=",", names=True)
    np.testing.assert_array_equal(frames["width_ok"], r.width_ok.astype(int))
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    fig = machscan.plot.width_depth_along(r, contour=0)
    labels = [line.get_label() for line in fig.axes[0].lines]
    assert "limits 0.47–0.49 mm" in labels
    with pytest.raises(ValueError, match="width_tolerance"):
        inspect_grooves(scan, truth.nominal_polylines, width_tolerance=0.48)
