//! Groove cross-sections as exact geometry: one family of shapes covering the grooves plants
//! cut — V, U (ball cutter or walls with a round bottom) and trapezoid (flat floor) — so that
//! width and depth are read from the fitted shape as the issue defines them: width = distance
//! between the flanks where they meet the surface line, depth = deepest point below it.
//!
//! Levelled coordinates (u along the surface, v up, the surface line is v = 0, the groove
//! below). The general section `p = [xL, xR, tL, tR, D, s]`:
//! - `xL, xR` — where the flank lines cross the surface; `tL, tR` — flank cotangents (run per
//!   unit depth, 0 = vertical wall, negative = overhang);
//! - `D` — depth of the deepest point;
//! - `s ∈ [0, 1]` — bottom fillet radius as a fraction of `r1 = (w − T·D)/K`, the largest radius
//!   that still reaches depth D (`w = xR − xL`, `T = tL + tR`, `a = √(1 + t²)`,
//!   `K = aL + aR − T`). `s = 1`: the bottom is one arc tangent to both flanks; `s < 1`: a flat
//!   floor at depth D with two fillets of radius `s·r1`.
//!
//! The models are special cases: trapezoid T (6 parameters) is `p` itself; round-bottomed V R
//! (5) fixes `s = 1`; sharp V (4) fixes `D = w/T`; U (3) `q = [xc, R, D]` is a circle of radius
//! R whose lowest point is D deep, continued up by vertical walls when its center lies below
//! the surface and cut by the surface when above. The elliptic U E (4) `q = [xc, R, D, k]` is
//! that U stretched across by k about its axis (semi-axes k·R across, R down): a ball cutter's
//! groove crossed obliquely by the laser line (stretched by 1/cos of the crossing angle), a
//! cutter on a tilted axis, a beam's profile. No straight-flanked model holds such a bottom,
//! flatter or sharper than a circle through the same edges.
//!
//! Residuals are measured along the sensor beam (noise is along the sensor's z, which in
//! levelled coordinates is the direction `(sin θ, cos θ)`): a reading on a steep wall of a
//! tilted frame then has a well-posed residual, where a vertical one in the levelled frame
//! traps the fit. Intersections and their derivatives are in closed form (implicit
//! differentiation of each piece's equation).

/// Flank cotangent bounds: slope at least 0.05; overhang up to atan(0.15) ≈ 8.5°, since a wall
/// vertical in the sensor frame leans by the tilt once the frame is levelled.
pub const T_MAX: f64 = 20.0;
const T_OVERHANG: f64 = 0.15;
/// The flank angles the cotangent bounds allow, degrees (2.9° to 98.5°).
pub fn flank_angle_bounds() -> (f64, f64) {
    (1.0f64.atan2(T_MAX).to_degrees(), 1.0f64.atan2(-T_OVERHANG).to_degrees())
}
/// The variance (degrees²) of an angle uniform over [`flank_angle_bounds`]: what a flank
/// angle is when the readings do not fix it, and so the most any flank angle's may be.
pub fn uniform_angle_variance() -> f64 {
    let (lo, hi) = flank_angle_bounds();
    (hi - lo).powi(2) / 12.0
}
/// A sharp V's flanks are at most this steep (cotangent): steeper is a U's wall.
const T_MIN_V: f64 = 0.01;
/// The trapezoid's fillets are at most this large (mm): round bottoms are R's and U's.
const R_T_MAX: f64 = 0.05;
/// Boundary tolerance of the piece tests, mm.
const TOL: f64 = 1e-9;

/// The section models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SectionModel {
    /// Trapezoid: flat floor, straight flanks, small bottom fillets (6 parameters).
    Trapezoid,
    /// Sharp V (4).
    V,
    /// V whose bottom is one arc tangent to both flanks; covers rounded V's, circular-arc U's
    /// and drafted walls with a round bottom (5).
    Round,
    /// Circle plus vertical walls (3).
    U,
    /// Ellipse (the U stretched across) plus vertical walls (4).
    Ellipse,
}

/// The elliptic U's stretch k is kept within these bounds (an ellipse four times wider than
/// deep, or the reverse, is a V or a slot to every reading).
const K_MIN: f64 = 0.25;
const K_MAX: f64 = 4.0;

impl SectionModel {
    pub const ALL: [SectionModel; 5] =
        [SectionModel::Trapezoid, SectionModel::V, SectionModel::Round, SectionModel::U, SectionModel::Ellipse];

    /// The model's position in [`SectionModel::ALL`], for per-model arrays.
    pub fn index(self) -> usize {
        self as usize
    }

    pub fn n_params(self) -> usize {
        match self {
            SectionModel::Trapezoid => 6,
            SectionModel::V => 4,
            SectionModel::Round => 5,
            SectionModel::U => 3,
            SectionModel::Ellipse => 4,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            SectionModel::Trapezoid => "trapezoid",
            SectionModel::V => "v",
            SectionModel::Round => "round",
            SectionModel::U => "u",
            SectionModel::Ellipse => "ellipse",
        }
    }

    /// The general section `p` of the model's parameters `q` (first `n_params` entries used).
    pub fn to_p(self, q: &[f64]) -> [f64; 6] {
        match self {
            SectionModel::Trapezoid => [q[0], q[1], q[2], q[3], q[4], q[5]],
            SectionModel::Round => [q[0], q[1], q[2], q[3], q[4], 1.0],
            SectionModel::V => {
                let t = q[2] + q[3];
                [q[0], q[1], q[2], q[3], (q[1] - q[0]) / t, 1.0]
            }
            SectionModel::U | SectionModel::Ellipse => [q[0] - q[1], q[0] + q[1], 0.0, 0.0, q[2], 1.0],
        }
    }

    /// Lower and upper bounds of each parameter at `q` (the coupled `T·D ≤ w` is kept by
    /// [`SectionModel::project`] alone).
    pub fn bounds(self, q: &[f64]) -> ([f64; 6], [f64; 6]) {
        let inf = f64::INFINITY;
        match self {
            SectionModel::U => ([-inf, 0.005, 1e-3, 0.0, 0.0, 0.0], [inf; 6]),
            SectionModel::Ellipse => ([-inf, 0.005, 1e-3, K_MIN, 0.0, 0.0], [inf, inf, inf, K_MAX, inf, inf]),
            SectionModel::V => ([-inf, -inf, T_MIN_V, T_MIN_V, 0.0, 0.0], [inf, inf, T_MAX, T_MAX, inf, inf]),
            SectionModel::Round => {
                ([-inf, -inf, -T_OVERHANG, -T_OVERHANG, 1e-4, 0.0], [inf, inf, T_MAX, T_MAX, inf, inf])
            }
            SectionModel::Trapezoid => {
                ([-inf, -inf, -T_OVERHANG, -T_OVERHANG, 1e-4, 0.0], [inf, inf, T_MAX, T_MAX, inf, s_max_trapezoid(q)])
            }
        }
    }

