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
    np.testing.assert_allclose([marker.get_xdata()[0], marker.get_ydata()[0]],
                               worst.theoretical[np.argmax(worst.error.errors), :2])


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
    np.testing.assert_allclose([p.get_y() for p in bars[2]],
                               np.array(expected[0]) + np.array(expected[1]))
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


def test_levelled_frame_template_matches_the_fit(run):
    report, x, z = run
    fits = report.fits
    for frame in np.nonzero(fits.ok)[0][[0, 50, 400]]:
        fig = plot.levelled_frame(x, z, frame, report)
        (ax,) = fig.axes
        (readings,) = _data_lines(ax, "levelled readings")
        (template,) = _data_lines(ax, "fitted template")
        lf = machscan.level_groove_frame(x, z[frame], window=200)
        np.testing.assert_array_equal(readings.get_xdata(), lf.x)
        # The drawn template at the readings leaves the fit's own residual RMS: the center was
        # mapped into the levelled frame correctly.
        model = np.interp(lf.x, template.get_xdata(), template.get_ydata())
        rms = np.sqrt(np.mean((lf.z - model) ** 2))
        assert rms == pytest.approx(fits.rms[frame], rel=0.02, abs=2e-4)
        assert "mm" in ax.get_xlabel() and "mm" in ax.get_ylabel()
        plt.close(fig)
    # One row instead of all frames, and no fits: the fit's initial guess.
    fig = plot.levelled_frame(x, z[7], 7)
    assert len(_data_lines(fig.axes[0], "initial guess")) == 1


def test_levelled_frame_maps_the_center_with_the_tilt():
    # A steeply tilted frame (80 mrad) high above the reference: drawing the template at the
    # unrotated (x0, z0), or rotating the wrong way, misses the readings by 20-50 µm RMS.
    x = (np.arange(400) - 200) * 0.025
    z = 0.5 + np.tan(0.08) * x - 0.3 * np.clip(1 - np.abs(x - 0.3) / 0.24, 0, 1)
    z = z + np.random.default_rng(1).normal(0, 0.002, x.size)
    fits = machscan.fit_grooves(x, z[None], window=200, window_center=212)
    assert fits.ok[0] and fits.tilt[0] == pytest.approx(0.08, abs=0.002)
    fig = plot.levelled_frame(x, z, 0, fits, window_center=212)
    (template,) = _data_lines(fig.axes[0], "fitted template")
    lf = machscan.level_groove_frame(x, z, window=200, window_center=212)
    model = np.interp(lf.x, template.get_xdata(), template.get_ydata())
    assert np.sqrt(np.mean((lf.z - model) ** 2)) == pytest.approx(fits.rms[0], rel=0.01)


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


def test_levelled_frame_draws_the_v_template_for_v_fits():
    import matplotlib

    matplotlib.use("Agg")
    x = (np.arange(200) - 100) * 0.025
    u = np.abs(x - 0.07)
    z = np.where(u < 0.24, -0.31 * (1 - u / 0.24), 0.0) + np.random.default_rng(0).normal(0, 0.008, 200)
    fits = machscan.fit_grooves(x, z[None, :], template="v", alpha=80.0)
    assert fits.template == "v" and fits.select([0]).template == "v"
    fig = machscan.plot.levelled_frame(x, z, 0, fits)
    line = next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == "fitted template")
    lf = machscan.level_groove_frame(x, z)
    # The drawn curve passes through the readings as closely as the fit's own rms.
    resid = lf.z - np.interp(lf.x, line.get_xdata(), line.get_ydata())
    assert abs(np.sqrt(np.mean(resid**2)) - fits.rms[0]) < 0.002
