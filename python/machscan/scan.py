"""Raw line-laser scans: the profiler model, the scan container, and its file formats.

A *scan* is what an on-machine measurement records (SPEC K1, K7; paper 000 §1-2): ``F``
profiler frames of ``N`` readings each, the machine axis positions ``X, Y, Z, A, C, C2`` at
every frame time, the C2 offset and the calibrated sensor mount, optionally the raw CNC axis
samples at their own rate, and free-form metadata.

Conventions (shared with the Rust core):

* Units are millimetres, radians and seconds, float64.
* Reading ``i`` of a frame is the SCS point ``((i - i0) * pitch, 0, d_i)``: the laser line runs
  along SCS x, ``d_i`` is a *height* along SCS z, which points out of the material towards the
  sensor, so an engraved groove appears as a dip (smaller ``d``).
* A reading is invalid when it is NaN, equal to the profiler's sentinel, or outside
  ``valid_range = (lo, hi)`` (bounds inclusive). Invalid readings never become points.

The methods that compute points call the compiled core (``machscan.profile_to_points`` /
``machscan.scan_to_wcs``).

Building a scan from your own data: a ``Scan`` takes NumPy arrays of frames, poses and frame
times with a :class:`Profiler` and the machine's C2 offset and mount; a CSV export (one frame per
row, one pose per row) is read by :func:`read_scan_csv`.

The formulas and their papers: ``docs/kinematics.md``.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "SENTINEL",
    "Profiler",
    "Scan",
    "read_profiles",
    "read_scan_csv",
    "write_scan_csv",
]

from machscan import _core

#: Value a profiler returns for a reading it could not take (the SR7140 / LJ "no data" code);
#: the default sentinel of :class:`Profiler` and of every function that makes points.
SENTINEL: float = _core.SENTINEL

#: Version of the ``.npz`` layout written by :meth:`Scan.save`.
_NPZ_VERSION = 1

_AXES = ("X", "Y", "Z", "A", "C", "C2")


# --------------------------------------------------------------------------------------------
# Profiler
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Profiler:
    """A 2D line-laser profiler (SPEC K1).

    Parameters
    ----------
    readings : int
        Number of readings ``N`` per frame (points along the laser line).
    pitch : float
        Spacing of the readings along the line, mm (the x-resolution ``delta``).
    center : float, optional
        Index ``i0`` of the reading at SCS x = 0. ``None`` means ``N / 2`` (paper 000 eq (5)).
    valid_range : (float, float), optional
        Measuring range ``(lo, hi)`` in mm along SCS z; readings outside it (bounds inclusive)
        are invalid. ``None``: every finite reading is valid.
    sentinel : float, optional
        The "no data" code the profiler writes for readings it could not take; default
        :data:`SENTINEL` (−99999, a height no real reading has, so the default is safe for
        profilers that write NaN too). ``None`` keeps every finite value as a reading.
        Readings equal to the sentinel are invalid whether or not ``valid_range`` is set.
    name : str
        Model name, for reports.
    noise : float, optional
        One-sigma height noise of a reading, mm (a profiler fact, used by synthetic scans and
        by fit diagnostics; not used by the kinematics).
    frame_rate : float, optional
        Maximum frame rate, frames per second.

    Notes
    -----
    The laser line direction is fixed as SCS x and the measuring direction as SCS z
    (:attr:`line_direction`, :attr:`measuring_direction`). A profiler whose line runs along
    another axis (paper 002's sensor runs along the tool Y axis) is described by folding that
    rotation into the mount.

    Examples
    --------
    >>> p = Profiler.sr7140()
    >>> p.readings, p.pitch, p.i0
    (3200, 0.025, 1600.0)
    >>> float(p.x[0]), float(p.x[-1])
    (-40.0, 39.975)
    """

    readings: int
    pitch: float
    center: float | None = None
    valid_range: tuple[float, float] | None = None
    sentinel: float | None = SENTINEL
    name: str = "profiler"
    noise: float | None = None
    frame_rate: float | None = None

    #: The laser line runs along SCS x (fixed).
    line_direction = "x"
    #: Heights are measured along SCS z, pointing towards the sensor (fixed).
    measuring_direction = "z"

    def __post_init__(self) -> None:
        n = self.readings
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"readings: expected a positive integer, got {n!r}")
        object.__setattr__(self, "readings", int(n))
        pitch = _finite_float(self.pitch, "pitch")
        if pitch <= 0.0:
            raise ValueError(f"pitch: expected a positive spacing in mm, got {pitch!r}")
        object.__setattr__(self, "pitch", pitch)
        if self.center is not None:
            object.__setattr__(self, "center", _finite_float(self.center, "center"))
        if self.valid_range is not None:
            vr = tuple(self.valid_range)
            if len(vr) != 2:
                raise ValueError(f"valid_range: expected (lo, hi), got {self.valid_range!r}")
            lo, hi = _finite_float(vr[0], "valid_range"), _finite_float(vr[1], "valid_range")
            if not lo < hi:
                raise ValueError(f"valid_range: expected lo < hi, got ({lo!r}, {hi!r})")
            object.__setattr__(self, "valid_range", (lo, hi))
        if self.sentinel is not None:
            s = float(self.sentinel)
            object.__setattr__(self, "sentinel", None if math.isnan(s) else s)
        for name in ("noise", "frame_rate"):
            v = getattr(self, name)
            if v is not None:
                v = _finite_float(v, name)
                if v < 0.0 or (name == "frame_rate" and v == 0.0):
                    raise ValueError(f"{name}: expected a positive value, got {v!r}")
                object.__setattr__(self, name, v)
        object.__setattr__(self, "name", str(self.name))

    @classmethod
    def sr7140(cls, readings: int = 3200) -> Profiler:
        """An SR7140-like profiler, as used in paper 000 §3.

        3200 readings at 0.025 mm pitch (an 80 mm line), Z accuracy +-0.024 mm in the paper,
        modelled as Gaussian noise of sigma 0.008 mm (the +-0.024 mm read as a 3-sigma band,
        which matches the paper's fit precision of 0.0081 mm), up to 2500 frames/s (paper 000
        §2.2). The sentinel is :data:`SENTINEL`; the measuring range ``(-20, 20)`` mm around the
        reference plane is an assumption (the paper does not give it).

        Parameters
        ----------
        readings : int
            Number of readings; fewer than 3200 models a cropped line (region of interest),
            same pitch, centered.
        """
        return cls(
            readings=readings,
            pitch=0.025,
            center=None,
            valid_range=(-20.0, 20.0),
            sentinel=SENTINEL,
            name="SR7140",
            noise=0.008,
            frame_rate=2500.0,
        )

    @property
    def i0(self) -> float:
        """Center index (reading at SCS x = 0): ``center`` or ``readings / 2``."""
        return self.readings / 2.0 if self.center is None else float(self.center)

    @property
    def x(self) -> np.ndarray:
        """SCS x of every reading, ``(i - i0) * pitch`` in mm, shape (N,)."""
        return (np.arange(self.readings, dtype=np.float64) - self.i0) * self.pitch

    @property
    def line_length(self) -> float:
        """Length covered by the readings, ``(N - 1) * pitch`` (mm)."""
        return (self.readings - 1) * self.pitch

    def valid_mask(self, frames) -> np.ndarray:
        """Boolean mask of the valid readings of ``frames`` (any shape).

        Valid means finite, not the sentinel, and inside ``valid_range`` (inclusive).
        """
        d = np.asarray(frames, dtype=np.float64)
        flat = _core.valid_readings(d.ravel(), valid_range=self.valid_range, sentinel=self.sentinel)
        return flat.reshape(d.shape)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able description (inverse of :meth:`from_dict`)."""
        return {
            "readings": self.readings,
            "pitch": self.pitch,
            "center": self.center,
            "valid_range": None if self.valid_range is None else list(self.valid_range),
            "sentinel": self.sentinel,
            "name": self.name,
            "noise": self.noise,
            "frame_rate": self.frame_rate,
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Profiler:
        """Profiler from :meth:`to_dict` output."""
        vr = d.get("valid_range")
        return cls(
            readings=int(d["readings"]),
            pitch=float(d["pitch"]),
            center=d.get("center"),
            valid_range=None if vr is None else (float(vr[0]), float(vr[1])),
            sentinel=d.get("sentinel", SENTINEL),
            name=d.get("name", "profiler"),
            noise=d.get("noise"),
            frame_rate=d.get("frame_rate"),
        )

    def __repr__(self) -> str:
        parts = [f"{self.name!r}", f"{self.readings} readings x {self.pitch:g} mm"]
        if self.center is not None:
            parts.append(f"i0={self.center:g}")
        if self.valid_range is not None:
            parts.append(f"range=[{self.valid_range[0]:g}, {self.valid_range[1]:g}] mm")
        if self.sentinel is not None:
            parts.append(f"sentinel={self.sentinel:g}")
        if self.noise is not None:
            parts.append(f"noise={self.noise:g} mm")
        if self.frame_rate is not None:
            parts.append(f"{self.frame_rate:g} frames/s")
        return "Profiler(" + ", ".join(parts) + ")"


# --------------------------------------------------------------------------------------------
# Scan
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False, repr=False)
class Scan:
    """Raw frames of a line-laser profiler plus the machine pose at every frame (SPEC K7).

    Parameters
    ----------
    frames : array_like, shape (F, N)
        Heights ``d_i`` in mm along SCS z; invalid readings are NaN, the profiler sentinel, or
        outside its valid range. ``N`` must equal ``profiler.readings``.
    poses : array_like, shape (F, 6)
        Axis positions ``X, Y, Z`` (mm), ``A, C, C2`` (rad) at each frame time, for the AC
        double-swing head with sixth axis C2 (SPEC K2, K3).
    frame_times : array_like, shape (F,)
        Frame timestamps in s, non-decreasing.
    profiler : Profiler
    c2_offset : array_like, shape (3,)
        ``(Lx, Ly, Lz)``, origin of the C2 frame in the tool frame, mm.
    mount : array_like, shape (6,)
        ``(theta, psi, phi, dx, dy, dz)`` (rad, mm): the calibrated pose of the SCS in the C2
        frame, rotation ``Rz(phi) Ry(theta) Rx(psi)``.
    axis_times : array_like, shape (S,), optional
        Timestamps (s, strictly increasing) of the raw CNC axis samples.
    axis_samples : array_like, shape (S, 6), optional
        Raw CNC axis positions ``X, Y, Z, A, C, C2`` at ``axis_times``; rotary axes may be
        wrapped (``machscan.interpolate_poses`` unwraps them). Give both or neither.
    metadata : dict, optional
        Free-form JSON-able information (str keys), saved with the scan.

    Notes
    -----
    Arrays are converted to C-contiguous float64 on construction (no copy when they already
    are). The container is frozen: fields cannot be rebound, but the arrays are ordinary NumPy
    arrays.

    Examples
    --------
    >>> import numpy as np
    >>> p = Profiler(readings=4, pitch=0.5)
    >>> s = Scan(np.zeros((2, 4)), np.zeros((2, 6)), [0.0, 0.001], p, (0, 0, 100), np.zeros(6))
    >>> s.n_frames, s.n_readings
    (2, 4)
    """

    frames: np.ndarray
    poses: np.ndarray
    frame_times: np.ndarray
    profiler: Profiler
    c2_offset: np.ndarray
    mount: np.ndarray
    axis_times: np.ndarray | None = None
    axis_samples: np.ndarray | None = None
    metadata: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.profiler, Profiler):
            raise ValueError(f"profiler: expected a machscan.scan.Profiler, got {type(self.profiler).__name__}")
        n = self.profiler.readings
        frames = _as_f64(self.frames, "frames")
        if frames.ndim != 2 or frames.shape[1] != n:
            raise ValueError(f"frames: expected shape (F, {n}) (F frames of profiler.readings = {n}), got {frames.shape}")
        f = frames.shape[0]
        poses = _as_f64(self.poses, "poses")
        if poses.shape != (f, 6):
            raise ValueError(f"poses: expected shape (F, 6) with F = {f} frames, got {poses.shape}")
        _check_finite_rows(poses, "poses", "X, Y, Z, A, C, C2")
        times = _as_f64(self.frame_times, "frame_times")
        if times.shape != (f,):
            raise ValueError(f"frame_times: expected shape (F,) with F = {f} frames, got {times.shape}")
        _check_finite_rows(times, "frame_times", "time")
        if f > 1:
            bad = np.flatnonzero(np.diff(times) < 0.0)
            if bad.size:
                i = int(bad[0]) + 1
                raise ValueError(
                    f"frame_times: expected non-decreasing timestamps, but frame {i} "
                    f"({float(times[i])!r} s) is earlier than frame {i - 1} ({float(times[i - 1])!r} s)"
                )
        c2 = _as_f64(self.c2_offset, "c2_offset")
        if c2.shape != (3,):
            raise ValueError(f"c2_offset: expected shape (3,) (Lx, Ly, Lz), got {c2.shape}")
        _check_finite_rows(c2, "c2_offset", "value")
        mount = _as_f64(self.mount, "mount")
        if mount.shape != (6,):
            raise ValueError(f"mount: expected shape (6,) (theta, psi, phi, dx, dy, dz), got {mount.shape}")
        _check_finite_rows(mount, "mount", "value")
        if (self.axis_times is None) != (self.axis_samples is None):
            missing = "axis_samples" if self.axis_samples is None else "axis_times"
            raise ValueError(f"{missing}: axis_times and axis_samples must be given together")
        at = asm = None
        if self.axis_times is not None:
            at = _as_f64(self.axis_times, "axis_times")
            if at.ndim != 1 or at.size < 1:
                raise ValueError(f"axis_times: expected shape (S,) with S >= 1, got {at.shape}")
            _check_finite_rows(at, "axis_times", "time")
            if at.size > 1:
                bad = np.flatnonzero(np.diff(at) <= 0.0)
                if bad.size:
                    i = int(bad[0]) + 1
                    raise ValueError(
                        f"axis_times: expected strictly increasing timestamps, but sample {i} "
                        f"({float(at[i])!r} s) does not follow sample {i - 1} ({float(at[i - 1])!r} s)"
                    )
            asm = _as_f64(self.axis_samples, "axis_samples")
            if asm.shape != (at.size, 6):
                raise ValueError(f"axis_samples: expected shape (S, 6) with S = {at.size} axis_times, got {asm.shape}")
            _check_finite_rows(asm, "axis_samples", "X, Y, Z, A, C, C2")
        meta = {} if self.metadata is None else self.metadata
        if not isinstance(meta, Mapping):
            raise ValueError(f"metadata: expected a dict, got {type(meta).__name__}")
        meta = dict(meta)
        for k in meta:
            if not isinstance(k, str):
                raise ValueError(f"metadata: keys must be str, got {k!r}")
        try:
            json.dumps(meta)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"metadata: must be JSON-serialisable ({exc})") from None
        for name, value in (
            ("frames", frames),
            ("poses", poses),
            ("frame_times", times),
            ("c2_offset", c2),
            ("mount", mount),
            ("axis_times", at),
            ("axis_samples", asm),
            ("metadata", meta),
        ):
            object.__setattr__(self, name, value)

    # ---- sizes -------------------------------------------------------------------------------

    @property
    def n_frames(self) -> int:
        """Number of frames ``F``."""
        return int(self.frames.shape[0])

    @property
    def n_readings(self) -> int:
        """Readings per frame ``N``."""
        return int(self.frames.shape[1])

    @property
    def duration(self) -> float:
        """Time from the first to the last frame, s (0 for fewer than two frames)."""
        return float(self.frame_times[-1] - self.frame_times[0]) if self.n_frames > 1 else 0.0

    def valid_mask(self) -> np.ndarray:
        """(F, N) boolean mask of the valid readings (see :meth:`Profiler.valid_mask`)."""
        return self.profiler.valid_mask(self.frames)

    # ---- points (compiled core) ---------------------------------------------------------------

    def scs_points(self) -> tuple[np.ndarray, np.ndarray]:
        """All valid readings as SCS points (SPEC K1).

        Returns
        -------
        points : ndarray, shape (M, 3)
            ``((i - i0) * pitch, 0, d_i)`` in mm, frame-major then reading order.
        frame_index : ndarray of int64, shape (M,)
            Frame of every point.
        """
        p = self.profiler
        return _core.profile_to_points(self.frames, p.pitch, center=p.center, valid_range=p.valid_range, sentinel=p.sentinel)

    def wcs_points(self) -> tuple[np.ndarray, np.ndarray]:
        """All valid readings as workpiece (WCS) points, through the AC + C2 chain (SPEC K2, K3).

        Returns
        -------
        points : ndarray, shape (M, 3)
            WCS points in mm, frame-major then reading order.
        frame_index : ndarray of int64, shape (M,)
        """
        p = self.profiler
        return _core.scan_to_wcs(
            self.frames,
            self.poses,
            p.pitch,
            self.c2_offset,
            self.mount,
            center=p.center,
            valid_range=p.valid_range,
            sentinel=p.sentinel,
        )

    def transforms(self) -> np.ndarray:
        """WCS <- SCS transform of every frame, shape (F, 4, 4) (``machscan.ac_head_transforms``)."""
        return _core.ac_head_transforms(self.poses, self.c2_offset, self.mount)

    # ---- selection ----------------------------------------------------------------------------

    def select(self, index) -> Scan:
        """A new scan with the frames picked by ``index`` (slice, integer array or boolean mask).

        Axis samples, profiler, offsets and metadata are carried over unchanged.
        """
        idx = index
        if isinstance(idx, slice):
            pass
        else:
            idx = np.asarray(idx)
            if idx.dtype == bool and idx.shape != (self.n_frames,):
                raise ValueError(f"index: expected a boolean mask of shape ({self.n_frames},), got {idx.shape}")
        return Scan(
            frames=self.frames[idx],
            poses=self.poses[idx],
            frame_times=self.frame_times[idx],
            profiler=self.profiler,
            c2_offset=self.c2_offset,
            mount=self.mount,
            axis_times=self.axis_times,
            axis_samples=self.axis_samples,
            metadata=dict(self.metadata),
        )

    # ---- display ------------------------------------------------------------------------------

    def __repr__(self) -> str:
        f, n = self.frames.shape
        valid = float(self.valid_mask().mean()) if f * n else 0.0
        lines = [
            f"Scan({f} frames x {n} readings, {self.duration:.3f} s, {100.0 * valid:.1f} % valid readings",
            f"  profiler={self.profiler!r}",
            "  c2_offset=[" + ", ".join(f"{v:g}" for v in self.c2_offset) + "] mm, "
            "mount=[" + ", ".join(f"{v:g}" for v in self.mount) + "] (rad, mm)",
        ]
        if self.axis_times is not None:
            lines.append(f"  axis samples: {self.axis_times.size} over [{self.axis_times[0]:.3f}, {self.axis_times[-1]:.3f}] s")
        if self.metadata:
            keys = ", ".join(sorted(self.metadata))
            lines.append(f"  metadata keys: {keys}")
        return "\n".join(lines) + ")"

    # ---- persistence --------------------------------------------------------------------------

    def save(self, path: str | os.PathLike) -> None:
        """Write the scan to one ``.npz`` file, exactly and without pickles.

        The arrays are stored as float64 members; the profiler and metadata as one JSON string
        member (``header``), so ``np.load(path, allow_pickle=False)`` reads everything. The file
        is written at ``path`` as given (no extension is appended).
        """
        header = {
            "format": "machscan.Scan",
            "version": _NPZ_VERSION,
            "profiler": self.profiler.to_dict(),
            "metadata": self.metadata,
        }
        arrays: dict[str, np.ndarray] = {
            "frames": self.frames,
            "poses": self.poses,
            "frame_times": self.frame_times,
            "c2_offset": self.c2_offset,
            "mount": self.mount,
            "header": np.array(json.dumps(header)),
        }
        if self.axis_times is not None and self.axis_samples is not None:
            arrays["axis_times"] = self.axis_times
            arrays["axis_samples"] = self.axis_samples
        with open(os.fspath(path), "wb") as fh:
            np.savez(fh, **arrays)  # type: ignore[arg-type]

    @classmethod
    def load(cls, path: str | os.PathLike) -> Scan:
        """Read a scan written by :meth:`save`."""
        p = os.fspath(path)
        with np.load(p, allow_pickle=False) as z:
            names = set(z.files)
            need = {"frames", "poses", "frame_times", "c2_offset", "mount", "header"}
            missing = sorted(need - names)
            if missing:
                raise ValueError(f"path: {p!r} is not a machscan scan file (missing {missing})")
            try:
                header = json.loads(str(z["header"][()]))
            except ValueError as exc:
                raise ValueError(f"path: {p!r} has an unreadable header ({exc})") from None
            if header.get("format") != "machscan.Scan":
                raise ValueError(f"path: {p!r} is not a machscan scan file")
            if int(header.get("version", 0)) > _NPZ_VERSION:
                raise ValueError(
                    f"path: {p!r} was written by a newer machscan (format version "
                    f"{header.get('version')}, this one reads up to {_NPZ_VERSION})"
                )
            has_axes = "axis_times" in names
            return cls(
                frames=z["frames"],
                poses=z["poses"],
                frame_times=z["frame_times"],
                profiler=Profiler.from_dict(header["profiler"]),
                c2_offset=z["c2_offset"],
                mount=z["mount"],
                axis_times=z["axis_times"] if has_axes else None,
                axis_samples=z["axis_samples"] if has_axes else None,
                metadata=header.get("metadata") or {},
            )