    /// `q` moved into the admissible set (applied after every step of the fit).
    pub fn project(self, q: &mut [f64]) {
        if matches!(self, SectionModel::U | SectionModel::Ellipse) {
            q[1] = q[1].max(0.005);
            q[2] = q[2].max(1e-3);
            if self == SectionModel::Ellipse {
                q[3] = q[3].clamp(K_MIN, K_MAX);
            }
            return;
        }
        let lo = if self == SectionModel::V { T_MIN_V } else { -T_OVERHANG };
        q[2] = q[2].clamp(lo, T_MAX);
        q[3] = q[3].clamp(lo, T_MAX);
        if !(q[1] >= q[0] + 0.01) {
            let m = 0.5 * (q[0] + q[1]);
            q[0] = m - 0.005;
            q[1] = m + 0.005;
        }
        if matches!(self, SectionModel::Trapezoid | SectionModel::Round) {
            q[4] = q[4].max(1e-4);
            let t = q[2] + q[3];
            if t * q[4] > q[1] - q[0] {
                q[4] = (q[1] - q[0]) / t;
            }
        }
        if self == SectionModel::Trapezoid {
            q[5] = q[5].clamp(0.0, s_max_trapezoid(q));
        }
    }

    /// `∂p/∂q`, 6 × n_params row-major in a 6 × 6 array.
    fn p_jacobian(self, q: &[f64]) -> [[f64; 6]; 6] {
        let mut j = [[0.0; 6]; 6];
        match self {
            SectionModel::Trapezoid => (0..6).for_each(|k| j[k][k] = 1.0),
            SectionModel::Round => (0..5).for_each(|k| j[k][k] = 1.0),
            SectionModel::V => {
                (0..4).for_each(|k| j[k][k] = 1.0);
                let (w, t) = (q[1] - q[0], q[2] + q[3]);
                j[4] = [-1.0 / t, 1.0 / t, -w / (t * t), -w / (t * t), 0.0, 0.0];
            }
            SectionModel::U | SectionModel::Ellipse => {
                j[0][0] = 1.0;
                j[0][1] = -1.0;
                j[1][0] = 1.0;
                j[1][1] = 1.0;
                j[4][2] = 1.0;
            }
        }
        j
    }
}

/// `√(1 + t²)`: a flank's length per unit depth. The cotangents are bounded, so the plain
/// formula is exact enough and much faster than `hypot`.
#[inline(always)]
pub(super) fn slant(t: f64) -> f64 {
    (1.0 + t * t).sqrt()
}

/// The depth of a round V crossing the surface at `xl` < `xr`, its flank cotangents `tl`, `tr`
/// and its tip an arc of `radius` tangent to both: D = (w − K·r)/T, the inverse of
/// r1 = (w − T·D)/K (`radius` 0: the sharp V's w/T). Not finite or not positive where the
/// flanks do not meet below such a tip.
#[inline(always)]
pub(super) fn round_v_depth(xl: f64, xr: f64, tl: f64, tr: f64, radius: f64) -> f64 {
    let t = tl + tr;
    ((xr - xl) - (slant(tl) + slant(tr) - t) * radius) / t
}

/// Upper bound of the trapezoid's `s`: its fillet radius `s·r1` is at most `R_T_MAX`.
fn s_max_trapezoid(q: &[f64]) -> f64 {
    let t = q[2] + q[3];
    let k = slant(q[2]) + slant(q[3]) - t;
    let r1 = (q[1] - q[0] - t * q[4]).max(0.0) / k;
    if r1 <= R_T_MAX {
        1.0
    } else {
        R_T_MAX / r1
    }
}

/// A section resolved into its pieces: `π = [xL, xR, tL, tR, D, hc, r, cL, cR]` with the
/// fillet radius r, its center depth hc = D − r, and the fillet center abscissae.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pieces {
    pub xl: f64,
    pub xr: f64,
    pub tl: f64,
    pub tr: f64,
    pub d: f64,
    pub hc: f64,
    pub r: f64,
    pub cl: f64,
    pub cr: f64,
    /// The stretch across about `xm` (the elliptic U: `k·R` across, `R` down; 1 for every
    /// other model): the section is the one the other fields describe, its abscissae moved to
    /// `xm + k·(u − xm)`.
    pub k: f64,
    pub xm: f64,
}

/// Indices into π, for derivatives.
const XL: usize = 0;
const XR: usize = 1;
const TL: usize = 2;
const TR: usize = 3;
const D: usize = 4;
const HC: usize = 5;
const R: usize = 6;
const CL: usize = 7;
const CR: usize = 8;

impl Pieces {
    pub fn new(p: [f64; 6]) -> Self {
        let [xl, xr, tl, tr, d, s] = p;
        let (w, t) = (xr - xl, tl + tr);
        let (al, ar) = (slant(tl), slant(tr));
        let k = al + ar - t;
        let r = s * (w - t * d).max(0.0) / k;
        let hc = d - r;
        Pieces { xl, xr, tl, tr, d, hc, r, cl: xl + tl * hc + r * al, cr: xr - tr * hc - r * ar, k: 1.0, xm: 0.0 }
    }

    pub fn of(model: SectionModel, q: &[f64]) -> Self {
        let p = Pieces::new(model.to_p(q));
        if model == SectionModel::Ellipse {
            Pieces { k: q[3], xm: q[0], ..p }
        } else {
            p
        }
    }

    /// Where an abscissa of the unstretched section lies on the section (the identity but
    /// for the elliptic U).
    #[inline(always)]
    pub(super) fn stretched(&self, u: f64) -> f64 {
        if self.k == 1.0 {
            u
        } else {
            self.xm + self.k * (u - self.xm)
        }
    }

    /// The abscissa of the unstretched section that lies at `u` on the section.
    #[inline(always)]
    fn unstretched(&self, u: f64) -> f64 {
        if self.k == 1.0 {
            u
        } else {
            self.xm + (u - self.xm) / self.k
        }
    }

    /// Depths where the left and right flank lines meet their fillet arcs (tangent points).
    pub(super) fn tangent_depths(&self) -> (f64, f64) {
        let (al, ar) = (slant(self.tl), slant(self.tr));
        (self.hc + self.r * self.tl / al, self.hc + self.r * self.tr / ar)
    }

