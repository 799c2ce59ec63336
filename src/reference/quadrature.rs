//! Oscillatory Hankel-type quadrature (written in the project: no crate does it).
//!
//! Two ways to evaluate a zero-order Hankel integral
//!
//! ```text
//! T(r) = ∫_0^∞ F(k) J0(k r) k dk        (k in 1/m, r in m)
//! ```
//!
//! for a spectrum `F` that is smooth for `k > 0`, has a mild `k² ln k`
//! singularity at `k = 0` and decays like `e^{-H k}`:
//!
//! * [`hankel_real`]: along the real axis. Gauss–Legendre panels, graded
//!   geometrically (ratio 2) towards `k = 0`, then of constant width
//!   `min(π/r, 1/(2H))` (at most half a period of `J0(k r)`, at most half the
//!   spectral scale). Panels are summed with Neumaier compensation and the
//!   march stops at the first panel end `k0` where a caller-supplied rigorous
//!   bound of `∫_{k0}^∞ |F(k)| k dk` (using `|J0| ≤ 1`) is below the tolerance.
//! * [`hankel_contour`]: along the imaginary axis. With `J0 = Re H0⁽¹⁾` and `F`
//!   analytic in the strip `0 ≤ Im k ≤ c`, Cauchy moves the path to
//!   `[0, i c] ∪ [i c, i c + ∞)`. On the horizontal leg `|H0⁽¹⁾(k r)| ≲ e^{-c r}`,
//!   so with `L = c r ≳ 50` it is negligible and, using
//!   `H0⁽¹⁾(i y r) = -(2i/π) K0(y r)`,
//!
//!   ```text
//!   T(r) = -(2/(π r²)) ∫_0^L Im F(i s/r) s K0(s) ds .
//!   ```
//!
//!   The integrand no longer oscillates and does not cancel, so the result has
//!   full relative accuracy even where `T(r)` is 10⁻¹² of the integrand scale
//!   on the real axis. Panels are geometric in `s` (ratio 1.15) from `s = 10⁻⁵`.
//!
//! Why panels rather than zeros of `J0`: the integrand decays exponentially,
//! so no series acceleration over half-periods is needed and panel ends need
//! not sit on the zeros (McMahon) of `J0(k r)`; what matters for Gauss–Legendre
//! is only that every panel is short compared with the distance to the nearest
//! singularity of the integrand (the branch point at 0, complex poles of `F`),
//! which the grading ensures.
//!
//! Why exact phases on the real axis: `pxfm::f_j0` is correctly rounded for
//! its argument, but the argument `k r` itself is rounded, a phase error
//! `~k r · 2⁻⁵³` per node. In an integral that cancels to `10⁻⁴…10⁻¹⁰` of its
//! absolute value these errors dominate (they limited `r = 100 H` to 1e-10).
//! When `π/r` is the panel width, panel `j` spans `k r ∈ [jπ/R, (j+1)π/R]`
//! and [`j0_phase`] evaluates `J0` at `jπ/R + t` without ever rounding the
//! large part of the phase (Hankel expansion with an exact rotation for
//! `k r ≥ 30`, a first-order `J1` correction below); the half-width of the
//! panels is passed exactly, not recomputed from rounded ends. What remains
//! is the rounding of `F` itself (~`k h · 2⁻⁵³` through `e^{-k h}`): about
//! 1e-13 relative at `r = 30 H`, 1e-11 at `100 H`, 1e-10 at `1000 H`.
//!
//! Why the contour for large `r`: it has no phase at all, no cancellation,
//! and costs ~2 k evaluations whatever `r` is; the real-axis cost grows like
//! `r/H`.

use gauss_quad::GaussLegendre;
use std::num::NonZeroUsize;

/// Compensated (Neumaier / Kahan–Babuška) summation (shared with [`crate::math::quadrature`]).
pub use crate::math::quadrature::CompensatedSum as Neumaier;

/// Gauss–Legendre nodes and weights on `[-1, 1]` (from `gauss-quad`).
#[derive(Clone, Debug)]
pub struct Rule {
    /// Nodes in `[-1, 1]`.
    pub x: Vec<f64>,
    /// Weights (sum 2).
    pub w: Vec<f64>,
}

