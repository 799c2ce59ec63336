//! Generic quadrature helpers: a 20-point Gauss-Legendre panel (nodes from
//! `gauss-quad`) and Neumaier's compensated sum.

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
