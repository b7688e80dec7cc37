"""Accuracy and time of mirror-milling compensation (issue #10 §5), against the closed-form truth of the
synthetic bent skin: a 300 × 200 mm plate bent to R = 1000 mm, misplaced by 1 mm / 0.5° (one seed per run),
scanned at 1.3 mm with 5 µm noise, two locating points and an 8 × 8 grid of matching points; a raster toolpath
on the skin and a second 2 mm into it. For each Jacobian and geodesic method: the matched points' error (RMS,
max), the iterations, the time; then the compensated toolpath's error (max inside the hull), the tool axes'
error and the reduction against the uncompensated path, for the default mapping and the paper's variant.

    python benchmarks/accuracy_mirror_milling.py [--seeds 3] [--methods exact,fmm]
"""

import argparse
import time

import numpy as np

import machscan
from machscan.synth import BentSkin, misplacement


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--methods", default="exact,fmm")
    args = ap.parse_args()
    print(
        f"{'seed':>4} {'method':6} {'jacobian':9} {'matched RMS µm':>14} {'max':>6} {'iter':>4} {'stop':>9} "
        f"{'match s':>7} | {'mapping':16} {'path max µm':>11} {'axes max °':>10} {'less error':>10} {'s':>5}"
    )
    for seed in range(args.seeds):
        skin = BentSkin(pose=misplacement(seed, translation=1.0, rotation=np.deg2rad(0.5)))
        theoretical, scan = skin.grid(1.3), skin.scan(1.3, 0.005, seed=seed)
        r, grid = skin.locating(), skin.matching_grid()
        r_actual, truth_grid = skin.actual(r)[0], skin.actual(grid)[0]
        tools = np.vstack([skin.raster(depth=0.0), skin.raster(step=25.0, depth=-2.0)])
        truth, normals = skin.actual(tools)
        before = np.linalg.norm(tools - truth, axis=1).max()
        for method in args.methods.split(","):
            for jacobian in ("quadratic", "gradient"):
                t0 = time.perf_counter()
                m = machscan.isometric_match(theoretical, scan, r, r_actual, grid, jacobian=jacobian, method=method)
                t_match = time.perf_counter() - t0
                e = np.linalg.norm(m.points - truth_grid, axis=1)
                head = (
                    f"{seed:4d} {method:6} {jacobian:9} {np.sqrt(np.mean(e**2)) * 1e3:14.1f} {e.max() * 1e3:6.1f} "
                    f"{m.iterations:4d} {m.stop:>9} {t_match:7.1f}"
                )
                for label, kw in (("cubic/smooth", {}), ("paper (linear/tri)", dict(interpolation="linear", normals="triangle"))):
                    t0 = time.perf_counter()
                    p = machscan.compensate_toolpath(tools, grid, m.points, scan, **kw)
                    t_comp = time.perf_counter() - t0
                    err = np.linalg.norm(p.points - truth, axis=1)[p.inside].max()
                    tilt = np.degrees(np.arccos(np.clip(np.sum(p.axes * normals, axis=1), -1, 1)))[p.inside].max()
                    print(f"{head} | {label:18} {err * 1e3:9.1f} {tilt:10.3f} {100 * (1 - err / before):9.2f}% {t_comp:5.2f}")
                    head = " " * len(head)


if __name__ == "__main__":
    main()