    /// Where the section meets the surface line: the flank line's crossing, or the fillet
    /// arc's where the arc reaches the surface before its tangent point (a circular U
    /// shallower than its radius).
    pub fn crossings(&self) -> (f64, f64) {
        let (htl, htr) = self.tangent_depths();
        let q = (self.r * self.r - self.hc * self.hc).max(0.0).sqrt();
        let (l, r) = (if htl >= 0.0 { self.xl } else { self.cl - q }, if htr >= 0.0 { self.xr } else { self.cr + q });
        (self.stretched(l), self.stretched(r))
    }

    /// The section's height v at u (vertical evaluation, for drawing).
    pub fn value(&self, u: f64) -> f64 {
        let u = self.unstretched(u);
        let (al, ar) = (slant(self.tl), slant(self.tr));
        let (utl, utr) = (self.cl - self.r / al, self.cr + self.r / ar);
        let arc = |c: f64| -self.hc - (self.r * self.r - (u - c) * (u - c)).max(0.0).sqrt();
        let v = if u < utl {
            -(u - self.xl) / self.tl.max(1e-12)
        } else if u < self.cl {
            arc(self.cl)
        } else if u <= self.cr {
            -self.d
        } else if u <= utr {
            arc(self.cr)
        } else {
            -(self.xr - u) / self.tr.max(1e-12)
        };
        v.min(0.0)
    }

    /// The angle between each flank and the surface line where they meet, degrees (90 = a
    /// vertical wall, above 90 an overhang), for the section leaning by `gamma` (points at
    /// depth h shifted sideways by −γh: the left flank's cotangent becomes `tL − γ`, the
    /// right's `tR + γ`). Where the fillet arc meets the surface before its tangent point
    /// (a circular U shallower than its radius) it is the arc's angle there; a lean shears the
    /// arc, so its angle is then the sheared tangent's.
    pub fn flank_angles(&self, gamma: f64) -> (f64, f64) {
        let (htl, htr) = self.tangent_depths();
        // The tangent at the surface crossing, as (run per unit depth) — the cotangent.
        let arc_cot = || {
            let q = (self.r * self.r - self.hc * self.hc).max(0.0).sqrt();
            // Radius to the crossing: (∓q, hc) from the centre; the tangent is perpendicular.
            if q > 0.0 {
                -self.hc / q
            } else {
                0.0
            }
        };
        // A stretch across by k multiplies every run by k.
        let tl = self.k * if htl >= 0.0 { self.tl } else { arc_cot() };
        let tr = self.k * if htr >= 0.0 { self.tr } else { arc_cot() };
        let angle = |t: f64| 1.0f64.atan2(t).to_degrees();
        (angle(tl - gamma), angle(tr + gamma))
    }

    /// Cross-section area between the surface line and the section, mm² (Green's theorem along
    /// the pieces: `½∮(u dv − v du)`, the surface line adding nothing; exact for lines and arcs,
    /// and unchanged by a lean, which is a shear). An arc of centre (c, −hc) from angle t₁ to t₂
    /// adds `½(r²(t₂ − t₁) + c·r(sin t₂ − sin t₁) + hc·r(cos t₂ − cos t₁))`, the sines and
    /// cosines read from its end points.
    pub fn area(&self) -> f64 {
        let (htl, htr) = self.tangent_depths();
        let (al, ar) = (slant(self.tl), slant(self.tr));
        let (r, hc) = (self.r, self.hc);
        let q = (r * r - hc * hc).max(0.0).sqrt();
        let chord = |(au, av): (f64, f64), (bu, bv): (f64, f64)| 0.5 * (au * bv - av * bu);
        // From end point (u₁, v₁) to (u₂, v₂), relative to the centre, at angles t₁, t₂.
        let arc = |c: f64, (t1, u1, v1): (f64, f64, f64), (t2, u2, v2): (f64, f64, f64)| {
            0.5 * (r * r * (t2 - t1) + c * (v2 - v1) + hc * (u2 - u1))
        };
        // The left arc runs up to the angle π − … of an overhang: counted from below, −π − ….
        let from_below = |t: f64| if t > 0.0 { t - std::f64::consts::TAU } else { t };
        let bottom = (-std::f64::consts::FRAC_PI_2, 0.0, -r);
        let mut area = chord((self.cl, -self.d), (self.cr, -self.d));
        if htl >= 0.0 {
            let start = (from_below((-self.tl).atan2(-1.0)), -r / al, -r * self.tl / al);
            area += chord((self.xl, 0.0), (self.cl - r / al, -htl)) + arc(self.cl, start, bottom);
        } else {
            area += arc(self.cl, (from_below(hc.atan2(-q)), -q, hc), bottom);
        }
        if htr >= 0.0 {
            let end = ((-self.tr).atan2(1.0), r / ar, -r * self.tr / ar);
            area += arc(self.cr, bottom, end) + chord((self.cr + r / ar, -htr), (self.xr, 0.0));
        } else {
            area += arc(self.cr, bottom, (hc.atan2(q), q, hc));
        }
        // A stretch across by k stretches every area by k.
        self.k * area
    }

    /// `∂π/∂p` (9 × 6), closed form.
    fn p_jacobian(p: &[f64; 6]) -> [[f64; 6]; 9] {
        let [xl, xr, tl, tr, d, s] = *p;
        let (w, t) = (xr - xl, tl + tr);
        let (al, ar) = (slant(tl), slant(tr));
        let k = al + ar - t;
        let r1p = w - t * d;
        let r1 = r1p.max(0.0) / k;
        let r = s * r1;
        let hc = d - r;
        let mut j = [[0.0; 6]; 9];
        for (i, row) in j.iter_mut().take(5).enumerate() {
            row[i] = 1.0;
        }
        let mut dr = [0.0; 6];
        if r1p > 0.0 {
            dr = [
                -s / k,
                s / k,
                -s * (d + r1 * (tl / al - 1.0)) / k,
                -s * (d + r1 * (tr / ar - 1.0)) / k,
                -s * t / k,
                r1,
            ];
        }
        let mut dhc = dr.map(|v| -v);
        dhc[4] += 1.0;
        j[R] = dr;
        j[HC] = dhc;
        for c in 0..6 {
            j[CL][c] = tl * dhc[c] + al * dr[c];
            j[CR][c] = -tr * dhc[c] - ar * dr[c];
        }
        j[CL][0] += 1.0;
        j[CL][2] += hc + r * tl / al;
        j[CR][1] += 1.0;
        j[CR][3] -= hc + r * tr / ar;
        j
    }
}

