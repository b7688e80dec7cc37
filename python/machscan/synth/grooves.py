"""Paper 000 groove plate scans with exact ground truth, for tests, demos and benchmarks (single
groove frames: :mod:`machscan.synth.frames`).

:func:`groove_scan` reproduces the experiment of paper 000 §3 (on-machine measurement of
laser-engraved chemical-milling grooves): a 200 mm x 200 mm aluminium plate covered with
maskant, bent a few tenths of a millimetre by clamping, carrying 11 engraved closed contours,
scanned contour by contour by an SR7140-like line-laser profiler on a gantry with an AC
double-swing head and a sixth axis C2 that keeps the laser line across the groove. Everything
the measurement pipeline should recover is returned in a :class:`GrooveTruth`: the groove
center, width and depth at every frame, the engraved contours, and the three error sources of
the paper's decomposition (rigid offset, bending, local wiggle) separately.

All lengths are in mm, angles in rad, times in s. The module is pure NumPy (it does not use
the compiled core), so its output can be checked against independent references.

Model summary (numbers from paper 000 unless marked as assumptions):

* Plate: ``[0, 200] x [0, 200]`` mm in the WCS, nominal (CAD) top surface of the maskant at
  ``z = 0``; 2 mm thick (assumption), lying on a machine table at ``z = -2``.
* Bending: a smooth low-order polynomial deflection ``w(x, y)`` whose peak ``|w|`` over the
  plate is ``bend`` (default 0.3 mm); largest at the x ends, as the paper's fig. 11 and 12
  describe. The engraved grooves sit on the bent surface.
* Grooves: V sections with straight flanks, the bottom rounded by the laser spot (radius
  0.01 mm) and the top edges by 0.01 mm (assumptions), width between the flanks at the surface
  ~0.48 mm and depth (deepest point) ~0.31 mm (paper: 0.4806 +- 0.0163 and 0.3124 +- 0.0148
  mm), varying smoothly along the arc length, with small laser-sintered lips (0.01-0.03 mm
  high) just outside both edges (paper fig. 10).
* Engraving errors per contour: a rigid offset of a few tens of um (paper: offset error
  0.0255 +- 0.0148 mm) and a smooth normal wiggle of ~15 um RMS along the arc length
  (paper: local error 0.0123 +- 0.0062 mm).
* Profiler: 3200 readings at 0.025 mm, Gaussian noise sigma 0.008 mm (the paper's +-0.024 mm
  read as 3 sigma), 2500 frames/s; dropouts (sentinel) in short runs and more often on the
  steep groove flanks; rare spikes; a shadow next to the plate edge.
* Machine: ``A = C = 0`` while scanning; ``C2`` turns the laser line onto the outward normal
  of the nominal contour; the SCS origin (reading center, height 0) follows the nominal
  contour on the nominal surface at the scanning feed (default 20 mm/s = 1200 mm/min, an
  assumption). Readings are ray-cast through the true (slightly misaligned) mount.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..scan import SENTINEL, Profiler, Scan
from .plate import (
    _TWO_PI,
    PLATE,
    ContourShape,
    Deflection,
    GrooveTruth,
    PeriodicProfile,
    _engraved_xy,
    _groove_height_k,
    _make_design,
    default_contours,
)

__all__ = [
    "DEFAULT_C2_OFFSET",
    "DEFAULT_MOUNT",
    "PLATE",
    "ContourShape",
    "Deflection",
    "GrooveTruth",
    "PeriodicProfile",
    "SurfaceError",
    "default_contours",
    "flat_plate_scan",
    "groove_scan",
    "surface_error",
]


#: ``(Lx, Ly, Lz)``: origin of the C2 frame in the tool frame, mm. The profiler hangs beside
#: the engraving head; with the default mount the SCS origin is 25 mm below the tool tip.
DEFAULT_C2_OFFSET = (-120.0, 35.0, 115.0)

#: ``(theta, psi, phi, dx, dy, dz)``: SCS pose in the C2 frame (rad, mm). A few mrad of
#: misalignment and a sub-mm offset of the line center from the C2 axis; ``dz = -140`` puts the
#: reference plane 140 mm below the C2 frame origin (an SR7140-like stand-off, assumption).
DEFAULT_MOUNT = (0.0031, -0.0024, 0.0042, 0.62, -0.41, -140.0)



# --------------------------------------------------------------------------------------------
# Kinematics (private NumPy copy of SPEC K2/K3; tests compare it with an independent reference)
# --------------------------------------------------------------------------------------------


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(np.shape(a) + (3, 3))
    out[..., 0, 0] = c
    out[..., 0, 1] = -s
    out[..., 1, 0] = s
    out[..., 1, 1] = c
    out[..., 2, 2] = 1.0
    return out


def _mount_rotation(theta, psi, phi):
    ct, st = math.cos(theta), math.sin(theta)
    cs, ss = math.cos(psi), math.sin(psi)
    cf, sf = math.cos(phi), math.sin(phi)
    return np.array(
        [
            [ct * cf, ss * st * cf - cs * sf, cs * st * cf + ss * sf],
            [ct * sf, ss * st * sf + cs * cf, cs * st * sf - ss * cf],
            [-st, ss * ct, cs * ct],
        ]
    )


def _transforms_a0c0(poses, c2_offset, mount):
    """WCS <- SCS rotation (F,3,3) and translation (F,3) for poses with A = C = 0."""
    m = np.asarray(mount, dtype=np.float64)
    rc2 = _rz(poses[:, 5])
    rot = rc2 @ _mount_rotation(m[0], m[1], m[2])
    trans = rc2 @ m[3:6] + np.asarray(c2_offset) + poses[:, :3]
    return rot, trans


# --------------------------------------------------------------------------------------------
# The generator
# --------------------------------------------------------------------------------------------


class _ScanPath:
    """The scan's path: each pass runs along its contour from u = −lead_in to u = L + lead_in at
    constant feed (the machine is up to speed before the first frame); passes are joined by
    straight moves of `gap` s; the CNC records `lead` s before the first and after the last pass.
    The frames kept (every `keep_every`-th of the profiler's), their contour, arc length, time
    and pose."""

    lead, gap, lead_in = 0.5, 2.0, 2.0

    def __init__(self, shapes, feed, rate, keep_every, c2_offset, mount):
        self.shapes, self.feed, self.c2_offset, self.mount = shapes, feed, c2_offset, mount
        step = feed / rate
        pass_starts: list[float] = []
        t = self.lead + self.lead_in / feed
        f_contour, f_u, f_t = [], [], []
        for k, sh in enumerate(shapes):
            L = sh.length
            n_raw = math.floor(L / step - 1e-9) + 1  # raw frames with u < L
            j = np.arange(0, n_raw, keep_every)
            pass_starts.append(t)
            f_contour.append(np.full(j.size, k, dtype=np.int64))
            f_u.append(j * step)
            f_t.append(t + j / rate)
            t = t + (L + 2.0 * self.lead_in) / feed + self.gap
        self.t_start = np.array(pass_starts)
        self.frame_contour = np.concatenate(f_contour)
        self.frame_u = np.concatenate(f_u)
        self.frame_times = np.concatenate(f_t)
        self.phi = float(mount[2])
        # Branch of C2 per pass: continuous over the whole scan, first pass starting in [0, 2 pi).
        self.c2_shift = np.zeros(len(shapes))
        prev_end = None
        for k, sh in enumerate(shapes):
            start = float(sh.tangent_angle(0.0)) - 0.5 * math.pi - self.phi
            if prev_end is None:
                self.c2_shift[k] = -_TWO_PI * math.floor(start / _TWO_PI)
            else:
                self.c2_shift[k] = _TWO_PI * round((prev_end - start) / _TWO_PI)
            prev_end = start + self.c2_shift[k] + _TWO_PI  # one full turn per closed contour
        self.poses = np.zeros((self.frame_u.size, 6))
        for k in range(len(shapes)):
            sel = self.frame_contour == k
            self.poses[sel] = self.pose_at(k, self.frame_u[sel])

    def pose_at(self, k: int, u) -> np.ndarray:
        """The poses X, Y, Z, A, C, C2 that put the profiler over arc length `u` of contour `k`."""
        sh = self.shapes[k]
        u = np.asarray(u, dtype=np.float64)
        p = sh.point(u)
        c2 = sh.tangent_angle(u) - 0.5 * math.pi - self.phi + self.c2_shift[k]
        rc2 = _rz(c2)
        off = rc2 @ self.mount[3:6] + self.c2_offset  # R_t = I
        out = np.zeros(u.shape + (6,))
        out[..., 0] = p[..., 0] - off[..., 0]
        out[..., 1] = p[..., 1] - off[..., 1]
        out[..., 2] = 0.0 - off[..., 2]
        out[..., 5] = c2
        return out

    def cnc_samples(self, axis_rate: float) -> tuple[np.ndarray, np.ndarray]:
        """The CNC's own samples of the axes at `axis_rate` Hz over the whole scan (C2 wrapped to
        [0, 2 pi) as a controller reports it), on a clock not aligned with the profiler's."""
        shapes, feed, lead_in = self.shapes, self.feed, self.lead_in
        t_end = self.t_start[-1] + (shapes[-1].length + lead_in) / feed + self.lead
        phase = 0.317e-3  # the CNC clock is not aligned with the profiler
        axis_times = phase + np.arange(math.floor((t_end - phase) * axis_rate) + 1) / axis_rate
        axis_samples = np.zeros((axis_times.size, 6))
        kt: list[float] = []
        kp: list[np.ndarray] = []
        in_pass = np.zeros(axis_times.size, dtype=bool)
        for k, sh in enumerate(shapes):
            t0 = self.t_start[k] - lead_in / feed
            t1 = self.t_start[k] + (sh.length + lead_in) / feed
            sel = (axis_times >= t0) & (axis_times <= t1)
            axis_samples[sel] = self.pose_at(k, feed * (axis_times[sel] - self.t_start[k]))
            in_pass |= sel
            kt += [t0, t1]
            kp += [self.pose_at(k, -lead_in), self.pose_at(k, sh.length + lead_in)]
        knots_t = np.array(kt)
        knots_p = np.array(kp)
        for c in range(6):  # moves between passes: straight lines (also before / after)
            axis_samples[~in_pass, c] = np.interp(axis_times[~in_pass], knots_t, knots_p[:, c])
        wrapped = axis_samples.copy()
        wrapped[:, 5] = np.mod(axis_samples[:, 5], _TWO_PI)
        return axis_times, wrapped


