"""A synthetic turbine blade and a touch-probe simulator with exact ground truth (paper 003 §4).

Paper 003 positions a turbine blade on a five-axis machine: a touch probe measures ~160 points on the
flattest regions of the blade, the points are registered to the CAD model, and the probing is repeated at
the corrected pose. The paper models the outer contour of the blade with cubic Bézier curves. This module
provides the three pieces needed to test such a positioning loop to the µm:

* :class:`Blade`: an analytic airfoil surface (cubic Bézier sections lofted along the span) with exact
  points and unit outward normals at any ``(u, v)``;
* :class:`TouchProbe`: where a ball probe moving along a commanded line really touches the part when the
  part sits at a pose the controller does not know;
* :func:`misplacement`: the random rigid "0.5 mm / 0.5°" error of a freshly clamped part.

All lengths are in mm, angles in rad. The module is pure NumPy (it does not use the compiled core), so its
truth is independent of the code it tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Blade", "TouchProbe", "misplacement"]


@dataclass(frozen=True)
class Blade:
    """An airfoil blade surface (no end caps), analytic in ``(u, v)``.

    Every section is a closed curve of four cubic Bézier segments in chord units: leading edge → suction
    side crest → trailing edge → pressure side crest → leading edge. The leading edge sits at the origin of
    the chord line and the trailing edge at ``(1, 0)``, both with a tangent perpendicular to the chord; the
    two crests lie ``± thickness / 2`` off a parabolic camber line ``4·camber·x·(1 − x)`` at ``x = crest``,
    with a tangent parallel to it. Control points on both sides of each joint are collinear (G1), so the
    normals are continuous around the section; the edge handles are sized so that both sides of each edge
    have the osculating radius ``le_radius`` (``te_radius``) there, so the curvature is continuous across
    the two edges too. The pressure side is concave, as on a real turbine blade.

    The sections are lofted along the span: at ``v`` (0 at the root, 1 at the tip) the section is scaled by
    the chord ``chord_root + (chord_tip − chord_root)·v``, rotated about the stacking point (at ``stack``
    of the chord, on the chord line) by the stagger angle ``stagger + twist·v``, shifted by the bowed
    stacking line ``(sweep·v², lean·v²)`` and placed at ``z = span·v``. The model frame: x axial, y
    tangential, z radial (along the span), origin at the root stacking point.

    Parameters
    ----------
    span : float
        Radial height of the blade, mm.
    chord_root, chord_tip : float
        Chord length at the root and at the tip, mm (linear taper).
    thickness : float
        Section thickness at the crest, across the camber line, as a fraction of the chord (close to the
        maximum thickness).
    camber : float
        Maximum camber of the parabolic camber line, as a fraction of the chord.
    crest : float
        Chord fraction of the two crest joints (where the section is thickest).
    le_radius, te_radius : float
        Osculating radius at the leading and trailing edges, as a fraction of the chord.
    stagger : float
        Angle of the chord to the x axis at the root, rad.
    twist : float
        Change of the stagger angle from root to tip, rad.
    stack : float
        Chord fraction of the stacking point, the center of the stagger rotation.
    sweep, lean : float
        Axial (x) and tangential (y) offset of the stacking line at the tip, mm; the stacking line is the
        parabola ``(sweep·v², lean·v², span·v)``, tangent to z at the root.

    Examples
    --------
    >>> blade = Blade()
    >>> points, normals = blade.surface([0.1, 0.6], 0.5)
    >>> points.shape, normals.shape
    ((2, 3), (2, 3))
    >>> bool(np.allclose(np.linalg.norm(normals, axis=-1), 1.0))
    True
    >>> blade.sample(200, 100)[0].shape
    (200, 100, 3)
    """

    span: float = 150.0
    chord_root: float = 120.0
    chord_tip: float = 90.0
    thickness: float = 0.11
    camber: float = 0.08
    crest: float = 0.35
    le_radius: float = 0.03
    te_radius: float = 0.006
    stagger: float = 0.5
    twist: float = 0.3
    stack: float = 0.4
    sweep: float = 3.0
    lean: float = 4.0

    def __post_init__(self) -> None:
        for name in ("span", "chord_root", "chord_tip", "thickness", "le_radius", "te_radius"):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name}: expected > 0, got {getattr(self, name)!r}")
        if not 0.1 <= self.crest <= 0.7:
            raise ValueError(f"crest: expected in [0.1, 0.7], got {self.crest!r}")
        if not 0.0 < self.thickness < 0.4 or not abs(self.camber) < 0.2:
            raise ValueError("thickness and camber: expected 0 < thickness < 0.4 and |camber| < 0.2")

    def control_points(self) -> np.ndarray:
        """The section's Bézier control points in chord units, shape ``(4 segments, 4 points, 2)``.

        Leading edge at ``(0, 0)``, trailing edge at ``(1, 0)``; the stacking point is not subtracted.
        Segment ``k`` covers ``u`` in ``[k/4, (k+1)/4)``.
        """
        x = self.crest
        yc = 4.0 * self.camber * x * (1.0 - x)
        slope = 4.0 * self.camber * (1.0 - 2.0 * x)
        tangent = np.array([1.0, slope]) / math.hypot(1.0, slope)
        across = np.array([-tangent[1], tangent[0]])  # unit normal of the camber line, toward the suction side
        half = 0.5 * self.thickness
        crest_s = np.array([x, yc]) + half * across
        crest_p = np.array([x, yc]) - half * across
        le, te = np.array([0.0, 0.0]), np.array([1.0, 0.0])
        # Crest handles: about a third of the way to each edge, so the sections stay free of loops.
        to_le, to_te = 0.5 * x, 0.4 * (1.0 - x)
        inner = {side: (c - to_le * tangent, c + to_te * tangent) for side, c in (("s", crest_s), ("p", crest_p))}

        # Edge handles along the edge tangent (perpendicular to the chord). At the end of a cubic with a
        # handle of length a and the next control point at distance b off the tangent line, the radius of
        # curvature is 1.5·a²/b: choose a to get the requested edge radius on each side.
        def handle(radius: float, offset: float) -> float:
            return math.sqrt(radius * abs(offset) / 1.5)

        a_s = handle(self.le_radius, inner["s"][0][0])
        a_p = handle(self.le_radius, inner["p"][0][0])
        e_s = handle(self.te_radius, 1.0 - inner["s"][1][0])
        e_p = handle(self.te_radius, 1.0 - inner["p"][1][0])
        up = np.array([0.0, 1.0])
        return np.array(
            [
                [le, le + a_s * up, inner["s"][0], crest_s],  # leading edge → suction crest
                [crest_s, inner["s"][1], te + e_s * up, te],  # suction crest → trailing edge
                [te, te - e_p * up, inner["p"][1], crest_p],  # trailing edge → pressure crest
                [crest_p, inner["p"][0], le - a_p * up, le],  # pressure crest → leading edge
            ]
        )

    def _frame(self, u: Any, v: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Points ``S`` and the exact partial derivatives ``S_u``, ``S_v``, each of shape ``(*broadcast, 3)``."""
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        u = np.mod(u, 1.0)
        # np.mod can round a tiny negative u up to exactly 1.0: the clip sends it to the end of the last
        # segment, which is the leading edge, the same point as u = 0.
        k = np.clip(np.floor(4.0 * u).astype(np.intp), 0, 3)
        s = (4.0 * u - k)[..., None]
        p0, p1, p2, p3 = np.moveaxis(self.control_points()[k], -2, 0)
        r = 1.0 - s
        q = r**3 * p0 + 3.0 * r**2 * s * p1 + 3.0 * r * s**2 * p2 + s**3 * p3
        # d/du = 4 d/ds: each segment covers a quarter of u.
        dq = 12.0 * (r**2 * (p1 - p0) + 2.0 * r * s * (p2 - p1) + s**2 * (p3 - p2))
        qx, qy = q[..., 0] - self.stack, q[..., 1]
        dqx, dqy = dq[..., 0], dq[..., 1]

        chord = self.chord_root + (self.chord_tip - self.chord_root) * v
        dchord = self.chord_tip - self.chord_root
        angle = self.stagger + self.twist * v
        cos, sin = np.cos(angle), np.sin(angle)
        rx, ry = cos * qx - sin * qy, sin * qx + cos * qy  # R(angle)·q
        # d/dangle R(angle)·q = R(angle + π/2)·q = (−ry, rx)
        point = np.stack([chord * rx + self.sweep * v**2, chord * ry + self.lean * v**2, self.span * v], axis=-1)
        s_u = np.stack([chord * (cos * dqx - sin * dqy), chord * (sin * dqx + cos * dqy), np.zeros_like(v)], axis=-1)
        s_v = np.stack(
            [
                dchord * rx - chord * self.twist * ry + 2.0 * self.sweep * v,
                dchord * ry + chord * self.twist * rx + 2.0 * self.lean * v,
                np.full_like(v, self.span),
            ],
            axis=-1,
        )
        return point, s_u, s_v

    def surface(self, u: Any, v: Any) -> tuple[np.ndarray, np.ndarray]:
        """Points and unit outward normals at the parameters ``(u, v)``.

        Parameters
        ----------
        u : array_like
            Position around the section, periodic with period 1 (wrapped into ``[0, 1)``): ``u = 0`` is the
            leading edge, ``1/4`` the suction crest, ``1/2`` the trailing edge, ``3/4`` the pressure crest.
        v : array_like
            Position along the span, 0 at the root and 1 at the tip; values outside ``[0, 1]`` extrapolate
            the loft smoothly (there is no end cap). Broadcast against ``u``.

        Returns
        -------
        points : ndarray, shape ``(*broadcast, 3)``
            Points of the surface in the model frame, mm.
        normals : ndarray, shape ``(*broadcast, 3)``
            Unit outward normals, the normalised ``S_v × S_u`` (the sections run clockwise seen from the
            tip, so this is ``S_u × S_v`` turned outward), from the analytic derivatives.

        Examples
        --------
        >>> points, normals = Blade().surface(np.linspace(0, 1, 5, endpoint=False), 0.0)
        >>> bool(np.allclose(points[0], [-0.4 * 120 * np.cos(0.5), -0.4 * 120 * np.sin(0.5), 0]))  # leading edge
        True
        """
        point, s_u, s_v = self._frame(u, v)
        normal = np.cross(s_v, s_u)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        return point, normal

    def sample(self, nu: int, nv: int) -> tuple[np.ndarray, np.ndarray]:
        """A model grid: :meth:`surface` at ``u = arange(nu) / nu`` and ``v = linspace(0, 1, nv)``.

        Returns
        -------
        points, normals : ndarray, shape ``(nu, nv, 3)``

        Examples
        --------
        >>> points, normals = Blade().sample(200, 100)
        >>> points.shape
        (200, 100, 3)
        """
        u = np.arange(nu) / nu
        v = np.linspace(0.0, 1.0, nv)
        return self.surface(u[:, None], v[None, :])


