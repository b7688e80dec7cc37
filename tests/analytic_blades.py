"""Analytic blades with exact normals, for the allowance and grinding paths on parts no generator in machscan makes
(pure NumPy). Independent of the package (it does not import it), so its truth is independent of the code it tests.

A part is a *blade*: a closed planar section curve C(u), u in [0, 1) counter-clockwise, swept
along the span z with a twist about the z axis and a lean/bow of the sections:

    S(u, z) = [R(theta(z)) C(u), z] + lean(z),   theta(z) = twist * (z / span - 1/2)
    lean(z) = (lx z + bx z^2, ly z + by z^2, 0)

Its unit outward normal n(u, z) is exact (S_u x S_z from analytic derivatives). A blank is the
offset surface O(u, z) = S(u, z) + d(u, z) n(u, z), sampled on its own grid, optionally jittered
along the surface and noised along n. Ground truth for a model point p = S(u0, z0) with normal
v = n(u0, z0) is the t with p + t v on O, found by Newton on (u, z, t) (`Blade.truth`); for a
uniform offset d it is exactly d wherever the offset is regular (|d| < concave radii, and
d > -edge radius).

Sections:
  EllipseSection(a, b)            semi-axes a (chord / 2, along x) and b; edge radius b^2 / a.
  LenticularSection(a, hu, hl, r) two circular arcs through (+-a, 0) with sagittas hu (upper,
                                  > 0) and hl (lower; > 0 bulges down = biconvex, < 0 bulges up
                                  = crescent, concave lower side), the corners rounded by
                                  tangent fillets of radius r (curvature jumps at the joins).
  StadiumSection(half, r)         two flats 2·half long joined by half circles of radius r (the
                                  curvature jumps from 0 to 1/r where they meet).

Also `stadium(sigma, z)`: a stadium section (flats joined by half circles, the curvature jumping
from 1/r to 0) extruded straight along z, by arc length; a blank offset by a field d(sigma, z)
along its normals has d at each model point as its exact allowance. `stadium_mesh` tessellates it as a CAD mesher
does (flats one triangle across), `stadium_offset_distance` is the exact distance along a line to its offset.

Example:
    blade = Blade(EllipseSection(20, 4), span=60, twist_deg=30, lean=(0.05, 0.02))
    u, z = blade.model_grid(0.3, z_range=(0, 60))
    p, v = blade.point(u, z), blade.normal(u, z)
    bk = blade.sample_blank(0.5, z_range=(-3, 63), offset=0.3, rng=np.random.default_rng(1))
    t_true = blade.truth(u, z, offset=0.3)          # == 0.3 here
    height = blade.height(path_points)              # signed distance of points from the surface, mm
"""
from __future__ import annotations

import numpy as np

TAU = 2.0 * np.pi


class Section:
    """A closed planar curve C(u), u in [0, 1), counter-clockwise (outward normal (C'y, -C'x))."""

    edge_radius: float
    edge_u: np.ndarray  # parameters of the edge tips (leading/trailing)

    def point(self, u):
        raise NotImplementedError

    def deriv(self, u):
        raise NotImplementedError

    def _arclength_table(self, n=200_000):
        if not hasattr(self, "_tab"):
            uu = np.linspace(0.0, 1.0, n + 1)
            sp = np.linalg.norm(self.deriv(uu), axis=-1)
            s = np.concatenate([[0.0], np.cumsum(0.5 * (sp[1:] + sp[:-1]) * np.diff(uu))])
            self._tab = (uu, s)
        return self._tab

    @property
    def length(self):
        return self._arclength_table()[1][-1]

    def arclength(self, u):
        uu, s = self._arclength_table()
        u = np.mod(u, 1.0)
        return np.interp(u, uu, s)

    def u_at(self, s):
        """Parameter at arc length s (periodic)."""
        uu, ss = self._arclength_table()
        return np.interp(np.mod(s, ss[-1]), ss, uu)

    def edge_distance(self, u):
        """Arc length from C(u) to the nearest edge tip, mm."""
        s, L = self.arclength(u), self.length
        d = np.full(np.shape(u), np.inf)
        for ue in self.edge_u:
            ds = np.abs(s - self.arclength(ue))
            d = np.minimum(d, np.minimum(ds, L - ds))
        return d


