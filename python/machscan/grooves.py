"""Groove cross-sections (SPEC G, paper 000 §2.1): per-frame template fit as a result object.

Every default of the fit is defined once, in the Rust core (``GrooveOptions::default()``), and
read from there by the signatures below: :data:`DEFAULTS`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from enum import IntEnum
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core

__all__ = [
    "DEFAULTS",
    "FitCriteria",
    "GrooveFits",
    "GrooveStatus",
    "LevelledFrame",
    "Template",
    "fit_grooves",
    "level_groove_frame",
]

#: The defaults of every groove fit option, by name, as the core defines them.
DEFAULTS = _core.groove_defaults()

Template = Literal["tanh", "v"]


@dataclass(frozen=True)
class FitCriteria:
    """When the Levenberg–Marquardt fit of a frame stops (grouped as Open3D groups
    ``ICPConvergenceCriteria``): after ``max_iterations``, or when the step is below
    ``step_tolerance`` relative to the parameters, the gradient ``‖Jᵀf‖∞`` below
    ``gradient_tolerance``, or paper 000's cost test ``½ Σ f²/t < cost_tolerance`` (0 turns it
    off, the default: noisy frames never meet it, quiet ones would stop before converging).

    Examples
    --------
    >>> fits = machscan.fit_grooves(x, z, criteria=machscan.grooves.FitCriteria(max_iterations=50))
    """

    max_iterations: int = DEFAULTS["max_iterations"]
    step_tolerance: float = DEFAULTS["step_tolerance"]
    gradient_tolerance: float = DEFAULTS["gradient_tolerance"]
    cost_tolerance: float = DEFAULTS["cost_tolerance"]


class GrooveStatus(IntEnum):
    """What became of a frame (the codes in :attr:`GrooveFits.status`)."""

    CONVERGED = 0
    """The fit converged."""
    MAX_ITERATIONS = 1
    """The iteration limit was hit; the parameters are the best found."""
    NO_GROOVE = 2
    """No dip deeper than ``min_depth`` (and 5× the surface noise), or the fit left the window."""
    TOO_FEW_VALID = 3
    """Too few valid readings in the window."""
    TWO_GROOVES = 4
    """A second dip at least half as deep lies in the window: narrow the window."""
    CLIPPED = 5
    """The groove touches the window edge: no surface on one side."""
    FAILED = 6
    """The fit failed numerically, or ran away to a width outside ¼–4× the nominal width."""


@dataclass(frozen=True, eq=False, repr=False)
class GrooveFits:
    """Per-frame groove fits: every array has one entry per frame.

    Frames that could not be fitted hold NaN in the float arrays and say why in ``status``
    (:class:`GrooveStatus`); use ``ok`` to select the good ones.

    Attributes
    ----------
    x0, z0 : ndarray (F,)
        Groove center and surface height there, mm, in the coordinates of the x and z given.
    depth, width : ndarray (F,)
        Template depth d and width w, mm (w is the width at the surface for a V groove).
    alpha : ndarray (F,)
        Template shape coefficient used or fitted, mm⁻¹.
    rms : ndarray (F,)
        Residual RMS of the fit, mm.
    se_depth, se_width : ndarray (F,)
        Standard errors of depth and width from the fit covariance ``σ̂² (JᵀJ)⁻¹``, mm.
    tilt : ndarray (F,)
        Surface slope angle used for levelling, rad.
    iterations, n_used : ndarray of int32 (F,)
        LM iterations and readings used.
    status : ndarray of uint8 (F,)
    template : str
        The template fitted: ``"tanh"`` (paper 000) or ``"v"``.
    """

    x0: NDArray[np.float64]
    z0: NDArray[np.float64]
    depth: NDArray[np.float64]
    width: NDArray[np.float64]
    alpha: NDArray[np.float64]
    rms: NDArray[np.float64]
    se_depth: NDArray[np.float64]
    se_width: NDArray[np.float64]
    tilt: NDArray[np.float64]
    iterations: NDArray[np.int32]
    n_used: NDArray[np.int32]
    status: NDArray[np.uint8]
    template: str = "tanh"

    def __len__(self) -> int:
        return len(self.status)

    @property
    def ok(self) -> NDArray[np.bool_]:
        """Frames whose fit converged."""
        return self.status == GrooveStatus.CONVERGED

    def counts(self) -> dict[str, int]:
        """Number of frames per status."""
        return {s.name.lower(): int(np.count_nonzero(self.status == s)) for s in GrooveStatus}

    def select(self, index: ArrayLike) -> GrooveFits:
        """The fits of a subset of frames (boolean mask or indices)."""
        arrays = {f.name: getattr(self, f.name)[index] for f in fields(self) if f.name != "template"}
        return GrooveFits(**arrays, template=self.template)

    def summary(self) -> str:
        """Width and depth statistics over the converged frames, and the status counts."""
        ok = self.ok
        lines = [f"{len(self)} frames, {int(ok.sum())} fitted"]
        if ok.any():
            for name in ("width", "depth", "rms"):
                v = getattr(self, name)[ok]
                lines.append(f"  {name:>5}: {v.mean():.4f} ± {v.std():.4f} mm (min {v.min():.4f}, max {v.max():.4f})")
        bad = {k: v for k, v in self.counts().items() if v and k != "converged"}
        if bad:
            lines.append("  not fitted: " + ", ".join(f"{k} {v}" for k, v in bad.items()))
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"GrooveFits({len(self)} frames, {int(self.ok.sum())} converged)"


def fit_grooves(
    x: ArrayLike,
    z: ArrayLike,
    alpha: float = DEFAULTS["alpha"],
    nominal_width: float = DEFAULTS["nominal_width"],
    window: int | None = DEFAULTS["window"],
    *,
    template: Template = DEFAULTS["template"],
    window_center: int | None = DEFAULTS["window_center"],
    fit_alpha: bool = DEFAULTS["fit_alpha"],
    spike_threshold: float | None = DEFAULTS["spike_threshold"],
    min_depth: float = DEFAULTS["min_depth"],
    min_valid: int = DEFAULTS["min_valid"],
    criteria: FitCriteria | None = None,
) -> GrooveFits:
    """Fit the groove template of paper 000 to every profiler frame (SPEC G).

    Per frame: keep ``window`` readings around ``window_center``, drop invalid ones and spikes,
    fit a line, take the point deepest below it as the groove bottom, refit the surface line
    without the readings within ``nominal_width`` of the bottom, level the profile by the
    surface slope, then fit ``z = z0 + ½d(tanh(α(x − x0 − w/4)) − tanh(α(x − x0 + w/4)))`` by
    Levenberg–Marquardt with Nielsen damping and the analytic Jacobian. All frames run in
    parallel with the GIL released; the result does not depend on the thread count.

    Parameters
    ----------
    x : array_like, shape (N,)
        Abscissa of each reading along the laser line, mm (shared by all frames).
    z : array_like, shape (F, N)
        Readings (heights), mm; NaN marks an invalid reading.
    alpha : float
        Template shape coefficient, mm⁻¹: α of the tanh template (paper: 20), or the corner
        sharpness β of the V template.
    nominal_width : float
        Nominal groove width l, mm.
    window : int, optional
        Number t of readings kept around the center; default all.
    window_center : int, optional
        Reading index the window is centered on; default N // 2.
    fit_alpha : bool
        Fit the shape coefficient as a fifth parameter.
    template : {"tanh", "v"}
        ``"tanh"``: paper 000 eq (11), for rounded (laser-sintered, U-like) sections; on a
        straight-sided V it reads ~18 % too wide and too shallow. ``"v"``: straight flanks
        with corners rounded over ~1/alpha mm; for V grooves (use ``alpha`` ≈ 80 or
        ``fit_alpha=True``); ``depth`` is then the depth of the flanks' meeting point.
    spike_threshold : float or None
        Drop readings further than this from their 5-reading median, mm.
    min_depth : float
        Shallowest dip that counts as a groove, mm.
    min_valid : int
        Fewest valid readings in the window.
    criteria : FitCriteria, optional
        When the fit stops; default ``FitCriteria()``.

    Returns
    -------
    GrooveFits
        Per-frame ``x0, z0, depth, width, rms, status, se_depth, se_width, ...``.

    Examples
    --------
    >>> fits = machscan.fit_grooves(x, z, alpha=20.0, nominal_width=0.5, window=200)
    >>> fits.width[fits.ok].mean()
    """
    c = FitCriteria() if criteria is None else criteria
    if not isinstance(c, FitCriteria):
        raise ValueError(f"criteria: expected a machscan.grooves.FitCriteria, got {type(c).__name__}")
    out = _core.fit_grooves(
        x, z, template=template, alpha=alpha, nominal_width=nominal_width, window=window,
        window_center=window_center, fit_alpha=fit_alpha, spike_threshold=spike_threshold,
        min_depth=min_depth, min_valid=min_valid, max_iterations=c.max_iterations,
        cost_tolerance=c.cost_tolerance, step_tolerance=c.step_tolerance,
        gradient_tolerance=c.gradient_tolerance,
    )
    return GrooveFits(**out, template=template)


@dataclass(frozen=True, eq=False, repr=False)
class LevelledFrame:
    """One frame as the groove fit sees it (SPEC G steps 1–4).

    Attributes
    ----------
    x, z : ndarray (M,)
        Valid readings of the window after the spike filter, levelled:
        ``x' = cos θ·x + sin θ·z``, ``z' = −sin θ·x + cos θ·z``, mm.
    tilt : float
        θ, the surface slope angle, rad.
    start : ndarray (5,)
        Initial guess (x0, z0, d, w, α) in the levelled coordinates.
    status : GrooveStatus
        CONVERGED when the frame is ready for the fit; otherwise why it is not.
    """

    x: NDArray[np.float64]
    z: NDArray[np.float64]
    tilt: float
    start: NDArray[np.float64]
    status: GrooveStatus

    def to_frame(self, x0: float, z0: float) -> tuple[float, float]:
        """Map a levelled point back to the frame's own coordinates (inverse of eq 13)."""
        c, s = np.cos(self.tilt), np.sin(self.tilt)
        return c * x0 - s * z0, s * x0 + c * z0

    def __repr__(self) -> str:
        return f"LevelledFrame({len(self.x)} readings, tilt={self.tilt:.3g} rad, {self.status.name})"


def level_groove_frame(
    x: ArrayLike,
    z: ArrayLike,
    alpha: float = DEFAULTS["alpha"],
    nominal_width: float = DEFAULTS["nominal_width"],
    window: int | None = DEFAULTS["window"],
    *,
    window_center: int | None = DEFAULTS["window_center"],
    spike_threshold: float | None = DEFAULTS["spike_threshold"],
    min_depth: float = DEFAULTS["min_depth"],
    min_valid: int = DEFAULTS["min_valid"],
) -> LevelledFrame:
    """One frame levelled exactly as :func:`fit_grooves` does before its template fit.

    For plots (the levelled profile under its template, paper 000 fig. 4) and for checking the
    fit against another solver on the same data. Parameters as in :func:`fit_grooves`;
    ``z`` is one frame, shape (N,).

    Examples
    --------
    >>> lf = machscan.level_groove_frame(x, z[0], window=200)
    >>> lf.x.shape, lf.start
    """
    out = _core.level_groove_frame(
        x, z, alpha=alpha, nominal_width=nominal_width, window=window, window_center=window_center,
        spike_threshold=spike_threshold, min_depth=min_depth, min_valid=min_valid,
    )
    out["status"] = GrooveStatus(out["status"])
    return LevelledFrame(**out)
