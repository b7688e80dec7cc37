"""Surface meshes against the reference libraries, side by side in one run (issue #10 §6):
Delaunay of 200 k points in xy against scipy.spatial.Delaunay (target ≥ 5×).

    python benchmarks/bench_mesh.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial import Delaunay

import machscan


def best(f, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 300, (200_000, 2))
    pts = np.column_stack([xy, 0.001 * (xy[:, 0] - 150) ** 2])
    ours = best(lambda: machscan.delaunay_xy(pts), args.repeat)
    ref = best(lambda: Delaunay(xy), args.repeat)
    print(f"Delaunay 200k points: machscan {ours * 1e3:.0f} ms, scipy {ref * 1e3:.0f} ms -> {ref / ours:.1f}x")


if __name__ == "__main__":
    main()