class EllipseSection(Section):
    """Ellipse x = a cos(2 pi u), y = b sin(2 pi u); edges (u = 0, 1/2) of radius b^2 / a."""

    def __init__(self, a, b):
        self.a, self.b = float(a), float(b)
        self.edge_radius = self.b**2 / self.a
        self.edge_u = np.array([0.0, 0.5])

    @classmethod
    def with_edge_radius(cls, a, r):
        return cls(a, np.sqrt(r * a))

    def point(self, u):
        w = TAU * np.asarray(u, float)
        return np.stack([self.a * np.cos(w), self.b * np.sin(w)], -1)

    def deriv(self, u):
        w = TAU * np.asarray(u, float)
        return TAU * np.stack([-self.a * np.sin(w), self.b * np.cos(w)], -1)

    def __repr__(self):
        return f"Ellipse(a={self.a:g}, b={self.b:.3g}, r_e={self.edge_radius:.3g})"


class LenticularSection(Section):
    """Two circular arcs through (+-a, 0), sagittas hu (up) and hl (down; < 0: crescent), corners
    rounded by fillets of radius r tangent to both arcs. Unit speed in arc length: u = s / L."""

    def __init__(self, a, hu, hl, r):
        assert hu > 0 and hu + hl > 0 and r > 0
        self.a, self.hu, self.hl, self.edge_radius = float(a), float(hu), float(hl), float(r)
        yu = (hu**2 - a**2) / (2 * hu)
        Ru = hu - yu
        yl = (a**2 - hl**2) / (2 * hl)
        Rl = abs(yl + hl)
        convex_lower = hl > 0
        du = Ru - r
        dl = Rl - r if convex_lower else Rl + r
        yf = 0.5 * (yu + yl) + (du**2 - dl**2) / (2 * (yl - yu))
        xf = np.sqrt(du**2 - (yf - yu) ** 2)
        cu, cl = np.array([0.0, yu]), np.array([0.0, yl])
        fr, fl = np.array([xf, yf]), np.array([-xf, yf])

        def toward(c, R, f):
            d = f - c
            return c + R * d / np.linalg.norm(d)

        tur, tul = toward(cu, Ru, fr), toward(cu, Ru, fl)
        tlr, tll = toward(cl, Rl, fr), toward(cl, Rl, fl)
        def ang(c, q):
            return np.arctan2(q[1] - c[1], q[0] - c[0])

        def arc(c, R, q0, q1, ccw):
            a0, a1 = ang(c, q0), ang(c, q1)
            sweep = np.mod(a1 - a0, TAU) if ccw else -np.mod(a0 - a1, TAU)
            return (c, R, a0, sweep)

        # CCW: upper arc (right -> left), left fillet, lower arc (left -> right), right fillet.
        self.pieces = [
            arc(cu, Ru, tur, tul, True),
            arc(fl, r, tul, tll, True),
            arc(cl, Rl, tll, tlr, convex_lower),
            arc(fr, r, tlr, tur, True),
        ]
        self.lens = np.array([R * abs(sw) for (_, R, _, sw) in self.pieces])
        self.starts = np.concatenate([[0.0], np.cumsum(self.lens)])
        self._L = self.starts[-1]
        # edge tips: middle of each fillet
        self.edge_u = np.array([(self.starts[1] + 0.5 * self.lens[1]) / self._L,
                                (self.starts[3] + 0.5 * self.lens[3]) / self._L])

    @property
    def length(self):
        return self._L

    def arclength(self, u):
        return np.mod(u, 1.0) * self._L

    def u_at(self, s):
        return np.mod(s, self._L) / self._L

    def _eval(self, u, which):
        s = np.mod(np.asarray(u, float), 1.0) * self._L
        out = np.empty(s.shape + (2,))
        k = np.clip(np.searchsorted(self.starts, s, side="right") - 1, 0, 3)
        for i, (c, R, a0, sw) in enumerate(self.pieces):
            m = k == i
            sg = np.sign(sw)
            phi = a0 + sg * (s[m] - self.starts[i]) / R
            if which == 0:
                out[m] = c + R * np.stack([np.cos(phi), np.sin(phi)], -1)
            else:
                out[m] = self._L * sg * np.stack([-np.sin(phi), np.cos(phi)], -1)
        return out

    def point(self, u):
        return self._eval(u, 0)

    def deriv(self, u):
        return self._eval(u, 1)

    def __repr__(self):
        return f"Lenticular(a={self.a:g}, hu={self.hu:g}, hl={self.hl:g}, r_e={self.edge_radius:g})"


