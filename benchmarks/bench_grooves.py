"""Groove measurement and Euclidean clustering against the reference libraries, side by side.

1. Accuracy of the default ``fit_grooves`` call on every groove shape plants cut
   (``synth.groove_frames``: V, U arc, U with walls, trapezoid; 8 µm noise, lips, tilt,
   dropouts, spikes; seed 7, never used by the tests; the tilt as a rotation, then as a shear
   ``z += k·x``) and on frames without a groove, against the exact truth. Issue #8 targets:
   median |width error| <= 10 µm, |depth error| <= 1.5 %, |center error| <= 10 µm, >= 99 %
   converged; no-groove frames flagged.
2. Speed of ``fit_grooves`` (whole measurement: spike filter, surface line, levelling, four
   section models, choice, refits) on >= 20,000 frames of t = 200 readings of each shape,
   against ``scipy.optimize.least_squares`` on the same frames already levelled by machscan
   (levelling not timed for scipy), three ways: (a) the same job, the four section models
   (trapezoid, V, round-bottomed V, U; vertical residuals, bounded ``trf``, finite-difference
   Jacobian as one writes it for a piecewise shape) fitted and the best chosen by AIC: the
   like-for-like ratio; (b) **one** V section (4 parameters, analytic Jacobian, ``lm``): a
   fraction of the work, so that ratio is a lower bound; (c) the paper's tanh template in
   both, the same model from the same start (``lm``, analytic Jacobian). scipy runs on a
   subset (--scipy-frames) because it is slow; all rates are frames/s. Targets: >= 50x scipy
   and >= 40,000 frames/s.
   Then the default call and the tanh template on the frames issue #3 set the target on
   (tanh-shaped grooves; --only issue3).
3. Several grooves per frame (``synth.multi_groove_frames``: 2–4 grooves of every shape per
   frame, 400 readings, with and without corners shared between neighbours; seed 7): share of
   frames whose every groove is found with ``select="all"`` and none extra, per-groove median
   errors against the truth, how often ``select="deepest"`` measures the truly deepest groove,
   and the rates (frames/s) of the default call and of ``select="all"`` (--only multi).
4. ``euclidean_clusters`` on >= 500,000 groove-center-like points against Open3D
   ``cluster_dbscan(eps, min_points=1)``, same points, same partition checked. Target: >= 2x.

    python benchmarks/bench_grooves.py [--only accuracy|speed|issue3|multi|clusters] [--frames 20000]
        [--scipy-frames 1000] [--points 500000]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from scipy.optimize import least_squares
from timing import timed

import machscan
from machscan import synth

# ---- accuracy -------------------------------------------------------------------------------


def bench_accuracy(n: int, seed: int = 7) -> None:
    print(f"groove fit accuracy, default call, {n} frames per shape (synth.groove_frames, seed {seed})")
    print(f"  {'shape':<19} {'converged':>9} {'|width| µm':>11} {'|depth| %':>10} {'|center| µm':>12}  models")
    for tilt_mode in ("rotate", "shear"):
        for shape in synth.GROOVE_SHAPES:
            g = synth.groove_frames(shape, n, seed=seed, tilt_mode=tilt_mode)
            f = machscan.fit_grooves(g.x, g.z)
            ok = f.ok
            w = 1000 * np.median(np.abs(f.width - g.width)[ok])
            d = 100 * np.median((np.abs(f.depth - g.depth) / g.depth)[ok])
            c = 1000 * np.median(np.abs(f.x0 - g.center[:, 0])[ok])
            models = ", ".join(f"{k} {v}" for k, v in f.model_counts().items() if v)
            name = shape if tilt_mode == "rotate" else f"{shape}, sheared"
            print(f"  {name:<19} {100 * ok.mean():8.2f}% {w:11.1f} {d:10.2f} {c:12.1f}  {models}")
    rng = np.random.default_rng(9)
    x = (np.arange(200) - 100) * 0.025
    flat = rng.normal(0, 0.008, (n, 200)) + rng.uniform(-0.1, 0.1, (n, 1)) * x
    bumps = flat + 0.03 * np.exp(-(((x - rng.uniform(-1, 1, (n, 1))) / 0.05) ** 2))
    f = machscan.fit_grooves(x, np.vstack([flat, bumps]))
    flagged = (f.status == machscan.GrooveStatus.NO_GROOVE).mean()
    print(f"  no groove (flat, and flat with a 30 µm bump), {2 * n} frames: {100 * flagged:.2f} % no_groove, "
          f"{int(f.ok.sum())} measured as a groove")


# ---- speed ----------------------------------------------------------------------------------


def v_section(p, x):
    """Levelled V groove in its surface: z = z0 − max(0, D − s·|x − x0|) (width 2D/s)."""
    x0, z0, depth, slope = p
    return z0 - np.maximum(0.0, depth - slope * np.abs(x - x0))


def v_jacobian(p, x):
    x0, _z0, _depth, slope = p
    inside = (p[2] - slope * np.abs(x - x0)) > 0
    j = np.zeros((len(x), 4))
    j[:, 1] = 1.0
    j[inside, 0] = -slope * np.sign(x[inside] - x0)
    j[inside, 2] = -1.0
    j[inside, 3] = np.abs(x[inside] - x0)
    return j


def tanh_template(p, x, a=20.0):
    x0, z0, d, w = p
    return z0 + 0.5 * d * (np.tanh(a * (x - x0 - 0.25 * w)) - np.tanh(a * (x - x0 + 0.25 * w)))


def tanh_jacobian(p, x, a=20.0):
    x0, _z0, d, w = p
    ta, tb = np.tanh(a * (x - x0 - w / 4)), np.tanh(a * (x - x0 + w / 4))
    sa, sb = 1 - ta * ta, 1 - tb * tb
    return np.column_stack([0.5 * d * a * (sb - sa), np.ones_like(x), 0.5 * (ta - tb), -0.125 * d * a * (sa + sb)])


def _scipy_rate(levelled, model, jacobian, start):
    t0 = time.perf_counter()
    for lf in levelled:
        least_squares(lambda p, lf=lf: model(p, lf.x) - lf.z, start(lf), jac=lambda p, lf=lf: jacobian(p, lf.x),
                      method="lm")
    return len(levelled) / (time.perf_counter() - t0)


def _data_start(lf):
    """A start from the readings, as a script would take it: the lowest reading and the surface."""
    k = int(np.argmin(lf.z))
    z0 = float(np.median(lf.z))
    depth = max(z0 - float(lf.z[k]), 0.01)
    return np.array([lf.x[k], z0, depth, 2 * depth / 0.5])


def _tanh_start(lf):
    k = int(np.argmin(lf.z))
    z0 = float(np.median(lf.z))
    return np.array([lf.x[k], z0, max(z0 - float(lf.z[k]), 0.01), 0.5])


def section_value(p, u):
    """Height of the general section p = [xL, xR, tL, tR, D, s] at u (crates/core/src/groove/section.rs)."""
    xl, xr, tl, tr, d, s = p
    t = tl + tr
    al, ar = np.sqrt(1 + tl * tl), np.sqrt(1 + tr * tr)
    r = s * max(xr - xl - t * d, 0.0) / (al + ar - t)
    hc = d - r
    cl, cr = xl + tl * hc + r * al, xr - tr * hc - r * ar
    utl, utr = cl - r / al, cr + r / ar
    arc_l = -hc - np.sqrt(np.maximum(r * r - (u - cl) ** 2, 0.0))
    arc_r = -hc - np.sqrt(np.maximum(r * r - (u - cr) ** 2, 0.0))
    v = np.select(
        [u < utl, u < cl, u <= cr, u <= utr],
        [-(u - xl) / max(tl, 1e-12), arc_l, np.full_like(u, -d), arc_r],
        -(xr - u) / max(tr, 1e-12),
    )
    return np.minimum(v, 0.0)


# The four models as scipy sees them: parameters -> general section, start, bounds (z0 last).
_SECTIONS = {
    "trapezoid": (lambda q: q[:6], lambda s: [*s["v"], s["d"], 0.1],
                  ([-np.inf, -np.inf, 1e-3, 1e-3, 1e-4, 0.0], [np.inf, np.inf, 20, 20, np.inf, 1.0])),
    "v": (lambda q: [*q[:4], (q[1] - q[0]) / (q[2] + q[3]), 1.0], lambda s: s["v"],
          ([-np.inf, -np.inf, 1e-2, 1e-2], [np.inf, np.inf, 20, 20])),
    "round": (lambda q: [*q[:5], 1.0], lambda s: [*s["v"], 0.98 * s["d"]],
              ([-np.inf, -np.inf, 1e-3, 1e-3, 1e-4], [np.inf, np.inf, 20, 20, np.inf])),
    "u": (lambda q: [q[0] - q[1], q[0] + q[1], 0.0, 0.0, q[2], 1.0], lambda s: [s["c"], s["h"], s["d"]],
          ([-np.inf, 5e-3, 1e-3], [np.inf, np.inf, np.inf])),
}


def _four_models(lf):
    """The same job in scipy: the four section models fitted, the best (AIC) kept; its depth."""
    x, z = lf.x, lf.z
    k = int(np.argmin(z))
    z0 = float(np.median(z))
    d = max(z0 - float(z[k]), 0.01)
    deep = x[z < z0 - 0.5 * d]
    c = float(np.mean(deep)) if len(deep) else float(x[k])
    h = max(float(np.ptp(deep)) if len(deep) else 0.1, 0.02)
    t = h / d
    start = {"v": [c - h, c + h, t, t], "d": d, "c": c, "h": h}
    fits = []
    for to_p, q0, (lo, hi) in _SECTIONS.values():
        q0 = np.clip([*q0(start), z0], [*lo, -np.inf], [*hi, np.inf])
        r = least_squares(lambda q, to_p=to_p: q[-1] + section_value(to_p(q), x) - z, q0,
                          bounds=([*lo, -np.inf], [*hi, np.inf]), method="trf")
        fits.append((r.cost, len(q0), to_p(r.x)[4]))
    # AIC with the noise variance of the most flexible model (the trapezoid).
    sigma2 = 2 * fits[0][0] / (len(x) - fits[0][1])
    return min(fits, key=lambda f: 2 * f[0] / sigma2 + 2 * f[1])[2]


def bench_speed(n_frames: int, n_scipy: int) -> None:
    print(f"\ngroove fit speed, t = 200 readings, {n_frames} frames per shape, {os.cpu_count()} cores")
    print(f"  {'shape':<10} {'machscan':>14} {'scipy, same job':>16} {'ratio':>7} {'scipy, one V':>14} {'ratio':>7}"
          f" {'machscan tanh':>14} {'scipy tanh':>12} {'ratio':>7}")
    for shape in synth.GROOVE_SHAPES:
        g = synth.groove_frames(shape, 4000, seed=21)
        z = np.tile(g.z, (-(-n_frames // 4000), 1))[:n_frames]
        t, _, fits = timed(lambda z=z, g=g: machscan.fit_grooves(g.x, z), 5)
        rate = n_frames / t
        t_tanh, _, _ = timed(lambda z=z, g=g: machscan.fit_grooves(g.x, z, template="tanh"), 5)
        rate_tanh = n_frames / t_tanh
        levelled = [machscan.level_groove_frame(g.x, row) for row in g.z[:n_scipy]]
        levelled = [lf for lf in levelled if len(lf.x) >= 8]
        n_same = max(len(levelled) // 10, 20)
        t0 = time.perf_counter()
        depths = np.array([_four_models(lf) for lf in levelled[:n_same]])
        sp_same = n_same / (time.perf_counter() - t0)
        agree = 1000 * np.nanmedian(np.abs(depths - g.depth[: len(depths)]))
        sp_v = _scipy_rate(levelled, v_section, v_jacobian, _data_start)
        sp_tanh = _scipy_rate(levelled, tanh_template, tanh_jacobian, _tanh_start)
        print(f"  {shape:<10} {rate:10,.0f} f/s {sp_same:12,.0f} f/s {rate / sp_same:6.0f}x {sp_v:10,.0f} f/s "
              f"{rate / sp_v:6.0f}x {rate_tanh:10,.0f} f/s {sp_tanh:8,.0f} f/s {rate_tanh / sp_tanh:6.0f}x")
        ours = 1000 * np.median(np.abs(fits.depth - np.resize(g.depth, n_frames))[fits.ok])
        print(f"  {'':<10} {int(fits.ok.sum())} converged; scipy same job on {n_same} frames, median |depth error|"
              f" {agree:.1f} µm (machscan: {ours:.1f} µm)")


def bench_issue3_frames(n_frames: int) -> None:
    """The frames issue #3 set the speed target on: tanh-shaped grooves (paper 000's template,
    depth 0.31, width 0.48 mm), 1 % invalid readings, a shear tilt up to 0.05, 8 µm noise."""
    rng = np.random.default_rng(0)
    x = (np.arange(200) - 100) * 0.025
    x0 = rng.uniform(-0.4, 0.4, (n_frames, 1))
    d = rng.normal(0.3124, 0.0148, (n_frames, 1))
    w = rng.normal(0.4806, 0.0163, (n_frames, 1))
    z = tanh_template((x0, 0.0, d, w), x) + rng.uniform(-0.05, 0.05, (n_frames, 1)) * x
    z += rng.normal(0, 0.008, z.shape)
    z[rng.random(z.shape) < 0.01] = np.nan
    print(f"\nissue #3 frames (tanh grooves), {n_frames} frames, {os.cpu_count()} cores")
    for template in ("auto", "tanh"):
        t, _, fits = timed(lambda template=template: machscan.fit_grooves(x, z, template=template), 5)
        print(f"  fit_grooves(template={template!r}): {n_frames / t:10,.0f} frames/s  ({int(fits.ok.sum())} converged)")


# ---- several grooves per frame --------------------------------------------------------------


def bench_multi(n: int, n_speed: int, seed: int = 7) -> None:
    print(f"\nseveral grooves per frame, synth.multi_groove_frames (2-4 grooves, 400 readings), {n} frames, seed {seed}")
    print(f"  {'corners shared':<15} {'all found':>9} {'extra':>6} {'|width| µm':>11} {'|depth| %':>10} {'|center| µm':>12}"
          f" {'deepest right':>14}")
    for shared in (0.0, 0.25):
        g = synth.multi_groove_frames(n, seed=seed, shared=shared)
        every = machscan.fit_grooves(g.x, g.z, select="all")
        errors, found = g.match(every)
        w, d, c = np.median(np.abs(errors), axis=0)
        deepest = machscan.fit_grooves(g.x, g.z)
        truth = np.array([g.center[k, np.nanargmax(g.depth[k])] for k in range(n)])
        right = np.mean(np.abs(deepest.x0 - truth)[deepest.ok] < 0.05)
        print(f"  {shared:<15.2f} {100 * np.mean(found == g.count):8.1f}% {100 * np.mean(found > g.count):5.1f}%"
              f" {1000 * w:11.1f} {100 * d:10.2f} {1000 * c:12.1f} {100 * right:13.1f}%")
    g = synth.multi_groove_frames(2000, seed=21)
    z = np.tile(g.z, (-(-n_speed // 2000), 1))[:n_speed]
    for select in ("deepest", "all"):
        t, _, fits = timed(lambda z=z, select=select: machscan.fit_grooves(g.x, z, select=select), 3)
        print(f"  fit_grooves(select={select!r}): {n_speed / t:10,.0f} frames/s, {len(fits) / t:10,.0f} grooves/s")


# ---- clustering -----------------------------------------------------------------------------


def bench_clusters(n_points: int) -> None:
    import open3d

    rng = np.random.default_rng(1)
    # Groove centers: ~0.1 mm apart along 400 closed contours on a 2 m x 2 m skin.
    per = n_points // 400
    pts = []
    for _ in range(400):
        r = rng.uniform(5, 40)
        t = np.linspace(0, 2 * np.pi, per, endpoint=False)
        cx, cy = rng.uniform(0, 2000, 2)
        pts.append(np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t), rng.normal(0, 0.02, per)]))
    p = np.vstack(pts)
    p = p[rng.permutation(len(p))]
    eps = 2.0
    ms, _, labels = timed(lambda: machscan.euclidean_clusters(p, eps), 3)
    pcd = open3d.geometry.PointCloud(open3d.utility.Vector3dVector(p))
    o3, _, ref = timed(lambda: np.asarray(pcd.cluster_dbscan(eps=eps, min_points=1)), 2)
    same = labels.max() == ref.max()
    print(f"\nEuclidean clustering, {len(p):,} points, radius {eps} mm")
    print(f"  machscan.euclidean_clusters : {ms * 1e3:8.1f} ms  ({labels.max() + 1} clusters)")
    print(f"  open3d cluster_dbscan(min_points=1) : {o3 * 1e3:8.1f} ms  ({ref.max() + 1} clusters, same count: {same})")
    print(f"  ratio: {o3 / ms:.1f}x")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--accuracy-frames", type=int, default=2000)
    ap.add_argument("--accuracy-seed", type=int, default=7, help="seed of the accuracy frames (no test uses 7)")
    ap.add_argument("--frames", type=int, default=20000)
    ap.add_argument("--scipy-frames", type=int, default=1000)
    ap.add_argument("--points", type=int, default=500000)
    ap.add_argument("--only", choices=["accuracy", "speed", "issue3", "multi", "clusters"], help="run one part")
    args = ap.parse_args()
    if args.only in (None, "accuracy"):
        bench_accuracy(args.accuracy_frames, args.accuracy_seed)
    if args.only in (None, "speed"):
        bench_speed(args.frames, args.scipy_frames)
    if args.only in (None, "issue3"):
        bench_issue3_frames(args.frames)
    if args.only in (None, "multi"):
        bench_multi(args.accuracy_frames, args.frames)
    if args.only in (None, "clusters"):
        bench_clusters(args.points)


if __name__ == "__main__":
    main()
