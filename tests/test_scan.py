"""Tests of machscan.scan (profiler model, Scan container, npz/CSV I/O) and of the NumPy
kinematics reference; the ``test_rust_*`` tests compare the compiled core with that reference.

The ``test_rust_*`` tests need the compiled extension and are never skipped: CI builds it.
While developing without it, deselect them with ``-k "not rust"``.
"""

from __future__ import annotations

import json
import math
import zipfile

import numpy as np
import pytest

import machscan
from kinematics_reference import (
    ac_head_transforms_np,
    interpolate_poses_np,
    mount_rotation,
    profile_to_points_np,
    reading_x,
    rot_x,
    rot_y,
    rot_z,
    scan_to_wcs_np,
    valid_mask_np,
)
from machscan.scan import SENTINEL, Profiler, Scan, read_scan_csv, write_scan_csv

# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def _profiler(n=16, **kw):
    kw.setdefault("pitch", 0.025)
    kw.setdefault("valid_range", (-20.0, 20.0))
    kw.setdefault("sentinel", SENTINEL)
    kw.setdefault("name", "test")
    kw.setdefault("frame_rate", 2500.0)
    return Profiler(readings=n, **kw)


def _random_scan(rng, f=12, n=16, axes=True, profiler=None):
    prof = profiler or _profiler(n)
    frames = rng.normal(0.0, 0.3, (f, n))
    frames[rng.random((f, n)) < 0.1] = SENTINEL
    frames[0, 3] = np.nan
    poses = np.column_stack(
        [
            rng.uniform(-100, 100, (f, 3)),
            rng.uniform(-0.5, 0.5, f),
            rng.uniform(-3, 3, f),
            rng.uniform(-6, 6, f),
        ]
    )
    times = 0.25 + np.arange(f) / 2500.0
    kw = {}
    if axes:
        kw["axis_times"] = np.linspace(0.2, 0.3, 101)
        kw["axis_samples"] = rng.normal(size=(101, 6))
    return Scan(
        frames,
        poses,
        times,
        prof,
        (-120.0, 35.0, 115.0),
        (0.003, -0.002, 0.004, 0.6, -0.4, -140.0),
        metadata={"operator": "test", "part": {"id": 7, "tags": ["a", "b"]}, "gain": 1.5},
        **kw,
    )


def _random_axes(rng, f):
    return np.column_stack(
        [
            rng.uniform(-500, 500, (f, 3)),
            rng.uniform(-1.2, 1.2, f),
            rng.uniform(-7, 7, f),
            rng.uniform(-7, 7, f),
        ]
    )


def _assert_scans_equal(a: Scan, b: Scan):
    np.testing.assert_array_equal(a.frames, b.frames)  # NaN == NaN here
    np.testing.assert_array_equal(a.poses, b.poses)
    np.testing.assert_array_equal(a.frame_times, b.frame_times)
    np.testing.assert_array_equal(a.c2_offset, b.c2_offset)
    np.testing.assert_array_equal(a.mount, b.mount)
    assert a.profiler == b.profiler
    if a.axis_times is None:
        assert b.axis_times is None and b.axis_samples is None
    else:
        np.testing.assert_array_equal(a.axis_times, b.axis_times)
        np.testing.assert_array_equal(a.axis_samples, b.axis_samples)
    for arr in (b.frames, b.poses, b.frame_times, b.c2_offset, b.mount):
        assert arr.dtype == np.float64 and arr.flags.c_contiguous


# --------------------------------------------------------------------------------------------
# the NumPy reference against closed forms (SPEC K2, K3 printed matrices) and loops
# --------------------------------------------------------------------------------------------


def test_reference_rotations_are_right_handed():
    a = 0.3
    np.testing.assert_allclose(rot_z(a) @ [1, 0, 0], [math.cos(a), math.sin(a), 0], atol=1e-15)
    np.testing.assert_allclose(rot_x(a) @ [0, 1, 0], [0, math.cos(a), math.sin(a)], atol=1e-15)
    np.testing.assert_allclose(rot_y(a) @ [0, 0, 1], [math.sin(a), 0, math.cos(a)], atol=1e-15)
    r = rot_z(np.array([0.1, 0.2]))
    assert r.shape == (2, 3, 3)


