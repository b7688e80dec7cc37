"""Frames + poses → WCS points: machscan against a vectorised NumPy implementation of the same
chain (tests/kinematics_reference.py), side by side on the same data in one run.

Issue #2 target on a 2-core machine: ≥ 5× NumPy and ≥ 20 M points/s (the SR7140 makes 8 M/s).

    python benchmarks/bench_kinematics.py [--frames 2500] [--readings 3200] [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from timing import timed

import machscan
from kinematics_reference import scan_to_wcs_np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=2500)
    ap.add_argument("--readings", type=int, default=3200)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    rng = np.random.default_rng(0)
    f, n = args.frames, args.readings
    frames = rng.normal(0.0, 0.5, (f, n))
    frames[rng.random((f, n)) < 0.03] = -99999.0  # dropouts as the vendor sentinel
    t = np.arange(f) / 2500.0
    axes = np.column_stack(
        [20 * t, 5 * np.sin(t), np.full(f, 150.0), 0.01 * t, 0.02 * t, np.linspace(0, 2 * np.pi, f)]
    )
    c2, mount = (12.5, -3.0, 165.0), (0.004, -0.003, 0.002, 42.0, 1.5, -118.0)
    vr = (-10.0, 10.0)

    ms_best, ms_med, (p1, i1) = timed(
        lambda: machscan.scan_to_wcs(frames, axes, 0.025, c2, mount, valid_range=vr), args.repeat
    )
    np_best, np_med, (p2, i2) = timed(
        lambda: scan_to_wcs_np(frames, axes, 0.025, c2, mount, valid_range=vr), max(2, args.repeat // 2)
    )
    assert np.array_equal(i1, i2) and np.allclose(p1, p2, rtol=0, atol=1e-9), "results differ"
    m = len(i1)
    print(f"machine: {os.cpu_count()} cores; frames {f} x readings {n} = {f * n / 1e6:.1f} M readings, "
          f"{m / 1e6:.2f} M valid points")
    for name, b, med in (("machscan.scan_to_wcs", ms_best, ms_med), ("NumPy reference", np_best, np_med)):
        print(f"{name:<21}: best {b * 1e3:8.1f} ms  median {med * 1e3:8.1f} ms  {m / b / 1e6:7.1f} M points/s")
    print(f"ratio (NumPy / machscan, best): {np_best / ms_best:.1f}x")


if __name__ == "__main__":
    main()
