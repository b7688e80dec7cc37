"""Figures: what the papers plot. For a groove inspection (paper 000 §3), from a
:class:`~machscan.GrooveReport`:

* :func:`width_depth_along`: groove width and depth along each contour.
* :func:`width_depth_histograms`: their distributions over all fitted frames.
* :func:`contour_error_map`: the contour error e_i over the part (paper fig. 11).
* :func:`error_decomposition`: offset, bending and local error per contour (paper §3).
* :func:`error_along`: the error and its parts along one contour (paper fig. 12).
* :func:`levelled_frame`: one profiler frame as the groove fit sees it, with the fitted
  template (paper fig. 4 and 10).

For the stock on a blank (paper 004 §1.2): :func:`allowance_map`, the allowance over the part.

matplotlib is an optional dependency (``pip install machscan[plot]``); it is imported when a
function is called. Without an ``ax``/``axes`` argument every function makes a new figure
with :mod:`matplotlib.pyplot` (so ``plt.show()`` shows it and ``plt.close(fig)`` frees it);
with one it draws there. Every function returns the :class:`matplotlib.figure.Figure`.
Lengths are in mm, angles in rad.

Examples
--------
>>> from machscan import plot
>>> report = machscan.inspect_grooves(scan, cad_contours)
>>> plot.contour_error_map(report).savefig("contour_error.png", dpi=150)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan.grooves import GrooveFits, GrooveOptions, level_groove_frame
from machscan.inspection import INSPECTION_GROOVE, ContourResult, GrooveReport

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "allowance_map",
    "contour_error_map",
    "deviation_map",
    "error_along",
    "error_decomposition",
    "levelled_frame",
    "width_depth_along",
    "width_depth_histograms",
]

_MISSING = "machscan.plot needs matplotlib: pip install machscan[plot]"


def _pyplot() -> Any:
    """matplotlib.pyplot, or the ImportError that says how to get it."""
    try:
        import matplotlib  # noqa: F401
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise ImportError(_MISSING) from exc
    return plt


def _check_report(report: object) -> GrooveReport:
    if not isinstance(report, GrooveReport):
        raise ValueError(f"report: expected a machscan.GrooveReport (from inspect_grooves), got {type(report).__name__}")
    return report


def _select(report: GrooveReport, contour: int | None) -> list[ContourResult]:
    """All matched contours, or the one with CAD index ``contour``."""
    if contour is None:
        return list(report.contours)
    for c in report.contours:
        if c.cad_index == contour:
            return [c]
    found = [c.cad_index for c in report.contours]
    raise ValueError(f"contour: CAD contour {contour} was not matched in this report; matched: {found}")


def _cad_arc_length(c: ContourResult) -> NDArray[np.float64]:
    """Arc length of every theoretical point from the CAD contour's first point, mm."""
    seg = np.linalg.norm(np.diff(c.theoretical, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(seg)])


def _frame_arc_length(c: ContourResult) -> NDArray[np.float64]:
    """Position of every frame of the contour along the CAD contour: the arc length of the CAD
    point nearest (in x-y) to the frame's groove center, mm."""
    flat = np.array([1.0, 1.0, 0.0])
    near, _ = _core.nearest_neighbors(c.theoretical * flat, c.actual * flat)
    return _cad_arc_length(c)[near]


def _empty(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes)


# ---- width and depth ------------------------------------------------------------------------


