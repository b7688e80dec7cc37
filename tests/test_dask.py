"""machscan.dask (issue 12): lazy results equal to the in-memory calls bit for bit, on Dask's threads and on a
LocalCluster of worker processes; Zarr scans; batches that survive a bad file; the per-thread kernel limit."""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import fields
from pathlib import Path

import cloudpickle
import dask
import dask.array as da
import distributed
import numpy as np
import pytest

import machscan
import machscan.dask as md
from machscan import synth
from machscan.cad import write_contours_csv
from machscan.cli import main
from machscan.synth.frames import groove_frames

# Functions of this module are sent to worker processes by value: the workers cannot import tests/.
cloudpickle.register_pickle_by_value(sys.modules[__name__])


@pytest.fixture(scope="module")
def client():
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster,
        distributed.Client(cluster) as c,
    ):
        yield c


@pytest.fixture(scope="module")
def frames():
    g = groove_frames("v", 3000, seed=3)
    return g.x, g.z


@pytest.fixture(scope="module")
def scan():
    scan, truth = synth.groove_scan(seed=5, readings=800, keep_every=100)
    return scan, truth


def assert_same_fits(a: machscan.GrooveFits, b: machscan.GrooveFits) -> None:
    for f in fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and np.array_equal(x, y, equal_nan=True), f.name
        else:
            assert x == y, f.name


@pytest.mark.parametrize("chunks", [(3000, -1), (700, -1), (512, 64)])
def test_groove_fits_equal_the_in_memory_call_bit_for_bit(frames, chunks):
    x, z = frames
    ref = machscan.fit_grooves(x, z, window=150)
    lazy = md.fit_grooves(x, da.from_array(z, chunks=chunks), window=150)
    assert isinstance(lazy.width, da.Array) and lazy.width.shape == (3000,)
    assert_same_fits(lazy.compute(), ref)
    # The fields are lazy arrays of their own: a reduction needs no GrooveFits.
    ok = lazy.status == int(machscan.GrooveStatus.CONVERGED)
    assert np.isclose(float(lazy.width[ok].mean().compute()), ref.width[ref.ok].mean(), rtol=1e-12)


def test_groove_fits_on_worker_processes(frames, client):
    x, z = frames
    ref = machscan.fit_grooves(x, z, template="tanh")
    assert_same_fits(md.fit_grooves(x, da.from_array(z, chunks=(400, -1)), template="tanh").compute(), ref)


def test_bad_groove_options_are_refused_before_any_task(frames):
    x, z = frames
    with pytest.raises(ValueError, match="template"):
        md.fit_grooves(x, da.from_array(z, chunks=(700, -1)), template="w")
    with pytest.raises(ValueError, match="x: expected shape"):
        md.fit_grooves(x[:-1], da.from_array(z, chunks=(700, -1)))
    with pytest.raises(ValueError, match="threads"):
        md.fit_grooves(x, z, threads=0)


def test_scan_points_equal_the_in_memory_call(scan, client):
    s, _ = scan
    ref_points, ref_frame = s.wcs_points()
    frames = da.from_array(s.frames, chunks=(37, -1))
    p = s.profiler
    points, frame = md.scan_to_wcs(
        frames, s.poses, p.pitch, s.c2_offset, s.mount, center=p.center, valid_range=p.valid_range, sentinel=p.sentinel
    )
    assert np.isnan(points.shape[0])  # invalid readings are dropped: chunk lengths are unknown until computed
    got_points, got_frame = dask.compute(points, frame)
    assert np.array_equal(got_points, ref_points) and np.array_equal(got_frame, ref_frame)


@pytest.mark.parametrize(("chunk", "partitions"), [(40_000, None), (77_777, 3), (200_000, 1), (13_000, 16)])
def test_voxel_grid_equals_the_in_memory_call_in_order(chunk, partitions):
    rng = np.random.default_rng(4)
    # A plate far from the origin: one z layer of voxels, 200 000 points, voxels straddling the chunk cuts.
    pts = rng.random((200_000, 3)) * [120.0, 80.0, 0.3] + [2500.0, -1800.0, 640.0]
    ref = machscan.voxel_downsample(pts, 0.5)
    got = md.voxel_downsample(da.from_array(pts, chunks=(chunk, 3)), 0.5, partitions=partitions).compute()
    assert got.shape == ref.shape and np.array_equal(got, ref)