class StadiumSection(Section):
    """Two flats 2·half long joined by half circles of radius r (the curvature jumps from 0 to 1/r where they meet),
    by arc length: u = s / length, counter-clockwise from the bottom flat's left end (-half, -r)."""

    def __init__(self, half, r):
        self.half, self.r = float(half), float(r)
        self.edge_radius = self.r
        self.legs = np.array([2 * self.half, np.pi * self.r, 2 * self.half, np.pi * self.r])
        self.start = np.concatenate([[0.0], np.cumsum(self.legs)])
        self.edge_u = np.array([self.start[1] + 0.5 * self.legs[1], self.start[3] + 0.5 * self.legs[3]]) / self.length

    @property
    def length(self):
        return float(self.start[-1])

    def arclength(self, u):
        return np.mod(np.asarray(u, float), 1.0) * self.length

    def u_at(self, s):
        return np.mod(np.asarray(s, float), self.length) / self.length

    def _eval(self, u):
        s = np.mod(np.asarray(u, float), 1.0) * self.length
        pt, tg = np.zeros(s.shape + (2,)), np.zeros(s.shape + (2,))
        for k in range(4):
            on = (s >= self.start[k]) & (s < self.start[k + 1]) if k < 3 else s >= self.start[3]
            t = s[on] - self.start[k]
            if k in (0, 2):
                sign = 1.0 if k == 0 else -1.0
                pt[on] = np.stack([sign * (-self.half + t), -sign * self.r * np.ones_like(t)], -1)
                tg[on] = [sign, 0.0]
            else:
                sign = 1.0 if k == 1 else -1.0
                a = t / self.r - np.pi / 2
                pt[on] = np.stack([sign * (self.half + self.r * np.cos(a)), sign * self.r * np.sin(a)], -1)
                tg[on] = np.stack([-sign * np.sin(a), sign * np.cos(a)], -1)
        return pt, tg * self.length

    def point(self, u):
        return self._eval(u)[0]

    def deriv(self, u):
        return self._eval(u)[1]

    def __repr__(self):
        return f"Stadium(half={self.half:g}, r={self.r:g})"


