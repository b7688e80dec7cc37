"""Kinematics (SPEC K): profiler frames and machine axis positions to workpiece points,
machine models as chains of elementary transforms, pose timing, and the sensor mount
calibration (SPEC K4) with its result object.

Invalid readings — NaN, the profiler's "no reading" code :data:`SENTINEL` (−99999 by default)
and anything outside a ``valid_range`` — are dropped by every function that makes points.

The formulas and their papers: ``docs/kinematics.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

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

if TYPE_CHECKING:
    from machscan.scan import Scan

__all__ = [
    "SENTINEL",
    "KinematicChain",
    "MountCalibration",
    "ab_mirror_support_points",
    "ac_head_transforms",
    "ac_table_rotate",
    "calibrate_mount",
    "calibrate_mount_sphere",
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
    """Result of :func:`calibrate_mount` and :func:`calibrate_mount_sphere`.

    Attributes
    ----------
    params : ndarray, shape (6,)
        Mount (theta, psi, phi, dx, dy, dz): Euler angles in rad
        (``R = Rz(phi) · Ry(theta) · Rx(psi)``) and translation in mm, in the order
        :func:`machscan.ac_head_transforms` takes as ``mount``.
    rms : float
        Root mean square of the residual distances, mm.
    std_errors : ndarray, shape (6,) or (9,)
        Standard errors from ``σ̂² (JᵀJ)⁻¹`` (``σ̂² = Σ r²`` over the degrees of freedom): of
        ``params``, then (sphere) of ``sphere_center``.
    covariance : ndarray, shape (6, 6) or (9, 9)
        In the same order.
    residuals : ndarray, shape (n,)
        Residual distance of each correspondence, or (sphere) each point's distance from the
        sphere (+ outside), mm.
    iterations : int
        Levenberg–Marquardt iterations.
    converged : bool
    sphere_center : ndarray, shape (3,), or None
        The reference sphere's centre in the WCS, mm (:func:`calibrate_mount_sphere`).
    frame_index : ndarray of int64, or None
        The frame of each residual (:func:`calibrate_mount_sphere`).
    """

    params: NDArray[np.float64]
    rms: float
    std_errors: NDArray[np.float64]
    covariance: NDArray[np.float64]
    residuals: NDArray[np.float64]
    iterations: int
    converged: bool
    sphere_center: NDArray[np.float64] | None = None
    frame_index: NDArray[np.int64] | None = None

    def summary(self) -> str:
        """A table of the parameters with their standard errors."""
        what = "points on the sphere" if self.sphere_center is not None else "correspondences"
        lines = [
            f"mount calibration: {len(self.residuals)} {what}, "
            f"rms {self.rms * 1000:.2f} µm, {'converged' if self.converged else 'NOT converged'}"
        ]
        for name, unit, v, s in zip(_NAMES, _UNITS, self.params, self.std_errors):
            if unit == "rad":
                lines.append(f"  {name:>5} = {v: .6f} rad   ± {s * 1e3:.4f} mrad")
            else:
                lines.append(f"  {name:>5} = {v: .4f} mm    ± {s * 1e3:.2f} µm")
        if self.sphere_center is not None:
            for axis, v, s in zip("xyz", self.sphere_center, self.std_errors[6:]):
                lines.append(f"  sphere {axis} = {v: .4f} mm ± {s * 1e3:.2f} µm")
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


def calibrate_mount_sphere(
    scan: Scan,
    radius: float,
    *,
    init: ArrayLike | None = None,
    sphere_center: ArrayLike | None = None,
) -> MountCalibration:
    """Sensor mount calibration with a reference sphere (SPEC K4, beyond paper 000): the way
    plants calibrate without a CMM. A sphere of known ``radius`` is scanned from several machine
    poses; every profile is an arc of it. The six mount parameters and the sphere's centre
    minimise the points' distances from the sphere, ``Σ (|WCS point − c| − R)²``, by
    Levenberg–Marquardt on the analytic Jacobian (``docs/kinematics.md``, K4).

    A sphere looks alike from every side: poses that always see it at the same place of the
    laser line and the same stand-off leave a turn of the sensor about the sphere unseen. Such a
    pose set is refused, naming the parameters it cannot tell apart and what to add: poses that
    turn the sensor differently (A, C, C2), the sphere at other places along the line and other
    stand-offs. Measured (tests): five poses, 8 µm noise: the mount within 5 µm and 0.05 mrad,
    the centre within 5 µm.

    Parameters
    ----------
    scan : Scan
        The sphere's scan: frames, the AC head's poses, the profiler, the C2 offset.
    radius : float
        The sphere's calibrated radius, mm.
    init : array_like, shape (6,), optional
        Start of the mount (theta, psi, phi, dx, dy, dz); default ``scan.mount`` (the nominal
        one). It need only be near: a few mrad and a millimetre.
    sphere_center : array_like, shape (3,), optional
        Start of the centre, mm; default the sphere fitted to the points at the start mount.

    Returns
    -------
    MountCalibration
        ``.params`` (the mount), ``.sphere_center``, ``.covariance`` (9 × 9: the mount, then the
        centre), ``.std_errors``, ``.rms``, ``.residuals`` per point, ``.frame_index``.

    Raises
    ------
    ValueError
        A pose set that does not determine the parameters (``scan: the poses do not determine
        …``), a radius that is not positive, fewer than nine valid readings.

    Examples
    --------
    >>> cal = machscan.calibrate_mount_sphere(sphere_scan, radius=12.7)
    >>> print(cal.summary())
    >>> calibrated = dataclasses.replace(scan, mount=cal.params)
    """
    p = scan.profiler
    out = _core.calibrate_mount_sphere(
        scan.frames,
        scan.poses,
        pitch=p.pitch,
        center=p.center,
        valid_range=p.valid_range,
        sentinel=p.sentinel,
        c2_offset=scan.c2_offset,
        radius=radius,
        mount=scan.mount if init is None else init,
        sphere_center=sphere_center,
    )
    return MountCalibration(**out)