def width_depth_along(
    report: GrooveReport,
    *,
    contour: int | None = None,
    axes: Sequence[Axes] | None = None,
) -> Figure:
    """Groove width and depth along the contours (paper 000 table 1, per frame).

    Each frame is placed at the arc length of the CAD point nearest to its groove center
    (from the first point of the CAD contour), so the curves of different scans of the same
    part line up. All contours are drawn end to end in CAD order, each starting where the
    previous one ends, with its index on top and the whole-part mean dashed. With one
    ``contour`` the band of ± one standard error of the fit (``fits.se_width``,
    ``fits.se_depth``) is shaded and the contour's mean drawn dashed.

    Parameters
    ----------
    report : GrooveReport
        From :func:`machscan.inspect_grooves`.
    contour : int, optional
        CAD index of the one contour to draw; default all matched contours.
    axes : pair of matplotlib Axes, optional
        Where to draw width and depth; default a new figure with two rows.

    Returns
    -------
    matplotlib.figure.Figure
        Top: width w (mm) against arc length (mm); bottom: depth d (mm). One line per contour.

    Examples
    --------
    >>> fig = machscan.plot.width_depth_along(report, contour=0)
    """
    report = _check_report(report)
    plt = _pyplot()
    chosen = _select(report, contour)
    if axes is None:
        fig, (aw, ad) = plt.subplots(2, 1, sharex=True, figsize=(10.0, 5.5), layout="constrained")
    else:
        aw, ad = axes
        fig = aw.figure
    one = len(chosen) == 1
    colors = ["tab:blue"] if one else ["tab:blue", "tab:orange"] * len(chosen)
    start = 0.0
    for c, col in zip(chosen, colors):
        s = _frame_arc_length(c)
        o = np.argsort(s, kind="stable")
        length = float(_cad_arc_length(c)[-1] + np.linalg.norm(c.theoretical[-1] - c.theoretical[0]))
        for ax, v, se in ((aw, c.width, report.fits.se_width), (ad, c.depth, report.fits.se_depth)):
            ax.plot(start + s[o], v[o], color=col, lw=0.7, marker=".", ms=2.5, label=f"contour {c.cad_index}")
            if one:
                e = se[c.frames][o]
                ax.fill_between(s[o], v[o] - e, v[o] + e, color=col, alpha=0.25, lw=0, label="± 1 standard error")
                ax.axhline(float(v.mean()), color="0.3", ls="--", lw=0.8, label=f"mean {v.mean():.4f} mm")
            elif start > 0:
                ax.axvline(start, color="0.6", lw=0.6)
        if not one:
            aw.text(
                start + length / 2,
                1.01,
                str(c.cad_index),
                transform=aw.get_xaxis_transform(),
                ha="center",
                va="bottom",
                fontsize="small",
            )
        start += length
    if not chosen:
        _empty(aw, "no contour matched")
    limits = {}
    for ax, tol in ((aw, report.width_tolerance), (ad, report.depth_tolerance)):
        if tol is not None:
            ax.axhline(tol.lower, color="tab:red", ls=":", lw=0.9, label=f"limits {tol.lower:g}–{tol.upper:g} mm")
            limits[ax] = ax.axhline(tol.upper, color="tab:red", ls=":", lw=0.9)
    aw.set_ylabel("groove width w (mm)")
    ad.set_ylabel("groove depth d (mm)")
    for ax in (aw, ad):
        ax.grid(True, lw=0.3, alpha=0.5)
    if one:
        ad.set_xlabel("arc length along the CAD contour (mm)")
        aw.set_title(f"Groove width and depth along contour {chosen[0].cad_index} ({len(chosen[0].frames)} frames)")
        aw.legend(loc="best", fontsize="small")
        ad.legend(loc="best", fontsize="small")
    elif chosen:
        ad.set_xlabel("arc length along the CAD contours, end to end (mm)")
        for ax, name in ((aw, "width"), (ad, "depth")):
            v = np.concatenate([getattr(c, name) for c in chosen])
            mean = ax.axhline(float(v.mean()), color="0.2", ls="--", lw=0.8, label=f"mean {v.mean():.4f} mm")
            tol = getattr(report, f"{name}_tolerance")
            if tol is not None:
                limits[ax].set_label(f"limits {tol.lower:g}–{tol.upper:g} mm")
            ax.legend(handles=[mean, *([limits[ax]] if ax in limits else [])], loc="upper right", fontsize="small")
        aw.set_xlim(0.0, start)
        aw.set_title(f"Groove width and depth along {len(chosen)} contours (contour index on top)", pad=16)
    return fig