def test_voxel_grid_on_worker_processes_and_its_checks(client):
    rng = np.random.default_rng(5)
    pts = rng.normal(size=(50_000, 3)) * 20.0
    ref = machscan.voxel_downsample(pts, 1.5)
    assert np.array_equal(md.voxel_downsample(da.from_array(pts, chunks=(9_000, 3)), 1.5).compute(), ref)
    assert md.voxel_downsample(da.zeros((0, 3), chunks=(10, 3)), 1.0).compute().shape == (0, 3)
    with pytest.raises(ValueError, match="voxel_size"):
        md.voxel_downsample(pts, 0.0)
    with pytest.raises(ValueError, match="points: expected shape"):
        md.voxel_downsample(pts[:, :2], 1.0)
    bad = pts.copy()
    bad[31_000, 1] = np.nan
    with pytest.raises(ValueError, match="points: point 31000 is not finite"):
        md.voxel_downsample(da.from_array(bad, chunks=(9_000, 3)), 1.5).compute(scheduler="threads")


def test_zarr_scan_round_trip_is_exact_and_lazy(scan, tmp_path):
    s, _ = scan
    md.save_scan(s, tmp_path / "a.zarr", chunk_frames=50)
    lazy = md.open_scan(tmp_path / "a.zarr")
    assert isinstance(lazy.frames, da.Array) and lazy.frames.chunks[0][0] == 50
    back = lazy.compute()
    for name in ("frames", "poses", "frame_times", "c2_offset", "mount", "axis_times", "axis_samples"):
        assert np.array_equal(getattr(back, name), getattr(s, name), equal_nan=True), name
    assert back.profiler == s.profiler and back.metadata == s.metadata
    # A lazy scan is written chunk by chunk; the functions take it whole.
    md.save_scan(lazy, tmp_path / "b.zarr", chunk_frames=64)
    again = md.open_scan(tmp_path / "b.zarr")
    assert np.array_equal(again.frames.compute(), s.frames, equal_nan=True)
    readings = np.where(s.valid_mask(), s.frames, np.nan)  # a scan's invalid readings are NaN to the fit
    assert (s.frames == s.profiler.sentinel).any()
    assert_same_fits(md.fit_grooves(again, window=200).compute(), machscan.fit_grooves(s.profiler.x, readings, window=200))
    points, frame = dask.compute(*md.scan_to_wcs(again))
    ref_points, ref_frame = s.wcs_points()
    assert np.array_equal(points, ref_points) and np.array_equal(frame, ref_frame)


def test_opening_what_is_not_a_scan_says_so(tmp_path):
    with pytest.raises(FileNotFoundError):
        md.open_scan(tmp_path / "missing.zarr")
    import zarr

    zarr.open_group(str(tmp_path / "other.zarr"), mode="w").create_array("frames", data=np.zeros((2, 2)))
    with pytest.raises(ValueError, match="not a machscan scan"):
        md.open_scan(tmp_path / "other.zarr")


def frames_of(path: str) -> int:
    return md.open_scan(path).n_frames


def test_a_bad_file_in_a_batch_is_reported_and_the_others_kept(scan, tmp_path, client):
    s, _ = scan
    paths = []
    for k in range(3):
        md.save_scan(s.select(slice(0, 100 + k)), tmp_path / f"s{k}.zarr", chunk_frames=40)
        paths.append(tmp_path / f"s{k}.zarr")
    (tmp_path / "broken.zarr").mkdir()
    paths.insert(1, tmp_path / "broken.zarr")
    for kwargs in (dict(client=client), dict()):  # worker processes, and Dask's threads
        out = md.map_files(frames_of, paths, progress=False, **kwargs)
        assert [o.path for o in out] == [os.fspath(p) for p in paths]
        assert [o.result for o in out] == [100, None, 101, 102]
        assert [o.ok for o in out] == [True, False, True, True]
        assert "broken.zarr" in out[1].error or "not a" in out[1].error


