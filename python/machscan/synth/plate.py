"""The engraved plate of paper 000's experiment and its exact truth: the 11 analytic contours,
the smooth profiles along them (width, depth, lips, local wiggle), the plate's deflection from
clamping, the groove's cross-section, and the truth a scan of it carries (:class:`GrooveTruth`).
:func:`machscan.synth.groove_scan` scans it. Pure NumPy; mm and rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["PLATE", "ContourShape", "Deflection", "GrooveTruth", "PeriodicProfile", "default_contours"]

#: Plate rectangle ``(x0, y0, x1, y1)`` in the WCS, mm (paper 000 §3: 200 mm x 200 mm).
PLATE = (0.0, 0.0, 200.0, 200.0)

_TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------------------------
# Analytic contours
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ContourShape:
    """A closed CAD contour: a (possibly rotated) rounded rectangle.

    Circles (``half_size = (r, r)``) and slots / stadiums (``radius = min(half_size)``) are the
    special cases. The contour is the boundary of the set of points within ``radius`` of the
    inner rectangle ``[-ex, ex] x [-ey, ey]`` (``ex = hx - radius``, ``ey = hy - radius``),
    rotated by ``angle`` and moved to ``center``.

    Parameters
    ----------
    kind : str
        ``"rounded_rectangle"``, ``"slot"`` or ``"circle"`` (a label; the geometry is given by
        the other fields).
    center : (float, float)
        Center in the WCS, mm.
    half_size : (float, float)
        Half extents ``(hx, hy)`` along the shape's own axes, mm.
    radius : float
        Corner radius, mm, ``0 < radius <= min(hx, hy)``.
    angle : float
        Rotation of the shape about its center, rad (counter-clockwise).

    Notes
    -----
    Arc length ``u`` (mm) starts at the local point ``(hx, 0)`` (middle of the local +x side)
    and runs counter-clockwise; :attr:`length` is the perimeter. The outward normal is the
    tangent turned by -90 degrees. :meth:`closest` gives the exact signed distance (positive
    outside) and the arc length of the closest contour point, in closed form.
    """

    kind: str
    center: tuple[float, float]
    half_size: tuple[float, float]
    radius: float
    angle: float = 0.0

    def __post_init__(self) -> None:
        c = tuple(float(v) for v in self.center)
        hs = tuple(float(v) for v in self.half_size)
        r = float(self.radius)
        if len(c) != 2 or len(hs) != 2:
            raise ValueError("center, half_size: expected two values each")
        if not (0.0 < r <= min(hs) + 1e-12):
            raise ValueError(f"radius: expected 0 < radius <= min(half_size) = {min(hs)}, got {r}")
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "half_size", hs)
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "angle", float(self.angle))

    # -- geometry --------------------------------------------------------------------------

    @property
    def _e(self) -> tuple[float, float]:
        return (max(self.half_size[0] - self.radius, 0.0), max(self.half_size[1] - self.radius, 0.0))

    @property
    def length(self) -> float:
        """Perimeter, mm."""
        ex, ey = self._e
        return 4.0 * ex + 4.0 * ey + _TWO_PI * self.radius

    def _to_local(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        dx = xy[..., 0] - self.center[0]
        dy = xy[..., 1] - self.center[1]
        if self.angle == 0.0:
            return dx, dy
        c, s = math.cos(self.angle), math.sin(self.angle)
        return c * dx + s * dy, -s * dx + c * dy

    def _to_world(self, lx, ly, vector: bool = False) -> np.ndarray:
        c, s = math.cos(self.angle), math.sin(self.angle)
        wx = c * lx - s * ly
        wy = s * lx + c * ly
        if not vector:
            wx = wx + self.center[0]
            wy = wy + self.center[1]
        return np.stack([wx, wy], axis=-1)

    def closest(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """Signed distance to the contour and arc length of the closest contour point.

        Parameters
        ----------
        xy : array_like, shape (..., 2)
            Points in the WCS plane, mm.

        Returns
        -------
        sdf : ndarray, shape (...)
            Signed distance, mm, positive outside.
        u : ndarray, shape (...)
            Arc length of the closest contour point, mm, in ``[0, length)``.
        """
        xy = np.asarray(xy, dtype=np.float64)
        lx, ly = self._to_local(xy)
        ex, ey = self._e
        r = self.radius
        ax, ay = np.abs(lx), np.abs(ly)
        qx, qy = ax - ex, ay - ey
        sdf = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0)) + np.minimum(np.maximum(qx, qy), 0.0) - r
        arc = (qx > 0.0) & (qy > 0.0)
        side = (~arc) & (qx >= qy)
        s1 = np.where(
            arc,
            ey + r * np.arctan2(np.maximum(qy, 0.0), np.maximum(qx, 0.0)),
            np.where(side, np.minimum(ay, ey), ey + 0.5 * math.pi * r + (ex - np.minimum(ax, ex))),
        )
        L = self.length
        u = np.where(
            lx >= 0.0,
            np.where(ly >= 0.0, s1, L - s1),
            np.where(ly >= 0.0, 0.5 * L - s1, 0.5 * L + s1),
        )
        u = np.where(u >= L, u - L, u)
        return sdf, u

    def signed_distance(self, xy) -> np.ndarray:
        """Signed distance to the contour (mm, positive outside); see :meth:`closest`."""
        return self.closest(xy)[0]

    def _first_quadrant(self, s1):
        ex, ey = self._e
        r = self.radius
        a1 = ey
        a2 = ey + 0.5 * math.pi * r
        th = np.clip((s1 - a1) / r, 0.0, 0.5 * math.pi)
        on_side = s1 < a1
        on_arc = (~on_side) & (s1 < a2)
        hx, hy = ex + r, ey + r
        px = np.where(on_side, hx, np.where(on_arc, ex + r * np.cos(th), ex - (s1 - a2)))
        py = np.where(on_side, s1, np.where(on_arc, ey + r * np.sin(th), hy))
        tx = np.where(on_side, 0.0, np.where(on_arc, -np.sin(th), -1.0))
        ty = np.where(on_side, 1.0, np.where(on_arc, np.cos(th), 0.0))
        return px, py, tx, ty

    def _local_frame(self, u):
        L = self.length
        u = np.mod(np.asarray(u, dtype=np.float64), L)
        q = np.minimum(np.floor(u / (0.25 * L)).astype(np.int64), 3)
        s = u - q * (0.25 * L)
        s1 = np.where((q == 1) | (q == 3), 0.25 * L - s, s)
        px, py, tx, ty = self._first_quadrant(s1)
        mx = np.where((q == 1) | (q == 2), -1.0, 1.0)
        my = np.where(q >= 2, -1.0, 1.0)
        rev = np.where((q == 1) | (q == 3), -1.0, 1.0)
        return mx * px, my * py, rev * mx * tx, rev * my * ty

    def point(self, u) -> np.ndarray:
        """Contour point at arc length ``u`` (mm, any real; taken modulo the length), shape (..., 2)."""
        lx, ly, _, _ = self._local_frame(u)
        return self._to_world(lx, ly)

    def tangent(self, u) -> np.ndarray:
        """Unit tangent (counter-clockwise) at arc length ``u``, shape (..., 2)."""
        _, _, tx, ty = self._local_frame(u)
        return self._to_world(tx, ty, vector=True)

    def normal(self, u) -> np.ndarray:
        """Unit outward normal at arc length ``u``, shape (..., 2)."""
        t = self.tangent(u)
        return np.stack([t[..., 1], -t[..., 0]], axis=-1)

    def tangent_angle(self, u) -> np.ndarray:
        """Direction of the tangent, rad, continuous in ``u`` (grows by 2 pi per loop)."""
        u = np.asarray(u, dtype=np.float64)
        L = self.length
        ex, ey = self._e
        r = self.radius
        loops = np.floor(u / L)
        v = u - loops * L
        lengths = [ey, 0.5 * math.pi * r, 2 * ex, 0.5 * math.pi * r, 2 * ey, 0.5 * math.pi * r, 2 * ex, 0.5 * math.pi * r, ey]
        starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        turned = np.zeros_like(v)
        for k in (1, 3, 5, 7):
            turned = turned + np.clip(v - starts[k], 0.0, lengths[k])
        return 0.5 * math.pi + self.angle + turned / r + _TWO_PI * loops

    def polyline(self, step: float = 0.1) -> np.ndarray:
        """Points every ~``step`` mm along the contour (not repeating the first), shape (n, 2)."""
        n = max(math.ceil(self.length / step), 8)
        return self.point(np.arange(n) * (self.length / n))

    def describe(self) -> dict:
        """JSON-able description."""
        return {
            "kind": self.kind,
            "center": list(self.center),
            "half_size": list(self.half_size),
            "radius": self.radius,
            "angle": self.angle,
        }


def default_contours() -> tuple[ContourShape, ...]:
    """The 11 engraved contours of the synthetic template, numbered by x like paper 000 §3.

    Rounded rectangles, slots and circles of different sizes (perimeters 63-207 mm, total
    about 1.45 m) on the 200 mm x 200 mm plate, at least 8 mm apart and at least 12 mm from
    the plate edges. Index ``k`` here is contour ``k + 1`` of the paper's numbering.
    """
    rr, sl, ci = "rounded_rectangle", "slot", "circle"
    shapes = [
        ContourShape(rr, (36.0, 41.0), (22.0, 25.0), 5.0),
        ContourShape(ci, (36.0, 100.0), (17.0, 17.0), 17.0),
        ContourShape(sl, (36.0, 160.0), (22.0, 14.0), 14.0),
        ContourShape(sl, (81.0, 53.0), (11.0, 30.0), 11.0, angle=0.2),
        ContourShape(rr, (100.0, 125.0), (30.0, 20.0), 10.0),
        ContourShape(sl, (100.0, 170.0), (30.0, 12.0), 12.0),
        ContourShape(ci, (116.0, 30.0), (10.0, 10.0), 10.0),
        ContourShape(rr, (118.0, 75.0), (14.0, 14.0), 8.0),
        ContourShape(rr, (165.0, 50.0), (22.0, 35.0), 12.0),
        ContourShape(ci, (165.0, 120.0), (20.0, 20.0), 20.0),
        ContourShape(rr, (165.0, 170.0), (22.0, 13.0), 4.0),
    ]
    return tuple(sorted(shapes, key=lambda s: (s.center[0], s.center[1])))


# --------------------------------------------------------------------------------------------
# Profiles along arc length and the plate deflection
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PeriodicProfile:
    """A smooth periodic function of arc length: ``mean + sum_j a_j cos(2 pi k_j u / period + p_j)``.

    Parameters
    ----------
    period : float
        Contour length, mm (the profile closes on itself).
    mean : float
    harmonics : ndarray of int
        ``k_j``: whole numbers of waves per loop.
    amplitudes, phases : ndarray
        ``a_j`` (same unit as ``mean``) and ``p_j`` (rad).
    """

    period: float
    mean: float
    harmonics: np.ndarray
    amplitudes: np.ndarray
    phases: np.ndarray

    def __call__(self, u) -> np.ndarray:
        u = np.asarray(u, dtype=np.float64)
        out = np.full(u.shape, self.mean)
        w = _TWO_PI / self.period
        for k, a, p in zip(self.harmonics, self.amplitudes, self.phases):
            out += a * np.cos((w * k) * u + p)
        return out

    @property
    def bound(self) -> float:
        """Upper bound of ``|f(u) - mean|``."""
        return float(np.abs(self.amplitudes).sum())

    @property
    def rms(self) -> float:
        """RMS of ``f - mean`` over a period."""
        return float(np.sqrt(0.5 * np.sum(self.amplitudes**2)))

    @staticmethod
    def random(
        rng: np.random.Generator, period: float, mean: float, rms: float, wavelengths: tuple[float, float], n: int
    ) -> PeriodicProfile:
        """``n`` random harmonics with wavelengths in ``wavelengths`` (mm) and the given RMS."""
        kmin = max(1, math.ceil(period / wavelengths[1]))
        kmax = max(kmin, math.floor(period / wavelengths[0]))
        pool = np.arange(kmin, kmax + 1)
        ks = np.sort(rng.choice(pool, size=min(n, pool.size), replace=False))
        amps = rng.normal(0.0, 1.0, ks.size)
        if rms > 0 and np.any(amps):
            amps *= rms / np.sqrt(0.5 * np.sum(amps**2))
        else:
            amps *= 0.0
        phases = rng.uniform(0.0, _TWO_PI, ks.size)
        return PeriodicProfile(float(period), float(mean), ks.astype(np.int64), amps, phases)

    def plus(self, other: PeriodicProfile) -> PeriodicProfile:
        """Sum of two profiles with the same period."""
        return PeriodicProfile(
            self.period,
            self.mean + other.mean,
            np.concatenate([self.harmonics, other.harmonics]),
            np.concatenate([self.amplitudes, other.amplitudes]),
            np.concatenate([self.phases, other.phases]),
        )

    def scaled(self, factor: float) -> PeriodicProfile:
        """The variation ``f - mean`` multiplied by ``factor``."""
        return PeriodicProfile(self.period, self.mean, self.harmonics, self.amplitudes * factor, self.phases)


@dataclass(frozen=True, eq=False)
class Deflection:
    """Smooth z deflection of the clamped plate: ``w(x, y) = sum_k c_k xi^i_k eta^j_k``.

    ``xi = (x - cx) / scale``, ``eta = (y - cy) / scale`` (mm); ``w`` in mm.

    Parameters
    ----------
    center : (float, float)
    scale : float
    exponents : ndarray of int, shape (K, 2)
    coefficients : ndarray, shape (K,)
    """

    center: tuple[float, float]
    scale: float
    exponents: np.ndarray
    coefficients: np.ndarray

    def __call__(self, x, y) -> np.ndarray:
        """Deflection at WCS ``(x, y)`` (mm)."""
        xi = (np.asarray(x, dtype=np.float64) - self.center[0]) * (1.0 / self.scale)
        eta = (np.asarray(y, dtype=np.float64) - self.center[1]) * (1.0 / self.scale)
        xi, eta = np.broadcast_arrays(xi, eta)
        # Horner in xi of polynomials in eta: w = sum_i xi^i P_i(eta)
        coef: dict[tuple[int, int], float] = {}
        for (i, j), c in zip(self.exponents.tolist(), self.coefficients.tolist()):
            coef[(i, j)] = coef.get((i, j), 0.0) + c
        maxi = max((i for i, _ in coef), default=0)
        out = np.zeros(xi.shape)
        tmp = np.empty(xi.shape)
        for i in range(maxi, -1, -1):
            out *= xi
            js = sorted(j for (ii, j) in coef if ii == i)
            if not js:
                continue
            # P_i(eta) by Horner, accumulated into out
            tmp.fill(0.0)
            for j in range(js[-1], -1, -1):
                tmp *= eta
                c = coef.get((i, j), 0.0)
                if c != 0.0:
                    tmp += c
            out += tmp
        return out

    @staticmethod
    def flat() -> Deflection:
        """No deflection."""
        return Deflection((100.0, 100.0), 100.0, np.zeros((0, 2), dtype=np.int64), np.zeros(0))


def _random_deflection(rng: np.random.Generator, bend: float) -> Deflection:
    """A bow that is largest at the x ends (paper 000 fig. 11) with a small y and twist part."""
    exps = np.array([[0, 0], [1, 0], [0, 1], [2, 0], [1, 1], [0, 2], [3, 0], [2, 1]], dtype=np.int64)
    base = np.array([0.30, 0.20, 0.10, 1.00, 0.20, -0.30, 0.12, -0.08])
    jitter = 1.0 + 0.25 * rng.normal(size=base.size)
    coef = base * jitter
    if bend == 0.0:
        return Deflection((100.0, 100.0), 100.0, exps, np.zeros(base.size))
    d = Deflection((100.0, 100.0), 100.0, exps, coef)
    g = np.linspace(0.0, 200.0, 201)
    gx, gy = np.meshgrid(g, g)
    peak = float(np.abs(d(gx, gy)).max())
    return Deflection((100.0, 100.0), 100.0, exps, coef * (bend / peak))


# --------------------------------------------------------------------------------------------
# Groove cross-section
# --------------------------------------------------------------------------------------------

_LIP_OFFSET = 0.045  # lip crest outside the groove edge, mm
_LIP_HALF_WIDTH = 0.05  # half width of the lip bead, mm
_TIP_RADIUS = 0.01  # the groove bottom rounded by the laser spot, mm (assumption)
_EDGE_RADIUS = 0.01  # the top edges rounded, mm (assumption)


def _groove_section(s, width, depth, lip_in, lip_out):
    """Height of a groove cross-section relative to the surface (mm) and a steep-flank mask.

    ``s`` is the signed distance to the groove centerline (positive outside the contour). The
    section is a V with straight flanks whose extensions meet the surface exactly ``width``
    apart (the groove's width as machscan defines it), its bottom rounded by a circle of radius
    ``_TIP_RADIUS`` tangent to both flanks, its top edges by ``_EDGE_RADIUS``; ``depth`` is the
    deepest point (the rounded bottom), exactly. Plus a lip bead ``h (1 - tau^2)^2`` of height
    ``lip_out`` / ``lip_in`` on the outer / inner side, crest ``_LIP_OFFSET`` outside the edge.
    """
    x = np.abs(s)
    a = 0.5 * np.asarray(width, dtype=np.float64)
    depth = np.asarray(depth, dtype=np.float64)
    rt, re = _TIP_RADIUS, _EDGE_RADIUS
    # Depth of the sharp V whose rounded bottom is `depth` deep: d = depth + rt (sec θ - 1),
    # tan θ = d / a (a few fixed-point steps; the correction is a few % of the depth).
    d = depth.copy()
    for _ in range(30):
        d = depth + rt * (np.sqrt(1.0 + (d / a) ** 2) - 1.0)
    m = d / a  # flank slope
    cos_t = 1.0 / np.sqrt(1.0 + m * m)
    sin_t = m * cos_t
    x_tip = rt * sin_t  # tip arc meets the flank
    c_tip = -d + rt / cos_t  # tip arc center height
    x_c = a + re * (1.0 / cos_t - 1.0) / m  # edge arc center (on the surface's level - re)
    x_edge = x_c - re * sin_t  # edge arc meets the flank
    tip = c_tip - np.sqrt(np.maximum(rt * rt - x * x, 0.0))
    flank_line = -d + m * x
    edge = -re + np.sqrt(np.maximum(re * re - (x - x_c) ** 2, 0.0))
    g = np.where(x < x_tip, tip, np.where(x <= x_edge, flank_line, np.where(x < x_c, edge, 0.0)))
    tau = (x - a - _LIP_OFFSET) / _LIP_HALF_WIDTH
    bump = np.where(np.abs(tau) < 1.0, (1.0 - tau * tau) ** 2, 0.0)
    lip = np.where(s >= 0.0, lip_out, lip_in)
    t = x / a
    flank = (t > 0.2) & (t < 0.85)
    return g + lip * bump, flank


# --------------------------------------------------------------------------------------------
# Truth
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False, repr=False)
class GrooveTruth:
    """Exact ground truth of a :func:`groove_scan`.

    Per-frame arrays (``F`` = number of frames of the scan). The *groove center* of a frame is
    the point where the laser plane (SCS y = 0) crosses the true engraved centerline, at the
    height of the (bent) surface, i.e. the point a template fit reports as ``(x0, z0)``.

    Attributes
    ----------
    frame_contour : ndarray of int64, shape (F,)
        Contour scanned by each frame (index into :attr:`contours`; paper numbering is +1).
    frame_u : ndarray, shape (F,)
        Arc length (mm) of the nominal contour point the SCS origin was driven to.
    center_u : ndarray, shape (F,)
        Arc length (mm) of the groove center on its contour.
    center_scs : ndarray, shape (F, 2)
        Groove center in the SCS: x along the laser line and z (height), mm. Its SCS y is 0.
    center_wcs : ndarray, shape (F, 3)
        Groove center in the WCS, mm; equals ``T_f @ (x, 0, z, 1)`` with the frame's true
        WCS <- SCS transform.
    width, depth : ndarray, shape (F,)
        True groove width at the surface and depth of the bottom below the surface at the
        center, mm.
    center_nominal : ndarray, shape (F, 3)
        CAD point at the same arc length (z = 0).
    center_offset : ndarray, shape (F, 3)
        Rigid engraving offset of the frame's contour (z = 0).
    center_local : ndarray, shape (F,)
        Local (machine dynamics) error: normal displacement of the engraved line, mm.
    center_normal : ndarray, shape (F, 3)
        Outward unit normal of the CAD contour at ``center_u`` (z = 0).
    center_bend : ndarray, shape (F,)
        Bending error: the plate deflection at the center, mm. Exactly,
        ``center_wcs = center_nominal + center_offset + center_local * center_normal
        + center_bend * e_z``.
    contours : tuple of ContourShape
        The nominal CAD contours (analytic).
    nominal_polylines : tuple of ndarray (n_k, 3)
        CAD contours sampled every ~0.05 mm at z = 0.
    engraved_polylines : tuple of ndarray (n_k, 3)
        True engraved centerlines on the bent surface, sampled every ~0.05 mm.
    offsets : ndarray, shape (K, 2)
        Rigid xy offset of every engraved contour, mm.
    wiggle : tuple of PeriodicProfile
        Normal displacement of the engraved line along arc length, per contour, mm.
    width_profile, depth_profile : tuple of PeriodicProfile
        Groove width and depth along arc length, per contour, mm.
    lip_profile : tuple of PeriodicProfile
        Lip height along arc length, per contour, mm; the outer lip is ``(1 + a)`` and the inner
        ``(1 - a)`` times it with ``a = lip_asymmetry[k]``.
    lip_asymmetry : ndarray, shape (K,)
    deflection : Deflection
        Plate deflection; ``truth.deflection(x, y)`` evaluates it (mm).
    plate : (float, float, float, float)
        ``(x0, y0, x1, y1)`` of the plate, mm.
    plate_thickness : float
        The table is at ``z = -plate_thickness``.
    mount_true : ndarray, shape (6,)
        The mount used to cast the readings (the scan carries the calibrated one).
    params : dict
        The generator's parameters.
    """

    frame_contour: np.ndarray
    frame_u: np.ndarray
    center_u: np.ndarray
    center_scs: np.ndarray
    center_wcs: np.ndarray
    width: np.ndarray
    depth: np.ndarray
    center_nominal: np.ndarray
    center_offset: np.ndarray
    center_local: np.ndarray
    center_normal: np.ndarray
    center_bend: np.ndarray
    contours: tuple
    nominal_polylines: tuple
    engraved_polylines: tuple
    offsets: np.ndarray
    wiggle: tuple
    width_profile: tuple
    depth_profile: tuple
    lip_profile: tuple
    lip_asymmetry: np.ndarray
    deflection: Deflection
    plate: tuple
    plate_thickness: float
    mount_true: np.ndarray
    params: dict

    @property
    def n_contours(self) -> int:
        return len(self.contours)

    def __repr__(self) -> str:
        return (
            f"GrooveTruth({self.frame_contour.size} frames, {self.n_contours} contours, "
            f"width {self.width.mean():.4f} +- {self.width.std():.4f} mm, "
            f"depth {self.depth.mean():.4f} +- {self.depth.std():.4f} mm, "
            f"peak bend {self.params.get('bend', float('nan')):g} mm)"
        )

    # -- evaluation -------------------------------------------------------------------------

    def engraved_point(self, k: int, u) -> np.ndarray:
        """True engraved centerline point of contour ``k`` at arc length ``u`` (mm), shape (..., 3)."""
        xy = _engraved_xy(self.contours[k], self.offsets[k], self.wiggle[k], u)
        z = self.deflection(xy[..., 0], xy[..., 1])
        return np.concatenate([xy, z[..., None]], axis=-1)

    def on_plate(self, x, y) -> np.ndarray:
        """True where ``(x, y)`` lies on the plate."""
        x0, y0, x1, y1 = self.plate
        x = np.asarray(x)
        y = np.asarray(y)
        return (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)

    def surface(self, x, y) -> np.ndarray:
        """Top surface without grooves: the deflection on the plate, the table elsewhere (mm)."""
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        return np.where(self.on_plate(x, y), self.deflection(x, y), -self.plate_thickness)

    def groove_signed_distance(self, x, y) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Signed distance (mm, positive outside) to the nearest engraved centerline.

        Returns ``(s, contour, u)``: the distance, the index of the nearest contour and the
        arc length of the closest point on it. Accurate to O(wiggle slope^2) near the lines.
        """
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        best = np.full(x.shape, np.inf)
        bk = np.full(x.shape, -1, dtype=np.int64)
        bu = np.zeros(x.shape)
        for k, shape in enumerate(self.contours):
            xy = np.stack([x - self.offsets[k, 0], y - self.offsets[k, 1]], axis=-1)
            sdf, u = shape.closest(xy)
            s = sdf - self.wiggle[k](u)
            better = np.abs(s) < np.abs(best)
            best = np.where(better, s, best)
            bk = np.where(better, k, bk)
            bu = np.where(better, u, bu)
        return best, bk, bu

    def height(self, x, y) -> np.ndarray:
        """Noise-free surface height at WCS ``(x, y)``, grooves and lips included (mm).

        This is the surface the synthetic profiler readings were ray-cast onto.
        """
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        z = self.surface(x, y)
        on = self.on_plate(x, y)
        for k in range(self.n_contours):
            g, _ = _groove_height_k(self, k, x, y)
            z = z + np.where(on, g, 0.0)
        return z


def _engraved_xy(shape: ContourShape, offset, wiggle: PeriodicProfile, u) -> np.ndarray:
    u = np.asarray(u, dtype=np.float64)
    return shape.point(u) + np.asarray(offset) + wiggle(u)[..., None] * shape.normal(u)


def _groove_height_k(t: GrooveTruth | _Design, k: int, x, y):
    """Groove contribution (height relative to the surface) of contour ``k`` at ``(x, y)``."""
    shape = t.contours[k]
    xy = np.stack([x - t.offsets[k, 0], y - t.offsets[k, 1]], axis=-1)
    sdf, u = shape.closest(xy)
    s = sdf - t.wiggle[k](u)
    lip = t.lip_profile[k](u)
    a = t.lip_asymmetry[k]
    return _groove_section(s, t.width_profile[k](u), t.depth_profile[k](u), lip * (1.0 - a), lip * (1.0 + a))


@dataclass
class _Design:
    """The random design of a synthetic part (internal)."""

    contours: tuple
    offsets: np.ndarray
    wiggle: tuple
    width_profile: tuple
    depth_profile: tuple
    lip_profile: tuple
    lip_asymmetry: np.ndarray
    deflection: Deflection
    band: np.ndarray  # per contour: |nominal sdf| beyond which the groove contributes nothing


def _make_design(rng: np.random.Generator, contours, bend: float) -> _Design:
    k = len(contours)
    # Rigid offsets: a common datum error plus a per-contour part (paper: 0.0255 +- 0.0148 mm).
    common = rng.normal(0.0, 0.014, 2)
    offsets = common + rng.normal(0.0, 0.014, (k, 2))
    wiggle, widths, depths, lips = [], [], [], []
    lip_asym = rng.uniform(-0.25, 0.25, k)
    band = np.zeros(k)
    for i, shape in enumerate(contours):
        L = shape.length
        # Local error (machine dynamics): ~15 um RMS, wavelengths 4-40 mm
        # (paper: local error 0.0123 +- 0.0062 mm as mean +- std of |e|).
        wg = PeriodicProfile.random(rng, L, 0.0, 0.015 * rng.uniform(0.75, 1.25), (4.0, 40.0), 5)
        # Width / depth: a per-contour mean (paper table 1 spreads 0.467-0.502 and
        # 0.306-0.326 mm), a slow drift along the contour and a little short-wavelength
        # variation (paper overall: 0.4806 +- 0.0163 and 0.3124 +- 0.0148 mm, measured).
        w_mean = float(np.clip(rng.normal(0.4806, 0.011), 0.45, 0.51))
        d_mean = float(np.clip(rng.normal(0.3124, 0.007), 0.295, 0.33))
        wp = PeriodicProfile.random(rng, L, w_mean, 0.008, (20.0, 200.0), 3).plus(
            PeriodicProfile.random(rng, L, 0.0, 0.005, (1.0, 4.0), 4)
        )
        dp = PeriodicProfile.random(rng, L, d_mean, 0.008, (20.0, 200.0), 3).plus(
            PeriodicProfile.random(rng, L, 0.0, 0.005, (1.0, 4.0), 4)
        )
        lp_mean = float(rng.uniform(0.012, 0.024))
        lp = PeriodicProfile.random(rng, L, lp_mean, 0.003, (2.0, 30.0), 4)
        if lp.bound > 0.6 * lp_mean:  # keep the lips positive (>= 0.4 of the mean)
            lp = lp.scaled(0.6 * lp_mean / lp.bound)
        wiggle.append(wg)
        widths.append(wp)
        depths.append(dp)
        lips.append(lp)
        w_max = wp.mean + wp.bound
        band[i] = 0.5 * w_max + _LIP_OFFSET + _LIP_HALF_WIDTH + wg.bound + 1e-6
    deflection = _random_deflection(rng, bend)
    return _Design(tuple(contours), offsets, tuple(wiggle), tuple(widths), tuple(depths), tuple(lips), lip_asym, deflection, band)