def test_reference_mount_rotation_matches_spec_k3_matrix():
    th, ps, ph = 0.31, -0.47, 1.13
    ct, st, cs, ss, cf, sf = (math.cos(th), math.sin(th), math.cos(ps), math.sin(ps), math.cos(ph), math.sin(ph))
    spec = np.array(
        [
            [ct * cf, ss * st * cf - cs * sf, cs * st * cf + ss * sf],
            [ct * sf, ss * st * sf + cs * cf, cs * st * sf - ss * cf],
            [-st, ss * ct, cs * ct],
        ]
    )
    np.testing.assert_allclose(mount_rotation(th, ps, ph), spec, atol=1e-15)


def test_reference_chain_matches_spec_k2_k3_closed_form():
    rng = np.random.default_rng(1)
    axes = _random_axes(rng, 50)
    L = np.array([-120.0, 35.0, 115.0])
    mount = np.array([0.02, -0.03, 0.5, 0.6, -0.4, -140.0])
    T = ac_head_transforms_np(axes, L, mount)
    assert T.shape == (50, 4, 4)
    for f in range(50):
        X, Y, Z, a, c, c2 = axes[f]
        rt = np.array(
            [
                [math.cos(c), -math.sin(c) * math.cos(a), math.sin(c) * math.sin(a)],
                [math.sin(c), math.cos(c) * math.cos(a), -math.cos(c) * math.sin(a)],
                [0.0, math.sin(a), math.cos(a)],
            ]
        )
        wt = np.eye(4)
        wt[:3, :3] = rt
        wt[:3, 3] = (X, Y, Z)
        tc2 = np.array(
            [[math.cos(c2), -math.sin(c2), 0, L[0]], [math.sin(c2), math.cos(c2), 0, L[1]], [0, 0, 1, L[2]], [0, 0, 0, 1]]
        )
        tm = np.eye(4)
        tm[:3, :3] = mount_rotation(*mount[:3])
        tm[:3, 3] = mount[3:]
        np.testing.assert_allclose(T[f], wt @ tc2 @ tm, atol=1e-12)
        np.testing.assert_allclose(T[f, :3, :3] @ T[f, :3, :3].T, np.eye(3), atol=1e-14)


def test_reference_scan_to_wcs_matches_per_point_loop():
    rng = np.random.default_rng(2)
    f, n = 7, 9
    frames = rng.normal(0, 1.0, (f, n))
    frames[1, 2] = np.nan
    frames[3, 0] = 50.0  # outside the range
    frames[4, 8] = -2.0  # on the lower bound: valid (inclusive)
    axes = _random_axes(rng, f)
    L, mount = (1.0, 2.0, 3.0), (0.1, 0.2, 0.3, 4.0, 5.0, 6.0)
    pts, fi = scan_to_wcs_np(frames, axes, 0.5, L, mount, center=3.5, valid_range=(-2.0, 2.0))
    T = ac_head_transforms_np(axes, L, mount)
    expect, efi = [], []
    for a in range(f):
        for i in range(n):
            d = frames[a, i]
            if np.isfinite(d) and -2.0 <= d <= 2.0:
                expect.append((T[a] @ [(i - 3.5) * 0.5, 0.0, d, 1.0])[:3])
                efi.append(a)
    np.testing.assert_allclose(pts, np.array(expect), atol=1e-12)
    np.testing.assert_array_equal(fi, efi)
    assert fi.dtype == np.int64
    spts, sfi = profile_to_points_np(frames, 0.5, center=3.5, valid_range=(-2.0, 2.0))
    np.testing.assert_array_equal(sfi, fi)
    np.testing.assert_array_equal(spts[:, 1], 0.0)
    np.testing.assert_allclose(reading_x(4, 0.5), [-1.0, -0.5, 0.0, 0.5])