def width_depth_histograms(
    report: GrooveReport,
    *,
    bins: int = 40,
    axes: Sequence[Axes] | None = None,
) -> Figure:
    """Distributions of groove width and depth over all fitted frames (paper 000 §3:
    0.4806 ± 0.0163 mm and 0.3124 ± 0.0148 mm).

    The legend gives mean ± standard deviation over all converged frames. The range is
    the 0.5–99.5 % percentiles widened by a quarter; frames beyond it (a stray fit) are
    counted in the legend, not drawn, so one outlier does not squash the histogram.

    Parameters
    ----------
    report : GrooveReport
        From :func:`machscan.inspect_grooves`.
    bins : int
        Number of bins.
    axes : pair of matplotlib Axes, optional
        Where to draw width and depth; default a new figure with two columns.

    Returns
    -------
    matplotlib.figure.Figure
        Left: width (mm), right: depth (mm); counts of frames.

    Examples
    --------
    >>> fig = machscan.plot.width_depth_histograms(report)
    """
    report = _check_report(report)
    plt = _pyplot()
    if axes is None:
        fig, (aw, ad) = plt.subplots(1, 2, figsize=(9.0, 3.8), layout="constrained")
    else:
        aw, ad = axes
        fig = aw.figure
    ok = report.used
    for ax, v, name, col in (
        (aw, report.fits.width[ok], "groove width w (mm)", "tab:blue"),
        (ad, report.fits.depth[ok], "groove depth d (mm)", "tab:orange"),
    ):
        ax.set_xlabel(name)
        ax.set_ylabel("frames")
        if len(v) == 0:
            _empty(ax, "no frame fitted")
            continue
        lo, hi = np.percentile(v, [0.5, 99.5])
        pad = 0.25 * max(hi - lo, 1e-6)
        lo, hi = lo - pad, hi + pad
        inside = (v >= lo) & (v <= hi)
        ax.hist(
            v[inside], bins=bins, range=(lo, hi), color=col, alpha=0.75, label=f"mean ± std: {v.mean():.4f} ± {v.std():.4f} mm"
        )
        ax.axvline(float(v.mean()), color="k", lw=1.0)
        for k in (-1, 1):
            ax.axvline(float(v.mean() + k * v.std()), color="k", lw=0.8, ls="--")
        if not inside.all():
            ax.plot([], [], " ", label=f"{int((~inside).sum())} frames outside the range")
        ax.legend(loc="upper right", fontsize="small")
        ax.grid(True, lw=0.3, alpha=0.5)
    fig.suptitle(f"Groove width and depth over {int(ok.sum())} fitted frames")
    return fig


# ---- contour error --------------------------------------------------------------------------


def contour_error_map(
    report: GrooveReport,
    *,
    ax: Axes | None = None,
    cmap: str = "viridis",
    vmin: float | None = None,
    vmax: float | None = None,
    max_points: int = 4000,
    show_centers: bool = True,
    label_contours: bool = True,
) -> Figure:
    """The contour error over the part (paper 000 fig. 11).

    Every matched CAD contour is drawn in the WCS x-y plane, colored by the point error e_i
    of eq (23) (offset plus compensated deviation, mm). The point of largest error is marked.
    The measured groove centers of all fitted frames are dotted lightly under the contours:
    at the scale of the part they lie on their contour; any away from one are stray fits or
    grooves with no CAD contour.

    Parameters
    ----------
    report : GrooveReport
        From :func:`machscan.inspect_grooves`.
    ax : matplotlib Axes, optional
        Where to draw; default a new figure.
    cmap : str
        Color map of the error.
    vmin, vmax : float, optional
        Color range, mm; default the smallest and largest e_i over all contours.
    max_points : int
        A contour of more theoretical points is drawn with about this many segments, each
        colored by the mean e_i of the points it covers (the CAD contours are resampled every
        few µm: hundreds of thousands of points per part).
    show_centers : bool
        Dot the measured groove centers.
    label_contours : bool
        Write the CAD index of every contour at its centroid.

    Returns
    -------
    matplotlib.figure.Figure
        The map (one :class:`~matplotlib.collections.LineCollection` per contour) and its
        color bar in mm.

    Examples
    --------
    >>> fig = machscan.plot.contour_error_map(report)
    """
    report = _check_report(report)
    plt = _pyplot()
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    own_figure = ax is None
    if ax is None:
        fig, ax = plt.subplots(figsize=(7.5, 6.8), layout="constrained")
    else:
        fig = ax.figure
    if max_points < 3:
        raise ValueError(f"max_points: must be at least 3, got {max_points}")
    if show_centers:
        q = report.center_wcs[np.isfinite(report.center_wcs).all(axis=1)]
        ax.scatter(q[:, 0], q[:, 1], s=1.5, color="0.55", alpha=0.5, lw=0, zorder=1)
    if not report.contours:
        _empty(ax, "no contour matched")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        return fig
    all_e = np.concatenate([c.error.errors for c in report.contours])
    norm = Normalize(vmin=float(all_e.min()) if vmin is None else vmin, vmax=float(all_e.max()) if vmax is None else vmax)
    lc = None
    for c in report.contours:
        p, e = c.theoretical[:, :2], c.error.errors
        step = max(1, int(np.ceil(len(p) / max_points)))
        idx = np.arange(0, len(p), step)
        counts = np.diff(np.append(idx, len(p)))
        color = np.add.reduceat(e, idx) / counts
        # The contour is closed: the last segment returns to the first point.
        ends = np.append(idx[1:], 0)
        segments = np.stack([p[idx], p[ends]], axis=1)
        lc = LineCollection(list(segments), cmap=cmap, norm=norm, linewidths=2.5, zorder=2, capstyle="round")
        lc.set_array(color)
        ax.add_collection(lc)
        if label_contours:
            cx, cy = p.mean(axis=0)
            ax.text(cx, cy, str(c.cad_index), ha="center", va="center", fontsize="small", color="0.2")
    worst = max(report.contours, key=lambda c: c.error.max)
    i = int(np.argmax(worst.error.errors))
    px, py = worst.theoretical[i, :2]
    ax.plot([px], [py], marker="x", color="red", ms=9, mew=2, ls="none", zorder=3)
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(f"Contour error e_i: {all_e.mean():.4f} ± {all_e.std():.4f} mm over {len(report.contours)} contours")
    from matplotlib.lines import Line2D

    handles = [
        Line2D(
            [],
            [],
            ls="none",
            marker="x",
            color="red",
            ms=7,
            mew=2,
            label=f"max e = {worst.error.max:.4f} mm (contour {worst.cad_index})",
        )
    ]
    if show_centers:
        handles.insert(0, Line2D([], [], ls="none", marker=".", color="0.55", ms=6, label="measured groove centers"))
    if own_figure:
        fig.legend(handles=handles, loc="outside lower center", ncol=2, fontsize="small", frameon=False)
    else:
        ax.legend(handles=handles, loc="best", fontsize="small")
    fig.colorbar(lc, ax=ax, label="contour error e_i (mm)", shrink=0.85)
    return fig


