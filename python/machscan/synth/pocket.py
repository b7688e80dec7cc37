"""A pocketed plate (steps with vertical or sloped walls) scanned as a height field, for the
octree simplification's quality against a voxel grid. Pure NumPy.
"""

from __future__ import annotations

import numpy as np

__all__ = ["pocket_plate"]


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
