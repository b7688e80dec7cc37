"""A reference sphere scanned from several poses of the AC head: the data of the sphere mount
calibration (:func:`machscan.calibrate_mount_sphere`), with its truth."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from machscan import _core
from machscan.scan import Profiler, Scan
from machscan.synth.grooves import DEFAULT_C2_OFFSET, DEFAULT_MOUNT

__all__ = ["SPHERE_POSES", "SphereTruth", "sphere_scan"]

#: Head orientations (A, C, C2), rad: tilted and turned so that the sensor sees the sphere from
#: different sides.
SPHERE_POSES = np.radians(
    [[0, 0, 0], [30, 0, 0], [30, 90, 0], [30, 180, 45], [45, 270, 90], [-20, 45, -30], [15, 135, 60], [40, 300, -60]]
)

#: Where the sphere's centre is put in the sensor's frame at each pose: along the laser line
#: (x) and away from the sensor (stand-off, z), mm. Three places, so that no turn of the sensor
#: about the sphere goes unseen.
SPHERE_SPOTS = ((-8.0, 52.0), (0.0, 60.0), (8.0, 68.0))


@dataclass(frozen=True)
class SphereTruth:
    """The truth of :func:`sphere_scan`: the mount, the sphere's centre (mm) and radius (mm)."""

    mount: np.ndarray
    center: np.ndarray
    radius: float


def sphere_scan(
    poses: int = 5,
    *,
    radius: float = 12.7,
    center: tuple[float, float, float] = (200.0, 100.0, -50.0),
    noise: float = 0.008,
    sweeps: int = 5,
    seed: int = 0,
) -> tuple[Scan, SphereTruth]:
    """A sphere of ``radius`` scanned by an SR7140-like profiler (801 readings, 0.05 mm) on the
    AC head from the first ``poses`` of :data:`SPHERE_POSES` (1–8), at each pose at the three
    :data:`SPHERE_SPOTS`, ``sweeps`` frames 3 mm apart across the line at each; heights with
    Gaussian ``noise`` (mm). The scan's ``mount`` is the nominal one (zero angles, the true
    translation rounded to the mm); the truth is :data:`DEFAULT_MOUNT`."""
    if not 1 <= poses <= len(SPHERE_POSES):
        raise ValueError(f"poses: 1 to {len(SPHERE_POSES)}, got {poses}")
    rng = np.random.default_rng(seed)
    mount = np.asarray(DEFAULT_MOUNT, dtype=np.float64)
    c2 = np.asarray(DEFAULT_C2_OFFSET, dtype=np.float64)
    c = np.asarray(center, dtype=np.float64)
    profiler = Profiler(readings=801, pitch=0.05, name="SR7140-like")
    x = profiler.x
    rows, frames = [], []
    for a, cc, c2a in SPHERE_POSES[:poses]:
        t0 = _core.ac_head_transforms(np.array([[0, 0, 0, a, cc, c2a]]), c2, mount)[0]
        for spot_x, standoff in SPHERE_SPOTS:
            for s in np.linspace(-6.0, 6.0, sweeps):
                want = c + t0[:3, :3] @ np.array([spot_x, s, standoff])
                pose = np.array([*(want - t0[:3, 3]), a, cc, c2a])
                t = np.linalg.inv(_core.ac_head_transforms(pose[None], c2, mount)[0])
                cs = t[:3, :3] @ c + t[:3, 3]
                h = radius**2 - (x - cs[0]) ** 2 - cs[1] ** 2
                with np.errstate(invalid="ignore"):
                    d = np.where(h > 0, cs[2] + np.sqrt(h), np.nan)
                frames.append(d + rng.normal(0.0, noise, len(x)))
                rows.append(pose)
    nominal = np.array([0.0, 0.0, 0.0, *np.round(mount[3:])])
    scan = Scan(np.array(frames), np.array(rows), np.arange(len(rows)) * 0.01, profiler, c2, nominal)
    return scan, SphereTruth(mount=mount, center=c, radius=radius)