# --------------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------------


def read_scan_csv(
    frames_csv: str | os.PathLike,
    poses_csv: str | os.PathLike,
    profiler: Profiler,
    c2_offset,
    mount,
    *,
    delimiter: str = ",",
    metadata: Mapping[str, Any] | None = None,
) -> Scan:
    """Read a scan from a plain CSV export: one file of frames, one file of poses.

    Parameters
    ----------
    frames_csv : path
        One frame per row. A row holds either ``N`` readings (``N = profiler.readings``) or a
        timestamp in s followed by the ``N`` readings; which one is decided by the width of
        the first data row (``N`` or ``N + 1`` cells) and then required of every row. Invalid
        readings are written as the sentinel or ``nan``; empty cells are an error.
    poses_csv : path
        One row per frame with columns ``X, Y, Z, A, C, C2`` (mm, rad), or ``t, X, Y, Z, A, C,
        C2`` (7 cells; ``t`` in s).
    profiler : Profiler
    c2_offset : array_like, shape (3,)
        ``(Lx, Ly, Lz)`` in mm.
    mount : array_like, shape (6,)
        ``(theta, psi, phi, dx, dy, dz)`` in rad and mm.
    delimiter : str
        Cell separator of both files.
    metadata : dict, optional
        Stored in the scan; the source file names are added under ``"source"``.

    Returns
    -------
    Scan

    Notes
    -----
    Both files are read by :func:`machscan.io.read_table` (a header line, comments, cp1252
    text). Frame times come from the frames file if it has timestamps, else from the poses
    file's ``t`` column, else ``i / profiler.frame_rate``; when both files carry times they
    must agree (to 1e-9 s). A problem in a file raises ``ValueError`` (``FileFormatError`` for
    its content) naming the file and the line; a file that cannot be read, ``OSError``.

    Examples
    --------
    >>> scan = read_scan_csv("frames.csv", "poses.csv", Profiler.sr7140(), (0, 0, 115),
    ...                      (0, 0, 0, 0, 0, -140))  # doctest: +SKIP
    """
    if not isinstance(profiler, Profiler):
        raise ValueError(f"profiler: expected a machscan.scan.Profiler, got {type(profiler).__name__}")
    n = profiler.readings
    from machscan.io import read_table

    # Readings may be NaN (no reading); poses and times may not (the frames' times: below).
    frames_table = read_table(frames_csv, delimiter=delimiter, widths=(n, n + 1), name="frames_csv")
    poses_table = read_table(poses_csv, delimiter=delimiter, widths=(6, 7), nan_columns=(), name="poses_csv")
    fdata, flines = frames_table.values, frames_table.lines
    pdata, plines = poses_table.values, poses_table.lines
    ff, fp = os.fspath(frames_csv), os.fspath(poses_csv)
    if fdata.shape[0] != pdata.shape[0]:
        raise ValueError(
            f"poses_csv: {fp!r} has {pdata.shape[0]} data rows but frames_csv {ff!r} has "
            f"{fdata.shape[0]} (one pose per frame expected)"
        )
    if fdata.shape[0] == 0:
        raise ValueError(f"frames_csv: {ff!r} holds no frames")
    ftimes = fdata[:, 0] if fdata.shape[1] == n + 1 else None
    frames = fdata[:, 1:] if ftimes is not None else fdata
    ptimes = pdata[:, 0] if pdata.shape[1] == 7 else None
    poses = pdata[:, 1:] if ptimes is not None else pdata
    if ftimes is not None and ptimes is not None:
        off = np.flatnonzero(np.abs(ftimes - ptimes) > 1e-9)
        if off.size:
            i = int(off[0])
            raise ValueError(
                f"poses_csv: {fp!r}, line {plines[i]}: time {float(ptimes[i])!r} s differs from the "
                f"frame time {float(ftimes[i])!r} s at frames_csv {ff!r}, line {flines[i]}"
            )
    if ftimes is not None:
        times = ftimes
        src, lines = "frames_csv", flines
    elif ptimes is not None:
        times = ptimes
        src, lines = "poses_csv", plines
    else:
        if profiler.frame_rate is None:
            raise ValueError(
                "frames_csv: no timestamps in either file and profiler.frame_rate is None; "
                "add a time column or give the profiler a frame_rate"
            )
        times = np.arange(frames.shape[0], dtype=np.float64) / profiler.frame_rate
        src, lines = "", flines
    if src == "frames_csv":
        nonfinite = np.flatnonzero(~np.isfinite(times))
        if nonfinite.size:
            raise ValueError(f"frames_csv: {ff!r}, line {lines[nonfinite[0]]}: timestamp is not finite")
    if src:
        back = np.flatnonzero(np.diff(times) < 0.0)
        if back.size:
            i = int(back[0]) + 1
            raise ValueError(
                f"{src}: {os.fspath(frames_csv if src == 'frames_csv' else poses_csv)!r}, "
                f"line {lines[i]}: timestamp {float(times[i])!r} s is earlier than the previous row's "
                f"{float(times[i - 1])!r} s"
            )
    meta = dict(metadata or {})
    meta.setdefault("source", {"frames_csv": ff, "poses_csv": fp})
    return Scan(
        frames=np.ascontiguousarray(frames),
        poses=np.ascontiguousarray(poses),
        frame_times=np.ascontiguousarray(times),
        profiler=profiler,
        c2_offset=c2_offset,
        mount=mount,
        metadata=meta,
    )