impl Rule {
    /// The `n`-point rule; panics if `n == 0`.
    pub fn new(n: usize) -> Self {
        let n = NonZeroUsize::new(n).expect("Gauss-Legendre rule needs n >= 1");
        let gl = GaussLegendre::new(n);
        let (x, w) = gl.as_node_weight_pairs().iter().copied().unzip();
        Self { x, w }
    }
    /// `∫_a^b f` for a smooth scalar `f`.
    pub fn integrate(&self, a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
        let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
        let s: f64 = self
            .x
            .iter()
            .zip(&self.w)
            .map(|(x, w)| w * f(m + h * x))
            .sum();
        s * h
    }
}

/// Discretisation knobs shared by both paths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadOptions {
    /// Gauss–Legendre nodes per panel (default 16).
    pub nodes: usize,
    /// Panel refinement: widths divided by `refine`, grading ratios replaced
    /// by their `refine`-th root (default 1). Used by convergence checks.
    pub refine: u32,
}

impl Default for QuadOptions {
    fn default() -> Self {
        Self {
            nodes: 16,
            refine: 1,
        }
    }
}

/// `T_c(r) = ∫_0^∞ F_c(k) J0(k r) k dk` for `m` spectra at once, along the
/// real axis.
///
/// * `k_scale` \[1/m\]: spectral scale, `1/H`; panel widths are at most
///   `min(π/r, k_scale/2)`; where `π/r` is the smaller, `J0` is evaluated
///   with exact phase ([`j0_phase`]).
/// * `k_first` \[1/m\]: end of the first panel `[0, k_first]`; panels grow by
///   ratio 2 from there to the constant width (resolves the `k² ln k` branch
///   point and features of size `~k_first`).
/// * `tol[c]` [same unit as `T`]: stop when `tail(k0)[c] ≤ tol[c]` for all `c`.
/// * `f(k, out)` writes `F_c(k)`; `tail(k0, out)` writes an upper bound of
///   `∫_{k0}^∞ |F_c(k)| k dk`.
///
/// Panics if the tail bound is not met after 10⁷ panels.
#[allow(clippy::too_many_arguments)]
pub fn hankel_real(
    r: f64,
    k_scale: f64,
    k_first: f64,
    m: usize,
    opts: &QuadOptions,
    tol: &[f64],
    mut f: impl FnMut(f64, &mut [f64]),
    mut tail: impl FnMut(f64, &mut [f64]),
) -> Vec<f64> {
    let rule = Rule::new(opts.nodes);
    let rf = opts.refine.max(1);
    // constant panel width; grading ratio
    let half_period = std::f64::consts::PI / r < 0.5 * k_scale;
    let w = (std::f64::consts::PI / r).min(0.5 * k_scale) / rf as f64;
    let ratio = 2f64.powf(1.0 / rf as f64);
    // graded ends, from k_first up to w
    let mut ends = vec![];
    let mut e = k_first.min(w);
    while e < w {
        ends.push(e);
        e *= ratio;
    }
    ends.push(w);
    let mut acc = vec![Neumaier::default(); m];
    let mut buf = vec![0.0; m];
    let mut part = vec![0.0; m];
    // one panel [a, b] into acc; `j` = Some(index) for a panel [jπ/(R r), (j+1)π/(R r)]
    // (half-width passed exactly: recomputing it from rounded panel ends
    // would add a relative error ~ n·2⁻⁵³ to panel n)
    let mut panel = |a: f64,
                     h: f64,
                     j: Option<u64>,
                     acc: &mut [Neumaier],
                     buf: &mut [f64],
                     part: &mut [f64]| {
        let mid = a + h;
        part.iter_mut().for_each(|p| *p = 0.0);
        for (x, wt) in rule.x.iter().zip(&rule.w) {
            let (k, j0) = match j {
                // exact phase: k r = jπ/R + t
                Some(j) => {
                    let t = (1.0 + x) * (0.5 * std::f64::consts::PI / rf as f64);
                    let xr = j as f64 * std::f64::consts::PI / rf as f64 + t;
                    (xr / r, j0_phase(j, rf, t, xr))
                }
                None => {
                    let k = mid + h * x;
                    (k, pxfm::f_j0(k * r))
                }
            };
            f(k, buf);
            let jk = j0 * k * wt;
            for (p, v) in part.iter_mut().zip(buf.iter()) {
                *p += v * jk;
            }
        }
        for (s, p) in acc.iter_mut().zip(part.iter()) {
            s.add(p * h);
        }
    };
    let mut a = 0.0;
    for &b in &ends {
        panel(a, 0.5 * (b - a), None, &mut acc, &mut buf, &mut part);
        a = b;
    }
    // constant-width panels until the tail bound is met
    let mut n = 0u64;
    loop {
        tail(a, &mut buf);
        if buf.iter().zip(tol).all(|(t, tl)| *t <= *tl) {
            break;
        }
        n += 1;
        assert!(n < 10_000_000, "hankel_real: tail bound not met by k = {a}");
        panel(
            a,
            0.5 * w,
            half_period.then_some(n),
            &mut acc,
            &mut buf,
            &mut part,
        );
        a = w * (n + 1) as f64;
    }
    acc.iter().map(Neumaier::total).collect()
}

