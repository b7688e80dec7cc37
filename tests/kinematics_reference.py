"""Vectorised NumPy reference for the machscan kinematics (SPEC K1-K3, K7).

This module is the independent reference that the tests compare the Rust core with, and the
"vectorised NumPy" side of the kinematics benchmark. It must never import machscan.

Conventions (identical to the Rust core):

* Units: millimetres and radians, float64.
* A profiler frame is ``N`` readings ``d_i``; reading ``i`` is the SCS point
  ``((i - i0) * pitch, 0, d_i)`` with ``i0 = N / 2`` unless given. ``d`` is a height: SCS z
  points out of the material towards the sensor.
* A reading is valid when it is finite and, if ``valid_range = (lo, hi)`` is given,
  ``lo <= d <= hi`` (bounds inclusive). Invalid readings are dropped.
* AC double-swing head with sixth axis C2 (SPEC K2, K3); ``axes`` columns are
  ``X, Y, Z, A, C, C2``, ``c2_offset = (Lx, Ly, Lz)``,
  ``mount = (theta, psi, phi, dx, dy, dz)``::

      T = [Rz(C) Rx(A), (X, Y, Z)] . [Rz(C2), (Lx, Ly, Lz)] . [Rz(phi) Ry(theta) Rx(psi), (dx, dy, dz)]

  is the WCS <- SCS homogeneous transform of one frame.
* Points come out frame-major, then by reading index, invalid readings dropped, with the frame
  index of every point (int64).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "ac_head_transforms_np",
    "interpolate_poses_np",
    "mount_rotation",
    "mount_transform",
    "profile_to_points_np",
    "reading_x",
    "rot_x",
    "rot_y",
    "rot_z",
    "scan_to_wcs_np",
    "valid_mask_np",
]


def _rot(angle, axis: int) -> np.ndarray:
    a = np.asarray(angle, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(a.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def rot_x(angle) -> np.ndarray:
    """Right-handed rotation about x by ``angle`` (rad); shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 0)


def rot_y(angle) -> np.ndarray:
    """Right-handed rotation about y by ``angle`` (rad); shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 1)


def rot_z(angle) -> np.ndarray:
    """Right-handed rotation about z by ``angle`` (rad); shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 2)


def mount_rotation(theta, psi, phi) -> np.ndarray:
    """Sensor mount rotation ``Rz(phi) @ Ry(theta) @ Rx(psi)`` (SPEC K3, paper 000 eq (8) fixed).

    theta is the nutation, psi the precession, phi the spin angle, all in rad.
    """
    return rot_z(phi) @ rot_y(theta) @ rot_x(psi)


def mount_transform(mount) -> np.ndarray:
    """4x4 homogeneous C2 <- SCS transform from ``mount = (theta, psi, phi, dx, dy, dz)``."""
    m = np.asarray(mount, dtype=np.float64).reshape(6)
    out = np.eye(4)
    out[:3, :3] = mount_rotation(m[0], m[1], m[2])
    out[:3, 3] = m[3:6]
    return out


def ac_head_transforms_np(axes, c2_offset, mount) -> np.ndarray:
    """WCS <- SCS transforms of an AC head with sixth axis C2, for every frame.

    Parameters
    ----------
    axes : array_like, shape (F, 6)
        ``X, Y, Z`` (mm), ``A, C, C2`` (rad) per frame.
    c2_offset : array_like, shape (3,)
        ``(Lx, Ly, Lz)``, origin of the C2 frame in the tool frame (mm).
    mount : array_like, shape (6,)
        ``(theta, psi, phi, dx, dy, dz)`` (rad, mm), the SCS pose in the C2 frame.

    Returns
    -------
    ndarray, shape (F, 4, 4)
    """
    ax = np.asarray(axes, dtype=np.float64)
    if ax.ndim != 2 or ax.shape[1] != 6:
        raise ValueError(f"axes: expected shape (F, 6), got {ax.shape}")
    L = np.asarray(c2_offset, dtype=np.float64).reshape(3)
    m = np.asarray(mount, dtype=np.float64).reshape(6)
    rm = mount_rotation(m[0], m[1], m[2])  # (3, 3)
    rt = rot_z(ax[:, 4]) @ rot_x(ax[:, 3])  # (F, 3, 3)
    rc2 = rot_z(ax[:, 5])  # (F, 3, 3)
    rtc = rt @ rc2
    out = np.zeros((ax.shape[0], 4, 4))
    out[:, :3, :3] = rtc @ rm
    # t = Rt (Rc2 d + L) + P
    inner = rc2 @ m[3:6] + L  # (F, 3)
    out[:, :3, 3] = np.einsum("fij,fj->fi", rt, inner) + ax[:, :3]
    out[:, 3, 3] = 1.0
    return out