def error_decomposition(report: GrooveReport, *, ax: Axes | None = None) -> Figure:
    """Offset, bending and local error per contour as stacked bars (paper 000 §3:
    offset 17.16 %, bending 74.56 %, local 8.28 %).

    Per contour: the offset error |E| once the bending is taken out, the mean bending error
    |B| at the CAD points and the mean local error (what is left). The last bar, "all",
    holds the overall means of :attr:`GrooveReport.decomposition`, whose shares are in the
    title. A black tick marks each contour's mean contour error e for comparison (e is not
    the sum of the parts: the parts are magnitudes of different vectors).

    Parameters
    ----------
    report : GrooveReport
        From :func:`machscan.inspect_grooves`.
    ax : matplotlib Axes, optional
        Where to draw; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure
        Three bar containers (offset, bending, local) of ``len(report.contours) + 1`` bars; mm.

    Examples
    --------
    >>> fig = machscan.plot.error_decomposition(report)
    """
    report = _check_report(report)
    plt = _pyplot()
    if ax is None:
        fig, ax = plt.subplots(figsize=(9.0, 4.5), layout="constrained")
    else:
        fig = ax.figure
    d = report.decomposition
    if d is None or not report.contours:
        _empty(ax, "no contour matched")
        return fig
    cs = report.contours
    names = [str(c.cad_index) for c in cs] + ["all"]
    off = np.array([c.offset_error for c in cs] + [d.offset])
    bend = np.array([float(c.bending.mean()) for c in cs] + [d.bending])
    loc = np.array([float(c.local.mean()) for c in cs] + [d.local])
    err = np.array([c.error.mean for c in cs] + [float(np.concatenate([c.error.errors for c in cs]).mean())])
    x = np.arange(len(names), dtype=float)
    x[-1] += 0.5  # set the overall bar apart
    ax.bar(x, off, width=0.7, color="tab:blue", label="offset |E|")
    ax.bar(x, bend, width=0.7, bottom=off, color="tab:orange", label="bending |B| (mean)")
    ax.bar(x, loc, width=0.7, bottom=off + bend, color="tab:green", label="local (mean)")
    ax.plot(x, err, ls="none", marker="_", ms=18, mew=2, color="k", label="mean contour error e")
    ax.set_xticks(x, names)
    ax.set_xlabel("contour")
    ax.set_ylabel("mean error (mm)")
    ax.grid(True, axis="y", lw=0.3, alpha=0.5)
    ax.legend(loc="upper left", fontsize="small")
    ax.set_title(
        f"Error decomposition: offset {100 * d.offset_share:.1f} %, bending {100 * d.bending_share:.1f} %, "
        f"local {100 * d.local_share:.1f} %"
    )
    return fig