/// `∂π/∂q` of a model at q: 9 × n_params (in a 9 × 6 array), closed form. The chain through
/// `∂p/∂q` is written out per model (it is mostly identity): this runs every LM iteration.
#[inline(always)]
pub fn pieces_jacobian(model: SectionModel, q: &[f64]) -> [[f64; 6]; 9] {
    let jp = Pieces::p_jacobian(&model.to_p(q));
    match model {
        SectionModel::Trapezoid => jp,
        SectionModel::Round => jp.map(|row| [row[0], row[1], row[2], row[3], row[4], 0.0]),
        SectionModel::V => {
            let jq = model.p_jacobian(q);
            let dd = jq[4];
            jp.map(|row| {
                let mut out = [0.0; 6];
                for (c, o) in out.iter_mut().take(4).enumerate() {
                    *o = row[c] + row[4] * dd[c];
                }
                out
            })
        }
        SectionModel::U | SectionModel::Ellipse => {
            jp.map(|row| [row[0] + row[1], row[1] - row[0], row[4], 0.0, 0.0, 0.0])
        }
    }
}

/// `∂λ/∂q` of a beam's hit on `model` at `q` (`jq`: [`pieces_jacobian`] there). The elliptic
/// U is hit in its unstretched frame, where the reading lies at `u' = xm + (u − xm)/k` and the
/// beam runs along `(sin/k, cos)`: its center and stretch move the reading there too, by
/// `∂λ/∂u'` times `1 − 1/k` and `−(Q'u − xm)/k` (Q' the hit; the beam's turn adds `λ·∂λ/∂u'`
/// per unit of its sine, which the hit's abscissa gathers).
#[inline(always)]
pub fn beam_gradient<const N: usize>(model: SectionModel, q: &[f64], hit: &Hit, jq: &[[f64; 6]; 9]) -> [f64; N] {
    let mut row = [0.0f64; N];
    for &(k, gk) in &hit.grad {
        if gk != 0.0 {
            for (r, j) in row.iter_mut().zip(&jq[k]) {
                *r += gk * j;
            }
        }
    }
    if model == SectionModel::Ellipse && N >= 4 {
        let k = q[3];
        row[0] += hit.du * (1.0 - 1.0 / k);
        row[3] = -hit.du * (hit.qu - q[0]) / k;
    }
    row
}

/// The measures read from a section, in the order of [`Measures::values`].
pub const WIDTH: usize = 0;
pub const DEPTH: usize = 1;
pub const CENTER: usize = 2;
pub const ANGLE_LEFT: usize = 3;
pub const ANGLE_RIGHT: usize = 4;
pub const AREA: usize = 5;
pub const RADIUS: usize = 6;
pub const MEASURES: usize = 7;

/// A section's measures — width, depth, center u, flank angles (degrees), area, bottom radius
/// (NaN for the trapezoid: a flat floor has none) — with their derivatives by the model's
/// parameters and by a raise δ of the surface line (the section fixed in space: the flank
/// lines then cross it at `xL − tL·δ` and `xR + tR·δ`, the fillets stay, the bottom lies δ
/// deeper; a lean γ shifts the crossings by γδ).
#[derive(Debug, Clone, Copy)]
pub struct Measures {
    pub values: [f64; MEASURES],
    /// `∂measure/∂q` (first `n_params` columns).
    pub grad: [[f64; 6]; MEASURES],
    /// `∂measure/∂δ`.
    pub surface: [f64; MEASURES],
}

impl Measures {
    /// The measures of `model` at `q` leaning by `gamma`. Closed form from `∂π/∂q`, but the
    /// area's parameter derivatives, which are forward differences (written out, the area's
    /// derivative through every piece is long and would not be more accurate than the fit).
    pub fn of(model: SectionModel, q: &[f64], gamma: f64) -> Measures {
        Measures::at(model, q, gamma, true)
    }

    /// The measures alone (the area's derivatives, the costly part, are not taken).
    pub fn values(model: SectionModel, q: &[f64], gamma: f64) -> [f64; MEASURES] {
        Measures::at(model, q, gamma, false).values
    }

    fn at(model: SectionModel, q: &[f64], gamma: f64, area_gradient: bool) -> Measures {
        if model == SectionModel::Ellipse {
            return Measures::of_ellipse(q, gamma, area_gradient);
        }
        let p = Pieces::of(model, q);
        let j = pieces_jacobian(model, q);
        let np = model.n_params();
        let (htl, htr) = p.tangent_depths();
        let qa = (p.r * p.r - p.hc * p.hc).max(0.0).sqrt();
        let row = |k: usize| j[k];
        let lin =
            |a: [f64; 6], x: f64, b: [f64; 6], y: f64| -> [f64; 6] { std::array::from_fn(|c| x * a[c] + y * b[c]) };
        // d q_arc = (r dr − hc dhc)/q on an arc crossing.
        let dq = || lin(row(R), p.r / qa, row(HC), -p.hc / qa);
        let (xcl, dxcl, sxl, cot_l, dcot_l, scot_l) = if htl >= 0.0 {
            (p.xl, row(XL), -p.tl + gamma, p.tl - gamma, row(TL), 0.0)
        } else {
            let d = dq();
            let cot = -p.hc / qa;
            let dcot: [f64; 6] = std::array::from_fn(|c| -row(HC)[c] / qa + p.hc * d[c] / (qa * qa));
            (p.cl - qa, lin(row(CL), 1.0, d, -1.0), p.hc / qa + gamma, cot - gamma, dcot, -p.r * p.r / qa.powi(3))
        };
        let (xcr, dxcr, sxr, cot_r, dcot_r, scot_r) = if htr >= 0.0 {
            (p.xr, row(XR), p.tr + gamma, p.tr + gamma, row(TR), 0.0)
        } else {
            let d = dq();
            let cot = -p.hc / qa;
            let dcot: [f64; 6] = std::array::from_fn(|c| -row(HC)[c] / qa + p.hc * d[c] / (qa * qa));
            (p.cr + qa, lin(row(CR), 1.0, d, 1.0), -p.hc / qa + gamma, cot + gamma, dcot, -p.r * p.r / qa.powi(3))
        };
        let degrees = 180.0 / std::f64::consts::PI;
        let angle = |cot: f64| 1.0f64.atan2(cot) * degrees;
        let dangle = |cot: f64| -degrees / (1.0 + cot * cot);
        let area = p.area();
        let mut grad = [[0.0; 6]; MEASURES];
        grad[WIDTH] = lin(dxcr, 1.0, dxcl, -1.0);
        grad[DEPTH] = row(D);
        grad[CENTER] = lin(dxcr, 0.5, dxcl, 0.5);
        grad[ANGLE_LEFT] = dcot_l.map(|v| v * dangle(cot_l));
        grad[ANGLE_RIGHT] = dcot_r.map(|v| v * dangle(cot_r));
        grad[RADIUS] = row(R);
        for c in (0..np).filter(|_| area_gradient) {
            let h = 1e-7 * q[c].abs().max(1.0);
            let mut up = [0.0; 6];
            up[..np].copy_from_slice(&q[..np]);
            up[c] += h;
            grad[AREA][c] = (Pieces::of(model, &up).area() - area) / h;
        }
        let radius = if model == SectionModel::Trapezoid { f64::NAN } else { p.r };
        Measures {
            values: [xcr - xcl, p.d, 0.5 * (xcl + xcr), angle(cot_l), angle(cot_r), area, radius],
            grad,
            surface: [
                sxr - sxl,
                1.0,
                0.5 * (sxl + sxr),
                scot_l * dangle(cot_l),
                scot_r * dangle(cot_r),
                xcr - xcl,
                0.0,
            ],
        }
    }

