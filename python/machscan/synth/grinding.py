"""Allowance clouds with exact ground truth, for grinding paths (paper 004 §2–3).

* :class:`WavyPanel`: a panel ``z = amplitude · sin(2π y / wavelength)`` whose curvature across rows along x
  runs from convex to concave and back, with a smooth allowance field; :meth:`WavyPanel.cusp_heights` measures the
  cusps a path leaves between its rows by exact circle geometry on the true surface.
* :func:`blade_allowance`: the paper 003 airfoil (:class:`machscan.synth.Blade`) sampled with a smooth allowance
  field, as a registered blade scan hands it to grinding.

All lengths in mm. Pure NumPy (it does not use the compiled core), so its truth is independent of the code it
tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan.synth.blade import Blade

__all__ = ["AllowanceCloud", "WavyPanel", "blade_allowance"]


@dataclass(frozen=True, eq=False)
class AllowanceCloud:
    """Model points, their unit outward normals and the stock above them.

    Attributes
    ----------
    points : ndarray, shape (N, 3)
    normals : ndarray, shape (N, 3)
    allowance : ndarray, shape (N,)
    """

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    allowance: NDArray[np.float64]

    def blank(self) -> NDArray[np.float64]:
        """The blank's surface: each model point raised by its allowance along its normal."""
        return self.points + self.allowance[:, None] * self.normals

    def __repr__(self) -> str:
        a = self.allowance
        return f"AllowanceCloud({len(a)} points, allowance {a.min():.3f} … {a.max():.3f} mm)"


@dataclass(frozen=True)
class WavyPanel:
    """A panel ``z = amplitude · sin(2π y / wavelength)`` over ``[0, width] × [0, length]`` with the allowance
    ``mean + variation · sin(2π x / 50) · cos(2π y / 35)``.

    Rows along x (section normal ``(0, 1, 0)``) cross convex stretches (radius down to
    ``wavelength² / (4π² amplitude)``), concave ones of the same radius, and inflections.

    Examples
    --------
    >>> panel = WavyPanel()
    >>> round(panel.min_radius(), 2)
    20.26
    >>> cloud = panel.sample(0.5)
    >>> cloud.points.shape
    (13041, 3)
    """

    width: float = 40.0
    length: float = 80.0
    amplitude: float = 2.0
    wavelength: float = 40.0
    mean: float = 0.25
    variation: float = 0.08

    def _k(self) -> float:
        return 2.0 * math.pi / self.wavelength

    def height(self, y: ArrayLike) -> NDArray[np.float64]:
        return self.amplitude * np.sin(self._k() * np.asarray(y, dtype=float))

    def slope(self, y: ArrayLike) -> NDArray[np.float64]:
        return self.amplitude * self._k() * np.cos(self._k() * np.asarray(y, dtype=float))

    def curvature(self, y: ArrayLike) -> NDArray[np.float64]:
        """Curvature across rows along x, 1/mm: > 0 convex (seen from +z)."""
        y = np.asarray(y, dtype=float)
        second = -self.amplitude * self._k() ** 2 * np.sin(self._k() * y)
        return -second / (1.0 + self.slope(y) ** 2) ** 1.5

    def min_radius(self) -> float:
        return 1.0 / (self.amplitude * self._k() ** 2)

    def normals(self, y: ArrayLike) -> NDArray[np.float64]:
        s = self.slope(y)
        n = np.stack([np.zeros_like(s), -s, np.ones_like(s)], axis=-1)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def allowance_at(self, points: ArrayLike) -> NDArray[np.float64]:
        """The allowance field at the points' x, y."""
        p = np.asarray(points, dtype=float)
        return self.mean + self.variation * np.sin(2.0 * math.pi * p[..., 0] / 50.0) * np.cos(2.0 * math.pi * p[..., 1] / 35.0)

    def sample(self, spacing: float, *, noise: float = 0.0, seed: int = 0) -> AllowanceCloud:
        """The panel on a grid of ``spacing`` in x and y (jittered by up to a quarter spacing), with ``noise`` (mm,
        Gaussian) along the normal; the allowance is the field at the true point."""
        rng = np.random.default_rng(seed)
        x, y = np.meshgrid(np.arange(0.0, self.width + 1e-9, spacing), np.arange(0.0, self.length + 1e-9, spacing))
        x = np.clip(x.ravel() + rng.uniform(-0.25, 0.25, x.size) * spacing, 0.0, self.width)
        y = np.clip(y.ravel() + rng.uniform(-0.25, 0.25, y.size) * spacing, 0.0, self.length)
        points = np.stack([x, y, self.height(y)], axis=-1)
        normals = self.normals(y)
        allowance = self.allowance_at(points)
        points = points + rng.normal(0.0, noise, len(points))[:, None] * normals if noise > 0 else points
        return AllowanceCloud(points, normals, allowance)

    def cusp_heights(self, points: ArrayLike, normals: ArrayLike, row: ArrayLike, tool_radius: float) -> NDArray[np.float64]:
        """The highest cusp between each pair of neighbouring rows of a path (rows along x), mm.

        The surface does not change along x, so the cut across the rows is the curve ``z = height(y)``: at each
        path point of row k the wheel is the circle of ``tool_radius`` about ``point + R·normal`` (the path's own
        point and normal), and the point of row k + 1 nearest in x gives the other circle. The cusp is where the two
        circles meet, and its height is its distance to the true curve (densely sampled and refined).
        """
        p, n, row = np.asarray(points, float), np.asarray(normals, float), np.asarray(row)
        r = float(tool_radius)
        out = []
        for k in range(int(row.max())):
            a, b = p[row == k], p[row == k + 1]
            na, nb = n[row == k], n[row == k + 1]
            pair = np.abs(a[:, None, 0] - b[None, :, 0]).argmin(axis=1)
            ca = a[:, 1:] + r * na[:, 1:]
            cb = b[pair][:, 1:] + r * nb[pair][:, 1:]
            mid, half = 0.5 * (ca + cb), 0.5 * np.linalg.norm(cb - ca, axis=1)
            across = (cb - ca) / (2.0 * half[:, None])
            side = np.stack([across[:, 1], -across[:, 0]], axis=1)  # ⟂, toward −z: the surface side
            cusp = mid + np.sqrt(r * r - half**2)[:, None] * side
            out.append(max(self._distance(c) for c in cusp))
        return np.asarray(out)

    def _distance(self, q: NDArray[np.float64]) -> float:
        """Signed distance from the point ``q = (y, z)`` to the curve (positive above it)."""
        y = np.linspace(q[0] - 3.0, q[0] + 3.0, 6001)
        for _ in range(3):
            d2 = (y - q[0]) ** 2 + (self.height(y) - q[1]) ** 2
            i = int(d2.argmin())
            y = np.linspace(y[max(i - 2, 0)], y[min(i + 2, len(y) - 1)], 2001)
        d = math.sqrt(float(d2.min()))
        return d if q[1] > float(self.height(q[0])) else -d


