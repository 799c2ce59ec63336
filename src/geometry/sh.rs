//! Star-shaped surfaces given by real spherical-harmonic (SH) expansions.
//!
//! ## The surface
//!
//! In the object's local frame the surface is the set of points at distance
//! `U(theta, phi)` from the origin in the direction `(theta, phi)`:
//!
//! ```text
//! U(theta, phi) = sum_{k=0..L} sum_{m=0..k} P_k^m(cos theta) (a_km cos m phi + b_km sin m phi)
//! ```
//!
//! `theta` is the polar angle from local `+z`, `phi` the azimuth from local
//! `+x` towards `+y`. `P_k^m` are the Schmidt semi-normalised associated
//! Legendre functions without the Condon-Shortley phase:
//! `P_k^m = sqrt((2 - delta_m0) (k - m)! / (k + m)!) (1 - x^2)^(m/2) d^m P_k / dx^m`,
//! so `P_k^0 = P_k`, `sum_m P_k^m(x)^2 = 1` and `|P_k^m| <= 1`. The world
//! placement is `x_world = center + scale R x_local` (`R` a proper rotation,
//! `scale > 0`); coefficients are in local units, world radii are `scale U`.
//! `U > 0` everywhere is required (checked by [`ShSurface::new`]): the
//! surface is then star-shaped about `center` (every ray from the centre
//! crosses it exactly once) and it bounds a solid.
//!
//! ## Evaluation
//!
//! Write `P_k^m(x) = s^m T_k^m(x)` with `s = sin theta` and `T_k^m` a
//! polynomial of degree `k - m` in `x = cos theta`:
//!
//! ```text
//! T_0^0 = T_1^1 = 1,  T_m^m = sqrt((2m - 1) / (2m)) T_{m-1}^{m-1}          (m >= 2)
//! T_k^m = [(2k - 1) x T_{k-1}^m - sqrt((k-1)^2 - m^2) T_{k-2}^m] / sqrt(k^2 - m^2)   (k > m)
//! ```
//!
//! and `T'` by differentiating the same recurrence. Then
//! `dP_k^m/dtheta = s^(m-1) (m x T - s^2 T')` (for `m = 0`: `-s T'`) and
//! `(1/s) dP_k^m cos(m phi)/dphi = -m s^(m-1) T sin(m phi)`: the surface
//! gradient `grad_S U = U_theta theta_hat + (1/s) U_phi phi_hat` is
//! evaluated without dividing by `sin theta`, so it is exact at the poles
//! (there only `m = 1` contributes and the result does not depend on the
//! arbitrary `phi` chosen there). For `F(x) = rho - U(x/rho)`,
//! `grad F = r_hat - grad_S U / rho`, which gives the outward normal.
//!
//! ## Bounds (the intersection never misses the first hit)
//!
//! Let `Y_k` be the degree-`k` part of `U` and `S_k = sum_m sqrt(a_km^2 + b_km^2)`
//! (`|a_k0|` for `m = 0`). Since `|P_k^m| <= 1` and
//! `|a cos + b sin| <= sqrt(a^2 + b^2)`, `|Y_k| <= S_k`, so
//! `|U - a_00| <= S = sum_{k>=1} S_k`: the surface lies between the spheres
//! of radii `a_00 - S` and `a_00 + S`. When `a_00 - S <= 0` this bound proves
//! nothing, and a grid over the sphere decides (below); the grid also
//! tightens both radii.
//!
//! Bernstein's inequality for spherical polynomials: the restriction of
//! `Y_k` to any great circle, as a function of the arc angle `psi`, is a
//! trigonometric polynomial of degree `<= k` bounded by `S_k`, so (by the
//! trigonometric Bernstein inequality) `|dY_k/dpsi| <= k S_k` and
//! `|d^2 Y_k/dpsi^2| <= k^2 S_k`. Every tangent direction lies on a great
//! circle, hence
//!
//! ```text
//! |grad_S U| <= G = sum_k k S_k,      |d^2 U/dpsi^2| <= H = sum_k k^2 S_k   (local units).
//! ```
//!
//! Grid check: with nodes `theta_i = i pi / n`, `phi_j = 2 pi j / (2n)`,
//! any direction is joined to a node `q` by a path of length
//! `delta <= (pi/n + pi/n) / 2` (along a meridian, then along a parallel),
//! and so by a great-circle arc no longer than `delta`. Along that arc
//! `|U - U(q)| <= G delta` and `|U - U(q)| <= |grad_S U(q)| delta + H delta^2 / 2`
//! (Taylor with the bound `H` on the second derivative), so
//! `min U >= min_q [U(q) - min(G delta, |grad_S U(q)| delta + H delta^2 / 2)]`
//! and likewise for `max U`. The second form makes the bounds tight to
//! `O(delta^2)` near the extremes (where the gradient vanishes). A node with
//! `U <= 0` proves the expansion is not star-shaped; a positive lower bound
//! proves it is; in between the grid is refined (up to [`MAX_GRID`] polar
//! rows) before giving up with [`ShError::Unverified`]. The same grid gives
//! `r_min`, `r_max` (never looser than `a_00 -/+ S`).
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
//! Cost: each level evaluation (value and gradient) is `O(L^2)`, the
//! recurrences of two orders interleaved; a ray needs about 20 (degree 8)
//! to 50 (degree 30) evaluations, march and refinement together.

use crate::io::csvio::{self, InputError};
use glam::{DMat3, DVec3};
use std::f64::consts::PI;
use std::path::Path;

/// Highest supported degree `L`.
///
/// Why: the recurrences are stable far beyond this, but the construction
/// check (a grid over the sphere fine enough for the gradient bound) and
/// the per-evaluation cost `O(L^2)` grow quickly.
pub const MAX_DEGREE: usize = 100;

/// Most polar rows of the star-shape verification grid (`2 MAX_GRID` azimuths).
pub const MAX_GRID: usize = 2048;

/// Floor step of the march, relative to the outer radius: the smallest
/// feature a grazing ray can miss.
const FLOOR_REL: f64 = 1e-9;

/// Points with `|f| <= ON_SURFACE_REL r_max` count as on the surface.
const ON_SURFACE_REL: f64 = 1e-12;

/// The outer ball used for clipping is inflated and the inner ball deflated
/// by this relative amount, so that their surfaces lie strictly outside /
/// inside the SH surface despite rounding (a sphere has `r_min = r_max`).
const CLIP_REL: f64 = 1e-8;

/// Relative tolerance in `t` of the bracket refinement.
const REFINE_REL: f64 = 1e-12;

/// Cap on level evaluations of one march; never reached in the tests
/// (see the step statistics there). Reaching it reports a miss.
const MAX_STEPS: usize = 100_000;

/// Cap on refinement iterations (Newton converges in a few; bisection of a
/// floor-step bracket to `1e-12` needs about 12).
const MAX_REFINE: usize = 200;

/// Tolerance of `R^T R = I` (largest entry of the difference).
const ROTATION_TOL: f64 = 1e-9;

/// One real SH coefficient pair of degree `k` and order `m` (local units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShCoeff {
    /// Degree `k >= 0`.
    pub k: usize,
    /// Order `0 <= m <= k`.
    pub m: usize,
    /// Cosine coefficient `a_km` [local length].
    pub a: f64,
    /// Sine coefficient `b_km` [local length]; must be 0 for `m = 0`.
    pub b: f64,
}

/// Invalid SH surfaces, coefficient files and fits.
#[derive(Debug, thiserror::Error)]
pub enum ShError {
    /// The coefficient list is empty.
    #[error("no spherical-harmonic coefficients given")]
    Empty,
    /// `m > k`.
    #[error("coefficient {index}: order m = {m} exceeds degree k = {k} (need m <= k)")]
    OrderAboveDegree { index: usize, k: usize, m: usize },
    /// `k > MAX_DEGREE`.
    #[error("coefficient {index}: degree k = {k} exceeds the supported maximum {max}")]
    DegreeTooHigh { index: usize, k: usize, max: usize },
    /// A coefficient is NaN or infinite.
    #[error("coefficient {index} (k = {k}, m = {m}): {which} = {value} is not finite")]
    NotFinite {
        index: usize,
        k: usize,
        m: usize,
        which: &'static str,
        value: f64,
    },
    /// `b != 0` at `m = 0`, where it has no effect.
    #[error(
        "coefficient {index} (k = {k}, m = 0): b = {b} must be 0 (sin(0 phi) = 0, so b has no effect at m = 0)"
    )]
    SineAtZeroOrder { index: usize, k: usize, b: f64 },
    /// The same `(k, m)` twice.
    #[error("coefficient {index} (k = {k}, m = {m}) repeats coefficient {first}")]
    Duplicate {
        index: usize,
        first: usize,
        k: usize,
        m: usize,
    },
    /// The centre is NaN or infinite.
    #[error("centre {center} is not finite")]
    Center { center: DVec3 },
    /// The scale is not a positive finite number.
    #[error("scale {scale} must be finite and > 0")]
    Scale { scale: f64 },
    /// The rotation is not a proper rotation matrix.
    #[error("rotation is not a proper rotation matrix: {reason}")]
    Rotation { reason: String },
    /// `U <= 0` somewhere: not star-shaped about the centre.
    #[error(
        "not star-shaped about the centre: radius U = {radius:e} <= 0 at theta = {theta} rad, phi = {phi} rad (local frame)"
    )]
    NotStarShaped { radius: f64, theta: f64, phi: f64 },
    /// `U > 0` on a fine grid but the rigorous bound could not prove it.
    #[error(
        "could not verify that the radius is positive everywhere: smallest grid value {grid_min:e} \
         (at theta = {theta} rad, phi = {phi} rad), rigorous lower bound {lower:e} on a {n_theta} x {n_phi} grid; \
         the surface (nearly) touches its centre"
    )]
    Unverified {
        grid_min: f64,
        theta: f64,
        phi: f64,
        lower: f64,
        n_theta: usize,
        n_phi: usize,
    },
    /// A bad coefficient file (names the file, line and field).
    #[error(transparent)]
    Input(#[from] InputError),
    /// Fewer fit points than unknowns.
    #[error(
        "fit: {count} points cannot determine the {needed} coefficients of degree {degree}; need at least {needed}"
    )]
    TooFewPoints {
        count: usize,
        degree: usize,
        needed: usize,
    },
    /// A fit point is NaN or infinite.
    #[error("fit: point {index} ({point}) is not finite")]
    PointNotFinite { index: usize, point: DVec3 },
    /// A fit point coincides with the centre (no direction).
    #[error("fit: point {index} coincides with the centre (its direction is undefined)")]
    PointAtCenter { index: usize },
    /// The fit directions do not determine the coefficients.
    #[error(
        "fit: the point directions do not determine the degree-{degree} coefficients \
         (condition number {condition:e}); spread the points over the sphere or lower the degree"
    )]
    IllConditioned { degree: usize, condition: f64 },
}

