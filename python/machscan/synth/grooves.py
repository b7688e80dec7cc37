"""Paper 000 groove plate scans and groove frames with exact ground truth, for tests, demos and benchmarks.

:func:`groove_scan` reproduces the experiment of paper 000 §3 (on-machine measurement of
laser-engraved chemical-milling grooves): a 200 mm x 200 mm aluminium plate covered with
maskant, bent a few tenths of a millimetre by clamping, carrying 11 engraved closed contours,
scanned contour by contour by an SR7140-like line-laser profiler on a gantry with an AC
double-swing head and a sixth axis C2 that keeps the laser line across the groove. Everything
the measurement pipeline should recover is returned in a :class:`GrooveTruth`: the groove
center, width and depth at every frame, the engraved contours, and the three error sources of
the paper's decomposition (rigid offset, bending, local wiggle) separately.

All lengths are in mm, angles in rad, times in s. The module is pure NumPy (it does not use
the compiled core), so its output can be checked against independent references.

Model summary (numbers from paper 000 unless marked as assumptions):

* Plate: ``[0, 200] x [0, 200]`` mm in the WCS, nominal (CAD) top surface of the maskant at
  ``z = 0``; 2 mm thick (assumption), lying on a machine table at ``z = -2``.
* Bending: a smooth low-order polynomial deflection ``w(x, y)`` whose peak ``|w|`` over the
  plate is ``bend`` (default 0.3 mm); largest at the x ends, as the paper's fig. 11 and 12
  describe. The engraved grooves sit on the bent surface.
* Grooves: V sections with straight flanks, the bottom rounded by the laser spot (radius
  0.01 mm) and the top edges by 0.01 mm (assumptions), width between the flanks at the surface
  ~0.48 mm and depth (deepest point) ~0.31 mm (paper: 0.4806 +- 0.0163 and 0.3124 +- 0.0148
  mm), varying smoothly along the arc length, with small laser-sintered lips (0.01-0.03 mm
  high) just outside both edges (paper fig. 10).
* Engraving errors per contour: a rigid offset of a few tens of um (paper: offset error
  0.0255 +- 0.0148 mm) and a smooth normal wiggle of ~15 um RMS along the arc length
  (paper: local error 0.0123 +- 0.0062 mm).
* Profiler: 3200 readings at 0.025 mm, Gaussian noise sigma 0.008 mm (the paper's +-0.024 mm
  read as 3 sigma), 2500 frames/s; dropouts (sentinel) in short runs and more often on the
  steep groove flanks; rare spikes; a shadow next to the plate edge.
* Machine: ``A = C = 0`` while scanning; ``C2`` turns the laser line onto the outward normal
  of the nominal contour; the SCS origin (reading center, height 0) follows the nominal
  contour on the nominal surface at the scanning feed (default 20 mm/s = 1200 mm/min, an
  assumption). Readings are ray-cast through the true (slightly misaligned) mount.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..scan import SENTINEL, Profiler, Scan

__all__ = [
    "DEFAULT_C2_OFFSET",
    "DEFAULT_MOUNT",
    "PLATE",
    "ContourShape",
    "Deflection",
    "GrooveFrames",
    "GrooveTruth",
    "PeriodicProfile",
    "SurfaceError",
    "default_contours",
    "flat_plate_scan",
    "groove_frames",
    "groove_scan",
    "pocket_plate",
    "surface_error",
]

#: Plate rectangle ``(x0, y0, x1, y1)`` in the WCS, mm (paper 000 §3: 200 mm x 200 mm).
PLATE = (0.0, 0.0, 200.0, 200.0)

#: ``(Lx, Ly, Lz)``: origin of the C2 frame in the tool frame, mm. The profiler hangs beside
#: the engraving head; with the default mount the SCS origin is 25 mm below the tool tip.
DEFAULT_C2_OFFSET = (-120.0, 35.0, 115.0)

#: ``(theta, psi, phi, dx, dy, dz)``: SCS pose in the C2 frame (rad, mm). A few mrad of
#: misalignment and a sub-mm offset of the line center from the C2 axis; ``dz = -140`` puts the
#: reference plane 140 mm below the C2 frame origin (an SR7140-like stand-off, assumption).
DEFAULT_MOUNT = (0.0031, -0.0024, 0.0042, 0.62, -0.41, -140.0)

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


# --------------------------------------------------------------------------------------------
# Kinematics (private NumPy copy of SPEC K2/K3; tests compare it with an independent reference)
# --------------------------------------------------------------------------------------------


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(np.shape(a) + (3, 3))
    out[..., 0, 0] = c
    out[..., 0, 1] = -s
    out[..., 1, 0] = s
    out[..., 1, 1] = c
    out[..., 2, 2] = 1.0
    return out


def _mount_rotation(theta, psi, phi):
    ct, st = math.cos(theta), math.sin(theta)
    cs, ss = math.cos(psi), math.sin(psi)
    cf, sf = math.cos(phi), math.sin(phi)
    return np.array(
        [
            [ct * cf, ss * st * cf - cs * sf, cs * st * cf + ss * sf],
            [ct * sf, ss * st * sf + cs * cf, cs * st * sf - ss * cf],
            [-st, ss * ct, cs * ct],
        ]
    )


def _transforms_a0c0(poses, c2_offset, mount):
    """WCS <- SCS rotation (F,3,3) and translation (F,3) for poses with A = C = 0."""
    m = np.asarray(mount, dtype=np.float64)
    rc2 = _rz(poses[:, 5])
    rot = rc2 @ _mount_rotation(m[0], m[1], m[2])
    trans = rc2 @ m[3:6] + np.asarray(c2_offset) + poses[:, :3]
    return rot, trans


# --------------------------------------------------------------------------------------------
# The generator
# --------------------------------------------------------------------------------------------


def groove_scan(
    seed: int = 0,
    *,
    bend: float = 0.3,
    readings: int = 3200,
    keep_every: int = 50,
    feed: float = 20.0,
    noise: float | None = None,
    dropout: float = 0.03,
    flank_dropout: float = 0.15,
    spike_rate: float = 5e-5,
    axis_rate: float = 1000.0,
    c2_offset=DEFAULT_C2_OFFSET,
    mount=DEFAULT_MOUNT,
    mount_error=None,
    contours: Sequence[ContourShape] | None = None,
    plate_thickness: float = 2.0,
) -> tuple[Scan, GrooveTruth]:
    """Synthetic on-machine scan of engraved chemical-milling grooves, with exact truth.

    Reproduces paper 000 §3: an 11-contour template on a 200 mm x 200 mm plate, scanned
    contour by contour with an SR7140-like profiler on an AC head with a sixth axis C2. See
    the module docstring for the model and where its numbers come from.

    Parameters
    ----------
    seed : int
        Seed (``np.random.SeedSequence(seed)``, one stream for the part, one for the
        measurement). The part (offsets, wiggles, widths, depths, lips, bending shape) depends
        only on ``seed``, ``bend`` and ``contours``; the measurement noise also on the scan
        parameters. Same arguments, same arrays, bit for bit.
    bend : float
        Peak ``|deflection|`` of the clamped plate over the plate, mm (paper 000 §3 fig. 12:
        a few tenths of a mm). 0 gives a flat plate.
    readings : int
        Readings per frame (3200 for the full 80 mm line; fewer crops the line about its
        center, for small test scans). The pitch stays 0.025 mm.
    keep_every : int
        Keep every k-th profiler frame. The profiler runs at 2500 frames/s, i.e. a frame
        every ``feed / 2500`` mm (8 um at the default feed); the default 50 keeps one frame
        every 0.4 mm, about 3800 frames. Timestamps are the real ones.
    feed : float
        Scanning feed along the contours, mm/s (default 20 mm/s = 1200 mm/min, assumption).
    noise : float, optional
        Sigma of the Gaussian height noise, mm; default the profiler's 0.008 mm.
    dropout : float
        Share of readings lost in short runs (mean length 3) anywhere, 0-1.
    flank_dropout : float
        Extra probability of losing a reading on a steep groove flank.
    spike_rate : float
        Probability of a spike (an outlier of 0.05-0.5 mm either way) per reading.
    axis_rate : float
        Sampling rate of the raw CNC axis positions, Hz (default 1 kHz); the samples cover the
        whole scan, including the moves between contours, on their own time grid.
    c2_offset : (3,) mm
        ``(Lx, Ly, Lz)``; see :data:`DEFAULT_C2_OFFSET`.
    mount : (6,) rad, mm
        The calibrated mount ``(theta, psi, phi, dx, dy, dz)``, stored in the scan and used to
        plan the poses; see :data:`DEFAULT_MOUNT`.
    mount_error : (6,), optional
        Calibration error: the readings are cast with ``mount + mount_error``
        (``truth.mount_true``). Default none.
    contours : sequence of ContourShape, optional
        The CAD contours; default :func:`default_contours`.
    plate_thickness : float
        mm; the machine table beside the plate is at ``z = -plate_thickness``.

    Returns
    -------
    scan : Scan
        Frames (sentinel for lost readings), poses at the frame times, frame times, the
        SR7140-like profiler, ``c2_offset``, the calibrated ``mount``, raw axis samples (C2
        wrapped to ``[0, 2 pi)`` like a modulo rotary axis), and metadata.
    truth : GrooveTruth

    Notes
    -----
    Poses follow the closed form ``P_t = p - R_t (R_C2 (dx, dy, dz) + (Lx, Ly, Lz))`` with
    ``R_t = I`` (A = C = 0), ``p`` the nominal contour point on ``z = 0``, and
    ``C2 = alpha - pi/2 - phi`` where ``alpha`` is the tangent direction, so the laser line
    (SCS +x) points along the outward normal of the CAD contour. Each reading is found by
    ray casting: ``h`` with ``T (x_i, 0, h)`` on the true surface, by fixed-point iteration
    (surface slope times mount tilt is tiny, so it converges to better than 1e-9 mm).

    Each contour is one pass, counter-clockwise from arc length 0 (see :class:`ContourShape`),
    with a 2 mm lead-in and run-out at feed (no frames there) and 2 s straight moves between
    passes. Readings beside the plate see the machine table; those within 0.8 mm of the plate
    edge are lost (the step shadows the laser line).

    Examples
    --------
    >>> scan, truth = groove_scan(seed=1, readings=400, keep_every=400)
    >>> scan.frames.shape[1], truth.n_contours
    (400, 11)
    """
    if keep_every < 1 or int(keep_every) != keep_every:
        raise ValueError(f"keep_every: expected a positive integer, got {keep_every!r}")
    keep_every = int(keep_every)
    if not (bend >= 0.0 and math.isfinite(bend)):
        raise ValueError(f"bend: expected a non-negative peak deflection in mm, got {bend!r}")
    if feed <= 0.0:
        raise ValueError(f"feed: expected a positive speed in mm/s, got {feed!r}")
    for name, v in (("dropout", dropout), ("flank_dropout", flank_dropout), ("spike_rate", spike_rate)):
        if not 0.0 <= v < 1.0:
            raise ValueError(f"{name}: expected a probability in [0, 1), got {v!r}")
    profiler = Profiler.sr7140(readings=readings)
    sigma = float(profiler.noise or 0.0) if noise is None else float(noise)
    if not (sigma >= 0.0 and math.isfinite(sigma)):
        raise ValueError(f"noise: expected a non-negative sigma in mm, got {noise!r}")
    c2_offset = np.asarray(c2_offset, dtype=np.float64).reshape(3)
    mount = np.asarray(mount, dtype=np.float64).reshape(6)
    mount_true = mount + (0.0 if mount_error is None else np.asarray(mount_error, dtype=np.float64).reshape(6))
    shapes = default_contours() if contours is None else tuple(contours)
    x0p, y0p, x1p, y1p = PLATE
    for k, sh in enumerate(shapes):
        pl = sh.polyline(0.5)
        if pl[:, 0].min() < x0p + 1 or pl[:, 0].max() > x1p - 1 or pl[:, 1].min() < y0p + 1 or pl[:, 1].max() > y1p - 1:
            raise ValueError(f"contours: contour {k} does not lie on the plate {PLATE}")

    seeds = np.random.SeedSequence(seed).spawn(2)
    design = _make_design(np.random.default_rng(seeds[0]), shapes, float(bend))
    rng = np.random.default_rng(seeds[1])

    # ---- path and frame times -------------------------------------------------------------
    rate = 2500.0 if profiler.frame_rate is None else profiler.frame_rate
    step = feed / rate
    # Each pass runs along its contour from u = -lead_in to u = L + lead_in at constant feed
    # (the machine is up to speed before the first frame); passes are joined by straight
    # moves of `gap` s; the CNC records `lead` s before the first and after the last pass.
    lead, gap, lead_in = 0.5, 2.0, 2.0
    pass_starts: list[float] = []
    t = lead + lead_in / feed
    f_contour, f_u, f_t = [], [], []
    for k, sh in enumerate(shapes):
        L = sh.length
        n_raw = math.floor(L / step - 1e-9) + 1  # raw frames with u < L
        j = np.arange(0, n_raw, keep_every)
        pass_starts.append(t)
        f_contour.append(np.full(j.size, k, dtype=np.int64))
        f_u.append(j * step)
        f_t.append(t + j / rate)
        t = t + (L + 2.0 * lead_in) / feed + gap
    t_start = np.array(pass_starts)
    frame_contour = np.concatenate(f_contour)
    frame_u = np.concatenate(f_u)
    frame_times = np.concatenate(f_t)

    phi = float(mount[2])
    # Branch of C2 per pass: continuous over the whole scan, first pass starting in [0, 2 pi).
    c2_shift = np.zeros(len(shapes))
    prev_end = None
    for k, sh in enumerate(shapes):
        start = float(sh.tangent_angle(0.0)) - 0.5 * math.pi - phi
        if prev_end is None:
            c2_shift[k] = -_TWO_PI * math.floor(start / _TWO_PI)
        else:
            c2_shift[k] = _TWO_PI * round((prev_end - start) / _TWO_PI)
        prev_end = start + c2_shift[k] + _TWO_PI  # one full turn per closed contour

    def pose_at(k: int, u) -> np.ndarray:
        sh = shapes[k]
        u = np.asarray(u, dtype=np.float64)
        p = sh.point(u)
        c2 = sh.tangent_angle(u) - 0.5 * math.pi - phi + c2_shift[k]
        rc2 = _rz(c2)
        off = rc2 @ mount[3:6] + c2_offset  # R_t = I
        out = np.zeros(u.shape + (6,))
        out[..., 0] = p[..., 0] - off[..., 0]
        out[..., 1] = p[..., 1] - off[..., 1]
        out[..., 2] = 0.0 - off[..., 2]
        out[..., 5] = c2
        return out

    poses = np.zeros((frame_u.size, 6))
    for k in range(len(shapes)):
        sel = frame_contour == k
        poses[sel] = pose_at(k, frame_u[sel])

    # ---- raw CNC samples ---------------------------------------------------------------------
    t_end = t_start[-1] + (shapes[-1].length + lead_in) / feed + lead
    phase = 0.317e-3  # the CNC clock is not aligned with the profiler
    axis_times = phase + np.arange(math.floor((t_end - phase) * axis_rate) + 1) / axis_rate
    axis_samples = np.zeros((axis_times.size, 6))
    kt: list[float] = []
    kp: list[np.ndarray] = []
    in_pass = np.zeros(axis_times.size, dtype=bool)
    for k, sh in enumerate(shapes):
        t0 = t_start[k] - lead_in / feed
        t1 = t_start[k] + (sh.length + lead_in) / feed
        sel = (axis_times >= t0) & (axis_times <= t1)
        axis_samples[sel] = pose_at(k, feed * (axis_times[sel] - t_start[k]))
        in_pass |= sel
        kt += [t0, t1]
        kp += [pose_at(k, -lead_in), pose_at(k, sh.length + lead_in)]
    knots_t = np.array(kt)
    knots_p = np.array(kp)
    for c in range(6):  # moves between passes: straight lines (also before / after)
        axis_samples[~in_pass, c] = np.interp(axis_times[~in_pass], knots_t, knots_p[:, c])
    axis_samples_wrapped = axis_samples.copy()
    axis_samples_wrapped[:, 5] = np.mod(axis_samples[:, 5], _TWO_PI)

    # ---- ray casting ---------------------------------------------------------------------------
    rot, trans = _transforms_a0c0(poses, c2_offset, mount_true)
    xs = profiler.x
    n = readings
    nf = frame_u.size
    frames = np.empty((nf, n))
    flank_all = np.zeros((nf, n), dtype=bool)
    deflection = design.deflection
    coarse = np.unique(np.concatenate([np.arange(0, n, 16), [n - 1]]))
    half = 8
    margin = 0.1
    chunk = max(1, 400_000 // n)
    offsets_win = np.arange(-half, half + 1)
    for f0 in range(0, nf, chunk):
        f1 = min(nf, f0 + chunk)
        c = f1 - f0
        r0 = rot[f0:f1, :, 0]
        az = rot[f0:f1, :, 2]
        tr = trans[f0:f1]
        ox = tr[:, 0:1] + xs[None, :] * r0[:, 0:1]
        oy = tr[:, 1:2] + xs[None, :] * r0[:, 1:2]
        oz = tr[:, 2:3] + xs[None, :] * r0[:, 2:3]
        ax_, ay_, az_ = az[:, 0:1], az[:, 1:2], az[:, 2:3]
        # candidate readings per contour (Lipschitz argument on the exact signed distance)
        cands = []
        cxy = np.stack([ox[:, coarse], oy[:, coarse]], axis=-1)
        for k, sh in enumerate(shapes):
            sdf, _ = sh.closest(cxy - design.offsets[k])
            fl_f, fl_j = np.nonzero(np.abs(sdf) < design.band[k] + half * profiler.pitch + margin)
            if fl_f.size == 0:
                continue
            idx = coarse[fl_j][:, None] + offsets_win[None, :]
            idx = np.clip(idx, 0, n - 1)
            mask = np.zeros((c, n), dtype=bool)
            mask[np.repeat(fl_f, offsets_win.size), idx.ravel()] = True
            cands.append((k, np.nonzero(mask)))
        # fixed-point iterations: two on the smooth surface everywhere, more on the grooves
        h = np.zeros((c, n))
        for _ in range(2):
            qx = ox + h * ax_
            qy = oy + h * ay_
            on = (qx >= x0p) & (qx <= x1p) & (qy >= y0p) & (qy <= y1p)
            z = np.where(on, deflection(qx, qy), -plate_thickness)
            for k, (fi, ii) in cands:
                g, _ = _groove_height_k(design, k, qx[fi, ii], qy[fi, ii])
                z[fi, ii] += np.where(on[fi, ii], g, 0.0)
            h = (z - oz) / az_
        for k, (fi, ii) in cands:
            azk = az_[fi, 0]
            for _ in range(3):
                qx = ox[fi, ii] + h[fi, ii] * ax_[fi, 0]
                qy = oy[fi, ii] + h[fi, ii] * ay_[fi, 0]
                on = (qx >= x0p) & (qx <= x1p) & (qy >= y0p) & (qy <= y1p)
                g, fl = _groove_height_k(design, k, qx, qy)
                z = np.where(on, deflection(qx, qy) + g, -plate_thickness)
                h[fi, ii] = (z - oz[fi, ii]) / azk
            flank_all[f0 + fi, ii] = fl & on
        # shadow next to the plate edge (the step hides the laser line from the camera)
        # (checked at the top-surface level and at the hit point, so that no ray grazing the
        # plate's side face is kept; the edge itself, 0.05 mm wide, is lost too)
        shadow = np.zeros((c, n), dtype=bool)
        for hh in (0.0, h):
            qx = ox + hh * ax_
            qy = oy + hh * ay_
            dist_out = np.maximum(np.maximum(x0p - qx, qx - x1p), np.maximum(y0p - qy, qy - y1p))
            shadow |= (dist_out > -0.05) & (dist_out < 0.8)
        # measurement effects
        d = h + rng.normal(0.0, sigma, (c, n)) if sigma > 0 else h.copy()
        lost = shadow
        if dropout > 0:
            p_start = dropout / 3.0
            run_starts = np.flatnonzero(rng.random(c * n) < p_start)
            lengths = rng.geometric(1.0 / 3.0, run_starts.size)
            tot = int(lengths.sum())
            if tot:
                first = np.repeat(np.cumsum(lengths) - lengths, lengths)
                idx = np.repeat(run_starts, lengths) + (np.arange(tot) - first)
                row_end = np.repeat((run_starts // n) * n + n - 1, lengths)
                idx = np.minimum(idx, row_end)
                runs = np.zeros(c * n, dtype=bool)
                runs[idx] = True
                lost = lost | runs.reshape(c, n)
        if flank_dropout > 0:
            lost = lost | (flank_all[f0:f1] & (rng.random((c, n)) < flank_dropout))
        if spike_rate > 0:
            sp = np.flatnonzero(rng.random(c * n) < spike_rate)
            mag = rng.uniform(0.05, 0.5, sp.size) * rng.choice([-1.0, 1.0], sp.size)
            d.ravel()[sp] += mag
        lo, hi = profiler.valid_range if profiler.valid_range is not None else (-np.inf, np.inf)
        lost |= (d < lo) | (d > hi)
        d[lost] = SENTINEL if profiler.sentinel is None else profiler.sentinel
        frames[f0:f1] = d

    # ---- truth per frame ---------------------------------------------------------------------
    center_u = np.zeros(nf)
    center_xy = np.zeros((nf, 2))
    for k, sh in enumerate(shapes):
        sel = np.flatnonzero(frame_contour == k)
        if sel.size == 0:
            continue
        ny = rot[sel, :, 1]  # SCS y axis in the WCS: normal of the laser plane
        tr = trans[sel]

        def plane_dist(u, k=k, ny=ny, tr=tr):
            xy = _engraved_xy(shapes[k], design.offsets[k], design.wiggle[k], u)
            zz = deflection(xy[:, 0], xy[:, 1])
            return (xy[:, 0] - tr[:, 0]) * ny[:, 0] + (xy[:, 1] - tr[:, 1]) * ny[:, 1] + (zz - tr[:, 2]) * ny[:, 2]

        u = frame_u[sel].copy()
        du = 1e-4
        for _ in range(20):
            g = plane_dist(u)
            dg = (plane_dist(u + du) - plane_dist(u - du)) / (2 * du)
            step_u = g / dg
            u = u - step_u
            if np.max(np.abs(step_u)) < 1e-12:
                break
        g = plane_dist(u)
        if np.max(np.abs(g)) > 1e-9:  # pragma: no cover - geometry guarantees convergence
            raise RuntimeError("groove_scan: groove center search did not converge")
        u = np.mod(u, sh.length)
        center_u[sel] = u
        center_xy[sel] = _engraved_xy(sh, design.offsets[k], design.wiggle[k], u)
    center_bend = deflection(center_xy[:, 0], center_xy[:, 1])
    center_wcs = np.column_stack([center_xy, center_bend])
    rel = center_wcs - trans
    center_scs = np.column_stack(
        [
            np.einsum("fi,fi->f", rot[:, :, 0], rel),
            np.einsum("fi,fi->f", rot[:, :, 2], rel),
        ]
    )
    width = np.zeros(nf)
    depth = np.zeros(nf)
    center_nominal = np.zeros((nf, 3))
    center_offset = np.zeros((nf, 3))
    center_local = np.zeros(nf)
    center_normal = np.zeros((nf, 3))
    for k, sh in enumerate(shapes):
        sel = frame_contour == k
        u = center_u[sel]
        width[sel] = design.width_profile[k](u)
        depth[sel] = design.depth_profile[k](u)
        center_nominal[sel, :2] = sh.point(u)
        center_offset[sel, :2] = design.offsets[k]
        center_local[sel] = design.wiggle[k](u)
        center_normal[sel, :2] = sh.normal(u)

    nominal_polylines = []
    engraved_polylines = []
    for k, sh in enumerate(shapes):
        m = max(math.ceil(sh.length / 0.05), 8)
        u = np.arange(m) * (sh.length / m)
        nominal_polylines.append(np.column_stack([sh.point(u), np.zeros(m)]))
        xy = _engraved_xy(sh, design.offsets[k], design.wiggle[k], u)
        engraved_polylines.append(np.column_stack([xy, deflection(xy[:, 0], xy[:, 1])]))

    params = {
        "generator": "machscan.synth.groove_scan",
        "seed": int(seed),
        "bend": float(bend),
        "readings": int(readings),
        "keep_every": keep_every,
        "feed": float(feed),
        "noise": float(sigma),
        "dropout": float(dropout),
        "flank_dropout": float(flank_dropout),
        "spike_rate": float(spike_rate),
        "axis_rate": float(axis_rate),
        "plate": list(PLATE),
        "plate_thickness": float(plate_thickness),
        "contours": [sh.describe() for sh in shapes],
    }
    scan = Scan(
        frames=frames,
        poses=poses,
        frame_times=frame_times,
        profiler=profiler,
        c2_offset=c2_offset,
        mount=mount,
        axis_times=axis_times,
        axis_samples=axis_samples_wrapped,
        metadata=params,
    )
    truth = GrooveTruth(
        frame_contour=frame_contour,
        frame_u=frame_u,
        center_u=center_u,
        center_scs=center_scs,
        center_wcs=center_wcs,
        width=width,
        depth=depth,
        center_nominal=center_nominal,
        center_offset=center_offset,
        center_local=center_local,
        center_normal=center_normal,
        center_bend=center_bend,
        contours=shapes,
        nominal_polylines=tuple(nominal_polylines),
        engraved_polylines=tuple(engraved_polylines),
        offsets=design.offsets,
        wiggle=design.wiggle,
        width_profile=design.width_profile,
        depth_profile=design.depth_profile,
        lip_profile=design.lip_profile,
        lip_asymmetry=design.lip_asymmetry,
        deflection=deflection,
        plate=PLATE,
        plate_thickness=float(plate_thickness),
        mount_true=mount_true,
        params=params,
    )
    return scan, truth


@dataclass(frozen=True)
class SurfaceError:
    """Heights of workpiece points against the true (bent) plate surface, away from the grooves.

    Attributes
    ----------
    n : int
        Number of points compared.
    mean, rms, max_abs : float
        Of ``e = z - w(x, y)`` (mm), spikes included.
    robust_sigma : float
        ``1.4826 * median(|e - median(e)|)`` (mm): the noise level, unaffected by spikes.
    n_outliers : int
        Points with ``|e| > outlier_threshold``.
    outlier_threshold : float
        mm (5 x the profiler noise by default).
    """

    n: int
    mean: float
    rms: float
    max_abs: float
    robust_sigma: float
    n_outliers: int
    outlier_threshold: float

    def __repr__(self) -> str:
        return (
            f"SurfaceError(n={self.n:,}, mean={self.mean * 1e3:.2f} um, "
            f"rms={self.rms * 1e3:.2f} um, robust sigma={self.robust_sigma * 1e3:.2f} um, "
            f"max |e|={self.max_abs * 1e3:.1f} um, {self.n_outliers} outliers "
            f"> {self.outlier_threshold * 1e3:.0f} um)"
        )


def surface_error(
    points,
    frame_index,
    truth: GrooveTruth,
    *,
    clearance: float = 1.0,
    edge_margin: float = 1.0,
    outlier_threshold: float | None = None,
) -> SurfaceError:
    """Compare workpiece points with the true bent surface, away from grooves and plate edges.

    A round-trip check of the kinematics on a synthetic scan: the points of the readings that
    hit the plain maskant should lie on ``truth.deflection`` within the profiler noise.

    Parameters
    ----------
    points : array_like, shape (M, 3)
        WCS points (mm), e.g. from ``scan.wcs_points()``.
    frame_index : array_like, shape (M,) or None
        Frame of every point (accepted for symmetry with ``wcs_points``; not needed).
    truth : GrooveTruth
    clearance : float
        Points closer than this to a CAD contour (plus its offset and wiggle bound), mm, are
        left out.
    edge_margin : float
        Points closer than this to the plate edge, or off the plate, are left out (mm).
    outlier_threshold : float, optional
        mm; default 5 x the generator's noise (or 0.04 mm for a noise-free scan).

    Returns
    -------
    SurfaceError
    """
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points: expected shape (M, 3), got {p.shape}")
    if frame_index is not None and np.shape(frame_index) != (p.shape[0],):
        raise ValueError(f"frame_index: expected shape ({p.shape[0]},), got {np.shape(frame_index)}")
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    x0, y0, x1, y1 = truth.plate
    keep = np.flatnonzero((x > x0 + edge_margin) & (x < x1 - edge_margin) & (y > y0 + edge_margin) & (y < y1 - edge_margin))
    # A 0.5 mm grid over the plate says which contour, if any, may be within reach of a cell;
    # the exact signed distance is then evaluated only for the points of those cells.
    cell = 0.5
    nx = math.ceil((x1 - x0) / cell)
    ny = math.ceil((y1 - y0) / cell)
    gx, gy = np.meshgrid(x0 + (np.arange(nx) + 0.5) * cell, y0 + (np.arange(ny) + 0.5) * cell, indexing="ij")
    owner = np.full((nx, ny), -1, dtype=np.int64)
    reach = np.zeros(len(truth.contours))
    for k, shape in enumerate(truth.contours):
        reach[k] = clearance + float(np.hypot(*truth.offsets[k])) + truth.wiggle[k].bound
        g = shape.signed_distance(np.stack([gx - truth.offsets[k, 0], gy - truth.offsets[k, 1]], axis=-1))
        owner[np.abs(g) < reach[k] + cell] = k  # cell half-diagonal < cell
    xk, yk = x[keep], y[keep]
    ix = np.clip(((xk - x0) * (1.0 / cell)).astype(np.int64), 0, nx - 1)
    iy = np.clip(((yk - y0) * (1.0 / cell)).astype(np.int64), 0, ny - 1)
    own = owner[ix, iy]
    away = np.ones(keep.size, dtype=bool)
    for k, shape in enumerate(truth.contours):
        sel = np.flatnonzero(own == k)
        if sel.size:
            sdf = shape.signed_distance(np.column_stack([xk[sel] - truth.offsets[k, 0], yk[sel] - truth.offsets[k, 1]]))
            away[sel[np.abs(sdf) < reach[k]]] = False
    keep = keep[away]
    e = z[keep] - truth.deflection(x[keep], y[keep])
    if outlier_threshold is None:
        sigma = float(truth.params.get("noise", 0.0))
        outlier_threshold = 5.0 * sigma if sigma > 0 else 0.04
    if e.size == 0:
        nan = float("nan")
        return SurfaceError(0, nan, nan, nan, nan, 0, float(outlier_threshold))
    med = float(np.median(e))
    return SurfaceError(
        n=int(e.size),
        mean=float(e.mean()),
        rms=float(np.sqrt(np.mean(e * e))),
        max_abs=float(np.abs(e).max()),
        robust_sigma=float(1.4826 * np.median(np.abs(e - med))),
        n_outliers=int(np.count_nonzero(np.abs(e) > outlier_threshold)),
        outlier_threshold=float(outlier_threshold),
    )


# --------------------------------------------------------------------------------------------
# Single groove frames of every shape
# --------------------------------------------------------------------------------------------

#: The groove shapes :func:`groove_frames` makes.
GROOVE_SHAPES = ("v", "u", "u_walls", "trapezoid")


def _fillet_polyline(pts, radii, arc_step=0.002):
    """The polyline through ``pts`` (K, 2) with interior vertex k rounded by a circular arc of
    radius ``radii[k]`` (0: sharp; reduced where the arc would not fit its segments)."""
    pts = np.asarray(pts, dtype=np.float64)
    out = [pts[0]]
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    for k in range(1, len(pts) - 1):
        r, p = radii[k], pts[k]
        a = (p - pts[k - 1]) / seg[k - 1]
        b = (pts[k + 1] - p) / seg[k]
        turn = math.acos(float(np.clip(a @ b, -1.0, 1.0)))
        if r <= 0 or turn < 1e-9:
            out.append(p)
            continue
        t = min(r * math.tan(turn / 2), 0.5 * min(seg[k - 1], seg[k]))
        r = t / math.tan(turn / 2)
        t1, t2 = p - a * t, p + b * t
        left = a[0] * b[1] - a[1] * b[0] > 0
        n = np.array([-a[1], a[0]]) if left else np.array([a[1], -a[0]])
        c = t1 + n * r
        a1 = math.atan2(t1[1] - c[1], t1[0] - c[0])
        a2 = math.atan2(t2[1] - c[1], t2[0] - c[0])
        da = (a2 - a1 + math.pi) % (2 * math.pi) - math.pi
        ang = a1 + da * np.linspace(0, 1, max(2, int(abs(da) * r / arc_step) + 1))
        out.extend(np.c_[c[0] + r * np.cos(ang), c[1] + r * np.sin(ang)])
    out.append(pts[-1])
    poly = np.array(out)
    # Densified so that the readings interpolate the section to well under a micrometre.
    steps = np.maximum(np.ceil(np.linalg.norm(np.diff(poly, axis=0), axis=1) / 0.002).astype(int), 1)
    dense = [poly[:1]]
    for q0, q1, m in zip(poly[:-1], poly[1:], steps):
        dense.append(q0 + (q1 - q0) * (np.arange(1, m + 1) / m)[:, None])
    return np.vstack(dense)


def _groove_polyline(shape: str, rng: np.random.Generator) -> tuple[np.ndarray, float]:
    """A groove section over |u| ≤ 4 mm (surface v = 0) and its width between the flanks at
    the surface (for a circular U, where the arc meets it)."""
    far = 4.0
    if shape == "v":
        while True:
            w, d = rng.uniform(0.2, 1.2), rng.uniform(0.05, 0.5)
            if 15 <= math.degrees(math.atan2(d, w / 2)) <= 70:
                break
        r_tip = 0.0 if rng.random() < 0.4 else rng.uniform(0.0, 0.05)
        r_top = 0.0 if rng.random() < 0.4 else rng.uniform(0.0, 0.03)
        pts = [(-far, 0), (-w / 2, 0), (0, -d), (w / 2, 0), (far, 0)]
        return _fillet_polyline(pts, [0, r_top, r_tip, r_top, 0]), w
    if shape == "trapezoid":
        while True:
            w, d, phi = rng.uniform(0.2, 1.2), rng.uniform(0.05, 0.5), rng.uniform(30, 80)
            run = d / math.tan(math.radians(phi))
            if w - 2 * run >= max(0.25 * w, 0.05):
                break
        r_bot = 0.0 if rng.random() < 0.4 else rng.uniform(0.0, 0.03)
        r_top = 0.0 if rng.random() < 0.4 else rng.uniform(0.0, 0.03)
        pts = [(-far, 0), (-w / 2, 0), (-w / 2 + run, -d), (w / 2 - run, -d), (w / 2, 0), (far, 0)]
        return _fillet_polyline(pts, [0, r_top, r_bot, r_bot, r_top, 0]), w
    if shape == "u":
        # A ball-end cutter: a circular arc of radius R, d ≤ R deep.
        while True:
            w = rng.uniform(0.2, 1.2)
            d = rng.uniform(0.05, min(0.5, w / 2))
            if d / w >= 0.1:
                break
        radius = (w * w / 4 + d * d) / (2 * d)
        a0 = math.asin(min(1.0, (w / 2) / radius))
        ang = np.linspace(-math.pi / 2 - a0, -math.pi / 2 + a0, 2000)
        arc = np.c_[radius * np.cos(ang), radius - d + radius * np.sin(ang)]
        arc[0], arc[-1] = (-w / 2, 0.0), (w / 2, 0.0)
        return np.vstack([[(-far, 0)], arc, [(far, 0)]]), w
    if shape == "u_walls":
        # Walls (vertical, or drafted up to 5°) tangent to a round bottom.
        while True:
            w = rng.uniform(0.2, 1.0)
            draft = math.radians(rng.uniform(0.0, 5.0)) if rng.random() < 0.7 else 0.0
            d_min = (w / 2) * math.cos(draft) / (1 + math.sin(draft))
            if d_min <= 0.48:
                d = rng.uniform(max(0.05, d_min), 0.5)
                break
        rho = (w / 2 - d * math.tan(draft)) * math.cos(draft) / (1 - math.sin(draft))
        ang = np.linspace(math.pi + draft, 2 * math.pi - draft, 2000)
        arc = np.c_[rho * np.cos(ang), -d + rho + rho * np.sin(ang)]
        r_top = 0.0 if rng.random() < 0.5 else rng.uniform(0.0, 0.03)
        left = _fillet_polyline(np.array([(-far, 0), (-w / 2, 0), tuple(arc[0]), tuple(arc[1])]), [0, r_top, 0, 0])[:-1]
        right = _fillet_polyline(np.array([tuple(arc[-2]), tuple(arc[-1]), (w / 2, 0), (far, 0)]), [0, 0, r_top, 0])[1:]
        return np.vstack([left, arc[1:-1], right]), w
    raise ValueError(f"shape: expected one of {', '.join(GROOVE_SHAPES)}, got {shape!r}")


def _topmost(px: np.ndarray, pz: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The highest point of the polyline on each vertical line x (NaN where there is none): an
    overhanging wall hides what lies below it, as it does from the sensor."""
    if np.all(np.diff(px) > 0):
        return np.interp(x, px, pz, left=np.nan, right=np.nan)
    xa, xb, za, zb = px[:-1], px[1:], pz[:-1], pz[1:]
    keep = xa != xb
    xa, xb, za, zb = xa[keep], xb[keep], za[keep], zb[keep]
    lo, hi = np.minimum(xa, xb), np.maximum(xa, xb)
    out = np.full(len(x), np.nan)
    for j, xj in enumerate(x):
        m = (lo <= xj) & (xj <= hi)
        if m.any():
            out[j] = np.max(za[m] + (xj - xa[m]) / (xb[m] - xa[m]) * (zb[m] - za[m]))
    return out