def _rigid(pose: Any) -> np.ndarray:
    pose = np.array(pose, dtype=float)
    if pose.shape != (4, 4):
        raise ValueError(f"pose: expected a (4, 4) matrix, got shape {pose.shape}")
    rot = pose[:3, :3]
    if (
        not np.allclose(rot.T @ rot, np.eye(3), atol=1e-9)
        or np.linalg.det(rot) <= 0.0
        or not np.allclose(pose[3], [0.0, 0.0, 0.0, 1.0])
    ):
        raise ValueError("pose: expected a rigid transform (rotation with det +1, last row 0 0 0 1)")
    pose.flags.writeable = False
    return pose


class TouchProbe:
    """A touch probe that measures a part sitting at a pose the controller does not know.

    A probing cycle moves the ball center along the line ``c(t) = p + t·d`` through the commanded point
    ``p`` in the approach direction ``d`` (a real cycle starts at ``p − clearance·d``) and stops at the
    first contact: where the ball of radius ``radius`` touches the true part, i.e. where ``c(t)`` meets the
    true surface offset outward by ``radius``, ``pose · (S + radius·N)``. It reports the ball center there,
    plus trigger noise along the approach direction.

    Parameters
    ----------
    part : Blade or similar
        Anything with ``surface(u, v) -> (points, normals)`` (unit outward normals, ``u`` periodic with
        period 1, ``v`` in ``[0, 1]``) and ``sample(nu, nv)`` on the grid ``u = arange(nu) / nu``,
        ``v = linspace(0, 1, nv)``, like :class:`Blade`.
    pose : array_like, shape (4, 4), optional
        Rigid transform model → machine: where the part truly sits. Default: the identity.
    radius : float
        Ball radius, mm. With 0 the probe returns points of the surface.
    noise : float
        Standard deviation of the Gaussian trigger noise along the approach direction, mm.
    seed : int
        Seed of the noise generator: repeated calls draw new noise, but the sequence is reproducible.
    travel : float
        How far before and beyond the commanded point the probe searches for contact, mm.
    grid : (int, int)
        ``(nu, nv)`` of the sample of the part that seeds the contact search. Its spacing should stay well
        below the part's curvature radii and its thickness.

    Attributes
    ----------
    part, pose, radius, noise, travel
        As given (``pose`` as a read-only float array).

    Examples
    --------
    >>> blade = Blade()
    >>> pose = misplacement(seed=1)
    >>> probe = TouchProbe(blade, pose)
    >>> model, normals = blade.surface([0.2, 0.3, 0.7], 0.5)
    >>> machine = model @ pose[:3, :3].T + pose[:3, 3]  # where the commanded points truly are
    >>> measured = probe(machine, -normals @ pose[:3, :3].T)
    >>> bool(np.allclose(measured, machine, atol=1e-9))
    True
    """

    def __init__(
        self,
        part: Any,
        pose: Any = None,
        *,
        radius: float = 0.0,
        noise: float = 0.0,
        seed: int = 0,
        travel: float = 5.0,
        grid: tuple[int, int] = (400, 200),
    ) -> None:
        if radius < 0.0 or noise < 0.0 or not travel > 0.0:
            raise ValueError("radius and noise: expected >= 0; travel: expected > 0")
        self.part = part
        self.pose = _rigid(np.eye(4) if pose is None else pose)
        self.radius = float(radius)
        self.noise = float(noise)
        self.travel = float(travel)
        self._rng = np.random.default_rng(seed)
        nu, nv = grid
        if nu < 4 or nv < 2:
            raise ValueError(f"grid: expected nu >= 4 and nv >= 2, got {grid!r}")
        points, normals = part.sample(nu, nv)
        self._grid = points + self.radius * normals  # the offset surface the ball center meets, (nu, nv, 3)
        self._grid_normals = normals
        self._grid_shape = (nu, nv)
        # A coarse subgrid (about 64 x 32) for the brute-force stage of the seed search; its spacing is
        # the tolerance of that stage, and a window of one coarse step around its pick is refined on the grid.
        self._stride = (max(1, nu // 64), max(1, nv // 32))
        iu = np.arange(0, nu, self._stride[0])
        iv = np.unique(np.r_[np.arange(0, nv, self._stride[1]), nv - 1])
        coarse = self._grid[np.ix_(iu, iv)]
        du = np.linalg.norm(np.roll(coarse, -1, axis=0) - coarse, axis=-1).max()
        dv = np.linalg.norm(np.diff(coarse, axis=1), axis=-1).max()
        self._coarse_spacing = float(max(du, dv))
        self._coarse_index = np.stack(np.meshgrid(iu, iv, indexing="ij"), axis=-1).reshape(-1, 2)
        self._coarse = coarse.reshape(-1, 3)
        self._coarse_normals = self._grid_normals[np.ix_(iu, iv)].reshape(-1, 3)
        self._coarse_sq = np.einsum("ij,ij->i", self._coarse, self._coarse)

    def __call__(self, points: Any, directions: Any) -> np.ndarray:
        """Probe along the lines ``points + t·directions``, ``|t| <= travel``.

        Parameters
        ----------
        points : array_like, shape (N, 3)
            Commanded contact points in machine coordinates, mm.
        directions : array_like, shape (N, 3)
            Approach directions, pointing into the surface (minus the outward normal at the estimated
            pose); normalised here.

        Returns
        -------
        ndarray, shape (N, 3)
            Ball centers at contact plus noise ``ε·d``, ``ε ~ N(0, noise)``, in machine coordinates; NaN
            rows where the line does not enter the part within ``± travel`` (or enters it only outside the
            span ``v ∈ [0, 1]``).
        """
        p = np.array(points, dtype=float)
        d = np.array(directions, dtype=float)
        if p.ndim != 2 or p.shape[1] != 3 or d.shape != p.shape:
            raise ValueError(f"points and directions: expected two (N, 3) arrays, got {p.shape} and {d.shape}")
        length = np.linalg.norm(d, axis=1, keepdims=True)
        if not np.all(length > 0.0):
            raise ValueError("directions: expected non-zero vectors")
        d /= length
        rot, shift = self.pose[:3, :3], self.pose[:3, 3]
        t = self._contact((p - shift) @ rot, d @ rot)  # R^T (p − T), R^T d, row by row
        # The measured center is on the commanded line by construction; the model-frame solve only gives t.
        eps = self._rng.standard_normal(len(p)) * self.noise
        return p + (t + eps)[:, None] * d

    def _seeds(self, p: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Grid indices ``(iu, iv)`` of two Newton seeds per line, shape ``(2, N, 2)`` (-1: none).

        Candidates face the approach (``N·d < 0``: the line enters the part there) and project within the
        travel. Seed A is the candidate nearest the line; seed B, among the candidates within two coarse
        steps of the line, the one with the smallest ``t``, so that an entry earlier than A's is found too.
        Both are picked on the coarse subgrid by brute force, then refined to the grid point nearest the
        line in a window of one coarse step around them.
        """
        n = len(p)
        picks = np.full((2, n), -1, dtype=np.intp)
        g, gn, g_sq = self._coarse, self._coarse_normals, self._coarse_sq
        reach = self.travel + self._coarse_spacing
        # Chunked brute force through matrix products: t = d·(g − p) and |g − p|² − t² for all pairs, one
        # line per row so that the reductions run along contiguous memory.
        step = max(1, 2_000_000 // len(g))
        for lo in range(0, n, step):
            pc, dc = p[lo : lo + step], d[lo : lo + step]
            rows = np.arange(len(pc))
            along = dc @ g.T - np.einsum("ij,ij->i", pc, dc)[:, None]
            perp2 = g_sq - 2.0 * (pc @ g.T) + np.einsum("ij,ij->i", pc, pc)[:, None] - along**2
            perp2[(dc @ gn.T >= 0.0) | (np.abs(along) > reach)] = np.inf
            i = np.argmin(perp2, axis=1)
            picks[0, lo : lo + step] = np.where(np.isfinite(perp2[rows, i]), i, -1)
            along[perp2 > (2.0 * self._coarse_spacing) ** 2] = np.inf
            j = np.argmin(along, axis=1)
            picks[1, lo : lo + step] = np.where(np.isfinite(along[rows, j]), j, -1)
        seeds = np.full((2, n, 2), -1, dtype=np.intp)
        for k in range(2):
            rows = np.flatnonzero(picks[k] >= 0)
            seeds[k, rows] = self._refine(self._coarse_index[picks[k, rows]], p[rows], d[rows])
        return seeds

    def _refine(self, index: np.ndarray, p: np.ndarray, d: np.ndarray) -> np.ndarray:
        """The grid point nearest each line among the facing ones in a coarse step around ``index``."""
        (nu, nv), (su, sv) = self._grid_shape, self._stride
        ou, ov = np.meshgrid(np.arange(-su, su + 1), np.arange(-sv, sv + 1), indexing="ij")
        iu = np.mod(index[:, :1] + ou.ravel(), nu)  # u is periodic
        iv = np.clip(index[:, 1:] + ov.ravel(), 0, nv - 1)
        rel = self._grid[iu, iv] - p[:, None, :]
        along = np.einsum("nwj,nj->nw", rel, d)
        perp2 = np.einsum("nwj,nwj->nw", rel, rel) - along**2
        facing = np.einsum("nwj,nj->nw", self._grid_normals[iu, iv], d) < 0.0
        perp2 = np.where(facing & (np.abs(along) <= self.travel + self._coarse_spacing), perp2, np.inf)
        w = np.argmin(perp2, axis=1)
        rows = np.arange(len(p))
        # The coarse pick itself qualified, so keep it when nothing in the window does better.
        best = np.stack([iu[rows, w], iv[rows, w]], axis=-1)
        return np.where(np.isfinite(perp2[rows, w])[:, None], best, index)

    def _residual(self, u: np.ndarray, v: np.ndarray, t: np.ndarray, p: np.ndarray, d: np.ndarray) -> np.ndarray:
        points, normals = self.part.surface(u, v)
        return points + self.radius * normals - p - t[:, None] * d

    def _newton(self, seed: np.ndarray, p: np.ndarray, d: np.ndarray) -> np.ndarray:
        """``t`` of the contact reached from the grid points ``seed`` (``(N, 2)`` indices; NaN: not an entry)."""
        nu, nv = self._grid_shape
        u, v = seed[:, 0] / nu, seed[:, 1] / (nv - 1)
        t = np.einsum("ij,ij->i", self._grid[seed[:, 0], seed[:, 1]] - p, d)
        h = 1e-6
        for _ in range(60):
            f = self._residual(u, v, t, p, d)
            # Iterate a little past the 1e-10 mm acceptance: Newton's last steps are nearly free.
            done = np.linalg.norm(f, axis=1) < 1e-12
            if done.all():
                break
            # Central differences of the exact residual: the Jacobian only steers, the root is exact.
            ju = (self._residual(u + h, v, t, p, d) - self._residual(u - h, v, t, p, d)) / (2.0 * h)
            jv = (self._residual(u, v + h, t, p, d) - self._residual(u, v - h, t, p, d)) / (2.0 * h)
            jac = np.stack([ju, jv, -d], axis=-1)
            # Grazing lines make the Jacobian singular (relative to its column sizes): leave those rows be.
            size = np.linalg.norm(ju, axis=1) * np.linalg.norm(jv, axis=1)
            singular = ~(np.abs(np.linalg.det(jac)) > 1e-12 * size)
            jac[singular] = np.eye(3)
            step = np.linalg.solve(jac, -f[..., None])[..., 0]
            step[singular | done] = 0.0
            # Damp long parameter steps (far seeds, grazing lines) so Newton stays on the same sheet.
            with np.errstate(divide="ignore"):
                scale = np.minimum(1.0, np.minimum(0.02 / np.abs(step[:, 0]), 0.1 / np.abs(step[:, 1])))
            step *= scale[:, None]
            u = np.mod(u + step[:, 0], 1.0)
            v = v + step[:, 1]
            t = t + step[:, 2]
        _, normals = self.part.surface(u, v)
        valid = (
            (np.linalg.norm(self._residual(u, v, t, p, d), axis=1) < 1e-10)
            & (v >= -1e-9)
            & (v <= 1.0 + 1e-9)
            & (np.abs(t) <= self.travel)
            & (np.einsum("ij,ij->i", normals, d) < 0.0)
        )
        return np.where(valid, t, np.nan)

    def _contact(self, p: np.ndarray, d: np.ndarray) -> np.ndarray:
        """``t`` of the first contact along each model-frame line (NaN: none)."""
        t = np.full(len(p), np.nan)
        for seed in self._seeds(p, d):
            rows = np.flatnonzero(seed[:, 0] >= 0)
            if len(rows):
                # The first contact is the smallest t among the valid entries found.
                t[rows] = np.fmin(t[rows], self._newton(seed[rows], p[rows], d[rows]))
        return t


def misplacement(
    seed: int = 0,
    *,
    translation: float = 0.5,
    rotation: float = float(np.deg2rad(0.5)),
    center: Any = (0.0, 0.0, 0.0),
) -> np.ndarray:
    """A random rigid misplacement of a clamped part: the "0.5 mm / 0.5°" error of paper 003.

    The transform turns by ``rotation`` about a random unit axis through ``center``, then shifts by
    ``translation`` in a random direction: ``x ↦ R·(x − center) + center + shift``.

    Parameters
    ----------
    seed : int
        Seed of the random axis and direction (reproducible).
    translation : float
        Length of the shift, mm.
    rotation : float
        Angle of the rotation, rad.
    center : array_like, shape (3,)
        A point on the rotation axis (e.g. the part's center, so the rotation does not move it far).

    Returns
    -------
    ndarray, shape (4, 4)
        The homogeneous transform model → machine.

    Examples
    --------
    >>> pose = misplacement(seed=3, center=(0, 0, 75))
    >>> bool(np.isclose(np.linalg.norm(pose[:3, :3] @ [0, 0, 75] + pose[:3, 3] - [0, 0, 75]), 0.5))
    True
    """
    rng = np.random.default_rng(seed)
    axis = rng.standard_normal(3)
    axis /= np.linalg.norm(axis)
    direction = rng.standard_normal(3)
    direction /= np.linalg.norm(direction)
    # Rodrigues: R = I + sin θ K + (1 − cos θ) K².
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    rot = np.eye(3) + math.sin(rotation) * k + (1.0 - math.cos(rotation)) * (k @ k)
    c = np.asarray(center, dtype=float)
    pose = np.eye(4)
    pose[:3, :3] = rot
    pose[:3, 3] = c - rot @ c + translation * direction
    return pose
