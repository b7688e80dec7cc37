"""Accuracy of blade positioning by touch-probe rounds (issue #9 §3), against the exact truth of
the synthetic blade: 20 misplacements of 0.5 mm / 0.5°, 2 µm probe noise, ball radius 0 or
1 mm, at most 4 rounds. Reports the pose error along the true normals over the whole model (what
the cutter feels) and the full displacement (sliding along the faces included), per probe
pattern and number of points.

    python benchmarks/accuracy_positioning.py [--seeds 20]
"""

import argparse

import numpy as np

import machscan
from machscan.synth import Blade, TouchProbe, misplacement


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    args = ap.parse_args()
    blade = Blade()
    grid, grid_normals = blade.sample(200, 100)
    p, n = grid.reshape(-1, 3), grid_normals.reshape(-1, 3)
    print(f"{'pattern':8} {'keep':>4} {'points':>6} {'along-normal RMS µm: mean':>26} {'max':>5} {'> 2':>4} "
          f"{'displacement RMS µm: mean':>26} {'max':>6} {'rounds':>6}")
    for pattern, keep in (("optimal", 0.5), ("random", 0.25), ("random", 0.5)):
        for points in (160, 400):
            along, full, rounds = [], [], []
            for seed in range(args.seeds):
                truth = misplacement(seed, center=p.mean(axis=0))
                radius = 1.0 if seed % 2 else 0.0
                probe = TouchProbe(blade, truth, radius=radius, noise=0.002, seed=seed)
                r = machscan.position_workpiece(grid, grid_normals, probe, n_points=points, probe_radius=radius,
                                                seed=seed, keep=keep, pattern=pattern, max_rounds=4)
                t = r.transformation
                d = (p @ t[:3, :3].T + t[:3, 3]) - (p @ truth[:3, :3].T + truth[:3, 3])
                along.append(np.sqrt(np.mean(np.einsum("ij,ij->i", d, n @ truth[:3, :3].T) ** 2)) * 1e3)
                full.append(np.sqrt(np.mean(np.sum(d**2, axis=1))) * 1e3)
                rounds.append(len(r.rounds))
            a, f = np.array(along), np.array(full)
            print(f"{pattern:8} {keep:4.2f} {points:6d} {a.mean():26.2f} {a.max():5.2f} {int((a > 2).sum()):4d} "
                  f"{f.mean():26.1f} {f.max():6.1f} {min(rounds):>3}-{max(rounds)}")


if __name__ == "__main__":
    main()
