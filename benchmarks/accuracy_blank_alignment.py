"""The blank found from where a plant starts (issue #32 §4): whole blades, edges and ends included, blanks offset
uniformly (0.3 mm) or smoothly (0.1–0.5 mm) and clamped up to 5 mm / 5° off about a random axis, found by
machscan.align_blank (coarse alignment, ICP, envelope fit) and by machscan.envelope_fit alone from the same start.

    python benchmarks/accuracy_blank_alignment.py [--seeds 3] [--parts airfoil,E0.8,Lt1.2]

Per part, offset and misplacement: the allowance's standard deviation over the model (µm) — the true one (the blank
where it was made) and after each — its mean and minimum, points without stock, and the time. For a uniform offset
the even allowance is the offset itself, so the std measures what the fit left.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import machscan
from machscan.synth import Blade

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import analytic_blades as parts


def airfoil(model_spacing: float, blank_spacing: float, offset):
    """The built-in airfoil over its whole span: model points with normals, and a blank on its own grid."""
    blade = Blade()
    ring, _ = blade.sample(2000, 2)
    perimeter = float(np.linalg.norm(np.diff(ring[:, 0], axis=0, append=ring[:1, 0]), axis=1).sum())

    def grid(spacing, phase):
        nu, nv = int(perimeter / spacing), int(blade.span / spacing) + 1
        uu, vv = np.meshgrid((np.arange(nu) + phase) / nu, np.linspace(0.0, 1.0, nv), indexing="ij")
        p, n = blade.surface(uu, vv)
        return p.reshape(-1, 3), n.reshape(-1, 3), uu.ravel(), vv.ravel()

    model, normals, _, _ = grid(model_spacing, 0.0)
    bp, bn, bu, bv = grid(blank_spacing, 0.37)
    d = offset if isinstance(offset, float) else 0.3 + 0.2 * np.sin(2 * np.pi * (bu + 0.5 * bv))
    return model, normals, bp + np.asarray(d).reshape(-1, 1) * bn


def analytic(name: str, model_spacing: float, blank_spacing: float, offset, flush: bool = False):
    e, lens = parts.EllipseSection, parts.LenticularSection
    twisted = dict(twist_deg=30, lean=(0.05, 0.02), bow=(5e-4, 0))
    blade = {
        "E0.8": parts.Blade(e(20, 4), 60, **twisted),
        "Lt1.2": parts.Blade(lens(20, 3, 2, 1.2), 60, **twisted),
    }[name]
    u, z = blade.model_grid(model_spacing, (0, 60), span_spacing=model_spacing)
    d = offset if isinstance(offset, float) else parts.smooth_offset(blade)
    span = (0, 60) if flush else (-3, 63)
    blank = blade.sample_blank(blank_spacing, span, d, np.random.default_rng(3), jitter=0.3)["points"]
    return blade.point(u, z), blade.normal(u, z), blank


def misplacement(angle_deg: float, shift_mm: float, centre: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    t = rng.normal(size=3)
    t *= shift_mm / np.linalg.norm(t)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    th = np.radians(angle_deg)
    r = np.eye(3) + np.sin(th) * k + (1 - np.cos(th)) * k @ k
    pose = np.eye(4)
    pose[:3, :3] = r
    pose[:3, 3] = centre - r @ centre + t
    return pose


def stats(a: np.ndarray) -> str:
    f = a[np.isfinite(a)]
    return f"std {1e3 * f.std():7.1f} µm mean {f.mean():.4f} min {f.min():+.4f} no stock {len(a) - len(f):5d}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--parts", default="airfoil,E0.8,Lt1.2")
    ap.add_argument(
        "--flush", action="store_true", help="the analytic blades' blanks end where the model ends (default: 3 mm beyond)"
    )
    args = ap.parse_args()
    for name in args.parts.split(","):
        for offset in (0.3, "smooth"):
            if name == "airfoil":
                model, normals, blank = airfoil(1.0, 0.5, offset)
            else:
                model, normals, blank = analytic(name, 0.5, 0.5, offset, args.flush)
            truth = machscan.allowance(model, normals, blank)
            print(f"{name} offset {offset}: {len(model)} model points, {len(blank)} blank points; true {stats(truth)}")
            for angle, shift in ((0.0, 0.3), (1.0, 1.0), (5.0, 5.0)):
                for seed in range(args.seeds):
                    pose = misplacement(angle, shift, model.mean(axis=0), seed)
                    moved = blank @ pose[:3, :3].T + pose[:3, 3]
                    t0 = time.perf_counter()
                    local = machscan.envelope_fit(model, normals, moved, min_allowance=0.1)
                    t1 = time.perf_counter()
                    found = machscan.align_blank(model, normals, moved, min_allowance=0.1)
                    t2 = time.perf_counter()
                    print(f"  {angle:3.0f}° {shift:3.1f} mm seed {seed}: envelope_fit alone {stats(local.allowance)} "
                          f"{t1 - t0:5.1f} s")
                    print(f"  {'':>22}align_blank       {stats(found.allowance)} {t2 - t1:5.1f} s "
                          f"({found.stages[2].name})")


if __name__ == "__main__":
    main()
