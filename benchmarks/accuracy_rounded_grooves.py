"""Issue #35 §1: the groove fit on laser-engraved V grooves whose bottom the beam rounded.

Frames of 200 readings at 25 µm across one V groove 0.40–0.56 mm wide and 0.27–0.35 mm deep
(paper 000's grooves), its bottom rounded over ``across`` mm (the horizontal extent of the
rounding) either by a circular arc tangent to both flanks ("arc") or by the sharp V blurred
with a Gaussian of 2σ = across/2 ("beam"), top corners rounded by 10 µm, recast lips of
10–30 µm beside both edges, a tilt up to ±0.05 rad, 8 µm noise. Against the exact truth:
median |depth error| (% of the depth), median depth bias (µm), median |width error| (µm), the
share of frames whose k = 2 depth interval holds the truth, the models the default call
chose and the tip-rounding prior it pooled over the set's V's; then the default models with
each frame's rounding on its own (``rounding="frame"``) and each V model alone on the same
frames. Issue #35 targets for the default
call: |depth| <= 1.5 %, bias <= 2 µm, |width| <= 10 µm on roundings of 0-0.1 mm.

Then the floor: the Cramér–Rao bound of the depth for the true shape family (a V whose tip is
a circular arc tangent to both flanks; both flanks, the tip, the arc's radius and the surface
line free), 200 readings at 25 µm, 8 µm noise, the groove 0.48 mm wide and 0.31 mm deep, no
tilt and no lips (so a lower bound for the frames above), averaged over where the bottom falls
between two readings: the standard deviation no unbiased estimator can beat, and the median
|error| it implies (0.674 sd).

Then, with ``--frontier``, what any depth estimator can reach on these frames: each frame's χ²
profile over the tip radius (the rounded V above fitted with the radius held at 0, 5, …, 75 µm,
the surface line from readings beyond the lips, the window given the true width: an advantage
no real call has), and the depths that estimators built on it give: the sharp V, the least
squares over the whole family, the Akaike average of the sharp V and that least squares (the
default call's rule), and the posterior median under a prior on the radius: uniform up to the
largest radius the generator draws (the best a call that knows the process can do), or a
share p0 at the sharp V and the rest uniform up to that radius (a call serving sharp and
rounded V's alike).

    python benchmarks/accuracy_rounded_grooves.py [--frames 1000] [--seed 3] [--frontier]
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from scipy.optimize import least_squares

import machscan
from machscan.synth.frames import _fillet_polyline, _topmost


def engraved_frames(n: int, seed: int, across: tuple[float, float], kind: str):
    rng = np.random.default_rng(seed)
    x = (np.arange(200) - 100) * 0.025
    z, width, depth = np.empty((n, 200)), np.empty(n), np.empty(n)
    for k in range(n):
        w, d = rng.uniform(0.4, 0.56), rng.uniform(0.27, 0.35)
        beta = math.atan2(d, w / 2)
        a = rng.uniform(*across)
        if kind == "arc":
            r = a / (2 * math.sin(beta)) if a > 0 else 0.0
            poly = _fillet_polyline([(-4, 0), (-w / 2, 0), (0, -d), (w / 2, 0), (4, 0)], [0, 0.01, r, 0.01, 0])
        else:
            u = np.linspace(-4, 4, 8001)
            v = np.minimum(0, -d + np.abs(u) * d / (w / 2))
            if a > 0:
                s = (a / 4) / 0.001
                kern = np.exp(-0.5 * (np.arange(-int(4 * s), int(4 * s) + 1) / s) ** 2)
                v = np.convolve(np.pad(v, len(kern) // 2, mode="edge"), kern / kern.sum(), mode="valid")
            poly = np.c_[u, v]
        u, v = poly[:, 0], poly[:, 1].copy()
        depth[k], width[k] = -v.min(), w
        for side in (-1, 1):
            h, half = rng.uniform(0.01, 0.03), 0.5 * rng.uniform(0.05, 0.12)
            tau = (u - side * (w / 2 + rng.uniform(0.0, 0.02) + half)) / half
            v += h * np.where(np.abs(tau) < 1, (1 - tau * tau) ** 2, 0.0)
        tilt, xc = rng.uniform(-0.05, 0.05), rng.uniform(-1, 1)
        c, s_ = math.cos(tilt), math.sin(tilt)
        z[k] = _topmost(xc + u * c - v * s_, u * s_ + v * c, x) + 0.008 * rng.standard_normal(200)
    return x, z, width, depth


def groove_depth(p: np.ndarray) -> float:
    """The depth of :func:`round_v`'s section below its surface line (dense sampling)."""
    u = np.linspace(p[2], p[3], 20001)
    return float(-(round_v(p, u) - (p[0] + p[1] * u)).min())