def blade_allowance(
    blade: Blade | None = None,
    spacing: float = 0.5,
    *,
    mean: float = 0.3,
    variation: float = 0.1,
    span: tuple[float, float] = (0.05, 0.95),
    seed: int = 0,
) -> AllowanceCloud:
    """A blade's surface sampled about every ``spacing`` mm (sections at ``v`` in ``span``), with the allowance
    ``mean + variation · (0.6 sin 2π(2u + 0.3v + φ) + 0.4 cos 2π(1.5v + u))`` (φ from ``seed``), smooth and
    periodic round the section.

    Examples
    --------
    >>> cloud = blade_allowance(spacing=2.0)
    >>> bool(cloud.allowance.min() > 0.15)
    True
    """
    blade = Blade() if blade is None else blade
    pts, _ = blade.sample(2000, 2)
    perimeter = float(np.linalg.norm(np.diff(pts[:, 0], axis=0, append=pts[:1, 0]), axis=1).sum())
    nu = max(int(perimeter / spacing), 8)
    nv = max(int(blade.span * (span[1] - span[0]) / spacing), 2) + 1
    u = np.arange(nu) / nu
    v = np.linspace(span[0], span[1], nv)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    points, normals = blade.surface(uu, vv)
    phase = np.random.default_rng(seed).uniform(0.0, 1.0)
    a = mean + variation * (
        0.6 * np.sin(2.0 * math.pi * (2.0 * uu + 0.3 * vv + phase)) + 0.4 * np.cos(2.0 * math.pi * (1.5 * vv + uu))
    )
    return AllowanceCloud(points.reshape(-1, 3), normals.reshape(-1, 3), a.ravel())