/// Start of order `m` in the m-major packed layout of degree `l`
/// (entries `(k, m)`, `k = m..=l`, at `offset + k - m`).
#[inline]
fn offset(l: usize, m: usize) -> usize {
    m * (l + 1) - m * m.saturating_sub(1) / 2
}

/// Number of `(k, m)` pairs with `0 <= m <= k <= l`.
#[inline]
fn pair_count(l: usize) -> usize {
    (l + 1) * (l + 2) / 2
}

/// Recurrence constants for `T_k^m` (m-major packed).
#[derive(Clone, Debug)]
struct Recurrence {
    /// Degree `L`.
    l: usize,
    /// `(2k - 1) / sqrt(k^2 - m^2)` at `(k, m)`, `k > m`.
    alpha: Vec<f64>,
    /// `sqrt((k - 1)^2 - m^2) / sqrt(k^2 - m^2)` at `(k, m)`, `k > m`.
    beta: Vec<f64>,
    /// `T_m^m`.
    diag: Vec<f64>,
}

impl Recurrence {
    fn new(l: usize) -> Self {
        let n = pair_count(l);
        let mut alpha = vec![0.0; n];
        let mut beta = vec![0.0; n];
        let mut diag = vec![1.0; l + 1];
        for m in 2..=l {
            diag[m] = diag[m - 1] * ((2 * m - 1) as f64 / (2 * m) as f64).sqrt();
        }
        for m in 0..=l {
            let off = offset(l, m);
            for k in m + 1..=l {
                let den = ((k * k - m * m) as f64).sqrt();
                alpha[off + k - m] = (2 * k - 1) as f64 / den;
                beta[off + k - m] = (((k - 1) * (k - 1) - m * m) as f64).sqrt() / den;
            }
        }
        Self {
            l,
            alpha,
            beta,
            diag,
        }
    }

    /// `T_k^m(z)` for all pairs (m-major packed) into `t`.
    fn table(&self, z: f64, t: &mut [f64]) {
        for m in 0..=self.l {
            let (off, end) = (offset(self.l, m), offset(self.l, m + 1));
            let (mut p2, mut p1) = (0.0, self.diag[m]);
            t[off] = p1;
            let consts = self.alpha[off + 1..end]
                .iter()
                .zip(&self.beta[off + 1..end]);
            for (ti, (&al, &be)) in t[off + 1..end].iter_mut().zip(consts) {
                let p = al * z * p1 - be * p2;
                *ti = p;
                p2 = p1;
                p1 = p;
            }
        }
    }

    /// `T_k^m(z)` into `t` and `dT_k^m/dz` into `dt`.
    fn table_with_derivative(&self, z: f64, t: &mut [f64], dt: &mut [f64]) {
        for m in 0..=self.l {
            let (off, end) = (offset(self.l, m), offset(self.l, m + 1));
            let (mut p2, mut p1) = (0.0, self.diag[m]);
            let (mut d2, mut d1) = (0.0, 0.0);
            t[off] = p1;
            dt[off] = 0.0;
            let consts = self.alpha[off + 1..end]
                .iter()
                .zip(&self.beta[off + 1..end]);
            let outs = t[off + 1..end].iter_mut().zip(&mut dt[off + 1..end]);
            for ((ti, di), (&al, &be)) in outs.zip(consts) {
                let p = al * z * p1 - be * p2;
                let d = al * (p1 + z * d1) - be * d2;
                *ti = p;
                *di = d;
                p2 = p1;
                p1 = p;
                d2 = d1;
                d1 = d;
            }
        }
    }
}

/// Schmidt semi-normalised associated Legendre functions `P_k^m(cos theta)`
/// (no Condon-Shortley phase) for all `0 <= m <= k <= l`, at index
/// `k (k + 1) / 2 + m`.
///
/// Pass `cos theta` and `sin theta >= 0` separately (computing one from the
/// other loses accuracy near the poles or the equator).
pub fn schmidt_legendre(l: usize, cos_theta: f64, sin_theta: f64) -> Vec<f64> {
    let rec = Recurrence::new(l);
    let mut t = vec![0.0; pair_count(l)];
    rec.table(cos_theta, &mut t);
    let mut out = vec![0.0; pair_count(l)];
    let mut sm = 1.0;
    for m in 0..=l {
        let off = offset(l, m);
        for k in m..=l {
            out[k * (k + 1) / 2 + m] = sm * t[off + k - m];
        }
        sm *= sin_theta;
    }
    out
}

/// Level, its derivative along the ray and the world gradient at one point.
#[derive(Clone, Copy, Debug)]
struct Probe {
    /// `|x - c|` [m].
    rho: f64,
    /// `f = rho - scale U` [m].
    f: f64,
    /// `df/dt = grad f . d` [1].
    fp: f64,
    /// `scale U` [m].
    su: f64,
    /// `grad f` (world) [1].
    grad: DVec3,
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

/// A star-shaped surface `r = U(theta, phi)` given by an SH expansion,
/// placed in the world by a centre, a rotation and a scale.
#[derive(Clone, Debug)]
pub struct ShSurface {
    /// Degree `L` (highest degree with a non-zero coefficient).
    degree: usize,
    /// Coefficients and recurrence constants of every `(k, m)`, m-major packed.
    terms: Vec<Term>,
    /// `T_m^m`, the start of each order's recurrence.
    diag: Vec<f64>,
    /// Centre [m].
    center: DVec3,
    /// Local-to-world rotation `R`.
    rot: DMat3,
    /// `R^T`.
    rot_t: DMat3,
    /// World length per local length [m].
    scale: f64,
    /// `a_00` [local].
    a00: f64,
    /// `S = sum_{k>=1} S_k` [local].
    s_sum: f64,
    /// `G = sum_k k S_k`, bound of `|grad_S U|` [local].
    g_bound: f64,
    /// `H = sum_k k^2 S_k`, bound of the second arc derivative [local].
    h_bound: f64,
    /// Lower bound of `U` [local], `> 0`.
    r_min: f64,
    /// Upper bound of `U` [local].
    r_max: f64,
}

/// One `(k, m)` entry of the evaluation table.
#[derive(Clone, Copy, Debug, Default)]
struct Term {
    /// `a_km` [local length].
    a: f64,
    /// `b_km` [local length].
    b: f64,
    /// Recurrence `alpha` at `(k, m)` (0 at `k = m`).
    alpha: f64,
    /// Recurrence `beta` at `(k, m)` (0 at `k = m`).
    beta: f64,
}

/// Sums over the degrees of one order `m`: `sum_k a_km T_k^m`,
/// `sum_k b_km T_k^m` and the same with `dT_k^m / dz`.
#[derive(Clone, Copy, Debug, Default)]
struct OrderSums {
    sa: f64,
    sb: f64,
    da: f64,
    db: f64,
}

/// Recurrence state of one order: `T_{k-1}, T_{k-2}` and their derivatives.
#[derive(Clone, Copy, Debug)]
struct Chain {
    t1: f64,
    t2: f64,
    d1: f64,
    d2: f64,
    sums: OrderSums,
}

impl Chain {
    /// Start at `T_m^m = diag` with the `(m, m)` term.
    #[inline(always)]
    fn new(diag: f64, first: &Term) -> Self {
        Self {
            t1: diag,
            t2: 0.0,
            d1: 0.0,
            d2: 0.0,
            sums: OrderSums {
                sa: first.a * diag,
                sb: first.b * diag,
                da: 0.0,
                db: 0.0,
            },
        }
    }

    /// Advance one degree.
    #[inline(always)]
    fn step(&mut self, z: f64, e: &Term) {
        // Grouped so that each new value is one multiply and one add away
        // from the previous one (the chains are latency-bound).
        let az = e.alpha * z;
        let t0 = az * self.t1 - e.beta * self.t2;
        let d0 = (e.alpha * self.t1 - e.beta * self.d2) + az * self.d1;
        self.sums.sa += e.a * t0;
        self.sums.sb += e.b * t0;
        self.sums.da += e.a * d0;
        self.sums.db += e.b * d0;
        self.t2 = self.t1;
        self.d2 = self.d1;
        self.t1 = t0;
        self.d1 = d0;
    }
}

/// Rigorous range of `U` from a grid.
struct GridRange {
    /// Smallest node value and its `(theta, phi)`.
    min: f64,
    min_at: (f64, f64),
    /// Lower and upper bounds of `U` over the whole sphere.
    lower: f64,
    upper: f64,
    n_theta: usize,
    n_phi: usize,
}

impl ShSurface {
    /// Build and validate a surface.
    ///
    /// `coeffs` in local units (missing pairs are zero); `center` [m];
    /// `rotation` a proper rotation (local to world); `scale` > 0 world
    /// metres per local unit. Rejects: an empty list, `m > k`,
    /// `k > MAX_DEGREE`, non-finite values, `b != 0` at `m = 0`, repeated
    /// `(k, m)`, a non-finite centre, a bad scale or rotation, and
    /// expansions with `U <= 0` somewhere ([`ShError::NotStarShaped`]) or
    /// where `U > 0` cannot be proved ([`ShError::Unverified`]); see the
    /// module docs for the bound-then-grid check. Trailing degrees whose
    /// coefficients are all zero are dropped.
    pub fn new(
        coeffs: &[ShCoeff],
        center: DVec3,
        rotation: DMat3,
        scale: f64,
    ) -> Result<Self, ShError> {
        if coeffs.is_empty() {
            return Err(ShError::Empty);
        }
        for (index, c) in coeffs.iter().enumerate() {
            if c.k > MAX_DEGREE {
                return Err(ShError::DegreeTooHigh {
                    index,
                    k: c.k,
                    max: MAX_DEGREE,
                });
            }
            if c.m > c.k {
                return Err(ShError::OrderAboveDegree {
                    index,
                    k: c.k,
                    m: c.m,
                });
            }
            for (which, value) in [("a", c.a), ("b", c.b)] {
                if !value.is_finite() {
                    return Err(ShError::NotFinite {
                        index,
                        k: c.k,
                        m: c.m,
                        which,
                        value,
                    });
                }
            }
            if c.m == 0 && c.b != 0.0 {
                return Err(ShError::SineAtZeroOrder {
                    index,
                    k: c.k,
                    b: c.b,
                });
            }
        }
        let k_max = coeffs.iter().map(|c| c.k).max().unwrap_or(0);
        let mut seen: Vec<Option<usize>> = vec![None; pair_count(k_max)];
        for (index, c) in coeffs.iter().enumerate() {
            let slot = &mut seen[c.k * (c.k + 1) / 2 + c.m];
            if let Some(first) = *slot {
                return Err(ShError::Duplicate {
                    index,
                    first,
                    k: c.k,
                    m: c.m,
                });
            }
            *slot = Some(index);
        }
        if !center.is_finite() {
            return Err(ShError::Center { center });
        }
        if !(scale.is_finite() && scale > 0.0) {
            return Err(ShError::Scale { scale });
        }
        check_rotation(rotation)?;

        let degree = coeffs
            .iter()
            .filter(|c| c.a != 0.0 || c.b != 0.0)
            .map(|c| c.k)
            .max()
            .unwrap_or(0);
        let rec = Recurrence::new(degree);
        let mut terms: Vec<Term> = rec
            .alpha
            .iter()
            .zip(&rec.beta)
            .map(|(&alpha, &beta)| Term {
                alpha,
                beta,
                ..Term::default()
            })
            .collect();
        for c in coeffs.iter().filter(|c| c.k <= degree) {
            let e = &mut terms[offset(degree, c.m) + c.k - c.m];
            e.a = c.a;
            e.b = c.b;
        }
        let mut s_k = vec![0.0; degree + 1];
        for m in 0..=degree {
            let off = offset(degree, m);
            for k in m..=degree {
                s_k[k] += terms[off + k - m].a.hypot(terms[off + k - m].b);
            }
        }
        let a00 = terms[0].a;
        let s_sum: f64 = s_k[1..].iter().sum();
        let g_bound: f64 = s_k.iter().enumerate().map(|(k, s)| k as f64 * s).sum();
        let h_bound: f64 = s_k
            .iter()
            .enumerate()
            .map(|(k, s)| (k * k) as f64 * s)
            .sum();
        let mut surf = Self {
            degree,
            terms,
            diag: rec.diag,
            center,
            rot: rotation,
            rot_t: rotation.transpose(),
            scale,
            a00,
            s_sum,
            g_bound,
            h_bound,
            r_min: a00 - s_sum,
            r_max: a00 + s_sum,
        };
        surf.verify_star_shaped()?;
        Ok(surf)
    }