def round_v(p: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Heights of a V from (xl, 0) to its tip (xt, -D) to (xr, 0), the tip rounded by an arc
    of radius r tangent to both flanks, on the line a + b·x."""
    a, b, xl, xr, xt, d, r = p
    sl, sr = -d / (xt - xl), d / (xr - xt)
    v = np.minimum(0.0, np.maximum(sl * (x - xl), sr * (x - xr)))
    # The arc's centre lies r above both flank lines (unit normals pointing up).
    nl, nr = np.array([-sl, 1.0]) / math.hypot(sl, 1), np.array([-sr, 1.0]) / math.hypot(sr, 1)
    c = np.linalg.solve(np.array([nl, nr]), [r + nl[0] * xl, r + nr[0] * xr])
    tl, tr = c - r * nl, c - r * nr
    on_arc = (x > tl[0]) & (x < tr[0])
    v = np.where(on_arc, c[1] - np.sqrt(np.maximum(r * r - (x - c[0]) ** 2, 0.0)), v)
    return v + a + b * x


def depth_bound(across: float, noise: float = 0.008, w: float = 0.48, d: float = 0.31) -> float:
    """The Cramér–Rao standard deviation of the rounded V's depth (mm), averaged over six
    positions of the bottom within a reading spacing."""
    x = (np.arange(200) - 100) * 0.025
    r = across / (2 * math.cos(math.atan2(w / 2, d)))  # the arc spans 2·r·cos(half opening)
    sds = []
    for xt in np.linspace(0.0, 0.025, 6, endpoint=False):
        p = np.array([0.0, 0.0, xt - w / 2, xt + w / 2, xt, d, r])
        jac, grad = np.empty((200, 7)), np.empty(7)
        for k in range(7):
            h = np.zeros(7)
            h[k] = 1e-6
            jac[:, k] = (round_v(p + h, x) - round_v(p - h, x)) / 2e-6
            grad[k] = (groove_depth(p + h) - groove_depth(p - h)) / 2e-6
        sds.append(math.sqrt(grad @ np.linalg.inv(jac.T @ jac) @ grad) * noise)
    return float(np.mean(sds))


FRONTIER_RADII = np.arange(0.0, 0.0751, 0.005)


def radius_profile(x: np.ndarray, z: np.ndarray, width: float) -> tuple[np.ndarray, np.ndarray]:
    """One frame's χ² (8 µm noise) and depth with the tip radius held at each of
    FRONTIER_RADII, the four other section parameters least squares."""
    centre = x[np.argmin(np.convolve(z, np.ones(5) / 5, "same"))]
    beyond = np.abs(x - centre) > width / 2 + 0.2  # past the lips
    a, b = np.polynomial.polynomial.polyfit(x[beyond], z[beyond], 1)
    h = z - (a + b * x)
    inside = (np.abs(x - centre) < width / 2 + 0.01) & (h < -0.02)
    xi, hi = x[inside], h[inside]
    q = np.array([centre - width / 2, centre + width / 2, centre, -hi.min()])
    chi2, depth = [], []
    for r in FRONTIER_RADII:
        fit = least_squares(lambda p, r=r: (round_v(np.r_[0.0, 0.0, p, r], xi) - hi) / 0.008, q, method="lm")
        if r == 0.0:
            q = fit.x  # the sharp V starts every rounded fit
        chi2.append(2 * fit.cost)
        depth.append(groove_depth(np.r_[0.0, 0.0, fit.x, r]))
    return np.array(chi2), np.array(depth)


def posterior_median(chi2: np.ndarray, depth: np.ndarray, prior: np.ndarray) -> float:
    w = prior * np.exp(-0.5 * (chi2 - chi2.min()))
    order = np.argsort(depth)
    return float(depth[order][np.searchsorted(np.cumsum(w[order]) / w.sum(), 0.5)])


def frontier(frames: int, seed: int) -> None:
    slab = FRONTIER_RADII > 0
    estimators = ["sharp V", "least squares", "Akaike average", "prior: the generator's"]
    estimators += [f"prior: p0 = {p0}" for p0 in (0.1, 0.2, 0.3, 0.5)]
    sets = [("sharp", "arc", (0.0, 0.0)), ("arc 0-0.1 mm", "arc", (0.0, 0.1)), ("beam 0-0.1 mm", "beam", (0.0, 0.1))]
    table = {name: [] for name in estimators}
    for _, kind, across in sets:
        x, z, width, depth = engraved_frames(frames, seed, across, kind)
        errors = {name: [] for name in estimators}
        for k in range(frames):
            chi2, d = radius_profile(x, z[k], width[k])
            j = int(np.argmin(chi2))
            w_sharp = 1.0 / (1.0 + np.exp(0.5 * (chi2[0] - chi2[j]) - 1.0)) if j else 1.0  # AIC: one more parameter
            # The generator's largest radius for this V: 0.1 mm across, tangent to flanks at atan(2d/w).
            r_max = across[1] / (2 * math.sin(math.atan2(d[0], width[k] / 2)))
            generator = (FRONTIER_RADII <= r_max + 1e-9) if across[1] > 0 else ~slab
            slab_prior = slab & (FRONTIER_RADII <= 0.1 / (2 * math.sin(math.atan2(d[0], width[k] / 2))))
            got = [d[0], d[j], w_sharp * d[0] + (1 - w_sharp) * d[j], posterior_median(chi2, d, generator.astype(float))]
            for p0 in (0.1, 0.2, 0.3, 0.5):
                got.append(posterior_median(chi2, d, np.where(slab, (1 - p0) * slab_prior / slab_prior.sum(), p0)))
            for name, value in zip(estimators, got):
                errors[name].append(value - depth[k])
        for name in estimators:
            e = np.array(errors[name])
            table[name].append(f"{100 * np.median(np.abs(e) / depth):6.2f} % {1000 * np.median(e):+5.1f} µm")
    print("\nWhat an estimator on the radius profile reaches (window given the true width): median |depth error|, bias")
    print(f"{'estimator':<24}" + "".join(f"{s[0]:>20}" for s in sets))
    for name in estimators:
        print(f"{name:<24}" + "".join(f"{cell:>20}" for cell in table[name]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--frontier", action="store_true", help="also what an estimator on the radius profile reaches")
    args = ap.parse_args()
    print(f"{'rounding':<16} {'template':<10} {'|depth| %':>9} {'bias µm':>8} {'|width| µm':>10} {'k=2 holds':>9}  models")
    for kind in ("arc", "beam"):
        for across in ((0.0, 0.0), (0.0, 0.05), (0.05, 0.1), (0.0, 0.1)):
            x, z, width, depth = engraved_frames(args.frames, args.seed, across, kind)
            for template in ("auto", "frame", "v", "round"):
                # "frame": the default models, each frame's rounding on its own (no pooled prior).
                f = (machscan.fit_grooves(x, z, rounding="frame") if template == "frame"
                     else machscan.fit_grooves(x, z, template=template))
                ok = f.ok
                e = (f.depth - depth)[ok]
                models = ", ".join(f"{k} {v}" for k, v in f.model_counts().items() if v) if template == "auto" else ""
                if template == "auto" and f.rounding_prior is not None:
                    models += f"; prior {100 * f.rounding_prior[0]:.0f} % sharp, up to {1000 * f.rounding_prior[1]:.1f} µm"
                print(f"{kind} {across[0]:.2f}-{across[1]:.2f} mm {template:<10} {100 * np.median(np.abs(e) / depth[ok]):9.2f}"
                      f" {1000 * np.median(e):+8.1f} {1000 * np.median(np.abs(f.width - width)[ok]):10.1f}"
                      f" {100 * np.mean(np.abs(e) <= 2 * f.se_depth[ok]):8.0f}%  {models}")
    print("\nCramér–Rao bound of the depth, rounded V with everything free (0.48 x 0.31 mm, 8 µm noise, no tilt or lips)")
    for across in (0.025, 0.05, 0.075, 0.1):
        sd = depth_bound(across)
        if sd > 0.1:
            print(f"  rounded over {across:.3f} mm: no bound (the arc holds at most one reading: its radius is not fixed)")
            continue
        print(f"  rounded over {across:.3f} mm: sd {1000 * sd:.2f} µm, median |error| {100 * 0.674 * sd / 0.31:.2f} %")
    if args.frontier:
        frontier(args.frames, args.seed)


if __name__ == "__main__":
    main()
