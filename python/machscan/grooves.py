"""Groove cross-sections (SPEC G, paper 000 §2.1): width, depth and center of the groove in
every profiler frame, as a result object.

By default the groove's geometry is measured: section models — trapezoid (flat floor), sharp
V, round-bottomed V (also a circular-arc U and drafted walls with a round bottom), U (circle
with vertical walls) and elliptic U (the U stretched across: a ball cutter's groove crossed
obliquely) — are fitted to each frame and the best by AIC is kept. Width is
the distance between the flanks where they meet the surface line, depth the deepest point below
the surface line. The paper's tanh template stays available (``template="tanh"``), whose width
and depth are the template's w and d.

Every default is defined once, in the Rust core (``GrooveOptions::default()``), and read from
there by the signatures below: :data:`DEFAULTS`.

The formulas and their papers: ``docs/grooves.md``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from enum import IntEnum
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan import progress as _progress
from machscan._options import changed

__all__ = [
    "CRITERIA_DEFAULTS",
    "DEFAULTS",
    "ROUNDING_POOLED_FRAMES",
    "FitCriteria",
    "GrooveFits",
    "GrooveModel",
    "GrooveOptions",
    "GrooveStatus",
    "LevelledFrame",
    "Misfit",
    "Rounding",
    "Select",
    "Template",
    "fit_grooves",
    "level_groove_frame",
]

#: The defaults of every groove option, by name, as the core defines them.
DEFAULTS = _core.groove_defaults()
#: The fit criteria each method uses where :class:`FitCriteria` leaves them at None.
CRITERIA_DEFAULTS = _core.fit_criteria_defaults()

#: Fewest frames per block when the fit shows progress: blocks keep every core busy.
PROGRESS_BLOCK = 2000

#: How a frame's groove is measured: "auto" (the best section model per frame), one section
#: model ("trapezoid", "v", "round", "u", "ellipse"), or the paper's "tanh" template.
Template = Literal["auto", "trapezoid", "v", "round", "u", "ellipse", "tanh"]

#: Which of a frame's grooves are measured: the deepest, the ``index``-th from the left or
#: right, the one nearest ``near``, or all of them (a row per groove).
Select = Literal["deepest", "left", "right", "nearest", "all"]
#: How a V's tip rounding is settled: a prior pooled over the call's V's, or each frame on its
#: own (or, as the option's value, a prior (share, r_max mm) given).
Rounding = Literal["pooled", "frame"]

#: How the misfit of the chosen section (at the groove's bottom; a U's against the ellipse)
#: enters the errors: its variance pooled over the call's frames, or none (or, as the option's
#: value, variances by name given).
Misfit = Literal["pooled", "none"]

#: Most frames a pooled rounding prior is estimated from (every k-th frame of a call).
ROUNDING_POOLED_FRAMES: int = _core.ROUNDING_POOLED_FRAMES

#: The fields of :class:`GrooveFits` that are one value for the call, not a row each.
_CALL_FIELDS = ("template", "rounding_prior", "misfit")


def _stretch_misfit(measure: str, bias: float, variance: float) -> str:
    """A measure's pooled ellipse-less-U difference, its mean and standard deviation, with units."""
    sd = variance**0.5
    if measure.startswith("flank_angle"):
        return f"{measure} {bias:+.2f}° ± {sd:.2f}°"
    if measure == "area":
        return f"{measure} {bias:+.3g} ± {sd:.3g} mm²"
    return f"{measure} {1000 * bias:+.1f} ± {1000 * sd:.1f} µm"


@dataclass(frozen=True)
class FitCriteria:
    """When the Levenberg–Marquardt fit of a frame stops (grouped as Open3D groups
    ``ICPConvergenceCriteria``). None takes the method's own default
    (:data:`CRITERIA_DEFAULTS`):

    ============================  ================================  =================================
    field                         section models (the default)      ``template="tanh"`` (paper)
    ============================  ================================  =================================
    ``max_iterations``            15 per model (8 for the           100
                                  trapezoid that screens a frame
                                  first; a chosen model not yet
                                  converged gets 3× as many more)
    ``cost_tolerance``            1e-5: an accepted step lowering   0 (off): paper 000's
                                  the cost less, relatively, ends   ``½ Σ f²/t < ε``
    ``step_tolerance``            1e-6: no parameter moves more     1e-8, relative to the
                                                                    parameters
    ``gradient_tolerance``        0 (off)                           1e-13, ``‖Jᵀf‖∞``
    ============================  ================================  =================================

    Examples
    --------
    >>> fits = machscan.fit_grooves(x, z, criteria=machscan.FitCriteria(max_iterations=30))
    """

    max_iterations: int | None = None
    cost_tolerance: float | None = None
    step_tolerance: float | None = None
    gradient_tolerance: float | None = None