/// `J0(x)` at `x = jπ/R + t` (`0 ≤ t ≤ π/R`) with the phase `x − π/4`
/// reduced exactly: the Hankel expansion
/// `J0(x) = √(2/(πx)) (P0(x) cos(x − π/4) − Q0(x) sin(x − π/4))` for
/// `x ≥ 30` (terms summed while above 1e-18; the series' own limit, about
/// `e^{-2x}`, is far below that), and below 30 `pxfm::f_j0` at the rounded
/// argument plus a first-order `J1` correction for the rounding.
///
/// Why: `f_j0(k·r)` is correctly rounded for its argument, but the argument
/// `k·r` itself carries an error `~x·2⁻⁵³`, i.e. a phase error that grows with
/// `x`; here the large part `jπ/R` of the phase is never rounded.
pub fn j0_phase(j: u64, rf: u32, t: f64, x: f64) -> f64 {
    let pi = std::f64::consts::PI;
    if x < 30.0 {
        // x_true = jπ/R + t exactly (π = PI + PI_LO, j·PI split by fma);
        // J0(x_true) = J0(x) − J1(x)(x_true − x) to first order
        const PI_LO: f64 = 1.224_646_799_147_353_2e-16;
        let (jf, rr) = (j as f64, rf as f64);
        let p = jf * pi;
        let e = jf.mul_add(pi, -p) + jf * PI_LO;
        let a = p / rr;
        let xd = a + t;
        let err = (a - xd) + t + (e - a.mul_add(rr, -p)) / rr;
        return pxfm::f_j0(xd) - pxfm::f_j1(xd) * err;
    }
    let (p, q) = hankel_pq(x);
    // χ = x − π/4 = jπ/R + ψ; rotate (cos ψ, sin ψ) by jπ/R
    let (sp, cp) = (t - 0.25 * pi).sin_cos();
    let (sj, cj) = rot(j % (2 * rf as u64), rf);
    let (c, s) = (cj * cp - sj * sp, sj * cp + cj * sp);
    (2.0 / (pi * x)).sqrt() * (p * c - q * s)
}

// (sin, cos) of mπ/R, exact where mπ/R is a multiple of π/2.
// Why: a rounded π here would shift the phase of every other panel by the
// same 1e-16, an error that does not cancel in the alternating panel sum.
fn rot(m: u64, rf: u32) -> (f64, f64) {
    let rf = rf as u64;
    if (2 * m).is_multiple_of(rf) {
        return match (2 * m / rf) % 4 {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        };
    }
    (m as f64 * std::f64::consts::PI / rf as f64).sin_cos()
}

// P0(x), Q0(x) of the Hankel expansion, x ≥ 30
fn hankel_pq(x: f64) -> (f64, f64) {
    // b_k = (-1)^k a_k(0)/x^k with a_k(0) = ∏(−(2i−1)²)/(k! 8^k): P sums even k, Q odd k with signs
    let (mut p, mut q) = (1.0, 0.0);
    let mut b = 1.0; // |a_k| / x^k
    for k in 1..60 {
        let kk = k as f64;
        b *= (2.0 * kk - 1.0) * (2.0 * kk - 1.0) / (8.0 * kk * x);
        // a_k(0) has sign (−1)^k; P = Σ (−1)^m a_{2m}, Q = Σ (−1)^m a_{2m+1}
        match k % 4 {
            1 => q -= b,
            2 => p -= b,
            3 => q += b,
            _ => p += b,
        }
        if b < 1e-18 {
            break;
        }
    }
    (p, q)
}

