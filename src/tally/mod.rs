//! Statistics: mergeable Welford accumulators over independent batches.
//!
//! Every estimate in lumest is a mean over `B` independent batches of chains.
//! With batch means `x_1 .. x_B` (each already averaged over its chains):
//!
//! - mean `m = (1/B) sum x_b`
//! - sample variance `s^2 = sum (x_b - m)^2 / (B - 1)` (Welford's update, merged
//!   with Chan et al.'s formula, never raw power sums)
//! - standard error of the mean `se = s / sqrt(B)`
//! - 95 % confidence interval `m +- t_{0.975, B-1} se` (Student t)
//! - relative error `R = se / |m|`
//! - figure of merit `FOM = 1 / (R^2 T)` with `T` the wall-clock time [s].
//!
//! Numbers in, statistics out: nothing here knows about scenes or chains.

use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

/// Mergeable running mean and variance (Welford 1962; Chan, Golub & LeVeque 1979).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Welford {
    n: u64,
    mean: f64,
    m2: f64,
}

impl Welford {
    /// An empty accumulator.
    pub const fn new() -> Self {
        Self {
            n: 0,
            mean: 0.0,
            m2: 0.0,
        }
    }

    /// Add one observation.
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let delta = x - self.mean;
        self.mean += delta / self.n as f64;
        self.m2 += delta * (x - self.mean);
    }

    /// Merge another accumulator into this one (order-independent up to rounding).
    pub fn merge(&mut self, other: &Welford) {
        if other.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *other;
            return;
        }
        let n = self.n + other.n;
        let delta = other.mean - self.mean;
        let fo = other.n as f64 / n as f64;
        self.mean += delta * fo;
        self.m2 += other.m2 + delta * delta * self.n as f64 * fo;
        self.n = n;
    }

    /// Number of observations.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// Sample mean (0 when empty).
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Unbiased sample variance (0 with fewer than two observations).
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            (self.m2 / (self.n - 1) as f64).max(0.0)
        }
    }

    /// Standard error of the mean, `sqrt(variance / n)` (0 with fewer than two observations).
    pub fn std_error(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            (self.variance() / self.n as f64).sqrt()
        }
    }
}

/// Relative error `R = se / |mean|`; 0 when both are 0, infinite when only the mean is 0.
pub fn relative_error(mean: f64, se: f64) -> f64 {
    if se == 0.0 {
        0.0
    } else if mean == 0.0 {
        f64::INFINITY
    } else {
        se / mean.abs()
    }
}

/// Figure of merit `1 / (R^2 T)` [1/s]; infinite for an exact (R = 0) estimate.
pub fn figure_of_merit(rel_err: f64, seconds: f64) -> f64 {
    let d = rel_err * rel_err * seconds;
    if d > 0.0 { 1.0 / d } else { f64::INFINITY }
}

/// Half-width factor of a two-sided confidence interval at level `level`
/// (e.g. 0.95) for a mean estimated from `batches` batches: the Student t
/// quantile with `batches - 1` degrees of freedom, or the normal one above
/// 1000 degrees of freedom (where statrs' t quantile loses accuracy).
pub fn t_factor(level: f64, batches: u64) -> f64 {
    let p = 0.5 + 0.5 * level;
    let dof = batches.saturating_sub(1);
    if dof == 0 {
        return f64::INFINITY;
    }
    if dof > 1000 {
        return Normal::standard().inverse_cdf(p);
    }
    StudentsT::new(0.0, 1.0, dof as f64)
        .expect("positive degrees of freedom")
        .inverse_cdf(p)
}

/// Two-sided bound for the largest of `m` independent |z| scores at family
/// error rate `alpha` (Sidak correction): per-test level `1 - (1-alpha)^(1/m)`.
/// With `batches` given, the bound uses Student t with `batches - 1` degrees of freedom.
pub fn sidak_bound(alpha: f64, m: usize, batches: Option<u64>) -> f64 {
    let per_test = -(-alpha).ln_1p() / m.max(1) as f64; // -ln(1-alpha)/m
    let per_test = -(-per_test).exp_m1(); // 1 - exp(-..) = 1 - (1-alpha)^(1/m)
    let level = 1.0 - per_test;
    match batches {
        Some(b) => t_factor(level, b),
        None => Normal::standard().inverse_cdf(0.5 + 0.5 * level),
    }
}

/// Summary of one estimated quantity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Mean, in the quantity's unit.
    pub mean: f64,
    /// Standard error of the mean, same unit.
    pub std_error: f64,
}

impl Estimate {
    /// Relative error `R`.
    pub fn rel_error(&self) -> f64 {
        relative_error(self.mean, self.std_error)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass_and_merges() {
        let xs: Vec<f64> = (0..1000)
            .map(|i| 1e9 + ((i * 7919) % 1000) as f64 * 1e-3)
            .collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (xs.len() - 1) as f64;
        let mut a = Welford::new();
        let mut b = Welford::new();
        let mut all = Welford::new();
        for (i, &x) in xs.iter().enumerate() {
            all.push(x);
            if i < 300 { a.push(x) } else { b.push(x) }
        }
        a.merge(&b);
        for w in [all, a] {
            assert_eq!(w.count(), 1000);
            assert!((w.mean() - mean).abs() <= 1e-15 * mean);
            assert!(
                (w.variance() - var).abs() <= 1e-6 * var,
                "{} vs {}",
                w.variance(),
                var
            );
        }
    }

    #[test]
    fn sidak_bound_reduces_to_normal_quantile() {
        // One test at alpha = 0.05: the familiar 1.959964.
        assert!((sidak_bound(0.05, 1, None) - 1.959_963_984_540_054).abs() < 1e-9);
        // More tests, larger bound; t with few dof is larger than normal.
        assert!(sidak_bound(0.01, 100, None) > sidak_bound(0.01, 10, None));
        assert!(sidak_bound(0.01, 10, Some(20)) > sidak_bound(0.01, 10, None));
        assert!((t_factor(0.95, 11) - 2.228_138_851_986_274).abs() < 1e-9);
    }

    #[test]
    fn relative_error_and_fom_edges() {
        assert_eq!(relative_error(0.0, 0.0), 0.0);
        assert!(relative_error(0.0, 1.0).is_infinite());
        assert_eq!(relative_error(-2.0, 1.0), 0.5);
        assert!(figure_of_merit(0.0, 1.0).is_infinite());
        assert!((figure_of_merit(0.1, 2.0) - 50.0).abs() < 1e-12);
    }
}