def error_along(
    report: GrooveReport,
    *,
    contour: int | None = None,
    ax: Axes | None = None,
    max_points: int = 5000,
) -> Figure:
    """The contour error and its parts along one contour (paper 000 fig. 12).

    Against the arc length of the CAD contour: the point error e_i, the bending error |B| at
    each CAD point, the offset |E| (a constant) and the local error. Where bending dominates,
    e_i follows |B| and the local error is the ripple about it.

    Parameters
    ----------
    report : GrooveReport
        From :func:`machscan.inspect_grooves`.
    contour : int, optional
        CAD index of the contour; default the first matched one.
    ax : matplotlib Axes, optional
        Where to draw; default a new figure.
    max_points : int
        Draw about this many points per curve (every k-th CAD point).

    Returns
    -------
    matplotlib.figure.Figure
        Errors (mm) against arc length (mm).

    Examples
    --------
    >>> fig = machscan.plot.error_along(report, contour=0)
    """
    report = _check_report(report)
    plt = _pyplot()
    if ax is None:
        fig, ax = plt.subplots(figsize=(9.0, 4.0), layout="constrained")
    else:
        fig = ax.figure
    if not report.contours:
        _empty(ax, "no contour matched")
        return fig
    c = report.contours[0] if contour is None else _select(report, contour)[0]
    s = _cad_arc_length(c)
    k = slice(None, None, max(1, int(np.ceil(len(s) / max(max_points, 2)))))
    ax.plot(s[k], c.error.errors[k], color="k", lw=1.0, label="contour error e_i")
    ax.plot(s[k], c.bending[k], color="tab:orange", lw=1.0, label="bending |B|")
    ax.axhline(c.offset_error, color="tab:blue", lw=1.0, ls="--", label="offset |E|")
    ax.plot(s[k], c.local[k], color="tab:green", lw=0.8, label="local")
    ax.set_xlabel("arc length along the CAD contour (mm)")
    ax.set_ylabel("error (mm)")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.set_title(f"Contour {c.cad_index}: e = {c.error.mean:.4f} ± {c.error.std:.4f} mm, max {c.error.max:.4f} mm")
    return fig


# ---- one frame ------------------------------------------------------------------------------