/// `T_c(r) = -(2/(π r²)) ∫_0^L g_c(s/r) s K0(s) ds`, the imaginary-axis form
/// of `∫_0^∞ F_c(k) J0(k r) k dk`, where `g(y, out)` writes `Im F_c(i y)`
/// (`y` in 1/m). Valid when every `F_c` is real on the real axis and analytic
/// in the strip `0 ≤ Im k ≤ L/r`, with `L` large enough that
/// `e^{-L}·sup|F_c|` on the line `Im k = L/r` is negligible (the caller
/// chooses `L`; see the module doc).
pub fn hankel_contour(
    r: f64,
    l: f64,
    m: usize,
    opts: &QuadOptions,
    mut g: impl FnMut(f64, &mut [f64]),
) -> Vec<f64> {
    let rule = Rule::new(opts.nodes);
    let ratio = 1.15f64.powf(1.0 / opts.refine.max(1) as f64);
    let mut acc = vec![Neumaier::default(); m];
    let mut buf = vec![0.0; m];
    let mut a = 0.0;
    let mut b = 1e-5f64.min(l);
    // geometric panels in s from 1e-5 to L
    loop {
        let (mid, h) = (0.5 * (a + b), 0.5 * (b - a));
        for (x, wt) in rule.x.iter().zip(&rule.w) {
            let s = mid + h * x;
            g(s / r, &mut buf);
            let kw = s * pxfm::f_k0(s) * wt * h;
            for (acc, v) in acc.iter_mut().zip(buf.iter()) {
                acc.add(v * kw);
            }
        }
        if b >= l {
            break;
        }
        a = b;
        b = (b * ratio).min(l);
    }
    let f = -2.0 / (std::f64::consts::PI * r * r);
    acc.iter().map(|s| s.total() * f).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    // Poisson kernel: ∫ e^{-a k} J0(k r) k dk = a / (r² + a²)^{3/2}
    fn poisson(a: f64, r: f64) -> f64 {
        a / (r * r + a * a).powf(1.5)
    }

    #[test]
    fn neumaier_recovers_lost_bits() {
        let mut s = Neumaier::default();
        for x in [1.0, 1e100, 1.0, -1e100] {
            s.add(x);
        }
        assert_eq!(s.total(), 2.0);
    }

    #[test]
    fn real_axis_poisson() {
        let a = 0.7;
        for r in [0.0, 1e-3, 0.5, 3.0, 30.0] {
            let t = hankel_real(
                r,
                1.0 / a,
                1e-3,
                1,
                &QuadOptions::default(),
                &[1e-18],
                |k, o| o[0] = (-a * k).exp(),
                |k0, o| o[0] = (-a * k0).exp() * (k0 / a + 1.0 / (a * a)),
            )[0];
            let e = poisson(a, r);
            assert!(((t - e) / e).abs() < 1e-13, "r={r} t={t} e={e}");
        }
    }

    #[test]
    fn j0_phase_matches_pxfm() {
        // at moderate x the argument rounding of f_j0 is still ~1e-14 or less
        let pi = std::f64::consts::PI;
        for rf in [1u32, 2, 3] {
            for j in [10u64, 11, 17, 40, 41, 100, 301] {
                for t in [0.0, 0.3, 0.999 * pi / rf as f64] {
                    let x = j as f64 * pi / rf as f64 + t;
                    if x < 30.0 {
                        continue;
                    }
                    let d = (j0_phase(j, rf, t, x) - pxfm::f_j0(x)).abs();
                    assert!(
                        d < 4e-16 + 2e-16 * x * (2.0 / (pi * x)).sqrt(),
                        "j={j} rf={rf} t={t} d={d}"
                    );
                }
            }
        }
    }

    #[test]
    fn contour_poisson() {
        // Im e^{-a i y} = -sin(a y)
        let a = 0.7;
        for r in [40.0, 100.0, 1e4, 1e6] {
            let t = hankel_contour(r, 60.0, 1, &QuadOptions::default(), |y, o| {
                o[0] = -(a * y).sin()
            })[0];
            let e = poisson(a, r);
            assert!(((t - e) / e).abs() < 1e-13, "r={r} t={t} e={e}");
        }
    }
}
