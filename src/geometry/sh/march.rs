//! Ray intersection with an SH surface by a Lipschitz-certified march
//! (sphere tracing with first- and second-order safe steps), then
//! safeguarded Newton/bisection on the bracket. Uses the bounds `G`, `H`,
//! `r_min`, `r_max` of `bounds.rs`.
//!
//! Along a ray `p(t) = p0 + t d` (relative to the centre, unit `d`, world
//! units) let `rho = |p|`, `b = |p0 x d|` its distance from the centre and
//! `psi` the angle of `p` in the plane of the ray and the centre. With
//! `tau = p . d` (so `rho^2 = b^2 + tau^2`): `rho' = tau / rho`,
//! `rho'' = b^2 / rho^3 <= 1 / rho`, `psi' = b / rho^2 <= 1 / rho` and
//! `|psi''| = 2 b |tau| / rho^4 <= 1 / rho^2` (as `2 b |tau| <= rho^2`). Along
//! the ray `U(p/rho) = g(psi)` with `g` the restriction of `U` to that great
//! circle (`|g'| <= G`, `|g''| <= H`), so the level
//! `f(t) = rho - scale U(p/rho)` obeys
//!
//! ```text
//! |f'|  <= L(rho) = 1 + scale G / rho
//! |f''| <= M(rho) = 1 / rho + scale (H + G) / rho^2.
//! ```
//!
//! Sphere tracing uses both on `[t, t + h]` with a lower bound `rho_lo` of
//! `rho` there: no zero lies in `[t, t + h)` when `h < |f| / L(rho_lo)`, nor
//! when `h < h2`, the positive root of `|f| + sign(f) f' h - M h^2 / 2`.
//! The march takes the larger of the two (the second one converges
//! quadratically near a transversal hit and takes long strides along
//! grazing rays). Valid `rho_lo`:
//!
//! - outside the surface (`f > 0`), up to the first zero `f > 0` means
//!   `rho > scale U >= r_min`; also `rho >= b`, and `rho >= rho(t)` when the
//!   ray moves away from the centre; for the first-order step alone,
//!   `h <= f` keeps `rho >= rho(t) - h >= scale U(t)`;
//! - inside (`f < 0`) the ray may pass close to the centre: the step is
//!   capped at `rho(t) / 2` (so `rho >= rho(t) / 2`) unless `b` or outward
//!   motion already bounds `rho`. Inside the inner ball (`rho < r_min`)
//!   `f < 0` for sure, and the march jumps to its exit. A ray from outside
//!   never reaches the inner ball before a hit.
//!
//! The march is first clipped to the outer ball (`rho <= r_max`; beyond it
//! `f > 0`). A floor step `FLOOR_REL r_max` (`1e-9` of the radius) keeps
//! grazing near-misses finite: when the safe step is smaller, the floor step
//! is taken and a sign change checked. This is the only place where a
//! crossing can be lost: a ray that dips into the solid along a chord
//! shorter than `1e-9 r_max` (a tangency within about `1e-18 r_max`) may be
//! reported as a miss. A sign change gives a bracket, refined by safeguarded
//! Newton/bisection to `1e-12` relative in `t`. All tolerances are relative to
//! `r_max` (and to `|t|`, `|center|` where rounding of positions scales with
//! them), so a scaled object behaves the same up to scale.
//!
//! Rays starting on the surface (`|f| <= 1e-12 r_max`, plus a few ulps of
//! `|center|`) take their side from the direction of travel (`f'`) and
//! leave with half the second-order step, so they do not report a hit at
//! their own start; a segment whose end lies on the surface (same band)
//! ends one floor step early, so its end is no crossing. Both make shadow
//! rays between surface points work. A ray *tangent* to the surface at its
//! start or end may still report a crossing there or not (the level is zero
//! to rounding on both sides).
//!
//! ## Termination (no step cap)
//!
//! The march has no cap on its steps, so it never reports a miss for a ray
//! that crosses (a cap did until it was removed: rays aimed at a dimple that
//! comes close to the centre needed more evaluations and were lost). It
//! still ends: every step is at least the floor step `floor = FLOOR_REL r_max`
//! and `t + h` rounds to at least `t + floor / 2` when an ulp of `t` is
//! below `floor`; otherwise the next double after `t` is taken, which is
//! further than `floor`. The clipped segment is at most `2 r_out` long, so
//! a march takes at most `4 (1 + CLIP_REL) / FLOOR_REL + 3` (about `4e9`)
//! level evaluations. Real rays take tens to thousands.
//!
//! Long marches come from loose bounds: outside and moving inwards the
//! bound `rho >= max(r_min, b)` holds over any step, and when the surface
//! nearly touches the centre (`r_min` tiny) it makes `M` huge and the steps
//! tiny all the way in. After `STEP_BUDGET` evaluations the march also tries
//! the step certified on `[t, t + rho(t) / 2]`, where `rho >= rho(t) / 2`,
//! and takes the longer of the two certified steps (before the budget it
//! keeps the first rule alone, so that existing results stay bit for bit).
//!
//! Cost: each level evaluation (value and gradient) is `O(L^2)`, the
//! recurrences of two orders interleaved; a ray needs about 20 (degree 8)
//! to 50 (degree 30) evaluations, march and refinement together.