@dataclass(frozen=True)
class _Measurement:
    """What the profiler adds to the true heights: noise (sigma, mm), runs of dropouts (a share
    of the readings), dropouts on steep flanks (a probability) and spikes (a rate)."""

    sigma: float
    dropout: float
    flank_dropout: float
    spike_rate: float


def _cast_rays(design, shapes, profiler, rot, trans, plate_thickness, measurement, rng) -> np.ndarray:
    """Every kept frame's readings: each laser ray cast onto the bent, engraved plate (fixed-point
    iterations on the height along the beam), then the measurement's effects and the shadow of
    the plate's edge; lost readings are the profiler's sentinel."""
    x0p, y0p, x1p, y1p = PLATE
    sigma, dropout, flank_dropout, spike_rate = (
        measurement.sigma,
        measurement.dropout,
        measurement.flank_dropout,
        measurement.spike_rate,
    )
    xs = profiler.x
    n = len(xs)
    nf = len(rot)
    frames = np.empty((nf, n))
    flank_all = np.zeros((nf, n), dtype=bool)
    deflection = design.deflection
    coarse = np.unique(np.concatenate([np.arange(0, n, 16), [n - 1]]))
    half = 8
    margin = 0.1
    chunk = max(1, 400_000 // n)
    offsets_win = np.arange(-half, half + 1)
    for f0 in range(0, nf, chunk):
        f1 = min(nf, f0 + chunk)
        c = f1 - f0
        r0 = rot[f0:f1, :, 0]
        az = rot[f0:f1, :, 2]
        tr = trans[f0:f1]
        ox = tr[:, 0:1] + xs[None, :] * r0[:, 0:1]
        oy = tr[:, 1:2] + xs[None, :] * r0[:, 1:2]
        oz = tr[:, 2:3] + xs[None, :] * r0[:, 2:3]
        ax_, ay_, az_ = az[:, 0:1], az[:, 1:2], az[:, 2:3]
        # candidate readings per contour (Lipschitz argument on the exact signed distance)
        cands = []
        cxy = np.stack([ox[:, coarse], oy[:, coarse]], axis=-1)
        for k, sh in enumerate(shapes):
            sdf, _ = sh.closest(cxy - design.offsets[k])
            fl_f, fl_j = np.nonzero(np.abs(sdf) < design.band[k] + half * profiler.pitch + margin)
            if fl_f.size == 0:
                continue
            idx = coarse[fl_j][:, None] + offsets_win[None, :]
            idx = np.clip(idx, 0, n - 1)
            mask = np.zeros((c, n), dtype=bool)
            mask[np.repeat(fl_f, offsets_win.size), idx.ravel()] = True
            cands.append((k, np.nonzero(mask)))
        # fixed-point iterations: two on the smooth surface everywhere, more on the grooves
        h = np.zeros((c, n))
        for _ in range(2):
            qx = ox + h * ax_
            qy = oy + h * ay_
            on = (qx >= x0p) & (qx <= x1p) & (qy >= y0p) & (qy <= y1p)
            z = np.where(on, deflection(qx, qy), -plate_thickness)
            for k, (fi, ii) in cands:
                g, _ = _groove_height_k(design, k, qx[fi, ii], qy[fi, ii])
                z[fi, ii] += np.where(on[fi, ii], g, 0.0)
            h = (z - oz) / az_
        for k, (fi, ii) in cands:
            azk = az_[fi, 0]
            for _ in range(3):
                qx = ox[fi, ii] + h[fi, ii] * ax_[fi, 0]
                qy = oy[fi, ii] + h[fi, ii] * ay_[fi, 0]
                on = (qx >= x0p) & (qx <= x1p) & (qy >= y0p) & (qy <= y1p)
                g, fl = _groove_height_k(design, k, qx, qy)
                z = np.where(on, deflection(qx, qy) + g, -plate_thickness)
                h[fi, ii] = (z - oz[fi, ii]) / azk
            flank_all[f0 + fi, ii] = fl & on
        # shadow next to the plate edge (the step hides the laser line from the camera)
        # (checked at the top-surface level and at the hit point, so that no ray grazing the
        # plate's side face is kept; the edge itself, 0.05 mm wide, is lost too)
        shadow = np.zeros((c, n), dtype=bool)
        for hh in (0.0, h):
            qx = ox + hh * ax_
            qy = oy + hh * ay_
            dist_out = np.maximum(np.maximum(x0p - qx, qx - x1p), np.maximum(y0p - qy, qy - y1p))
            shadow |= (dist_out > -0.05) & (dist_out < 0.8)
        # measurement effects
        d = h + rng.normal(0.0, sigma, (c, n)) if sigma > 0 else h.copy()
        lost = shadow
        if dropout > 0:
            p_start = dropout / 3.0
            run_starts = np.flatnonzero(rng.random(c * n) < p_start)
            lengths = rng.geometric(1.0 / 3.0, run_starts.size)
            tot = int(lengths.sum())
            if tot:
                first = np.repeat(np.cumsum(lengths) - lengths, lengths)
                idx = np.repeat(run_starts, lengths) + (np.arange(tot) - first)
                row_end = np.repeat((run_starts // n) * n + n - 1, lengths)
                idx = np.minimum(idx, row_end)
                runs = np.zeros(c * n, dtype=bool)
                runs[idx] = True
                lost = lost | runs.reshape(c, n)
        if flank_dropout > 0:
            lost = lost | (flank_all[f0:f1] & (rng.random((c, n)) < flank_dropout))
        if spike_rate > 0:
            sp = np.flatnonzero(rng.random(c * n) < spike_rate)
            mag = rng.uniform(0.05, 0.5, sp.size) * rng.choice([-1.0, 1.0], sp.size)
            d.ravel()[sp] += mag
        lo, hi = profiler.valid_range if profiler.valid_range is not None else (-np.inf, np.inf)
        lost |= (d < lo) | (d > hi)
        d[lost] = SENTINEL if profiler.sentinel is None else profiler.sentinel
        frames[f0:f1] = d

    return frames


def _frame_truth(design, shapes, frame_contour, frame_u, rot, trans) -> dict[str, np.ndarray]:
    """The truth of every kept frame: where the laser plane crosses the engraved groove's center
    line (Newton on the contour's arc length), that center in the WCS and the SCS, and the
    groove's width, depth and the parts of its position (nominal, offset, local, bend)."""
    deflection = design.deflection
    nf = len(frame_u)
    center_u = np.zeros(nf)
    center_xy = np.zeros((nf, 2))
    for k, sh in enumerate(shapes):
        sel = np.flatnonzero(frame_contour == k)
        if sel.size == 0:
            continue
        ny = rot[sel, :, 1]  # SCS y axis in the WCS: normal of the laser plane
        tr = trans[sel]

        def plane_dist(u, k=k, ny=ny, tr=tr):
            xy = _engraved_xy(shapes[k], design.offsets[k], design.wiggle[k], u)
            zz = deflection(xy[:, 0], xy[:, 1])
            return (xy[:, 0] - tr[:, 0]) * ny[:, 0] + (xy[:, 1] - tr[:, 1]) * ny[:, 1] + (zz - tr[:, 2]) * ny[:, 2]

        u = frame_u[sel].copy()
        du = 1e-4
        for _ in range(20):
            g = plane_dist(u)
            dg = (plane_dist(u + du) - plane_dist(u - du)) / (2 * du)
            step_u = g / dg
            u = u - step_u
            if np.max(np.abs(step_u)) < 1e-12:
                break
        g = plane_dist(u)
        if np.max(np.abs(g)) > 1e-9:  # pragma: no cover - geometry guarantees convergence
            raise RuntimeError("groove_scan: groove center search did not converge")
        u = np.mod(u, sh.length)
        center_u[sel] = u
        center_xy[sel] = _engraved_xy(sh, design.offsets[k], design.wiggle[k], u)
    center_bend = deflection(center_xy[:, 0], center_xy[:, 1])
    center_wcs = np.column_stack([center_xy, center_bend])
    rel = center_wcs - trans
    center_scs = np.column_stack(
        [
            np.einsum("fi,fi->f", rot[:, :, 0], rel),
            np.einsum("fi,fi->f", rot[:, :, 2], rel),
        ]
    )
    width = np.zeros(nf)
    depth = np.zeros(nf)
    center_nominal = np.zeros((nf, 3))
    center_offset = np.zeros((nf, 3))
    center_local = np.zeros(nf)
    center_normal = np.zeros((nf, 3))
    for k, sh in enumerate(shapes):
        sel = frame_contour == k
        u = center_u[sel]
        width[sel] = design.width_profile[k](u)
        depth[sel] = design.depth_profile[k](u)
        center_nominal[sel, :2] = sh.point(u)
        center_offset[sel, :2] = design.offsets[k]
        center_local[sel] = design.wiggle[k](u)
        center_normal[sel, :2] = sh.normal(u)

    return dict(
        center_u=center_u,
        center_scs=center_scs,
        center_wcs=center_wcs,
        width=width,
        depth=depth,
        center_nominal=center_nominal,
        center_offset=center_offset,
        center_local=center_local,
        center_normal=center_normal,
        center_bend=center_bend,
    )


def groove_scan(
    seed: int = 0,
    *,
    bend: float = 0.3,
    readings: int = 3200,
    keep_every: int = 50,
    feed: float = 20.0,
    noise: float | None = None,
    dropout: float = 0.03,
    flank_dropout: float = 0.15,
    spike_rate: float = 5e-5,
    axis_rate: float = 1000.0,
    c2_offset=DEFAULT_C2_OFFSET,
    mount=DEFAULT_MOUNT,
    mount_error=None,
    contours: Sequence[ContourShape] | None = None,
    plate_thickness: float = 2.0,
) -> tuple[Scan, GrooveTruth]:
    """Synthetic on-machine scan of engraved chemical-milling grooves, with exact truth.

    Reproduces paper 000 §3: an 11-contour template on a 200 mm x 200 mm plate, scanned
    contour by contour with an SR7140-like profiler on an AC head with a sixth axis C2. See
    the module docstring for the model and where its numbers come from.

    Parameters
    ----------
    seed : int
        Seed (``np.random.SeedSequence(seed)``, one stream for the part, one for the
        measurement). The part (offsets, wiggles, widths, depths, lips, bending shape) depends
        only on ``seed``, ``bend`` and ``contours``; the measurement noise also on the scan
        parameters. Same arguments, same arrays, bit for bit.
    bend : float
        Peak ``|deflection|`` of the clamped plate over the plate, mm (paper 000 §3 fig. 12:
        a few tenths of a mm). 0 gives a flat plate.
    readings : int
        Readings per frame (3200 for the full 80 mm line; fewer crops the line about its
        center, for small test scans). The pitch stays 0.025 mm.
    keep_every : int
        Keep every k-th profiler frame. The profiler runs at 2500 frames/s, i.e. a frame
        every ``feed / 2500`` mm (8 um at the default feed); the default 50 keeps one frame
        every 0.4 mm, about 3800 frames. Timestamps are the real ones.
    feed : float
        Scanning feed along the contours, mm/s (default 20 mm/s = 1200 mm/min, assumption).
    noise : float, optional
        Sigma of the Gaussian height noise, mm; default the profiler's 0.008 mm.
    dropout : float
        Share of readings lost in short runs (mean length 3) anywhere, 0-1.
    flank_dropout : float
        Extra probability of losing a reading on a steep groove flank.
    spike_rate : float
        Probability of a spike (an outlier of 0.05-0.5 mm either way) per reading.
    axis_rate : float
        Sampling rate of the raw CNC axis positions, Hz (default 1 kHz); the samples cover the
        whole scan, including the moves between contours, on their own time grid.
    c2_offset : (3,) mm
        ``(Lx, Ly, Lz)``; see :data:`DEFAULT_C2_OFFSET`.
    mount : (6,) rad, mm
        The calibrated mount ``(theta, psi, phi, dx, dy, dz)``, stored in the scan and used to
        plan the poses; see :data:`DEFAULT_MOUNT`.
    mount_error : (6,), optional
        Calibration error: the readings are cast with ``mount + mount_error``
        (``truth.mount_true``). Default none.
    contours : sequence of ContourShape, optional
        The CAD contours; default :func:`default_contours`.
    plate_thickness : float
        mm; the machine table beside the plate is at ``z = -plate_thickness``.

    Returns
    -------
    scan : Scan
        Frames (sentinel for lost readings), poses at the frame times, frame times, the
        SR7140-like profiler, ``c2_offset``, the calibrated ``mount``, raw axis samples (C2
        wrapped to ``[0, 2 pi)`` like a modulo rotary axis), and metadata.
    truth : GrooveTruth

    Notes
    -----
    Poses follow the closed form ``P_t = p - R_t (R_C2 (dx, dy, dz) + (Lx, Ly, Lz))`` with
    ``R_t = I`` (A = C = 0), ``p`` the nominal contour point on ``z = 0``, and
    ``C2 = alpha - pi/2 - phi`` where ``alpha`` is the tangent direction, so the laser line
    (SCS +x) points along the outward normal of the CAD contour. Each reading is found by
    ray casting: ``h`` with ``T (x_i, 0, h)`` on the true surface, by fixed-point iteration
    (surface slope times mount tilt is tiny, so it converges to better than 1e-9 mm).

    Each contour is one pass, counter-clockwise from arc length 0 (see :class:`ContourShape`),
    with a 2 mm lead-in and run-out at feed (no frames there) and 2 s straight moves between
    passes. Readings beside the plate see the machine table; those within 0.8 mm of the plate
    edge are lost (the step shadows the laser line).

    Examples
    --------
    >>> scan, truth = groove_scan(seed=1, readings=400, keep_every=400)
    >>> scan.frames.shape[1], truth.n_contours
    (400, 11)
    """
    if keep_every < 1 or int(keep_every) != keep_every:
        raise ValueError(f"keep_every: expected a positive integer, got {keep_every!r}")
    keep_every = int(keep_every)
    if not (bend >= 0.0 and math.isfinite(bend)):
        raise ValueError(f"bend: expected a non-negative peak deflection in mm, got {bend!r}")
    if feed <= 0.0:
        raise ValueError(f"feed: expected a positive speed in mm/s, got {feed!r}")
    for name, v in (("dropout", dropout), ("flank_dropout", flank_dropout), ("spike_rate", spike_rate)):
        if not 0.0 <= v < 1.0:
            raise ValueError(f"{name}: expected a probability in [0, 1), got {v!r}")
    profiler = Profiler.sr7140(readings=readings)
    sigma = float(profiler.noise or 0.0) if noise is None else float(noise)
    if not (sigma >= 0.0 and math.isfinite(sigma)):
        raise ValueError(f"noise: expected a non-negative sigma in mm, got {noise!r}")
    c2_offset = np.asarray(c2_offset, dtype=np.float64).reshape(3)
    mount = np.asarray(mount, dtype=np.float64).reshape(6)
    mount_true = mount + (0.0 if mount_error is None else np.asarray(mount_error, dtype=np.float64).reshape(6))
    shapes = default_contours() if contours is None else tuple(contours)
    x0p, y0p, x1p, y1p = PLATE
    for k, sh in enumerate(shapes):
        pl = sh.polyline(0.5)
        if pl[:, 0].min() < x0p + 1 or pl[:, 0].max() > x1p - 1 or pl[:, 1].min() < y0p + 1 or pl[:, 1].max() > y1p - 1:
            raise ValueError(f"contours: contour {k} does not lie on the plate {PLATE}")

    seeds = np.random.SeedSequence(seed).spawn(2)
    design = _make_design(np.random.default_rng(seeds[0]), shapes, float(bend))
    rng = np.random.default_rng(seeds[1])
    rate = 2500.0 if profiler.frame_rate is None else profiler.frame_rate
    path = _ScanPath(shapes, feed, rate, keep_every, c2_offset, mount)
    axis_times, axis_samples_wrapped = path.cnc_samples(axis_rate)
    rot, trans = _transforms_a0c0(path.poses, c2_offset, mount_true)
    noise_model = _Measurement(sigma, dropout, flank_dropout, spike_rate)
    frames = _cast_rays(design, shapes, profiler, rot, trans, plate_thickness, noise_model, rng)
    frame_contour, frame_u, poses, frame_times = path.frame_contour, path.frame_u, path.poses, path.frame_times
    center = _frame_truth(design, shapes, frame_contour, frame_u, rot, trans)
    deflection = design.deflection

    nominal_polylines = []
    engraved_polylines = []
    for k, sh in enumerate(shapes):
        m = max(math.ceil(sh.length / 0.05), 8)
        u = np.arange(m) * (sh.length / m)
        nominal_polylines.append(np.column_stack([sh.point(u), np.zeros(m)]))
        xy = _engraved_xy(sh, design.offsets[k], design.wiggle[k], u)
        engraved_polylines.append(np.column_stack([xy, deflection(xy[:, 0], xy[:, 1])]))

    params = {
        "generator": "machscan.synth.groove_scan",
        "seed": int(seed),
        "bend": float(bend),
        "readings": int(readings),
        "keep_every": keep_every,
        "feed": float(feed),
        "noise": float(sigma),
        "dropout": float(dropout),
        "flank_dropout": float(flank_dropout),
        "spike_rate": float(spike_rate),
        "axis_rate": float(axis_rate),
        "plate": list(PLATE),
        "plate_thickness": float(plate_thickness),
        "contours": [sh.describe() for sh in shapes],
    }
    scan = Scan(
        frames=frames,
        poses=poses,
        frame_times=frame_times,
        profiler=profiler,
        c2_offset=c2_offset,
        mount=mount,
        axis_times=axis_times,
        axis_samples=axis_samples_wrapped,
        metadata=params,
    )
    truth = GrooveTruth(
        frame_contour=frame_contour,
        frame_u=frame_u,
        **center,
        contours=shapes,
        nominal_polylines=tuple(nominal_polylines),
        engraved_polylines=tuple(engraved_polylines),
        offsets=design.offsets,
        wiggle=design.wiggle,
        width_profile=design.width_profile,
        depth_profile=design.depth_profile,
        lip_profile=design.lip_profile,
        lip_asymmetry=design.lip_asymmetry,
        deflection=deflection,
        plate=PLATE,
        plate_thickness=float(plate_thickness),
        mount_true=mount_true,
        params=params,
    )
    return scan, truth


@dataclass(frozen=True)
class SurfaceError:
    """Heights of workpiece points against the true (bent) plate surface, away from the grooves.

    Attributes
    ----------
    n : int
        Number of points compared.
    mean, rms, max_abs : float
        Of ``e = z - w(x, y)`` (mm), spikes included.
    robust_sigma : float
        ``1.4826 * median(|e - median(e)|)`` (mm): the noise level, unaffected by spikes.
    n_outliers : int
        Points with ``|e| > outlier_threshold``.
    outlier_threshold : float
        mm (5 x the profiler noise by default).
    """

    n: int
    mean: float
    rms: float
    max_abs: float
    robust_sigma: float
    n_outliers: int
    outlier_threshold: float

    def __repr__(self) -> str:
        return (
            f"SurfaceError(n={self.n:,}, mean={self.mean * 1e3:.2f} um, "
            f"rms={self.rms * 1e3:.2f} um, robust sigma={self.robust_sigma * 1e3:.2f} um, "
            f"max |e|={self.max_abs * 1e3:.1f} um, {self.n_outliers} outliers "
            f"> {self.outlier_threshold * 1e3:.0f} um)"
        )


def surface_error(
    points,
    frame_index,
    truth: GrooveTruth,
    *,
    clearance: float = 1.0,
    edge_margin: float = 1.0,
    outlier_threshold: float | None = None,
) -> SurfaceError:
    """Compare workpiece points with the true bent surface, away from grooves and plate edges.

    A round-trip check of the kinematics on a synthetic scan: the points of the readings that
    hit the plain maskant should lie on ``truth.deflection`` within the profiler noise.

    Parameters
    ----------
    points : array_like, shape (M, 3)
        WCS points (mm), e.g. from ``scan.wcs_points()``.
    frame_index : array_like, shape (M,) or None
        Frame of every point (accepted for symmetry with ``wcs_points``; not needed).
    truth : GrooveTruth
    clearance : float
        Points closer than this to a CAD contour (plus its offset and wiggle bound), mm, are
        left out.
    edge_margin : float
        Points closer than this to the plate edge, or off the plate, are left out (mm).
    outlier_threshold : float, optional
        mm; default 5 x the generator's noise (or 0.04 mm for a noise-free scan).

    Returns
    -------
    SurfaceError
    """
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points: expected shape (M, 3), got {p.shape}")
    if frame_index is not None and np.shape(frame_index) != (p.shape[0],):
        raise ValueError(f"frame_index: expected shape ({p.shape[0]},), got {np.shape(frame_index)}")
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    x0, y0, x1, y1 = truth.plate
    keep = np.flatnonzero((x > x0 + edge_margin) & (x < x1 - edge_margin) & (y > y0 + edge_margin) & (y < y1 - edge_margin))
    # A 0.5 mm grid over the plate says which contour, if any, may be within reach of a cell;
    # the exact signed distance is then evaluated only for the points of those cells.
    cell = 0.5
    nx = math.ceil((x1 - x0) / cell)
    ny = math.ceil((y1 - y0) / cell)
    gx, gy = np.meshgrid(x0 + (np.arange(nx) + 0.5) * cell, y0 + (np.arange(ny) + 0.5) * cell, indexing="ij")
    owner = np.full((nx, ny), -1, dtype=np.int64)
    reach = np.zeros(len(truth.contours))
    for k, shape in enumerate(truth.contours):
        reach[k] = clearance + float(np.hypot(*truth.offsets[k])) + truth.wiggle[k].bound
        g = shape.signed_distance(np.stack([gx - truth.offsets[k, 0], gy - truth.offsets[k, 1]], axis=-1))
        owner[np.abs(g) < reach[k] + cell] = k  # cell half-diagonal < cell
    xk, yk = x[keep], y[keep]
    ix = np.clip(((xk - x0) * (1.0 / cell)).astype(np.int64), 0, nx - 1)
    iy = np.clip(((yk - y0) * (1.0 / cell)).astype(np.int64), 0, ny - 1)
    own = owner[ix, iy]
    away = np.ones(keep.size, dtype=bool)
    for k, shape in enumerate(truth.contours):
        sel = np.flatnonzero(own == k)
        if sel.size:
            sdf = shape.signed_distance(np.column_stack([xk[sel] - truth.offsets[k, 0], yk[sel] - truth.offsets[k, 1]]))
            away[sel[np.abs(sdf) < reach[k]]] = False
    keep = keep[away]
    e = z[keep] - truth.deflection(x[keep], y[keep])
    if outlier_threshold is None:
        sigma = float(truth.params.get("noise", 0.0))
        outlier_threshold = 5.0 * sigma if sigma > 0 else 0.04
    if e.size == 0:
        nan = float("nan")
        return SurfaceError(0, nan, nan, nan, nan, 0, float(outlier_threshold))
    med = float(np.median(e))
    return SurfaceError(
        n=int(e.size),
        mean=float(e.mean()),
        rms=float(np.sqrt(np.mean(e * e))),
        max_abs=float(np.abs(e).max()),
        robust_sigma=float(1.4826 * np.median(np.abs(e - med))),
        n_outliers=int(np.count_nonzero(np.abs(e) > outlier_threshold)),
        outlier_threshold=float(outlier_threshold),
    )


def flat_plate_scan(seed: int = 0, *, readings: int = 400, keep_every: int = 400, **kwargs) -> tuple[Scan, GrooveTruth]:
    """A small, quick :func:`groove_scan` of the unbent plate (about 360 frames of 400 readings).

    Keyword arguments are passed on to :func:`groove_scan` (``bend`` defaults to 0).
    """
    kwargs.setdefault("bend", 0.0)
    return groove_scan(seed, readings=readings, keep_every=keep_every, **kwargs)
