"""Figures of a groove inspection (machscan.plot) on a small synthetic scan."""

import re
import sys

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection, PathCollection  # noqa: E402
from matplotlib.container import BarContainer  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

import machscan  # noqa: E402
from machscan import plot  # noqa: E402


@pytest.fixture(scope="module")
def run(small_groove_scan):
    scan, truth = small_groove_scan
    report = machscan.inspect_grooves(scan, truth.nominal_polylines)
    x = (np.arange(scan.n_readings) - scan.profiler.i0) * scan.profiler.pitch
    z = np.where(scan.valid_mask(), scan.frames, np.nan)
    return report, x, z


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def _data_lines(ax, prefix):
    return [ln for ln in ax.get_lines() if ln.get_label().startswith(prefix)]


def test_width_depth_along_every_contour(run):
    report, _, _ = run
    fig = plot.width_depth_along(report)
    assert isinstance(fig, Figure)
    aw, ad = fig.axes
    for ax, name in ((aw, "width"), (ad, "depth")):
        lines = _data_lines(ax, "contour ")
        assert len(lines) == len(report.contours)
        start = 0.0
        for ln, c in zip(lines, report.contours):
            assert ln.get_label() == f"contour {c.cad_index}"
            # Every frame drawn once, at an arc length within the contour; contours end to end.
            np.testing.assert_array_equal(np.sort(ln.get_ydata()), np.sort(getattr(c, name)))
            s = ln.get_xdata()
            length = np.linalg.norm(np.diff(c.theoretical, axis=0, append=c.theoretical[:1]), axis=1).sum()
            assert start - 1e-9 <= s.min() and s.max() <= start + length + 1e-9 and np.all(np.diff(s) >= 0)
            start += length
        (mean,) = _data_lines(ax, "mean")
        assert mean.get_ydata()[0] == pytest.approx(np.concatenate([getattr(c, name) for c in report.contours]).mean())
    assert "mm" in aw.get_ylabel() and "mm" in ad.get_ylabel() and "mm" in ad.get_xlabel()


def test_width_depth_along_one_contour(run):
    report, _, _ = run
    c = report.contours[3]
    fig = plot.width_depth_along(report, contour=c.cad_index)
    aw, _ad = fig.axes
    assert len(_data_lines(aw, "contour ")) == 1
    mean_line = _data_lines(aw, "mean")[0]
    assert mean_line.get_ydata()[0] == pytest.approx(c.width.mean())
    assert len(aw.collections) == 1  # the ± standard error band
    with pytest.raises(ValueError, match="CAD contour 99 was not matched"):
        plot.width_depth_along(report, contour=99)


def test_width_depth_histograms(run):
    report, _, _ = run
    fig = plot.width_depth_histograms(report, bins=30)
    assert len(fig.axes) == 2
    ok = report.used
    for ax, v in zip(fig.axes, (report.fits.width[ok], report.fits.depth[ok])):
        bars = ax.patches
        assert len(bars) == 30
        (text, *rest) = [t.get_text() for t in ax.get_legend().get_texts()]
        assert text == f"mean ± std: {v.mean():.4f} ± {v.std():.4f} mm"
        outside = int(rest[0].split()[0]) if rest else 0
        assert sum(b.get_height() for b in bars) + outside == ok.sum()
        assert "mm" in ax.get_xlabel()


def test_contour_error_map_has_one_collection_per_contour(run):
    report, _, _ = run
    fig = plot.contour_error_map(report, max_points=500)
    ax, cbar = fig.axes
    assert "mm" in cbar.get_ylabel()
    lcs = [col for col in ax.collections if isinstance(col, LineCollection)]
    assert len(lcs) == len(report.contours)
    lo = min(c.error.errors.min() for c in report.contours)
    hi = max(c.error.errors.max() for c in report.contours)
    for lc, c in zip(lcs, report.contours):
        color = lc.get_array()
        assert 250 < len(color) <= 500
        assert lo <= color.min() and color.max() <= hi
        # Chunk means of e_i: their mean is the contour's mean error up to the short last chunk.
        assert color.mean() == pytest.approx(c.error.mean, abs=0.002)
        # Segments follow the CAD contour and close it.
        segs = lc.get_segments()
        np.testing.assert_allclose(segs[0][0], c.theoretical[0, :2])
        np.testing.assert_allclose(segs[-1][1], c.theoretical[0, :2])
    (centers,) = [col for col in ax.collections if isinstance(col, PathCollection)]
    assert len(centers.get_offsets()) == np.isfinite(report.center_wcs).all(axis=1).sum()
    worst = max(report.contours, key=lambda c: c.error.max)
    (marker,) = [ln for ln in ax.get_lines() if ln.get_marker() == "x"]
    np.testing.assert_allclose(
        [marker.get_xdata()[0], marker.get_ydata()[0]], worst.theoretical[np.argmax(worst.error.errors), :2]
    )


