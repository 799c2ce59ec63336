//! Hankel-type integrals `int_0^inf f(k) J0(k r) k dk` of smooth, exponentially
//! decaying transforms (written in the project: no crate does it).
//!
//! Method: composite Gauss-Legendre (20 nodes, `gauss-quad`) on panels of
//! width `w = min(pi / r, 1 / H)`, i.e. at most half a period of `J0(k r)` and
//! at most the decay length `1/H` of the integrand; the first panel `[0, w]`
//! is graded geometrically towards `k = 0` (ratio 1/2, 40 levels) because the
//! transforms carry `k^2 ln k` terms there. Panels are summed with Neumaier's
//! compensated summation until a rigorous tail bound (supplied by the caller)
//! falls below the requested absolute tolerance.
//!
//! Why not a series acceleration (Wynn, Ogata): the transforms here decay like
//! `e^(-H k)`, so the panel sum is finite in practice, and the oscillation
//! only sets the panel width. The cancellation at large `r` is reduced by the
//! caller, which subtracts the small-`k` behaviour analytically.

use gauss_quad::legendre::GaussLegendre;
use std::sync::OnceLock;

/// Gauss-Legendre nodes and weights on [-1, 1].
fn rule() -> &'static [(f64, f64)] {
    static RULE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    RULE.get_or_init(|| {
        let n = std::num::NonZeroUsize::new(20).expect("non-zero");
        GaussLegendre::new(n).as_node_weight_pairs().to_vec()
    })
}

/// Neumaier (improved Kahan) compensated sum.
#[derive(Clone, Copy, Debug, Default)]
pub struct CompensatedSum {
    sum: f64,
    c: f64,
}

impl CompensatedSum {
    /// Add one term.
    #[inline]
    pub fn add(&mut self, x: f64) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.c += (self.sum - t) + x;
        } else {
            self.c += (x - t) + self.sum;
        }
        self.sum = t;
    }

    /// The compensated total.
    pub fn total(&self) -> f64 {
        self.sum + self.c
    }
}

/// `int_a^b g(k) dk` by one Gauss-Legendre panel.
#[inline]
pub fn panel<G: Fn(f64) -> f64>(g: &G, a: f64, b: f64) -> f64 {
    let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
    let mut s = 0.0;
    for &(x, w) in rule() {
        s += w * g(m + h * x);
    }
    s * h
}

/// `int_0^inf f(k) J0(k r) k dk`.
///
/// `scale` is the decay length of `f` (`f ~ e^(-k/scale)`), `tail(K)` must
/// bound `int_K^inf |f(k)| k dk`, and `tol` is the absolute tolerance for the
/// neglected tail. Panics if the tail bound never falls below `tol` within
/// `10^8` panels (a caller error). `refine > 1` divides the panel width, for
/// convergence studies.
pub fn hankel0<F: Fn(f64) -> f64, T: Fn(f64) -> f64>(
    f: F,
    r: f64,
    scale: f64,
    tail: T,
    tol: f64,
    refine: u32,
) -> f64 {
    let w = if r > 0.0 {
        (std::f64::consts::PI / r).min(scale)
    } else {
        scale
    };
    let w = w / f64::from(refine.max(1));
    let g = |k: f64| f(k) * pxfm::f_j0(k * r) * k;
    let mut sum = CompensatedSum::default();
    // First panel, graded towards 0.
    let levels = 40;
    let mut b = w;
    for _ in 0..levels {
        let a = 0.5 * b;
        sum.add(panel(&g, a, b));
        b = a;
    }
    sum.add(panel(&g, 0.0, b));
    // Uniform panels until the tail is negligible. Edges are `i w`, not a
    // running `k += w`: the running sum drifts off the half-periods of
    // J0(k r) and left a systematic error growing with r (4e-8 at r = 300).
    let mut i = 1u64;
    while tail(i as f64 * w) > tol {
        sum.add(panel(&g, i as f64 * w, (i + 1) as f64 * w));
        i += 1;
        assert!(
            i < 100_000_000,
            "hankel0: tail bound does not converge (k = {})",
            i as f64 * w
        );
    }
    sum.total()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponential_transforms_are_exact() {
        // int e^(-pk) J0(kr) k dk = p / (p^2 + r^2)^(3/2): the direct-light kernel.
        // (At large r p the raw integral cancels to ~1e-10 relative; callers
        // subtract the small-k behaviour analytically, see reference::sobolev.)
        for &(p, r) in &[
            (0.5f64, 0.0f64),
            (0.5, 0.3),
            (1.0, 3.0),
            (0.2, 2.0),
            (2.0, 1.0),
        ] {
            let exact = p / (p * p + r * r).powf(1.5);
            let tail = |k: f64| (k / p + 1.0 / (p * p)) * (-p * k).exp();
            let got = hankel0(|k| (-p * k).exp(), r, 1.0 / p, tail, 1e-18 * exact, 1);
            assert!(
                (got / exact - 1.0).abs() < 1e-12,
                "p={p} r={r}: {got} vs {exact}"
            );
        }
    }

    #[test]
    fn compensated_sum_keeps_small_terms() {
        let mut s = CompensatedSum::default();
        for x in [1e16, 1.0, -1e16, 1.0] {
            s.add(x);
        }
        assert_eq!(s.total(), 2.0);
    }
}