def test_reference_interpolation_unwraps_rotary_axes():
    t = np.array([0.0, 1.0, 2.0])
    s = np.zeros((3, 6))
    s[:, 0] = [0.0, 10.0, 30.0]
    s[:, 5] = [6.2, 0.1, 0.3]  # wrapped C2 crossing 2 pi
    out = interpolate_poses_np(t, s, [0.5, 1.5])
    np.testing.assert_allclose(out[:, 0], [5.0, 20.0])
    np.testing.assert_allclose(out[0, 5], 0.5 * (6.2 + 0.1 + 2 * np.pi))
    np.testing.assert_allclose(out[1, 5], 0.2 + 2 * np.pi)


# --------------------------------------------------------------------------------------------
# Profiler
# --------------------------------------------------------------------------------------------


def test_profiler_sr7140_facts():
    p = Profiler.sr7140()
    assert (p.readings, p.pitch, p.noise, p.frame_rate, p.name) == (3200, 0.025, 0.008, 2500.0, "SR7140")
    assert p.i0 == 1600.0 and p.center is None
    assert p.x[1600] == 0.0 and p.x[0] == -40.0
    assert p.line_direction == "x" and p.measuring_direction == "z"
    assert p.sentinel == SENTINEL
    assert not (p.valid_range[0] <= SENTINEL <= p.valid_range[1])
    assert Profiler.sr7140(readings=400).x[0] == -5.0
    assert "SR7140" in repr(p)


def test_profiler_valid_mask():
    p = _profiler(4, valid_range=(-1.0, 1.0))
    m = p.valid_mask([[0.0, np.nan, SENTINEL, 1.0], [-1.0, 1.5, -0.5, np.inf]])
    np.testing.assert_array_equal(m, [[True, False, False, True], [True, False, True, False]])
    q = Profiler(readings=3, pitch=1.0, sentinel=-5.0)  # sentinel without a range
    np.testing.assert_array_equal(q.valid_mask([-5.0, 0.0, 1e9]), [False, True, True])


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"readings": 0, "pitch": 0.1}, "readings"),
        ({"readings": 2.5, "pitch": 0.1}, "readings"),
        ({"readings": 10, "pitch": -0.1}, "pitch"),
        ({"readings": 10, "pitch": float("nan")}, "pitch"),
        ({"readings": 10, "pitch": 0.1, "valid_range": (1.0, -1.0)}, "valid_range"),
        ({"readings": 10, "pitch": 0.1, "valid_range": (1.0,)}, "valid_range"),
        ({"readings": 10, "pitch": 0.1, "frame_rate": 0.0}, "frame_rate"),
        ({"readings": 10, "pitch": 0.1, "center": "middle"}, "center"),
    ],
)
def test_profiler_rejects_bad_arguments(kwargs, name):
    with pytest.raises(ValueError, match=name):
        Profiler(**kwargs)


def test_profiler_dict_round_trip():
    for p in (Profiler.sr7140(), Profiler(readings=7, pitch=0.1, center=2.5)):
        assert Profiler.from_dict(json.loads(json.dumps(p.to_dict()))) == p


# --------------------------------------------------------------------------------------------
# Scan validation
# --------------------------------------------------------------------------------------------


def _scan_args(f=5, n=16):
    return dict(
        frames=np.zeros((f, n)),
        poses=np.zeros((f, 6)),
        frame_times=np.arange(f) / 2500.0,
        profiler=_profiler(n),
        c2_offset=(0.0, 0.0, 100.0),
        mount=np.zeros(6),
    )


def test_scan_converts_and_reports_sizes():
    args = _scan_args()
    args["frames"] = np.zeros((5, 16), dtype=np.float32)
    args["poses"] = np.asfortranarray(np.zeros((5, 6)))
    s = Scan(**args)
    assert s.frames.dtype == np.float64 and s.poses.flags.c_contiguous
    assert (s.n_frames, s.n_readings) == (5, 16)
    assert s.duration == pytest.approx(4 / 2500.0)
    r = repr(s)
    assert "5 frames x 16 readings" in r and "test" in r and "0.002 s" in r