def levelled_frame(
    x: ArrayLike,
    z: ArrayLike,
    frame: int,
    fits: GrooveFits | GrooveReport | None = None,
    *,
    options: GrooveOptions | None = None,
    ax: Axes | None = None,
    **changes: Any,
) -> Figure:
    """One profiler frame levelled as the groove fit sees it, with the fitted section or
    template (paper 000 fig. 4 and 10).

    The readings of the window, after the spike filter, are rotated by the surface tilt θ
    (``x' = cos θ·x + sin θ·z``, ``z' = −sin θ·x + cos θ·z``) and the shape fitted to the frame
    is drawn over them — evaluated by the core (:func:`machscan.level_groove_frame`), so the
    figure shows exactly what was fitted. The width (between the flanks at the surface line)
    and the depth (deepest point below it) are marked.

    The options must be those of the fit: by default :func:`machscan.inspect_grooves`'s
    (``INSPECTION_GROOVE``, a window of 200 readings) with the template of ``fits``.

    Parameters
    ----------
    x : array_like, shape (N,)
        Abscissa of each reading along the laser line, mm (``scan.profiler.x``).
    z : array_like, shape (F, N) or (N,)
        All frames (NaN marks an invalid reading), or just the one frame, mm.
    frame : int
        Index of the frame (its row of ``z`` and its entry in ``fits``).
    fits : GrooveFits or GrooveReport, optional
        The fits the figure is of: their template is used, and the frame's values are checked
        against the drawing.
    options : GrooveOptions, optional
        As in :func:`machscan.fit_grooves`.
    ax : matplotlib Axes, optional
        Where to draw; default a new figure.
    **changes
        Fields of :class:`machscan.GrooveOptions` changed for this figure.

    Returns
    -------
    matplotlib.figure.Figure
        Levelled readings and the fitted shape: levelled x' and z', mm.

    Examples
    --------
    >>> z = np.where(scan.valid_mask(), scan.frames, np.nan)
    >>> fig = machscan.plot.levelled_frame(scan.profiler.x, z, 120, report)
    """
    plt = _pyplot()
    z_arr = np.asarray(z, dtype=np.float64)
    if z_arr.ndim == 2:
        if not -z_arr.shape[0] <= frame < z_arr.shape[0]:
            raise ValueError(f"frame: {frame} is out of range for {z_arr.shape[0]} frames")
        row = z_arr[frame]
    elif z_arr.ndim == 1:
        row = z_arr
    else:
        raise ValueError(f"z: expected shape (F, N) or (N,), got {z_arr.shape}")
    if isinstance(fits, GrooveReport):
        fits = fits.fits
    if fits is not None and not -len(fits) <= frame < len(fits):
        raise ValueError(f"frame: {frame} is out of range for fits of {len(fits)} frames")
    if options is None:
        template = fits.template if fits is not None else INSPECTION_GROOVE.template
        options = replace(INSPECTION_GROOVE, template=template)  # type: ignore[arg-type]
    lf = level_groove_frame(x, row, options=options, **changes)
    if fits is not None and not np.array_equal(lf.fit.width, fits.width[frame : frame + 1], equal_nan=True):
        raise ValueError("fits: the frame's fit differs from this figure's: pass the settings the fits were made with")
    if ax is None:
        fig, ax = plt.subplots(figsize=(8.0, 4.0), layout="constrained")
    else:
        fig = ax.figure
    ax.plot(lf.x, lf.z, ls="none", marker=".", ms=4, color="tab:blue", label=f"levelled readings ({len(lf.x)})")
    status = lf.status
    model = lf.model.name.lower()
    if len(lf.shape_x):
        ax.plot(lf.shape_x, lf.shape_z, color="tab:red", lw=1.5, label=f"fitted section ({model})")
    w, d = float(lf.fit.width[0]), float(lf.fit.depth[0])
    if np.isfinite(w) and np.isfinite(d):
        x0l, z0l = lf.to_levelled(float(lf.fit.x0[0]), float(lf.fit.z0[0]))
        ax.annotate(
            "",
            xy=(x0l - w / 2, z0l),
            xytext=(x0l + w / 2, z0l),
            arrowprops=dict(arrowstyle="<->", color="0.25", lw=0.9, shrinkA=0, shrinkB=0),
        )
        box = dict(boxstyle="round,pad=0.2", fc="white", ec="none", alpha=0.85)
        ax.annotate(
            f"w = {w:.3f} mm",
            xy=(x0l, z0l),
            xytext=(0, 14),
            textcoords="offset points",
            ha="center",
            va="bottom",
            fontsize="small",
            color="0.2",
            bbox=box,
        )
        ax.annotate(
            "",
            xy=(x0l, z0l),
            xytext=(x0l, z0l - d),
            arrowprops=dict(arrowstyle="<->", color="0.25", lw=0.9, shrinkA=0, shrinkB=0),
        )
        ax.annotate(
            f"d = {d:.3f} mm",
            xy=(x0l + w / 2, z0l - d / 2),
            xytext=(8, 0),
            textcoords="offset points",
            ha="left",
            va="center",
            fontsize="small",
            color="0.2",
            bbox=box,
        )
        title = (
            f"Frame {frame}: w = {w:.4f} mm, d = {d:.4f} mm, rms {1000 * float(lf.fit.rms[0]):.1f} µm, "
            f"tilt {1000 * lf.tilt:.2f} mrad ({model}, {status.name.lower()})"
        )
    else:
        title = f"Frame {frame}: levelled readings, tilt {1000 * lf.tilt:.2f} mrad ({status.name.lower()})"
    ax.margins(y=0.15)
    ax.set_xlabel("x' along the laser line, levelled (mm)")
    ax.set_ylabel("z' height, levelled (mm)")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="lower left", fontsize="small")
    ax.set_title(title, fontsize="medium")
    return fig


def _axes3d(plt: Any, ax: Axes | None, elev: float, azim: float) -> tuple[Any, Any]:
    """The figure and 3D axes a map draws on: ``ax``, or a new figure's at the view angles given.
    Typed ``Any``: matplotlib's stubs type ``add_subplot`` as the 2D Axes, whose scatter takes (x, y)."""
    if ax is not None:
        return ax.figure, ax
    fig = plt.figure(figsize=(8, 6.5), layout="constrained")
    ax3d = fig.add_subplot(projection="3d")
    ax3d.view_init(elev=elev, azim=azim)
    return fig, ax3d