def read_profiles(
    path: str | os.PathLike[str],
    *,
    pitch: float | None = None,
    x_start: float | None = None,
    y_pitch: float | None = None,
) -> Scan:
    """A line-profiler export as a :class:`Scan`: the files plants have from their profilers'
    own software, read by content (Rust; ``docs/clouds.md``).

    - **LMI Gocator CSV** (the web interface's or emulator's CSV export): the ``Profile``
      section (resampled profiles: a row per frame with Frame, Time, Encoder, Y and one height
      per x column) or the ``Part`` section (a resampled surface: a row per y). The readings' x
      grid comes from the column headers (its pitch and offset: the profiler's ``pitch`` and
      ``center``), the frame's position along the scan from the ``Y`` column, its time from
      ``Time`` (µs, as the sensor stamps it, made seconds from the first frame), and ``Encoder``
      and ``Frame`` go to ``scan.metadata``. Empty cells are no reading (NaN). ``RawProfile`` and
      ``SurfacePointCloud`` exports (points off a grid) are refused: export with uniform spacing.
    - **Keyence LJ-X / LJ-V height rows** (the communication library samples' ``…_height.csv``,
      UTF-16 or ASCII, one profile per line): integers in 0.01 µm with the sensor's no-reading
      codes (−2147483648…−2147483645, and their 20-bit forms) → NaN; numbers with a decimal point
      are mm, with LJ-Navigator's −999.99… no reading. The file has no x grid and no frame
      spacing: give ``pitch``, ``x_start`` (the sensor's profile information, in mm) and
      ``y_pitch``.

    Heights are as the vendor gives them (larger is nearer the sensor: machscan's SCS z). The scan
    is of a part moving under a fixed sensor: every pose is ``(0, y, 0, 0, 0, 0)`` with no mount
    offset, so :meth:`Scan.wcs_points` gives the vendor's own (x, y, z).

    Parameters
    ----------
    path : str or os.PathLike
    pitch, x_start : float, optional
        Keyence: the readings' spacing and the first reading's x, mm.
    y_pitch : float, optional
        The frames' spacing along the scan, mm: Keyence, or a Gocator export without a Y column.

    Returns
    -------
    Scan
        ``metadata`` holds ``layout``, ``model``, ``serial`` and, where the file has them,
        ``encoder`` and ``frame`` per frame.

    Raises
    ------
    machscan.io.FileFormatError
        A layout machscan does not read, or a cell that is not what its column holds — naming
        the file, the line and what was expected; an x grid that is not uniform.
    ValueError
        A Keyence file without ``pitch``, ``x_start`` or ``y_pitch``, or one of them given where
        the file has its own.

    Examples
    --------
    >>> scan = machscan.io.read_profiles("gocator_export.csv")
    >>> fits = machscan.fit_grooves(scan.profiler.x, scan.frames)
    >>> points, frame = scan.wcs_points()
    """
    from machscan.io import FileFormatError

    out = _core.read_profiles(os.fspath(path))
    heights = out["heights"]
    frames, readings = heights.shape
    layout = out["layout"]
    keyence = layout.startswith("Keyence")
    if keyence:
        missing = [n for n, v in (("pitch", pitch), ("x_start", x_start), ("y_pitch", y_pitch)) if v is None]
        if missing:
            raise ValueError(
                f"{', '.join(missing)}: a Keyence height export holds no x grid and no frame spacing; give pitch= "
                "and x_start= (mm: the sensor's X pitch and X start) and y_pitch= (mm between frames)"
            )
        step = _finite_float(pitch, "pitch")
        x0 = _finite_float(x_start, "x_start")
    else:
        for name, given in (("pitch", pitch), ("x_start", x_start)):
            if given is not None:
                raise ValueError(f"{name}: the {layout} export gives its own x grid; leave {name} out")
        x = out["x"]
        x0 = float(x[0])
        step = float((x[-1] - x[0]) / (readings - 1)) if readings > 1 else float(out["x_resolution"] or 1.0)
        off = np.abs(x - (x0 + step * np.arange(readings)))
        # The headers are printed to 5 decimals: their rounding, and no more.
        if readings > 1 and (not step > 0 or off.max() > 1e-5 + 1e-9 * np.abs(x).max()):
            raise FileFormatError(
                f"{os.fspath(path)}: the x positions of the {layout} columns are not an even grid (off by up to "
                f"{off.max():.3g} mm): a Scan holds readings at a fixed pitch"
            )
    if not step > 0:
        raise ValueError(f"pitch: must be a positive spacing in mm, got {step}")
    given_y = out["y"]
    if given_y is not None and y_pitch is not None:
        raise ValueError("y_pitch: the export gives each frame's Y; leave y_pitch out")
    if given_y is not None:
        y = np.asarray(given_y, dtype=np.float64)
    elif y_pitch is None:
        raise ValueError(f"y_pitch: the {layout} export has no Y column; give the frames' spacing, mm")
    else:
        y = _finite_float(y_pitch, "y_pitch") * np.arange(frames, dtype=np.float64)
    times = np.zeros(frames)
    if out["time"] is not None and np.all(np.diff(out["time"]) >= 0):
        times = (out["time"] - out["time"][0]) * 1e-6
    poses = np.zeros((frames, 6))
    poses[:, 1] = y
    name = " ".join(v for v in (layout.split()[0], out["model"]) if v)
    profiler = Profiler(readings=readings, pitch=step, center=-x0 / step, sentinel=None, name=name)
    metadata: dict[str, Any] = {"source": os.fspath(path), "layout": layout, "model": out["model"], "serial": out["serial"]}
    for key in ("encoder", "frame"):
        column = out["encoder"] if key == "encoder" else out["frame"]
        if column is not None:
            metadata[key] = [float(v) for v in column]
    return Scan(heights, poses, times, profiler, np.zeros(3), np.zeros(6), metadata=metadata)