def test_error_decomposition_bars(run):
    report, _, _ = run
    fig = plot.error_decomposition(report)
    (ax,) = fig.axes
    bars = [c for c in ax.containers if isinstance(c, BarContainer)]
    assert len(bars) == 3
    n = len(report.contours)
    assert all(len(b) == n + 1 for b in bars)
    d = report.decomposition
    expected = (
        [c.offset_error for c in report.contours] + [d.offset],
        [c.bending.mean() for c in report.contours] + [d.bending],
        [c.local.mean() for c in report.contours] + [d.local],
    )
    for b, want in zip(bars, expected):
        np.testing.assert_allclose([p.get_height() for p in b], want)
    # Stacked: each part starts where the previous ends.
    np.testing.assert_allclose([p.get_y() for p in bars[2]], np.array(expected[0]) + np.array(expected[1]))
    assert f"bending {100 * d.bending_share:.1f} %" in ax.get_title()
    assert "mm" in ax.get_ylabel()


def test_error_along_one_contour(run):
    report, _, _ = run
    c = report.contours[-1]
    fig = plot.error_along(report, contour=c.cad_index, max_points=10**9)
    (ax,) = fig.axes
    (e,) = _data_lines(ax, "contour error")
    np.testing.assert_array_equal(e.get_ydata(), c.error.errors)
    (off,) = _data_lines(ax, "offset")
    assert off.get_ydata()[0] == pytest.approx(c.offset_error)


def _assert_section_drawn(line, lf, fits, frame):
    """The drawn section is the fitted one, placed where the fit put it in the levelled frame."""
    sx, sz = line.get_xdata(), line.get_ydata()
    assert np.all(np.diff(sx) >= 0)
    x0, z0 = lf.to_levelled(fits.x0[frame], fits.z0[frame])
    w, d, a = fits.width[frame], fits.depth[frame], fits.alpha[frame]
    # The flanks cross the surface line at the measured width around the measured center:
    # each crossing lies between the two drawn samples on either side of it. The tanh template
    # z0 + ½d(tanh(α(x−x0−w/4)) − tanh(α(x−x0+w/4))) never meets its surface line; at
    # x0 ± w/2 it stands at the level below.
    level = z0 if fits.template != "tanh" else z0 + d / 2 * (np.tanh(a * w / 4) - np.tanh(3 * a * w / 4))
    below = np.nonzero(sz < level - 1e-9)[0]
    left, right = below[0], below[-1]
    assert sx[left - 1] - 1e-9 <= x0 - w / 2 <= sx[left] + 1e-9
    assert sx[right] - 1e-9 <= x0 + w / 2 <= sx[right + 1] + 1e-9
    # Inside the groove the section leaves residuals of the size the fit reported. The fit's
    # RMS is along the beam over the readings it kept, so it agrees to the noise, not exactly;
    # a section misplaced by a wrong tilt mapping leaves tens of µm.
    inside = np.abs(lf.x - x0) < w / 2
    rms = np.sqrt(np.mean((lf.z[inside] - np.interp(lf.x[inside], sx, sz)) ** 2))
    assert 0.5 * fits.rms[frame] < rms < 2 * fits.rms[frame] + 0.002


def test_levelled_frame_draws_the_fitted_section(run):
    report, x, z = run
    fits = report.fits
    for frame in np.nonzero(fits.ok)[0][[0, 50, 400]]:
        fig = plot.levelled_frame(x, z, frame, report)
        (ax,) = fig.axes
        (readings,) = _data_lines(ax, "levelled readings")
        (section,) = _data_lines(ax, "fitted section")
        model = machscan.GrooveModel(fits.model[frame]).name.lower()
        assert section.get_label() == f"fitted section ({model})"
        lf = machscan.level_groove_frame(x, z[frame], window=200)
        np.testing.assert_array_equal(readings.get_xdata(), lf.x)
        _assert_section_drawn(section, lf, fits, frame)
        assert "mm" in ax.get_xlabel() and "mm" in ax.get_ylabel()
        plt.close(fig)
    # One row instead of all frames, and no fits: the frame is fitted for the figure.
    fig = plot.levelled_frame(x, z[7], 7)
    assert len(_data_lines(fig.axes[0], "fitted section")) == 1


def test_levelled_frame_refuses_fits_of_other_settings(run):
    report, x, z = run
    frame = int(np.nonzero(report.fits.ok)[0][0])
    with pytest.raises(ValueError, match="fits: the frame's fit differs"):
        plot.levelled_frame(x, z, frame, report, window=120)


def test_levelled_frame_maps_the_center_with_the_tilt():
    # A steeply tilted frame (80 mrad) high above the reference: drawing the section at the
    # unrotated (x0, z0), or rotating the wrong way, shifts it by z0·sin θ = 40 µm along the
    # line, three drawn samples and 50 µm RMS on the flanks.
    x = (np.arange(400) - 200) * 0.025
    z = 0.5 + np.tan(0.08) * x - 0.3 * np.clip(1 - np.abs(x - 0.3) / 0.24, 0, 1)
    z = z + np.random.default_rng(1).normal(0, 0.002, x.size)
    fits = machscan.fit_grooves(x, z[None], window=200, window_center=212)
    assert fits.ok[0] and fits.tilt[0] == pytest.approx(0.08, abs=0.002)
    fig = plot.levelled_frame(x, z, 0, fits, window_center=212)
    (section,) = _data_lines(fig.axes[0], "fitted section")
    lf = machscan.level_groove_frame(x, z, window=200, window_center=212)
    _assert_section_drawn(section, lf, fits, 0)