use super::ShSurface;
use glam::DVec3;

/// Floor step of the march, relative to the outer radius: the smallest
/// feature a grazing ray can miss.
const FLOOR_REL: f64 = 1e-9;

/// Points with `|f| <= ON_SURFACE_REL r_max` count as on the surface.
const ON_SURFACE_REL: f64 = 1e-12;

/// The outer ball used for clipping is inflated and the inner ball deflated
/// by this relative amount, so that their surfaces lie strictly outside /
/// inside the SH surface despite rounding (a sphere has `r_min = r_max`).
const CLIP_REL: f64 = 1e-8;

/// Origins further than this many outer radii from the centre are moved
/// along the ray before the march (see `ShSurface::rebase`).
const REBASE_REL: f64 = 1e6;

/// Relative tolerance in `t` of the bracket refinement.
const REFINE_REL: f64 = 1e-12;

/// Level evaluations after which the march also tries the wider outside
/// step (see the module docs, "Termination"). It is a switch, not a cap:
/// the march goes on until it finds a bracket or reaches the end.
pub(super) const STEP_BUDGET: usize = 100_000;

/// Cap on refinement iterations (Newton converges in a few; bisection of a
/// floor-step bracket to `1e-12` needs about 12).
const MAX_REFINE: usize = 200;

/// Level, its derivative along the ray and the world gradient at one point.
#[derive(Clone, Copy, Debug)]
pub(super) struct Probe {
    /// `|x - c|` \[m\].
    pub(super) rho: f64,
    /// `f = rho - scale U` \[m\].
    pub(super) f: f64,
    /// `df/dt = grad f . d` \[1\].
    pub(super) fp: f64,
    /// `scale U` \[m\].
    pub(super) su: f64,
    /// `grad f` (world) \[1\].
    pub(super) grad: DVec3,
}

/// Result of a march: a miss, or a bracket `[ta, tb]` with `side f(ta) > 0 >= side f(tb)`.
#[derive(Clone, Copy, Debug)]
enum March {
    Miss,
    Bracket {
        ta: f64,
        tb: f64,
        side: f64,
        pa: Probe,
        pb: Probe,
    },
}

impl ShSurface {
    /// Level and gradient at `p = x - center` (world); `d` the ray direction.
    #[inline]
    pub(super) fn probe(&self, p: DVec3, d: DVec3) -> Probe {
        let rho = p.length();
        if rho == 0.0 || rho.is_nan() {
            // At the centre: any direction gives f < 0; moving away, rho' = 1.
            let su = self.scale * self.eval(DVec3::Z).0;
            return Probe {
                rho,
                f: rho - su,
                fp: 1.0,
                su,
                grad: d,
            };
        }
        let (u, gs, yl) = self.eval(self.rot_t * (p / rho));
        let su = self.scale * u;
        let grad = self.rot * (yl - gs * (self.scale / rho));
        Probe {
            rho,
            f: rho - su,
            fp: grad.dot(d),
            su,
            grad,
        }
    }

    /// Half-width of the "on the surface" band of the level \[m\].
    fn band(&self) -> f64 {
        ON_SURFACE_REL * self.scale * self.r_max
            + 64.0 * f64::EPSILON * self.center.abs().max_element()
    }

