"""Grinding paths on analytic blades no generator in machscan makes (issue #32 §5): rows, pieces, path points,
the stock the simulated pass leaves and the time, per part and cloud spacing.

The parts (`tests/analytic_blades.py`, pure NumPy, exact normals): an elliptic section (edge radius 0.8 mm), a
biconvex and a crescent circular-arc section (edges rounded 0.8 and 0.5 mm; the crescent's lower side concave), each
60 mm of span with 30° of twist and a lean. The cloud is the model sampled every `spacing` along the section and the
span (each scan line shifted along the section from the one before, as a scan's lines do not line up), with its exact
normals and a smooth allowance of 0.2–0.4 mm. The path: R 10 mm, scallop 10 µm, sections across the span, the
paper's removal model with its own feeds. The stock left is checked on a separate, denser cloud of the same blank
(every 0.25 mm), so a cut between the path cloud's points is seen; the path points' height off the exact surface on
every 7th point.

    python benchmarks/grinding_parts.py [--spacings 0.3,0.4,...,1.5] [--parts ellipse,biconvex,crescent]
        [--scallops 0.005,0.01,0.02] [--across 0.5 | --poisson]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import machscan

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from analytic_blades import Blade, EllipseSection, LenticularSection, StadiumSection, smooth_offset

MODEL = dict(C=0.05, exponents=(0.6, -0.7, 0.8), belt_speed=20.0, force=15.0, feed_limits=(0.5, 200.0))
PARTS = {
    "ellipse": lambda: Blade(EllipseSection(20.0, 4.0), span=60.0, twist_deg=30.0, lean=(0.05, 0.02)),
    "biconvex": lambda: Blade(LenticularSection(20.0, 3.0, 2.0, 0.8), span=60.0, twist_deg=30.0, lean=(0.03, -0.04)),
    "crescent": lambda: Blade(LenticularSection(20.0, 5.0, -1.5, 0.5), span=60.0, twist_deg=30.0, lean=(-0.04, 0.03)),
    "stadium": lambda: Blade(StadiumSection(8.0, 2.0), span=40.0, twist_deg=0.0),
    "stadium-twisted": lambda: Blade(StadiumSection(8.0, 2.0), span=40.0, twist_deg=20.0, lean=(0.02, 0.0)),
}
STAGGER = 0.382  # golden-ratio shift of each scan line along the section


def cloud(blade: Blade, spacing: float, stagger: float = STAGGER, across: float | None = None, poisson: bool = False):
    """Model points every `spacing` along the sections and every `across` (default `spacing`) along the span — or,
    `poisson`, spread at random and thinned so that no two are closer than `spacing` (as a CAD mesh is sampled) — their
    exact normals and the allowance 0.2–0.4 mm."""
    if poisson:
        rng = np.random.default_rng(7)
        count = int(10 * blade.section.length * blade.span / (np.pi * (spacing / 2) ** 2))
        u = blade.section.u_at(rng.uniform(0, blade.section.length, count))
        z = rng.uniform(0, blade.span, count)
        keep = machscan.remove_duplicates(blade.point(u, z), spacing)
        u, z = u[keep], z[keep]
    else:
        u, z = blade.model_grid(spacing, span_spacing=across, stagger=stagger)
    d = smooth_offset(blade, 0.2, 0.4)
    return blade.point(u, z), blade.normal(u, z), d(u, z)


def measure(blade: Blade, spacing: float, scallop: float, check, across: float | None = None, poisson: bool = False) -> dict:
    p, n, a = cloud(blade, spacing, across=across, poisson=poisson)
    row = dict(points_in=len(p))
    t0 = time.perf_counter()
    try:
        paths = machscan.grinding_paths(p, n, a, 10.0, scallop, (0, 0, 1), removal_model=MODEL)
    except ValueError as e:
        row.update(time=time.perf_counter() - t0, refused=str(e))
        return row
    row["time"] = time.perf_counter() - t0
    # The check cloud over the path cloud's stretch of the span: beyond it no path is asked for.
    cp, cn, ca = check
    inside = (cp[:, 2] >= p[:, 2].min()) & (cp[:, 2] <= p[:, 2].max())
    cp, cn, ca = cp[inside], cn[inside], ca[inside]
    result = machscan.simulate_removal(paths, cp, cn, ca)
    own = machscan.simulate_removal(paths, p, n, a)
    height = blade.height(paths.points[::7])
    row.update(
        rows=len(np.unique(paths.row_offsets)),
        pieces=len(paths.row_offsets),
        path_points=len(paths.points),
        stock_min=float(np.nanmin(result.deviation)),
        stock_max=float(np.nanmax(result.deviation)),
        own_min=float(np.nanmin(own.deviation)),
        own_max=float(np.nanmax(own.deviation)),
        outside=int(np.sum(np.abs(result.deviation) > 0.08)),
        height=float(np.abs(height).max()),
    )
    return row


def refusal(message: str) -> str:
    """The refusal in a table cell: why, and the spacing the call says the cloud needs."""
    if "no surface fit" in message:
        why = "no fit"
    elif "disagree by " in message:
        why = "fits disagree by " + message.split("disagree by ")[1].split(" mm")[0] + " mm"
    else:
        return f"refused: {message}"
    needed = message.split("points every ")[1].split(" mm")[0]
    return f"refused: {why}; needs ≤ {needed} mm"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spacings", default="0.3,0.4,0.5,0.6,0.75,0.9,1,1.25,1.5")
    ap.add_argument("--parts", default=",".join(PARTS))
    ap.add_argument("--scallops", default="0.01", help="scallop heights, mm; several give the density table too")
    ap.add_argument("--poisson", action="store_true", help="clouds spread at random, no two closer than the spacing")
    ap.add_argument("--across", type=float, default=None,
                    help="span spacing of the cloud's sections, mm (default: the spacing along them, an even cloud)")
    args = ap.parse_args()
    spacings = [float(s) for s in args.spacings.split(",")]
    scallops = [float(h) for h in args.scallops.split(",")]
    largest = {}
    for scallop in scallops:
        print(f"\nR 10 mm, scallop {scallop * 1000:g} µm, allowance 0.2–0.4 mm; stock left on a 0.25 mm check cloud\n")
        print(
            "| part | cloud mm | cloud points | rows | pieces | path points | stock left min … max mm | outside ±0.08 | "
            "path off surface µm | time s |"
        )
        print("|---|---:|---:|---:|---:|---:|---|---:|---:|---:|")
        for name in args.parts.split(","):
            blade = PARTS[name]()
            check = cloud(blade, 0.25, stagger=0.5)
            for spacing in spacings:
                r = measure(blade, spacing, scallop, check, args.across, args.poisson)
                if "refused" in r:
                    print(f"| {name} | {spacing:g} | {r['points_in']:,} | {refusal(r['refused'])} | | | | | | {r['time']:.2f} |")
                else:
                    print(
                        f"| {name} | {spacing:g} | {r['points_in']:,} | {r['rows']} | {r['pieces']} | "
                        f"{r['path_points']:,} | {r['stock_min']:+.4f} … {r['stock_max']:+.4f} | {r['outside']} | "
                        f"{1000 * r['height']:.1f} | {r['time']:.2f} |"
                    )
                    if r["outside"] == 0 and r["rows"] == r["pieces"]:
                        largest[name, scallop] = max(largest.get((name, scallop), 0.0), spacing)
                sys.stdout.flush()
    if len(scallops) > 1:
        print("\nLargest cloud spacing (of those tried) whose path is made, whole and within ±0.08 mm, mm\n")
        print("| part | " + " | ".join(f"h {1000 * h:g} µm" for h in scallops) + " |")
        print("|---|" + "---:|" * len(scallops))
        for name in args.parts.split(","):
            print(f"| {name} | " + " | ".join(f"{largest.get((name, h), 0.0):g}" for h in scallops) + " |")


if __name__ == "__main__":
    main()