def test_drawing_into_given_axes(run):
    report, x, z = run
    fig, axs = plt.subplots(2, 3)
    assert plot.width_depth_along(report, axes=axs[0, :2]) is fig
    assert plot.width_depth_histograms(report, axes=axs[1, :2]) is fig
    assert plot.error_decomposition(report, ax=axs[0, 2]) is fig
    assert plot.levelled_frame(x, z, 3, report.fits, ax=axs[1, 2]) is fig
    assert len(fig.axes) == 6


def test_every_figure_saves_as_png(run, tmp_path):
    report, x, z = run
    figures = {
        "along": plot.width_depth_along(report),
        "histograms": plot.width_depth_histograms(report),
        "map": plot.contour_error_map(report),
        "decomposition": plot.error_decomposition(report),
        "error_along": plot.error_along(report),
        "frame": plot.levelled_frame(x, z, 100, report),
    }
    for name, fig in figures.items():
        path = tmp_path / f"{name}.png"
        fig.savefig(path, dpi=60)
        data = path.read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000, name


def test_not_a_report():
    with pytest.raises(ValueError, match=r"expected a machscan\.GrooveReport"):
        plot.contour_error_map(object())


def test_missing_matplotlib_says_how_to_install(run, monkeypatch):
    report, _, _ = run
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    msg = "machscan.plot needs matplotlib: pip install machscan[plot]"
    with pytest.raises(ImportError, match=re.escape(msg)):
        plot.width_depth_histograms(report)
    with pytest.raises(ImportError, match=re.escape(msg)):
        plot.contour_error_map(report)


@pytest.mark.parametrize("template", ["v", "trapezoid", "tanh"])
def test_levelled_frame_draws_the_template_of_the_fits(template):
    x = (np.arange(200) - 100) * 0.025
    u = np.abs(x - 0.07)
    z = np.where(u < 0.24, -0.31 * (1 - u / 0.24), 0.0) + np.random.default_rng(0).normal(0, 0.008, 200)
    fits = machscan.fit_grooves(x, z[None, :], template=template)
    assert fits.ok[0] and fits.template == template and fits.select([0]).template == template
    fig = machscan.plot.levelled_frame(x, z, 0, fits)
    (section,) = _data_lines(fig.axes[0], "fitted section")
    assert section.get_label() == f"fitted section ({machscan.GrooveModel(fits.model[0]).name.lower()})"
    if template != "tanh":
        assert section.get_label() == f"fitted section ({template})"
    lf = machscan.level_groove_frame(x, z, template=template)
    _assert_section_drawn(section, lf, fits, 0)


def test_allowance_map_colors_the_stock_and_rings_the_short_points():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(500, 3))
    a = np.linspace(-0.1, 0.4, 500)
    a[7] = np.nan
    fig = plot.allowance_map(p, a)
    ax = fig.axes[0]
    colored = [c for c in ax.collections if c.get_array() is not None]
    assert len(colored) == 1 and np.allclose(np.sort(colored[0].get_array()), np.sort(a[np.isfinite(a)]))
    short = int(np.sum(a[np.isfinite(a)] < 0))
    assert f"{short} points below 0 mm" in ax.get_title()
    assert colored[0].norm.vcenter == 0.0
    with pytest.raises(ValueError, match="allowance"):
        plot.allowance_map(p, a[:-1])
    plt.close(fig)


def test_deviation_map_centres_on_zero_marks_the_band_and_greys_the_cad_without_data():
    rng = np.random.default_rng(1)
    p = rng.normal(size=(400, 3)) * 10
    d = np.linspace(-0.08, 0.03, 400)
    d[5] = np.nan
    v = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], dtype=float)
    t = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    fig = plot.deviation_map(p, d, tolerance=(-0.05, 0.02), vertices=v, triangles=t)
    ax = fig.axes[0]
    colored = [c for c in ax.collections if isinstance(c, PathCollection) and c.get_array() is not None]
    assert len(colored) == 1
    norm = colored[0].norm
    assert norm.vmin == -norm.vmax == pytest.approx(-0.08)  # symmetric about zero
    out = int(np.sum((d < -0.05) | (d > 0.02)))
    assert f"{out} points outside [-0.05, 0.02] mm" in ax.get_title() and "1 without a distance" in ax.get_title()
    bar = fig.axes[1]
    assert "mm" in bar.get_ylabel()
    assert sorted(round(line.get_ydata()[0], 6) for line in bar.lines) == [-0.05, 0.02]
    # The CAD drawn underneath, grey.
    assert any(type(c).__name__ == "Poly3DCollection" for c in ax.collections)
    with pytest.raises(ValueError, match="distances"):
        plot.deviation_map(p, d[:-1], tolerance=0.05)
    with pytest.raises(ValueError, match="tolerance"):
        plot.deviation_map(p, d, tolerance=(0.1, -0.1))
    plt.close(fig)