def _scatter_field(
    ax3d: Any,
    p: NDArray[np.float64],
    values: NDArray[np.float64],
    flagged: NDArray[np.bool_],
    max_points: int,
    cmap: str,
    norm: Any,
) -> Any:
    """Points coloured by a field: an even subsample of about ``max_points`` (every flagged point
    kept), those without a value grey, the flagged ones ringed in black. Returns the coloured set."""
    keep = np.zeros(len(p), dtype=bool)
    keep[:: max(1, int(np.ceil(len(p) / max_points)))] = True
    keep |= flagged
    finite = np.isfinite(values)
    grey = keep & ~finite
    if grey.any():
        ax3d.scatter(*p[grey].T, s=2, color="0.6", lw=0)
    ok = keep & finite
    sc = ax3d.scatter(*p[ok].T, c=values[ok], cmap=cmap, norm=norm, s=3, lw=0)
    if flagged.any():
        ax3d.scatter(*p[flagged].T, s=12, facecolors="none", edgecolors="k", lw=0.6)
    return sc


def _label_mm(ax3d: Any) -> None:
    ax3d.set_xlabel("x (mm)")
    ax3d.set_ylabel("y (mm)")
    if hasattr(ax3d, "set_zlabel"):
        ax3d.set_zlabel("z (mm)")


