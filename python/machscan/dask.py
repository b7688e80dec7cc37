"""machscan on Dask: long scans chunked along their frames, clouds larger than one call, many files.

Needs the optional dependencies (``pip install 'machscan[dask]'``: dask[distributed], zarr, tqdm);
``machscan.dask`` is imported on first use.

The functions here take Dask arrays (or NumPy arrays, chunked for you) and return lazy results
whose ``.compute()`` equals the in-memory call on the whole input — bit for bit — on any scheduler:
the threaded default, a ``distributed.LocalCluster`` of worker processes, or a cluster given by
its scheduler's address. No kernel is new: each task calls the in-memory function on its chunk,
and where a result needs points from several chunks (the voxel grid) the chunks' partial results
are merged exactly.

Threads: each task runs the kernels on ``threads`` threads (default 1, :func:`machscan.thread_limit`),
so that workers × threads-per-worker tasks at a time never ask for more cores than there are.
Give ``threads=None`` to let each task use every core (one task at a time on the machine).

What parallelises how:

- per frame — :func:`fit_grooves`, :func:`scan_to_wcs`: any chunking along the frames;
- per voxel — :func:`voxel_downsample`: points of one voxel may sit in any chunk; each chunk's
  points are sent to one of ``partitions`` groups by voxel, and each group sums its voxels'
  points in the original point order, as the in-memory call does;
- per neighbourhood — statistical and radius outlier removal, normals, curvature: a point's
  result depends on its k nearest points, which a chunk cut may leave in another chunk. They
  need halos (each spatial block with the points within the neighbourhood radius around it),
  which only a spatial (not a frame-order) chunking bounds; they are not offered here yet — run
  them in memory on the downsampled cloud;
- per file — :func:`map_files`: any function over many scans, one task per file.
"""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

try:
    import dask
    import dask.array as da
    from dask.delayed import delayed
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    raise ImportError("machscan.dask needs Dask: pip install 'machscan[dask]'") from exc

from machscan import _core
from machscan import grooves as _grooves
from machscan import kinematics as _kinematics
from machscan import progress as _progress
from machscan.scan import SENTINEL, Profiler, Scan
from machscan.threads import thread_limit

__all__ = [
    "DaskGrooveFits",
    "FileOutcome",
    "LazyScan",
    "fit_grooves",
    "map_files",
    "open_scan",
    "save_scan",
    "scan_to_wcs",
    "voxel_downsample",
]

#: Threads each task's kernels run on, unless told otherwise.
TASK_THREADS = 1
#: Frames per chunk when NumPy frames are chunked here and when a scan is written to Zarr:
#: 4096 frames of 3200 readings are 100 MB, and about 0.2 s of groove fitting on one thread —
#: well above the few ms a task costs the scheduler (BENCHMARKS.md, "Dask").
CHUNK_FRAMES = 4096
#: Points per chunk when a NumPy cloud is chunked here.
CHUNK_POINTS = 1 << 20

# ---- arguments -----------------------------------------------------------------------------


def _task_threads(threads: int | None) -> int | None:
    if threads is None:
        return None
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads: expected an int >= 1 or None (all cores), got {threads!r}")
    return threads


def _frames_array(frames: Any, name: str = "frames") -> da.Array:
    """(F, N) frames as a Dask array chunked along the frames only."""
    a = frames if isinstance(frames, da.Array) else da.from_array(np.asarray(frames, dtype=np.float64), chunks=(CHUNK_FRAMES, -1))
    if a.ndim != 2:
        raise ValueError(f"{name}: expected shape (F, N), got {a.shape}")
    if len(a.chunks[1]) > 1:
        a = a.rechunk({1: -1})
    return a


# ---- grooves -------------------------------------------------------------------------------


