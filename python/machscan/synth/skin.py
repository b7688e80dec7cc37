"""A thin skin that bends when it is clamped, with exact ground truth (paper 002, mirror milling).

The theoretical skin is a flat plate ``z = 0`` over ``[-length/2, length/2] × [-width/2, width/2]``. Clamped on
the mirror-milling machine it bends onto a cylinder of radius ``radius`` whose axis is parallel to y (so the
plate's middle line x = 0 keeps its place and the edges rise), and the whole part sits misplaced by a rigid
``pose``. Bending a plate onto a cylinder is an isometry: every point keeps its geodesic distances, which is
the assumption of isometric matching, and the true place of every theoretical point is known in closed form.

``second_radius`` bends it along y as well (a doubly curved, stretched skin): the map is then no isometry and
shows what isometric matching does when its assumption is broken.

A point offset from the skin (a pocket floor ``h`` below it, ``z = h`` in the theoretical frame) stays on the
normal of its foot: ``actual(u, v, h) = S(u, v) + h·n(u, v)``.

All lengths in mm. Pure NumPy (it does not use the compiled core), so its truth is independent of the code it
tests.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["BentSkin"]


def _identity() -> NDArray[np.float64]:
    return np.eye(4)


@dataclass(frozen=True)
class BentSkin:
    """A flat skin bent onto a cylinder (optionally also along y) and misplaced rigidly.

    Parameters
    ----------
    length, width : float
        Plate size in x and y, mm.
    radius : float
        Bend radius about an axis parallel to y, mm (``inf``: not bent).
    second_radius : float
        Bend radius along y, mm; finite values stretch the skin (not an isometry).
    pose : ndarray, shape (4, 4)
        Rigid misplacement, bent skin → machine.

    Examples
    --------
    >>> skin = BentSkin(radius=1000.0)
    >>> p, n = skin.actual([[150.0, 0.0, 0.0]])
    >>> round(float(p[0, 2]), 3)  # the edge rises by R (1 − cos(150/R))
    11.229
    """

    length: float = 300.0
    width: float = 200.0
    radius: float = 1000.0
    second_radius: float = float("inf")
    pose: NDArray[np.float64] = field(default_factory=_identity)

    def actual(self, theoretical: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Where theoretical points go: ``(x, y, h)`` of the flat plate (h off the skin along +z) →
        machine points and the skin's unit normals there (pointing to the side +z came to)."""
        t = np.atleast_2d(np.asarray(theoretical, dtype=np.float64))
        u, v, h = t[:, 0], t[:, 1], t[:, 2]
        s, n = self._bend(u, v)
        p = s + h[:, None] * n
        rot, shift = self.pose[:3, :3], self.pose[:3, 3]
        return p @ rot.T + shift, n @ rot.T

    def _bend(self, u: NDArray[np.float64], v: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        def arc(w: NDArray[np.float64], r: float) -> tuple[NDArray[np.float64], ...]:
            if np.isinf(r):
                return w, np.zeros_like(w), np.zeros_like(w)
            a = w / r
            # Position along, rise, and the slope angle of the bent line.
            return r * np.sin(a), r * (1.0 - np.cos(a)), a

        x, zx, ax = arc(u, self.radius)
        y, zy, ay = arc(v, self.second_radius)
        s = np.stack([x, y, zx + zy], axis=1)
        # Normal of the surface (x(u), y(v), zx(u) + zy(v)): ∂/∂u = (cos ax, 0, sin ax), ∂/∂v = (0, cos ay, sin ay).
        du = np.stack([np.cos(ax), np.zeros_like(ax), np.sin(ax)], axis=1)
        dv = np.stack([np.zeros_like(ay), np.cos(ay), np.sin(ay)], axis=1)
        n = np.cross(du, dv)
        return s, n / np.linalg.norm(n, axis=1, keepdims=True)

    def grid(self, spacing: float, *, margin: float = 0.0) -> NDArray[np.float64]:
        """Theoretical points ``(x, y, 0)`` on a grid of about ``spacing`` over the plate, ``margin``
        inside its edges."""
        if not (np.isfinite(spacing) and spacing > 0):
            raise ValueError(f"spacing: must be a positive finite number of mm, got {spacing}")
        nx = max(2, round((self.length - 2 * margin) / spacing) + 1)
        ny = max(2, round((self.width - 2 * margin) / spacing) + 1)
        x = np.linspace(-self.length / 2 + margin, self.length / 2 - margin, nx)
        y = np.linspace(-self.width / 2 + margin, self.width / 2 - margin, ny)
        xx, yy = np.meshgrid(x, y)
        return np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)], axis=1)

    def matching_grid(self, nx: int = 8, ny: int = 8, *, margin: float = 10.0) -> NDArray[np.float64]:
        """An ``nx × ny`` grid of theoretical matching points, ``margin`` inside the edges."""
        x = np.linspace(-self.length / 2 + margin, self.length / 2 - margin, nx)
        y = np.linspace(-self.width / 2 + margin, self.width / 2 - margin, ny)
        xx, yy = np.meshgrid(x, y)
        return np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)], axis=1)

    def locating(self, *, margin: float = 5.0) -> NDArray[np.float64]:
        """Two theoretical locating points, near opposite ends of the plate's middle line (where locating
        holes or pins usually are)."""
        a = self.length / 2 - margin
        return np.array([[-a, 0.0, 0.0], [a, 0.0, 0.0]])

    def scan(self, spacing: float = 1.3, noise: float = 0.005, *, seed: int = 0) -> NDArray[np.float64]:
        """The laser scan of the clamped skin: the bent plate sampled at ``spacing`` (along it), with
        Gaussian ``noise`` (σ, mm) along the machine's z."""
        p, _ = self.actual(self.grid(spacing))
        rng = np.random.default_rng(seed)
        p[:, 2] += rng.normal(0.0, noise, len(p))
        return p

    def raster(
        self, step: float = 10.0, spacing: float = 2.0, *, depth: float = 0.0, margin: float = 12.0
    ) -> NDArray[np.float64]:
        """A zigzag toolpath over the theoretical plate: rows ``step`` apart along x, points ``spacing`` apart
        along each row, ``depth`` off the skin (negative: into it), ``margin`` inside the edges."""
        ys = np.arange(-self.width / 2 + margin, self.width / 2 - margin + 1e-9, step)
        xs = np.arange(-self.length / 2 + margin, self.length / 2 - margin + 1e-9, spacing)
        rows = [
            np.stack([xs if k % 2 == 0 else xs[::-1], np.full(len(xs), y), np.full(len(xs), depth)], axis=1)
            for k, y in enumerate(ys)
        ]
        return np.concatenate(rows)
