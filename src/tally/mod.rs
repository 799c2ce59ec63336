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
//! - figure of merit `FOM = 1 / (R^2 T)` with `T` the wall-clock time \[s\].
//!
//! Diagnostics of a tally (in the spirit of MCNP's statistical checks, but on
//! batch means), see [`Diagnostics`]:
//!
//! - variance of the variance `VOV = sum (x_b - m)^4 / (sum (x_b - m)^2)^2 - 1/B`,
//!   the relative variance of the estimated variance; about `2/B` for
//!   well-behaved (normal) batch means. Flagged above the larger of 0.1
//!   (the transport codes' bound) and its quantile for normal batch means
//!   at the run's false-alarm rate ([`check_bounds`]): `6/B` at 32 batches
//!   for one receiver (with 0.1 alone, 4 % of perfectly normal tallies of
//!   32 batches would be flagged), more for many.
//! - FOM stability: `FOM(B_h) / FOM(B) = (R^2 B) / (R_h^2 B_h)` between the
//!   largest power-of-two batch count `B_h <= B/2` and the end (the time is
//!   taken proportional to the batches, `FOM = 1/(R^2 T)`); near 1 when the
//!   error falls like `1/sqrt(T)`, above 1 when the FOM falls as the run
//!   goes on (a rare large score arrived late; infinite when nothing had
//!   scored at all by `B_h`). Flagged outside `[0.5, 2]`,
//!   widened to its quantiles for normal batch means at the run's
//!   false-alarm rate ([`check_bounds`]).
//! - heavy tail: the largest `|x_b - m| / s` over the batches (Grubbs'
//!   statistic) against its critical value for `B` normal values at the
//!   run's false-alarm rate ([`check_bounds`]); a batch that far out means
//!   rare huge scores (a heavy tail). Flagged when above.
//! - These three bounds hold the rate of false alarms per *run* (per
//!   tally of `m` receivers) at [`check_bounds::FALSE_ALARM`] = 0.1 % each
//!   for normal batch means, not per receiver: at 0.1 % per receiver,
//!   10,000 Sobolev points carried flags in 7 of 10 sound runs.
//! - `R > 0.1` is flagged: the estimate is not yet trustworthy.
//! - fewer than 32 batches is flagged: too few for the error bar or the
//!   checks to be trusted (a `--chains` run below 32 chains).
//! - `sparse` (local estimates at illuminance points): fewer than
//!   [`SPARSE_HITS`] = 10 collisions scored into the point from its *watched
//!   neighbourhood*, the ball of radius `10 x` the median distance to the
//!   surfaces it sees (16 probe rays; see
//!   [`crate::estimator::view_radius`]; the shell outside the near-field
//!   ball with `--near-radius`), while the reflected part is not 0. That
//!   neighbourhood holds almost all of the point's view (99.5 % facing a
//!   plane), so its light rests on fewer than 10 samples, and the batch
//!   statistics above cannot see what never happened: in the far field of
//!   two highly reflecting planes the plain estimate is 95-100 % low with a
//!   small, steady error bar, which only this check catches. Like MCNP's
//!   point-detector table of contributions by distance, it looks at where
//!   the scores came from rather than at their spread. For the backward
//!   estimator the counted events are path vertices within `d / 2` of a
//!   light (`d`: the receiver's distance to its nearest light), the region
//!   where the light piles up: paths that never get there miss that light
//!   (in the far field of two highly reflecting planes the backward
//!   estimate is 44 % low with steady batch statistics otherwise).
//!   For the near part of the near/far split the counted events are its
//!   path vertices within a light's *core* (the ball of radius the median
//!   distance from the light to the first surface, 16 probes), and the
//!   check applies once some vertex was *exposed* to a core (the split
//!   radius there was the receiver's radius `R`, not `d / 2`, and the core
//!   met the region within it, whose light the path must fetch itself
//!   instead of the pool; with `d / 2` the core lies beyond the region and
//!   its light comes from the pool, as at `r = 1e4`). Near a point source the light
//!   the path fetches grows like `1/d^3` down to that scale, so paths that
//!   never enter a core miss it: at `r = 100 m` between planes with
//!   `rho1 rho2 = 0.99` and `--near-radius 50`, 42 % of `E` comes from
//!   vertices within 10 m of the source, and runs whose paths never get
//!   there read half of `E` with a 3 % error bar and no other flag.
//! - `near` (plain local estimates at illuminance points): a surface in
//!   view closer than a tenth of the distance to the nearest light (64
//!   probe rays), while the near/far split is off there. The local
//!   estimate's kernel `1/d^2` is then close to singular: its variance is
//!   infinite in a corner and next to a lit wall it misses up to a third
//!   of `E` in any run of practical length, with error bars that look
//!   fine. `--near-radius auto` (the default) never leaves such a point on
//!   the plain estimate.
//!
//! Higher moments are accumulated with the one-pass updates and merges of
//! Pébay (2008), never raw power sums.
//!
//! Numbers in, statistics out: nothing here knows about scenes or chains.