class Blade:
    """A section swept along z in [0, span] with a twist (deg, total) and lean/bow (see module)."""

    def __init__(self, section, span=60.0, twist_deg=30.0, lean=(0.0, 0.0), bow=(0.0, 0.0)):
        self.section, self.span = section, float(span)
        self.twist = np.radians(twist_deg)
        self.lean, self.bow = np.asarray(lean, float), np.asarray(bow, float)

    def __repr__(self):
        return f"Blade({self.section}, twist={np.degrees(self.twist):g} deg)"

    def _theta(self, z):
        return self.twist * (np.asarray(z, float) / self.span - 0.5)

    def point(self, u, z):
        u, z = np.broadcast_arrays(np.asarray(u, float), np.asarray(z, float))
        c = self.section.point(u)
        th = self._theta(z)
        co, si = np.cos(th), np.sin(th)
        x = co * c[..., 0] - si * c[..., 1] + self.lean[0] * z + self.bow[0] * z * z
        y = si * c[..., 0] + co * c[..., 1] + self.lean[1] * z + self.bow[1] * z * z
        return np.stack([x, y, z], -1)

    def derivs(self, u, z):
        """(S_u, S_z), exact."""
        u, z = np.broadcast_arrays(np.asarray(u, float), np.asarray(z, float))
        c, dc = self.section.point(u), self.section.deriv(u)
        th = self._theta(z)
        co, si = np.cos(th), np.sin(th)
        su = np.stack([co * dc[..., 0] - si * dc[..., 1], si * dc[..., 0] + co * dc[..., 1],
                       np.zeros_like(z)], -1)
        w = self.twist / self.span
        sz = np.stack([w * (-si * c[..., 0] - co * c[..., 1]) + self.lean[0] + 2 * self.bow[0] * z,
                       w * (co * c[..., 0] - si * c[..., 1]) + self.lean[1] + 2 * self.bow[1] * z,
                       np.ones_like(z)], -1)
        return su, sz

    def normal(self, u, z):
        """Unit outward normal."""
        su, sz = self.derivs(u, z)
        n = np.cross(su, sz)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def offset_point(self, u, z, offset):
        """O(u, z) = S + d(u, z) n; `offset` is a number or a callable d(u, z)."""
        d = offset(u, z) if callable(offset) else offset
        return self.point(u, z) + np.asarray(d)[..., None] * self.normal(u, z)

    # ---- sampling -------------------------------------------------------------------------
    def model_grid(self, spacing, z_range=None, span_spacing=None, stagger=0.0):
        """(u, z) of model points: rows every `span_spacing` (default `spacing`) in z, points
        every `spacing` of section arc length along each row, each row's points shifted along it
        by `stagger` × spacing more than the row before's (a scan's lines do not line up).
        Flattened arrays."""
        z0, z1 = z_range if z_range is not None else (0.0, self.span)
        dz = span_spacing or spacing
        zs = np.arange(z0, z1 + 1e-9, dz)
        L = self.section.length
        s = np.arange(0.0, L - 1e-9, spacing)
        U = [self.section.u_at(s + np.mod(k * stagger, 1.0) * spacing) for k in range(len(zs))]
        return np.concatenate(U), np.repeat(zs, len(s))

    def height(self, points):
        """Signed distance of `points` from the surface (positive outside), mm."""
        q = np.asarray(points, float).reshape(-1, 3)
        u, z = self.foot(q)
        return np.sum((q - self.point(u, z)) * self.normal(u, z), -1)

    def foot(self, points, iters=30):
        """(u, z) of the surface point nearest each of `points`: Newton on (u, z), started from the
        nearest of a grid every 0.1 mm of section and 0.5 mm of span about the point's z (a point
        lies within a few mm of its foot)."""
        q = np.asarray(points, float).reshape(-1, 3)
        us = self.section.u_at(np.arange(0.0, self.section.length, 0.1))
        dz = np.linspace(-1.0, 1.0, 5)
        u, z = np.empty(len(q)), np.empty(len(q))
        for k in range(0, len(q), 256):
            p = q[k : k + 256]
            zs = np.clip(p[:, 2:3] + dz, 0.0, self.span)  # (m, 5)
            grid = self.point(us[None, None, :], zs[:, :, None])  # (m, 5, nu, 3)
            d2 = np.sum((grid - p[:, None, None, :]) ** 2, axis=-1).reshape(len(p), -1)
            i = np.argmin(d2, axis=1)
            u[k : k + 256], z[k : k + 256] = us[i % len(us)], zs[np.arange(len(p)), i // len(us)]
        for _ in range(iters):
            su, sz = self.derivs(u, z)
            f = self.point(u, z) - q
            g = np.stack([np.sum(f * su, -1), np.sum(f * sz, -1)], -1)
            j = np.stack([np.sum(su * su, -1), np.sum(su * sz, -1), np.sum(su * sz, -1), np.sum(sz * sz, -1)], -1)
            j = j.reshape(-1, 2, 2)
            step = np.linalg.solve(j, g[..., None])[..., 0]
            u, z = u - step[:, 0], z - step[:, 1]
            if np.max(np.abs(step)) < 1e-13:
                break
        return u, z

    def sample_blank(self, spacing, z_range=None, offset=0.3, rng=None, jitter=0.0, noise=0.0,
                     stagger=True):
        """Blank points on the offset surface O(u, z): rows every `spacing` in z (random phase),
        along each row uniform in the arc length of the *offset* curve (random phase per row
        if `stagger`, so the grid is not aligned with the model's). `jitter` (fraction of the
        spacing) moves each point along the surface (in u and z); `noise` (mm, sigma) moves it
        along the model normal n(u, z) (= the blank's normal for a uniform offset).
        Returns dict(points, u, z)."""
        rng = np.random.default_rng(0) if rng is None else rng
        z0, z1 = z_range if z_range is not None else (-0.05 * self.span, 1.05 * self.span)
        zs = np.arange(z0 + rng.uniform(0, spacing), z1, spacing)
        L = self.section.length
        n_dense = max(4000, int(20 * L / spacing))
        ud = np.linspace(0.0, 1.0, n_dense + 1)
        U, Z = [], []
        for z in zs:
            q = self.offset_point(ud, np.full_like(ud, z), offset)
            s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(q, axis=0), axis=1))])
            # The section is closed: n equal steps round it, so no gap opens where u wraps (a
            # fillet join on the lenticular sections).
            n = max(3, round(s[-1] / spacing))
            step = s[-1] / n
            ph = rng.uniform(0, step) if stagger else 0.0
            st = ph + step * np.arange(n)
            U.append(np.interp(st, s, ud))
            Z.append(np.full(st.shape, z))
        U, Z = np.concatenate(U), np.concatenate(Z)
        if jitter:
            # u jitter in arc length at the model: du = ds / |C'(u)| (approx. per point)
            sp = np.linalg.norm(self.section.deriv(U), axis=-1)
            U = np.mod(U + rng.uniform(-jitter, jitter, U.shape) * spacing / sp, 1.0)
            Z = Z + rng.uniform(-jitter, jitter, Z.shape) * spacing
        P = self.offset_point(U, Z, offset)
        if noise:
            P = P + rng.normal(0.0, noise, U.shape)[:, None] * self.normal(U, Z)
        return dict(points=P, u=U, z=Z)

    # ---- ground truth ------------------------------------------------------------------------
    def truth(self, u, z, offset, iters=30, tol=1e-11, return_params=False):
        """Exact allowance along the model normal: t with S(u,z) + t n(u,z) on the offset
        surface O; Newton on (u', z', t) with a central-difference Jacobian of O (the residual
        is exact, so the root is exact to ~1e-12 mm). NaN where Newton fails. With
        `return_params`, also (u', z'): where on the blank's parameter grid the line meets it
        (to decide whether a cut-off blank covers the point)."""
        u, z = np.asarray(u, float).ravel(), np.asarray(z, float).ravel()
        p, v = self.point(u, z), self.normal(u, z)
        d0 = offset(u, z) if callable(offset) else np.full(u.shape, float(offset))
        if not callable(offset) and not return_params:
            return d0.copy()  # exact where the offset is regular
        off = offset if callable(offset) else (lambda uu, zz, c=float(offset): np.full(np.shape(uu), c))
        offset = off
        x = np.stack([u, z, d0], -1)
        hu, hz = 1e-6, 1e-5
        for _ in range(iters):
            F = self.offset_point(x[:, 0], x[:, 1], offset) - p - x[:, 2:3] * v
            if np.max(np.abs(F)) < tol:
                break
            Ju = (self.offset_point(x[:, 0] + hu, x[:, 1], offset)
                  - self.offset_point(x[:, 0] - hu, x[:, 1], offset)) / (2 * hu)
            Jz = (self.offset_point(x[:, 0], x[:, 1] + hz, offset)
                  - self.offset_point(x[:, 0], x[:, 1] - hz, offset)) / (2 * hz)
            J = np.stack([Ju, Jz, -v], -1)
            x = x - np.linalg.solve(J, F[..., None])[..., 0]
        F = self.offset_point(x[:, 0], x[:, 1], offset) - p - x[:, 2:3] * v
        t = x[:, 2].copy()
        t[np.linalg.norm(F, axis=1) > 1e-9] = np.nan
        if return_params:
            return t, np.mod(x[:, 0], 1.0), x[:, 1]
        return t