@pytest.mark.parametrize(
    "field_, value, pattern",
    [
        ("frames", np.zeros(16), r"frames: expected shape \(F, 16\).*got \(16,\)"),
        ("frames", np.zeros((5, 15)), r"frames: expected shape \(F, 16\).*got \(5, 15\)"),
        ("poses", np.zeros((4, 6)), r"poses: expected shape \(F, 6\) with F = 5 frames, got \(4, 6\)"),
        ("poses", np.zeros((5, 5)), r"poses: .*got \(5, 5\)"),
        ("frame_times", np.zeros(4), r"frame_times: expected shape \(F,\) with F = 5"),
        ("frame_times", [0.0, 1.0, 0.5, 2.0, 3.0], r"frame_times: .*frame 2"),
        ("frame_times", [0.0, 1.0, np.nan, 2.0, 3.0], r"frame_times: entry 2"),
        ("c2_offset", (1.0, 2.0), r"c2_offset: expected shape \(3,\)"),
        ("mount", np.zeros(5), r"mount: expected shape \(6,\)"),
        ("mount", [0, 0, 0, 0, np.inf, 0], r"mount: entry 4"),
        ("profiler", "SR7140", r"profiler:"),
        ("metadata", {"a": object()}, r"metadata: must be JSON"),
        ("metadata", {1: "x"}, r"metadata: keys must be str"),
        ("frames", [["a"] * 16] * 5, r"frames: cannot be read"),
    ],
)
def test_scan_rejects_bad_fields(field_, value, pattern):
    args = _scan_args()
    args[field_] = value
    with pytest.raises(ValueError, match=pattern):
        Scan(**args)


def test_scan_rejects_nan_pose_naming_first_bad_row():
    args = _scan_args()
    args["poses"][2, 4] = np.nan
    args["poses"][3, 0] = np.nan
    with pytest.raises(ValueError, match=r"poses: row 2 is not finite.*2 bad rows"):
        Scan(**args)


def test_scan_axis_samples_validation():
    args = _scan_args()
    with pytest.raises(ValueError, match="axis_samples"):
        Scan(**args, axis_times=np.arange(3.0))
    with pytest.raises(ValueError, match="axis_times"):
        Scan(**args, axis_samples=np.zeros((3, 6)))
    with pytest.raises(ValueError, match=r"axis_samples: expected shape \(S, 6\) with S = 3"):
        Scan(**args, axis_times=np.arange(3.0), axis_samples=np.zeros((3, 5)))
    with pytest.raises(ValueError, match=r"axis_times: .*sample 2"):
        Scan(**args, axis_times=[0.0, 1.0, 1.0], axis_samples=np.zeros((3, 6)))
    with pytest.raises(ValueError, match=r"axis_samples: row 1"):
        Scan(**args, axis_times=[0.0, 1.0, 2.0], axis_samples=[[0] * 6, [0, 0, np.nan, 0, 0, 0], [0] * 6])


def test_scan_select():
    s = _random_scan(np.random.default_rng(3))
    sub = s.select(slice(2, 5))
    np.testing.assert_array_equal(sub.frames, s.frames[2:5])
    np.testing.assert_array_equal(sub.frame_times, s.frame_times[2:5])
    mask = np.zeros(s.n_frames, dtype=bool)
    mask[[0, 7]] = True
    np.testing.assert_array_equal(s.select(mask).poses, s.poses[[0, 7]])
    with pytest.raises(ValueError, match="index"):
        s.select(np.ones(3, dtype=bool))


# --------------------------------------------------------------------------------------------
# npz round trip
# --------------------------------------------------------------------------------------------


def test_save_load_round_trip_is_exact(tmp_path):
    s = _random_scan(np.random.default_rng(4))
    p = tmp_path / "scan.npz"
    s.save(p)
    back = Scan.load(p)
    _assert_scans_equal(s, back)
    assert back.metadata == s.metadata
    with np.load(p, allow_pickle=False) as z:  # no pickles anywhere
        assert all(z[k].dtype != object for k in z.files)


