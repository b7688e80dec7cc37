"""Registration (SPEC R; papers 003 and 004 §1): where a measured part really sits against its
model. :func:`icp` is the kernel the positioning and allowance workflows stand on; its
definitions and stop rule are Open3D's ``registration_icp``, so results carry over.

Each default is read from the core (:data:`ICP_DEFAULTS`), where it is written once.

The formulas and their papers: ``docs/registration.md``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan._core import ALLOWANCE_NEIGHBORS, coarse_align
from machscan._options import changed

__all__ = [
    "ALLOWANCE_NEIGHBORS",
    "ALLOWANCE_SURFACE",
    "ICP_DEFAULTS",
    "PROBE_KEEP",
    "PROBE_PATTERN",
    "PROBE_POINTS",
    "PROBE_RADIUS",
    "PROBE_SEED",
    "AlignmentStage",
    "BlankAlignment",
    "BlankSurface",
    "EnvelopeFit",
    "IcpCriteria",
    "IcpHistory",
    "IcpMethod",
    "IcpResult",
    "MeshFit",
    "PositioningErrors",
    "PositioningResult",
    "ProbePattern",
    "ProbeRound",
    "RobustKernel",
    "align_blank",
    "allowance",
    "coarse_align",
    "envelope_fit",
    "fit_to_mesh",
    "icp",
    "locating_points",
    "position_workpiece",
    "positioning_errors",
    "probe_plan",
    "probe_round",
]

#: How :func:`allowance` and :func:`envelope_fit` take the blank's surface: the stock field over
#: the model, the blank's own implicit quadric, or the paper's plane.
BlankSurface = Literal["stock", "quadric", "plane"]

#: The default: the stock field, which follows a blank round edges where the curvature jumps.
ALLOWANCE_SURFACE: BlankSurface = "stock"


def allowance(
    model_points: ArrayLike,
    model_normals: ArrayLike,
    blank_points: ArrayLike,
    *,
    surface: BlankSurface = ALLOWANCE_SURFACE,
    k: int | None = None,
    spacing: float | None = None,
) -> NDArray[np.float64]:
    """Machining allowance (SPEC R7; paper 004 §1.2): the stock the blank leaves over each model
    point, measured along the point's outward normal to the blank's surface there.

    The default ``surface="stock"`` measures where the blank was measured: each blank point's
    distance from the model (its foot found on the osculating circle of the model's normal
    section, curvatures from the model normals), then fits that stock field about each model point (a weighted quadratic
    over 1.5 blank spacings, ``docs/registration.md``). A point on the model normal's line has the
    model point for its foot, so the field there is the allowance; it stays smooth where model
    and blank both turn — round a blade's edge, where a fillet meets a flank — which no surface
    fitted to the blank points alone follows at a coarse spacing. Measured against exact offsets
    of twisted elliptic and circular-arc blades (BENCHMARKS.md, blank 0.2–1 mm apart, model
    sections 0.15 mm along them): within 5.9 µm at edges of radius 0.8–10 blank spacings, fillet
    joins included, 0.9 µm elsewhere. It needs the part's own normals (CAD), and it reads the model's
    shape between model points: a curvature jump between model points d apart costs up to
    Δκ·(d/2)²/2. So where the model is sampled more coarsely than the blank (a model point's
    fourth nearest neighbour farther than the blank's spacing), that point is measured on the
    blank's own quadric (below) instead. Sample the model finely where its curvature jumps: in
    sections 0.15 mm along them, or evenly (:meth:`machscan.cad.CadMesh.sample`,
    :func:`machscan.mesh.sample_surface`) at 0.15 mm or finer — Poisson-disk models
    0.16 mm apart held 4.9 µm where a 1.5 mm edge meets a flat at 1 mm blank spacing, 0.24 mm
    apart up to 10.8 µm, 0.4 mm apart 16.4 µm (five draws); with the model every 1 mm, fillet
    joins at 0.75–1 mm blank spacing are 13–19 µm off. ``machscan allowance`` samples a mesh
    model so.
    ``surface="quadric"`` fits an implicit quadric to the blank points alone about a centre on
    the line, Gaussian-weighted over 1.5 blank spacings, moved to where the line meets it (four
    fits): it holds circles and cylinders of any orientation, does not depend on the model's
    sampling, and is within 3 µm on smooth edges of radius ≥ 1.5 spacings, but 10–18 µm where a
    fillet meets a flank at 0.75–1 mm spacing. ``surface="plane"`` is the paper's least-squares
    plane of the ``k`` nearest blank points, ``t = n·(q0 − p) / (n·v)`` (eq 10 as SPEC R7
    corrects it), which sits below a curved blank by the mean sag of its points, κ·d²/2, and is
    0.1–0.6 mm wrong at such edges.

    Parameters
    ----------
    model_points : array_like, shape (N, 3)
        The finished part (CAD points), mm.
    model_normals : array_like, shape (N, 3)
        Their outward normals (normalised here; none may be zero).
    blank_points : array_like, shape (M, 3)
        The measured blank, in the model's frame (e.g. after :func:`machscan.align_blank`), mm.
    surface : {"stock", "quadric", "plane"}
        How the blank's surface is taken (above).
    k : int, optional
        The plane's blank points, 3 ≤ k ≤ M (default :data:`ALLOWANCE_NEIGHBORS`, 8). The stock
        field's and the quadric's neighbourhoods follow the spacing instead (giving ``k`` with
        them is refused).
    spacing : float, optional
        The blank's point spacing, mm; by default estimated from the blank (the median over its
        points of the radius holding eight neighbours, as an even grid's spacing). Give it for a
        scan of lines much farther apart than their points: about √(line gap × point spacing),
        or more.

    Returns
    -------
    ndarray, shape (N,)
        Signed allowance, mm: negative where the blank does not envelop the model; NaN where no
        stock is measured — the blank does not cover the point (beyond its end, over a hole), or
        its surface is inclined more than 60° to the model's normal plane there. Every consumer
        of an allowance (:func:`machscan.grinding_paths`, :func:`machscan.envelope_fit`,
        :func:`machscan.plot.allowance_map`, ``machscan grind``) leaves such points out and
        counts them.

    Examples
    --------
    >>> a = machscan.allowance(model, normals, blank)
    >>> short = a < 0  # where the part would come out short
    """
    return _core.allowance(model_points, model_normals, blank_points, surface=surface, k=k, spacing=spacing)


#: Defaults of :func:`icp`'s options, from ``IcpOptions::new`` in the core.
ICP_DEFAULTS = _core.icp_defaults()

#: What each iteration minimises.
IcpMethod = Literal["point_to_point", "point_to_plane"]
#: The robust loss of the residuals.
RobustKernel = Literal["huber", "tukey"]


@dataclass(frozen=True)
class IcpCriteria:
    """When :func:`icp` stops (Open3D's ``ICPConvergenceCriteria``, with paper 003's threshold):
    after ``max_iterations``, or when fitness and rmse changed by less than ``relative_fitness``
    and ``relative_rmse`` (absolute changes, as Open3D compares them; both 0 run exactly
    ``max_iterations``), or when the mean squared correspondence distance falls below
    ``mse_threshold``, mm² (paper 003 eq 10; None: not used). The defaults are the core's
    (:data:`ICP_DEFAULTS`).

    Examples
    --------
    >>> r = machscan.icp(src, tgt, 0.05, criteria=machscan.IcpCriteria(max_iterations=50))
    """

    max_iterations: int = ICP_DEFAULTS["max_iterations"]
    relative_fitness: float = ICP_DEFAULTS["relative_fitness"]
    relative_rmse: float = ICP_DEFAULTS["relative_rmse"]
    mse_threshold: float | None = ICP_DEFAULTS["mse_threshold"]


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
    criteria: IcpCriteria | None = None,
    robust: RobustKernel | None = ICP_DEFAULTS["robust"],
    robust_scale: float | None = None,
    trim: float = ICP_DEFAULTS["trim"],
    **changes: Any,
) -> IcpResult:
    """Iterative closest point (SPEC R2; paper 003 §3.2, paper 004 eq 1): the rigid transform
    that brings ``source`` onto ``target``.

    A correspondence is a source point's nearest target point closer than ``max_distance``.
    Each iteration estimates an update from the correspondences, applies it and finds them
    again, until ``criteria`` (:class:`IcpCriteria`) says it is done. Fitness and rmse are those
    of the returned transform.
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
    criteria : IcpCriteria, optional
        When it stops (default ``IcpCriteria()``).
    robust : {"huber", "tukey"}, optional
        Robust weights of the residuals (distance, or distance along the normal): Huber bounds
        the influence of outliers, Tukey removes gross ones.
    robust_scale : float, optional
        The kernel's threshold k, mm. Default: from the residuals of each iteration,
        ``1.345`` (Huber) or ``4.685`` (Tukey) × ``1.4826 · median |r|``.
    trim : float
        Share of the correspondences, the farthest, left out of each estimate (0 ≤ trim < 1).
    **changes
        Fields of :class:`IcpCriteria` changed for this call: ``icp(s, t, 0.05, max_iterations=50)``.

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
    c = changed(IcpCriteria() if criteria is None else criteria, changes, "icp")
    if not isinstance(c, IcpCriteria):
        raise ValueError(f"criteria: expected a machscan.IcpCriteria, got {type(c).__name__}")
    out = _core.icp(
        source,
        target,
        max_distance,
        init=init,
        target_normals=target_normals,
        method=method,
        max_iterations=c.max_iterations,
        relative_fitness=c.relative_fitness,
        relative_rmse=c.relative_rmse,
        robust=robust,
        robust_scale=robust_scale,
        trim=trim,
        mse_threshold=c.mse_threshold,
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


@dataclass(frozen=True, eq=False)
class MeshFit(IcpResult):
    """Result of :func:`fit_to_mesh`: the fields of :class:`IcpResult` (``rmse`` over the
    distances to the triangles), and the motions found.

    Attributes
    ----------
    motion : dict of str to float
        ``x``, ``y``, ``z`` (mm) and ``a``, ``b``, ``c`` (degrees) of the fit, after ``init``; exactly
        0 for every held motion.
    dof : str
        The free motions, in the machine's letters.
    undetermined : str
        Free motions the points do not fix (a flat face leaves its own shifts and turn, a
        cylinder its turn about its axis): held at 0 rather than left to drift.
    """

    motion: dict[str, float]
    dof: str
    undetermined: str


def fit_to_mesh(
    points: ArrayLike,
    vertices: ArrayLike,
    triangles: ArrayLike,
    max_distance: float,
    init: ArrayLike | None = None,
    *,
    dof: str = "xyzabc",
    axis: tuple[ArrayLike, ArrayLike] | None = None,
    criteria: IcpCriteria | None = None,
    **changes: Any,
) -> MeshFit:
    """The best fit of a scan to the CAD mesh itself, in the motions the set-up allows.

    Each iteration pairs every point with its closest point on the triangles (not on the mesh's
    vertices, which a CAD tessellation has few of) and minimises the squared distances to the
    paired triangles' planes (point to plane) by a Gauss–Newton step in the free motions alone.
    The pose is rebuilt from the six numbers every iteration,
    ``T = Shift(x, y, z) · Rz(c) Ry(b) Rx(a) (about the pivot) · init``, so a held motion is
    exactly zero — not the residue composed updates leave. Correspondences, fitness, rmse and
    the stop rule are :func:`icp`'s (Open3D's). The GIL is released; results do not depend on the
    thread count.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        The scan, mm.
    vertices, triangles : array_like, shape (V, 3), (M, 3)
        The CAD mesh, mm (e.g. :func:`machscan.io.read_cad`).
    max_distance : float
        Largest correspondence distance, mm.
    init : array_like, shape (4, 4), optional
        Start pose of the scan (default identity): the motions are found after it.
    dof : str
        The free motions in the machine's letters: ``x y z`` shifts, ``a b c`` rotations about
        lines parallel to X, Y, Z through the origin (default all six). ``"xyc"`` holds Z, A and B.
    axis : (point, direction), optional
        A rotary table: C turns about this line (and A, B about lines through its point, square
        to it) instead.
    criteria : IcpCriteria, optional
        When it stops (default ``IcpCriteria()``; ``mse_threshold`` is not used).
    **changes
        Fields of :class:`IcpCriteria` changed for this call.

    Returns
    -------
    MeshFit
        ``.transformation`` (scan → CAD), ``.fitness``, ``.rmse``, ``.converged``, ``.motion``,
        ``.undetermined``.

    Examples
    --------
    >>> fit = machscan.fit_to_mesh(scan, cad.vertices, cad.triangles, 1.0, dof="xyc",
    ...                            axis=((0, 0, 0), (0, 0, 1)))
    >>> fit.motion["c"]  # degrees the part sits turned on the table
    """
    c = changed(IcpCriteria() if criteria is None else criteria, changes, "fit_to_mesh")
    if not isinstance(c, IcpCriteria):
        raise ValueError(f"criteria: expected a machscan.IcpCriteria, got {type(c).__name__}")
    if not isinstance(dof, str):
        raise ValueError(f"dof: expected letters of x y z a b c, got {type(dof).__name__}")
    axis_point = axis_direction = None
    if axis is not None:
        if not isinstance(axis, tuple | list) or len(axis) != 2:
            raise ValueError("axis: expected (point, direction)")
        axis_point, axis_direction = axis
    out = _core.fit_to_mesh(
        points,
        vertices,
        triangles,
        max_distance,
        init=init,
        dof=dof,
        axis_point=axis_point,
        axis_direction=axis_direction,
        max_iterations=c.max_iterations,
        relative_fitness=c.relative_fitness,
        relative_rmse=c.relative_rmse,
    )
    m = out["motion"]
    motion = {"x": m[0], "y": m[1], "z": m[2], "a": np.degrees(m[3]), "b": np.degrees(m[4]), "c": np.degrees(m[5])}
    return MeshFit(
        transformation=out["transformation"],
        fitness=out["fitness"],
        rmse=out["rmse"],
        correspondences=out["correspondences"],
        iterations=out["iterations"],
        converged=out["converged"],
        history=IcpHistory(out["history_fitness"], out["history_rmse"]),
        motion={k: float(v) for k, v in motion.items()},
        dof="".join(ch for ch in "xyzabc" if ch in dof.lower()),
        undetermined=out["undetermined"],
    )


#: How :func:`locating_points` chooses from the flattest share.
ProbePattern = Literal["random", "optimal"]


def locating_points(
    points: ArrayLike,
    *,
    m: int = 160,
    keep: float = 0.25,
    k: int = 20,
    seed: int = 0,
    normals: ArrayLike | None = None,
    pattern: ProbePattern = "random",
) -> NDArray[np.int64]:
    """Probe points for locating a part (SPEC R4, paper 003 §2.2): ``m`` points from the
    flattest ``keep`` share of the surface, where locating is most accurate — drawn at random,
    reproducibly from ``seed`` (the paper: 160 of 20 000 points), or designed.

    The curvature is the U-direction line curvature for a gridded scan ``(nu, nv, 3)`` (the
    circle through each point and its two neighbors along the first axis: exactly 1/R on a
    radius R), and the surface variation λ0 / (λ0 + λ1 + λ2) over the ``k`` nearest points for
    a cloud ``(N, 3)``.

    ``pattern="optimal"`` (needs ``normals``) chooses instead the points that fix the part's
    pose best where the cutter feels it: the pose error that probe noise leaves, measured along
    the normals over the whole model, is smallest (an I-optimal design, chosen greedily and
    kept spread over the region). On the synthetic blade it halves that error against a random
    draw of as many points; ``seed`` then plays no part.

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
    normals : array_like, same shape as points, optional
        Outward normals; needed by ``pattern="optimal"``.
    pattern : {"random", "optimal"}

    Returns
    -------
    ndarray of int64, shape (m,)
        Indices into the points (into ``points.reshape(-1, 3)`` for a grid), ascending.

    Examples
    --------
    >>> idx = machscan.locating_points(model_points, m=160, seed=1)
    >>> probe = model_points[idx]
    """
    a = np.asarray(points, dtype=np.float64)
    if a.ndim == 3:
        return _core.locating_points_grid(a, m=m, keep=keep, seed=seed, normals=normals, pattern=pattern)
    return _core.locating_points_cloud(a, m=m, keep=keep, k=k, seed=seed, normals=normals, pattern=pattern)


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


def positioning_errors(measured: ArrayLike, model_points: ArrayLike, model_normals: ArrayLike | None = None) -> PositioningErrors:
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


#: The plant's probe cycle: ``measure(points, directions) -> measured``. ``points`` (N, 3) are
#: the commanded contact points in machine coordinates and ``directions`` (N, 3) the unit
#: approach directions (into the surface); it returns the (N, 3) probe readings (ball centres
#: at contact; NaN rows where the probe found no surface).
ProbeMeasure = Callable[[NDArray[np.float64], NDArray[np.float64]], ArrayLike]


@dataclass(frozen=True, eq=False)
class ProbeRound:
    """One probe round of :func:`position_workpiece`.

    Attributes
    ----------
    transformation : ndarray, shape (4, 4)
        The pose fitted to this round (model → machine).
    commanded, directions : ndarray, shape (n, 3)
        Where the probe was sent and along what, at the pose estimate before this round.
    measured : ndarray, shape (n, 3)
        What the probe returned (NaN rows: missed).
    surface : ndarray, shape (n, 3)
        The probed surface points in the model frame at ``transformation``, the probe ball
        compensated (NaN rows: missed).
    residuals : ndarray, shape (n,)
        Distance of each surface point from the tangent plane of its model point, mm.
    errors : PositioningErrors
        Per-axis errors of the surface points against the model (paper 003 eq 11–14).
    rms : float
        RMS of the residuals, mm (NaN when too few points were hit to fit).
    correction : float
        How far this round moved the probe points along their normals (RMS), mm: what the
        round changed.
    moved : ndarray, shape (n,)
        That move of each probe point, mm.
    """

    transformation: NDArray[np.float64]
    commanded: NDArray[np.float64]
    directions: NDArray[np.float64]
    measured: NDArray[np.float64]
    surface: NDArray[np.float64]
    residuals: NDArray[np.float64]
    errors: PositioningErrors
    rms: float
    correction: float
    moved: NDArray[np.float64]

    @property
    def hits(self) -> int:
        """Probe points that found the surface."""
        return int(np.isfinite(self.measured).all(axis=1).sum())


@dataclass(frozen=True, eq=False)
class PositioningResult:
    """Result of :func:`position_workpiece`.

    Attributes
    ----------
    transformation : ndarray, shape (4, 4)
        Model → machine: where the part sits (the last round's fit).
    rounds : tuple of ProbeRound
    indices : ndarray of int64
        The probe points, indices into the model points (flattened for a grid).
    converged : bool
        The last round changed the pose by no more than its own noise (or ``tolerance``): a
        further round would measure the same. False when the rounds ran out first, or when a
        round hit fewer than 6 points (that round's pose is then the one before).
    """

    transformation: NDArray[np.float64]
    rounds: tuple[ProbeRound, ...]
    indices: NDArray[np.int64]
    converged: bool

    @property
    def history(self) -> NDArray[np.float64]:
        """Residual RMS of each round, mm."""
        return np.array([r.rms for r in self.rounds])

    @property
    def errors(self) -> PositioningErrors:
        """Per-axis positioning errors of the last round."""
        return self.rounds[-1].errors

    def summary(self) -> str:
        """Per-axis errors per round, as paper 003's table 1 lists them (mm)."""
        head = f"{'round':>5} {'hits':>5} {'rms':>9} {'max|e_x|':>9} {'max|e_y|':>9} {'max|e_z|':>9}"
        rows = [head + f" {'e_total min-max':>17} {'correction':>10}"]
        for k, r in enumerate(self.rounds, 1):
            e = r.errors
            if len(e.e_total) == 0:
                rows.append(f"{k:5d} {r.hits:5d} {'-':>9}")
                continue
            axes = " ".join(f"{np.abs(a).max():9.4f}" for a in (e.e_x, e.e_y, e.e_z))
            span = f"{e.e_total.min():.4f}-{e.e_total.max():.4f}"
            rows.append(f"{k:5d} {r.hits:5d} {r.rms:9.4f} {axes} {span:>17} {r.correction:10.4f}")
        return "\n".join(rows)


#: A round whose correction is below this many times its noise (Σ d² against σ² of the fit)
#: changed nothing measurable: the 99 % point of χ² with 6 degrees of freedom, doubled because
#: both poses compared are noisy.
_NOISE_CHI2 = 2 * 16.81


#: Defaults of :func:`position_workpiece`, which its signature and ``machscan position`` read.
PROBE_POINTS = 160
PROBE_KEEP = 0.5
PROBE_PATTERN: ProbePattern = "optimal"
PROBE_SEED = 0
PROBE_RADIUS = 0.0


def position_workpiece(
    model_points: ArrayLike,
    model_normals: ArrayLike,
    measure: ProbeMeasure,
    *,
    n_points: int = PROBE_POINTS,
    seed: int = PROBE_SEED,
    max_rounds: int = 5,
    probe_radius: float = PROBE_RADIUS,
    init: ArrayLike | None = None,
    keep: float = PROBE_KEEP,
    pattern: ProbePattern = PROBE_PATTERN,
    tolerance: float = 1e-4,
) -> PositioningResult:
    """Where a clamped part really sits, by rounds of touch probing (SPEC R6; paper 003 §4).

    Each round sends the probe to ``n_points`` locating points of the model (SPEC R4, from the
    flattest ``keep`` share; by default those that fix the pose best, see
    :func:`locating_points`) at the current pose estimate,
    along their normals; ``measure`` runs the probe cycle and returns what it found; the pose is
    fitted so that each probed point lies on the tangent plane of its model point. The next
    round probes at the corrected pose, so the probe lands where it was sent and approaches
    along the true normals; the rounds stop when a round no longer changes the pose beyond its
    own noise (the paper converges in two), or after ``max_rounds``.

    Parameters
    ----------
    model_points : array_like, shape (N, 3) or (nu, nv, 3)
        The part's model (CAD points), mm; a grid uses line curvature to choose the points.
    model_normals : array_like, same shape
        Outward unit normals of the model points.
    measure : callable
        ``measure(points, directions) -> (n, 3)``: the probe cycle (see :data:`ProbeMeasure`),
        or a simulator such as :class:`machscan.synth.TouchProbe`.
    n_points : int
        Probe points per round (the paper: 160).
    seed : int
        Seed of the draw of the probe points (``pattern="random"``).
    max_rounds : int
    probe_radius : float
        Radius of the probe ball, mm, when ``measure`` returns ball centres (0: surface points).
        Compensated exactly: the centre lies on the surface offset by the radius.
    init : array_like, shape (4, 4), optional
        The nominal pose (model → machine) the first round probes at (default: identity).
    keep : float
        Share of the model, the flattest, the probe points are chosen from.
    pattern : {"optimal", "random"}
        Designed points (least pose error along the normals over the model) or the paper's
        random draw.
    tolerance : float
        A round that moves the probe points by less than this along their normals (RMS, mm)
        ends the rounds too (noise-free probes).

    Returns
    -------
    PositioningResult
        ``.transformation``, ``.history`` (residual RMS per round), ``.errors`` (last round),
        ``.rounds`` and ``summary()``.

    Examples
    --------
    >>> probe = machscan.synth.TouchProbe(blade, truth, noise=0.002)
    >>> r = machscan.position_workpiece(points, normals, probe, n_points=160)
    >>> print(r.summary())
    """
    grid, normals = _model(model_points, model_normals)
    if not callable(measure):
        raise TypeError(f"measure: expected a callable measure(points, directions), got {type(measure).__name__}")
    if max_rounds < 1:
        raise ValueError(f"max_rounds: must be at least 1, got {max_rounds}")
    if not (np.isfinite(probe_radius) and probe_radius >= 0):
        raise ValueError(f"probe_radius: must be ≥ 0 mm, got {probe_radius}")
    indices = locating_points(grid, m=n_points, keep=keep, seed=seed, normals=normals, pattern=pattern)
    pose = _pose(init, "init")
    points, normals = grid.reshape(-1, 3), normals.reshape(-1, 3)
    q, n = _targets(points, normals, indices)
    rounds: list[ProbeRound] = []
    converged = False
    for _ in range(max_rounds):
        commanded, directions = _commands(q, n, pose)
        measured = measure(commanded, directions)
        round_ = _fit_round(points, normals, q, n, pose, commanded, directions, measured, probe_radius)
        rounds.append(round_)
        if round_.hits < 6:
            break
        d2 = np.nansum(round_.moved**2)
        sigma2 = float(np.nansum(round_.residuals**2)) / max(round_.hits - 6, 1)
        pose = round_.transformation
        if round_.correction <= tolerance or d2 <= _NOISE_CHI2 * sigma2:
            converged = True
            break
    return PositioningResult(transformation=pose, rounds=tuple(rounds), indices=indices, converged=converged)


def probe_round(
    model_points: ArrayLike,
    model_normals: ArrayLike,
    indices: ArrayLike,
    pose: ArrayLike,
    measured: ArrayLike,
    *,
    probe_radius: float = 0.0,
) -> ProbeRound:
    """One round of :func:`position_workpiece` from probe readings taken elsewhere (a probe cycle
    run by the NC program): the model points ``indices`` were probed at ``pose``, along their
    normals, and ``measured`` came back. The fitted pose is ``.transformation``.

    Parameters
    ----------
    model_points, model_normals : array_like, shape (N, 3) or (nu, nv, 3)
    indices : array_like of int, shape (n,)
        The probed model points (into the flattened model).
    pose : array_like, shape (4, 4)
        The pose (model → machine) the probe points were commanded at.
    measured : array_like, shape (n, 3)
        The probe readings (NaN rows: missed).
    probe_radius : float
        Ball radius, mm, when the readings are ball centres.

    Returns
    -------
    ProbeRound
        With the pose unchanged and ``rms`` NaN when fewer than 6 points were hit.
    """
    grid, normals = _model(model_points, model_normals)
    points, normals = grid.reshape(-1, 3), normals.reshape(-1, 3)
    q, n = _targets(points, normals, indices)
    pose = _pose(pose, "pose")
    commanded, directions = _commands(q, n, pose)
    return _fit_round(points, normals, q, n, pose, commanded, directions, measured, probe_radius)


def probe_plan(
    model_points: ArrayLike, model_normals: ArrayLike, indices: ArrayLike, pose: ArrayLike | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Where to send the probe (the plan of one round of :func:`position_workpiece`): the model
    points ``indices`` at ``pose``, in machine coordinates, and the approach directions (minus
    their unit normals at that pose).

    Parameters
    ----------
    model_points, model_normals : array_like, shape (N, 3) or (nu, nv, 3)
    indices : array_like of int, shape (n,)
        The probe points (into the flattened model), e.g. from :func:`locating_points`.
    pose : array_like, shape (4, 4), optional
        Model → machine (default: identity), e.g. the last round's ``.transformation``.

    Returns
    -------
    points, directions : ndarray, shape (n, 3)
        Commanded contact points, mm, and unit approach directions.

    Examples
    --------
    >>> points, directions = machscan.registration.probe_plan(model, normals, idx, pose)
    """
    grid, normals = _model(model_points, model_normals)
    q, n = _targets(grid.reshape(-1, 3), normals.reshape(-1, 3), indices)
    return _commands(q, n, _pose(pose, "pose"))


def _model(model_points: ArrayLike, model_normals: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Model points and normals of one shape, (N, 3) or a grid (nu, nv, 3)."""
    points = np.asarray(model_points, dtype=np.float64)
    normals = np.asarray(model_normals, dtype=np.float64)
    if normals.shape != points.shape:
        raise ValueError(f"model_normals: expected the shape of model_points {points.shape}, got {normals.shape}")
    return points, normals


def _pose(value: ArrayLike | None, name: str) -> NDArray[np.float64]:
    """A 4×4 transform argument, the identity when omitted."""
    pose = np.eye(4) if value is None else np.array(value, dtype=np.float64)
    if pose.shape != (4, 4):
        raise ValueError(f"{name}: expected a 4×4 transform, got shape {pose.shape}")
    return pose


def _targets(points, normals, indices) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The probed model points and their unit normals (points and normals flattened)."""
    idx = np.asarray(indices, dtype=np.int64)
    if idx.ndim != 1 or (len(idx) and (idx.min() < 0 or idx.max() >= len(points))):
        raise ValueError(f"indices: expected indices into the {len(points)} model points")
    n = normals[idx]
    return points[idx], n / np.linalg.norm(n, axis=1, keepdims=True)


def _commands(q, n, pose) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The model points at the pose, and the approach along their normals."""
    return q @ pose[:3, :3].T + pose[:3, 3], -(n @ pose[:3, :3].T)


def _fit_round(points, normals, q, n, pose, commanded, directions, measured, probe_radius) -> ProbeRound:
    """Fits the pose to one round's readings (the core of :func:`probe_round`)."""
    measured = np.asarray(measured, dtype=np.float64)
    if measured.shape != commanded.shape:
        raise ValueError(f"measure: returned shape {measured.shape}, expected {commanded.shape} (one per point)")
    hit = np.isfinite(measured).all(axis=1)
    nan3 = np.full_like(commanded, np.nan)
    if hit.sum() < 6:
        empty = np.zeros(0)
        return ProbeRound(
            pose,
            commanded,
            directions,
            measured,
            nan3,
            np.full(len(q), np.nan),
            PositioningErrors(empty, empty, empty, empty),
            float("nan"),
            float("nan"),
            nan3[:, 0],
        )
    fit = _core.probe_fit(measured[hit], q[hit], n[hit], probe_radius=probe_radius, init=pose)
    new = fit["transformation"]
    inverse = np.linalg.inv(new)
    surface = nan3.copy()
    surface[hit] = measured[hit] @ inverse[:3, :3].T + inverse[:3, 3] - probe_radius * n[hit]
    residuals = np.full(len(q), np.nan)
    residuals[hit] = fit["residuals"]
    # How far the fitted pose moves each probe point along its normal: what the round changed.
    moved = np.einsum("ij,ij->i", (q @ new[:3, :3].T + new[:3, 3]) - commanded, n @ new[:3, :3].T)
    return ProbeRound(
        transformation=new,
        commanded=commanded,
        directions=directions,
        measured=measured,
        surface=surface,
        residuals=residuals,
        errors=positioning_errors(surface[hit], points, normals),
        rms=float(np.sqrt(np.mean(fit["residuals"] ** 2))),
        correction=float(np.sqrt(np.mean(moved**2))),
        moved=moved,
    )


@dataclass(frozen=True, eq=False)
class EnvelopeFit:
    """Result of :func:`envelope_fit`.

    Attributes
    ----------
    transformation : ndarray, shape (4, 4)
        Applied to the blank (blank → model frame).
    allowance : ndarray, shape (N,)
        Allowance of each model point at ``transformation``, mm (NaN where the blank does not
        cover the point). A point the blank covered at some pose of the fit and no longer does
        keeps counting, by the allowance its last measurement extrapolates to: the fit cannot
        escape the minimum by moving the blank off a point.
    feasible : bool
        Every allowance is ≥ ``min_allowance`` (to 1e-9 mm), those extrapolated included. When False, ``transformation``
        is the pose of the largest smallest allowance: the blank cannot hold the minimum.
    min_allowance : float
        The minimum asked for.
    iterations : int
    converged : bool
        The last step moved the blank by less than 1 nm.
    """

    transformation: NDArray[np.float64]
    allowance: NDArray[np.float64]
    feasible: bool
    min_allowance: float
    iterations: int
    converged: bool

    @classmethod
    def _of(cls, arrays: Mapping[str, Any], min_allowance: float) -> EnvelopeFit:
        """From the core's ``_EnvelopeFitArrays`` and the minimum asked for."""
        return cls(
            transformation=arrays["transformation"],
            allowance=arrays["allowance"],
            feasible=bool(arrays["feasible"]),
            min_allowance=float(min_allowance),
            iterations=int(arrays["iterations"]),
            converged=bool(arrays["converged"]),
        )

    def summary(self) -> str:
        """Allowance statistics: smallest, mean, largest, spread and points short of the minimum."""
        a = self.allowance[np.isfinite(self.allowance)]
        short = int(np.sum(a < self.min_allowance - 1e-9))
        state = "holds" if self.feasible else "does NOT hold"
        none = len(self.allowance) - len(a)
        return (
            f"allowance (mm): min {a.min():.4f}  mean {a.mean():.4f}  max {a.max():.4f}  "
            f"spread {a.max() - a.min():.4f}  std {a.std():.4f}\n"
            f"minimum {self.min_allowance:.4f} mm {state}: {short} of {len(a)} points below it"
            + (f"; {none} without stock measured (NaN: the blank does not cover them)" if none else "")
        )


def envelope_fit(
    model_points: ArrayLike,
    model_normals: ArrayLike,
    blank_points: ArrayLike,
    *,
    min_allowance: float = 0.0,
    surface: BlankSurface = ALLOWANCE_SURFACE,
    k: int | None = None,
    spacing: float | None = None,
    init: ArrayLike | None = None,
) -> EnvelopeFit:
    """Where to hold the blank so that it envelops the part (SPEC R8; paper 004, datum alignment
    and contour inclusion): every allowance ≥ ``min_allowance`` when that is feasible, and among
    those poses the most even allowance (least variance) — the balanced best fit. Where a plain
    best fit leaves negative stock somewhere, this finds the pose that does not, if there is
    one; where there is none, the pose of the largest smallest allowance (``feasible`` False).

    The allowance is :func:`allowance`'s (``surface``, ``k``, ``spacing`` as there). The fit is
    local: start it near the answer with ``init``, or use :func:`align_blank`, which finds the
    start from where the blank was clamped (coarse alignment, ICP) and then runs this fit.

    Parameters
    ----------
    model_points : array_like, shape (N, 3)
    model_normals : array_like, shape (N, 3)
        Outward normals.
    blank_points : array_like, shape (M, 3)
        The measured blank, mm.
    min_allowance : float
        The least stock to leave everywhere, mm.
    surface, k, spacing
        The blank's local surface, as in :func:`allowance`.
    init : array_like, shape (4, 4), optional
        Start pose of the blank (blank → model frame; default identity).

    Returns
    -------
    EnvelopeFit
        ``.transformation`` (applied to the blank), ``.allowance``, ``.feasible``, ``summary()``.

    Examples
    --------
    >>> fit = machscan.envelope_fit(model, normals, blank, min_allowance=0.1)
    >>> fit.feasible, fit.allowance.min()
    """
    out = _core.envelope_fit(
        model_points,
        model_normals,
        blank_points,
        min_allowance=min_allowance,
        surface=surface,
        k=k,
        spacing=spacing,
        init=init,
    )
    return EnvelopeFit._of(out, min_allowance)


@dataclass(frozen=True, eq=False)
class AlignmentStage:
    """One stage of :func:`align_blank`.

    Attributes
    ----------
    name : str
        ``"start"``, ``"coarse"``, ``"icp from the start"`` or ``"icp from the coarse pose"`` (the one kept),
        ``"envelope"``.
    transformation : ndarray, shape (4, 4)
        The blank's pose after the stage (blank → model frame).
    fitness, rmse : float
        How the blank's points sit on the model there: the share with a model point within the last ICP
        correspondence distance, and their RMS distance, mm (0 with none in reach: a stock wider than that distance,
        on a small part).
    allowance : ndarray, shape (N,)
        The allowance of every model point at that pose, mm (NaN: the blank does not cover it).
    """

    name: str
    transformation: NDArray[np.float64]
    fitness: float
    rmse: float
    allowance: NDArray[np.float64]

    def line(self, start: NDArray[np.float64]) -> str:
        """The stage in one line: how far it moved the blank from ``start``, its figures and the allowance."""
        rel = self.transformation @ np.linalg.inv(start)
        angle = np.degrees(np.arccos(np.clip((np.trace(rel[:3, :3]) - 1) / 2, -1.0, 1.0)))
        a = self.allowance[np.isfinite(self.allowance)]
        stock = (
            f"allowance min {a.min():+.4f} mean {a.mean():.4f} std {a.std():.4f} mm"
            if len(a)
            else "no allowance measured"
        )
        none = len(self.allowance) - len(a)
        # No blank point within the last ICP distance (a stock wider than it): there is no RMS distance to give.
        sits = f"fitness {self.fitness:.3f}  rmse {self.rmse:.4f} mm" if self.fitness > 0 else "fitness 0 (rmse: none in reach)"
        return (
            f"{self.name:<25} moved {np.linalg.norm(rel[:3, 3]):8.3f} mm {angle:7.3f}°  {sits}  "
            f"{stock}" + (f", {none} points without stock" if none else "")
        )


@dataclass(frozen=True, eq=False)
class BlankAlignment:
    """Result of :func:`align_blank`.

    Attributes
    ----------
    stages : tuple of AlignmentStage
        Start, coarse alignment, the ICP kept, the envelope fit.
    fit : EnvelopeFit
        The envelope fit that ends the chain (its ``transformation`` and ``allowance`` are the answer).
    """

    stages: tuple[AlignmentStage, ...]
    fit: EnvelopeFit

    @property
    def transformation(self) -> NDArray[np.float64]:
        """The blank's pose found (blank → model frame)."""
        return self.fit.transformation

    @property
    def allowance(self) -> NDArray[np.float64]:
        """The allowance at that pose, mm."""
        return self.fit.allowance

    @property
    def feasible(self) -> bool:
        """Every allowance is at least the minimum asked for."""
        return self.fit.feasible

    def summary(self) -> str:
        """Each stage's move from the start, figures and allowance; then the envelope fit's statistics."""
        start = self.stages[0].transformation
        return "\n".join([*(s.line(start) for s in self.stages), self.fit.summary()])


def align_blank(
    model_points: ArrayLike,
    model_normals: ArrayLike,
    blank_points: ArrayLike,
    *,
    min_allowance: float = 0.0,
    surface: BlankSurface = ALLOWANCE_SURFACE,
    k: int | None = None,
    spacing: float | None = None,
    init: ArrayLike | None = None,
) -> BlankAlignment:
    """Where the blank sits, from where a plant starts: coarse alignment, ICP, then the balanced envelope fit
    (SPEC R3, R2, R8; paper 004 §1). :func:`envelope_fit` alone is local and stalls when the blank is clamped
    millimetres and degrees off; this chain first brings the blank near by its points:

    1. ``start``: ``init`` (default identity: the blank as measured, in the model's frame);
    2. ``coarse``: the principal frames put on top of each other (:func:`coarse_align`);
    3. point-to-point ICP of the blank onto the model from both, the correspondence distance shrinking from 5 %
       of the model's size by thirds (three passes); the one pairing more blank points, then the closer, is kept;
    4. ``envelope``: :func:`envelope_fit` from there.

    Measured on whole blades, edges and ends included (the built-in airfoil and the elliptic blades of
    ``tests/analytic_blades.py``), with blanks misplaced by up to 5 mm / 5°: the allowance ends as even as the
    blank allows (BENCHMARKS.md).

    Parameters
    ----------
    model_points, model_normals : array_like, shape (N, 3)
        The finished part and its outward normals, mm.
    blank_points : array_like, shape (M, 3)
        The measured blank, mm, roughly in the model's frame (or anywhere, for the coarse alignment to find).
    min_allowance : float
        The least stock to leave everywhere, mm (see :func:`envelope_fit`).
    surface, k, spacing
        The blank's local surface, as in :func:`allowance`.
    init : array_like, shape (4, 4), optional
        The start pose (blank → model frame).

    Returns
    -------
    BlankAlignment
        ``.transformation``, ``.allowance``, ``.feasible``, ``.stages`` (each stage's pose and figures),
        ``.fit`` and ``summary()``.

    Examples
    --------
    >>> found = machscan.align_blank(model, normals, blank, min_allowance=0.1)
    >>> print(found.summary())
    >>> blank_in_model = blank @ found.transformation[:3, :3].T + found.transformation[:3, 3]
    """
    out = _core.align_blank(
        model_points,
        model_normals,
        blank_points,
        min_allowance=min_allowance,
        surface=surface,
        k=k,
        spacing=spacing,
        init=init,
    )
    fit = EnvelopeFit._of(out["fit"], min_allowance)
    return BlankAlignment(stages=tuple(AlignmentStage(**s) for s in out["stages"]), fit=fit)