def test_batch_grooves_command(scan, tmp_path):
    s, truth = scan
    md.save_scan(s, tmp_path / "good.zarr", chunk_frames=100)
    s.save(tmp_path / "good2.npz")
    (tmp_path / "bad.npz").write_bytes(b"not a scan")
    write_contours_csv(tmp_path / "cad.csv", truth.nominal_polylines)
    args = ["batch", "grooves", str(tmp_path / "good.zarr"), str(tmp_path / "bad.npz"), str(tmp_path / "good2.npz")]
    args += ["--cad", str(tmp_path / "cad.csv"), "--workers", "2", "--out", str(tmp_path / "out"), "--no-progress"]
    assert main(args) == 3  # one scan failed
    rows = (tmp_path / "out" / "batch.csv").read_text().splitlines()
    assert rows[0].startswith("scan,ok,")
    assert rows[1].split(",")[1] == "True" and rows[3].split(",")[1] == "True"
    assert rows[2].split(",")[1] == "False" and "bad.npz" in rows[2]
    ref = machscan.inspect_grooves(s, truth.nominal_polylines)
    for name in ("good", "good2"):
        table = np.genfromtxt(tmp_path / "out" / name / "contour_errors.csv", delimiter=",", names=True)
        np.testing.assert_allclose(table["error_mean_mm"][:-1], [c.error.mean for c in ref.contours], rtol=1e-12)


def pool_threads() -> set[str]:
    return {Path(f"/proc/self/task/{t}/comm").read_text().strip() for t in os.listdir("/proc/self/task")}


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="thread names from /proc (Linux)")
def test_thread_limit_runs_the_kernels_on_a_pool_of_that_size():
    pts = np.random.default_rng(0).random((400_000, 3))
    ref = machscan.voxel_downsample(pts, 0.01)
    with machscan.thread_limit(3):
        got = machscan.voxel_downsample(pts, 0.01)
        assert machscan._core.set_thread_limit(3) == 3  # the limit holds inside the block
    assert np.array_equal(got, ref)
    names = pool_threads()
    assert {"machscan-3-0", "machscan-3-1", "machscan-3-2"} <= names and "machscan-3-3" not in names
    assert machscan._core.set_thread_limit(0) == 0  # restored on leaving the block


def test_thread_limit_checks_its_argument():
    with pytest.raises(ValueError, match="threads"), machscan.thread_limit(0):
        pass
    with pytest.raises(TypeError, match="threads"), machscan.thread_limit(2.0):  # type: ignore[arg-type]
        pass
    with pytest.raises(ValueError, match="threads: at most"):
        machscan._core.set_thread_limit(10**9)


def test_progress_bars_show_frames_and_files_and_change_nothing(frames, scan, tmp_path, capfd):
    x, z = frames
    quiet = machscan.fit_grooves(x, z)
    shown = machscan.fit_grooves(x, z, progress=True)
    err = capfd.readouterr().err
    assert "groove fits" in err and "3.00k/3.00k" in err and "frames/s" in err
    assert_same_fits(shown, quiet)
    machscan.fit_grooves(x, z, progress=None)  # stderr is not a terminal here: no bar
    assert capfd.readouterr().err == ""
    s, _ = scan
    md.save_scan(s.select(slice(0, 50)), tmp_path / "p.zarr")
    out = md.map_files(frames_of, [tmp_path / "p.zarr"] * 3, progress=True, scheduler="threads")
    assert [o.result for o in out] == [50, 50, 50]
    assert "100%" in capfd.readouterr().err
    with pytest.raises(TypeError, match="progress"):
        machscan.fit_grooves(x, z, progress="yes")  # type: ignore[arg-type]


def test_batch_grooves_on_a_running_scheduler_by_address(scan, tmp_path, client):
    s, truth = scan
    md.save_scan(s.select(slice(0, 400)), tmp_path / "one.zarr", chunk_frames=100)
    write_contours_csv(tmp_path / "cad.csv", truth.nominal_polylines)
    args = ["batch", "grooves", str(tmp_path / "one.zarr"), "--cad", str(tmp_path / "cad.csv")]
    args += ["--scheduler", client.scheduler.address, "--out", str(tmp_path / "out"), "--no-progress"]
    code = main(args)
    rows = (tmp_path / "out" / "batch.csv").read_text().splitlines()
    assert len(rows) == 2 and str(tmp_path / "one.zarr") in rows[1]
    assert code in (0, 3) and (rows[1].split(",")[1] == "True") == (code == 0)
    assert (tmp_path / "out" / "one" / "frames.csv").stat().st_size > 0


def test_machscan_dask_is_imported_on_first_use():
    code = "import sys, machscan; a = 'dask' in sys.modules; machscan.dask.fit_grooves; print(a, 'dask' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]
    assert "dask" in dir(machscan)