def _groove_dtype(n_readings: int, options: _grooves.GrooveOptions) -> np.dtype:
    """The record of one frame's fit: the GrooveFits arrays' names and dtypes, from a call on no
    frames (one source for them: the in-memory result)."""
    empty = _grooves.fit_grooves(np.arange(n_readings, dtype=np.float64), np.empty((0, n_readings)), options=options)
    return np.dtype([(f.name, getattr(empty, f.name).dtype) for f in fields(empty) if f.name not in _grooves._CALL_FIELDS])


def _valid_readings(block: np.ndarray, profiler: Profiler) -> np.ndarray:
    """A scan's frames as the groove fit takes them: invalid readings (NaN, the sentinel, out of
    the valid range) as NaN, as :func:`machscan.inspect_grooves` does."""
    return np.where(profiler.valid_mask(block), block, np.nan)


def _fit_block(
    block: np.ndarray,
    x: np.ndarray,
    options: _grooves.GrooveOptions,
    dtype: np.dtype,
    threads: int | None,
    block_info: dict[Any, Any] | None = None,
) -> np.ndarray:
    with thread_limit(threads):
        fits = _grooves.fit_grooves(x, block, options=options)
    out = np.empty(len(fits), dtype=dtype)
    for name in dtype.names or ():
        out[name] = getattr(fits, name)
    # The rows' frames counted from the whole array's first frame, not the chunk's.
    out["frame"] += block_info[0]["array-location"][0][0] if block_info else 0
    return out


@dataclass(frozen=True, eq=False, repr=False)
class DaskGrooveFits:
    """The lazy result of :func:`fit_grooves`: one record per frame (with ``select="all"`` per
    groove) in ``records`` (a Dask array chunked as the frames), each :class:`machscan.GrooveFits` field as a Dask array
    (``fits.width``, ``fits.status``, ...), and :meth:`compute` for the in-memory result."""

    records: da.Array
    template: str
    rounding_prior: tuple[float, float] | None = None
    misfit: dict[str, float] | None = None

    def __getattr__(self, name: str) -> da.Array:
        names = self.records.dtype.names or ()
        if name in names:
            return self.records[name]
        raise AttributeError(f"'DaskGrooveFits' has no attribute {name!r}")

    def __dir__(self) -> list[str]:
        return sorted(set(super().__dir__()) | set(self.records.dtype.names or ()))

    def __len__(self) -> int:
        return int(self.records.shape[0])

    def to_fits(self, records: np.ndarray) -> _grooves.GrooveFits:
        """The :class:`machscan.GrooveFits` of computed ``records``."""
        return _grooves.GrooveFits(
            **{name: np.ascontiguousarray(records[name]) for name in records.dtype.names or ()},
            template=self.template,
            rounding_prior=self.rounding_prior,
            misfit=self.misfit,
        )

    def compute(self, **kwargs: Any) -> _grooves.GrooveFits:
        """Run the fits (``kwargs`` go to ``dask.compute``, e.g. ``scheduler=``)."""
        (records,) = dask.compute(self.records, **kwargs)
        return self.to_fits(records)

    def __repr__(self) -> str:
        return f"DaskGrooveFits({len(self)} frames in {self.records.numblocks[0]} chunks, lazy)"