def test_save_load_without_axis_samples_and_custom_profiler(tmp_path):
    prof = Profiler(
        readings=16, pitch=0.1, center=7.25, valid_range=None, sentinel=None, name="custom", noise=None, frame_rate=None
    )
    s = _random_scan(np.random.default_rng(5), axes=False, profiler=prof)
    p = tmp_path / "scan_without_extension"
    s.save(p)
    assert p.exists() and not (tmp_path / "scan_without_extension.npz").exists()
    back = Scan.load(p)
    _assert_scans_equal(s, back)
    assert back.profiler.center == 7.25 and back.profiler.valid_range is None


def test_load_rejects_foreign_npz(tmp_path):
    p = tmp_path / "other.npz"
    np.savez(p, frames=np.zeros((2, 2)))
    with pytest.raises(ValueError, match=r"path: .*not a machscan scan file"):
        Scan.load(p)
    assert zipfile.is_zipfile(p)


# --------------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("timestamps", [True, False])
@pytest.mark.parametrize("header", [True, False])
@pytest.mark.parametrize("delimiter", [",", ";", "\t"])
def test_csv_round_trip_is_exact(tmp_path, timestamps, header, delimiter):
    s = _random_scan(np.random.default_rng(6), axes=False)
    if not timestamps:  # without a time column the frame times come from the frame rate
        s = Scan(s.frames, s.poses, np.arange(s.n_frames) / 2500.0, s.profiler, s.c2_offset, s.mount)
    fp, pp = tmp_path / "frames.csv", tmp_path / "poses.csv"
    write_scan_csv(s, fp, pp, delimiter=delimiter, timestamps=timestamps, header=header)
    back = read_scan_csv(fp, pp, s.profiler, s.c2_offset, s.mount, delimiter=delimiter)
    _assert_scans_equal(s, back)
    assert back.metadata["source"]["frames_csv"] == str(fp)


def test_csv_times_from_poses_file_only(tmp_path):
    s = _random_scan(np.random.default_rng(7), axes=False)
    fp, pp = tmp_path / "f.csv", tmp_path / "p.csv"
    np.savetxt(fp, s.frames, fmt="%.17g", delimiter=",")
    np.savetxt(pp, np.column_stack([s.frame_times, s.poses]), fmt="%.17g", delimiter=",")
    back = read_scan_csv(fp, pp, s.profiler, s.c2_offset, s.mount)
    np.testing.assert_array_equal(back.frame_times, s.frame_times)


def _write_lines(path, lines):
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def csv_pair(tmp_path):
    prof = _profiler(3)
    fp, pp = tmp_path / "frames.csv", tmp_path / "poses.csv"
    _write_lines(fp, ["t,r0,r1,r2", "0.0,1,2,3", "0.1,4,5,6", "0.2,7,8,9"])
    _write_lines(pp, ["t,X,Y,Z,A,C,C2", "0.0,1,2,3,0,0,0", "0.1,1,2,3,0,0,0", "0.2,1,2,3,0,0,0"])
    return prof, fp, pp


