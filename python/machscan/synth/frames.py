"""Single profiler frames across V, U and trapezoid grooves with exact truth (width, depth,
center), for the groove fit's accuracy and speed: lips, tilt, dropouts, spikes and noise as a
line-laser profiler sees them. Pure NumPy, like the rest of :mod:`machscan.synth`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["GROOVE_SHAPES", "GrooveFrames", "MultiGrooveFrames", "groove_frames", "multi_groove_frames"]


# --------------------------------------------------------------------------------------------
# Single groove frames of every shape
# --------------------------------------------------------------------------------------------

#: The groove shapes :func:`groove_frames` makes.
GROOVE_SHAPES = ("v", "u", "u_walls", "trapezoid")


def _fillet_polyline(pts, radii, arc_step=0.002, used=None):
    """The polyline through ``pts`` (K, 2) with interior vertex k rounded by a circular arc of
    radius ``radii[k]`` (0: sharp; reduced where the arc would not fit its segments: the radii
    drawn go to the list ``used``, when given)."""
    pts = np.asarray(pts, dtype=np.float64)
    out = [pts[0]]
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    for k in range(1, len(pts) - 1):
        r, p = radii[k], pts[k]
        a = (p - pts[k - 1]) / seg[k - 1]
        b = (pts[k + 1] - p) / seg[k]
        turn = math.acos(float(np.clip(a @ b, -1.0, 1.0)))
        if r <= 0 or turn < 1e-9:
            out.append(p)
            if used is not None:
                used.append(0.0)
            continue
        t = min(r * math.tan(turn / 2), 0.5 * min(seg[k - 1], seg[k]))
        r = t / math.tan(turn / 2)
        if used is not None:
            used.append(r)
        t1, t2 = p - a * t, p + b * t
        left = a[0] * b[1] - a[1] * b[0] > 0
        n = np.array([-a[1], a[0]]) if left else np.array([a[1], -a[0]])
        c = t1 + n * r
        a1 = math.atan2(t1[1] - c[1], t1[0] - c[0])
        a2 = math.atan2(t2[1] - c[1], t2[0] - c[0])
        da = (a2 - a1 + math.pi) % (2 * math.pi) - math.pi
        ang = a1 + da * np.linspace(0, 1, max(2, int(abs(da) * r / arc_step) + 1))
        out.extend(np.c_[c[0] + r * np.cos(ang), c[1] + r * np.sin(ang)])
    out.append(pts[-1])
    poly = np.array(out)
    # Densified so that the readings interpolate the section to well under a micrometre.
    steps = np.maximum(np.ceil(np.linalg.norm(np.diff(poly, axis=0), axis=1) / 0.002).astype(int), 1)
    dense = [poly[:1]]
    for q0, q1, m in zip(poly[:-1], poly[1:], steps):
        dense.append(q0 + (q1 - q0) * (np.arange(1, m + 1) / m)[:, None])
    return np.vstack(dense)


@dataclass(frozen=True)
class _Section:
    """One drawn groove section (surface v = 0) and its exact measures."""

    poly: np.ndarray
    width: float
    flank_angles: tuple[float, float]
    bottom_radius: float

    @property
    def depth(self) -> float:
        return float(-self.poly[:, 1].min())

    @property
    def area(self) -> float:
        """Area between the surface line and the section, mm² (the polyline's, by the
        trapezoid rule on its densified vertices: exact for its straight pieces)."""
        u, v = self.poly[:, 0], np.minimum(self.poly[:, 1], 0.0)
        return float(-np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(u)))


def _groove_polyline(shape: str, rng: np.random.Generator) -> _Section:
    """A groove section over |u| ≤ 4 mm (surface v = 0), its width between the flanks at the
    surface (for a circular U, where the arc meets it), flank angles (degrees) and bottom
    radius (NaN for a flat floor)."""
    far = 4.0
    if shape == "v":
        while True:
            w, d = rng.uniform(0.2, 1.2), rng.uniform(0.05, 0.5)
            if 15 <= math.degrees(math.atan2(d, w / 2)) <= 70:
                break
        r_tip = 0.0 if rng.random() < 0.4 else rng.uniform(0.0, 0.05)
        r_top = 0.0 if rng.random() < 0.4 else rng.uniform(0.0, 0.03)
        pts = [(-far, 0), (-w / 2, 0), (0, -d), (w / 2, 0), (far, 0)]
        used: list[float] = []
        poly = _fillet_polyline(pts, [0, r_top, r_tip, r_top, 0], used=used)
        angle = math.degrees(math.atan2(d, w / 2))
        return _Section(poly, w, (angle, angle), used[1])
    if shape == "trapezoid":
        while True:
            w, d, phi = rng.uniform(0.2, 1.2), rng.uniform(0.05, 0.5), rng.uniform(30, 80)
            run = d / math.tan(math.radians(phi))
            if w - 2 * run >= max(0.25 * w, 0.05):
                break
        r_bot = 0.0 if rng.random() < 0.4 else rng.uniform(0.0, 0.03)
        r_top = 0.0 if rng.random() < 0.4 else rng.uniform(0.0, 0.03)
        pts = [(-far, 0), (-w / 2, 0), (-w / 2 + run, -d), (w / 2 - run, -d), (w / 2, 0), (far, 0)]
        return _Section(_fillet_polyline(pts, [0, r_top, r_bot, r_bot, r_top, 0]), w, (phi, phi), math.nan)
    if shape == "u":
        # A ball-end cutter: a circular arc of radius R, d ≤ R deep.
        while True:
            w = rng.uniform(0.2, 1.2)
            d = rng.uniform(0.05, min(0.5, w / 2))
            if d / w >= 0.1:
                break
        radius = (w * w / 4 + d * d) / (2 * d)
        a0 = math.asin(min(1.0, (w / 2) / radius))
        ang = np.linspace(-math.pi / 2 - a0, -math.pi / 2 + a0, 2000)
        arc = np.c_[radius * np.cos(ang), radius - d + radius * np.sin(ang)]
        arc[0], arc[-1] = (-w / 2, 0.0), (w / 2, 0.0)
        angle = math.degrees(math.acos((radius - d) / radius))
        return _Section(np.vstack([[(-far, 0)], arc, [(far, 0)]]), w, (angle, angle), radius)
    if shape == "u_walls":
        # Walls (vertical, or drafted up to 5°) tangent to a round bottom.
        while True:
            w = rng.uniform(0.2, 1.0)
            draft = math.radians(rng.uniform(0.0, 5.0)) if rng.random() < 0.7 else 0.0
            d_min = (w / 2) * math.cos(draft) / (1 + math.sin(draft))
            if d_min <= 0.48:
                d = rng.uniform(max(0.05, d_min), 0.5)
                break
        rho = (w / 2 - d * math.tan(draft)) * math.cos(draft) / (1 - math.sin(draft))
        ang = np.linspace(math.pi + draft, 2 * math.pi - draft, 2000)
        arc = np.c_[rho * np.cos(ang), -d + rho + rho * np.sin(ang)]
        r_top = 0.0 if rng.random() < 0.5 else rng.uniform(0.0, 0.03)
        left = _fillet_polyline(np.array([(-far, 0), (-w / 2, 0), tuple(arc[0]), tuple(arc[1])]), [0, r_top, 0, 0])[:-1]
        right = _fillet_polyline(np.array([tuple(arc[-2]), tuple(arc[-1]), (w / 2, 0), (far, 0)]), [0, 0, r_top, 0])[1:]
        angle = 90.0 - math.degrees(draft)
        return _Section(np.vstack([left, arc[1:-1], right]), w, (angle, angle), rho)
    raise ValueError(f"shape: expected one of {', '.join(GROOVE_SHAPES)}, got {shape!r}")


def _topmost(px: np.ndarray, pz: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The highest point of the polyline on each vertical line x (NaN where there is none): an
    overhanging wall hides what lies below it, as it does from the sensor."""
    if np.all(np.diff(px) > 0):
        return np.interp(x, px, pz, left=np.nan, right=np.nan)
    xa, xb, za, zb = px[:-1], px[1:], pz[:-1], pz[1:]
    keep = xa != xb
    xa, xb, za, zb = xa[keep], xb[keep], za[keep], zb[keep]
    lo, hi = np.minimum(xa, xb), np.maximum(xa, xb)
    out = np.full(len(x), np.nan)
    for j, xj in enumerate(x):
        m = (lo <= xj) & (xj <= hi)
        if m.any():
            out[j] = np.max(za[m] + (xj - xa[m]) / (xb[m] - xa[m]) * (zb[m] - za[m]))
    return out