def fit_grooves(
    x: Any,
    frames: Any = None,
    *,
    options: _grooves.GrooveOptions | None = None,
    threads: int | None = TASK_THREADS,
    **changes: Any,
) -> DaskGrooveFits:
    """:func:`machscan.fit_grooves` over frames chunked along the frames: lazy, one task per chunk.

    Parameters
    ----------
    x : array_like (N,), or a :class:`LazyScan` / :class:`machscan.Scan`
        Abscissa of the readings, mm; given a scan, its profiler's, and its frames with the
        invalid readings (sentinel, out of range) as NaN.
    frames : dask or NumPy array (F, N)
        Readings, mm (NaN: invalid); NumPy arrays are chunked every ``CHUNK_FRAMES`` frames, and
        chunks across the readings are joined.
    options : GrooveOptions, optional
        How the groove is measured, as in :func:`machscan.fit_grooves`.
    threads : int or None
        Threads each task's fits run on (None: all cores).
    **changes
        Fields of :class:`machscan.GrooveOptions` changed for this call (``window=200``, ...).

    Returns
    -------
    DaskGrooveFits
        ``.compute()`` gives the :class:`machscan.GrooveFits` of the in-memory call, bit for bit
        (every frame is fitted on its own; with ``rounding="pooled"`` and ``misfit="pooled"``,
        the defaults, under the tip-rounding prior and the misfit of the frames the in-memory
        call pools, every k-th frame, which are read and fitted first, eagerly: one pass over
        the chunks before the lazy one).

    Examples
    --------
    >>> fits = machscan.dask.fit_grooves(x, da.from_zarr("scan.zarr/frames"), window=200)
    >>> fits.width.mean().compute()   # lazy per-frame arrays
    >>> result = fits.compute()       # a machscan.GrooveFits
    """
    threads = _task_threads(threads)
    if "progress" in changes:
        raise ValueError("progress: not per task; use Dask's bars (dask.diagnostics.ProgressBar, distributed.progress)")
    if isinstance(x, (LazyScan, Scan)):
        if frames is not None:
            raise ValueError("frames: give a scan or x and frames, not both")
        scan = x
        profiler = scan.profiler
        x = profiler.x
        frames = da.map_blocks(_valid_readings, _frames_array(scan.frames), profiler, dtype=np.float64)
    elif frames is None:
        raise ValueError("frames: missing (give x and frames, or a scan)")
    x = np.ascontiguousarray(x, dtype=np.float64)
    frames = _frames_array(frames)
    if x.ndim != 1 or x.shape[0] != frames.shape[1]:
        raise ValueError(f"x: expected shape ({frames.shape[1]},) (one abscissa per reading of frames), got {x.shape}")
    options = _grooves.groove_options(options, changes, "machscan.dask.fit_grooves")
    # The chunks measure under what the in-memory call pools to (the rounding prior, the
    # misfit): the frames it pools (every k-th) are fitted first, here, eagerly.
    pooled, options = _grooves.settled_pools(x, frames, options)
    dtype = _groove_dtype(x.shape[0], options)
    fit = functools.partial(_fit_block, x=x, options=options, dtype=dtype, threads=threads)
    # A row per groove: how many a chunk gives is known only once it is fitted.
    rows = ((np.nan,) * frames.numblocks[0],) if options.select == "all" else None
    records = frames.map_blocks(fit, dtype=dtype, drop_axis=1, chunks=rows, meta=np.empty((0,), dtype))
    return DaskGrooveFits(records, options.template, **pooled)


# ---- frames to points -----------------------------------------------------------------------


def _wcs_block(frames, poses, first, pitch, c2_offset, mount, center, valid_range, sentinel, threads):
    with thread_limit(threads):
        points, frame = _kinematics.scan_to_wcs(
            frames, poses, pitch, c2_offset, mount, center=center, valid_range=valid_range, sentinel=sentinel
        )
    return points, frame + first