    /// Sphere-trace the open segment; returns the first bracket (see module docs).
    fn march(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> (March, usize) {
        if !(o.is_finite() && d.is_finite()) || t_min.is_nan() || t_max.is_nan() || t_max <= t_min {
            return (March::Miss, 0);
        }
        debug_assert!(
            (d.length() - 1.0).abs() < 1e-6,
            "ray direction must be unit"
        );
        let (rmin, rmax) = self.bounds();
        let p0 = o - self.center;
        let tc = -p0.dot(d);
        let b = p0.cross(d).length();
        let r_out = rmax * (1.0 + CLIP_REL);
        if b >= r_out {
            return (March::Miss, 0);
        }
        let half = ((r_out - b) * (r_out + b)).sqrt();
        let (t_in, t_out) = (tc - half, tc + half);
        let at_origin = t_min >= t_in;
        let mut t = if at_origin { t_min } else { t_in };
        if t >= t_max.min(t_out) {
            return (March::Miss, 0);
        }
        let band = self.band();
        let floor = FLOOR_REL * rmax;
        let mut steps = 0;
        let t_end = if t_max < t_out {
            steps += 1;
            if self.probe(p0 + t_max * d, d).f.abs() <= band {
                // The segment ends on the surface: its own end is no crossing.
                t_max - floor
            } else {
                t_max
            }
        } else {
            t_out
        };
        if t >= t_end {
            return (March::Miss, steps);
        }
        let r_skip = rmin * (1.0 - CLIP_REL);
        let sg = self.scale * self.g_bound;
        let sgh = self.scale * (self.g_bound + self.h_bound);

        let mut pr = self.probe(p0 + t * d, d);
        steps += 1;
        if pr.f.is_nan() {
            return (March::Miss, steps);
        }
        let mut on_start = at_origin && pr.f.abs() <= band;
        let side = if on_start {
            if pr.fp < 0.0 { -1.0 } else { 1.0 }
        } else if pr.f > 0.0 {
            1.0
        } else {
            -1.0
        };
        loop {
            if side < 0.0 && pr.rho < r_skip {
                // Inside the inner ball f < 0: jump to its exit.
                let t_exit = tc + ((r_skip - b) * (r_skip + b)).max(0.0).sqrt();
                if t_exit >= t_end {
                    return (March::Miss, steps);
                }
                if t_exit > t {
                    let (prev, pprev) = (t, pr);
                    t = t_exit;
                    pr = self.probe(p0 + t * d, d);
                    steps += 1;
                    if side * pr.f <= 0.0 {
                        let m = March::Bracket {
                            ta: prev,
                            tb: t,
                            side,
                            pa: pprev,
                            pb: pr,
                        };
                        return (m, steps);
                    }
                }
                on_start = false;
            }
            let over_budget = steps >= STEP_BUDGET;
            let g = (side * pr.f).max(0.0);
            let gp = side * pr.fp;
            let outward = (p0 + t * d).dot(d) >= 0.0;
            let (rho_lo, cap) = if side > 0.0 {
                let r = rmin.max(b);
                (if outward { r.max(pr.rho) } else { r }, f64::INFINITY)
            } else if outward {
                (pr.rho.max(b), f64::INFINITY)
            } else if b >= 0.5 * pr.rho {
                (b, f64::INFINITY)
            } else {
                (0.5 * pr.rho, 0.5 * pr.rho)
            };
            // The certified step on `[t, t + h]` given a lower bound `rho_lo`
            // of `rho` there, valid for `h <= cap`.
            let safe_step = |rho_lo: f64, cap: f64| {
                let lip = if side > 0.0 {
                    // h <= f keeps rho >= rho(t) - h >= scale U(t).
                    1.0 + sg / rho_lo.max(pr.su)
                } else {
                    1.0 + sg / rho_lo
                };
                let h1 = g / lip;
                let m2 = 1.0 / rho_lo + sgh / (rho_lo * rho_lo);
                let disc = (gp * gp + 2.0 * m2 * g).sqrt();
                let h2 = if gp >= 0.0 {
                    (gp + disc) / m2
                } else {
                    2.0 * g / (disc - gp)
                };
                if on_start {
                    // Leaving the surface: half the root keeps f clearly off zero.
                    0.5 * h2
                } else {
                    h1.max(h2)
                }
                .min(cap)
            };
            let mut h = safe_step(rho_lo, cap);
            if over_budget && side > 0.0 && !outward {
                // Outside and moving inwards: with h <= rho(t) / 2 also
                // rho >= rho(t) / 2, a far better bound than r_min or b when
                // the surface comes close to the centre.
                let wide = safe_step(rmin.max(b).max(0.5 * pr.rho), 0.5 * pr.rho);
                h = h.max(wide);
            }
            on_start = false;
            if h.is_nan() || h < floor {
                h = floor;
            }
            // Rounding of `t + h` when |t| is huge: still advance.
            let tn = if t + h > t { t + h } else { next_up(t) };
            let (tn, last) = if tn >= t_end {
                (t_end, true)
            } else {
                (tn, false)
            };
            let pn = self.probe(p0 + tn * d, d);
            steps += 1;
            if pn.f.is_nan() {
                return (March::Miss, steps);
            }
            if side * pn.f <= 0.0 {
                let m = March::Bracket {
                    ta: t,
                    tb: tn,
                    side,
                    pa: pr,
                    pb: pn,
                };
                return (m, steps);
            }
            if last {
                return (March::Miss, steps);
            }
            t = tn;
            pr = pn;
        }
    }

    /// Safeguarded Newton/bisection on a bracket (`side f(ta) > 0 >= side f(tb)`).
    ///
    /// Newton steps are taken from the best point while they stay inside the
    /// bracket and at least halve the previous step, otherwise the bracket is
    /// bisected. Stops after a Newton step shorter than `1e-12` relative
    /// (the error is then about its square) or when the bracket is a few ulps wide.
    fn refine(
        &self,
        p0: DVec3,
        d: DVec3,
        (ta, pa): (f64, Probe),
        (tb, pb): (f64, Probe),
        side: f64,
    ) -> (f64, Probe, usize) {
        let tol = REFINE_REL * (self.scale * self.r_max).max(tb.abs());
        let (mut lo, mut hi) = (ta, tb);
        // Start from the end nearer the root, but never from a start on the surface.
        let (mut t, mut pr) = if pa.f.abs() < pb.f.abs() && pa.f.abs() > self.band() {
            (ta, pa)
        } else {
            (tb, pb)
        };
        let mut dx_old = f64::INFINITY;
        let mut evals = 0;
        for _ in 0..MAX_REFINE {
            if pr.f == 0.0 {
                break;
            }
            let newton = t - pr.f / pr.fp;
            let dx_newton = newton - t;
            let use_newton = newton > lo && newton < hi && 2.0 * dx_newton.abs() <= dx_old.abs();
            let tn = if use_newton { newton } else { 0.5 * (lo + hi) };
            if tn == t {
                break;
            }
            dx_old = tn - t;
            t = tn;
            pr = self.probe(p0 + t * d, d);
            evals += 1;
            if side * pr.f > 0.0 {
                lo = t;
            } else {
                hi = t;
            }
            if (use_newton && dx_old.abs() <= tol)
                || hi - lo <= 4.0 * f64::EPSILON * hi.abs().max(lo.abs())
            {
                break;
            }
        }
        (t, pr, evals)
    }

    /// Shift `t0` of the ray's origin for the march: `0` unless the origin
    /// lies more than `REBASE_REL r_max` from the centre and before the
    /// segment's start, and then the `t` two outer radii before the closest
    /// approach. Positions `o + t d` with `|t|` that large carry rounding
    /// errors (about `|t| 1e-16`) beyond the clip margin `CLIP_REL r_max`,
    /// so that the first probe could even find itself inside; from the
    /// shifted origin they are exact to the scale of the object. The shifted
    /// ray is the same line to the rounding of `o + t0 d`; an unshifted ray
    /// (`t0 = 0`) is marched exactly as before.
    fn rebase(&self, o: DVec3, d: DVec3, t_min: f64) -> f64 {
        let p0 = o - self.center;
        let r_max = self.scale * self.r_max;
        let t0 = -p0.dot(d) - 2.0 * r_max;
        if p0.length() > REBASE_REL * r_max && t0 > t_min {
            t0
        } else {
            0.0
        }
    }

    /// First crossing of the surface by the ray `o + t d` (unit `d`) with
    /// `t` in the open interval `(t_min, t_max)`: `(t [m], outward unit
    /// normal)`. Entering from outside or leaving from inside both count.
    ///
    /// Never misses a crossing except along chords shorter than `1e-9`
    /// of the outer radius (see the module docs); `t` is accurate to about
    /// `1e-12` relative. A ray starting on the surface does not hit it at
    /// its start.
    pub fn first_hit(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<(f64, DVec3)> {
        self.first_hit_counted(o, d, t_min, t_max).0
    }

    /// [`first_hit`](Self::first_hit) and the number of level evaluations
    /// used (march and refinement).
    pub(super) fn first_hit_counted(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> (Option<(f64, DVec3)>, usize) {
        let t0 = self.rebase(o, d, t_min);
        let (o, t_min, t_max) = (o + t0 * d, t_min - t0, t_max - t0);
        match self.march(o, d, t_min, t_max) {
            (March::Miss, n) => (None, n),
            (
                March::Bracket {
                    ta,
                    tb,
                    side,
                    pa,
                    pb,
                },
                n,
            ) => {
                let (t, pr, nr) = self.refine(o - self.center, d, (ta, pa), (tb, pb), side);
                let hit = (t > t_min && t < t_max).then(|| (t0 + t, pr.grad.normalize()));
                (hit, n + nr)
            }
        }
    }

    /// Whether the open segment `o + t d`, `t` in `(t_min, t_max)` (unit
    /// `d`), crosses the surface (shadow rays). Stops at the first bracket
    /// found, without refining it. Endpoints on the surface do not count.
    pub fn crosses(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> bool {
        let t0 = self.rebase(o, d, t_min);
        let (o, t_min, t_max) = (o + t0 * d, t_min - t0, t_max - t0);
        matches!(self.march(o, d, t_min, t_max).0, March::Bracket { .. })
    }
}

/// The next double above a finite `t` (`f64::next_up`, stable only since Rust 1.86).
fn next_up(t: f64) -> f64 {
    if t == 0.0 {
        f64::from_bits(1)
    } else if t > 0.0 {
        f64::from_bits(t.to_bits() + 1)
    } else {
        f64::from_bits(t.to_bits() - 1)
    }
}