def write_scan_csv(
    scan: Scan,
    frames_csv: str | os.PathLike,
    poses_csv: str | os.PathLike,
    *,
    delimiter: str = ",",
    timestamps: bool = True,
    header: bool = True,
) -> None:
    """Write a scan as the two CSV files :func:`read_scan_csv` reads.

    Values are written with 17 significant digits, so reading them back is exact. Invalid
    readings keep their value (the sentinel, or ``nan``).

    Parameters
    ----------
    scan : Scan
    frames_csv, poses_csv : path
    delimiter : str
    timestamps : bool
        Write the frame time as the first column of both files.
    header : bool
        Write one header line in each file.
    """
    d = delimiter
    n = scan.n_readings
    fmt = "%.17g"
    fcols = (["t"] if timestamps else []) + [f"r{i}" for i in range(n)]
    pcols = (["t"] if timestamps else []) + list(_AXES)
    fdata = np.column_stack([scan.frame_times, scan.frames]) if timestamps else scan.frames
    pdata = np.column_stack([scan.frame_times, scan.poses]) if timestamps else scan.poses
    np.savetxt(os.fspath(frames_csv), fdata, fmt=fmt, delimiter=d, header=d.join(fcols) if header else "", comments="")
    np.savetxt(os.fspath(poses_csv), pdata, fmt=fmt, delimiter=d, header=d.join(pcols) if header else "", comments="")


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def _finite_float(v, name: str) -> float:
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {v!r}") from None
    if not math.isfinite(f):
        raise ValueError(f"{name}: expected a finite number, got {f!r}")
    return f


def _as_f64(v, name: str) -> np.ndarray:
    try:
        return np.ascontiguousarray(np.asarray(v, dtype=np.float64))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: cannot be read as a float64 array ({exc})") from None


def _check_finite_rows(a: np.ndarray, name: str, what: str) -> None:
    if a.ndim == 1:
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            i = int(bad[0])
            raise ValueError(f"{name}: entry {i} is not finite ({float(a[i])!r}); expected {what}")
        return
    bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
    if bad.size:
        i = int(bad[0])
        vals = ", ".join(repr(float(v)) for v in a[i])
        raise ValueError(
            f"{name}: row {i} is not finite ([{vals}]); expected {what} ({bad.size} bad row{'s' if bad.size > 1 else ''} in all)"
        )