    /// The elliptic U's measures (bottom radius: the curvature radius there, k²·R), with their
    /// derivatives by central differences when `derivatives` (the closed forms would be the
    /// U's through the stretch again, and these are taken once per fit whose errors are
    /// wanted, not per iteration).
    fn of_ellipse(q: &[f64], gamma: f64, derivatives: bool) -> Measures {
        // The measures of `q` with the surface raised by δ: the section moved down by δ.
        let at = |q: &[f64], delta: f64| -> [f64; MEASURES] {
            let p = Pieces::of(SectionModel::Ellipse, &[q[0], q[1], q[2] + delta, q[3]]);
            let (l, r) = p.crossings();
            let (al, ar) = p.flank_angles(gamma);
            [r - l, p.d, 0.5 * (l + r) + gamma * delta, al, ar, p.area(), p.k * p.k * p.r]
        };
        let values = at(q, 0.0);
        if !derivatives {
            return Measures { values, grad: [[0.0; 6]; MEASURES], surface: [0.0; MEASURES] };
        }
        let central = |f: &dyn Fn(f64) -> [f64; MEASURES], h: f64| -> [f64; MEASURES] {
            let (a, b) = (f(h), f(-h));
            std::array::from_fn(|m| (a[m] - b[m]) / (2.0 * h))
        };
        let mut grad = [[0.0; 6]; MEASURES];
        for c in 0..4 {
            let h = 1e-6 * q[c].abs().max(0.1);
            let d = central(
                &|h: f64| {
                    let mut moved = [q[0], q[1], q[2], q[3]];
                    moved[c] += h;
                    at(&moved, 0.0)
                },
                h,
            );
            for m in 0..MEASURES {
                grad[m][c] = d[m];
            }
        }
        let surface = central(&|h: f64| at(q, h), 1e-6);
        Measures { values, grad, surface }
    }
}

/// The beam from a reading and its hit on the section: `λ`, the distance along the beam
/// direction `(sn, cs)` from the reading to the section point the sensor sees (reading minus
/// model is `−λ`), and `∂λ/∂π` as up to three (index, value) pairs; in the unstretched frame
/// (the elliptic U's, [`beam_gradient`]) `∂λ/∂u` of the reading and the hit's abscissa.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub lambda: f64,
    pub grad: [(usize, f64); 3],
    pub du: f64,
    pub qu: f64,
}

impl Hit {
    const NONE: [(usize, f64); 3] = [(0, 0.0); 3];
}

/// Precomputed quantities of one section, for evaluating many beams.
#[derive(Debug, Clone, Copy)]
pub struct Beams {
    pub pieces: Pieces,
    /// Beam direction (not unit when a lean is applied) and its squared length.
    sn: f64,
    cs: f64,
    dd: f64,
    /// Lean γ: points at depth h are shifted sideways by −γh; readings are un-leaned.
    gamma: f64,
    htl: f64,
    htr: f64,
    utl: f64,
    utr: f64,
    uls: f64,
    urs: f64,
    /// The u-ranges of the flank lines (between the surface crossing and the tangent point).
    left_flank: (f64, f64),
    right_flank: (f64, f64),
    /// Reciprocals used for every beam: 1/cos, 1/|d|², and of each flank's φ·d (0 when the
    /// beam runs along the flank).
    inv_cs: f64,
    inv_dd: f64,
    inv_left: f64,
    inv_right: f64,
}

impl Beams {
    /// Beams of direction `(sin θ, cos θ)` on `pieces` leaning by `gamma`.
    #[inline(always)]
    pub fn new(pieces: Pieces, sin: f64, cos: f64, gamma: f64) -> Self {
        // The elliptic U is hit in its unstretched frame, where the beam's run is 1/k as long.
        let (sn, cs) = ((sin - gamma * cos) / pieces.k, cos);
        let (htl, htr) = pieces.tangent_depths();
        let (al, ar) = (slant(pieces.tl), slant(pieces.tr));
        let (uls, urs) = pieces.crossings();
        let (utl, utr) = (pieces.cl - pieces.r / al, pieces.cr + pieces.r / ar);
        let span = |a: f64, b: f64| if a <= b { (a, b) } else { (b, a) };
        let inverse = |den: f64| if den.abs() > 1e-12 { 1.0 / den } else { 0.0 };
        Beams {
            inv_cs: 1.0 / cs,
            inv_dd: 1.0 / (sn * sn + cs * cs),
            inv_left: inverse(sn + pieces.tl * cs),
            inv_right: inverse(sn - pieces.tr * cs),
            pieces,
            sn,
            cs,
            dd: sn * sn + cs * cs,
            gamma,
            htl,
            htr,
            utl,
            utr,
            uls,
            urs,
            left_flank: span(pieces.xl, utl),
            right_flank: span(utr, pieces.xr),
        }
    }

    /// The topmost intersection of the beam through reading (u, v) with the section.
    #[inline(always)]
    pub fn hit(&self, u: f64, v: f64) -> Hit {
        let u = self.pieces.unstretched(u - self.gamma * v);
        // Every piece lies in −D ≤ v ≤ 0, so the hit is at most (D + |v|)/cos along the beam
        // and at most |sin| times that sideways: pieces farther than that cannot be hit, and
        // are not tried. (Exact pruning; should rounding still miss, every piece is tried.)
        let reach = self.sn.abs() * (self.pieces.d + v.abs()) * self.inv_cs + 1e-9;
        let hit = self.hit_pieces(u, v, reach);
        if hit.lambda > f64::NEG_INFINITY {
            return hit;
        }
        let hit = self.hit_pieces(u, v, f64::INFINITY);
        if hit.lambda > f64::NEG_INFINITY {
            return hit;
        }
        // A connected section is always hit; should rounding miss every piece, fall back to the
        // vertical distance (no gradient).
        let lambda = (self.pieces.value(self.pieces.stretched(u)) - v) / self.cs;
        Hit { lambda, grad: Hit::NONE, du: 0.0, qu: u }
    }

