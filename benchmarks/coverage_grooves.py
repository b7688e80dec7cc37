"""Issue #35 §3: do the groove measures' standard errors say how far off they are?

Monte Carlo: frames with exact truth, fitted by the default call; for every measure the share
of converged frames whose k = 2 interval (value ± 2·se) holds the truth (target 93–97 %), the
median |error| and the median standard error. Frame sets:

- the generators' (``machscan.synth.groove_frames``: V, U, U with walls, trapezoid; 25 µm
  pitch, 8 µm noise, lips, tilt, dropouts; the step's truth is 0), and the U's tilted by a
  shear instead of a rotation (their sections lean);
- shapes the generators do not make, drawn here: V's with unequal flanks (30–60° left, 45–75°
  right), trapezoids with unequal flanks, U's whose walls are drafted by up to 5° either way
  (bottom radius 0.15–0.3 mm, walls 0.05–0.2 mm), half-ellipses cut below their axis (0.5–0.7 mm
  across, 0.18–0.26 mm semi-axis down: the elliptic U holds it, the U nearly), gap-and-flush profiles (a V gap with the right
  surface 0–50 µm above or below the left: the step), and bowls ``v = −d·(1 − |2u/w|^e)``, parabolic
  (e = 2) and quartic (e = 4), 0.35–0.7 mm wide and 0.08–0.3 mm deep (curved flanks, sections
  no model has), at a 20 µm pitch with 5 µm noise; and
  the unequal V's on a coarse profiler (50 µm pitch, 12 µm noise: 2–20 readings across), the
  unequal trapezoids on a noisy one (25 µm pitch, 20 µm noise);
- laser-engraved V's with rounded bottoms (0–0.1 mm across: ``accuracy_rounded_grooves.py``).

    python benchmarks/coverage_grooves.py [--frames 1000] [--seed 3] [--only TEXT]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import machscan
from machscan.synth import groove_frames
from machscan.synth.frames import _fillet_polyline, _topmost

MEASURES = ("width", "depth", "x0", "z0", "flank_angle_left", "flank_angle_right", "area", "bottom_radius", "step")
UNITS = {"flank_angle_left": "°", "flank_angle_right": "°", "area": "mm²"}


def polyline_area(poly: np.ndarray) -> float:
    u, v = poly[:, 0], np.minimum(poly[:, 1], 0.0)
    return float(-np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(u)))


# Profilers other than the generators' (the shape, pitch and noise in mm): a coarse one on the
# unequal V's, a noisy one on the unequal trapezoids; the other shapes at a 20 µm pitch with
# 5 µm noise.
PROFILERS = {"coarse_v": ("asymmetric_v", 0.05, 0.012), "noisy_trapezoid": ("asymmetric_trapezoid", 0.025, 0.02)}


def other_shapes(kind: str, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Frames 5 mm long at 20 µm (``PROFILERS``: the shape, pitch and noise of the coarse and
    noisy sets), 5 µm noise, lips up to 20 µm, tilt ±0.05 rad (a rotation), across one groove of
    ``kind``; the truth of every measure it defines (NaN where it does not)."""
    rng = np.random.default_rng(seed)
    kind, pitch, noise = PROFILERS.get(kind, (kind, 0.02, 0.005))
    readings, far = round(5.0 / pitch), 4.0
    x = (np.arange(readings) - readings // 2) * pitch
    z = np.empty((n, readings))
    truth = {m: np.full(n, np.nan) for m in MEASURES}
    for k in range(n):
        step = 0.0
        if kind == "asymmetric_v":
            d = rng.uniform(0.08, 0.4)
            a_l, a_r = rng.uniform(30, 60), rng.uniform(45, 75)
            left, right = d / math.tan(math.radians(a_l)), d / math.tan(math.radians(a_r))
            used: list[float] = []
            poly = _fillet_polyline(
                [(-far, 0), (-left, 0), (0, -d), (right, 0), (far, 0)],
                [0, rng.uniform(0, 0.02), rng.uniform(0, 0.03), rng.uniform(0, 0.02), 0],
                used=used,
            )
            truth["bottom_radius"][k] = used[1]
        elif kind == "asymmetric_trapezoid":
            d, floor = rng.uniform(0.08, 0.35), rng.uniform(0.15, 0.6)
            a_l, a_r = rng.uniform(35, 80), rng.uniform(50, 85)
            left, right = d / math.tan(math.radians(a_l)), d / math.tan(math.radians(a_r))
            poly = _fillet_polyline(
                [(-far, 0), (-floor / 2 - left, 0), (-floor / 2, -d), (floor / 2, -d), (floor / 2 + right, 0), (far, 0)],
                [0, rng.uniform(0, 0.02), rng.uniform(0, 0.02), rng.uniform(0, 0.02), rng.uniform(0, 0.02), 0],
            )
            left, right = floor / 2 + left, floor / 2 + right
        elif kind == "drafted_u_walls":
            # A round bottom under walls drafted either way (a worn or tilted cutter): the
            # generators' U's with walls hold them within a degree or two of vertical.
            r, wall, draft = rng.uniform(0.15, 0.3), rng.uniform(0.05, 0.2), math.radians(rng.uniform(-5, 5))
            t = np.linspace(math.pi, 2 * math.pi, 2001)
            left = right = r + wall * math.tan(draft)
            bottom = np.c_[r * np.cos(t), -wall + r * np.sin(t)]
            poly = np.vstack([[(-far, 0.0), (-left, 0.0)], bottom, [(right, 0.0), (far, 0.0)]])
            a_l = a_r = math.degrees(math.atan2(wall, wall * math.tan(draft)))
            truth["bottom_radius"][k] = r
        elif kind == "half_ellipse":
            # An elliptic section cut below its axis (the elliptic U holds it: a ball cutter on a tilted
            # axis, or a beam's profile): semi-axes a across, b down.
            a, b, cut = rng.uniform(0.25, 0.35), rng.uniform(0.18, 0.26), rng.uniform(0.0, 0.06)
            left = right = a * math.sqrt(1 - (cut / b) ** 2)
            uu = np.concatenate([[-far], np.linspace(-left, left, 4001), [far]])
            vv = -(b * np.sqrt(np.clip(1 - (uu / a) ** 2, 0, 1)) - cut)
            vv[[0, -1]] = 0.0
            poly = np.c_[uu, vv]
            # The flanks meet the surface at the ellipse's slope there; the bottom's radius of
            # curvature is a²/b.
            a_l = a_r = math.degrees(math.atan2(b * b * left, a * a * cut)) if cut > 0 else 90.0
            truth["bottom_radius"][k] = a * a / b
        elif kind in ("parabolic_bowl", "quartic_bowl"):
            # A bowl v = −d·(1 − |2u/w|^e), e = 2 or 4: curved flanks and a bottom no model
            # holds (a worn or ablating tool; the quartic's floor is flat, its walls steep).
            # Its flank angle is the tangent's where it meets the surface; only the parabola
            # has a bottom radius, (w/2)²/(2d).
            e = 2 if kind == "parabolic_bowl" else 4
            w, d = rng.uniform(0.35, 0.7), rng.uniform(0.08, 0.3)
            left = right = w / 2
            uu = np.concatenate([[-far], np.linspace(-left, right, 4001), [far]])
            vv = -d * (1 - np.abs(uu / left) ** e)
            vv[[0, -1]] = 0.0
            poly = np.c_[uu, vv]
            a_l = a_r = math.degrees(math.atan(e * d / left))
            if e == 2:
                truth["bottom_radius"][k] = left * left / (2 * d)
        else:  # gap and flush: a V gap, the right surface `step` above the left
            d, a = rng.uniform(0.1, 0.3), rng.uniform(40, 70)
            step = rng.uniform(-0.05, 0.05)
            run = 1 / math.tan(math.radians(a))
            left = d * run
            poly = np.array([(-far, 0.0), (-left, 0.0), (0.0, -d), ((d + step) * run, step), (far, step)])
            truth["step"][k] = step
        u, v = poly[:, 0], poly[:, 1].copy()
        if kind != "gap_flush":
            truth["width"][k], truth["depth"][k] = left + right, -v.min()
            truth["flank_angle_left"][k], truth["flank_angle_right"][k] = a_l, a_r
            truth["area"][k] = polyline_area(poly)
        for side, edge in ((-1, -left), (1, poly[-2, 0] if kind == "gap_flush" else right)):
            if rng.random() < 0.75:
                h, half = rng.uniform(0, 0.02), 0.5 * rng.uniform(0.05, 0.12)
                tau = (u - (edge + side * (half + rng.uniform(0, 0.02)))) / half
                v += h * np.where(np.abs(tau) < 1, (1 - tau * tau) ** 2, 0.0)
        tilt, xc, z_off = rng.uniform(-0.05, 0.05), rng.uniform(-1, 1), rng.uniform(-0.3, 0.3)
        c, s = math.cos(tilt), math.sin(tilt)
        # The groove's center (the midpoint of the crossings) in the frame, and the surface there.
        mid = 0.5 * (right - left) if kind != "gap_flush" else np.nan
        truth["x0"][k], truth["z0"][k] = xc + mid * c, z_off + mid * s
        z[k] = _topmost(xc + u * c - v * s, z_off + u * s + v * c, x) + noise * rng.standard_normal(readings)
    if kind != "gap_flush":
        truth["step"][:] = 0.0
    return x, z, truth


def generator_frames(
    shape: str, n: int, seed: int, tilt_mode: str = "rotate"
) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    g = groove_frames(shape, n, seed=seed, tilt_mode=tilt_mode)
    truth = {
        "width": g.width,
        "depth": g.depth,
        "x0": g.center[:, 0],
        "z0": g.center[:, 1],
        "flank_angle_left": g.flank_angle[:, 0],
        "flank_angle_right": g.flank_angle[:, 1],
        "area": g.area,
        "bottom_radius": g.bottom_radius,
        "step": np.zeros(n),
    }
    return g.x, g.z, truth


def engraved(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    from accuracy_rounded_grooves import engraved_frames

    x, z, width, depth = engraved_frames(n, seed, (0.0, 0.1), "arc")
    nan = np.full(n, np.nan)
    return x, z, {m: nan for m in MEASURES} | {"width": width, "depth": depth, "step": np.zeros(n)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--only", metavar="TEXT", help="run only the sets whose name contains TEXT")
    args = ap.parse_args()
    sets = [(f"synth {s}", lambda s=s: generator_frames(s, args.frames, args.seed)) for s in ("v", "u", "u_walls", "trapezoid")]
    # Tilted by a shear (a groove cut square to the machine on a tilted surface): the arcs lean.
    sets += [(f"synth {s}, sheared", lambda s=s: generator_frames(s, args.frames, args.seed, "shear"))
             for s in ("u", "u_walls")]
    sets += [(k.replace("_", " "), lambda k=k: other_shapes(k, args.frames, args.seed))
             for k in ("asymmetric_v", "asymmetric_trapezoid", "drafted_u_walls", "half_ellipse", "gap_flush",
                       "coarse_v", "noisy_trapezoid", "parabolic_bowl", "quartic_bowl")]
    sets += [("engraved V, rounded 0-0.1 mm", lambda: engraved(args.frames, args.seed))]
    sets = [(name, make) for name, make in sets if args.only is None or args.only in name]
    print(f"k = 2 coverage of the groove measures, default call, {args.frames} frames per set (seed {args.seed})")
    print(f"  {'set':<30} {'measure':<18} {'frames':>6} {'k=2 holds':>9} {'median |error|':>15} {'median se':>10}")
    for name, make in sets:
        x, z, truth = make()
        f = machscan.fit_grooves(x, z)
        for m in MEASURES:
            t = truth[m]
            est, se = getattr(f, m), getattr(f, "se_" + m)
            keep = f.ok & np.isfinite(t) & np.isfinite(est)
            if not keep.any():
                continue
            e, s = (est - t)[keep], se[keep]
            scale, unit = (1.0, UNITS[m]) if m in UNITS else (1000.0, "µm")
            print(f"  {name:<30} {m:<18} {keep.sum():6d} {100 * np.mean(np.abs(e) <= 2 * s):8.1f}%"
                  f" {scale * np.median(np.abs(e)):11.4g} {unit:<3} {scale * np.median(s):8.4g} {unit}")


if __name__ == "__main__":
    main()
