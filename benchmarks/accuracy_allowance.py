"""Accuracy of machscan.allowance on blades unlike the built-in one (issue #32 §3): twisted elliptic sections,
circular-arc (lenticular) sections with filleted edges, straight and twisted, a crescent with a concave side, edge
radii 0.3–2 mm, blanks sampled 0.2–1 mm apart on their own jittered grid, offset uniformly (+0.3, −0.1 mm) or
smoothly (0.1–0.5 mm), with optional noise. The truth is exact: the line along the model normal meets the analytic
offset surface (Newton on the part's parameters, tests/analytic_blades.py).

    python benchmarks/accuracy_allowance.py [--noise 0.005] [--parts E0.8,Lt0.5] [--spacings 0.2,0.5,1.0]
        [--model-spacing 0.15] [--model-rows 4] [--surfaces stock,quadric,plane]

Prints, per part, blank spacing and offset, the largest and RMS error near the edges (within 2 + 2 r of an edge
tip) and elsewhere, in µm, the NaN count (the blank covers every model point: there should be none) and the time per
model point, for the stock field (default), the quadric and the paper's plane. The model is sampled in sections
(`--model-spacing` along them, `--model-rows` apart): the stock field reads the model's shape between its points.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import machscan

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import analytic_blades as parts


def catalogue() -> dict[str, parts.Blade]:
    e, lens = parts.EllipseSection, parts.LenticularSection
    twisted = dict(twist_deg=30, lean=(0.05, 0.02), bow=(5e-4, 0))
    return {
        "E0.3": parts.Blade(e.with_edge_radius(20, 0.3), 60, **twisted),
        "E0.5": parts.Blade(e.with_edge_radius(20, 0.5), 60, **twisted),
        "E0.8": parts.Blade(e(20, 4), 60, **twisted),
        "E2.0": parts.Blade(e.with_edge_radius(20, 2.0), 60, **twisted),
        "Ls0.8": parts.Blade(lens(20, 3, 2, 0.8), 60, 0),
        "Ls1.5": parts.Blade(lens(20, 3, 2, 1.5), 60, 0),
        "Lt0.5": parts.Blade(lens(20, 3, 2, 0.5), 60, **twisted),
        "Lt1.2": parts.Blade(lens(20, 3, 2, 1.2), 60, **twisted),
        "Ct0.5": parts.Blade(lens(20, 5, -1.5, 0.5), 60, **twisted),
        "Ct1.5": parts.Blade(lens(20, 5, -1.5, 1.5), 60, **twisted),
    }


def statistics(error: np.ndarray, near_edge: np.ndarray) -> str:
    cells = []
    for zone in (near_edge, ~near_edge):
        e = error[zone]
        ok = np.isfinite(e)
        worst = 1e3 * np.abs(e[ok]).max() if ok.any() else np.nan
        rms = 1e3 * np.sqrt(np.mean(e[ok] ** 2)) if ok.any() else np.nan
        cells.append(f"{worst:7.1f} {rms:6.1f} {int((~ok).sum()):5d}")
    return " | ".join(cells)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--noise", type=float, default=0.0, help="Gaussian noise of the blank along its normal, mm")
    ap.add_argument("--parts", default=None, help="comma-separated names (default: all)")
    ap.add_argument("--spacings", default="0.2,0.3,0.5,0.75,1.0", help="blank spacings, mm")
    ap.add_argument("--offsets", default="0.3,-0.1,smooth", help="uniform offsets in mm, or 'smooth'")
    ap.add_argument("--model-spacing", type=float, default=0.15, help="model points along each section, mm")
    ap.add_argument("--model-rows", type=float, default=4.0, help="model sections apart along the span, mm")
    ap.add_argument("--surfaces", default="stock,quadric,plane", help="comma-separated surfaces to compare")
    args = ap.parse_args()
    cat = catalogue()
    names = args.parts.split(",") if args.parts else list(cat)
    print(f"{'part':6} {'s mm':>5} {'r/s':>5} {'offset':>7} {'surface':8} "
          f"{'edge max µm':>11} {'rms':>6} {'NaN':>5} | {'rest max':>7} {'rms':>6} {'NaN':>5}   µs/pt")
    for name in names:
        blade = cat[name]
        r = blade.section.edge_radius
        u, z = blade.model_grid(args.model_spacing, (2, 58), span_spacing=args.model_rows)
        p, v = blade.point(u, z), blade.normal(u, z)
        near_edge = blade.section.edge_distance(u) < 2 + 2 * r
        for s in map(float, args.spacings.split(",")):
            if r < 0.75 * s - 1e-9:
                continue
            for off in args.offsets.split(","):
                d = parts.smooth_offset(blade) if off == "smooth" else float(off)
                truth = blade.truth(u, z, d)
                blank = blade.sample_blank(s, (-3, 63), d, np.random.default_rng(7), jitter=0.3, noise=args.noise)
                for surface in args.surfaces.split(","):
                    t0 = time.perf_counter()
                    a = machscan.allowance(p, v, blank["points"], surface=surface)
                    us = (time.perf_counter() - t0) / len(p) * 1e6
                    print(f"{name:6} {s:5.2f} {r / s:5.2f} {off:>7} {surface:8} {statistics(a - truth, near_edge)}   {us:.1f}",
                          flush=True)


if __name__ == "__main__":
    main()