@dataclass(frozen=True)
class GrooveOptions:
    """How every frame's groove is measured: the options of :func:`fit_grooves`,
    :func:`level_groove_frame`, :func:`machscan.inspect_grooves` (its ``groove``),
    :func:`machscan.dask.fit_grooves` and the ``machscan grooves`` command, each default written
    once, in the core (:data:`DEFAULTS`).

    Attributes
    ----------
    template : {"auto", "trapezoid", "v", "round", "u", "ellipse", "tanh"}
        "auto": the best section model per frame; a model name: that model only; "tanh": the
        paper's template.
    alpha : float
        The tanh template's shape coefficient, mm⁻¹ (paper: 20).
    nominal_width : float
        The tanh template pipeline's nominal groove width l, mm (the section models find the
        groove's extent from the data).
    window : int, optional
        Number t of readings kept around the center; None: all.
    window_center : int, optional
        Reading index the window is centered on; None: N // 2.
    fit_alpha : bool
        Fit the tanh template's α as a fifth parameter.
    spike_threshold : float or None
        Spike test threshold, mm (None: off).
    min_depth : float
        Shallowest dip that counts as a groove, mm.
    min_valid : int
        Fewest valid readings in the window.
    criteria : FitCriteria
        When each fit stops; its None fields: each method's own (:data:`CRITERIA_DEFAULTS`).
    sentinel : float or None
        The profiler's "no reading" code, mm (default :data:`machscan.SENTINEL`, −99999).
        Readings equal to it, NaN and readings outside ``valid_range`` are invalid and left out,
        by the same rule as :func:`machscan.scan_to_wcs` and :meth:`machscan.Profiler.valid_mask`.
    valid_range : (float, float), optional
        The profiler's measuring range ``(lo, hi)``, mm.
    select : {"deepest", "left", "right", "nearest", "all"}
        Which grooves of a frame are measured (section models; the tanh template measures the
        one groove of its window). Every dip deeper than ``min_depth`` and 4× the surface noise
        is a groove, its extent walked out from its bottom to the surface or to a corner it
        shares with a neighbour; one surface line is fitted without any of them. "deepest":
        the deepest; "left" / "right": the ``index``-th from that side (0 = the outermost);
        "nearest": the one whose bottom is nearest ``near``; "all": every groove, a row each
        (:attr:`GrooveFits.frame`, :attr:`GrooveFits.groove`). Grooves measured outside the
        validity limits do not count.
    index : int
        For "left" / "right": which groove from that side, counting grooves within the limits.
    near : float, optional
        For "nearest": the x (frame coordinates, mm) the groove's bottom should be nearest.
    min_width, max_width, max_depth : float, optional
        Validity limits, mm: a groove measured outside them is not one of the part's (a
        scratch, a neighbouring feature) and is passed over (``min_depth`` is the lower depth
        limit).
    rounding : "pooled", "frame" or (share, r_max)
        How a V's tip rounding is settled, which one frame's readings cannot tell from a
        sharp tip (a rounding over a reading or two moves the depth by 5–25 µm). "pooled": a
        prior on the tip radius — ``share`` of the V's sharp, the rest rounded uniformly up to
        ``r_max`` mm — estimated from the call's V's (every k-th frame, at most
        :data:`ROUNDING_POOLED_FRAMES` frames; the frames of one scan share a tool or a beam),
        each V's depth the median of its posterior under it (:attr:`GrooveFits.rounding_prior`
        says which; below 30 V's, each frame's own rule). "frame": each frame on its own (the
        Akaike-weighted mean of the sharp and the round V). ``(share, r_max)``: that prior (a
        process the plant knows, or a pooled call's, to measure one frame alike).
    misfit : "pooled", "none" or {name: variance}
        How the misfit of the chosen section enters the errors. A section no model holds (a
        bowl with curved flanks) is measured as the nearest model's, whose bias one frame's
        readings barely show; and a U is kept over the ellipse unless the ellipse fits clearly
        better, so a section a little wider than deep is measured as a circle. "pooled":
        estimated over the call's frames (the frames pooled for ``rounding``; from at least 30
        of them): per model chosen, the variance of the residual at the bottom beyond the
        noise, which each frame's ``se_depth`` takes its own residual's share of; and per
        measure, the mean of the ellipse's value less the U's and their variance beyond what
        the noise gives them, which each U's errors take their own difference's share of
        (:attr:`GrooveFits.misfit` says what was pooled; 0 where the models hold the section).
        "none": the models' errors alone. ``{"u": 4e-6, "u:flank_angle_left": 2.5,
        "u:flank_angle_left:bias": -3.1, ...}``: those, by model name in mm², by ``"u:"`` and a
        measure in its unit squared, with ``":bias"`` in its unit (a pooled call's, to measure
        one frame alike). V's whose depth the rounding settles are left to it.

    Examples
    --------
    >>> options = machscan.GrooveOptions(window=200, template="tanh")
    >>> fits = machscan.fit_grooves(x, z, options=options)
    >>> fits = machscan.fit_grooves(x, z, options=options, window=150)   # one option changed for this call
    """

    template: Template = DEFAULTS["template"]
    alpha: float = DEFAULTS["alpha"]
    nominal_width: float = DEFAULTS["nominal_width"]
    window: int | None = DEFAULTS["window"]
    window_center: int | None = DEFAULTS["window_center"]
    fit_alpha: bool = DEFAULTS["fit_alpha"]
    spike_threshold: float | None = DEFAULTS["spike_threshold"]
    min_depth: float = DEFAULTS["min_depth"]
    min_valid: int = DEFAULTS["min_valid"]
    criteria: FitCriteria = field(default_factory=lambda: FitCriteria())
    sentinel: float | None = DEFAULTS["sentinel"]
    valid_range: tuple[float, float] | None = DEFAULTS["valid_range"]
    select: Select = DEFAULTS["select"]
    index: int = DEFAULTS["index"]
    near: float | None = DEFAULTS["near"]
    min_width: float | None = DEFAULTS["min_width"]
    max_width: float | None = DEFAULTS["max_width"]
    max_depth: float | None = DEFAULTS["max_depth"]
    rounding: Rounding | tuple[float, float] = DEFAULTS["rounding"]
    misfit: Misfit | Mapping[str, float] | tuple[tuple[str, float], ...] = DEFAULTS["misfit"]

    def __post_init__(self) -> None:
        if not isinstance(self.criteria, FitCriteria):
            raise ValueError(f"criteria: expected a machscan.FitCriteria, got {type(self.criteria).__name__}")
        if self.valid_range is not None:
            lo, hi = self.valid_range
            object.__setattr__(self, "valid_range", (lo, hi))
        if not isinstance(self.rounding, str):
            # A prior as any pair (a list, an array); the core checks the values.
            try:
                share, r_max = (float(v) for v in self.rounding)
            except (TypeError, ValueError):
                raise ValueError(
                    f'rounding: expected "pooled", "frame" or (share, r_max) with r_max in mm, got {self.rounding!r}'
                ) from None
            object.__setattr__(self, "rounding", (share, r_max))
        if not isinstance(self.misfit, str):
            # Variances by name as (name, variance) pairs, so that the options stay hashable;
            # the core checks the names and values.
            try:
                pairs = tuple((str(k), float(v)) for k, v in dict(self.misfit).items())
            except (TypeError, ValueError):
                raise ValueError(
                    'misfit: expected "pooled", "none" or variances by name (a model in mm², "u:" and a'
                    f" measure in its unit squared), got {self.misfit!r}"
                ) from None
            object.__setattr__(self, "misfit", pairs)

    def with_changes(self, changes: Mapping[str, Any], where: str = "options") -> GrooveOptions:
        """These options with ``changes`` (option names and values) made; an unknown name is an
        error naming it and ``where``, the call it was given to."""
        return changed(self, changes, where)


