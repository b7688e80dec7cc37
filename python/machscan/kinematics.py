"""Kinematics (SPEC K): profiler frames and machine axis positions to workpiece points,
machine models as chains of elementary transforms, pose timing, and the sensor mount
calibration (SPEC K4) with its result object.

Invalid readings — NaN, the profiler's "no reading" code :data:`SENTINEL` (−99999 by default)
and anything outside a ``valid_range`` — are dropped by every function that makes points.

The formulas and their papers: ``docs/kinematics.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from machscan import _core
from machscan._core import (
    KinematicChain,
    ab_mirror_support_points,
    ac_head_transforms,
    ac_table_rotate,
    interpolate_poses,
    profile_to_points,
    scan_to_wcs,
)

__all__ = [
    "SENTINEL",
    "KinematicChain",
    "MountCalibration",
    "ab_mirror_support_points",
    "ac_head_transforms",
    "ac_table_rotate",
    "calibrate_mount",
    "interpolate_poses",
    "profile_to_points",
    "scan_to_wcs",
]

#: The "no reading" code of the SR7140 / LJ family of profilers, mm: dropped by default.
SENTINEL: float = _core.SENTINEL

_NAMES = ("theta", "psi", "phi", "dx", "dy", "dz")
_UNITS = ("rad", "rad", "rad", "mm", "mm", "mm")


@dataclass(frozen=True, eq=False, repr=False)
class MountCalibration:
    """Result of :func:`calibrate_mount`.

    Attributes
    ----------
    params : ndarray, shape (6,)
        Mount (theta, psi, phi, dx, dy, dz): Euler angles in rad
        (``R = Rz(phi) · Ry(theta) · Rx(psi)``) and translation in mm, in the order
        :func:`machscan.ac_head_transforms` takes as ``mount``.
    rms : float
        Root mean square of the 3D residual distances, mm.
    std_errors : ndarray, shape (6,)
        Standard errors of ``params`` from ``σ̂² (JᵀJ)⁻¹``, ``σ̂² = Σ r² / (3n − 6)``.
    covariance : ndarray, shape (6, 6)
    residuals : ndarray, shape (n,)
        Residual distance of each correspondence, mm.
    iterations : int
        Levenberg–Marquardt iterations after the Kabsch start.
    converged : bool
    """

    params: NDArray[np.float64]
    rms: float
    std_errors: NDArray[np.float64]
    covariance: NDArray[np.float64]
    residuals: NDArray[np.float64]
    iterations: int
    converged: bool

    def summary(self) -> str:
        """A table of the parameters with their standard errors."""
        lines = [
            f"mount calibration: {len(self.residuals)} correspondences, "
            f"rms {self.rms * 1000:.2f} µm, {'converged' if self.converged else 'NOT converged'}"
        ]
        for name, unit, v, s in zip(_NAMES, _UNITS, self.params, self.std_errors):
            if unit == "rad":
                lines.append(f"  {name:>5} = {v: .6f} rad   ± {s * 1e3:.4f} mrad")
            else:
                lines.append(f"  {name:>5} = {v: .4f} mm    ± {s * 1e3:.2f} µm")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (
            f"MountCalibration(params={np.array2string(self.params, precision=6)}, "
            f"rms={self.rms:.4g} mm, converged={self.converged})"
        )


def calibrate_mount(
    scs_points: ArrayLike,
    wcs_points: ArrayLike,
    axes: ArrayLike | None = None,
    c2_offset: ArrayLike | None = None,
) -> MountCalibration:
    """Recover the profiler mount from SCS ↔ WCS correspondences (SPEC K4, paper 000 eq 9–10).

    The same physical points are seen by the profiler (SCS, all with y = 0) and measured
    independently in the WCS (e.g. a CMM-measured calibration block). Every WCS point is first
    brought into the C2 frame with its known machine pose; a Kabsch fit gives the start and a
    Levenberg–Marquardt solve on the exact Euler form ``Rz(phi)·Ry(theta)·Rx(psi)`` the
    answer. A plain linear solve is not used: with y = 0 everywhere it cannot fix the rotation.

    Limits: the points must not be collinear (a profile of a flat face is a line: use a block
    with steps or a V, or several poses). Precision scales with noise / (spread · √n).

    Parameters
    ----------
    scs_points : array_like, shape (n, 3)
        Profiler points in the SCS, mm.
    wcs_points : array_like, shape (n, 3)
        The same points in the WCS, mm.
    axes : array_like, shape (n, 6), optional
        Machine pose X, Y, Z, A, C, C2 (mm, rad) at which each point was seen. Default: all
        axes at zero and no C2 offset, i.e. WCS = mount · SCS.
    c2_offset : array_like, shape (3,), optional
        (Lx, Ly, Lz) of the C2 axis, mm, used with ``axes``.

    Returns
    -------
    MountCalibration
        ``.params`` (theta, psi, phi, dx, dy, dz), ``.rms``, ``.std_errors``, ...

    Examples
    --------
    >>> cal = machscan.calibrate_mount(scs, wcs)
    >>> print(cal.summary())
    """
    out = _core.calibrate_mount(scs_points, wcs_points, axes=axes, c2_offset=c2_offset)
    return MountCalibration(**out)