@dataclass(frozen=True, eq=False, repr=False)
class GrooveFrames:
    """Profiler frames across single grooves, with their exact truth (:func:`groove_frames`).

    Attributes
    ----------
    x : ndarray (N,)
        Reading abscissae, mm.
    z : ndarray (F, N)
        Readings, mm; NaN where a reading was lost.
    width : ndarray (F,)
        Distance between the flanks where they meet the surface line (straight flanks extended
        through any rounded top corner; a circular U where the arc meets the surface), along
        it, mm (a shear stretches it by √(1 + k²)).
    depth : ndarray (F,)
        Distance of the groove's deepest point from the surface line, mm (a shear shortens it
        by √(1 + k²)).
    center : ndarray (F, 2)
        (x, z) of the midpoint of the two crossings, in the frame, mm.
    tilt : ndarray (F,)
        Surface tilt, rad.
    shape : str
    flank_angle : ndarray (F, 2)
        Angle between the left and the right flank and the surface line where they meet,
        degrees (a circular U: the arc's there; as the frame shows it, so a shear turns them).
    area : ndarray (F,)
        Area between the surface line and the section, mm² (unchanged by tilt and shear).
    bottom_radius : ndarray (F,)
        Radius of the round bottom (a U's arc, a rounded V tip; 0 for a sharp V; NaN for a
        trapezoid's flat floor), mm.
    """

    x: np.ndarray
    z: np.ndarray
    width: np.ndarray
    depth: np.ndarray
    center: np.ndarray
    tilt: np.ndarray
    shape: str
    flank_angle: np.ndarray
    area: np.ndarray
    bottom_radius: np.ndarray

    def __repr__(self) -> str:
        return f"GrooveFrames({self.shape}: {len(self.z)} frames x {len(self.x)} readings)"