def test_csv_reads_small_files(csv_pair):
    prof, fp, pp = csv_pair
    s = read_scan_csv(fp, pp, prof, (0, 0, 0), np.zeros(6))
    np.testing.assert_array_equal(s.frames, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    np.testing.assert_array_equal(s.frame_times, [0.0, 0.1, 0.2])


@pytest.mark.parametrize(
    "which, lines, pattern",
    [
        (
            "frames",
            ["t,r0,r1,r2", "0.0,1,2,3", "0.1,4,5", "0.2,7,8,9"],
            r"frames.csv: line 3 \(frames_csv\): ragged row: 3 cells, where the first data row has 4",
        ),
        (
            "frames",
            ["t,r0,r1,r2", "0.0,1,2,3", "0.1,4,5,6", "0.2,7,x8,9"],
            r"frames.csv: line 4, column 3 \(frames_csv\): \"x8\" is not a number",
        ),
        ("frames", ["0.0,1,2,3", "0.1,4,,6", "0.2,7,8,9"], r"frames.csv: line 2, column 3 \(frames_csv\): empty cell"),
        (
            "frames",
            ["t,r0,r1,r2", "0.0,1,2,3,4,5", "0.1,4,5,6,7,8", "0.2,7,8,9,1,2"],
            r"frames.csv: line 2 \(frames_csv\): 6 cells, expected 3 or 4",
        ),
        (
            "frames",
            ["t,r0,r1,r2", "0.0,1,2,3", "0.1,4,5,6"],
            r"poses_csv: '.*poses.csv' has 3 data rows but frames_csv '.*frames.csv' has 2",
        ),
        (
            "poses",
            ["t,X,Y,Z,A,C,C2", "0.0,1,2,3,0,0,0", "0.1,1,2,3,0,0", "0.2,1,2,3,0,0,0"],
            r"poses.csv: line 3 \(poses_csv\): ragged row",
        ),
        (
            "poses",
            ["0.0,1,2,3,0,0,0", "0.15,1,2,3,0,0,0", "0.2,1,2,3,0,0,0"],
            r"poses_csv: '.*', line 2: time 0.15 s differs from the frame time 0.1 s",
        ),
        (
            "poses",
            ["t,X,Y,Z,A,C,C2", "0.0,1,2,3,0,0,0", "0.1,1,nan,3,0,0,0", "0.2,1,2,3,0,0,0"],
            r"poses.csv: line 3, column 3 \(poses_csv\): nan is not finite",
        ),
        ("poses", ["0,1,2,3,0", "0,1,2,3,0", "0,1,2,3,0"], r"poses.csv: line 1 \(poses_csv\): 5 cells, expected 6 or 7"),
    ],
)
def test_csv_errors_name_file_and_line(csv_pair, which, lines, pattern):
    prof, fp, pp = csv_pair
    _write_lines(fp if which == "frames" else pp, lines)
    with pytest.raises(ValueError, match=pattern):
        read_scan_csv(fp, pp, prof, (0, 0, 0), np.zeros(6))


def test_csv_backwards_time_is_reported(tmp_path):
    prof = _profiler(2)
    fp, pp = tmp_path / "f.csv", tmp_path / "p.csv"
    _write_lines(fp, ["0.0,1,2", "0.2,1,2", "0.1,1,2"])
    _write_lines(pp, ["1,2,3,0,0,0"] * 3)
    with pytest.raises(ValueError, match=r"frames_csv: '.*f.csv', line 3: timestamp 0.1 s is earlier"):
        read_scan_csv(fp, pp, prof, (0, 0, 0), np.zeros(6))


def test_csv_without_any_time_needs_frame_rate(tmp_path):
    prof = Profiler(readings=2, pitch=0.1)
    fp, pp = tmp_path / "f.csv", tmp_path / "p.csv"
    _write_lines(fp, ["1,2", "3,4"])
    _write_lines(pp, ["1,2,3,0,0,0"] * 2)
    with pytest.raises(ValueError, match="frame_rate"):
        read_scan_csv(fp, pp, prof, (0, 0, 0), np.zeros(6))
    # The OS's refusal stays an OSError (not a ValueError), naming the file.
    with pytest.raises(FileNotFoundError, match=r"missing\.csv"):
        read_scan_csv(tmp_path / "missing.csv", pp, prof, (0, 0, 0), np.zeros(6))


# --------------------------------------------------------------------------------------------
# compiled core against the reference (never skipped; CI builds the extension)
# --------------------------------------------------------------------------------------------


def test_rust_profile_to_points_matches_reference():
    rng = np.random.default_rng(10)
    frames = rng.normal(0, 2.0, (40, 321))
    frames[rng.random(frames.shape) < 0.05] = np.nan
    frames[rng.random(frames.shape) < 0.05] = SENTINEL
    for center, vr in ((None, None), (100.5, (-3.0, 3.0)), (None, (-1.0, 1.0))):
        f = np.where(frames == SENTINEL, np.nan, frames) if vr is None else frames
        got, gfi = machscan.profile_to_points(f, 0.025, center=center, valid_range=vr)
        exp, efi = profile_to_points_np(f, 0.025, center=center, valid_range=vr)
        np.testing.assert_allclose(got, exp, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(gfi, efi)
        assert gfi.dtype == np.int64


def test_rust_ac_head_transforms_matches_reference():
    rng = np.random.default_rng(11)
    axes = _random_axes(rng, 500)
    L = rng.normal(0, 100, 3)
    mount = np.concatenate([rng.normal(0, 0.5, 3), rng.normal(0, 50, 3)])
    got = machscan.ac_head_transforms(axes, L, mount)
    assert got.shape == (500, 4, 4)
    np.testing.assert_allclose(got, ac_head_transforms_np(axes, L, mount), rtol=0, atol=1e-10)


def test_rust_scan_to_wcs_matches_reference():
    rng = np.random.default_rng(12)
    f, n = 300, 640
    frames = rng.normal(0, 1.0, (f, n))
    frames[rng.random(frames.shape) < 0.03] = np.nan
    frames[rng.random(frames.shape) < 0.03] = SENTINEL
    axes = _random_axes(rng, f)
    L = (-120.0, 35.0, 115.0)
    mount = (0.003, -0.002, 0.004, 0.6, -0.4, -140.0)
    for center in (None, 317.25):
        got, gfi = machscan.scan_to_wcs(frames, axes, 0.025, L, mount, center=center, valid_range=(-20.0, 20.0))
        exp, efi = scan_to_wcs_np(frames, axes, 0.025, L, mount, center=center, valid_range=(-20.0, 20.0))
        np.testing.assert_array_equal(gfi, efi)
        np.testing.assert_allclose(got, exp, rtol=0, atol=1e-9)


def test_rust_interpolate_poses_matches_reference():
    rng = np.random.default_rng(13)
    st = np.sort(rng.uniform(0, 10, 2000))
    st = np.unique(st)
    samples = np.cumsum(rng.normal(0, 0.05, (st.size, 6)), axis=0)
    samples[:, 5] = np.mod(np.linspace(0, 40, st.size), 2 * np.pi)  # wrapped C2, 6+ turns
    ft = np.sort(rng.uniform(st[0], st[-1], 700))
    got = machscan.interpolate_poses(st, samples, ft, rotary=(3, 4, 5))
    exp = interpolate_poses_np(st, samples, ft, rotary=(3, 4, 5))
    np.testing.assert_allclose(got, exp, rtol=0, atol=1e-9)


def test_rust_scan_methods_match_reference():
    rng = np.random.default_rng(14)
    s = _random_scan(rng, f=30, n=64)
    p = s.profiler
    pts, fi = s.wcs_points()
    exp, efi = scan_to_wcs_np(s.frames, s.poses, p.pitch, s.c2_offset, s.mount, valid_range=p.valid_range)
    np.testing.assert_array_equal(fi, efi)
    np.testing.assert_allclose(pts, exp, rtol=0, atol=1e-9)
    assert fi.size == int(s.valid_mask().sum())
    spts, _sfi = s.scs_points()
    np.testing.assert_allclose(spts, profile_to_points_np(s.frames, p.pitch, valid_range=p.valid_range)[0], atol=1e-12)
    np.testing.assert_allclose(s.transforms(), ac_head_transforms_np(s.poses, s.c2_offset, s.mount), atol=1e-10)
    # sentinel without a valid range: the Scan turns it into NaN before calling the core
    prof = Profiler(readings=64, pitch=0.025, sentinel=SENTINEL)
    s2 = Scan(s.frames, s.poses, s.frame_times, prof, s.c2_offset, s.mount)
    pts2, fi2 = s2.wcs_points()
    mask = valid_mask_np(np.where(s.frames == SENTINEL, np.nan, s.frames))
    assert fi2.size == int(mask.sum())
    np.testing.assert_allclose(pts2, exp, atol=1e-9)