def smooth_offset(blade, lo=0.1, hi=0.5, waves=(1, 1.5), phase=(0.3, 0.7)):
    """A smooth offset d(u, z) in [lo, hi], varying around the section (`waves[0]` periods)
    and along the span (`waves[1]` periods over the span)."""
    mid, amp = 0.5 * (lo + hi), 0.5 * (hi - lo)

    def d(u, z):
        return mid + amp * np.sin(TAU * waves[0] * np.asarray(u) + TAU * phase[0]) * np.cos(
            TAU * waves[1] * np.asarray(z) / blade.span + TAU * phase[1])

    return d


def stadium(sigma, z, half=5.0, r=1.5):
    """A stadium section (flats 2·half long joined by half circles of radius r: the curvature jumps from 1/r to 0
    where they meet) extruded along z: points and outward normals at arc length σ and height z. σ runs clockwise seen
    from +z from (−half, r): `StadiumSection` mirrored in y."""
    section = StadiumSection(half, r)
    u = np.asarray(sigma, float) / section.length
    c, d = section.point(u), section.deriv(u)
    normal = np.stack([d[..., 1], -d[..., 0]], -1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    flip = np.array([1.0, -1.0])
    z = np.broadcast_to(np.asarray(z, float), u.shape)
    return np.column_stack([c * flip, z]), np.column_stack([normal * flip, np.zeros_like(z)])


def stadium_mesh(half=5.0, r=1.5, length=20.0, arc_step_deg=10.0):
    """The stadium prism as a CAD mesher tessellates it: each flat one triangle pair across, the half circles cut every
    `arc_step_deg`, two rows of vertices at z = 0 and `length`; wound outward. (vertices (N, 3), triangles (T, 3))."""
    arc_n = round(180.0 / arc_step_deg)
    arc = np.pi * r
    cuts = np.linspace(0, arc, arc_n + 1)
    sigma = np.concatenate([[0.0], 2 * half + cuts, 4 * half + arc + cuts[:-1]])
    sigma = np.unique(np.round(sigma, 9))
    s, z = np.meshgrid(sigma, [0.0, length], indexing="ij")
    vertices, _ = stadium(s.ravel(), z.ravel())
    k = len(sigma)
    i = np.arange(k)
    a, b, c, d = 2 * i, 2 * ((i + 1) % k), 2 * ((i + 1) % k) + 1, 2 * i + 1
    # stadium() runs clockwise seen from +z, so (a, b, c) would wind inward.
    return vertices, np.concatenate([np.column_stack([a, c, b]), np.column_stack([a, d, c])])


def stadium_offset_distance(points, directions, offset, half=5.0, r=1.5):
    """Distance t along each unit direction from each point to the stadium offset by `offset` (flats at |y| = r +
    offset, half circles of radius r + offset about (±half, 0)): exact, the nearest crossing ahead within 1 mm."""
    p, v = np.asarray(points, float), np.asarray(directions, float)
    t = np.full(len(p), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        for sign in (1, -1):
            flat = (sign * (r + offset) - p[:, 1]) / v[:, 1]
            x = p[:, 0] + flat * v[:, 0]
            t = np.where(np.isnan(t) & (np.abs(x) <= half) & (np.abs(flat) < 1), flat, t)
        for sign in (1, -1):
            q, w = p[:, :2] - [sign * half, 0.0], v[:, :2]
            a, b, c = np.sum(w * w, 1), 2 * np.sum(q * w, 1), np.sum(q * q, 1) - (r + offset) ** 2
            root = (-b + np.sqrt(b * b - 4 * a * c)) / (2 * a)
            x = p[:, 0] + root * v[:, 0]
            t = np.where(np.isnan(t) & (sign * (x - sign * half) >= 0) & (np.abs(root) < 1), root, t)
    return t


def _inside(q, poly):
    """Even-odd point-in-polygon (for the self-test)."""
    x, y = q[:, 0:1], q[:, 1:2]
    x0, y0, x1, y1 = poly[:-1, 0], poly[:-1, 1], poly[1:, 0], poly[1:, 1]
    cross = ((y0 > y) != (y1 > y)) & (x < x0 + (y - y0) * (x1 - x0) / (y1 - y0 + 1e-300))
    return np.sum(cross, axis=1) % 2 == 1


def self_test():
    rng = np.random.default_rng(0)
    for sec in [EllipseSection(20, 4), LenticularSection(20, 3, 2, 0.8),
                LenticularSection(20, 5, -1.5, 0.5)]:
        b = Blade(sec, 60, 30, lean=(0.05, -0.03), bow=(1e-3, 0))
        u = rng.uniform(0, 1, 500)
        z = rng.uniform(0, 60, 500)
        # derivatives vs finite differences
        su, sz = b.derivs(u, z)
        h = 1e-6
        assert np.allclose((b.point(u + h, z) - b.point(u - h, z)) / (2 * h), su, atol=1e-5)
        assert np.allclose((b.point(u, z + h) - b.point(u, z - h)) / (2 * h), sz, atol=1e-5)
        # curve closed and C1: tangent continuous; outward normal points away from centroid
        c = sec.point(np.linspace(0, 1, 20001))
        assert np.linalg.norm(c[0] - c[-1]) < 1e-9
        tg = sec.deriv(np.linspace(0, 1, 20001))
        tg /= np.linalg.norm(tg, axis=1, keepdims=True)
        assert np.min(np.sum(tg[1:] * tg[:-1], 1)) > 0.99
        # outward: a step along n(u, 0) (no twist/lean at z where theta = 0 ... use 2D check)
        b0 = Blade(sec, 60, 0)
        q = b0.point(u, 0 * u)[:, :2] + 0.05 * b0.normal(u, 0 * u)[:, :2]
        assert not np.any(_inside(q, c)), "normal not outward"
        # edge radius from curvature at the tip
        ue = sec.edge_u[0]
        d1, d2 = sec.deriv(ue), (sec.deriv(ue + 1e-6) - sec.deriv(ue - 1e-6)) / 2e-6
        r = np.linalg.norm(d1) ** 3 / (d1[0] * d2[1] - d1[1] * d2[0])
        assert abs(r - sec.edge_radius) < 1e-4, (r, sec.edge_radius)
        # truth for a smooth offset: point on O and on the line
        d = smooth_offset(b)
        t = b.truth(u, z, d)
        assert np.all(np.isfinite(t)) and np.all((t > 0.09) & (t < 0.51))
    print("parts self-test ok")


if __name__ == "__main__":
    self_test()