def scan_to_wcs(
    frames: Any,
    axes: Any = None,
    pitch: float | None = None,
    c2_offset: ArrayLike | None = None,
    mount: ArrayLike | None = None,
    *,
    center: float | None = None,
    valid_range: ArrayLike | None = None,
    sentinel: float | None = SENTINEL,
    threads: int | None = TASK_THREADS,
) -> tuple[da.Array, da.Array]:
    """:func:`machscan.scan_to_wcs` on frames and poses chunked along the frames: lazy.

    Takes the in-memory call's arguments, or a :class:`LazyScan` / :class:`machscan.Scan` alone
    (its poses, profiler, C2 offset and mount). The poses are chunked as the frames.

    Returns
    -------
    points : dask array (M, 3)
        WCS points, mm, frame-major then reading order; chunks of unknown length (invalid
        readings are dropped), one per frame chunk.
    frame_index : dask array of int64 (M,)
        Frame of every point, counted over the whole scan.

    ``dask.compute(points, frame_index)`` equals the in-memory call, bit for bit.
    """
    threads = _task_threads(threads)
    if isinstance(frames, (LazyScan, Scan)):
        if axes is not None or pitch is not None:
            raise ValueError("axes: give a scan or the frames with their axes, pitch, c2_offset and mount, not both")
        scan = frames
        p = scan.profiler
        frames, axes, pitch, c2_offset, mount = scan.frames, scan.poses, p.pitch, scan.c2_offset, scan.mount
        center, valid_range, sentinel = p.center, p.valid_range, p.sentinel
    missing = [name for name, v in (("axes", axes), ("pitch", pitch), ("c2_offset", c2_offset), ("mount", mount)) if v is None]
    if missing:
        raise ValueError(f"{missing[0]}: missing (give the frames with their axes, pitch, c2_offset and mount, or a scan)")
    frames = _frames_array(frames)
    if isinstance(axes, da.Array):
        poses = axes
    else:
        poses = da.from_array(np.asarray(axes, dtype=np.float64), chunks=(frames.chunks[0], -1))
    if poses.ndim != 2 or poses.shape != (frames.shape[0], 6):
        raise ValueError(f"axes: expected shape ({frames.shape[0]}, 6) (one pose per frame), got {poses.shape}")
    poses = poses.rechunk((frames.chunks[0], 6))
    c2 = np.asarray(c2_offset, dtype=np.float64)
    mnt = np.asarray(mount, dtype=np.float64)
    starts = np.concatenate([[0], np.cumsum(frames.chunks[0])[:-1]]).astype(np.int64)
    f_blocks, p_blocks = frames.to_delayed().ravel(), poses.to_delayed().ravel()
    point_parts, index_parts = [], []
    for f, p, first in zip(f_blocks, p_blocks, starts):
        out = delayed(_wcs_block, nout=2, pure=True)(f, p, int(first), pitch, c2, mnt, center, valid_range, sentinel, threads)
        point_parts.append(da.from_delayed(out[0], shape=(np.nan, 3), dtype=np.float64))
        index_parts.append(da.from_delayed(out[1], shape=(np.nan,), dtype=np.int64))
    if not point_parts:
        return da.zeros((0, 3), dtype=np.float64), da.zeros((0,), dtype=np.int64)
    return da.concatenate(point_parts, axis=0), da.concatenate(index_parts, axis=0)


# ---- voxel grid ------------------------------------------------------------------------------


def _voxel_split(points: np.ndarray, first: int, origin: np.ndarray, voxel: float, partitions: int) -> list[tuple]:
    """One chunk's points as `partitions` groups by voxel key: (keys, global indices, points)."""
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        raise ValueError(f"points: point {first + int(bad[0])} is not finite ({points[bad[0]].tolist()})")
    # The in-memory grid's keys, from the core that makes them.
    keys, ijk = _core.voxel_keys(points, origin, voxel_size=voxel)
    # A spatial hash of the three indices spreads a flat part's voxels (one z index) over the groups.
    group = ((ijk[:, 0] * 73856093) ^ (ijk[:, 1] * 19349663) ^ (ijk[:, 2] * 83492791)) % partitions
    index = np.arange(first, first + len(points), dtype=np.int64)
    return [(keys[group == g], index[group == g], points[group == g]) for g in range(partitions)]