use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
pub mod zcheck;

mod batch;
mod batch_means;
pub mod check_bounds;
pub mod checkpoint;
mod rms_precision;
pub mod shard;
mod state_file;
pub mod surface_figures;
mod tallies;
pub use batch::Batch;
pub use batch_means::BatchMeans;
pub use rms_precision::rms_effective_receivers;
pub use tallies::{Tallies, bucket, bucket_count};

/// Mergeable running mean, variance, third and fourth central moments and
/// extremes (Welford 1962; Chan, Golub & LeVeque 1979; Pébay 2008).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Welford {
    n: u64,
    mean: f64,
    m2: f64,
    m3: f64,
    m4: f64,
    min: f64,
    max: f64,
}

impl Default for Welford {
    fn default() -> Self {
        Self::new()
    }
}

impl Welford {
    /// An empty accumulator.
    pub const fn new() -> Self {
        Self {
            n: 0,
            mean: 0.0,
            m2: 0.0,
            m3: 0.0,
            m4: 0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }

    /// The exact state `(n, [mean, m2, m3, m4, min, max])`, for a
    /// checkpoint ([`Self::from_parts`] restores it bit for bit).
    pub fn to_parts(&self) -> (u64, [f64; 6]) {
        (
            self.n,
            [self.mean, self.m2, self.m3, self.m4, self.min, self.max],
        )
    }

    /// The accumulator of a state from [`Self::to_parts`].
    pub fn from_parts(n: u64, v: [f64; 6]) -> Self {
        let [mean, m2, m3, m4, min, max] = v;
        Self {
            n,
            mean,
            m2,
            m3,
            m4,
            min,
            max,
        }
    }

    /// Add one observation.
    #[inline]
    pub fn push(&mut self, x: f64) {
        let n1 = self.n as f64;
        self.n += 1;
        let n = self.n as f64;
        let delta = x - self.mean;
        let dn = delta / n;
        let dn2 = dn * dn;
        let term1 = delta * dn * n1;
        self.mean += dn;
        self.m4 += term1 * dn2 * (n * n - 3.0 * n + 3.0) + 6.0 * dn2 * self.m2 - 4.0 * dn * self.m3;
        self.m3 += term1 * dn * (n - 2.0) - 3.0 * dn * self.m2;
        self.m2 += term1;
        self.min = self.min.min(x);
        self.max = self.max.max(x);
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
        let (na, nb) = (self.n as f64, other.n as f64);
        let n = na + nb;
        let d = other.mean - self.mean;
        let (d2, d3, d4) = (d * d, d * d * d, d * d * d * d);
        let m2 = self.m2 + other.m2 + d2 * na * nb / n;
        let m3 = self.m3
            + other.m3
            + d3 * na * nb * (na - nb) / (n * n)
            + 3.0 * d * (na * other.m2 - nb * self.m2) / n;
        let m4 = self.m4
            + other.m4
            + d4 * na * nb * (na * na - na * nb + nb * nb) / (n * n * n)
            + 6.0 * d2 * (na * na * other.m2 + nb * nb * self.m2) / (n * n)
            + 4.0 * d * (na * other.m3 - nb * self.m3) / n;
        self.mean += d * nb / n;
        self.m2 = m2;
        self.m3 = m3;
        self.m4 = m4;
        self.n += other.n;
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    /// Variance of the variance, `M4 / M2^2 - 1/n` (0 when the values are all equal).
    pub fn vov(&self) -> f64 {
        if self.n < 2 || self.m2 <= 0.0 {
            0.0
        } else {
            self.m4 / (self.m2 * self.m2) - 1.0 / self.n as f64
        }
    }

    /// Skewness of the observations (0 when they are all equal).
    pub fn skewness(&self) -> f64 {
        if self.n < 2 || self.m2 <= 0.0 {
            0.0
        } else {
            (self.n as f64).sqrt() * self.m3 / self.m2.powf(1.5)
        }
    }

    /// Largest `|x - mean| / s` over the observations (0 when `s = 0`).
    pub fn max_deviation(&self) -> f64 {
        let s = self.variance().sqrt();
        if s == 0.0 || self.n == 0 {
            0.0
        } else {
            (self.max - self.mean).max(self.mean - self.min) / s
        }
    }

    /// Number of observations.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// Sample mean (0 when empty).
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Unbiased sample variance (0 with fewer than two observations; NaN
    /// when an observation was not a number, never hidden as 0).
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            // Rounding can leave m2 a hair below 0; `f64::max` would also
            // turn a NaN into 0, an exact-looking estimate.
            let v = self.m2 / (self.n - 1) as f64;
            if v < 0.0 { 0.0 } else { v }
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
    // Memoised for the last arguments (per thread): a run's rows share them,
    // and a quantile costs microseconds (a second at 1,000,000 points).
    thread_local! {
        static LAST: std::cell::Cell<Option<(u64, u64, f64)>> = const { std::cell::Cell::new(None) };
    }
    let key = (level.to_bits(), batches);
    if let Some((l, b, t)) = LAST.with(std::cell::Cell::get)
        && (l, b) == key
    {
        return t;
    }
    let t = t_quantile(level, batches);
    LAST.with(|c| c.set(Some((key.0, key.1, t))));
    t
}

/// [`t_factor`], computed.
fn t_quantile(level: f64, batches: u64) -> f64 {
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

/// Statistical checks of one tally (formulas in the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diagnostics {
    /// Relative error `R` of the total (exact part included).
    pub rel_err: f64,
    /// Variance of the variance.
    pub vov: f64,
    /// `FOM(B_h) / FOM(B)`, when a snapshot at `B_h <= B/2` batches exists.
    pub fom_ratio: Option<f64>,
    /// Largest batch deviation `|x_b - m| / s`.
    pub max_deviation: f64,
    /// Bound the largest deviation is checked against (Grubbs' critical
    /// value at the run's false-alarm rate, [`check_bounds`]).
    pub deviation_bound: f64,
    /// Largest trusted VOV ([`check_bounds`]).
    pub vov_bound: f64,
    /// Accepted range of `fom_ratio` ([`check_bounds`]).
    pub fom_bounds: (f64, f64),
    /// Number of batches behind the estimate.
    pub batches: u64,
    /// Collisions that scored from the point's watched neighbourhood over
    /// the run, when the `sparse` check applies (local estimates at
    /// illuminance points with a surface in view).
    pub near_hits: Option<u64>,
    /// Near part of the near/far split: its path vertices inside a light's
    /// neighbourhood over the run, when some vertex was *exposed* to one
    /// (the receiver's radius, not `d / 2`, set the vertex's split radius
    /// and the neighbourhood met the region within it, whose light the path
    /// must fetch itself rather than the pool); `None`
    /// when no vertex was or there is no near part. Fewer than
    /// [`SPARSE_HITS`] flags `sparse`.
    pub near_reach: Option<u64>,
    /// Whether the reflected part is exactly 0 (nothing scored at all).
    pub indirect_zero: bool,
    /// The `near` check: a surface much closer than the nearest light,
    /// on the plain local estimate.
    pub near: bool,
    /// The point sees the back of a surface in most directions (inside a
    /// solid, behind a wall, outside a closed room).
    pub enclosed: bool,
    /// The scene's lights approximate it (median cut): a bias no error bar
    /// holds ([`crate::scene::Scene::approximate`]).
    pub approximate: bool,
    /// The batch count `B_h` of the FOM ratio's snapshot, if any.
    pub half_batches: Option<u64>,
    /// The receivers the bounds hold the false-alarm rate over (the run's,
    /// or a gate's family, [`Self::among`]).
    pub family: usize,
}

impl Diagnostics {
    /// Checks of accumulator `w` for an estimate whose total is `exact +
    /// w.mean()`, with `half = (B_h, R^2 B_h)` at an earlier batch count
    /// `B_h`, if any, for one of `receivers` receivers checked in the run
    /// (the bounds hold the false alarms per run, [`check_bounds`]).
    pub fn of(w: &Welford, exact: f64, half: Option<(u64, f64)>, receivers: usize) -> Self {
        let rel_err = relative_error(exact + w.mean(), w.std_error());
        let r2b = rel_err * rel_err * w.count() as f64;
        // FOM(B_h) / FOM(B) = (R^2 B) / (R_h^2 B_h); none where the end is
        // exact (0). An exact snapshot before an error (nothing at all
        // scored in the first B_h batches, then something) is an infinite
        // ratio, and a NaN stays a NaN ratio: both flag.
        let fom_ratio = half.map(|h| h.1).filter(|_| r2b != 0.0).map(|h| r2b / h);
        // The bounds are set by `among`, for the run's receivers.
        Self {
            rel_err,
            vov: w.vov(),
            fom_ratio,
            max_deviation: w.max_deviation(),
            deviation_bound: f64::NAN,
            vov_bound: f64::NAN,
            fom_bounds: (f64::NAN, f64::NAN),
            batches: w.count(),
            near_hits: None,
            near_reach: None,
            indirect_zero: w.mean() == 0.0,
            near: false,
            enclosed: false,
            approximate: false,
            half_batches: half.map(|h| h.0),
            family: 1,
        }
        .among(receivers)
    }

    /// The same checks with their bounds held over a family of `family`
    /// receivers (never fewer than [`Self::family`]): a gate that judges
    /// the rows of several runs together fails a sound set of runs in at
    /// most [`check_bounds::FALSE_ALARM`] of its judgements per check,
    /// however many runs it makes.
    pub fn among(&self, family: usize) -> Self {
        let family = family.max(self.family);
        let bounds = check_bounds::CheckBounds::new(self.batches, self.half_batches, family);
        Self {
            deviation_bound: bounds.deviation,
            vov_bound: bounds.vov,
            fom_bounds: self.half_batches.map_or((0.0, f64::INFINITY), |b_h| {
                check_bounds::fom_bounds(&bounds, self.rel_err, self.batches, b_h)
            }),
            family,
            ..*self
        }
    }

    /// The failed checks, as `R`, `VOV`, `FOM`, `tail`, `batches` (fewer than
    /// 32, too few for the checks themselves), `sparse`, `near`,
    /// `enclosed`, `approx`, joined by `;`, or `ok`. A non-finite relative error is flagged `R`.
    pub fn flag(&self) -> String {
        let mut f = Vec::new();
        if self.batches < 32 {
            f.push("batches");
        }
        if self.rel_err.is_nan() || self.rel_err > 0.1 {
            f.push("R");
        }
        // NaN or infinite statistics are failures, never `ok`.
        if self.vov.is_nan() || self.vov > self.vov_bound {
            f.push("VOV");
        }
        let (lo, hi) = self.fom_bounds;
        if self.fom_ratio.is_some_and(|r| !(lo..=hi).contains(&r)) {
            f.push("FOM");
        }
        if self.max_deviation.is_nan() || self.max_deviation > self.deviation_bound {
            f.push("tail");
        }
        let few = |h: Option<u64>| h.is_some_and(|h| h < SPARSE_HITS);
        if !self.indirect_zero && (few(self.near_hits) || few(self.near_reach)) {
            f.push("sparse");
        }
        if self.near {
            f.push("near");
        }
        if self.enclosed {
            f.push("enclosed");
        }
        if self.approximate {
            f.push("approx");
        }
        if f.is_empty() {
            "ok".to_string()
        } else {
            f.join(";")
        }
    }
}

/// Fewest collisions that must score from a point's watched neighbourhood
/// before its local estimate is trusted (the `sparse` check).
pub const SPARSE_HITS: u64 = 10;

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
    fn vov_limit_rarely_flags_normal_batch_means() {
        // 4000 tallies of 32 normal batch means (Box-Muller on Philox): the
        // raised limit flags about 0.1 % of them; 0.1 alone would flag ~4 %.
        let mut rng = crate::sampling::Philox4x32::new(17, 0);
        let (mut raised, mut plain) = (0, 0);
        for _ in 0..4000 {
            let mut w = Welford::new();
            for _ in 0..16 {
                let [u, v] = rng.next_2d();
                let r = (-2.0 * (1.0 - u).ln()).sqrt();
                let (s, c) = (std::f64::consts::TAU * v).sin_cos();
                w.push(r * c);
                w.push(r * s);
            }
            raised += usize::from(w.vov() > check_bounds::CheckBounds::new(w.count(), None, 1).vov);
            plain += usize::from(w.vov() > 0.1);
        }
        assert!(raised <= 16, "{raised} of 4000 flagged");
        assert!(plain >= 80, "{plain}: the plain limit should flag ~4 %");
        assert_eq!(check_bounds::CheckBounds::new(1000, None, 1).vov, 0.1);
    }

    /// A batch mean that is not a number makes the error NaN, not an
    /// exact-looking 0 (and so the relative error, and a run's largest).
    #[test]
    fn a_nan_observation_is_not_an_exact_estimate() {
        let mut w = Welford::new();
        for x in [1.0, f64::NAN, 2.0] {
            w.push(x);
        }
        assert!(w.variance().is_nan() && w.std_error().is_nan());
        assert!(relative_error(w.mean(), w.std_error()).is_nan());
        let mut c = Welford::new();
        for _ in 0..4 {
            c.push(3.0);
        }
        assert_eq!((c.variance(), c.std_error()), (0.0, 0.0));
    }

    /// A statistic that is not a number fails its check, never passes: a
    /// NaN batch mean flags the FOM and tail checks too (not only `R` and
    /// `VOV`), and so does a NaN FOM snapshot of an otherwise sound tally;
    /// an exact (0) snapshot before a finite error is an infinite ratio,
    /// flagged (nothing had scored in the first half of the run).
    #[test]
    fn nan_statistics_flag_every_check_they_reach() {
        let mut w = Welford::new();
        for i in 0..64 {
            w.push(1.0 + 0.01 * ((i * 7919 % 64) as f64 / 64.0 - 0.5));
        }
        let r2b = Diagnostics::of(&w, 0.0, None, 1).rel_err.powi(2) * 64.0;
        assert_eq!(Diagnostics::of(&w, 0.0, Some((32, r2b)), 1).flag(), "ok");
        let d = Diagnostics::of(&w, 0.0, Some((32, f64::NAN)), 1);
        assert!(d.fom_ratio.is_some_and(f64::is_nan), "{d:?}");
        assert_eq!(d.flag(), "FOM");
        let late = Diagnostics::of(&w, 0.0, Some((32, 0.0)), 1);
        assert_eq!(
            (late.fom_ratio, late.flag().as_str()),
            (Some(f64::INFINITY), "FOM")
        );
        // An exact end (and so an exact snapshot) has no ratio.
        let mut exact = Welford::new();
        (0..64).for_each(|_| exact.push(0.0));
        assert_eq!(
            Diagnostics::of(&exact, 2.0, Some((32, 0.0)), 1).fom_ratio,
            None
        );
        let mut nan = w;
        nan.push(f64::NAN);
        for m in [0, 1, 10_000_000] {
            let flag = Diagnostics::of(&nan, 0.0, Some((32, r2b)), m).flag();
            assert_eq!(flag, "R;VOV;FOM;tail", "{m}");
        }
    }

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
    fn higher_moments_match_two_pass_and_merge() {
        // A skewed sample: squares of a ramp.
        let xs: Vec<f64> = (0..500)
            .map(|i| ((i * 37 % 500) as f64 / 100.0).powi(2))
            .collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let m = |k: i32| xs.iter().map(|x| (x - mean).powi(k)).sum::<f64>();
        let (m2, m3, m4) = (m(2), m(3), m(4));
        let mut all = Welford::new();
        let (mut a, mut b) = (Welford::new(), Welford::new());
        for (i, &x) in xs.iter().enumerate() {
            all.push(x);
            if i % 3 == 0 { a.push(x) } else { b.push(x) }
        }
        a.merge(&b);
        for w in [all, a] {
            assert!((w.vov() - (m4 / (m2 * m2) - 1.0 / n)).abs() < 1e-12);
            assert!((w.skewness() - n.sqrt() * m3 / m2.powf(1.5)).abs() < 1e-12);
            let s = (m2 / (n - 1.0)).sqrt();
            let dev = xs.iter().map(|x| (x - mean).abs()).fold(0.0, f64::max) / s;
            assert!((w.max_deviation() - dev).abs() < 1e-12);
        }
    }

    #[test]
    fn diagnostics_flag_what_they_should() {
        // Normal-looking batch means: nothing flagged.
        let mut w = Welford::new();
        for i in 0..64 {
            w.push(1.0 + 0.01 * ((i * 7919 % 64) as f64 / 64.0 - 0.5));
        }
        assert_eq!(Diagnostics::of(&w, 0.0, None, 1).flag(), "ok");
        // The same R^2 B at half the batches: a stable FOM.
        let r2b = Diagnostics::of(&w, 0.0, None, 1).rel_err.powi(2) * 64.0;
        assert_eq!(
            Diagnostics::of(&w, 0.0, Some((32, r2b)), 1).fom_ratio,
            Some(1.0)
        );
        assert!(
            Diagnostics::of(&w, 0.0, Some((32, 3.0 * r2b)), 1)
                .flag()
                .contains("FOM")
        );
        // The ratio is FOM(half) / FOM(end): R^2 B at half the run four times
        // the final one means the FOM was 4 times lower then, i.e. a ratio of 1/4.
        let ratio = Diagnostics::of(&w, 0.0, Some((32, 4.0 * r2b)), 1)
            .fom_ratio
            .unwrap();
        assert!((ratio - 0.25).abs() < 1e-12, "{ratio}");
        // One huge batch among many small ones: a heavy tail and a large VOV.
        let mut h = Welford::new();
        for _ in 0..63 {
            h.push(1.0);
        }
        h.push(1000.0);
        // Also among a million receivers: the bounds per run still catch it.
        for m in [1, 1_000_000] {
            let d = Diagnostics::of(&h, 0.0, None, m);
            assert!(
                d.flag().contains("VOV") && d.flag().contains("tail"),
                "{m}: {d:?}"
            );
        }
        // A relative error above 0.1.
        let mut r = Welford::new();
        for x in [0.0, 2.0, 0.0, 2.0] {
            r.push(x);
        }
        assert!(Diagnostics::of(&r, 0.0, None, 1).flag().contains('R'));
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