    /// The topmost hit among the pieces whose u-range lies within `reach` of u.
    #[inline(always)]
    fn hit_pieces(&self, u: f64, v: f64, reach: f64) -> Hit {
        let p = &self.pieces;
        let (sn, cs) = (self.sn, self.cs);
        let near = |(a, b): (f64, f64)| u >= a - reach && u <= b + reach;
        let mut best = Hit { lambda: f64::NEG_INFINITY, grad: Hit::NONE, du: 0.0, qu: u };
        // (λ, ∂λ/∂π, ∂λ/∂u)
        let mut take = |lambda: f64, grad: [(usize, f64); 3], du: f64| {
            if lambda > best.lambda {
                best = Hit { lambda, grad, du, qu: u + sn * lambda };
            }
        };
        // Surface halves v = 0.
        if u - reach <= self.uls || u + reach >= self.urs {
            let lam = -v * self.inv_cs;
            let qu = u + sn * lam;
            if qu <= self.uls + TOL || qu >= self.urs - TOL {
                take(lam, Hit::NONE, 0.0);
            }
        }
        // Floor v = −D between the fillet centers.
        if near((p.cl, p.cr)) {
            let lam = (-p.d - v) * self.inv_cs;
            let qu = u + sn * lam;
            if qu >= p.cl - TOL && qu <= p.cr + TOL {
                take(lam, [(D, -self.inv_cs), (0, 0.0), (0, 0.0)], 0.0);
            }
        }
        // Flanks: φ = Qu ± t·Qv − x.
        let inv = self.inv_left;
        if self.htl > 0.0 && inv != 0.0 && near(self.left_flank) {
            let lam = -(u + p.tl * v - p.xl) * inv;
            let qv = v + cs * lam;
            if qv <= TOL && qv >= -self.htl - TOL {
                take(lam, [(XL, inv), (TL, -qv * inv), (0, 0.0)], -inv);
            }
        }
        let inv = self.inv_right;
        if self.htr > 0.0 && inv != 0.0 && near(self.right_flank) {
            let lam = -(u - p.tr * v - p.xr) * inv;
            let qv = v + cs * lam;
            if qv <= TOL && qv >= -self.htr - TOL {
                take(lam, [(XR, inv), (TR, qv * inv), (0, 0.0)], -inv);
            }
        }
        // Fillet arcs: φ = |Q − C| − r, C = (c, −hc); the lower intersection.
        if p.r > 0.0 {
            for (c, lo, hi, ci) in [(p.cl, self.utl, p.cl, CL), (p.cr, p.cr, self.utr, CR)] {
                if !near((lo, hi)) {
                    continue;
                }
                let (pu, pv) = (u - c, v + p.hc);
                let b = sn * pu + cs * pv;
                let disc = b * b - self.dd * (pu * pu + pv * pv - p.r * p.r);
                if disc < 0.0 {
                    continue;
                }
                let root = disc.sqrt();
                let lam = (-b - root) * self.inv_dd;
                let (qu, qv) = (u + sn * lam, v + cs * lam);
                // ∇φ·d = ((Q − C)·d)/r, and (Q − C)·d = b + λ|d|² = −√disc.
                if root > 1e-12 * p.r && qu >= lo - TOL && qu <= hi + TOL && qv <= TOL && qv <= -p.hc + TOL {
                    let e = -1.0 / root;
                    take(lam, [(ci, (qu - c) * e), (HC, -(qv + p.hc) * e), (R, p.r * e)], -(qu - c) * e);
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_is_the_position_in_all() {
        for (i, m) in SectionModel::ALL.iter().enumerate() {
            assert_eq!(m.index(), i, "{m:?}");
        }
    }

    fn q_of(model: SectionModel) -> Vec<f64> {
        match model {
            SectionModel::Trapezoid => vec![-0.31, 0.27, 0.4, 0.55, 0.2, 0.3],
            SectionModel::V => vec![-0.26, 0.24, 0.45, 0.38],
            SectionModel::Round => vec![-0.26, 0.24, 0.45, 0.38, 0.5],
            SectionModel::U => vec![0.02, 0.21, 0.15],
            SectionModel::Ellipse => vec![0.02, 0.21, 0.15, 1.4],
        }
    }

    #[test]
    fn pieces_jacobian_equals_finite_differences() {
        for model in SectionModel::ALL {
            let q = q_of(model);
            let j = pieces_jacobian(model, &q);
            let pi = |q: &[f64]| {
                let p = Pieces::of(model, q);
                [p.xl, p.xr, p.tl, p.tr, p.d, p.hc, p.r, p.cl, p.cr]
            };
            for c in 0..model.n_params() {
                let h = 1e-7;
                let (mut a, mut b) = (q.clone(), q.clone());
                a[c] += h;
                b[c] -= h;
                let (pa, pb) = (pi(&a), pi(&b));
                for k in 0..9 {
                    let fd = (pa[k] - pb[k]) / (2.0 * h);
                    assert!((fd - j[k][c]).abs() < 1e-7, "{model:?} π{k}/q{c}: {fd} vs {}", j[k][c]);
                }
            }
        }
    }

    #[test]
    fn beam_derivatives_equal_finite_differences_on_every_piece() {
        let (sin, cos) = (0.07f64.sin(), 0.07f64.cos());
        for model in SectionModel::ALL {
            let q = q_of(model);
            for gamma in [0.0, 0.05] {
                let beams = Beams::new(Pieces::of(model, &q), sin, cos, gamma);
                let jq = pieces_jacobian(model, &q);
                for k in 0..60 {
                    let u = -0.5 + k as f64 / 59.0;
                    let v = beams.pieces.value(u) + 0.004 * ((k as f64 * 1.7).sin());
                    let hit = beams.hit(u, v);
                    let row: [f64; 6] = beam_gradient(model, &q, &hit, &jq);
                    for c in 0..model.n_params() {
                        let analytic = row[c];
                        let h = 1e-7;
                        let (mut a, mut b) = (q.clone(), q.clone());
                        a[c] += h;
                        b[c] -= h;
                        let la = Beams::new(Pieces::of(model, &a), sin, cos, gamma).hit(u, v).lambda;
                        let lb = Beams::new(Pieces::of(model, &b), sin, cos, gamma).hit(u, v).lambda;
                        let fd = (la - lb) / (2.0 * h);
                        // Kinks (piece boundaries) have no derivative; they are measure zero.
                        if (la - hit.lambda).abs() < 1e-6 && (lb - hit.lambda).abs() < 1e-6 {
                            assert!((fd - analytic).abs() < 1e-5, "{model:?} γ {gamma} u {u} q{c}: {fd} vs {analytic}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn geometry_of_the_special_cases() {
        // A sharp V: depth w/T, crossings at the flank lines.
        let v = Pieces::of(SectionModel::V, &[-0.25, 0.25, 0.5, 0.5]);
        assert!((v.d - 0.5).abs() < 1e-15 && v.r.abs() < 1e-12);
        assert_eq!(v.crossings(), (-0.25, 0.25));
        assert!((v.value(0.0) + 0.5).abs() < 1e-12 && (v.value(0.125) + 0.25).abs() < 1e-12);
        // A circular U shallower than its radius meets the surface where the circle does.
        let u = Pieces::of(SectionModel::U, &[0.0, 0.5, 0.2]);
        let (l, r) = u.crossings();
        let half = (0.5f64 * 0.5 - 0.3 * 0.3).sqrt();
        assert!((l + half).abs() < 1e-12 && (r - half).abs() < 1e-12);
        assert!((u.value(0.0) + 0.2).abs() < 1e-12);
        // A U deeper than its radius: vertical walls at ±R.
        let w = Pieces::of(SectionModel::U, &[0.1, 0.2, 0.5]);
        assert_eq!(w.crossings(), (-0.1, 0.30000000000000004));
        // A trapezoid: flat floor at D between the fillets.
        let t = Pieces::of(SectionModel::Trapezoid, &[-0.5, 0.5, 0.5, 0.5, 0.3, 0.0]);
        assert!((t.value(0.0) + 0.3).abs() < 1e-15 && (t.value(-0.4) + 0.2).abs() < 1e-12);
        // The beam hits what it should: vertically, the reading's height difference.
        let b = Beams::new(t, 0.0, 1.0, 0.0);
        assert!((b.hit(0.1, -0.31).lambda - 0.01).abs() < 1e-12);
        assert!((b.hit(0.9, 0.02).lambda + 0.02).abs() < 1e-12);
    }

    #[test]
    fn elliptic_u_is_the_u_stretched_across() {
        // Semi-axes a = k·R across and b = R down, its center c = R − D above the surface.
        let (xc, rr, d, k) = (0.05, 0.2, 0.16, 1.5);
        let e = Pieces::of(SectionModel::Ellipse, &[xc, rr, d, k]);
        let (a, b, c) = (k * rr, rr, rr - d);
        let half = a * (1.0 - (c / b).powi(2)).sqrt();
        let (l, r) = e.crossings();
        assert!((l - (xc - half)).abs() < 1e-12 && (r - (xc + half)).abs() < 1e-12);
        for t in [-0.9, -0.3, 0.0, 0.5, 0.8] {
            let u = xc + t * half;
            let on_ellipse = c - b * (1.0 - ((u - xc) / a).powi(2)).sqrt();
            assert!((e.value(u) - on_ellipse).abs() < 1e-12, "{u}");
        }
        // Area: the ellipse's segment below the surface, by polygon; the flank angle: the
        // ellipse's slope at the crossing, run/drop = (a²·c)/(b²·half).
        let n = 200_000;
        let mut poly: Vec<(f64, f64)> = (0..=n)
            .map(|i| {
                let u = l + (r - l) * i as f64 / n as f64;
                (u, e.value(u))
            })
            .collect();
        poly.push((l, 0.0));
        let shoelace: f64 = poly.windows(2).map(|p| 0.5 * (p[0].0 * p[1].1 - p[0].1 * p[1].0)).sum();
        assert!((e.area() - shoelace.abs()).abs() < 1e-9, "{} {shoelace}", e.area());
        let cot = a * a * c / (b * b * half);
        let angle = 1.0f64.atan2(cot).to_degrees();
        let (al, ar) = e.flank_angles(0.0);
        assert!((al - angle).abs() < 1e-9 && (ar - angle).abs() < 1e-9, "{al} {angle}");
        let m = Measures::of(SectionModel::Ellipse, &[xc, rr, d, k], 0.0);
        assert!((m.values[RADIUS] - a * a / b).abs() < 1e-12 && (m.values[DEPTH] - d).abs() < 1e-15);
        // A beam from a reading straight above hits the ellipse there.
        let beams = Beams::new(e, 0.0, 1.0, 0.0);
        let u = xc + 0.4 * half;
        assert!((beams.hit(u, 0.01).lambda - (e.value(u) - 0.01)).abs() < 1e-12);
        // Stretched by 1 it is the U, bit for bit.
        let (u1, e1) =
            (Pieces::of(SectionModel::U, &[xc, rr, d]), Pieces::of(SectionModel::Ellipse, &[xc, rr, d, 1.0]));
        assert_eq!((u1.crossings(), u1.area(), u1.value(0.1)), (e1.crossings(), e1.area(), e1.value(0.1)));
    }

    #[test]
    fn area_and_flank_angles_equal_the_closed_forms() {
        let deg = |t: f64| 1.0f64.atan2(t).to_degrees();
        // Sharp V: a triangle.
        let v = Pieces::of(SectionModel::V, &[-0.3, 0.2, 0.6, 0.4]);
        assert!((v.area() - 0.5 * 0.5 * 0.5).abs() < 1e-14);
        assert_eq!(v.flank_angles(0.0), (deg(0.6), deg(0.4)));
        // Trapezoid without fillets: D·(2w − T·D)/2; with fillets of radius r each corner of
        // interior angle β loses r²(cot(β/2) − (π − β)/2).
        let t = Pieces::of(SectionModel::Trapezoid, &[-0.5, 0.5, 0.5, 0.25, 0.3, 0.0]);
        assert!((t.area() - 0.3 * (2.0 - 0.75 * 0.3) / 2.0).abs() < 1e-14);
        let tf = Pieces::of(SectionModel::Trapezoid, &[-0.5, 0.5, 0.5, 0.25, 0.3, 0.1]);
        let corner = |tc: f64| {
            let beta = std::f64::consts::PI - 1.0f64.atan2(tc);
            tf.r * tf.r * (1.0 / (0.5 * beta).tan() - 0.5 * (std::f64::consts::PI - beta))
        };
        assert!(tf.r > 0.0);
        assert!((tf.area() - (t.area() - corner(0.5) - corner(0.25))).abs() < 1e-13);
        // A circular U shallower than its radius: a circular segment; the arc meets the
        // surface at acos((R − D)/R).
        let (rr, d) = (0.5, 0.2);
        let u = Pieces::of(SectionModel::U, &[0.1, rr, d]);
        let seg = rr * rr * ((rr - d) / rr).acos() - (rr - d) * (2.0 * rr * d - d * d).sqrt();
        assert!((u.area() - seg).abs() < 1e-14, "{} {seg}", u.area());
        let a = ((rr - d) / rr).acos().to_degrees();
        let (l, r) = u.flank_angles(0.0);
        assert!((l - a).abs() < 1e-10 && (r - a).abs() < 1e-10);
        // A U with walls: a rectangle and a half disc; vertical walls.
        let w = Pieces::of(SectionModel::U, &[0.1, 0.2, 0.5]);
        assert!((w.area() - (0.4 * 0.3 + 0.5 * std::f64::consts::PI * 0.04)).abs() < 1e-14);
        assert_eq!(w.flank_angles(0.0), (90.0, 90.0));
        // A round V: the sharp V less the tip, r²(cot(β/2) − (π − β)/2) at the tip's angle β.
        let rv = Pieces::of(SectionModel::Round, &[-0.3, 0.2, 0.6, 0.4, 0.35]);
        let sharp = Pieces::of(SectionModel::V, &[-0.3, 0.2, 0.6, 0.4]);
        let beta = std::f64::consts::PI - 1.0f64.atan2(0.6) - 1.0f64.atan2(0.4);
        let tip = rv.r * rv.r * (1.0 / (0.5 * beta).tan() - 0.5 * (std::f64::consts::PI - beta));
        assert!(rv.r > 0.0 && (rv.area() - (sharp.area() - tip)).abs() < 1e-13);
        // Overhangs (a round V whose walls lean out by 5°): the area by polygon on a fine
        // sampling of the section.
        let o = Pieces::of(SectionModel::Round, &[-0.2, 0.2, -0.08, -0.05, 0.6]);
        let (htl, htr) = o.tangent_depths();
        assert!(htl > 0.0 && htr > 0.0 && o.tl < 0.0);
        let mut poly = vec![(o.xl, 0.0), (o.cl - o.r / slant(o.tl), -htl)];
        let (t0, t1) = ((-o.tl).atan2(-1.0) - std::f64::consts::TAU, (-o.tr).atan2(1.0));
        for k in 0..=20000 {
            let th = t0 + (t1 - t0) * k as f64 / 20000.0;
            poly.push((o.cl + o.r * th.cos(), -o.hc + o.r * th.sin()));
        }
        poly.push((o.xr, 0.0));
        let shoelace: f64 = poly.windows(2).map(|p| 0.5 * (p[0].0 * p[1].1 - p[0].1 * p[1].0)).sum();
        assert!((o.area() - shoelace).abs() < 1e-8, "{} {shoelace}", o.area());
        assert!(o.flank_angles(0.0).0 > 90.0);
        // A lean γ turns the flanks: tL − γ and tR + γ.
        assert_eq!(v.flank_angles(0.1), (deg(0.5), deg(0.5)));
    }

    /// The measures with the surface raised by δ, by moving the section down and measuring at
    /// v = 0 (as a user would see it): the reference of the δ derivatives.
    fn raised(model: SectionModel, q: &[f64], gamma: f64, delta: f64) -> [f64; MEASURES] {
        let mut p = model.to_p(q);
        p[0] -= p[2] * delta;
        p[1] += p[3] * delta;
        p[4] += delta;
        let pieces = Pieces::new(p);
        let pieces = if model == SectionModel::Ellipse { Pieces { k: q[3], xm: q[0], ..pieces } } else { pieces };
        let (l, r) = pieces.crossings();
        let (al, ar) = pieces.flank_angles(gamma);
        let radius = if model == SectionModel::Trapezoid { f64::NAN } else { pieces.k * pieces.k * pieces.r };
        [r - l, pieces.d, 0.5 * (l + r) + gamma * delta, al, ar, pieces.area(), radius]
    }

    #[test]
    fn measures_and_their_derivatives_equal_finite_differences() {
        let mut cases: Vec<(SectionModel, Vec<f64>)> = SectionModel::ALL.iter().map(|&m| (m, q_of(m))).collect();
        // A U with walls, an elliptic U with walls and a narrow one, and a round V with an
        // overhang.
        cases.push((SectionModel::U, vec![0.1, 0.2, 0.5]));
        cases.push((SectionModel::Ellipse, vec![0.1, 0.2, 0.5, 1.3]));
        cases.push((SectionModel::Ellipse, vec![-0.1, 0.3, 0.2, 0.7]));
        cases.push((SectionModel::Round, vec![-0.2, 0.2, -0.08, -0.05, 0.6]));
        for (model, q) in cases {
            for gamma in [0.0, 0.05] {
                let m = Measures::of(model, &q, gamma);
                let at = raised(model, &q, gamma, 0.0);
                for (k, (value, want)) in m.values.iter().zip(at).enumerate() {
                    let both_nan = value.is_nan() && want.is_nan();
                    assert!(both_nan || (value - want).abs() < 1e-12, "{model:?} {k}: {value} vs {want}");
                }
                let h = 1e-6;
                let (up, dn) = (raised(model, &q, gamma, h), raised(model, &q, gamma, -h));
                for k in 0..MEASURES - 1 {
                    let fd = (up[k] - dn[k]) / (2.0 * h);
                    assert!(
                        (fd - m.surface[k]).abs() < 1e-5 * fd.abs().max(1.0),
                        "{model:?} γ {gamma} δ, measure {k}: {fd} vs {}",
                        m.surface[k]
                    );
                }
                for c in 0..model.n_params() {
                    let (mut a, mut b) = (q.clone(), q.clone());
                    a[c] += h;
                    b[c] -= h;
                    let (ma, mb) = (raised(model, &a, gamma, 0.0), raised(model, &b, gamma, 0.0));
                    for k in 0..MEASURES {
                        if model == SectionModel::Trapezoid && k == RADIUS {
                            continue;
                        }
                        let fd = (ma[k] - mb[k]) / (2.0 * h);
                        assert!(
                            (fd - m.grad[k][c]).abs() < 1e-4 * fd.abs().max(1.0),
                            "{model:?} γ {gamma} q{c}, measure {k}: {fd} vs {}",
                            m.grad[k][c]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn projection_keeps_every_model_admissible() {
        let mut q = [0.3, 0.1, -3.0, 40.0, 5.0, 2.0];
        SectionModel::Trapezoid.project(&mut q);
        assert!(q[1] >= q[0] + 0.01 - 1e-12 && q[2] >= -T_OVERHANG && q[3] <= T_MAX);
        assert!((q[2] + q[3]) * q[4] <= q[1] - q[0] + 1e-12 && (0.0..=1.0).contains(&q[5]));
        let mut u = [0.0, -1.0, -1.0];
        SectionModel::U.project(&mut u);
        assert_eq!(u, [0.0, 0.005, 1e-3]);
    }
}
