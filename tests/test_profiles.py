"""Line-profiler exports to a Scan (``machscan.io.read_profiles``): Gocator CSV (Profile and Part
sections, laid out as LMI's manual describes them) and Keyence height rows (as the LJ-X
communication library's samples write them), written here from known frames; the route on to
groove fits and points; and the messages for files machscan does not read."""

from __future__ import annotations

import numpy as np
import pytest

import machscan
from machscan.cli import main

PITCH, READINGS = 0.025, 161


def groove_frames(n_frames: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """x grid and frames of a V groove 0.6 mm wide and 0.2 mm deep on a surface at 12.5 mm,
    with dropouts (NaN)."""
    x = -2.0 + PITCH * np.arange(READINGS)
    rng = np.random.default_rng(seed)
    frames = np.empty((n_frames, READINGS))
    for f in range(n_frames):
        centre = 0.1 * np.sin(f / 7)
        frames[f] = 12.5 - np.clip(0.2 - np.abs(x - centre) * (0.2 / 0.3), 0, None)
    frames[rng.random(frames.shape) < 0.03] = np.nan
    return x, np.round(frames, 5)


def cell(v: float) -> str:
    return "" if np.isnan(v) else f"{v:.5f}"


def write_gocator_profile(path, x, frames, y, time_us, encoder) -> None:
    lines = [
        "Info",
        "CSV Version,Sensor Count,Trigger Mode,Trigger Rate,Trigger Delay Domain,Trigger Delay,Operation Mode,"
        "XResolution,YResolution,ZResolution,YSpeed,Layout",
        f"2,1,1,200.00000,0,0.00000,2,{PITCH:.5f},0.10000,0.00200,20.00000,0",
        "End",
        "",
        "DeviceInfo",
        "ID,Model,Version,Exposure Mode,Exposure 0",
        "41234,2340,5.3.19.50,0,250.000",
        "End",
        "",
        "Profile",
        "Frame Count,Column Count,X Offset,Y Offset,Z Offset",
        f"{len(frames)},{len(x)},{x[0]:.5f},0.00000,0.00000",
        "Frame,Source,Time,Encoder,Z Encoder,Inputs,Exposure,Y,Axis," + ",".join(f"{v:.5f}" for v in x),
    ]
    for f, row in enumerate(frames):
        head = f"{f},0,{time_us[f]},{encoder[f]},0,0,250,{y[f]:.5f}"
        lines.append(f"{head},Z," + ",".join(cell(v) for v in row))
        lines.append(f"{head},I," + ",".join("100" for _ in row))
    lines += ["End", ""]
    path.write_text("\r\n".join(lines))


def test_a_gocator_profile_export_is_a_scan_of_its_frames(tmp_path):
    x, frames = groove_frames(40)
    y = 0.1 * np.arange(40)
    time_us = 1_000_000 + 5000 * np.arange(40)
    encoder = 100 * np.arange(40)
    path = tmp_path / "export.csv"
    write_gocator_profile(path, x, frames, y, time_us, encoder)
    scan = machscan.io.read_profiles(path)
    assert scan.n_frames == 40 and scan.n_readings == READINGS
    np.testing.assert_array_equal(np.isnan(scan.frames), np.isnan(frames))
    np.testing.assert_allclose(scan.frames, frames, atol=0, equal_nan=True)
    assert scan.profiler.pitch == pytest.approx(PITCH, abs=1e-12)
    np.testing.assert_allclose(scan.profiler.x, x, atol=1e-9)
    np.testing.assert_allclose(scan.frame_times, (time_us - time_us[0]) * 1e-6, atol=1e-12)
    assert scan.metadata["encoder"] == list(map(float, encoder)) and scan.metadata["serial"] == "41234"
    assert scan.profiler.name == "Gocator 2340"
    # The points are the vendor's own (x, y, z); NaN readings dropped.
    points, _ = scan.wcs_points()
    valid = ~np.isnan(frames)
    xs, ys = np.broadcast_to(x, frames.shape)[valid], np.broadcast_to(y[:, None], frames.shape)[valid]
    want = np.column_stack([xs, ys, frames[valid]])
    np.testing.assert_allclose(points, want, atol=1e-9)
    # On to the groove fit: 0.6 mm wide, 0.2 mm deep.
    fits = machscan.fit_grooves(scan.profiler.x, scan.frames)
    ok = fits.ok
    assert ok.mean() > 0.9
    assert np.median(np.abs(fits.width[ok] - 0.6)) < 0.01 and np.median(np.abs(fits.depth[ok] - 0.2)) < 0.005


def test_a_gocator_part_export_is_a_frame_per_row(tmp_path):
    x, frames = groove_frames(5, seed=1)
    y = -1.0 + 0.2 * np.arange(5)
    rows = [
        "Part",
        "Frame,Source,Time,Encoder,Z Encoder,Inputs,Row Count,Column Count,X Offset,Y Offset,Z Offset",
        f"1,0,544820424776,7,0,0,5,{READINGS},{x[0]:.5f},-1.00000,0.00000",
        "Y\\X," + ",".join(f"{v:.5f}" for v in x),
        *(f"{y[r]:.5f}," + ",".join(cell(v) for v in frames[r]) for r in range(5)),
        "End",
    ]
    path = tmp_path / "part.csv"
    path.write_text("\n".join(rows) + "\n")
    scan = machscan.io.read_profiles(path)
    np.testing.assert_allclose(scan.frames, frames, equal_nan=True)
    np.testing.assert_allclose(scan.poses[:, 1], y)
    assert scan.metadata["layout"] == "Gocator Part" and np.all(scan.frame_times == 0)


def test_keyence_height_rows_need_their_grid_and_drop_the_sensor_codes(tmp_path):
    x, frames = groove_frames(6, seed=2)
    raw = np.round(np.nan_to_num(frames) * 1e5).astype(np.int64)  # 0.01 µm
    codes = np.array([-2147483648, -2147483647, -2147483646, -2147483645])
    raw[np.isnan(frames)] = codes[np.arange(np.isnan(frames).sum()) % 4]
    path = tmp_path / "scan_height.csv"
    text = "".join("".join(f"{v}\t" for v in row) + "\r\n" for row in raw)
    path.write_bytes(b"\xff\xfe" + text.encode("utf-16-le"))
    with pytest.raises(ValueError, match="pitch, x_start, y_pitch: a Keyence height export"):
        machscan.io.read_profiles(path)
    scan = machscan.io.read_profiles(path, pitch=PITCH, x_start=-2.0, y_pitch=0.05)
    np.testing.assert_allclose(scan.frames, frames, atol=1e-9, equal_nan=True)
    np.testing.assert_allclose(scan.profiler.x, x, atol=1e-12)
    np.testing.assert_allclose(scan.poses[:, 1], 0.05 * np.arange(6))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("Profile\nFrame Count\n1\nFrame,Y,Axis,0.0,0.1\n0,0,Z,1.0,high\nEnd\n", r"line 5, column 5: expected a height"),
        ("RawProfile\nFrame\n1\nEnd\n", "not on an x grid"),
        ("Info\nXResolution\n0.1\nEnd\n", "expected a Profile or Part section"),
        ("Profile\nFrame Count\n1\nFrame,Y,Axis,0.0,0.1,0.3\n0,0,Z,1.0,1.1,1.2\nEnd\n", "not an even grid"),
    ],
)
def test_layouts_machscan_does_not_read_are_named(tmp_path, text, message):
    path = tmp_path / "odd.csv"
    path.write_text(text)
    with pytest.raises(machscan.io.FileFormatError, match=message) as e:
        machscan.io.read_profiles(path)
    assert "odd.csv" in str(e.value)


def test_the_cli_reads_a_gocator_export_as_a_scan(tmp_path):
    x, frames = groove_frames(30)
    path = tmp_path / "export.csv"
    write_gocator_profile(path, x, frames, 0.1 * np.arange(30), 1000 * np.arange(30), np.arange(30))
    out = tmp_path / "cloud.ply"
    assert main(["points", str(path), "--out", str(out)]) == 0
    cloud = machscan.io.read(out)
    assert len(cloud.points) == int((~np.isnan(frames)).sum())