@dataclass(frozen=True, eq=False, repr=False)
class GrooveFrames:
    """Profiler frames across single grooves, with their exact truth (:func:`groove_frames`).

    Attributes
    ----------
    x : ndarray (N,)
        Reading abscissae, mm.
    z : ndarray (F, N)
        Readings, mm; NaN where a reading was lost.
    width : ndarray (F,)
        Distance between the flanks where they meet the surface line (straight flanks extended
        through any rounded top corner; a circular U where the arc meets the surface), mm.
    depth : ndarray (F,)
        Deepest point of the groove below the surface line, mm.
    center : ndarray (F, 2)
        (x, z) of the midpoint of the two crossings, in the frame, mm.
    tilt : ndarray (F,)
        Surface tilt, rad.
    shape : str
    """

    x: np.ndarray
    z: np.ndarray
    width: np.ndarray
    depth: np.ndarray
    center: np.ndarray
    tilt: np.ndarray
    shape: str

    def __repr__(self) -> str:
        return f"GrooveFrames({self.shape}: {len(self.z)} frames x {len(self.x)} readings)"


def groove_frames(
    shape: str,
    n: int,
    seed: int = 0,
    *,
    noise: float = 0.008,
    readings: int = 200,
    pitch: float = 0.025,
    max_tilt: float = 0.1,
    tilt_mode: str = "rotate",
    lips: float = 0.05,
    dropout: float = 0.03,
    flank_dropout: float = 0.15,
    spike_rate: float = 5e-4,
) -> GrooveFrames:
    """Frames across single grooves of one shape, with exact truth: the plants' groove shapes
    for testing a groove measurement (widths 0.2–1.2 mm, depths 0.05–0.5 mm).

    Shapes: ``"v"`` (flanks 15–70°, sharp or rounded tip up to 0.05 mm, top corners up to
    0.03 mm), ``"u"`` (a ball cutter's circular arc, depth ≤ radius), ``"u_walls"`` (vertical or
    drafted walls on a round bottom), ``"trapezoid"`` (flanks 30–80°, flat floor at least a
    quarter of the width, fillets up to 0.03 mm). Each frame: recast lips up to ``lips`` mm
    high just outside the edges (0 with probability 1/4, independent per side), the groove
    center within ±1 mm of the window center, a tilt up to ``max_tilt`` rad as a rotation
    (``tilt_mode="rotate"``) or as ``z += tan(tilt)·x`` (``"shear"``), a height offset up to
    ±0.5 mm; each reading the topmost point of the section on its vertical line, then Gaussian
    noise, dropouts (and more on flanks steeper than 0.5) and spikes of 0.2–1 mm.

    Examples
    --------
    >>> g = machscan.synth.groove_frames("v", 200, seed=1)
    >>> fits = machscan.fit_grooves(g.x, g.z)
    >>> np.median(np.abs(fits.width - g.width))
    """
    if tilt_mode not in ("rotate", "shear"):
        raise ValueError(f"tilt_mode: expected 'rotate' or 'shear', got {tilt_mode!r}")
    rng = np.random.default_rng(seed)
    x = (np.arange(readings) - readings // 2) * pitch
    z = np.empty((n, readings))
    width, depth, tilt, center = np.empty(n), np.empty(n), np.empty(n), np.empty((n, 2))
    for k in range(n):
        poly, w = _groove_polyline(shape, rng)
        depth[k] = -poly[:, 1].min()
        width[k] = w
        u, v = poly[:, 0], poly[:, 1].copy()
        if lips > 0:
            for side in (-1, 1):
                h = 0.0 if rng.random() < 0.25 else rng.uniform(0.0, lips)
                half = 0.5 * rng.uniform(0.05, 0.15)
                crest = side * (w / 2 + rng.uniform(-0.005, 0.02) + half)
                tau = (u - crest) / half
                v += h * np.where(np.abs(tau) < 1, (1 - tau * tau) ** 2, 0.0)
        theta = rng.uniform(-max_tilt, max_tilt)
        xc, z_off = rng.uniform(-1.0, 1.0), rng.uniform(-0.5, 0.5)
        if tilt_mode == "rotate":
            c, s = math.cos(theta), math.sin(theta)
            px, pz = xc + u * c - v * s, z_off + u * s + v * c
        else:
            px, pz = xc + u, z_off + v + math.tan(theta) * u
        zk = _topmost(px, pz, x)
        inside = np.abs(x - xc) < (w / 2) * math.cos(theta)
        with np.errstate(invalid="ignore", divide="ignore"):
            slope = np.abs(np.interp(x, px, np.gradient(pz, px))) if np.all(np.diff(px) > 0) else np.ones(readings)
        lost = rng.random(readings) < dropout
        lost |= inside & (slope > 0.5) & (rng.random(readings) < flank_dropout)
        zk = zk + noise * rng.standard_normal(readings)
        spikes = rng.random(readings) < spike_rate
        zk[spikes] += rng.choice([-1.0, 1.0], spikes.sum()) * rng.uniform(0.2, 1.0, spikes.sum())
        zk[lost] = np.nan
        z[k] = zk
        tilt[k] = theta
        center[k] = (xc, z_off)
    return GrooveFrames(x=x, z=z, width=width, depth=depth, center=center, tilt=tilt, shape=shape)


def flat_plate_scan(seed: int = 0, *, readings: int = 400, keep_every: int = 400, **kwargs) -> tuple[Scan, GrooveTruth]:
    """A small, quick :func:`groove_scan` of the unbent plate (about 360 frames of 400 readings).

    Keyword arguments are passed on to :func:`groove_scan` (``bend`` defaults to 0).
    """
    kwargs.setdefault("bend", 0.0)
    return groove_scan(seed, readings=readings, keep_every=keep_every, **kwargs)


def pocket_plate(seed: int = 0, *, spacing: float = 0.25, noise: float = 0.003, wall_angle: float = 90.0) -> np.ndarray:
    """A scanned pocket plate for simplification studies: sharp features and a free boundary.

    A 120 mm x 80 mm plate (top at z = 0) with a notch cut from its outline (x > 90, y > 55),
    a 3 mm deep pocket over ``(20, 70) x (15, 60)`` and a boss of radius 8 mm about (45, 37)
    rising to z = -1 inside it. Sampled as a height field, as a line laser from above sees it:
    a ``spacing`` grid jittered by +-30 % of the spacing, Gaussian height noise ``noise`` (mm).

    ``wall_angle`` (degrees from horizontal) drafts the pocket wall and the boss flank: 90 gives
    vertical steps (z jumps), smaller angles continuous surfaces with creases at the top and the
    foot of each wall.

    Returns the ``(N, 3)`` points, about 150 k at the default spacing.
    """
    if not 0.0 < wall_angle <= 90.0:
        raise ValueError(f"wall_angle must be in (0, 90] degrees, got {wall_angle}")
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.arange(0, 120, spacing), np.arange(0, 80, spacing))
    x = x.ravel() + rng.uniform(-0.3, 0.3, x.size) * spacing
    y = y.ravel() + rng.uniform(-0.3, 0.3, y.size) * spacing
    keep = ~((x > 90) & (y > 55))
    x, y = x[keep], y[keep]
    if wall_angle == 90.0:
        z = np.zeros_like(x)
        z[(x > 20) & (x < 70) & (y > 15) & (y < 60)] = -3.0
        z[(x - 45) ** 2 + (y - 37) ** 2 < 64] = -1.0
    else:
        slope = np.tan(np.radians(wall_angle))
        inside = np.minimum.reduce([x - 20, 70 - x, y - 15, 60 - y])
        pocket = -np.clip(inside * slope, 0.0, 3.0)
        boss = np.minimum(-1.0, -1.0 - (np.hypot(x - 45, y - 37) - 8) * slope)
        z = np.maximum(pocket, boss)
    return np.column_stack([x, y, z + rng.normal(0, noise, x.size)])
