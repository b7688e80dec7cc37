"""How the model's sampling sets the allowance's accuracy (issue #32 §3): a stadium extruded along z (edges of 1.5 mm
whose curvature jumps to the flats', tests/analytic_blades.py), the model sampled as a CAD mesh is (Poisson-disk: no
two points closer than 0.8 of the spacing, as `CadMesh.sample` does) or uniformly at random (with gaps), the blank on
its own jittered grid with a stock varying 0.1–0.5 mm round it and along it. Truth exact: the stock at each model point.

    python benchmarks/accuracy_allowance_sampling.py [--model-spacings 0.15,0.2,0.3,0.5] [--spacings 0.5,0.75,1.0]
        [--kinds poisson,random] [--seeds 5]

Prints, per model sampling and blank spacing, the largest |error| (µm) of the stock field (default) and of the blank's
own quadric, and the NaN count (none: the blank covers the model).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import machscan

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import analytic_blades as parts

PERIMETER = 4 * 5.0 + 2 * np.pi * 1.5
SPAN = (2.0, 18.0)


def stock(sigma, z):
    return 0.3 + 0.2 * np.sin(2 * np.pi * sigma / PERIMETER + 0.4) * np.cos(z / 7)


def poisson_disk(spacing: float, rng: np.random.Generator) -> np.ndarray:
    """(sigma, z) with no two closer than 0.8·spacing on the unrolled surface (dart throwing on a grid)."""
    r = 0.8 * spacing
    count = int(PERIMETER * (SPAN[1] - SPAN[0]) / spacing**2 * 3)
    darts = np.column_stack([rng.uniform(0, PERIMETER, count), rng.uniform(*SPAN, count)])
    cells: dict[tuple[int, int], list[np.ndarray]] = {}
    kept = []
    for c in darts:
        gx, gy = int(c[0] // r), int(c[1] // r)
        near = (q for dx in (-1, 0, 1) for dy in (-1, 0, 1) for q in cells.get((gx + dx, gy + dy), []))
        if all(min(abs(c[0] - q[0]), PERIMETER - abs(c[0] - q[0])) ** 2 + (c[1] - q[1]) ** 2 >= r * r for q in near):
            cells.setdefault((gx, gy), []).append(c)
            kept.append(c)
    return np.array(kept)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model-spacings", default="0.15,0.2,0.3,0.5", help="model spacings, mm")
    ap.add_argument("--spacings", default="0.5,0.75,1.0", help="blank spacings, mm")
    ap.add_argument("--kinds", default="poisson,random", help="model samplings")
    ap.add_argument("--seeds", type=int, default=1, help="draws of model and blank (seeds 5, 6, …); the worst is shown")
    args = ap.parse_args()
    print(f"{'model':>8} {'mm':>5} {'points':>7} {'blank mm':>8} {'stock µm':>9} {'quadric µm':>11} {'NaN':>4}")
    for kind in args.kinds.split(","):
        for m in map(float, args.model_spacings.split(",")):
            for s in map(float, args.spacings.split(",")):
                worst, nans, points = [0.0, 0.0], 0, 0
                for seed in range(5, 5 + args.seeds):
                    rng = np.random.default_rng(seed)
                    if kind == "poisson":
                        sz = poisson_disk(m, rng)
                    else:
                        count = int(PERIMETER * (SPAN[1] - SPAN[0]) / m**2)
                        sz = np.column_stack([rng.uniform(0, PERIMETER, count), rng.uniform(*SPAN, count)])
                    model, normals = parts.stadium(sz[:, 0], sz[:, 1])
                    truth = stock(sz[:, 0], sz[:, 1])
                    gs, gz = np.meshgrid(np.arange(0, PERIMETER, s), np.arange(SPAN[0] - 4, SPAN[1] + 4, s))
                    gs = gs + rng.uniform(-0.3 * s, 0.3 * s, gs.shape)
                    gz = gz + rng.uniform(-0.3 * s, 0.3 * s, gz.shape)
                    surface, n = parts.stadium(gs.ravel(), gz.ravel())
                    blank = surface + stock(gs.ravel(), gz.ravel())[:, None] * n
                    a = machscan.allowance(model, normals, blank)
                    q = machscan.allowance(model, normals, blank, surface="quadric")
                    worst = [max(w, 1e3 * np.nanmax(np.abs(x - truth))) for w, x in zip(worst, (a, q))]
                    nans += int(np.isnan(a).sum())
                    points = len(model)
                print(f"{kind:>8} {m:5.2f} {points:7d} {s:8.2f} {worst[0]:9.1f} {worst[1]:11.1f} {nans:4d}", flush=True)


if __name__ == "__main__":
    main()