def groove_options(options: GrooveOptions | None, changes: Mapping[str, Any], where: str) -> GrooveOptions:
    """The options a call measures with: ``options`` (default ``GrooveOptions()``) with the
    call's keyword ``changes``."""
    if options is None:
        options = GrooveOptions()
    if not isinstance(options, GrooveOptions):
        raise ValueError(f"options: expected a machscan.GrooveOptions, got {type(options).__name__}")
    return options.with_changes(changes, where)


class GrooveStatus(IntEnum):
    """What became of a frame (the codes in :attr:`GrooveFits.status`)."""

    CONVERGED = 0
    """The fit converged."""
    MAX_ITERATIONS = 1
    """The iteration limit was hit; the result is the best found (still measured)."""
    NO_GROOVE = 2
    """No dip deeper than ``min_depth`` and 4× the surface noise."""
    TOO_FEW_VALID = 3
    """Too few valid readings in the window."""
    TWO_GROOVES = 4
    """The tanh template only: a second dip at least half as deep lies in the window (narrow
    the window, or use the section models, which find every groove: ``select``)."""
    CLIPPED = 5
    """The groove reaches the window edge: fewer than 3 surface readings on one side."""
    FAILED = 6
    """The fit failed numerically (or, for the tanh template, ran away to a width outside
    ¼–4× the nominal width)."""