    /// Prove `U > 0` (bound, then grids) and tighten `r_min`, `r_max`.
    fn verify_star_shaped(&mut self) -> Result<(), ShError> {
        let reference = self.a00.abs().max(self.s_sum).max(f64::MIN_POSITIVE);
        // Rounding of the node values: a few ulps of the largest possible sum.
        let margin = 1e-12 * (self.a00.abs() + self.s_sum);
        // Initial grid: G delta about 5 % of the radius.
        let rec = Recurrence::new(self.degree);
        let mut n = ((PI * self.g_bound / (0.05 * reference)).ceil() as usize).clamp(16, 256);
        loop {
            let g = self.grid_range(&rec, n, margin);
            if g.min <= 0.0 {
                return Err(ShError::NotStarShaped {
                    radius: g.min,
                    theta: g.min_at.0,
                    phi: g.min_at.1,
                });
            }
            if g.lower > 0.0 {
                self.r_min = (self.a00 - self.s_sum).max(g.lower);
                self.r_max = (self.a00 + self.s_sum).min(g.upper);
                return Ok(());
            }
            if n >= MAX_GRID {
                return Err(ShError::Unverified {
                    grid_min: g.min,
                    theta: g.min_at.0,
                    phi: g.min_at.1,
                    lower: g.lower,
                    n_theta: g.n_theta,
                    n_phi: g.n_phi,
                });
            }
            n = (2 * n).min(MAX_GRID);
        }
    }

    /// `U` and `|grad_S U|` on the grid `theta_i = i pi / n` (`i = 0..=n`),
    /// `phi_j = pi j / n` (`j < 2n`): the smallest node value and rigorous
    /// bounds over the sphere. Every direction lies within the path length
    /// `delta = (pi/n + pi/n) / 2` of a node, so near node `q`
    /// `|U - U(q)| <= min(G delta, |grad_S U(q)| delta + H delta^2 / 2)`
    /// (first- and second-order Bernstein bounds along the great circle
    /// from `q`); `margin` covers rounding.
    fn grid_range(&self, rec: &Recurrence, n_theta: usize, margin: f64) -> GridRange {
        let l = self.degree;
        let n_phi = 2 * n_theta;
        let delta = 0.5 * (PI / n_theta as f64 + 2.0 * PI / n_phi as f64);
        let slack1 = self.g_bound * delta;
        let half_h = 0.5 * self.h_bound * delta * delta;
        let mut cos_tab = vec![0.0; n_phi * (l + 1)];
        let mut sin_tab = vec![0.0; n_phi * (l + 1)];
        for j in 0..n_phi {
            let phi = 2.0 * PI * j as f64 / n_phi as f64;
            for m in 0..=l {
                let (s, c) = (m as f64 * phi).sin_cos();
                cos_tab[j * (l + 1) + m] = c;
                sin_tab[j * (l + 1) + m] = s;
            }
        }
        let mut t = vec![0.0; pair_count(l)];
        let mut dt = vec![0.0; pair_count(l)];
        // Per order m: coefficients of cos(m phi) and sin(m phi) in U,
        // U_theta and (1/sin theta) U_phi along the current row.
        let mut cu = vec![[0.0; 6]; l + 1];
        let mut out = GridRange {
            min: f64::INFINITY,
            min_at: (0.0, 0.0),
            lower: f64::INFINITY,
            upper: f64::NEG_INFINITY,
            n_theta,
            n_phi,
        };
        for i in 0..=n_theta {
            let theta = PI * i as f64 / n_theta as f64;
            let (s, z) = if i == 0 {
                (0.0, 1.0)
            } else if i == n_theta {
                (0.0, -1.0)
            } else {
                theta.sin_cos()
            };
            rec.table_with_derivative(z, &mut t, &mut dt);
            let (mut spow, mut spow1) = (1.0, 0.0);
            for (m, cm) in cu.iter_mut().enumerate() {
                let off = offset(l, m);
                let (mut sa, mut sb, mut da, mut db) = (0.0, 0.0, 0.0, 0.0);
                for i in off..=off + l - m {
                    let e = &self.terms[i];
                    sa += e.a * t[i];
                    sb += e.b * t[i];
                    da += e.a * dt[i];
                    db += e.b * dt[i];
                }
                let mf = m as f64;
                *cm = if m == 0 {
                    [sa, sb, -s * da, -s * db, 0.0, 0.0]
                } else {
                    [
                        spow * sa,
                        spow * sb,
                        spow1 * (mf * z * sa - s * s * da),
                        spow1 * (mf * z * sb - s * s * db),
                        mf * spow1 * sb,
                        -mf * spow1 * sa,
                    ]
                };
                spow1 = spow;
                spow *= s;
            }
            // At the poles every azimuth gives the same value and gradient.
            let j_end = if s == 0.0 { 1 } else { n_phi };
            for j in 0..j_end {
                let row = j * (l + 1);
                let (mut u, mut ut, mut up) = (0.0, 0.0, 0.0);
                for (m, cm) in cu.iter().enumerate() {
                    let (c, sn) = (cos_tab[row + m], sin_tab[row + m]);
                    u += cm[0] * c + cm[1] * sn;
                    ut += cm[2] * c + cm[3] * sn;
                    up += cm[4] * c + cm[5] * sn;
                }
                if u < out.min {
                    out.min = u;
                    out.min_at = (theta, 2.0 * PI * j as f64 / n_phi as f64);
                }
                let slack = slack1.min((ut * ut + up * up).sqrt() * delta + half_h) + margin;
                out.lower = out.lower.min(u - slack);
                out.upper = out.upper.max(u + slack);
            }
        }
        out
    }

    /// Degree `L`: the highest degree with a non-zero coefficient.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Centre [m].
    pub fn center(&self) -> DVec3 {
        self.center
    }

    /// Local-to-world rotation `R`.
    pub fn rotation(&self) -> DMat3 {
        self.rot
    }

    /// World metres per local unit.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// World radius bounds [m]: the surface lies between the spheres of
    /// these radii around the centre (`a_00 -/+ S`, tightened by the
    /// verification grid; see the module docs). Both are `> 0`.
    pub fn bounds(&self) -> (f64, f64) {
        (self.scale * self.r_min, self.scale * self.r_max)
    }

    /// Bounds `(G, H)` of the first and second arc derivatives of `U` on the
    /// unit sphere (Bernstein; local units): `|grad_S U| <= G = sum_k k S_k`,
    /// `|d^2 U / dpsi^2| <= H = sum_k k^2 S_k` along any great circle.
    pub fn derivative_bounds(&self) -> (f64, f64) {
        (self.g_bound, self.h_bound)
    }

    /// The coefficients of all pairs `0 <= m <= k <= degree()` (zeros
    /// included), in k-major order.
    pub fn coefficients(&self) -> Vec<ShCoeff> {
        let l = self.degree;
        let mut out = Vec::with_capacity(pair_count(l));
        for k in 0..=l {
            for m in 0..=k {
                let i = offset(l, m) + k - m;
                out.push(ShCoeff {
                    k,
                    m,
                    a: self.terms[i].a,
                    b: self.terms[i].b,
                });
            }
        }
        out
    }

    /// Sums of the `N` orders `m .. m + N` (`m + N <= L + 1`), their
    /// independent recurrences interleaved so the CPU can overlap them
    /// (each is a serial dependency chain).
    #[inline(always)]
    fn order_block<const N: usize>(&self, m: usize, z: f64) -> [OrderSums; N] {
        let l = self.degree;
        let rows: [&[Term]; N] =
            std::array::from_fn(|j| &self.terms[offset(l, m + j)..offset(l, m + j + 1)]);
        let mut ch: [Chain; N] = std::array::from_fn(|j| Chain::new(self.diag[m + j], &rows[j][0]));
        // Order m + j has L - m - j + 1 degrees: the last order sets the
        // common length, the others then finish N - 1 - j more steps.
        let common = rows[N - 1].len();
        for i in 1..common {
            for (c, row) in ch.iter_mut().zip(&rows) {
                c.step(z, &row[i]);
            }
        }
        for (c, row) in ch.iter_mut().zip(&rows) {
            for e in &row[common..] {
                c.step(z, e);
            }
        }
        ch.map(|c| c.sums)
    }

    /// `U` and the surface gradient `grad_S U` (a local vector tangent to
    /// the unit sphere) at the local direction `y` (any non-zero length;
    /// normalised here), and the unit direction used.
    #[inline]
    fn eval(&self, y: DVec3) -> (f64, DVec3, DVec3) {
        let y = y / y.length();
        let z = y.z;
        let s = (y.x * y.x + y.y * y.y).sqrt();
        let (c1, s1) = if s > 0.0 {
            (y.x / s, y.y / s)
        } else {
            (1.0, 0.0)
        };
        let l = self.degree;
        let mut acc = [0.0; 3]; // U, U_theta, U_phi / sin theta
        // cos(m phi), sin(m phi), s^m, s^(m-1)
        let mut rot = (1.0, 0.0);
        let mut pow = (1.0, 0.0);
        let mut add = |m: usize, o: OrderSums| {
            let (cm, sm) = rot;
            let (spow, spow1) = pow;
            let c = o.sa * cm + o.sb * sm;
            let d = o.da * cm + o.db * sm;
            acc[0] += spow * c;
            if m == 0 {
                acc[1] -= s * d;
            } else {
                let mf = m as f64;
                acc[1] += spow1 * (mf * z * c - s * s * d);
                acc[2] += mf * spow1 * (o.sb * cm - o.sa * sm);
            }
            pow = (spow * s, spow);
            rot = (cm * c1 - sm * s1, sm * c1 + cm * s1);
        };
        let mut m = 0;
        while m + 2 <= l + 1 {
            for (j, o) in self.order_block::<2>(m, z).into_iter().enumerate() {
                add(m + j, o);
            }
            m += 2;
        }
        if m == l {
            add(m, self.order_block::<1>(m, z)[0]);
        }
        let theta_hat = DVec3::new(z * c1, z * s1, -s);
        let phi_hat = DVec3::new(-s1, c1, 0.0);
        (acc[0], acc[1] * theta_hat + acc[2] * phi_hat, y)
    }

