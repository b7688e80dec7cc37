"""Writes data/profiler-exports/: small profiler exports laid out as the vendors document them,
for the README tour and the tests — a V groove 0.6 mm wide and 0.2 mm deep, its centre wandering
±0.1 mm, 3 % dropouts, 40 frames 0.1 mm apart of 161 readings 0.025 mm apart:

- gocator_profile.csv: LMI Gocator CSV export, Info / DeviceInfo / Profile sections (the layout
  of LMI's Gocator line-profiler manual, "CSV File Format"), empty cells for dropouts;
- keyence_height.csv: Keyence LJ-X height rows as the communication library's samples save
  them: UTF-16, tab-separated, integers in 0.01 µm, dropouts as the sensor's codes.

    python scripts/make_profile_exports.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent.parent / "data" / "profiler-exports"
PITCH, READINGS, FRAMES, Y_PITCH = 0.025, 161, 40, 0.1


def frames() -> tuple[np.ndarray, np.ndarray]:
    x = -2.0 + PITCH * np.arange(READINGS)
    rng = np.random.default_rng(0)
    f = np.empty((FRAMES, READINGS))
    for k in range(FRAMES):
        centre = 0.1 * np.sin(k / 7)
        f[k] = 12.5 - np.clip(0.2 - np.abs(x - centre) * (0.2 / 0.3), 0, None) + rng.normal(0, 0.002, READINGS)
    f[rng.random(f.shape) < 0.03] = np.nan
    return x, np.round(f, 5)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    x, z = frames()
    cell = lambda v: "" if np.isnan(v) else f"{v:.5f}"  # noqa: E731
    lines = [
        "Info",
        "CSV Version,Sensor Count,Trigger Mode,Trigger Rate,Trigger Delay Domain,Trigger Delay,Operation Mode,"
        "XResolution,YResolution,ZResolution,YSpeed,Layout",
        f"2,1,1,200.00000,0,0.00000,2,{PITCH:.5f},{Y_PITCH:.5f},0.00200,20.00000,0",
        "End",
        "",
        "DeviceInfo",
        "ID,Model,Version,Exposure Mode,Exposure 0",
        "41234,2340,5.3.19.50,0,250.000",
        "End",
        "",
        "Profile",
        "Frame Count,Column Count,X Offset,Y Offset,Z Offset",
        f"{FRAMES},{READINGS},{x[0]:.5f},0.00000,0.00000",
        "Frame,Source,Time,Encoder,Z Encoder,Inputs,Exposure,Y,Axis," + ",".join(f"{v:.5f}" for v in x),
    ]
    for k, row in enumerate(z):
        head = f"{k},0,{1_000_000 + 5000 * k},{100 * k},0,0,250,{Y_PITCH * k:.5f}"
        lines.append(f"{head},Z," + ",".join(cell(v) for v in row))
    lines += ["End", ""]
    (OUT / "gocator_profile.csv").write_text("\r\n".join(lines))
    raw = np.round(np.nan_to_num(z, nan=0.0) * 1e5).astype(np.int64)
    raw[np.isnan(z)] = -2147483648
    text = "".join("".join(f"{v}\t" for v in row) + "\r\n" for row in raw)
    (OUT / "keyence_height.csv").write_bytes(b"\xff\xfe" + text.encode("utf-16-le"))
    print(f"written {OUT}")


if __name__ == "__main__":
    main()