class GrooveModel(IntEnum):
    """What was fitted to a frame (the codes in :attr:`GrooveFits.model`)."""

    NONE = 0
    """Nothing: the frame was not measured."""
    TANH = 1
    """Paper 000's tanh template."""
    TRAPEZOID = 2
    """Flat floor, straight flanks, small bottom fillets."""
    V = 3
    """Sharp V."""
    ROUND = 4
    """V whose bottom is one arc: a rounded V, a circular-arc U, drafted walls and a round bottom."""
    U = 5
    """Circle with vertical walls."""
    ELLIPSE = 6
    """Ellipse with vertical walls: the U stretched across (crossed obliquely, a tilted cutter)."""


@dataclass(frozen=True, eq=False, repr=False)
class GrooveFits:
    """Groove measurements: every array has one entry per row — a row per frame, or with
    ``select="all"`` a row per groove (and one for a frame without any), ``frame`` and
    ``groove`` saying which.

    Frames that could not be measured hold NaN in the float arrays and say why in ``status``
    (:class:`GrooveStatus`); use ``ok`` to select the converged ones.

    Attributes
    ----------
    x0, z0 : ndarray (F,)
        Groove center (the midpoint of the flank crossings) and the surface height there, mm,
        in the coordinates of the x and z given.
    depth : ndarray (F,)
        Deepest point of the groove below the surface line, mm (tanh template: its d; a V's:
        the median of its posterior under the tip-rounding prior, ``rounding_prior``).
    width : ndarray (F,)
        Distance between the flanks where they meet the surface line, mm (tanh template: its w).
    alpha : ndarray (F,)
        The tanh template's shape coefficient used or fitted, mm⁻¹; NaN for the section models.
    rms : ndarray (F,)
        Residual RMS of the fit, mm (along the sensor beam for the section models).
    se_depth, se_width : ndarray (F,)
        Standard errors of depth and width, mm: the fit's covariance (the larger of the
        classical ``σ̂² (JᵀJ)⁻¹``, scaled by Student's t for its m − p degrees of freedom, and
        the HC3 sandwich), the surface line's, the spread of the other models fitted by their
        Akaike weights, and for an edge between two readings the gap it may lie in
        (``docs/grooves.md``, step 11); and the misfit the call pools (``misfit``: ``se_depth``
        the bottoms', a U's errors the ellipse's). value ± 2·se is meant to hold the truth 95 %
        of the time. On a section no model holds (a bowl with curved flanks) the nearest model's
        bias is in ``se_depth`` through the pooled misfit, but not in the other errors: on
        parabolic and quartic bowls ±2·se held the flank angles in 19–68 % of frames
        (``benchmarks/coverage_grooves.py``).
    flank_angle_left, flank_angle_right : ndarray (F,)
        Angle between each flank and the surface line where they meet, degrees (90: a
        vertical wall; a circular U shallower than its radius: the arc's angle there), within
        2.9–98.5° and the section's lean (a profiler sees no deeper overhang: an angle the fit
        put past that is held at the bound, its standard error that of an angle anywhere in
        the span, 27.6°). NaN for the tanh template, as are the measures below.
    area : ndarray (F,)
        Cross-section area between the surface line and the section, mm².
    bottom_radius : ndarray (F,)
        Radius of the round bottom, mm: a U's, a round V's (for V's the Akaike-weighted mean
        of the sharp V's 0 and the round V's, whatever ``rounding``); NaN for a trapezoid's flat
        floor.
    step : ndarray (F,)
        Surface step across the groove: the right surface minus the left, along the surface
        line's normal, mm (two parallel lines fitted to the surface readings beside the groove,
        lips left out; NaN when a side has fewer than three, as beside a shared corner).
    se_x0, se_z0, se_flank_angle_left, se_flank_angle_right, se_area, se_bottom_radius, se_step : ndarray (F,)
        Standard errors of those measures, in their units (mm, degrees, mm²), as ``se_depth``:
        the fit's covariance and the surface line's by the delta method, and the model spread;
        the step's from its own line fit.
    tilt : ndarray (F,)
        Surface slope angle used for levelling, rad.
    iterations, n_used : ndarray of int32 (F,)
        LM iterations (all fits of the frame) and readings fitted.
    status : ndarray of uint8 (F,)
        :class:`GrooveStatus` codes.
    model : ndarray of uint8 (F,)
        :class:`GrooveModel` codes: what was fitted to each frame.
    groove : ndarray of int32 (F,)
        The groove's place among its frame's grooves, from the left (0 = leftmost; −1: none
        found).
    frame : ndarray of int32 (F,)
        The frame of each row.
    template : str
        The ``template`` option used.
    rounding_prior : (float, float) or None
        The prior the V's tip rounding was settled with: the share of sharp tips and the
        largest radius, mm (``rounding`` pooled or given); None: each frame's own rule.
    misfit : dict or None
        The misfit variances the errors took in (``misfit`` pooled: from at least 30 of the
        frames pooled; or given): by model name, the section's residual at the bottom beyond the
        noise (in ``se_depth``), mm²; by ``"u:"`` and a measure (``"u:width"``, ``"u:depth"``,
        ``"u:x0"``, ``"u:flank_angle_left"``, ``"u:flank_angle_right"``, ``"u:area"``,
        ``"u:bottom_radius"``), the variance of the ellipse's value less the U's beyond the
        noise, in the measure's unit squared (mm², degrees², mm⁴ for the area), and with
        ``":bias"`` their mean, in its unit (0 where within two of its standard errors of 0),
        both in a U's ``se_<measure>``; None: ``misfit="none"``.
    """

    x0: NDArray[np.float64]
    z0: NDArray[np.float64]
    depth: NDArray[np.float64]
    width: NDArray[np.float64]
    alpha: NDArray[np.float64]
    rms: NDArray[np.float64]
    se_depth: NDArray[np.float64]
    se_width: NDArray[np.float64]
    flank_angle_left: NDArray[np.float64]
    flank_angle_right: NDArray[np.float64]
    area: NDArray[np.float64]
    bottom_radius: NDArray[np.float64]
    step: NDArray[np.float64]
    se_x0: NDArray[np.float64]
    se_z0: NDArray[np.float64]
    se_flank_angle_left: NDArray[np.float64]
    se_flank_angle_right: NDArray[np.float64]
    se_area: NDArray[np.float64]
    se_bottom_radius: NDArray[np.float64]
    se_step: NDArray[np.float64]
    tilt: NDArray[np.float64]
    iterations: NDArray[np.int32]
    n_used: NDArray[np.int32]
    status: NDArray[np.uint8]
    model: NDArray[np.uint8]
    groove: NDArray[np.int32]
    frame: NDArray[np.int32]
    template: str = DEFAULTS["template"]
    rounding_prior: tuple[float, float] | None = None
    misfit: dict[str, float] | None = None

    def __len__(self) -> int:
        return len(self.status)

    @property
    def ok(self) -> NDArray[np.bool_]:
        """Frames whose fit converged."""
        return self.status == GrooveStatus.CONVERGED

    @property
    def measured(self) -> NDArray[np.bool_]:
        """Frames with a result: converged, or at the iteration limit with the best found."""
        return (self.status == GrooveStatus.CONVERGED) | (self.status == GrooveStatus.MAX_ITERATIONS)

    @property
    def models_hold(self) -> bool | None:
        """Whether the section models hold these grooves' bottoms: False where the largest
        misfit at the bottom (:attr:`misfit`, by model) is over a third of the fits' median
        ``rms`` — it then widens an error of the noise's size by more than 5 %, and the errors
        of the flank angles, widths and radii leave out what it stands for (a curved wall);
        None where nothing tells: ``misfit="none"``, no fit, or no model's misfit pooled (fewer
        than 30 of its fits; V's whose depths the tip-rounding prior settles pool none).

        Examples
        --------
        >>> fits = machscan.fit_grooves(x, z)
        >>> if fits.models_hold is False:   # a curved wall: angles and widths beyond their errors
        ...     print(fits.pooled_lines())
        """
        rms = self.rms[np.isfinite(self.rms)]
        bottom = [v for k, v in (self.misfit or {}).items() if ":" not in k]
        if not bottom or rms.size == 0:
            return None
        # A misfit over a third of the RMS: sqrt(1 + 1/9) = 1.054 on an error of the noise's size.
        return max(bottom) ** 0.5 <= float(np.median(rms)) / 3

    def counts(self) -> dict[str, int]:
        """Number of frames per status."""
        return {s.name.lower(): int(np.count_nonzero(self.status == s)) for s in GrooveStatus}

    def model_counts(self) -> dict[str, int]:
        """Number of measured frames per fitted model."""
        return {m.name.lower(): int(np.count_nonzero(self.model == m)) for m in GrooveModel if m != GrooveModel.NONE}

    def select(self, index: ArrayLike) -> GrooveFits:
        """The fits of a subset of frames (boolean mask or indices)."""
        arrays = {f.name: getattr(self, f.name)[index] for f in fields(self) if f.name not in _CALL_FIELDS}
        return GrooveFits(**arrays, template=self.template, rounding_prior=self.rounding_prior, misfit=self.misfit)

    def summary(self) -> str:
        """Width and depth statistics over the converged frames, the models fitted and the
        status counts."""
        ok = self.ok
        frames = len(np.unique(self.frame))
        rows = f"{frames} frames" if frames == len(self) else f"{len(self)} grooves in {frames} frames"
        lines = [f"{rows}, {int(ok.sum())} fitted"]
        if ok.any():
            for name in ("width", "depth", "rms"):
                v = getattr(self, name)[ok]
                lines.append(f"  {name:>5}: {v.mean():.4f} ± {v.std():.4f} mm (min {v.min():.4f}, max {v.max():.4f})")
            # The section models' further measures (NaN for the tanh template: left out).
            for name, unit, digits in (
                ("flank_angle_left", "°", 2),
                ("flank_angle_right", "°", 2),
                ("area", " mm²", 5),
                ("bottom_radius", " mm", 4),
                ("step", " mm", 4),
            ):
                v = getattr(self, name)[ok]
                v = v[np.isfinite(v)]
                if len(v):
                    lines.append(f"  {name}: {v.mean():.{digits}f} ± {v.std():.{digits}f}{unit} ({len(v)} fits)")
            models = {k: v for k, v in self.model_counts().items() if v}
            lines.append("  models: " + ", ".join(f"{k} {v}" for k, v in models.items()))
            lines += ["  " + line for line in self.pooled_lines()]
        bad = {k: v for k, v in self.counts().items() if v and k != "converged"}
        if bad:
            lines.append("  not fitted: " + ", ".join(f"{k} {v}" for k, v in bad.items()))
        return "\n".join(lines)

    def pooled_lines(self) -> list[str]:
        """What the call pooled over its frames, a line each, with units: the V tip-rounding
        prior, the misfit at the bottom that ``se_depth`` took in (standard deviations by
        model; where they do not hold, :attr:`models_hold`, that no section model holds these
        bottoms) and a U's against the ellipse (mean ± standard deviation by
        measure); those that are 0 are left out."""
        lines = []
        if self.rounding_prior is not None:
            share, r_max = self.rounding_prior
            lines.append(f"V tip rounding prior: {100 * share:.0f} % sharp, the rest rounded up to {1000 * r_max:.1f} µm")
        misfit = self.misfit or {}
        bottom = {k: v for k, v in misfit.items() if ":" not in k and v > 0}
        if bottom:
            line = "bottom misfit in se_depth (sd): " + ", ".join(f"{k} {1000 * v**0.5:.1f} µm" for k, v in bottom.items())
            if self.models_hold is False:
                line += "; no section model holds these bottoms: flank angles, widths and radii may be off by more"
                line += " than their errors"
            lines.append(line)
        stretch = []
        for key in (k for k in misfit if k.startswith("u:") and not k.endswith(":bias")):
            variance, bias = misfit[key], misfit.get(key + ":bias", 0.0)
            if variance > 0 or bias != 0:
                stretch.append(_stretch_misfit(key.removeprefix("u:"), bias, variance))
        if stretch:
            lines.append("U against the ellipse in its errors: " + ", ".join(stretch))
        return lines

    def __repr__(self) -> str:
        return f"GrooveFits({len(self)} rows, {int(self.ok.sum())} converged)"