    /// Radius `U` [local units] in the local direction `dir_local` (any
    /// non-zero length; normalised here).
    pub fn radius(&self, dir_local: DVec3) -> f64 {
        self.eval(dir_local).0
    }

    /// Radius `U` [local units] and its surface gradient `grad_S U`
    /// [local units per radian], a local vector tangent to the unit sphere at
    /// `dir_local` (normalised here). Exact at the poles.
    pub fn radius_and_gradient(&self, dir_local: DVec3) -> (f64, DVec3) {
        let (u, g, _) = self.eval(dir_local);
        (u, g)
    }

    /// Level and gradient at `p = x - center` (world); `d` the ray direction.
    #[inline]
    fn probe(&self, p: DVec3, d: DVec3) -> Probe {
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

    /// "Level" `f(x) = |x - c| - scale U(dir)` [m]: `< 0` inside, `> 0`
    /// outside (at the centre, `-scale U(+z)`).
    pub fn level(&self, x: DVec3) -> f64 {
        self.probe(x - self.center, DVec3::Z).f
    }

    /// Outward unit normal at a surface point `x` (world), from the analytic
    /// gradient of the level (exact at the poles). Off the surface, the
    /// normalised gradient of the level; `+z` of the local frame at the centre.
    pub fn normal(&self, x: DVec3) -> DVec3 {
        let p = self.probe(x - self.center, DVec3::Z);
        if p.rho > 0.0 {
            p.grad.normalize()
        } else {
            self.rot * DVec3::Z
        }
    }

    /// Half-width of the "on the surface" band of the level [m].
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
            if steps >= MAX_STEPS {
                return (March::Miss, steps);
            }
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
            let mut h = if on_start {
                // Leaving the surface: half the root keeps f clearly off zero.
                on_start = false;
                0.5 * h2
            } else {
                h1.max(h2)
            }
            .min(cap);
            if h.is_nan() || h < floor {
                h = floor;
            }
            let (tn, last) = if t + h >= t_end {
                (t_end, true)
            } else {
                (t + h, false)
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
    fn first_hit_counted(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> (Option<(f64, DVec3)>, usize) {
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
                let hit = (t > t_min && t < t_max).then(|| (t, pr.grad.normalize()));
                (hit, n + nr)
            }
        }
    }

    /// Whether the open segment `o + t d`, `t` in `(t_min, t_max)` (unit
    /// `d`), crosses the surface (shadow rays). Stops at the first bracket
    /// found, without refining it. Endpoints on the surface do not count.
    pub fn crosses(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> bool {
        matches!(self.march(o, d, t_min, t_max).0, March::Bracket { .. })
    }

    /// Number of real coefficients defining the shape: `(L + 1)^2` (`a_km`
    /// for `0 <= m <= k <= L`, `b_km` for `m >= 1`); `8` bytes each in the
    /// most compact storage.
    pub fn coefficient_count(&self) -> usize {
        (self.degree + 1) * (self.degree + 1)
    }

    /// Bytes this surface occupies in memory: the struct plus its arrays
    /// (per `(k, m)`: `a`, `b` and two recurrence constants; per order: `T_m^m`).
    pub fn storage_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.terms.capacity() * std::mem::size_of::<Term>()
            + self.diag.capacity() * std::mem::size_of::<f64>()
    }
}

/// Check that `r` is a proper rotation (orthonormal within `ROTATION_TOL`, determinant +1).
fn check_rotation(r: DMat3) -> Result<(), ShError> {
    if !r.is_finite() {
        return Err(ShError::Rotation {
            reason: "entries are not finite".into(),
        });
    }
    let e = (r.transpose() * r - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |acc, x| acc.max(x.abs()));
    if e.is_nan() || e > ROTATION_TOL {
        return Err(ShError::Rotation {
            reason: format!(
                "R^T R differs from the identity by {e:e} (tolerance {ROTATION_TOL:e})"
            ),
        });
    }
    let det = r.determinant();
    if det < 0.0 {
        return Err(ShError::Rotation {
            reason: format!("determinant {det} < 0 (a reflection)"),
        });
    }
    Ok(())
}

/// Display name of a path as csvio prints it (`-` is standard input).
fn display_name(path: &str) -> String {
    if path == "-" {
        "<stdin>".to_string()
    } else {
        path.to_string()
    }
}

/// Parse a non-negative integer index from a cell.
fn index_cell(cell: &str, file: &str, line: u64, field: &str) -> Result<usize, InputError> {
    cell.parse::<usize>().map_err(|_| InputError::Field {
        file: display_name(file),
        line,
        field: field.to_string(),
        message: format!("`{cell}` is not a non-negative integer"),
    })
}

/// Read SH coefficients from a CSV file with the header columns `k,m,a,b`
/// (any order; other columns ignored; `#` starts a comment; `-` is
/// standard input). `a`, `b` in local units.
///
/// Errors name the file, the line and the field: a missing column, a
/// non-integer `k` or `m`, `k > MAX_DEGREE`, `m > k`, a non-finite `a` or
/// `b`, `b != 0` at `m = 0`, a repeated `(k, m)`, or an empty table.
pub fn read_coefficients(path: &Path) -> Result<Vec<ShCoeff>, ShError> {
    let name = path.to_string_lossy();
    let name = name.as_ref();
    let table = csvio::read_table(name)?;
    let cols = csvio::columns(&table.headers, &["k", "m", "a", "b"], name)?;
    let field_err = |line: u64, field: &str, message: String| InputError::Field {
        file: display_name(name),
        line,
        field: field.to_string(),
        message,
    };
    let mut out = Vec::with_capacity(table.rows.len());
    let mut seen = std::collections::HashMap::new();
    for (row, &line) in table.rows.iter().zip(&table.lines) {
        let cell = |i: usize| row.get(cols[i]).map_or("", String::as_str);
        let k = index_cell(cell(0), name, line, "k")?;
        let m = index_cell(cell(1), name, line, "m")?;
        let a = csvio::number(cell(2), name, line, "a")?;
        let b = csvio::number(cell(3), name, line, "b")?;
        if k > MAX_DEGREE {
            let msg = format!("degree {k} exceeds the supported maximum {MAX_DEGREE}");
            return Err(field_err(line, "k", msg).into());
        }
        if m > k {
            let msg = format!("order m = {m} exceeds degree k = {k} (need m <= k)");
            return Err(field_err(line, "m", msg).into());
        }
        if m == 0 && b != 0.0 {
            let msg = format!("b = {b} must be 0 at m = 0 (sin(0 phi) = 0)");
            return Err(field_err(line, "b", msg).into());
        }
        if let Some(first) = seen.insert((k, m), line) {
            let msg = format!("(k, m) = ({k}, {m}) repeats line {first}");
            return Err(field_err(line, "k,m", msg).into());
        }
        out.push(ShCoeff { k, m, a, b });
    }
    if out.is_empty() {
        return Err(InputError::File {
            file: display_name(name),
            message: "no coefficients in the file".into(),
        }
        .into());
    }
    Ok(out)
}

/// Write coefficients as CSV `k,m,a,b` with shortest round-trip numbers
/// (reading the file back gives the same `f64`s), atomically (temporary
/// file, then rename); `-` writes to standard output.
pub fn write_coefficients(path: &Path, coeffs: &[ShCoeff]) -> std::io::Result<()> {
    let mut text = String::from("k,m,a,b\n");
    for c in coeffs {
        text.push_str(&format!(
            "{},{},{},{}\n",
            c.k,
            c.m,
            csvio::format_number(c.a),
            csvio::format_number(c.b)
        ));
    }
    csvio::write_atomic(&path.to_string_lossy(), text.as_bytes())
}

/// Result of a least-squares SH fit (world units).
#[derive(Clone, Debug)]
pub struct ShFit {
    /// All pairs `0 <= m <= k <= degree`, k-major, in metres: use with
    /// `ShSurface::new(&coeffs, center, DMat3::IDENTITY, 1.0)`.
    pub coeffs: Vec<ShCoeff>,
    /// Root-mean-square radial residual `|p - c| - U(dir)` [m].
    pub rms_residual: f64,
    /// Largest absolute radial residual [m].
    pub max_residual: f64,
    /// Mean of `|p - c|` over the points [m].
    pub mean_radius: f64,
}

/// Largest condition number accepted by [`fit`].
const FIT_MAX_CONDITION: f64 = 1e12;

/// Least-squares fit of the radii `|p - center|` of `points` (world, [m])
/// as a function of direction by an SH expansion up to `degree` (world
/// frame, identity rotation, scale 1), by SVD (nalgebra).
///
/// Needs at least `(degree + 1)^2` points whose directions determine the
/// coefficients (condition number `<= 1e12`); rejects non-finite points and
/// points at the centre. The fitted expansion is not checked for `U > 0`;
/// [`ShSurface::new`] does that.
pub fn fit(points: &[DVec3], center: DVec3, degree: usize) -> Result<ShFit, ShError> {
    if !center.is_finite() {
        return Err(ShError::Center { center });
    }
    if degree > MAX_DEGREE {
        return Err(ShError::DegreeTooHigh {
            index: 0,
            k: degree,
            max: MAX_DEGREE,
        });
    }
    let needed = (degree + 1) * (degree + 1);
    if points.len() < needed {
        return Err(ShError::TooFewPoints {
            count: points.len(),
            degree,
            needed,
        });
    }
    let l = degree;
    let rec = Recurrence::new(l);
    let mut t = vec![0.0; pair_count(l)];
    let mut design = nalgebra::DMatrix::<f64>::zeros(points.len(), needed);
    let mut radii = nalgebra::DVector::<f64>::zeros(points.len());
    for (index, &p) in points.iter().enumerate() {
        if !p.is_finite() {
            return Err(ShError::PointNotFinite { index, point: p });
        }
        let v = p - center;
        let r = v.length();
        if r == 0.0 {
            return Err(ShError::PointAtCenter { index });
        }
        radii[index] = r;
        let y = v / r;
        let s = y.x.hypot(y.y);
        let (c1, s1) = if s > 0.0 {
            (y.x / s, y.y / s)
        } else {
            (1.0, 0.0)
        };
        rec.table(y.z, &mut t);
        let (mut cm, mut sm, mut spow) = (1.0, 0.0, 1.0);
        for m in 0..=l {
            let off = offset(l, m);
            for k in m..=l {
                let pkm = spow * t[off + k - m];
                let (ca, cb) = fit_columns(k, m);
                design[(index, ca)] = pkm * cm;
                if let Some(cb) = cb {
                    design[(index, cb)] = pkm * sm;
                }
            }
            spow *= s;
            (cm, sm) = (cm * c1 - sm * s1, sm * c1 + cm * s1);
        }
    }
    let svd = nalgebra::SVD::new(design.clone(), true, true);
    let sv = &svd.singular_values;
    let (smax, smin) = (sv.max(), sv.min());
    let condition = if smin > 0.0 {
        smax / smin
    } else {
        f64::INFINITY
    };
    if condition.is_nan() || condition > FIT_MAX_CONDITION {
        return Err(ShError::IllConditioned { degree, condition });
    }
    let x = svd
        .solve(&radii, 0.0)
        .expect("U and V were computed by the SVD");
    let residual = &radii - &design * &x;
    let n = points.len() as f64;
    let rms_residual = (residual.norm_squared() / n).sqrt();
    let max_residual = residual.amax();
    let mean_radius = radii.sum() / n;
    let mut coeffs = Vec::with_capacity(pair_count(l));
    for k in 0..=l {
        for m in 0..=k {
            let (ca, cb) = fit_columns(k, m);
            coeffs.push(ShCoeff {
                k,
                m,
                a: x[ca],
                b: cb.map_or(0.0, |c| x[c]),
            });
        }
    }
    Ok(ShFit {
        coeffs,
        rms_residual,
        max_residual,
        mean_radius,
    })
}

/// Columns of `a_km` and `b_km` (none at `m = 0`) in the fit's design
/// matrix: degree `k` occupies columns `k^2 .. (k+1)^2`, as
/// `a_k0, a_k1, b_k1, a_k2, b_k2, ...`.
fn fit_columns(k: usize, m: usize) -> (usize, Option<usize>) {
    if m == 0 {
        (k * k, None)
    } else {
        (k * k + 2 * m - 1, Some(k * k + 2 * m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Philox4x32;

    fn c(k: usize, m: usize, a: f64, b: f64) -> ShCoeff {
        ShCoeff { k, m, a, b }
    }

    fn unit(r: &mut Philox4x32) -> DVec3 {
        let z = 1.0 - 2.0 * r.next_f64();
        let s = (1.0 - z * z).max(0.0).sqrt();
        let (sp, cp) = (2.0 * PI * r.next_f64()).sin_cos();
        DVec3::new(s * cp, s * sp, z)
    }

    /// A unit vector orthogonal to `n`, random.
    fn tangent(r: &mut Philox4x32, n: DVec3) -> DVec3 {
        loop {
            let v = unit(r);
            let t = v - n * n.dot(v);
            if t.length() > 0.1 {
                return t.normalize();
            }
        }
    }

    fn rotation() -> DMat3 {
        DMat3::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7)
    }

    fn binom(n: usize, k: usize) -> f64 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
    }

    /// Schmidt `P_k^m` from the explicit sum for `P_k` and exact polynomial
    /// differentiation (independent of the recurrences).
    fn schmidt_explicit(k: usize, m: usize, x: f64) -> f64 {
        let mut dm = 0.0;
        for j in 0..=k / 2 {
            let n = k - 2 * j;
            if n < m {
                continue;
            }
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            let coef = sign * binom(k, j) * binom(2 * k - 2 * j, k) / 2f64.powi(k as i32);
            let fall: f64 = (0..m).map(|i| (n - i) as f64).product();
            dm += coef * fall * x.powi((n - m) as i32);
        }
        let fact = |n: usize| (1..=n).fold(1.0, |a, i| a * i as f64);
        let norm = if m == 0 {
            1.0
        } else {
            (2.0 * fact(k - m) / fact(k + m)).sqrt()
        };
        let s = ((1.0 - x) * (1.0 + x)).sqrt();
        norm * s.powi(m as i32) * dm
    }

    fn xs() -> Vec<f64> {
        let mut v: Vec<f64> = (0..=40).map(|i| -1.0 + i as f64 / 20.0).collect();
        v.extend([0.123_456_789, -0.987_654_321, 1.0 - 1e-9, -1.0 + 1e-12]);
        v
    }

    #[test]
    fn legendre_matches_closed_forms() {
        let r3 = 3f64.sqrt();
        for x in xs() {
            let s = ((1.0 - x) * (1.0 + x)).sqrt();
            let p = schmidt_legendre(12, x, s);
            let at = |k: usize, m: usize| p[k * (k + 1) / 2 + m];
            let closed = [
                (0, 0, 1.0),
                (1, 0, x),
                (1, 1, s),
                (2, 0, 0.5 * (3.0 * x * x - 1.0)),
                (2, 1, r3 * x * s),
                (2, 2, 0.5 * r3 * s * s),
                (3, 0, 0.5 * (5.0 * x * x * x - 3.0 * x)),
                (3, 1, (3.0f64 / 8.0).sqrt() * s * (5.0 * x * x - 1.0)),
                (3, 2, 0.5 * 15f64.sqrt() * x * s * s),
                (3, 3, (5.0f64 / 8.0).sqrt() * s * s * s),
                (4, 4, (35.0f64 / 64.0).sqrt() * s.powi(4)),
            ];
            for (k, m, want) in closed {
                let got = at(k, m);
                assert!(
                    (got - want).abs() <= 2e-15,
                    "P_{k}^{m}({x}) = {got}, closed form {want}"
                );
            }
            for k in 0..=12 {
                for m in 0..=k {
                    let want = schmidt_explicit(k, m, x);
                    let got = at(k, m);
                    assert!(
                        (got - want).abs() <= 1e-12,
                        "P_{k}^{m}({x}) = {got}, explicit {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn schmidt_addition_theorem() {
        let l = 60;
        for x in xs() {
            let s = ((1.0 - x) * (1.0 + x)).sqrt();
            let p = schmidt_legendre(l, x, s);
            for k in 0..=l {
                let row = &p[k * (k + 1) / 2..=k * (k + 1) / 2 + k];
                let sum: f64 = row.iter().map(|v| v * v).sum();
                assert!((sum - 1.0).abs() <= 1e-13, "k = {k}, x = {x}: sum {sum}");
                assert!(row.iter().all(|v| v.abs() <= 1.0 + 1e-15));
            }
        }
    }

    #[test]
    fn single_terms_match_closed_forms() {
        let mut r = Philox4x32::new(11, 0);
        let (a, b) = (0.3, -0.2);
        // (k, m, P_k^m(x) as a function of (x, s))
        type ClosedForm = fn(f64, f64) -> f64;
        let cases: [(usize, usize, ClosedForm); 4] = [
            (1, 1, |_, s| s),
            (2, 1, |x, s| 3f64.sqrt() * x * s),
            (3, 2, |x, s| 0.5 * 15f64.sqrt() * x * s * s),
            (3, 3, |_, s| (5.0f64 / 8.0).sqrt() * s * s * s),
        ];
        for (k, m, p) in cases {
            let surf = ShSurface::new(
                &[c(0, 0, 2.0, 0.0), c(k, m, a, b)],
                DVec3::ZERO,
                DMat3::IDENTITY,
                1.0,
            )
            .unwrap();
            assert_eq!(surf.degree(), k);
            let mut dirs: Vec<DVec3> = (0..200).map(|_| unit(&mut r)).collect();
            dirs.extend([
                DVec3::Z,
                -DVec3::Z,
                DVec3::X,
                DVec3::new(0.0, -1.0, 1.0).normalize(),
            ]);
            for y in dirs {
                let s = y.x.hypot(y.y);
                let phi = y.y.atan2(y.x);
                let mf = m as f64;
                let want = 2.0 + p(y.z, s) * (a * (mf * phi).cos() + b * (mf * phi).sin());
                let got = surf.radius(y);
                assert!(
                    (got - want).abs() <= 1e-15,
                    "k {k} m {m} dir {y}: {got} vs {want}"
                );
            }
        }
    }

    /// Pseudo-random bumpy coefficients: `a_00 = 1`, degree-k amplitudes `amp / k`.
    fn bumpy_coeffs(degree: usize, amp: f64, seed: u64) -> Vec<ShCoeff> {
        let mut r = Philox4x32::new(seed, 7);
        let mut v = vec![c(0, 0, 1.0, 0.0)];
        for k in 1..=degree {
            for m in 0..=k {
                let w = amp / k as f64;
                let a = w * (2.0 * r.next_f64() - 1.0);
                let b = if m == 0 {
                    0.0
                } else {
                    w * (2.0 * r.next_f64() - 1.0)
                };
                v.push(c(k, m, a, b));
            }
        }
        v
    }

    /// The degree-8 bumpy test shape at a given scale (centre scales too).
    fn bumpy(scale: f64) -> ShSurface {
        ShSurface::new(
            &bumpy_coeffs(8, 0.2, 1),
            scale * DVec3::new(0.2, -0.1, 0.3),
            rotation(),
            scale * 1.7,
        )
        .unwrap()
    }

    #[test]
    fn surface_gradient_matches_finite_differences() {
        let surf = bumpy(1.0);
        let mut r = Philox4x32::new(12, 0);
        let mut dirs: Vec<DVec3> = (0..300).map(|_| unit(&mut r)).collect();
        dirs.extend([DVec3::Z, -DVec3::Z]);
        let h: f64 = 1e-5;
        for y in dirs {
            let (_, g) = surf.radius_and_gradient(y);
            assert!(g.dot(y).abs() <= 1e-13, "gradient not tangent at {y}");
            for _ in 0..2 {
                let e = tangent(&mut r, y);
                // Along the great circle through y in direction e.
                let fd = (surf.radius(y * h.cos() + e * h.sin())
                    - surf.radius(y * h.cos() - e * h.sin()))
                    / (2.0 * h);
                assert!(
                    (fd - g.dot(e)).abs() <= 1e-7,
                    "dir {y}: fd {fd} vs {}",
                    g.dot(e)
                );
            }
        }
    }

    #[test]
    fn bounds_enclose_the_surface() {
        let surf = bumpy(2.5);
        let (lo, hi) = surf.bounds();
        let (a00, s) = (surf.a00, surf.s_sum);
        assert!(lo >= 2.5 * 1.7 * (a00 - s) && hi <= 2.5 * 1.7 * (a00 + s));
        assert!(lo > 0.0);
        let mut r = Philox4x32::new(13, 0);
        let (mut umin, mut umax) = (f64::INFINITY, 0.0f64);
        for _ in 0..50_000 {
            let u = surf.scale() * surf.radius(unit(&mut r));
            umin = umin.min(u);
            umax = umax.max(u);
        }
        assert!(
            lo <= umin && umax <= hi,
            "[{lo}, {hi}] vs sampled [{umin}, {umax}]"
        );
        // The grid bounds are tight (second-order slack).
        assert!(
            umin - lo <= 0.01 * umin && hi - umax <= 0.01 * umax,
            "[{lo}, {hi}] vs sampled [{umin}, {umax}]"
        );
        // The bounds are tight to the 5 % grid slack.
        eprintln!(
            "bumpy: a00 -/+ S = {} / {}, bounds [{lo}, {hi}], sampled [{umin}, {umax}], G = {}, H = {}",
            2.5 * 1.7 * (a00 - s),
            2.5 * 1.7 * (a00 + s),
            surf.g_bound,
            surf.h_bound
        );
    }

    #[test]
    fn grid_proves_star_shape_when_the_coefficient_bound_cannot() {
        // U = 0.7 + 0.6 x + 0.9 x^2 (x = cos theta): min 0.6 at x = -1/3, but a00 - S = -0.2.
        let coeffs = [c(0, 0, 1.0, 0.0), c(1, 0, 0.6, 0.0), c(2, 0, 0.6, 0.0)];
        let surf = ShSurface::new(&coeffs, DVec3::ZERO, DMat3::IDENTITY, 1.0).unwrap();
        let (lo, hi) = surf.bounds();
        assert!(lo > 0.59 && lo <= 0.6, "r_min {lo}");
        assert!((2.2..2.25).contains(&hi), "r_max {hi}");
        // Positive everywhere but by 1e-12 only: cannot be proved.
        let coeffs = [
            c(0, 0, 0.4 + 1e-12, 0.0),
            c(1, 0, 0.6, 0.0),
            c(2, 0, 0.6, 0.0),
        ];
        let e = ShSurface::new(&coeffs, DVec3::ZERO, DMat3::IDENTITY, 1.0).unwrap_err();
        assert!(matches!(e, ShError::Unverified { .. }), "{e}");
        assert!(e.to_string().contains("could not verify"), "{e}");
        // Negative somewhere: U(theta = pi) = 1 - 2 = -1.
        let e = ShSurface::new(
            &[c(0, 0, 1.0, 0.0), c(1, 0, 2.0, 0.0)],
            DVec3::ZERO,
            DMat3::IDENTITY,
            1.0,
        )
        .unwrap_err();
        match e {
            ShError::NotStarShaped { radius, theta, .. } => {
                assert!(radius < 0.0 && (theta - PI).abs() < 0.1)
            }
            e => panic!("{e}"),
        }
    }

    #[test]
    fn constructor_rejects_bad_input() {
        let ok = [c(0, 0, 1.0, 0.0)];
        let i = DMat3::IDENTITY;
        let z = DVec3::ZERO;
        let err = |cs: &[ShCoeff], center: DVec3, rot: DMat3, scale: f64| {
            ShSurface::new(cs, center, rot, scale)
                .unwrap_err()
                .to_string()
        };
        assert!(err(&[], z, i, 1.0).contains("no spherical-harmonic coefficients"));
        assert!(
            err(&[c(0, 0, 1.0, 0.0), c(2, 3, 0.1, 0.0)], z, i, 1.0)
                .contains("order m = 3 exceeds degree k = 2")
        );
        assert!(
            err(&[c(0, 0, 1.0, 0.0), c(1, 1, f64::NAN, 0.0)], z, i, 1.0)
                .contains("a = NaN is not finite")
        );
        assert!(
            err(&[c(0, 0, 1.0, 0.0), c(1, 1, 0.0, f64::INFINITY)], z, i, 1.0)
                .contains("b = inf is not finite")
        );
        assert!(err(&[c(0, 0, 1.0, 0.5)], z, i, 1.0).contains("b = 0.5 must be 0"));
        assert!(
            err(
                &[c(0, 0, 1.0, 0.0), c(1, 1, 0.1, 0.0), c(1, 1, 0.2, 0.0)],
                z,
                i,
                1.0
            )
            .contains("coefficient 2 (k = 1, m = 1) repeats coefficient 1")
        );
        assert!(
            err(&[c(MAX_DEGREE + 1, 0, 1.0, 0.0)], z, i, 1.0)
                .contains("exceeds the supported maximum")
        );
        assert!(err(&ok, DVec3::new(f64::NAN, 0.0, 0.0), i, 1.0).contains("centre"));
        assert!(err(&ok, z, i, 0.0).contains("scale 0 must be finite and > 0"));
        assert!(err(&ok, z, i, f64::INFINITY).contains("scale"));
        assert!(err(&ok, z, i * 1.01, 1.0).contains("R^T R differs"));
        assert!(
            err(
                &ok,
                z,
                DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0)),
                1.0
            )
            .contains("reflection")
        );
        assert!(err(&[c(0, 0, -1.0, 0.0)], z, i, 1.0).contains("not star-shaped"));
        // Trailing zero degrees are dropped; missing pairs are zero.
        let s = ShSurface::new(&[c(0, 0, 1.0, 0.0), c(5, 2, 0.0, 0.0)], z, i, 1.0).unwrap();
        assert_eq!(s.degree(), 0);
        assert_eq!(s.coefficient_count(), 1);
        let b = bumpy(1.0);
        assert_eq!(b.coefficient_count(), 81);
        assert!(b.storage_bytes() >= 81 * 8);
        assert_eq!(b.coefficients().len(), 45);
    }

    // ---------------------------------------------------------------
    // Sphere: degree 0 against the analytic sphere.

    /// First `t` in `(t_min, t_max)` where the ray meets the sphere.
    fn sphere_hit(
        center: DVec3,
        r: f64,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<f64> {
        let p = o - center;
        let tc = -p.dot(d);
        let b = p.cross(d).length();
        if b >= r {
            return None;
        }
        let h = ((r - b) * (r + b)).sqrt();
        [tc - h, tc + h]
            .into_iter()
            .find(|&t| t > t_min && t < t_max)
    }

    /// All sphere checks at one scale; returns the hit distances divided by the scale.
    fn sphere_checks(scale: f64) -> Vec<Option<f64>> {
        let r0 = 1.3;
        let rw = scale * r0;
        let center = scale * DVec3::new(0.3, -0.2, 0.5);
        let rot = rotation();
        let s = ShSurface::new(&[c(0, 0, r0, 0.0)], center, rot, scale).unwrap();
        assert_eq!(s.bounds(), (rw, rw));
        let mut r = Philox4x32::new(21, 0);
        let mut out = Vec::new();
        let check = |o: DVec3, d: DVec3, t_min: f64, t_max: f64, out: &mut Vec<Option<f64>>| {
            let want = sphere_hit(center, rw, o, d, t_min, t_max);
            let got = s.first_hit(o, d, t_min, t_max);
            match (want, got) {
                (None, None) => {}
                (Some(tw), Some((t, n))) => {
                    assert!(
                        (t - tw).abs() <= 1e-12 * rw,
                        "scale {scale}: t {t} vs {tw} (o {o}, d {d})"
                    );
                    let nw = (o + tw * d - center) / rw;
                    assert!((n - nw).length() <= 1e-12, "normal {n} vs {nw}");
                    assert!((s.normal(o + tw * d) - nw).length() <= 1e-12);
                }
                (w, g) => panic!("scale {scale}: analytic {w:?}, got {g:?} (o {o}, d {d})"),
            }
            assert_eq!(s.crosses(o, d, t_min, t_max), want.is_some());
            out.push(got.map(|(t, _)| t / scale));
        };
        // From outside, aimed near the sphere (hits and misses).
        for _ in 0..400 {
            let o = center + rw * (1.2 + 2.0 * r.next_f64()) * unit(&mut r);
            let target = center + rw * 1.3 * r.next_f64() * unit(&mut r);
            check(o, (target - o).normalize(), 0.0, f64::INFINITY, &mut out);
        }
        // From inside (random, and from the centre).
        for _ in 0..200 {
            let o = center + rw * 0.99 * r.next_f64().cbrt() * unit(&mut r);
            check(o, unit(&mut r), 0.0, f64::INFINITY, &mut out);
        }
        let d = unit(&mut r);
        check(center, d, 0.0, f64::INFINITY, &mut out);
        // Through the centre, and through the poles (local +-z) from outside and inside.
        check(center - 3.0 * rw * d, d, 0.0, f64::INFINITY, &mut out);
        let w = rot * DVec3::Z;
        for pole in [w, -w] {
            check(
                center + 3.0 * rw * pole,
                -pole,
                0.0,
                f64::INFINITY,
                &mut out,
            );
            check(center + 0.5 * rw * pole, pole, 0.0, f64::INFINITY, &mut out);
            check(center - 0.5 * rw * pole, pole, 0.0, f64::INFINITY, &mut out);
            let (t, n) = s
                .first_hit(center + 3.0 * rw * pole, -pole, 0.0, f64::INFINITY)
                .unwrap();
            assert!((t - 2.0 * rw).abs() <= 1e-12 * rw && (n - pole).length() <= 1e-12);
        }
        // Grazing: passing 1e-6 R inside / outside the sphere; exactly tangent.
        for _ in 0..50 {
            let d = unit(&mut r);
            let e = tangent(&mut r, d);
            for b in [1.0 - 1e-6, 1.0 + 1e-6, 1.0 - 1e-3] {
                check(
                    center + rw * b * e - 3.0 * rw * d,
                    d,
                    0.0,
                    f64::INFINITY,
                    &mut out,
                );
            }
            // 1e-12 R inside: still a chord of 1.4e-6 R, found; t ill-conditioned.
            let o = center + rw * (1.0 - 1e-12) * e - 3.0 * rw * d;
            let (t, _) = s
                .first_hit(o, d, 0.0, f64::INFINITY)
                .expect("near-tangent hit");
            assert!((t - 3.0 * rw).abs() <= 2e-6 * rw);
            // Tangent: either answer, finite and near the tangent point.
            if let Some((t, n)) = s.first_hit(center + rw * e - 3.0 * rw * d, d, 0.0, f64::INFINITY)
            {
                assert!((t - 3.0 * rw).abs() <= 1e-5 * rw && n.is_finite());
            }
        }
        // Segment limits: stops before the sphere; starts between entry and exit.
        let o = center - 3.0 * rw * d;
        check(o, d, 0.0, 1.5 * rw, &mut out);
        check(o, d, 2.5 * rw, f64::INFINITY, &mut out);
        check(o, d, 3.5 * rw, 4.5 * rw, &mut out);
        // Starting on the surface: leaving outward nothing; inward the far side.
        for _ in 0..100 {
            let n = unit(&mut r);
            let x = center + rw * n;
            let e = tangent(&mut r, n);
            let out_dir = (n + e * (2.0 * r.next_f64() - 1.0) * 3.0).normalize();
            let out_dir = if out_dir.dot(n) > 0.0 {
                out_dir
            } else {
                -out_dir
            };
            assert!(s.first_hit(x, out_dir, 0.0, f64::INFINITY).is_none());
            let (t, nn) = s
                .first_hit(x, -out_dir, 0.0, f64::INFINITY)
                .expect("far side");
            let tw = 2.0 * rw * out_dir.dot(n);
            assert!(
                (t - tw).abs() <= 1e-12 * rw
                    && (nn - (x - out_dir * tw - center) / rw).length() <= 1e-12
            );
            // Shadow segment between two surface points: no crossing inside it.
            assert!(!s.crosses(x, -out_dir, 0.0, t));
            assert!(!s.crosses(x, -out_dir, 0.0, tw));
            // Through the surface and beyond: crossing.
            assert!(s.crosses(x, -out_dir, 0.0, 1.5 * tw));
        }
        out
    }

    #[test]
    fn degree_zero_is_the_analytic_sphere_at_every_scale() {
        let base = sphere_checks(1.0);
        for scale in [1e-3, 1e4] {
            let other = sphere_checks(scale);
            assert_eq!(base.len(), other.len());
            for (a, b) in base.iter().zip(&other) {
                match (a, b) {
                    (None, None) => {}
                    (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-12 * 1.3, "{a} vs {b}"),
                    _ => panic!("scale {scale}: {a:?} vs {b:?}"),
                }
            }
        }
    }

    // ---------------------------------------------------------------
    // Bumpy shape against brute force.

    /// Brute force: sample `f` on `n` uniform steps over the part of
    /// `(t_min, t_max)` inside a ball of radius `1.001 r_max`, bisect the
    /// first sign change. Returns the first crossing and the grid spacing.
    fn brute_first(
        s: &ShSurface,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        n: usize,
    ) -> (Option<f64>, f64) {
        let rb = 1.001 * s.bounds().1;
        let p = o - s.center();
        let tc = -p.dot(d);
        let b = p.cross(d).length();
        if b >= rb {
            return (None, 0.0);
        }
        let h = ((rb - b) * (rb + b)).sqrt();
        let (t0, t1) = (t_min.max(tc - h), t_max.min(tc + h));
        if t0 >= t1 {
            return (None, 0.0);
        }
        let f = |t: f64| s.level(o + t * d);
        let sign = f(t0).signum();
        let dt = (t1 - t0) / n as f64;
        let mut prev = t0;
        for i in 1..=n {
            let t = if i == n { t1 } else { t0 + dt * i as f64 };
            if f(t) * sign <= 0.0 {
                if i == n && t == t_max {
                    break;
                }
                let (mut lo, mut hi) = (prev, t);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if f(mid) * sign > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return (Some(hi), dt);
            }
            prev = t;
        }
        (None, dt)
    }

    /// A random surface point (world) and its outward normal.
    fn surface_point(s: &ShSurface, r: &mut Philox4x32) -> (DVec3, DVec3) {
        let y = unit(r);
        let x = s.center() + s.scale() * s.radius(y) * (s.rotation() * y);
        (x, s.normal(x))
    }

    #[derive(Default, Debug)]
    struct Stats {
        rays: usize,
        hits: usize,
        thin: usize,
        touch: usize,
        steps: usize,
        max_steps: usize,
    }

    /// Compare `first_hit` with brute force on one ray; updates stats.
    fn compare(
        s: &ShSurface,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        n: usize,
        st: &mut Stats,
    ) {
        let rw = s.bounds().1;
        let (got, steps) = s.first_hit_counted(o, d, t_min, t_max);
        st.rays += 1;
        st.steps += steps;
        st.max_steps = st.max_steps.max(steps);
        let (want, dt) = brute_first(s, o, d, t_min, t_max, n);
        assert_eq!(
            s.crosses(o, d, t_min, t_max),
            got.is_some(),
            "crosses vs first_hit (o {o}, d {d})"
        );
        if let Some((t, nrm)) = got {
            st.hits += 1;
            assert!(t > t_min && t < t_max);
            let x = o + t * d;
            assert!(
                s.level(x).abs() <= 1e-11 * rw,
                "not on the surface: {}",
                s.level(x)
            );
            assert!((nrm - s.normal(x)).length() <= 1e-12 && (nrm.length() - 1.0).abs() < 1e-14);
        }
        // Root tolerance: 1e-9 of the radius, wider where the ray is nearly
        // tangent (a level error of ~1e-16 R moves the root by ~1e-16 R / |n.d|).
        let tol = |t: f64| {
            let slope = s.normal(o + t * d).dot(d).abs();
            1e-9 * rw + 1e-14 * rw / slope.max(1e-300)
        };
        match (want, got) {
            (None, None) => {}
            (Some(tb), None) => {
                panic!("missed a hit: brute {tb} (o {o}, d {d}, t in ({t_min}, {t_max}))")
            }
            (Some(tb), Some((t, _))) if (t - tb).abs() <= tol(t) => {}
            (Some(tb), Some((t, _))) if tb < t => {
                panic!("brute force found an earlier hit: {tb} < {t} (o {o}, d {d})")
            }
            (_, Some((t, _))) => {
                // An earlier crossing pair thinner than the brute-force grid:
                // confirm a sign change near t on a grid 1000 times finer.
                st.thin += 1;
                let (w, _) = brute_first(s, o, d, (t - 2.0 * dt).max(t_min), t + 2.0 * dt, 4000);
                let slope = s.normal(o + t * d).dot(d);
                let level = s.level(o + t * d);
                match w {
                    Some(w) => assert!((w - t).abs() <= tol(t), "thin crossing at {w} vs {t}"),
                    // A tangent touch: the level dips below zero by rounding only.
                    None if slope.abs() <= 1e-6 && level.abs() <= 1e-14 * rw => st.touch += 1,
                    None => {
                        panic!("thin crossing not confirmed: t {t}, slope {slope}, level {level}")
                    }
                }
            }
        }
    }

    #[test]
    fn bumpy_random_rays_agree_with_brute_force() {
        let s = bumpy(1.0);
        let (_, rmax) = s.bounds();
        let c0 = s.center();
        let mut r = Philox4x32::new(31, 0);
        let mut st = Stats::default();
        for i in 0..3000 {
            let (o, d, t_max) = match i % 4 {
                0 | 1 => {
                    // From outside, aimed into the bounding ball.
                    let o = c0 + rmax * (1.1 + 2.0 * r.next_f64()) * unit(&mut r);
                    let target = c0 + rmax * 1.05 * r.next_f64() * unit(&mut r);
                    let t_max = if i % 8 == 1 {
                        3.0 * rmax * r.next_f64()
                    } else {
                        f64::INFINITY
                    };
                    (o, (target - o).normalize(), t_max)
                }
                2 => {
                    // From inside the solid.
                    let y = unit(&mut r);
                    let o = c0 + s.scale() * s.radius(y) * 0.99 * r.next_f64() * (s.rotation() * y);
                    (o, unit(&mut r), f64::INFINITY)
                }
                _ => {
                    // Skimming: near-tangent to the surface at a random point.
                    let (x, n) = surface_point(&s, &mut r);
                    let e = tangent(&mut r, n);
                    let d = (e + n * 0.02 * (2.0 * r.next_f64() - 1.0)).normalize();
                    let o = x + n * rmax * 1e-3 * (2.0 * r.next_f64() - 1.0) - 2.0 * rmax * d;
                    (o, d, f64::INFINITY)
                }
            };
            compare(&s, o, d, 0.0, t_max, 4000, &mut st);
        }
        eprintln!(
            "bumpy random rays: {st:?}, mean evaluations per ray {:.1}",
            st.steps as f64 / st.rays as f64
        );
        assert!(st.hits > st.rays / 3, "too few hits to be a test: {st:?}");
        assert!(st.thin <= st.rays / 100, "{st:?}");
        assert!(st.max_steps < 5000, "{st:?}");
    }

    #[test]
    fn bumpy_grazing_inside_centre_and_pole_rays() {
        let s = bumpy(1.0);
        let (_, rmax) = s.bounds();
        let c0 = s.center();
        let rot = s.rotation();
        let mut r = Philox4x32::new(41, 0);
        let mut st = Stats::default();
        // Grazing at 1e-7 and 1e-4 of the radius above / below the tangent plane, and on it.
        for _ in 0..30 {
            let (x, n) = surface_point(&s, &mut r);
            let e = tangent(&mut r, n);
            for eps in [1e-7, -1e-7, 1e-4, -1e-4, 0.0] {
                let o = x + n * rmax * eps - 2.0 * rmax * e;
                compare(&s, o, e, 0.0, f64::INFINITY, 30_000, &mut st);
            }
        }
        // Rays starting on the surface: leaving outward / inward (no hit at the start).
        for _ in 0..100 {
            let (x, n) = surface_point(&s, &mut r);
            let e = tangent(&mut r, n);
            for sign in [1.0, -1.0] {
                let d = (n * sign + e * 2.0 * r.next_f64()).normalize();
                let got = s.first_hit(x, d, 0.0, f64::INFINITY);
                if let Some((t, _)) = got {
                    assert!(t > 1e-6 * rmax, "self-hit at t = {t}");
                }
                let (want, _) = brute_first(&s, x, d, 1e-6 * rmax, f64::INFINITY, 10_000);
                match (want, got) {
                    (None, None) => {}
                    (Some(tb), Some((t, _))) => {
                        assert!((t - tb).abs() <= 1e-9 * rmax, "{t} vs {tb}")
                    }
                    (w, g) => panic!("on-surface start: brute {w:?}, got {g:?}"),
                }
            }
        }
        // Radial rays: from the centre, through the centre, through the poles.
        for i in 0..200 {
            let y = match i {
                0 => DVec3::Z,
                1 => -DVec3::Z,
                _ => unit(&mut r),
            };
            let w = rot * y;
            let u = s.scale() * s.radius(y);
            let (t, n) = s.first_hit(c0, w, 0.0, f64::INFINITY).unwrap();
            assert!((t - u).abs() <= 1e-12 * rmax, "from the centre: {t} vs {u}");
            assert!(n.dot(w) > 0.0 && (n - s.normal(c0 + u * w)).length() <= 1e-12);
            let (t, _) = s
                .first_hit(c0 + 3.0 * rmax * w, -w, 0.0, f64::INFINITY)
                .unwrap();
            assert!(
                (t - (3.0 * rmax - u)).abs() <= 1e-12 * rmax,
                "radial from outside: {t}"
            );
            // Through the centre from the other side.
            let u_back = s.scale() * s.radius(-y);
            let (t, _) = s
                .first_hit(c0 + 0.5 * u_back * -w, w, 0.0, f64::INFINITY)
                .unwrap();
            assert!(
                (t - (0.5 * u_back + u)).abs() <= 1e-12 * rmax,
                "through the centre: {t}"
            );
            compare(
                &s,
                c0 - 3.0 * rmax * w,
                w,
                0.0,
                f64::INFINITY,
                4000,
                &mut st,
            );
        }
        // Shadow segments between surface points: crosses iff brute force finds
        // a sign change strictly inside (ends excluded by 1e-6 of the radius).
        for _ in 0..200 {
            let (x1, _) = surface_point(&s, &mut r);
            let (x2, _) = surface_point(&s, &mut r);
            let len = (x2 - x1).length();
            let d = (x2 - x1) / len;
            let (want, _) = brute_first(&s, x1, d, 1e-6 * rmax, len - 1e-6 * rmax, 10_000);
            assert_eq!(
                s.crosses(x1, d, 0.0, len),
                want.is_some(),
                "segment {x1} -> {x2}"
            );
        }
        eprintln!("bumpy special rays: {st:?}");
        assert!(st.max_steps < 5000, "{st:?}");
    }

    #[test]
    fn bumpy_is_scale_invariant() {
        let base = bumpy(1.0);
        let mut r = Philox4x32::new(51, 0);
        let rays: Vec<(DVec3, DVec3)> = (0..500)
            .map(|_| {
                let o = base.center() + 3.0 * unit(&mut r);
                let target = base.center() + 1.7 * r.next_f64() * unit(&mut r);
                (o, (target - o).normalize())
            })
            .collect();
        for scale in [1e-3, 1e4] {
            let s = bumpy(scale);
            for &(o, d) in &rays {
                let a = base.first_hit(o, d, 0.0, f64::INFINITY);
                let b = s.first_hit(o * scale, d, 0.0, f64::INFINITY);
                match (a, b) {
                    (None, None) => {}
                    (Some((ta, na)), Some((tb, nb))) => {
                        assert!((ta - tb / scale).abs() <= 1e-10, "{ta} vs {}", tb / scale);
                        assert!((na - nb).length() <= 1e-9);
                    }
                    _ => panic!("scale {scale}: {a:?} vs {b:?}"),
                }
            }
        }
    }

    #[test]
    fn normals_match_finite_differences_and_pole_limits() {
        let s = bumpy(1.0);
        let (_, rmax) = s.bounds();
        let mut r = Philox4x32::new(61, 0);
        let fd_normal = |x: DVec3| {
            let h = 1e-5 * rmax;
            let g = DVec3::new(
                s.level(x + DVec3::X * h) - s.level(x - DVec3::X * h),
                s.level(x + DVec3::Y * h) - s.level(x - DVec3::Y * h),
                s.level(x + DVec3::Z * h) - s.level(x - DVec3::Z * h),
            );
            g.normalize()
        };
        let rot = s.rotation();
        let on = |y: DVec3| s.center() + s.scale() * s.radius(y) * (rot * y.normalize());
        for _ in 0..300 {
            let x = on(unit(&mut r));
            let n = s.normal(x);
            assert!(
                (n - fd_normal(x)).length() <= 1e-7,
                "normal {n} vs fd {}",
                fd_normal(x)
            );
        }
        for pole in [DVec3::Z, -DVec3::Z] {
            let xp = on(pole);
            let np = s.normal(xp);
            assert!(
                (np - fd_normal(xp)).length() <= 1e-7,
                "pole {pole}: {np} vs fd {}",
                fd_normal(xp)
            );
            // Nearby points on all sides converge to the pole normal.
            for eps in [1e-4, 1e-6, 1e-8] {
                for j in 0..12 {
                    let phi = 2.0 * PI * j as f64 / 12.0;
                    let y = DVec3::new(eps * phi.cos(), eps * phi.sin(), pole.z);
                    let dn = (s.normal(on(y)) - np).length();
                    assert!(dn <= 100.0 * eps, "pole {pole}, eps {eps}, phi {phi}: {dn}");
                }
            }
        }
    }

    // ---------------------------------------------------------------
    // Fit and files.

    fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
        let golden = PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let s = (1.0 - z * z).sqrt();
                let (sp, cp) = (golden * i as f64).sin_cos();
                DVec3::new(s * cp, s * sp, z)
            })
            .collect()
    }

    #[test]
    fn fit_recovers_exact_coefficients() {
        let truth = bumpy_coeffs(4, 0.1, 5);
        let center = DVec3::new(1.0, -2.0, 0.5);
        let s = ShSurface::new(&truth, center, DMat3::IDENTITY, 1.0).unwrap();
        let pts: Vec<DVec3> = fibonacci_sphere(800)
            .into_iter()
            .map(|y| center + s.radius(y) * y)
            .collect();
        let f = fit(&pts, center, 4).unwrap();
        assert_eq!(f.coeffs.len(), 15);
        for (t, g) in truth.iter().zip(&f.coeffs) {
            assert_eq!((t.k, t.m), (g.k, g.m));
            assert!(
                (t.a - g.a).abs() <= 1e-10 && (t.b - g.b).abs() <= 1e-10,
                "{t:?} vs {g:?}"
            );
        }
        assert!(f.rms_residual <= 1e-12 && f.max_residual <= 1e-11, "{f:?}");
        let mean = pts.iter().map(|p| (*p - center).length()).sum::<f64>() / pts.len() as f64;
        assert!((f.mean_radius - mean).abs() <= 1e-14);
        // Higher degree: the extra coefficients vanish.
        let f6 = fit(&pts, center, 6).unwrap();
        assert!(
            f6.coeffs
                .iter()
                .filter(|c| c.k > 4)
                .all(|c| c.a.abs() < 1e-10 && c.b.abs() < 1e-10)
        );
        // Lower degree: a positive residual.
        let f3 = fit(&pts, center, 3).unwrap();
        assert!(
            f3.rms_residual > 1e-4 && f3.max_residual >= f3.rms_residual,
            "{f3:?}"
        );
        // The fitted coefficients make a surface.
        let back = ShSurface::new(&f.coeffs, center, DMat3::IDENTITY, 1.0).unwrap();
        let y = DVec3::new(0.3, -0.4, 0.5).normalize();
        assert!((back.radius(y) - s.radius(y)).abs() <= 1e-11);
    }

    #[test]
    fn fit_rejects_bad_input() {
        let c0 = DVec3::ZERO;
        let pts = fibonacci_sphere(10);
        assert!(matches!(
            fit(&pts, c0, 3),
            Err(ShError::TooFewPoints { needed: 16, .. })
        ));
        let mut bad = fibonacci_sphere(50);
        bad[7] = c0;
        assert!(matches!(
            fit(&bad, c0, 2),
            Err(ShError::PointAtCenter { index: 7 })
        ));
        bad[7] = DVec3::new(f64::NAN, 0.0, 0.0);
        assert!(matches!(
            fit(&bad, c0, 2),
            Err(ShError::PointNotFinite { index: 7, .. })
        ));
        // All points on the equator: P_1^0 = 0 there, so a_10 is undetermined.
        let ring: Vec<DVec3> = (0..100)
            .map(|i| {
                let (s, c) = (2.0 * PI * i as f64 / 100.0).sin_cos();
                DVec3::new(c, s, 0.0)
            })
            .collect();
        let e = fit(&ring, c0, 2).unwrap_err();
        assert!(matches!(e, ShError::IllConditioned { .. }), "{e}");
    }

    #[test]
    fn coefficient_files_round_trip_and_report_bad_lines() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("coeffs.csv");
        let coeffs = bumpy_coeffs(3, 0.1, 9);
        write_coefficients(&path, &coeffs).unwrap();
        assert_eq!(read_coefficients(&path).unwrap(), coeffs);

        let bad = |text: &str| {
            let p = dir.path().join("bad.csv");
            std::fs::write(&p, text).unwrap();
            let e = read_coefficients(&p).unwrap_err().to_string();
            let name = p.to_string_lossy().into_owned();
            assert!(e.starts_with(&name), "{e}");
            e
        };
        let e = bad("k,m,a,b\n0,0,1,0\n1,x,0.1,0\n");
        assert!(
            e.contains(":3: field `m`: `x` is not a non-negative integer"),
            "{e}"
        );
        let e = bad("k,m,a,b\n0,0,1,0\n1,-1,0.1,0\n");
        assert!(e.contains(":3: field `m`"), "{e}");
        let e = bad("k,m,a,b\n0,0,1,0\n1,1,abc,0\n");
        assert!(e.contains(":3: field `a`: `abc` is not a number"), "{e}");
        let e = bad("k,m,a,b\n0,0,1,0\n1,1,0.1,inf\n");
        assert!(e.contains(":3: field `b`: `inf` is not finite"), "{e}");
        let e = bad("k,m,a,b\n0,0,1,0\n2,3,0.1,0\n");
        assert!(
            e.contains(":3: field `m`: order m = 3 exceeds degree k = 2"),
            "{e}"
        );
        let e = bad("k,m,a,b\n0,0,1,0.5\n");
        assert!(
            e.contains(":2: field `b`: b = 0.5 must be 0 at m = 0"),
            "{e}"
        );
        let e = bad("k,m,a,b\n0,0,1,0\n1,1,0.1,0\n1,1,0.2,0\n");
        assert!(
            e.contains(":4: field `k,m`: (k, m) = (1, 1) repeats line 3"),
            "{e}"
        );
        let e = bad("k,m,a,b\n101,0,1,0\n");
        assert!(e.contains(":2: field `k`: degree 101 exceeds"), "{e}");
        let e = bad("k,m,a\n0,0,1\n");
        assert!(e.contains("missing column `b`"), "{e}");
        let e = bad("0,0,1,0\n1,0,0.1,0\n");
        assert!(e.contains("missing column `k`"), "{e}");
        let e = bad("k,m,a,b\n");
        assert!(e.contains("no coefficients in the file"), "{e}");
        // Extra columns and any column order are fine.
        let p = dir.path().join("order.csv");
        std::fs::write(&p, "b,a,id,m,k\n0,1.5,x,0,0\n0.25,0,y,1,1\n").unwrap();
        assert_eq!(
            read_coefficients(&p).unwrap(),
            vec![c(0, 0, 1.5, 0.0), c(1, 1, 0.0, 0.25)]
        );
    }

    /// Cost of one `first_hit` on the bumpy shape:
    /// `cargo test --release -p lumest --lib geometry::sh::tests::bench_first_hit -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn bench_first_hit() {
        let s = bumpy(1.0);
        let (_, rmax) = s.bounds();
        let mut r = Philox4x32::new(71, 0);
        let rays: Vec<(DVec3, DVec3)> = (0..200_000)
            .map(|_| {
                let o = s.center() + 3.0 * rmax * unit(&mut r);
                let target = s.center() + rmax * r.next_f64() * unit(&mut r);
                (o, (target - o).normalize())
            })
            .collect();
        let (mut best, mut best_level) = (f64::INFINITY, f64::INFINITY);
        let (mut hits, mut evals, mut sum) = (0usize, 0usize, 0.0);
        for _ in 0..5 {
            let t0 = std::time::Instant::now();
            (hits, evals) = (0, 0);
            for &(o, d) in &rays {
                let (h, n) = s.first_hit_counted(o, d, 0.0, f64::INFINITY);
                hits += usize::from(h.is_some());
                evals += n;
            }
            best = best.min(t0.elapsed().as_secs_f64());
            let t1 = std::time::Instant::now();
            for &(o, _) in &rays {
                sum += s.level(o);
            }
            best_level = best_level.min(t1.elapsed().as_secs_f64());
        }
        let n = rays.len() as f64;
        eprintln!(
            "first_hit: {:.0} ns/ray ({hits} hits of {n}), {:.1} level evaluations/ray; level: {:.0} ns ({sum:.1}); best of 5",
            best / n * 1e9,
            evals as f64 / n,
            best_level / n * 1e9
        );
    }
}
