"""Time and memory of grinding-path generation on a 1 M-point allowance cloud (issue #11 §5), with the accuracy
it keeps at that size: the synthetic blade (paper 003 airfoil, closed sections round the span) and the wavy
panel (convex and concave stretches, exact cusp geometry). There is no reference library that makes grinding
paths to time against; the figures are absolute, on this machine, with the cusp, allowance and removal-check
figures next to them so a faster version cannot trade them away.

    python benchmarks/bench_grinding.py [--points 1000000] [--repeat 1]
"""

import argparse
import math
import resource
import time

import numpy as np

import machscan
from machscan.synth import WavyPanel, blade_allowance

MODEL = dict(C=0.05, exponents=(0.6, -0.7, 0.8), belt_speed=20.0, force=15.0, feed_limits=(0.5, 200.0))


def timed(repeat, f):
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()

    # Blade: ~N points over 5–95 % of the span.
    probe = blade_allowance(spacing=1.0)
    spacing = math.sqrt(len(probe.allowance) / args.points)
    cloud = blade_allowance(spacing=spacing)
    n = len(cloud.allowance)
    t, paths = timed(
        args.repeat,
        lambda: machscan.grinding_paths(cloud.points, cloud.normals, cloud.allowance, 10.0, 0.01, (0, 0, 1), removal_model=MODEL),
    )
    tc, check = timed(1, lambda: machscan.simulate_removal(paths, cloud.points, cloud.normals, cloud.allowance))
    dev = check.deviation
    print(
        f"blade  {n:>9,} points ({spacing:.3f} mm): grinding_paths {t:6.2f} s → {len(paths.row_offsets)} rows, "
        f"{len(paths.points):,} path points; simulate_removal {tc:5.2f} s, stock left {dev.min():+.4f} … {dev.max():+.4f} mm, "
        f"{np.mean(np.abs(dev) <= 0.08) * 100:.3f} % within ±0.08 mm"
    )

    # Panel: ~N points, rows along x.
    panel = WavyPanel(width=80.0, length=100.0)
    spacing = math.sqrt(panel.width * panel.length / args.points)
    pc = panel.sample(spacing, seed=0)
    t, pp = timed(
        args.repeat,
        lambda: machscan.grinding_paths(pc.points, pc.normals, pc.allowance, 8.0, 0.01, (0, 1, 0), removal_model=MODEL),
    )
    cusp = panel.cusp_heights(pp.points, pp.normals, pp.row, 8.0)
    err = np.abs(pp.allowance - panel.allowance_at(pp.points)).max()
    print(
        f"panel  {len(pc.allowance):>9,} points ({spacing:.3f} mm): grinding_paths {t:6.2f} s → {len(pp.row_offsets)} rows, "
        f"{len(pp.points):,} path points; cusp/h max {cusp.max() / 0.01:.3f} mean {cusp.mean() / 0.01:.3f}; "
        f"allowance error max {err * 1000:.3f} µm"
    )
    print(f"peak resident memory of the run: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