def fit_grooves(
    x: ArrayLike,
    z: ArrayLike,
    *,
    options: GrooveOptions | None = None,
    progress: bool | None = False,
    **changes: Any,
) -> GrooveFits:
    """Measure the groove in every profiler frame (SPEC G): width, depth and center.

    Definitions: **width** is the distance between the groove's flanks where they meet the
    surface line (for straight flanks with rounded top corners, the flank lines extended to the
    surface; for a circular U, where the arc meets it); **depth** is the groove's deepest point
    below the surface line; the **center** is the midpoint of the two crossings, at the surface.

    The default (``template="auto"``) measures V, U and trapezoid (flat-floored) grooves, with
    recast lips beside the edges, surface tilt, dropouts and spikes, and needs no nominal
    width. Per frame: valid readings, spikes dropped (a two-sided extrapolation test that keeps
    V tips and wall corners); a robust surface line (least trimmed squares) and levelling; the
    groove's extent by a walk from its bottom out to the surface; the surface refitted without
    the groove and its lips; then the section models — trapezoid, sharp V, round-bottomed V, U,
    and the U stretched into an ellipse where that promises a better fit — fitted by a bounded
    Levenberg–Marquardt with residuals along the sensor beam, the one with the smallest AIC kept
    (outliers against it dropped and the models refitted once; a frame tilted by shear rather
    than rotation tested with the section leaning by the tilt).
    The models are fitted in the order the groove's first outline suggests, and one that
    already fits the readings within their noise rules out those that could not beat it (a V
    that fits leaves the trapezoid and the U out): 1.1–1.6 times faster than fitting all four.
    A V's tip rounded by a reading spacing or two is barely visible at 8 µm noise, so its
    rounding is settled over the call's V's (``rounding``, :class:`GrooveOptions`): a prior on
    the tip radius they pool to, and each V's depth the median of its posterior. Accuracy,
    measured on V, U and trapezoid grooves 0.2–1.2 mm wide and 0.05–0.5 mm deep with 8 µm
    noise, lips, ±0.1 rad tilt, dropouts and spikes: median |width error| 5–6 µm, |depth
    error| 0.4–1.5 %, |center error| 1.4–2.9 µm, ≥ 99.5 % of frames measured (BENCHMARKS.md).

    ``template="tanh"`` is paper 000's method: the template
    ``z = z0 + ½d(tanh(α(x − x0 − w/4)) − tanh(α(x − x0 + w/4)))`` fitted after the paper's
    levelling; its width and depth are the template's w and d. It measures its own shape well
    and a straight V badly (~18 % too wide and too shallow at α = 20).

    All frames run in parallel with the GIL released; the result does not depend on the thread
    count.

    Parameters
    ----------
    x : array_like, shape (N,)
        Abscissa of each reading along the laser line, mm (shared by all frames).
    z : array_like, shape (F, N) or (N,)
        Readings (heights), mm, raw as the profiler gives them or with NaN for invalid readings. One frame may be
        given as (N,): the result then has length 1.
    options : GrooveOptions, optional
        How the groove is measured (default :class:`GrooveOptions()`; every field is described
        there).
    **changes
        Fields of :class:`GrooveOptions` changed for this call: ``fit_grooves(x, z, window=200)``
        is ``fit_grooves(x, z, options=GrooveOptions(window=200))``.
    progress : bool or None
        Show a progress bar (frames done, rate, time left) on stderr; None: when stderr is a
        terminal. The frames are then fitted in 50 blocks; the result is the same.

    Returns
    -------
    GrooveFits
        Per-frame ``x0, z0, width, depth, rms, status, model, se_width, se_depth, ...``.

    Examples
    --------
    >>> fits = machscan.fit_grooves(x, z, window=200)
    >>> fits.width[fits.ok].mean(), fits.model_counts()
    """
    options = groove_options(options, changes, "fit_grooves")
    if np.ndim(z) == 1:  # one frame
        z = np.asarray(z, dtype=np.float64)[np.newaxis, :]
    frames = np.asarray(z, dtype=np.float64) if _progress.wanted(progress) else None
    if frames is None or frames.ndim != 2 or len(frames) == 0:  # the core names a shape error
        return GrooveFits(**_core.fit_grooves(x, z, options), template=options.template)
    z = frames
    # The blocks measure under what the whole call pools to (the same frames pooled).
    pooled, block_options = settled_pools(x, z, options)
    step = max(PROGRESS_BLOCK, -(-len(z) // 50))
    parts = []
    with _progress.bar(len(z), "frames", True, "groove fits") as shown:
        for start in range(0, len(z), step):
            part = _core.fit_grooves(x, z[start : start + step], block_options)
            part["frame"] += start
            parts.append(part)
            shown.update(len(z[start : start + step]))
    merged: dict[str, Any] = {
        name: np.concatenate([p[name] for p in parts])  # type: ignore[literal-required]
        for name in parts[0]
        if name not in _CALL_FIELDS
    }
    return GrooveFits(**merged, template=options.template, **pooled)


def settled_pools(x: ArrayLike, frames: Any, options: GrooveOptions) -> tuple[dict[str, Any], GrooveOptions]:
    """For a call measured in parts (blocks, chunks): what the whole call pools to — the
    rounding prior and the misfit variances, fitted on the frames it pools, every k-th — as
    the :class:`GrooveFits` fields ``rounding_prior`` and ``misfit``, and the options that
    measure each part under them (given, or ``rounding="frame"`` where too few V's pool).
    Options that pool nothing are returned as they are."""
    # What the in-memory call gives where nothing is pooled: the given values, or none; a
    # pooled misfit over no frames (or the tanh template's, which has no bottom residuals)
    # has no model.
    rounding = options.rounding if isinstance(options.rounding, tuple) else None
    misfit = None if options.misfit == "none" else dict(options.misfit) if isinstance(options.misfit, tuple) else {}
    pools = options.template != "tanh" and "pooled" in (options.rounding, options.misfit)
    if pools and len(frames):
        stride = max(1, -(-len(frames) // ROUNDING_POOLED_FRAMES))
        sample = _core.fit_grooves(x, np.asarray(frames[::stride], dtype=np.float64), options)
        changes: dict[str, Any] = {}
        if options.rounding == "pooled":
            rounding = sample["rounding_prior"]
            changes["rounding"] = rounding if rounding is not None else "frame"
        if options.misfit == "pooled":
            misfit = sample["misfit"]
            changes["misfit"] = misfit
        options = options.with_changes(changes)
    return {"rounding_prior": rounding, "misfit": misfit}, options


@dataclass(frozen=True, eq=False, repr=False)
class LevelledFrame:
    """One frame as the groove fit sees it, for figures: the readings levelled and the fitted
    shape, both in the levelled coordinates ``x' = cos θ·x + sin θ·z``,
    ``z' = −sin θ·x + cos θ·z`` (mm).

    Attributes
    ----------
    x, z : ndarray (M,)
        Valid readings of the window after the spike filter, levelled.
    shape_x, shape_z : ndarray (K,)
        The fitted section (or template), sampled densely; empty when nothing was fitted.
    tilt : float
        θ, the surface slope angle, rad.
    fit : GrooveFits
        The fit of this frame (length 1).
    """

    x: NDArray[np.float64]
    z: NDArray[np.float64]
    shape_x: NDArray[np.float64]
    shape_z: NDArray[np.float64]
    tilt: float
    fit: GrooveFits

    @property
    def status(self) -> GrooveStatus:
        return GrooveStatus(int(self.fit.status[0]))

    @property
    def model(self) -> GrooveModel:
        return GrooveModel(int(self.fit.model[0]))

    def to_frame(self, x0: float, z0: float) -> tuple[float, float]:
        """Map a levelled point back to the frame's own coordinates."""
        c, s = np.cos(self.tilt), np.sin(self.tilt)
        return c * x0 - s * z0, s * x0 + c * z0

    def to_levelled(self, x: float, z: float) -> tuple[float, float]:
        """Map a point of the frame into the levelled coordinates."""
        c, s = np.cos(self.tilt), np.sin(self.tilt)
        return c * x + s * z, -s * x + c * z

    def __repr__(self) -> str:
        return f"LevelledFrame({len(self.x)} readings, tilt={self.tilt:.3g} rad, {self.status.name}, {self.model.name})"


def level_groove_frame(
    x: ArrayLike,
    z: ArrayLike,
    *,
    options: GrooveOptions | None = None,
    **changes: Any,
) -> LevelledFrame:
    """One frame levelled exactly as :func:`fit_grooves` levels it, with the shape it fits.

    For figures (the levelled profile under its section or template, paper 000 fig. 4) and for
    checking a fit. ``options`` and ``**changes`` as in :func:`fit_grooves`; ``z`` is one frame,
    shape (N,).

    Examples
    --------
    >>> lf = machscan.level_groove_frame(x, z[0], window=200)
    >>> lf.model, lf.fit.width[0]
    """
    options = groove_options(options, changes, "level_groove_frame")
    out = _core.view_groove_frame(x, z, options)
    fit = GrooveFits(**out["fit"], template=options.template)
    return LevelledFrame(x=out["x"], z=out["z"], shape_x=out["shape_x"], shape_z=out["shape_z"], tilt=out["tilt"], fit=fit)