def _voxel_group(*parts: tuple) -> tuple[np.ndarray, np.ndarray]:
    """The voxels of one group: (first point's global index, centroid) per voxel. The parts come
    in chunk order and each in point order, so every voxel sums its points in the order the
    in-memory grid does, and divides by the count as it does."""
    keys = np.concatenate([p[0] for p in parts])
    index = np.concatenate([p[1] for p in parts])
    points = np.concatenate([p[2] for p in parts]).reshape(-1, 3)
    if len(keys) == 0:
        return np.empty(0, np.int64), np.empty((0, 3))
    _, first, inverse, counts = np.unique(keys, return_index=True, return_inverse=True, return_counts=True)
    # bincount adds its weights one by one in input order: the in-memory grid's sequential sums.
    sums = np.stack([np.bincount(inverse, weights=points[:, k], minlength=len(first)) for k in range(3)], axis=1)
    return index[first], sums / counts[:, None].astype(np.float64)


def _voxel_merge(groups: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    first = np.concatenate([g[0] for g in groups])
    centroids = np.concatenate([g[1] for g in groups]).reshape(-1, 3)
    return centroids[np.argsort(first, kind="stable")]


def _bounds(points: da.Array) -> tuple[da.Array, da.Array]:
    """The bounds of the finite points: a non-finite one is refused by its own chunk, by index."""
    finite = da.isfinite(points)
    return da.where(finite, points, np.inf).min(axis=0), da.where(finite, points, -np.inf).max(axis=0)


def _origin(lo: np.ndarray, hi: np.ndarray, voxel: float) -> np.ndarray:
    return _core.voxel_origin(lo, hi, voxel_size=voxel)


def voxel_downsample(points: Any, voxel_size: float, *, partitions: int | None = None) -> da.Array:
    """:func:`machscan.voxel_downsample` on an (N, 3) Dask array chunked along the points: lazy.

    The grid is the in-memory one (origin at the whole cloud's minimum bound less half a voxel).
    Each chunk's points are split by voxel into ``partitions`` groups (default: the number of
    chunks); each group's voxels are the centroids of their points summed in the original point
    order; the voxels come back in the order of their first point. So ``.compute()`` equals the
    in-memory call bit for bit, in the same order, whatever the chunking. Memory: one group's
    points at a time per task, about N / partitions.

    Returns
    -------
    dask array (M, 3)
        Centroids, one chunk of unknown length.
    """
    number = isinstance(voxel_size, (int, float)) and not isinstance(voxel_size, bool)
    if not (number and np.isfinite(voxel_size) and voxel_size > 0):
        raise ValueError(f"voxel_size: must be a finite number > 0 mm, got {voxel_size!r}")
    voxel = float(voxel_size)
    if isinstance(points, da.Array):
        pts = points
    else:
        pts = da.from_array(np.asarray(points, dtype=np.float64), chunks=(CHUNK_POINTS, 3))
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points: expected shape (N, 3), got {pts.shape}")
    pts = pts.astype(np.float64).rechunk({1: 3})
    if pts.shape[0] == 0:
        return da.zeros((0, 3), dtype=np.float64)
    n_chunks = pts.numblocks[0]
    k = n_chunks if partitions is None else int(partitions)
    if k < 1:
        raise ValueError(f"partitions: must be >= 1, got {partitions}")
    lo, hi = _bounds(pts)
    origin = delayed(_origin, pure=True)(lo, hi, voxel)
    starts = np.concatenate([[0], np.cumsum(pts.chunks[0])[:-1]]).astype(np.int64)
    splits = [
        delayed(_voxel_split, nout=k, pure=True)(block, int(first), origin, voxel, k)
        for block, first in zip(pts.to_delayed().ravel(), starts)
    ]
    groups = [delayed(_voxel_group, pure=True)(*[split[g] for split in splits]) for g in range(k)]
    merged = delayed(_voxel_merge, pure=True)(groups)
    return da.from_delayed(merged, shape=(np.nan, 3), dtype=np.float64)


# ---- scans in Zarr ---------------------------------------------------------------------------

_ZARR_FORMAT = "machscan.Scan"
_ZARR_VERSION = 1


@dataclass(frozen=True, eq=False, repr=False)
class LazyScan:
    """A :class:`machscan.Scan` whose frames, poses and frame times are Dask arrays (chunked along
    the frames), as :func:`open_scan` reads it from Zarr. :meth:`compute` loads it as a Scan."""

    frames: da.Array
    poses: da.Array
    frame_times: da.Array
    profiler: Profiler
    c2_offset: np.ndarray
    mount: np.ndarray
    axis_times: np.ndarray | None = None
    axis_samples: np.ndarray | None = None
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def n_frames(self) -> int:
        return int(self.frames.shape[0])

    def compute(self, **kwargs: Any) -> Scan:
        """Load the scan (``kwargs`` go to ``dask.compute``)."""
        frames, poses, times = dask.compute(self.frames, self.poses, self.frame_times, **kwargs)
        stored = {f.name: getattr(self, f.name) for f in fields(self)}
        return Scan(**stored | dict(frames=frames, poses=poses, frame_times=times, metadata=dict(self.metadata)))

    def __repr__(self) -> str:
        f, n = self.frames.shape
        return f"LazyScan({f} frames x {n} readings in {self.frames.numblocks[0]} chunks, profiler={self.profiler!r})"


def save_scan(scan: Scan | LazyScan, path: str | os.PathLike, *, chunk_frames: int = CHUNK_FRAMES) -> None:
    """Write a scan as a Zarr group: ``frames``, ``poses``, ``frame_times`` chunked every
    ``chunk_frames`` frames, the C2 offset, mount and any raw axis samples as small arrays, and
    the profiler and metadata as JSON attributes. A :class:`LazyScan` is written chunk by chunk,
    never whole in memory. Values are stored exactly (float64, lossless compression)."""
    import zarr

    if isinstance(chunk_frames, bool) or not isinstance(chunk_frames, int) or chunk_frames < 1:
        raise ValueError(f"chunk_frames: must be an int >= 1, got {chunk_frames!r}")
    root = zarr.open_group(os.fspath(path), mode="w")
    root.attrs.update(
        {
            "format": _ZARR_FORMAT,
            "version": _ZARR_VERSION,
            "profiler": scan.profiler.to_dict(),
            "metadata": scan.metadata,
        }
    )
    n = scan.frames.shape[1]
    for name, width in (("frames", n), ("poses", 6), ("frame_times", None)):
        a = getattr(scan, name)
        chunks = (chunk_frames,) if width is None else (chunk_frames, width)
        if isinstance(a, da.Array):
            da.to_zarr(a.astype(np.float64).rechunk(chunks), os.fspath(path), component=name, overwrite=True)
        else:  # in memory already: written directly, not shipped through a scheduler
            root.create_array(name, data=np.asarray(a, dtype=np.float64), chunks=chunks)
    for name in ("c2_offset", "mount", "axis_times", "axis_samples"):
        value = getattr(scan, name)
        if value is not None:
            root.create_array(name, data=np.asarray(value, dtype=np.float64))


def _stored(root: Any, name: str) -> np.ndarray:
    """A small array of a Zarr scan, read whole."""
    return np.asarray(root[name][...])


def open_scan(path: str | os.PathLike) -> LazyScan:
    """Open a scan written by :func:`save_scan` lazily: frames, poses and frame times as Dask
    arrays on the stored chunks."""
    import zarr

    p = os.fspath(path)
    try:
        root = zarr.open_group(p, mode="r")
    except FileNotFoundError:
        raise
    except Exception as exc:
        if not os.path.exists(p):
            raise FileNotFoundError(f"path: no such scan {p!r}") from None
        raise ValueError(f"path: {p!r} is not a Zarr scan ({exc})") from None
    attrs: dict[str, Any] = dict(root.attrs)
    if attrs.get("format") != _ZARR_FORMAT:
        raise ValueError(f"path: {p!r} is not a machscan scan (no format {_ZARR_FORMAT!r} in its attributes)")
    if int(attrs.get("version", 0)) > _ZARR_VERSION:
        version = attrs.get("version")
        raise ValueError(f"path: {p!r} was written by a newer machscan (version {version}, this one reads {_ZARR_VERSION})")
    names = set(root.array_keys())
    missing = sorted({"frames", "poses", "frame_times", "c2_offset", "mount"} - names)
    if missing:
        raise ValueError(f"path: {p!r} is not a machscan scan (missing {missing})")
    has_axes = "axis_times" in names and "axis_samples" in names
    return LazyScan(
        frames=da.from_zarr(p, component="frames"),
        poses=da.from_zarr(p, component="poses"),
        frame_times=da.from_zarr(p, component="frame_times"),
        profiler=Profiler.from_dict(attrs["profiler"]),
        c2_offset=_stored(root, "c2_offset"),
        mount=_stored(root, "mount"),
        axis_times=_stored(root, "axis_times") if has_axes else None,
        axis_samples=_stored(root, "axis_samples") if has_axes else None,
        metadata=attrs.get("metadata") or {},
    )


# ---- many files ------------------------------------------------------------------------------


@dataclass(frozen=True)
class FileOutcome:
    """What one file of a batch gave: its ``result``, or the ``error`` that stopped it (then
    ``result`` is None)."""

    path: str
    result: Any = None
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None


def _run_file(func: Callable[[str], Any], path: str, threads: int | None) -> FileOutcome:
    try:
        # One task is one file on its share of the cores: Dask work inside it (a lazy scan read)
        # runs in the task, not as new tasks sent back to the cluster.
        with thread_limit(threads), dask.config.set(scheduler="sync"):
            return FileOutcome(path, func(path))
    except Exception as exc:  # one bad file must not lose the others' results
        return FileOutcome(path, None, f"{type(exc).__name__}: {exc}")


def map_files(
    func: Callable[[str], Any],
    paths: Iterable[str | os.PathLike],
    *,
    client: Any = None,
    threads: int | None = TASK_THREADS,
    progress: bool | None = None,
    scheduler: str | None = None,
) -> list[FileOutcome]:
    """Run ``func(path)`` on every file, one task per file, and collect what each gave.

    A file whose call raises does not stop the batch: its :class:`FileOutcome` carries the error
    (type and message) and the others their results, in the order of ``paths``.

    Parameters
    ----------
    func : callable
        Takes a path (str); must be picklable for worker processes (a module-level function).
    paths : iterable of path-like
    client : distributed.Client, optional
        Runs the tasks on its cluster; default Dask's current scheduler (threads).
    threads : int or None
        Threads each task's kernels run on (None: all cores).
    progress : bool, optional
        A progress bar on stderr — files done, rate and time left with a client (tqdm), Dask's own
        bar otherwise; default: when stderr is a terminal.
    scheduler : str, optional
        Without a client: the Dask scheduler to use ("threads", "processes", "sync"); default
        Dask's current one.
    """
    threads = _task_threads(threads)
    names = [os.fspath(p) for p in paths]
    show = _progress.wanted(progress)
    if client is not None:
        from distributed import as_completed

        # The function (with what it carries, e.g. CAD contours) goes to the workers once.
        (shared,) = client.scatter([func], broadcast=True, hash=False)
        futures = client.map(_run_file, [shared] * len(names), names, [threads] * len(names), pure=False)
        position = {f.key: k for k, f in enumerate(futures)}
        out: list[FileOutcome | None] = [None] * len(names)
        with _progress.bar(len(names), "file", show, "files") as bar:
            for future in as_completed(futures):
                out[position[future.key]] = future.result()
                bar.update(1)
        return [o for o in out if o is not None]
    tasks = [delayed(_run_file, pure=False)(func, name, threads) for name in names]
    if show:
        from dask.diagnostics import ProgressBar

        with ProgressBar(out=sys.stderr):
            return list(dask.compute(*tasks, scheduler=scheduler))
    return list(dask.compute(*tasks, scheduler=scheduler))
