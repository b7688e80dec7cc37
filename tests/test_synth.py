"""Tests of machscan.synth: the synthetic groove scan is deterministic, paper-like, and its
ground truth agrees with its frames through the independent NumPy kinematics reference.

``test_rust_*`` tests need the compiled extension (never skipped; CI builds it). While
developing without it, deselect them with ``-k "not rust"``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import machscan
from kinematics_reference import ac_head_transforms_np, interpolate_poses_np, scan_to_wcs_np
from machscan import synth
from machscan.scan import SENTINEL, Scan
from machscan.synth import (
    DEFAULT_MOUNT,
    PLATE,
    ContourShape,
    default_contours,
    flat_plate_scan,
    groove_scan,
    surface_error,
)

QUIET = dict(noise=0.0, dropout=0.0, flank_dropout=0.0, spike_rate=0.0)


@pytest.fixture(scope="module")
def noisy():
    """A mid-size scan with every measurement effect on (about 380 frames x 2000 readings)."""
    return groove_scan(7, readings=2000, keep_every=400)


@pytest.fixture(scope="module")
def clean():
    """Same part geometry as ``noisy`` (same seed), noise-free and without dropouts."""
    return groove_scan(7, readings=2000, keep_every=400, **QUIET)


def _wcs(scan: Scan, mount=None):
    p = scan.profiler
    return scan_to_wcs_np(
        scan.frames, scan.poses, p.pitch, scan.c2_offset, scan.mount if mount is None else mount, valid_range=p.valid_range
    )


def _inside_plate(x, y, margin):
    x0, y0, x1, y1 = PLATE
    return (x > x0 + margin) & (x < x1 - margin) & (y > y0 + margin) & (y < y1 - margin)


# --------------------------------------------------------------------------------------------
# determinism
# --------------------------------------------------------------------------------------------


def test_same_seed_gives_identical_arrays_and_other_seed_differs():
    a, ta = groove_scan(11, readings=300, keep_every=300)
    b, tb = groove_scan(11, readings=300, keep_every=300)
    c, tc = groove_scan(12, readings=300, keep_every=300)
    for name in ("frames", "poses", "frame_times", "axis_times", "axis_samples", "mount"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    for name in ("center_wcs", "center_scs", "width", "depth", "offsets", "frame_u"):
        np.testing.assert_array_equal(getattr(ta, name), getattr(tb, name))
    assert a.metadata == b.metadata
    assert not np.array_equal(a.frames, c.frames)
    assert not np.array_equal(ta.offsets, tc.offsets)
    assert not np.array_equal(ta.width, tc.width)
    np.testing.assert_array_equal(a.poses, c.poses)  # the path is the CAD path: same


def test_part_does_not_depend_on_scan_parameters():
    _, t1 = groove_scan(5, readings=200, keep_every=400)
    _, t2 = groove_scan(5, readings=300, keep_every=300, noise=0.02)
    np.testing.assert_array_equal(t1.offsets, t2.offsets)
    np.testing.assert_array_equal(t1.deflection.coefficients, t2.deflection.coefficients)
    for k in range(t1.n_contours):
        u = np.linspace(0, t1.contours[k].length, 50)
        np.testing.assert_array_equal(t1.engraved_point(k, u), t2.engraved_point(k, u))
        np.testing.assert_array_equal(t1.width_profile[k](u), t2.width_profile[k](u))


# --------------------------------------------------------------------------------------------
# the part: layout, analytic contours, paper-like numbers
# --------------------------------------------------------------------------------------------


def test_layout_is_a_paper_like_template():
    shapes = default_contours()
    assert len(shapes) == 11
    assert {s.kind for s in shapes} == {"rounded_rectangle", "slot", "circle"}
    xs = [s.center[0] for s in shapes]
    assert xs == sorted(xs)  # numbered by x like paper 000 §3
    polys = [s.polyline(0.05) for s in shapes]
    for p in polys:
        assert _inside_plate(p[:, 0], p[:, 1], 12.0 - 1e-6).all()
    clearance = min(cKDTree(polys[j]).query(polys[i])[0].min() for i in range(11) for j in range(i + 1, 11))
    assert clearance >= 8.0
    lengths = [s.length for s in shapes]
    assert len(set(np.round(lengths, 3))) == 11  # different sizes


@pytest.mark.parametrize(
    "shape",
    list(default_contours())
    + [
        ContourShape("rounded_rectangle", (50.0, 60.0), (20.0, 8.0), 3.0, angle=-0.7),
        ContourShape("slot", (50.0, 60.0), (5.0, 15.0), 5.0, angle=2.5),
    ],
)
def test_contour_shape_closed_forms(shape):
    L = shape.length
    u = np.linspace(0.0, L, 2001)[:-1]
    p = shape.point(u)
    # perimeter
    seg = np.linalg.norm(np.diff(np.vstack([p, p[:1]]), axis=0), axis=1)
    assert seg.sum() == pytest.approx(L, rel=1e-5)
    # closest() inverts point()
    sdf, uu = shape.closest(p)
    np.testing.assert_allclose(sdf, 0.0, atol=1e-9)
    du = np.mod(uu - u + 0.5 * L, L) - 0.5 * L
    np.testing.assert_allclose(du, 0.0, atol=1e-7)
    # tangent is the derivative of point(); normal points outwards
    t = shape.tangent(u)
    fd = (shape.point(u + 1e-6) - shape.point(u - 1e-6)) / 2e-6
    np.testing.assert_allclose(fd, t, atol=1e-5)
    n = shape.normal(u)
    np.testing.assert_allclose(shape.signed_distance(p + 0.3 * n), 0.3, atol=1e-9)
    np.testing.assert_allclose(shape.signed_distance(p - 0.3 * n), -0.3, atol=1e-9)
    ang = shape.tangent_angle(u)
    np.testing.assert_allclose(np.cos(ang), t[:, 0], atol=1e-12)
    np.testing.assert_allclose(np.sin(ang), t[:, 1], atol=1e-12)
    assert shape.tangent_angle(L + 1.0) == pytest.approx(shape.tangent_angle(1.0) + 2 * np.pi)
    # |signed distance| equals the brute-force distance to a dense polyline
    rng = np.random.default_rng(0)
    q = np.asarray(shape.center) + rng.uniform(-40, 40, (2000, 2))
    dense = shape.point(np.linspace(0, L, 200_000, endpoint=False))
    d, _ = cKDTree(dense).query(q)
    np.testing.assert_allclose(np.abs(shape.signed_distance(q)), d, atol=1e-3)


def test_width_depth_and_lips_are_paper_like(noisy):
    _, truth = noisy
    # paper 000 §3: width 0.4806 +- 0.0163 mm, depth 0.3124 +- 0.0148 mm (measured)
    assert abs(truth.width.mean() - 0.4806) < 0.015
    assert 0.006 < truth.width.std() < 0.025
    assert abs(truth.depth.mean() - 0.3124) < 0.012
    assert 0.005 < truth.depth.std() < 0.02
    assert truth.width.min() > 0.40 and truth.width.max() < 0.56
    # lips 0.01-0.03 mm just outside the edges
    for k, lp in enumerate(truth.lip_profile):
        v = lp(np.linspace(0, truth.contours[k].length, 500))
        a = truth.lip_asymmetry[k]
        assert 0.004 < (v * (1 - abs(a))).min() and (v * (1 + abs(a))).max() < 0.04


def test_error_components_are_paper_like(noisy):
    _, truth = noisy
    # offset error (paper: 0.0255 +- 0.0148 mm) and local error (0.0123 +- 0.0062 mm)
    e = np.linalg.norm(truth.offsets, axis=1)
    assert 0.008 < e.mean() < 0.05 and e.max() < 0.1
    loc = np.abs(truth.center_local)
    assert 0.006 < loc.mean() < 0.02 and loc.max() < 0.06
    # bending dominates (paper: 74.56 % of the error) and peaks at `bend` over the plate
    g = np.linspace(0, 200, 201)
    gx, gy = np.meshgrid(g, g)
    assert np.abs(truth.deflection(gx, gy)).max() == pytest.approx(0.3, abs=1e-12)
    b = np.abs(truth.center_bend)
    assert b.max() <= 0.3 and b.mean() > 2 * (e.mean() + loc.mean())


def test_deflection_is_the_stated_polynomial(noisy):
    _, truth = noisy
    d = truth.deflection
    rng = np.random.default_rng(3)
    x, y = rng.uniform(0, 200, 1000), rng.uniform(0, 200, 1000)
    xi, eta = (x - d.center[0]) / d.scale, (y - d.center[1]) / d.scale
    naive = sum(c * xi**i * eta**j for (i, j), c in zip(d.exponents, d.coefficients))
    np.testing.assert_allclose(d(x, y), naive, rtol=0, atol=1e-15)
    assert len(d.coefficients) >= 6 and d.exponents.shape == (len(d.coefficients), 2)


def test_surface_error_is_the_profiler_noise(noisy, clean):
    scan, truth = noisy
    pts, fi = _wcs(scan)
    err = surface_error(pts, fi, truth)
    assert err.n > 100_000
    assert err.robust_sigma == pytest.approx(scan.profiler.noise, rel=0.1)
    assert abs(err.mean) < 0.001 and err.rms < 2 * scan.profiler.noise
    assert 0 < err.n_outliers < 1e-3 * err.n and err.max_abs > 0.04  # the spikes
    cscan, _ = clean
    cerr = surface_error(*_wcs(cscan, truth.mount_true), truth)
    assert cerr.max_abs < 1e-8 and cerr.n_outliers == 0
    # points in a groove are not compared
    inside = truth.center_wcs - [0.0, 0.0, 0.3]
    assert surface_error(inside, None, truth).n == 0
    with pytest.raises(ValueError, match="points"):
        surface_error(pts[:, :2], None, truth)
    with pytest.raises(ValueError, match="frame_index"):
        surface_error(pts, fi[:-1], truth)


def test_flat_plate_has_no_deflection():
    scan, truth = flat_plate_scan(2)
    g = np.linspace(0, 200, 11)
    assert np.all(truth.deflection(*np.meshgrid(g, g)) == 0.0)
    np.testing.assert_array_equal(truth.center_bend, 0.0)
    assert scan.n_readings == 400 and 200 < scan.n_frames < 600
    pts, _ = _wcs(scan)
    s, _, _ = truth.groove_signed_distance(pts[:, 0], pts[:, 1])
    far = (np.abs(s) > 1.0) & _inside_plate(pts[:, 0], pts[:, 1], 1.0)
    assert abs(np.median(pts[far, 2])) < 0.002


# --------------------------------------------------------------------------------------------
# truth against frames, through the independent reference chain
# --------------------------------------------------------------------------------------------


def test_readings_are_exact_ray_casts_of_the_true_surface(clean):
    scan, truth = clean
    pts, fi = _wcs(scan, truth.mount_true)
    assert fi.size > 0.98 * scan.frames.size  # without dropouts only the edge shadow is lost
    np.testing.assert_allclose(pts[:, 2], truth.height(pts[:, 0], pts[:, 1]), atol=1e-8)
    # the plate is there and the table beside it
    on = truth.on_plate(pts[:, 0], pts[:, 1])
    assert on.mean() > 0.5 and (~on).sum() > 1000
    np.testing.assert_allclose(pts[~on, 2], -truth.plate_thickness, atol=1e-12)


def test_true_center_is_the_frame_transform_of_its_scs_coordinates(noisy):
    scan, truth = noisy
    T = ac_head_transforms_np(scan.poses, scan.c2_offset, truth.mount_true)
    f = scan.n_frames
    scs = np.column_stack([truth.center_scs[:, 0], np.zeros(f), truth.center_scs[:, 1], np.ones(f)])
    wcs = np.einsum("fij,fj->fi", T, scs)[:, :3]
    np.testing.assert_allclose(wcs, truth.center_wcs, rtol=0, atol=1e-9)
    # the center is on the engraved line, on the bent surface
    for k in range(truth.n_contours):
        sel = truth.frame_contour == k
        np.testing.assert_allclose(truth.engraved_point(k, truth.center_u[sel]), truth.center_wcs[sel], atol=1e-12)
    c = truth.center_wcs
    np.testing.assert_allclose(c[:, 2], truth.deflection(c[:, 0], c[:, 1]), atol=1e-15)
    s, k, _ = truth.groove_signed_distance(c[:, 0], c[:, 1])
    np.testing.assert_allclose(s, 0.0, atol=1e-9)
    np.testing.assert_array_equal(k, truth.frame_contour)
    # the decomposition offset + local + bending is exact
    recon = truth.center_nominal + truth.center_offset + truth.center_local[:, None] * truth.center_normal
    recon[:, 2] += truth.center_bend
    np.testing.assert_allclose(recon, truth.center_wcs, atol=1e-12)
    # the groove appears near the middle of the line
    assert np.abs(truth.center_scs[:, 0]).max() < 0.2


def test_reading_at_true_center_is_a_depth_deep_dip(noisy):
    scan, truth = noisy
    p = scan.profiler
    fr = scan.frames
    rows = np.arange(scan.n_frames)
    i = np.rint(truth.center_scs[:, 0] / p.pitch + p.i0).astype(int)
    off = 16  # 0.4 mm: beyond the groove and its lips on both sides
    dn, left, right = fr[rows, i], fr[rows, i - off], fr[rows, i + off]
    ok = p.valid_mask(dn) & p.valid_mask(left) & p.valid_mask(right)
    assert ok.mean() > 0.6
    dip = 0.5 * (left + right) - dn
    np.testing.assert_allclose(np.median((dip - truth.depth)[ok]), 0.0, atol=0.01)
    assert np.quantile(np.abs(dip - truth.depth)[ok], 0.9) < 0.04
    # the bottom is depth below the surface height of the center (SCS z)
    bottom = truth.center_scs[:, 1] - truth.depth
    assert np.median(np.abs(dn - bottom)[ok]) < 0.012


def test_readings_away_from_grooves_lie_on_the_bent_surface(noisy):
    scan, truth = noisy
    pts, _ = _wcs(scan)  # the calibrated mount is the true one by default
    np.testing.assert_array_equal(truth.mount_true, scan.mount)
    s, _, _ = truth.groove_signed_distance(pts[:, 0], pts[:, 1])
    far = (np.abs(s) > 1.0) & _inside_plate(pts[:, 0], pts[:, 1], 1.0)
    assert far.sum() > 100_000
    r = pts[far, 2] - truth.deflection(pts[far, 0], pts[far, 1])
    sigma = scan.profiler.noise
    core = np.abs(r) < 5 * sigma
    assert abs(r[core].mean()) < 0.0005
    assert r[core].std() == pytest.approx(sigma, rel=0.1)
    spikes = (~core).mean()
    assert 0 < spikes < 1e-3  # occasional spikes
    assert (np.abs(truth.deflection(pts[far, 0], pts[far, 1])) > 0.1).any()  # it is bent


def test_dropouts_runs_sentinel_and_flanks(noisy, clean):
    scan, truth = noisy
    lost = scan.frames == SENTINEL
    assert not np.isnan(scan.frames).any()
    cscan, _ = clean
    pts, _fi = _wcs(cscan, truth.mount_true)  # positions of every reading, from the clean twin
    valid_clean = cscan.profiler.valid_mask(cscan.frames)
    lost_at = lost[valid_clean]
    on_plate = truth.on_plate(pts[:, 0], pts[:, 1])
    assert 0.02 < lost_at[on_plate].mean() < 0.07  # a few % on the plate
    s, k, u = truth.groove_signed_distance(pts[:, 0], pts[:, 1])
    w = np.zeros_like(s)
    for c in range(truth.n_contours):
        w[k == c] = truth.width_profile[c](u[k == c])
    t = np.abs(s) / (0.5 * w)
    flank = on_plate & (t > 0.2) & (t < 0.9)
    away = on_plate & (t > 3.0)
    assert lost_at[flank].mean() > lost_at[away].mean() + 0.08  # more on the steep flanks
    # short runs: lost readings often have a lost neighbor
    pairs = lost[:, 1:] & lost[:, :-1]
    assert pairs.sum() > 0.4 * lost.sum()
    # the shadow next to the plate edge is lost, the table further out is measured
    x0, y0, x1, y1 = PLATE
    dout = np.maximum(np.maximum(x0 - pts[:, 0], pts[:, 0] - x1), np.maximum(y0 - pts[:, 1], pts[:, 1] - y1))
    assert not (valid_clean[valid_clean] & ((dout > 0) & (dout < 0.8))).any()
    assert (dout > 0.8).sum() > 0


# --------------------------------------------------------------------------------------------
# machine path, timing, axis samples
# --------------------------------------------------------------------------------------------


def test_poses_follow_the_closed_form(noisy):
    scan, truth = noisy
    T = ac_head_transforms_np(scan.poses, scan.c2_offset, scan.mount)
    np.testing.assert_array_equal(scan.poses[:, 3:5], 0.0)  # A = C = 0
    for k, shape in enumerate(truth.contours):
        sel = truth.frame_contour == k
        u = truth.frame_u[sel]
        # SCS origin (reading center, height 0) on the nominal contour, nominal surface
        np.testing.assert_allclose(T[sel, :2, 3], shape.point(u), atol=1e-9)
        np.testing.assert_allclose(T[sel, 2, 3], 0.0, atol=1e-9)
        # laser line (SCS x) across the contour, along the outward normal
        line = T[sel, :2, 0]
        assert np.abs(np.einsum("fi,fi->f", line, shape.tangent(u))).max() < 1e-12
        assert np.einsum("fi,fi->f", line, shape.normal(u)).min() > 0.9999
    # P_t = p - (R_C2 d + L) with A = C = 0
    c2 = scan.poses[:, 5]
    d = scan.mount[3:]
    rd = np.column_stack([np.cos(c2) * d[0] - np.sin(c2) * d[1], np.sin(c2) * d[0] + np.cos(c2) * d[1], np.full_like(c2, d[2])])
    np.testing.assert_allclose(scan.poses[:, :3] + rd + scan.c2_offset, T[:, :3, 3], atol=1e-9)


def test_frame_times_are_real_profiler_times(noisy):
    scan, truth = noisy
    keep = scan.metadata["keep_every"]
    dt = np.diff(scan.frame_times)
    same = truth.frame_contour[1:] == truth.frame_contour[:-1]
    np.testing.assert_allclose(dt[same], keep / 2500.0, rtol=1e-9)
    assert (dt[~same] > 1.0).all()  # moves between contours
    du = np.diff(truth.frame_u)[same]
    np.testing.assert_allclose(du, keep * scan.metadata["feed"] / 2500.0, rtol=1e-9)


def test_axis_samples_cover_frames_and_interpolate_to_the_poses(noisy):
    scan, _truth = noisy
    at, samples = scan.axis_times, scan.axis_samples
    assert at[0] < scan.frame_times[0] and at[-1] > scan.frame_times[-1]
    np.testing.assert_allclose(np.diff(at), 1e-3, rtol=1e-9)
    assert np.all(np.isin(scan.frame_times, at)) is np.False_  # own clock
    assert samples[:, 5].min() >= 0 and samples[:, 5].max() < 2 * np.pi  # modulo C2
    assert np.ptp(scan.poses[:, 5]) > 2 * np.pi  # poses carry the continuous C2
    got = interpolate_poses_np(at, samples, scan.frame_times)
    np.testing.assert_allclose(got[:, :3], scan.poses[:, :3], atol=2e-3)
    np.testing.assert_allclose(got[:, 5], scan.poses[:, 5], atol=2e-3)
    np.testing.assert_array_equal(got[:, 3:5], 0.0)
    Tg = ac_head_transforms_np(got, scan.c2_offset, scan.mount)
    T = ac_head_transforms_np(scan.poses, scan.c2_offset, scan.mount)
    np.testing.assert_allclose(Tg[:, :3, 3], T[:, :3, 3], atol=5e-3)


def test_mount_error_is_in_the_truth_not_in_the_scan():
    err = np.array([0.002, -0.001, 0.0015, 0.05, -0.03, 0.02])
    scan, truth = groove_scan(4, readings=300, keep_every=400, mount_error=err, **QUIET)
    np.testing.assert_array_equal(scan.mount, DEFAULT_MOUNT)
    np.testing.assert_allclose(truth.mount_true, np.asarray(DEFAULT_MOUNT) + err)
    pts_true, _ = _wcs(scan, truth.mount_true)
    np.testing.assert_allclose(pts_true[:, 2], truth.height(pts_true[:, 0], pts_true[:, 1]), atol=1e-8)
    pts_cal, _ = _wcs(scan)
    assert np.abs(pts_cal - pts_true).max() > 0.02


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"keep_every": 0}, "keep_every"),
        ({"bend": -0.1}, "bend"),
        ({"feed": 0.0}, "feed"),
        ({"dropout": 1.5}, "dropout"),
        ({"contours": [ContourShape("circle", (5.0, 100.0), (10.0, 10.0), 10.0)]}, "contours"),
    ],
)
def test_groove_scan_rejects_bad_arguments(kwargs, name):
    with pytest.raises(ValueError, match=name):
        groove_scan(0, readings=100, **kwargs)


def test_custom_contours_and_save_round_trip(tmp_path):
    shapes = [
        ContourShape("circle", (100.0, 100.0), (30.0, 30.0), 30.0),
        ContourShape("slot", (100.0, 30.0), (40.0, 8.0), 8.0, angle=0.1),
    ]
    scan, truth = groove_scan(1, readings=200, keep_every=100, contours=shapes)
    assert truth.n_contours == 2 and set(truth.frame_contour) == {0, 1}
    p = tmp_path / "synth.npz"
    scan.save(p)
    back = Scan.load(p)
    np.testing.assert_array_equal(back.frames, scan.frames)
    np.testing.assert_array_equal(back.axis_samples, scan.axis_samples)
    assert back.metadata == scan.metadata
    assert back.metadata["contours"][1]["angle"] == 0.1


# --------------------------------------------------------------------------------------------
# compiled core on the synthetic scan (never skipped; CI builds the extension)
# --------------------------------------------------------------------------------------------


def test_rust_wcs_points_of_synthetic_scan_match_reference(noisy):
    scan, _truth = noisy
    pts, fi = scan.wcs_points()
    exp, efi = _wcs(scan)
    np.testing.assert_array_equal(fi, efi)
    np.testing.assert_allclose(pts, exp, rtol=0, atol=1e-9)


def test_rust_interpolated_poses_of_synthetic_scan(noisy):
    scan, _ = noisy
    got = machscan.interpolate_poses(scan.axis_times, scan.axis_samples, scan.frame_times, rotary=(3, 4, 5))
    exp = interpolate_poses_np(scan.axis_times, scan.axis_samples, scan.frame_times)
    np.testing.assert_allclose(got, exp, rtol=0, atol=1e-9)
    np.testing.assert_allclose(got[:, 5], scan.poses[:, 5], atol=2e-3)


# --------------------------------------------------------------------------------------------
# pocket plate (simplification studies)
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("wall_angle", [90.0, 45.0])
def test_pocket_plate_heights(wall_angle):
    p = synth.pocket_plate(wall_angle=wall_angle, noise=0.0)
    x, y, z = p.T
    assert not np.any((x > 90) & (y > 55))  # the notch
    assert np.all(z[(x < 19) | (y < 14)] == 0.0)  # plate top, outside the pocket
    assert np.all(z[(x > 30) & (x < 60) & (y > 25) & (y < 50) & (np.hypot(x - 45, y - 37) > 12)] == -3.0)
    assert np.all(z[np.hypot(x - 45, y - 37) < 7.9] == -1.0)  # boss top
    if wall_angle == 45.0:
        # On the drafted wall z follows the 45° flank: 1 mm in, 1 mm down.
        band = (np.abs(x - 21) < 0.01) & (y > 25) & (y < 50)
        assert band.any() and np.allclose(z[band], -(x[band] - 20), atol=1e-9)


def test_pocket_plate_bad_angle():
    with pytest.raises(ValueError, match="wall_angle"):
        synth.pocket_plate(wall_angle=0.0)