def allowance_map(
    points: ArrayLike,
    allowance: ArrayLike,
    *,
    min_allowance: float = 0.0,
    ax: Axes | None = None,
    cmap: str = "RdYlBu",
    max_points: int = 60000,
    elev: float = 25.0,
    azim: float = -60.0,
) -> Figure:
    """The machining allowance over the part (SPEC R7, paper 004 §1.2): the model points in 3D,
    colored by the stock the blank leaves there, the color scale centred on ``min_allowance``
    (red short of it, blue above it); points short of it are ringed in black, points without stock
    measured (NaN: the blank does not cover them) are grey and counted in the title.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        The model points, mm.
    allowance : array_like, shape (N,)
        From :func:`machscan.allowance` or :class:`machscan.EnvelopeFit`, mm.
    min_allowance : float
        The least stock asked for, mm: the color scale's centre.
    ax : matplotlib 3D Axes, optional
        Where to draw (``projection="3d"``); default a new figure.
    cmap : str
        A diverging color map.
    max_points : int
        More points are drawn as an even subsample of about this many (short points always).
    elev, azim : float
        View angles of a new 3D axes, degrees.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> a = machscan.allowance(model, normals, blank)
    >>> machscan.plot.allowance_map(model, a).savefig("allowance.png", dpi=150)
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    a = np.asarray(allowance, dtype=np.float64).reshape(-1)
    if len(a) != len(p):
        raise ValueError(f"allowance: expected one value per point ({len(p)}), got {len(a)}")
    if max_points < 1:
        raise ValueError(f"max_points: must be at least 1, got {max_points}")
    plt = _pyplot()
    from matplotlib.colors import TwoSlopeNorm

    fig, ax3d = _axes3d(plt, ax, elev, azim)
    finite = np.isfinite(a)
    short = finite & (a < min_allowance)
    if not finite.any():
        _empty(ax3d, "no allowance")
        return fig
    lo, hi = float(a[finite].min()), float(a[finite].max())
    # A two-slope norm needs the centre strictly inside the range.
    span = max(hi - lo, 1e-9)
    norm = TwoSlopeNorm(
        vcenter=min_allowance, vmin=min(lo, min_allowance - 1e-3 * span), vmax=max(hi, min_allowance + 1e-3 * span)
    )
    sc = _scatter_field(ax3d, p, a, short, max_points, cmap, norm)
    try:  # equal scales on a 3D axes (matplotlib >= 3.3)
        ax3d.set_box_aspect(np.ptp(p[finite], axis=0) + 1e-9)
    except (AttributeError, TypeError):  # pragma: no cover - a 2D axes given
        pass
    _label_mm(ax3d)
    n_short, n_none = int(short.sum()), int((~finite).sum())
    none = f"; {n_none} without stock measured (grey)" if n_none else ""
    ax3d.set_title(
        f"Allowance: min {lo:.3f}, mean {a[finite].mean():.3f}, max {hi:.3f} mm; "
        f"{n_short} point{'s' if n_short != 1 else ''} below {min_allowance:g} mm{none}"
    )
    fig.colorbar(sc, ax=ax3d, label="allowance (mm)", shrink=0.7)
    return fig


def deviation_map(
    points: ArrayLike,
    distances: ArrayLike,
    *,
    tolerance: float | tuple[float, float],
    vertices: ArrayLike | None = None,
    triangles: ArrayLike | None = None,
    ax: Axes | None = None,
    cmap: str = "RdBu_r",
    max_points: int = 60000,
    max_triangles: int = 20000,
    elev: float = 25.0,
    azim: float = -60.0,
) -> Figure:
    """The signed deviation from the CAD model (:func:`machscan.signed_distances`) as a colour
    map: the measured points in 3D, diverging colours centred on zero (red outside the material,
    blue inside), the tolerance band marked on the colour bar and every point outside it ringed
    in black. With the CAD mesh given, the mesh is drawn in grey underneath: grey is where no
    point was measured. Points without a distance (NaN) are grey and counted in the title.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        The measured points, in the model's frame, mm.
    distances : array_like, shape (N,)
        Their signed distances, mm.
    tolerance : float or (float, float)
        ``t`` for the band ±t, or ``(lower, upper)``, mm.
    vertices, triangles : array_like, optional
        The CAD mesh, drawn in grey (an even subsample of about ``max_triangles``).
    ax : matplotlib 3D Axes, optional
        Where to draw (``projection="3d"``); default a new figure.
    cmap : str
        A diverging colour map.
    max_points : int
        More points are drawn as an even subsample of about this many (out-of-tolerance points
        always).
    elev, azim : float
        View angles of a new 3D axes, degrees.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> d = machscan.signed_distances(scan, cad.vertices, cad.triangles)
    >>> machscan.plot.deviation_map(scan, d.distances, tolerance=0.05).savefig("deviation.png")
    """
    from machscan.deviation import tolerance_band

    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    d = np.asarray(distances, dtype=np.float64).reshape(-1)
    if len(d) != len(p):
        raise ValueError(f"distances: expected one value per point ({len(p)}), got {len(d)}")
    if max_points < 1 or max_triangles < 1:
        raise ValueError(f"max_points, max_triangles: must be at least 1, got {max_points}, {max_triangles}")
    if (vertices is None) != (triangles is None):
        raise ValueError("vertices, triangles: give both (the CAD mesh) or neither")
    lower, upper = tolerance_band(tolerance)
    plt = _pyplot()
    from matplotlib.colors import Normalize

    fig, ax3d = _axes3d(plt, ax, elev, azim)
    extent = p
    if vertices is not None and triangles is not None:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
        t = np.asarray(triangles).reshape(-1, 3)
        t = t[:: max(1, int(np.ceil(len(t) / max_triangles)))]
        ax3d.add_collection3d(Poly3DCollection(v[t], facecolors="0.8", edgecolors="none", alpha=0.35))
        extent = np.vstack([p, v]) if len(p) else v
    finite = np.isfinite(d)
    out = finite & ((d < lower) | (d > upper))
    if not finite.any():
        _empty(ax3d, "no deviation measured")
        return fig
    # Symmetric about zero, and wide enough to show the band.
    reach = max(float(np.abs(d[finite]).max()), abs(lower), abs(upper), 1e-9)
    norm = Normalize(vmin=-reach, vmax=reach)
    sc = _scatter_field(ax3d, p, d, out, max_points, cmap, norm)
    if len(extent):
        ax3d.set_box_aspect(np.ptp(extent, axis=0) + 1e-9)
        lo, hi = extent.min(axis=0), extent.max(axis=0)
        ax3d.set_xlim(lo[0], hi[0])
        ax3d.set_ylim(lo[1], hi[1])
        ax3d.set_zlim(lo[2], hi[2])
    _label_mm(ax3d)
    n_out, n_none = int(out.sum()), int((~finite).sum())
    none = f"; {n_none} without a distance (grey)" if n_none else ""
    ax3d.set_title(
        f"Deviation: min {d[finite].min():+.3f}, mean {d[finite].mean():+.3f}, max {d[finite].max():+.3f} mm\n"
        f"{n_out} point{'s' if n_out != 1 else ''} outside [{lower:g}, {upper:g}] mm{none}"
    )
    bar = fig.colorbar(sc, ax=ax3d, label="signed deviation (mm), + outside the material", shrink=0.7)
    for edge in (lower, upper):
        bar.ax.axhline(edge, color="k", lw=1.2)
    bar.ax.axhspan(lower, upper, color="k", alpha=0.08)
    return fig
