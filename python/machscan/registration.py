"""Registration (SPEC R; papers 003 and 004 §1): where a measured part really sits against its
model. :func:`icp` is the kernel the positioning and allowance workflows stand on; its
definitions and stop rule are Open3D's ``registration_icp``, so results carry over.

Each default is read from the core (:data:`ICP_DEFAULTS`), where it is written once.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan._core import allowance, coarse_align

__all__ = [
    "ICP_DEFAULTS",
    "IcpHistory",
    "IcpMethod",
    "IcpResult",
    "PositioningErrors",
    "RobustKernel",
    "allowance",
    "coarse_align",
    "icp",
    "locating_points",
    "positioning_errors",
]

#: Defaults of :func:`icp`'s options, from ``IcpOptions::new`` in the core.
ICP_DEFAULTS = _core.icp_defaults()

#: What each iteration minimises.
IcpMethod = Literal["point_to_point", "point_to_plane"]
#: The robust loss of the residuals.
RobustKernel = Literal["huber", "tukey"]


@dataclass(frozen=True, eq=False)
class IcpHistory:
    """Fitness and rmse after each iteration (at the transform that iteration reached)."""

    fitness: NDArray[np.float64]
    rmse: NDArray[np.float64]

    def __len__(self) -> int:
        return len(self.fitness)


@dataclass(frozen=True, eq=False)
class IcpResult:
    """Result of :func:`icp`.

    Attributes
    ----------
    transformation : ndarray, shape (4, 4)
        The rigid transform applied to the source (``init`` included): ``target ≈ T · source``.
    fitness : float
        Correspondences / source points, at ``transformation`` (Open3D's fitness).
    rmse : float
        RMS distance of the correspondences at ``transformation``, mm (Open3D's
        ``inlier_rmse``); 0 when there is none.
    correspondences : int
        Source points with a target point closer than ``max_distance`` at ``transformation``.
    iterations : int
    converged : bool
        A stop test held: fitness and rmse changed by less than their thresholds, or the mean
        squared distance fell below ``mse_threshold``. False when the iterations ran out first
        or no correspondence was in reach.
    history : IcpHistory
        Fitness and rmse after each iteration.
    """

    transformation: NDArray[np.float64]
    fitness: float
    rmse: float
    correspondences: int
    iterations: int
    converged: bool
    history: IcpHistory


def icp(
    source: ArrayLike,
    target: ArrayLike,
    max_distance: float,
    init: ArrayLike | None = None,
    *,
    method: IcpMethod = ICP_DEFAULTS["method"],
    target_normals: ArrayLike | None = None,
    max_iterations: int = ICP_DEFAULTS["max_iterations"],
    relative_fitness: float = ICP_DEFAULTS["relative_fitness"],
    relative_rmse: float = ICP_DEFAULTS["relative_rmse"],
    robust: RobustKernel | None = ICP_DEFAULTS["robust"],
    robust_scale: float | None = None,
    trim: float = ICP_DEFAULTS["trim"],
    mse_threshold: float | None = ICP_DEFAULTS["mse_threshold"],
) -> IcpResult:
    """Iterative closest point (SPEC R2; paper 003 §3.2, paper 004 eq 1): the rigid transform
    that brings ``source`` onto ``target``.

    A correspondence is a source point's nearest target point closer than ``max_distance``.
    Each iteration estimates an update from the correspondences, applies it and finds them
    again. It stops after ``max_iterations``, or when fitness and rmse changed by less than
    ``relative_fitness`` and ``relative_rmse`` (absolute changes, as Open3D compares them; set
    both to 0 to run exactly ``max_iterations``), or when the mean squared distance is below
    ``mse_threshold`` (paper 003 eq 10). Fitness and rmse are those of the returned transform.
    Results do not depend on the thread count; the GIL is released while it runs.

    Parameters
    ----------
    source, target : array_like, shape (N, 3), (M, 3)
        mm.
    max_distance : float
        Largest correspondence distance, mm.
    init : array_like, shape (4, 4), optional
        Start transform of the source (default: identity), e.g. from a coarse alignment.
    method : {"point_to_point", "point_to_plane"}
        Point to point: Kabsch/Umeyama in closed form (reflection guard). Point to plane: the
        distances along the target normals, linearised in the rotation (Open3D's convention
        ``Rz(γ) Ry(β) Rx(α)``); converges in fewer iterations on smooth parts.
    target_normals : array_like, shape (M, 3), optional
        For point to plane; estimated from the 20 nearest target points when omitted.
    max_iterations : int
    relative_fitness, relative_rmse : float
        Stop thresholds (Open3D's ``ICPConvergenceCriteria``).
    robust : {"huber", "tukey"}, optional
        Robust weights of the residuals (distance, or distance along the normal): Huber bounds
        the influence of outliers, Tukey removes gross ones.
    robust_scale : float, optional
        The kernel's threshold k, mm. Default: from the residuals of each iteration,
        ``1.345`` (Huber) or ``4.685`` (Tukey) × ``1.4826 · median |r|``.
    trim : float
        Share of the correspondences, the farthest, left out of each estimate (0 ≤ trim < 1).
    mse_threshold : float, optional
        Stop when the mean squared correspondence distance is below this, mm².

    Returns
    -------
    IcpResult
        ``.transformation``, ``.fitness``, ``.rmse``, ``.iterations``, ``.converged``,
        ``.history``.

    Examples
    --------
    >>> r = machscan.icp(measured, model, max_distance=1.0, method="point_to_plane")
    >>> aligned = measured @ r.transformation[:3, :3].T + r.transformation[:3, 3]
    """
    out = _core.icp(
        source,
        target,
        max_distance,
        init=init,
        target_normals=target_normals,
        method=method,
        max_iterations=max_iterations,
        relative_fitness=relative_fitness,
        relative_rmse=relative_rmse,
        robust=robust,
        robust_scale=robust_scale,
        trim=trim,
        mse_threshold=mse_threshold,
    )
    history = IcpHistory(out["history_fitness"], out["history_rmse"])
    return IcpResult(
        transformation=out["transformation"],
        fitness=out["fitness"],
        rmse=out["rmse"],
        correspondences=out["correspondences"],
        iterations=out["iterations"],
        converged=out["converged"],
        history=history,
    )


def locating_points(
    points: ArrayLike, m: int = 160, *, keep: float = 0.25, k: int = 20, seed: int = 0
) -> NDArray[np.int64]:
    """Probe points for locating a part (SPEC R4, paper 003 §2.2): ``m`` points drawn at
    random, reproducibly from ``seed``, from the flattest ``keep`` share of the surface, where
    locating is most accurate (the paper: 160 of 20 000 points).

    The curvature is the U-direction line curvature for a gridded scan ``(nu, nv, 3)`` (the
    circle through each point and its two neighbors along the first axis: exactly 1/R on a
    radius R), and the surface variation λ0 / (λ0 + λ1 + λ2) over the ``k`` nearest points for
    a cloud ``(N, 3)``.

    Parameters
    ----------
    points : array_like, shape (N, 3) or (nu, nv, 3)
        mm.
    m : int
        Points to draw.
    keep : float
        Share of the points, the flattest, drawn from (0 < keep ≤ 1).
    k : int
        Neighbors of the surface variation (clouds only).
    seed : int
        The same seed draws the same points on every platform.

    Returns
    -------
    ndarray of int64, shape (m,)
        Indices into the points (into ``points.reshape(-1, 3)`` for a grid), ascending.

    Examples
    --------
    >>> idx = machscan.locating_points(model_points, 160, seed=1)
    >>> probe = model_points[idx]
    """
    a = np.asarray(points, dtype=np.float64)
    if a.ndim == 3:
        return _core.locating_points_grid(a, m=m, keep=keep, seed=seed)
    return _core.locating_points_cloud(a, m=m, keep=keep, k=k, seed=seed)


@dataclass(frozen=True, eq=False)
class PositioningErrors:
    """Per-axis positioning errors of measured points against the model (paper 003 eq 11–14),
    mm: ``e_x = x_p − x_q``, ``e_y``, ``e_z`` and ``e_total = √(e_x² + e_y² + e_z²)``."""

    e_x: NDArray[np.float64]
    e_y: NDArray[np.float64]
    e_z: NDArray[np.float64]
    e_total: NDArray[np.float64]

    def summary(self) -> str:
        """Mean and largest |error| per axis, as the paper's table 1 lists them."""
        rows = [f"{'':8} {'mean |e|':>10} {'max |e|':>10}"]
        for name, e in (("e_x", self.e_x), ("e_y", self.e_y), ("e_z", self.e_z), ("e_total", self.e_total)):
            a = np.abs(e)
            rows.append(f"{name:8} {a.mean():10.4f} {a.max():10.4f}" if len(a) else f"{name:8} {'-':>10} {'-':>10}")
        return "\n".join(rows)


def positioning_errors(
    measured: ArrayLike, model_points: ArrayLike, model_normals: ArrayLike | None = None
) -> PositioningErrors:
    """Positioning errors of measured points against the model (SPEC R5; paper 003 eq 11–14).

    The reference of each measured point p is the closest model point q; with
    ``model_normals`` it is the closest point of the model surface, the tangent plane at q
    (``e = ((p − q)·n) n``), so that the spacing of the model points does not count as error.

    Parameters
    ----------
    measured : array_like, shape (N, 3)
        mm, in the model's frame.
    model_points : array_like, shape (M, 3)
    model_normals : array_like, shape (M, 3), optional

    Returns
    -------
    PositioningErrors
        ``.e_x``, ``.e_y``, ``.e_z``, ``.e_total`` and ``summary()``.

    Examples
    --------
    >>> err = machscan.positioning_errors(probed, model, model_normals)
    >>> print(err.summary())
    """
    e = _core.positioning_errors(measured, model_points, model_normals=model_normals)
    return PositioningErrors(e[:, 0], e[:, 1], e[:, 2], np.linalg.norm(e, axis=1))