def groove_frames(
    shape: str,
    n: int,
    seed: int = 0,
    *,
    noise: float = 0.008,
    readings: int = 200,
    pitch: float = 0.025,
    max_tilt: float = 0.1,
    tilt_mode: str = "rotate",
    lips: float = 0.05,
    dropout: float = 0.03,
    flank_dropout: float = 0.15,
    spike_rate: float = 5e-4,
) -> GrooveFrames:
    """Frames across single grooves of one shape, with exact truth: the plants' groove shapes
    for testing a groove measurement (widths 0.2–1.2 mm, depths 0.05–0.5 mm).

    Shapes: ``"v"`` (flanks 15–70°, sharp or rounded tip up to 0.05 mm, top corners up to
    0.03 mm), ``"u"`` (a ball cutter's circular arc, depth ≤ radius), ``"u_walls"`` (vertical or
    drafted walls on a round bottom), ``"trapezoid"`` (flanks 30–80°, flat floor at least a
    quarter of the width, fillets up to 0.03 mm). Each frame: recast lips up to ``lips`` mm
    high just outside the edges (0 with probability 1/4, independent per side), the groove
    center within ±1 mm of the window center, a tilt up to ``max_tilt`` rad as a rotation
    (``tilt_mode="rotate"``) or as ``z += tan(tilt)·x`` (``"shear"``), a height offset up to
    ±0.5 mm; each reading the topmost point of the section on its vertical line, then Gaussian
    noise, dropouts (and more on flanks steeper than 0.5) and spikes of 0.2–1 mm.

    Examples
    --------
    >>> g = machscan.synth.groove_frames("v", 200, seed=1)
    >>> fits = machscan.fit_grooves(g.x, g.z)
    >>> np.median(np.abs(fits.width - g.width))
    """
    if tilt_mode not in ("rotate", "shear"):
        raise ValueError(f"tilt_mode: expected 'rotate' or 'shear', got {tilt_mode!r}")
    rng = np.random.default_rng(seed)
    x = (np.arange(readings) - readings // 2) * pitch
    z = np.empty((n, readings))
    width, depth, tilt, center = np.empty(n), np.empty(n), np.empty(n), np.empty((n, 2))
    flank_angle, area, bottom_radius = np.empty((n, 2)), np.empty(n), np.empty(n)
    for k in range(n):
        section = _groove_polyline(shape, rng)
        poly, w = section.poly, section.width
        depth[k] = section.depth
        width[k] = w
        area[k] = section.area
        bottom_radius[k] = section.bottom_radius
        u, v = poly[:, 0], poly[:, 1].copy()
        if lips > 0:
            for side in (-1, 1):
                h = 0.0 if rng.random() < 0.25 else rng.uniform(0.0, lips)
                half = 0.5 * rng.uniform(0.05, 0.15)
                crest = side * (w / 2 + rng.uniform(-0.005, 0.02) + half)
                tau = (u - crest) / half
                v += h * np.where(np.abs(tau) < 1, (1 - tau * tau) ** 2, 0.0)
        theta = rng.uniform(-max_tilt, max_tilt)
        xc, z_off = rng.uniform(-1.0, 1.0), rng.uniform(-0.5, 0.5)
        if tilt_mode == "rotate":
            c, s = math.cos(theta), math.sin(theta)
            px, pz = xc + u * c - v * s, z_off + u * s + v * c
            flank_angle[k] = section.flank_angles
        else:
            px, pz = xc + u, z_off + v + math.tan(theta) * u
            # A flank of cotangent t (run per depth) against the sheared surface line: the
            # angle from (1, k) to the sheared (t, k·t − 1) is atan2(1, t(1 + k²) − k), and
            # mirrored on the right.
            shear = math.tan(theta)
            # The crossings lie w apart in x on the line z = k·x, so w·√(1 + k²) along it; the
            # deepest point, d below the line in z, lies d/√(1 + k²) from it.
            width[k] *= math.hypot(1.0, shear)
            depth[k] /= math.hypot(1.0, shear)
            cot = [1 / math.tan(math.radians(a)) for a in section.flank_angles]
            flank_angle[k] = [
                math.degrees(math.atan2(1.0, cot[0] * (1 + shear * shear) - shear)),
                math.degrees(math.atan2(1.0, cot[1] * (1 + shear * shear) + shear)),
            ]
        zk = _topmost(px, pz, x)
        inside = np.abs(x - xc) < (w / 2) * math.cos(theta)
        with np.errstate(invalid="ignore", divide="ignore"):
            slope = np.abs(np.interp(x, px, np.gradient(pz, px))) if np.all(np.diff(px) > 0) else np.ones(readings)
        lost = rng.random(readings) < dropout
        lost |= inside & (slope > 0.5) & (rng.random(readings) < flank_dropout)
        zk = zk + noise * rng.standard_normal(readings)
        spikes = rng.random(readings) < spike_rate
        zk[spikes] += rng.choice([-1.0, 1.0], spikes.sum()) * rng.uniform(0.2, 1.0, spikes.sum())
        zk[lost] = np.nan
        z[k] = zk
        tilt[k] = theta
        center[k] = (xc, z_off)
    return GrooveFrames(
        x=x,
        z=z,
        width=width,
        depth=depth,
        center=center,
        tilt=tilt,
        shape=shape,
        flank_angle=flank_angle,
        area=area,
        bottom_radius=bottom_radius,
    )


@dataclass(frozen=True, eq=False, repr=False)
class MultiGrooveFrames:
    """Profiler frames each across several grooves, with their exact truth
    (:func:`multi_groove_frames`). Per-groove arrays are (F, K), left to right, NaN past a
    frame's ``count``.

    Attributes
    ----------
    x : ndarray (N,)
        Reading abscissae, mm.
    z : ndarray (F, N)
        Readings, mm; NaN where a reading was lost.
    count : ndarray of int (F,)
        Grooves in each frame.
    width, depth : ndarray (F, K)
        Each groove's width between its flanks at the surface line and its deepest point below
        it, mm (as :class:`GrooveFrames`).
    center : ndarray (F, K)
        x of the midpoint of each groove's two crossings, mm.
    """

    x: np.ndarray
    z: np.ndarray
    count: np.ndarray
    width: np.ndarray
    depth: np.ndarray
    center: np.ndarray

    def __repr__(self) -> str:
        return f"MultiGrooveFrames({len(self.z)} frames x {len(self.x)} readings, {int(self.count.sum())} grooves)"

    def match(self, fits) -> tuple[np.ndarray, np.ndarray]:
        """Each converged row of ``fits`` (``machscan.fit_grooves(x, z, select="all")``) paired
        with the truth groove of its frame whose center is nearest: the signed errors of width
        (mm), depth (relative to the true depth) and center x (mm), (M, 3), and how many rows
        each frame has (F,)."""
        found = np.zeros(len(self.z), dtype=int)
        errors = []
        for r in np.flatnonzero(fits.ok):
            k = fits.frame[r]
            c = self.center[k, : self.count[k]]
            j = int(np.argmin(np.abs(c - fits.x0[r])))
            found[k] += 1
            errors.append((fits.width[r] - self.width[k, j], fits.depth[r] / self.depth[k, j] - 1.0, fits.x0[r] - c[j]))
        return np.array(errors).reshape(-1, 3), found


def multi_groove_frames(
    n: int,
    seed: int = 0,
    *,
    grooves: tuple[int, int] = (2, 4),
    shapes: tuple[str, ...] = GROOVE_SHAPES,
    noise: float = 0.008,
    readings: int = 400,
    pitch: float = 0.025,
    max_tilt: float = 0.05,
    lips: float = 0.03,
    dropout: float = 0.02,
    shared: float = 0.25,
) -> MultiGrooveFrames:
    """Frames across 2–4 grooves each (``grooves``, inclusive), of random ``shapes`` (as
    :func:`groove_frames` draws them), with exact truth: the engraved lines that cross one
    profile. Grooves lie left to right with gaps of 0.2–1.5 mm, or, with probability
    ``shared``, share a corner with their left neighbour (their flanks meet below the surface,
    up to a tenth of the shallower depth); recast lips on free edges, a tilt up to
    ``max_tilt`` rad (a shear ``z += tan(tilt)·x``), noise and dropouts as :func:`groove_frames`.
    Lengths in mm.

    Examples
    --------
    >>> g = machscan.synth.multi_groove_frames(200, seed=1)
    >>> fits = machscan.fit_grooves(g.x, g.z, select="all")
    >>> errors, found = g.match(fits)          # width mm, depth relative, center mm
    >>> (found == g.count).mean()              # frames with every groove found
    """
    rng = np.random.default_rng(seed)
    lo, hi = grooves
    if not 1 <= lo <= hi:
        raise ValueError(f"grooves: expected (lo, hi) with 1 <= lo <= hi, got {grooves}")
    x = (np.arange(readings) - readings // 2) * pitch
    z = np.empty((n, readings))
    count = np.empty(n, dtype=np.int64)
    width, depth, center = (np.full((n, hi), np.nan) for _ in range(3))
    for f in range(n):
        k = int(rng.integers(lo, hi + 1))
        drawn = (_groove_polyline(str(rng.choice(list(shapes))), rng) for _ in range(k))
        sections = [(sec.poly, sec.width) for sec in drawn]
        # Left to right: a gap, or a corner shared with the left neighbour at a depth of 0–10 %
        # of the shallower of the two (the overlap found by bisection on the union). Laid out
        # from 0 first; gaps shrunk if the grooves would not fit in the frame.
        share = [False] + [bool(rng.random() < shared) for _ in range(k - 1)]
        steps: list[float] = []
        edge = 0.0
        centers: list[float] = []
        for j, (poly, w) in enumerate(sections):
            step = 0.0
            if share[j]:
                prev_poly, prev_w = sections[j - 1]
                corner = rng.uniform(0.0, 0.1) * min(-poly[:, 1].min(), -prev_poly[:, 1].min())

                def ridge(overlap, poly=poly, w=w, prev_poly=prev_poly, prev_c=centers[-1], edge=edge):
                    c = edge - overlap + w / 2
                    uu = np.linspace(prev_c, c, 400)
                    a = np.interp(uu, prev_poly[:, 0] + prev_c, prev_poly[:, 1], left=0.0, right=0.0)
                    b = np.interp(uu, poly[:, 0] + c, poly[:, 1], left=0.0, right=0.0)
                    return -np.minimum(a, b).max()

                lo_o, hi_o = 0.0, 0.5 * min(w, prev_w)
                for _ in range(40):
                    mid = 0.5 * (lo_o + hi_o)
                    lo_o, hi_o = (mid, hi_o) if ridge(mid) < corner else (lo_o, mid)
                step = -lo_o
            elif j > 0:
                step = rng.uniform(0.2, 1.5)
            steps.append(step)
            edge += step
            centers.append(edge + w / 2)
            edge += w
        room = (x[-1] - 0.6) - (x[0] + 0.6)
        gaps = sum(st for st in steps if st > 0)
        scale = 1.0 if edge <= room or gaps <= 0 else max(0.0, 1 - (edge - room) / gaps)
        start = x[0] + 0.6 + rng.uniform(0, max(0.0, room - (edge - (1 - scale) * gaps)))
        centers, edge = [], start
        for st, (_, w) in zip(steps, sections):
            edge += st * scale if st > 0 else st
            centers.append(edge + w / 2)
            edge += w
        u = np.linspace(x[0] - 1, x[-1] + 1, 20 * readings)
        v = np.zeros_like(u)
        for (poly, _), c in zip(sections, centers):
            v = np.minimum(v, np.interp(u, poly[:, 0] + c, poly[:, 1], left=0.0, right=0.0))
        for j, ((poly, w), c) in enumerate(zip(sections, centers)):
            for side, free in ((-1, not share[j]), (1, j + 1 == k or not share[j + 1])):
                if free and lips > 0 and rng.random() < 0.75:
                    h, half = rng.uniform(0.0, lips), 0.5 * rng.uniform(0.05, 0.15)
                    crest = c + side * (w / 2 + half + rng.uniform(0.0, 0.02))
                    tau = (u - crest) / half
                    bead = h * np.where(np.abs(tau) < 1, (1 - tau * tau) ** 2, 0.0)
                    v = np.where(v < 0, v, v + bead)
            width[f, j], depth[f, j], center[f, j] = w, -poly[:, 1].min(), c
        tilt = rng.uniform(-max_tilt, max_tilt)
        # Measured along and across the sheared surface line (as groove_frames' truth).
        width[f, :k] *= math.hypot(1.0, math.tan(tilt))
        depth[f, :k] /= math.hypot(1.0, math.tan(tilt))
        zf = np.interp(x, u, v) + math.tan(tilt) * x + rng.uniform(-0.3, 0.3)
        zf += noise * rng.standard_normal(readings)
        zf[rng.random(readings) < dropout] = np.nan
        z[f] = zf
        count[f] = k
    return MultiGrooveFrames(x=x, z=z, count=count, width=width, depth=depth, center=center)