def reading_x(n: int, pitch: float, center: float | None = None) -> np.ndarray:
    """SCS x of the ``n`` readings of a frame: ``(i - i0) * pitch`` (mm), ``i0 = n / 2`` default."""
    i0 = n / 2.0 if center is None else float(center)
    return (np.arange(n, dtype=np.float64) - i0) * float(pitch)


def valid_mask_np(frames, valid_range=None) -> np.ndarray:
    """Boolean mask of valid readings: finite and inside ``valid_range`` (inclusive) if given."""
    d = np.asarray(frames, dtype=np.float64)
    mask = np.isfinite(d)
    if valid_range is not None:
        lo, hi = valid_range
        with np.errstate(invalid="ignore"):
            mask &= (d >= lo) & (d <= hi)
    return mask


def profile_to_points_np(frames, pitch, center=None, valid_range=None):
    """SCS points of all valid readings (SPEC K1).

    Returns
    -------
    points : ndarray, shape (M, 3)
        ``((i - i0) * pitch, 0, d_i)`` in mm, frame-major then reading order.
    frame_index : ndarray of int64, shape (M,)
    """
    d = np.asarray(frames, dtype=np.float64)
    if d.ndim != 2:
        raise ValueError(f"frames: expected shape (F, N), got {d.shape}")
    mask = valid_mask_np(d, valid_range)
    fi, ii = np.nonzero(mask)
    x = reading_x(d.shape[1], pitch, center)
    pts = np.zeros((fi.size, 3))
    pts[:, 0] = x[ii]
    pts[:, 2] = d[fi, ii]
    return pts, fi.astype(np.int64)


def scan_to_wcs_np(frames, axes, pitch, c2_offset, mount, center=None, valid_range=None):
    """Workpiece (WCS) points of all valid readings of a scan (SPEC K1-K3).

    Vectorised over frames and readings: one transform per frame, then one gather per
    coordinate; no Python loop over frames.

    Parameters
    ----------
    frames : array_like, shape (F, N)
        Heights in mm; NaN or outside ``valid_range`` means invalid.
    axes : array_like, shape (F, 6)
        ``X, Y, Z`` (mm), ``A, C, C2`` (rad) at each frame.
    pitch : float
        Reading spacing along the laser line (mm).
    c2_offset, mount : array_like
        See :func:`ac_head_transforms_np`.
    center : float, optional
        Center reading index ``i0``; default ``N / 2``.
    valid_range : (float, float), optional
        Inclusive measuring range (mm).

    Returns
    -------
    points : ndarray, shape (M, 3)
        WCS points (mm), frame-major then reading order.
    frame_index : ndarray of int64, shape (M,)
    """
    d = np.asarray(frames, dtype=np.float64)
    if d.ndim != 2:
        raise ValueError(f"frames: expected shape (F, N), got {d.shape}")
    ax = np.asarray(axes, dtype=np.float64)
    if ax.shape != (d.shape[0], 6):
        raise ValueError(f"axes: expected shape ({d.shape[0]}, 6), got {ax.shape}")
    T = ac_head_transforms_np(ax, c2_offset, mount)
    mask = valid_mask_np(d, valid_range)
    fi, ii = np.nonzero(mask)
    x = reading_x(d.shape[1], pitch, center)[ii]
    z = d[fi, ii]
    pts = np.empty((fi.size, 3))
    for k in range(3):
        pts[:, k] = T[fi, k, 0] * x + T[fi, k, 2] * z + T[fi, k, 3]
    return pts, fi.astype(np.int64)


def interpolate_poses_np(sample_times, samples, frame_times, rotary=(3, 4, 5)) -> np.ndarray:
    """Axis positions at frame times by linear interpolation (SPEC K7).

    Rotary columns are unwrapped (``np.unwrap``, period 2 pi) before interpolating, so the
    result is continuous; it is not wrapped back. Frame times outside the sample span take
    the end values (``np.interp`` semantics).
    """
    t = np.asarray(sample_times, dtype=np.float64)
    s = np.array(samples, dtype=np.float64)
    if s.ndim != 2 or s.shape[0] != t.shape[0]:
        raise ValueError(f"samples: expected shape ({t.shape[0]}, n_axes), got {s.shape}")
    ft = np.asarray(frame_times, dtype=np.float64)
    for c in rotary:
        s[:, c] = np.unwrap(s[:, c])
    out = np.empty((ft.shape[0], s.shape[1]))
    for c in range(s.shape[1]):
        out[:, c] = np.interp(ft, t, s[:, c])
    return out
