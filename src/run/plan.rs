//! Planning a run aimed at an error target (`--rel-error`, `--rms-error`,
//! `--figure-target`): the pilot stages, the margin, the batch size and
//! the number of batches. [`super::drive`] runs what is planned here.
//!
//! A run that can grow its batches does that instead ([`super::grow`]: no
//! pilot; the one Sobolev point at 0.1 % in about the least fixed run's
//! chains). The plan here applies where it cannot: with `--batch-size`,
//! to shards run apart (`--shard`, which cannot exchange the batches a
//! grown run measures at every stage), to `--figure-target`, and to work
//! that does not grow (the backward estimator).
//!
//! # The `--rel-error` rule: a pilot, then a fixed count
//!
//! Stopping at the first batch count whose *estimated* error meets the target
//! biases both the mean and its interval when batch means are skewed: a run
//! that happens to be low also tends to have a small spread and stops early
//! (simulated with lognormal batch means, `sigma = 0.6`, target 8 %: mean
//! 0.85 % low and 92.4 % coverage of the 95 % interval). So the rule is a
//! two-stage one (in the spirit of Stein 1945): a pilot of [`PILOT_BATCHES`]
//! batches on streams of their own (seed `seed ^ PILOT_KEY`) measures the
//! largest relative error `R_p` over the receivers, and the run proper then
//! traces a fixed number of fresh batches,
//!
//! `B = max(32, ceil(B_p (R_p / target)^2 q))`, with
//! `q = (B_p - 1) / chi2_{B_p - 1}(0.1)` (1.446 for `B_p = 32`)
//!
//! the 90 % upper confidence factor of the pilot's variance with `B_p - 1`
//! degrees of freedom, or more for an RMS target (below); `R_p` rescaled
//! to the run's batch size (below). The reported estimate uses the fresh batches only, whose number
//! does not depend on their own values: the mean is unbiased and the
//! interval is that of a fixed-count run; indeed the result is
//! bit-identical to `--chains B * batch_size --batch-size batch_size` with
//! the same seed. A caller may have the pilot measure something else that
//! falls like a standard error ([`super::RunConfig::pilot_measure`]: a grid
//! figure's interval half-width over its target, with target 1, for
//! `--figure-target`). A missed target is never hidden: the result carries
//! the achieved error and the plan ([`Pilot`]), and the commands say so.
//! Measured by `tests/rel_error_rule.rs`.
//!
//! ## Sizing the batches of the plan
//!
//! The work's default batch size (`bs`, chosen for throughput) would make
//! a small target overshoot: 32 batches of 16,384 chains on one point where
//! about 20,000 chains meet 0.1 %. So, unless `--batch-size` fixes it, the
//! plan also picks the batch size, from chains alone (never from timing, so
//! every thread count and every shard plans alike):
//!
//! 1. a first pilot stage of 32 batches of [`super::MIN_TIMED_BATCH`] chains (the
//!    smallest batches whose means are near enough normal for the checks;
//!    where the work's own batch `bs` is no larger, costly chains such as
//!    the backward estimator's, a quarter of `bs`, at least 8, so that the
//!    pilot costs a quarter of a minimum run, not a whole one)
//!    gives the chains `N` the target needs ([`planned_chains`]);
//! 2. the run's batch size is the largest power of two giving at least 32
//!    batches for `N` chains, between the pilot's and `bs`
//!    ([`plan_batch_size`]);
//! 3. where that is more than 8 times the first stage's batches, the
//!    variance per chain may be much lower at the run's size (stratified
//!    batches: measured 2-3 times lower at 16,384 chains than at 256 on the
//!    Sobolev points), and the plan from small batches would overshoot; a
//!    second stage of 32 batches of an eighth of that size
//!    ([`pilot_batch_size`], seed offset `SECOND_KEY`) then measures again
//!    and the plan is made from it (step 2 again). Its cost is at most
//!    four batches of the run proper. Where the first stage measured its
//!    error precisely (an RMS over many receivers, below), the second
//!    stage runs 16 batches of a quarter of the size the first stage
//!    planned instead, for the same chains.
//! 4. For an RMS target over few effective receivers (below; over many,
//!    the plan is measured on the run's own batches), with two stages, the fall
//!    of the variance per chain between them, `v(b) ~ b^-alpha`, is
//!    measured and the pilot's error is rescaled to the run's batches with
//!    half of it ([`variance_fall`]: half a 90 % lower bound on `alpha`,
//!    at most [`MAX_VARIANCE_FALL`]). Not for a largest error: the
//!    receiver that decides it may differ between the stages (one whose
//!    error falls fast leads at small batches, a flat one at large), and
//!    the fall measured between them is then one no receiver has.
//!
//! The margin `q` is sized for the precision of the pilot's measure: `B_p
//! - 1` degrees of freedom for one receiver (and for a largest error over
//! many, where one receiver decides), but an RMS over many receivers is
//! measured more precisely, by the effective number of independent
//! receivers behind it ([`crate::tally::rms_effective_receivers`], from
//! the correlations and the tails of the pilot's batch means; its 90 %
//! lower bound is used, as it is estimated from the same 32 batches), and
//! where a fall is extrapolated its noise widens the margin
//! ([`extrapolated_dof`]): on the 100 x 100 Sobolev grid about 130
//! degrees of freedom, `q` about 1.18 in place of 1.446.
//!
//! ## An RMS target over many receivers: planned on the run's own batches
//!
//! Extrapolated from a pilot of smaller batches, an RMS plan overshot the
//! least chains 1.45-1.84 times on the 100 x 100 Sobolev grid: the margin
//! (`q` about 1.18) and, more, the half of the variance's fall it leaves
//! out. So where the first stage counts at least
//! [`CALIBRATION_RECEIVERS`] effective receivers (90 % lower bound), the
//! plan is measured where it applies: the batch size is the largest that
//! would still need 32 batches or more even if the variance per chain
//! fell as steeply as allowed ([`calibrated_batch_size`]: too large
//! batches force 32 of them, too small ones cost only a little of the
//! fall; no second stage), the run proper's
//! first [`CALIBRATION_BATCHES`] batches measure `R_c` and its degrees of
//! freedom `31 m` at the run's own size, and
//!
//! `B = max(32, ceil(32 (R_c / target)^2 q))`
//!
//! counts them: no fall is extrapolated and no chain of the 32 is wasted,
//! as every run has at least 32 batches. The estimate keeps them, so, as in
//! Stein's two-stage rule, the count leans a little on the noise of
//! batches the mean keeps: a receiver's mean is biased by about its batch
//! means' skewness times its share in the RMS, about `1 / m` of what one
//! receiver alone would be (0.66 % +- 0.11 % low for lognormal batch means
//! of skewness 2.3 at an 8 % error, hence the gate at `m >= 4`): measured
//! over 32 and 128 independent such receivers, 0.035 % and 0.012 % low,
//! under 1 % of a standard error, with the intervals covering as a fixed
//! count's do (`tests/rel_error_rule.rs` checks the gate and 256 skewed
//! receivers). The result is still
//! bit-identical to `--chains B * bs --batch-size bs`. A shard run alone
//! (`--shard`) traces the 32 calibrating batches itself, so that all plan
//! alike, and keeps its own among them: it costs `32 + (B - 32) / M`
//! batches, not `B / M`. Shards that run at once (MPI ranks) share them out
//! instead ([`super::RunConfig::share`]): each traces its own and they exchange
//! them. On
//! the grid: about 15 effective receivers, `q` about 1.09, and 1.1-1.2
//! times the least chains with the pilot (`tests/batch_plan.rs`).
//!
//! Fewer chains per batch make batch means more skewed, which is why no
//! batch goes below [`super::MIN_TIMED_BATCH`] and no run below [`MIN_BATCHES`]
//! batches; larger batches are never worse for the error here. What
//! remains of the overshoot is the margin `q`, the noise of the pilot's
//! `R_p` (the largest of many noisy errors is biased up), and the part of
//! the variance's fall between the pilot's and the run's batch size that
//! the plan leaves out. The target is met in about 90 % of runs (measured
//! in `tests/batch_plan.rs`, with normal, heavy-tailed and mixed models).

use super::MIN_BATCHES;
use crate::tally::Tallies;

/// Batches of the `--rel-error` pilot (see the module docs).
pub const PILOT_BATCHES: u64 = 32;

/// Seed offset of the pilot's streams.
pub(super) const PILOT_KEY: u64 = 0x7069_6c6f_7452_4552; // "pilotRER"

/// Further seed offset of a second pilot stage's streams.
pub(super) const SECOND_KEY: u64 = 0x7365_636f_6e64; // "second"

/// What the `--rel-error` pilot measured and planned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pilot {
    /// The target for the largest relative error.
    pub target: f64,
    /// Batches in the pilot.
    pub batches: u64,
    /// Chains per pilot batch ([`pilot_batch_size`]).
    pub batch_size: u64,
    /// Wall time of the pilot \[s\].
    pub wall: f64,
    /// Largest (or, for an RMS target, root mean square) relative error
    /// over the receivers after the pilot, rescaled to batches of the run
    /// proper.
    pub rel_error: f64,
    /// The target is on the RMS relative error (`--rms-error`).
    pub rms: bool,
    /// The pilot measured a caller's quantity ([`super::RunConfig::pilot_measure`]).
    pub custom: bool,
    /// Degrees of freedom of the pilot's squared error, which size the
    /// margin ([`variance_margin`]): `batches - 1`, or that times the
    /// effective receivers for an RMS over many
    /// ([`crate::tally::rms_effective_receivers`]).
    pub dof: f64,
    /// Exponent of the fall of the variance per chain with the batch size
    /// used to rescale the pilot to the run's batches ([`variance_fall`]; 0
    /// with one stage and for a largest error).
    pub fall: f64,
    /// Batches planned for the run proper.
    pub planned: u64,
    /// Wall time the planned batches need at the pilot's pace \[s\]
    /// (infinite when no plan could be made); for a grown run, the wall
    /// time its stages took.
    pub estimated_time: f64,
    /// The time limit the run proper ran under when none was given
    /// ([`DEFAULT_REL_ERROR_CAP`]); `None` with `--time`.
    pub default_cap: Option<f64>,
    /// Pilot stages run: 1, or 2 where the first (batches of
    /// [`super::MIN_TIMED_BATCH`] chains) only sized the second (module docs);
    /// `batches`, `batch_size` and `rel_error` are the last stage's, `wall`
    /// covers both.
    pub stages: u32,
    /// Chains the pilot stages traced on their own streams (not in the
    /// result).
    pub pilot_chains: u64,
    /// Batches of the run proper that measured the error the plan was made
    /// from (an RMS target over several effective receivers, module docs);
    /// `batches`, `batch_size`, `rel_error` and `dof` are then theirs, and
    /// `planned` counts them. 0: the plan came from the pilot alone.
    pub calibration: u64,
    /// Of those, the batches this process traced: all of them, or a
    /// shard's own where the shards share them ([`super::RunConfig::share`]).
    pub calibration_traced: u64,
    /// Stages of a run that grew its batches ([`super::grow`]): no pilot
    /// ran, `batches`, `batch_size` and `rel_error` are the run's own at
    /// its last stage, and `fall` the fall of its variance per chain
    /// measured between its first stage and its last. 0: a planned run.
    pub grown: u32,
    /// A grown run stopped within its last stage (an interrupt): its
    /// batches differ in size and `batch_size` is the largest of them.
    pub cut: bool,
}

/// Batches of the run proper that an RMS target's plan is measured on
/// before the rest is planned (module docs): the least a run has anyway.
pub const CALIBRATION_BATCHES: u64 = MIN_BATCHES;

/// Fewest effective receivers (the 90 % lower bound the first pilot stage
/// measured, [`crate::tally::rms_effective_receivers`]) behind an RMS
/// target for its plan to be made from the run's own first batches: with
/// fewer, one receiver's batch means decide much of the plan, and a plan
/// from batches the estimate keeps leans on their own noise. Measured
/// with this gate at 0 on one receiver with lognormal batch means (the
/// runs of `tests/rel_error_rule.rs`, 4,000 of them): mean 0.66 % +- 0.11
/// % low and 92.0 % coverage, against 0.02 % and 93.9 % for runs of the
/// same fixed count (module docs).
pub const CALIBRATION_RECEIVERS: f64 = 4.0;

/// Most batch means (receivers times pilot batches) a pilot keeps to
/// measure the precision of an RMS target: 4M values, 32 MB (131,072
/// receivers; beyond, the margin is one receiver's).
pub(super) const RMS_PRECISION_VALUES: u64 = 1 << 22;

/// Degrees of freedom of a first pilot stage's squared error above which
/// the second stage runs half the batches at twice the size (eight times
/// one receiver's 31).
pub(super) const PRECISE_DOF: f64 = 248.0;

/// Largest exponent of the fall of the variance per chain with the batch
/// size that a plan extrapolates with: Owen-scrambled nets of an integrand
/// with discontinuities in `d >= 2` dimensions reach a variance of
/// `O(N^(-1 - 1/d))`, a fall of at most `1/d` per chain.
pub const MAX_VARIANCE_FALL: f64 = 0.5;

/// One pilot stage: its batches of `batch_size` chains, the error `r` it
/// measured, and the degrees of freedom of `r^2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stage {
    /// Batches the stage ran.
    pub batches: u64,
    /// Chains per batch.
    pub batch_size: u64,
    /// Its largest (or RMS) relative error over the receivers.
    pub r: f64,
    /// Degrees of freedom of `r^2`.
    pub dof: f64,
}

impl Stage {
    /// Chains the target needs at this stage's variance per chain, with
    /// its margin ([`planned_chains`]).
    pub(super) fn chains(&self, target: f64) -> u64 {
        let q = variance_margin(self.dof);
        planned_chains_with(self.batches, self.batch_size, self.r, target, q)
    }

    /// Variance per chain, relative: `r^2 batches batch_size`.
    fn per_chain(&self) -> f64 {
        self.r * self.r * self.batches as f64 * self.batch_size as f64
    }
}

/// The exponent with which a plan extrapolates the variance per chain
/// from the second pilot stage's batch size to the run's, `v(b) ~
/// b^-alpha`, from two stages at batch sizes `b1 < b2` (stratified
/// batches: exponents 0.33-0.45 measured on the Sobolev grid, 0.14-0.21 in
/// the office). The measured exponent's 90 % lower confidence bound,
/// `alpha^ - 1.2816 sigma` with `sigma^2 = (2 / dof_1 + 2 / dof_2) /
/// ln(b2 / b1)^2` the variance of the log ratio of two chi-square
/// estimates, and then half of it: a variance per chain that is a sum of
/// power laws (a part stratification reduces and a part it does not, or
/// receivers that differ) is convex in log-log, so beyond `b2` its slope
/// lies between 0 and the measured one, and half is the geometric middle
/// of the two factors; within `[0,` [`MAX_VARIANCE_FALL`]`]`. Returned
/// with its standard deviation (`sigma / 2`; 0 where it is clamped to 0),
/// which the plan's margin takes in ([`extrapolated_dof`]).
pub fn variance_fall(first: &Stage, second: &Stage) -> (f64, f64) {
    let (v1, v2) = (first.per_chain(), second.per_chain());
    let span = (second.batch_size as f64 / first.batch_size as f64).ln();
    if !(v1 > 0.0 && v2 > 0.0 && v1.is_finite() && v2.is_finite() && span > 0.0) {
        return (0.0, 0.0);
    }
    let alpha = (v1 / v2).ln() / span;
    let sigma = (2.0 / first.dof + 2.0 / second.dof).sqrt() / span;
    let fall = (0.5 * (alpha - 1.2816 * sigma)).clamp(0.0, MAX_VARIANCE_FALL);
    (fall, if fall > 0.0 { 0.5 * sigma } else { 0.0 })
}

/// Degrees of freedom of the pilot's error extrapolated to the run's
/// batches: the second stage's `dof` (`var ln R^2 = 2 / dof`) and the
/// fall's noise carried over `ln(bs / b2)`, `var = (ln(bs / b2) sd)^2`,
/// added on the log scale and returned as `2 / var`.
pub fn extrapolated_dof(dof: f64, fall_sd: f64, b2: u64, bs: u64) -> f64 {
    let lever = (bs as f64 / b2 as f64).ln().max(0.0) * fall_sd;
    2.0 / (2.0 / dof + lever * lever)
}

/// Degrees of freedom of the RMS relative error of `tallies` (whose batch
/// means keep every receiver): `B - 1` times the effective receivers
/// ([`crate::tally::rms_effective_receivers`]). The count is itself
/// estimated from the batches: its 90 % lower bound (the shared part of
/// the variance is measured with `B - 1` degrees of freedom), never below
/// one receiver's.
pub(super) fn rms_dof(tallies: &Tallies, direct: &[f64]) -> f64 {
    let m = crate::tally::rms_effective_receivers(&tallies.batch_means, direct);
    let b = tallies.batches().max(2) as f64;
    let lower = m / (1.0 + 1.2816 * (2.0 / (b - 1.0)).sqrt());
    let receivers = if m > 1.0 { lower.max(1.0) } else { m };
    receivers * (b - 1.0)
}

/// Time limit \[s\] of a `--rel-error` run given no `--time`: an unreachable
/// target stops here (with a message) rather than running forever.
pub const DEFAULT_REL_ERROR_CAP: f64 = 3600.0;

/// Chains per pilot batch for runs of `bs` chains per batch (the pilot
/// with `--batch-size`, and the second stage otherwise): an eighth
/// (at least 256, or `bs` if that is smaller), so that the pilot costs four
/// batches of the run proper. Its batch means are noisier, which only makes
/// the plan cautious: with stratified batches the variance per chain falls
/// as batches grow, so a plan from smaller batches errs on the long side.
pub fn pilot_batch_size(bs: u64) -> u64 {
    (bs / 8).max(bs.min(256)).max(1)
}

/// Batches the run proper needs after a pilot of `pilot_batches` batches
/// whose largest relative error is `r_p`, for the target `target` (module
/// docs): `max(32, ceil(B_p (r_p / target)^2 q))` with `q` the 90 % upper
/// confidence factor of the pilot's variance; `u64::MAX` when `r_p` is not
/// finite (no plan can be made).
pub fn planned_batches(pilot_batches: u64, r_p: f64, target: f64) -> u64 {
    let q = variance_margin((pilot_batches.max(2) - 1) as f64);
    planned_batches_with(pilot_batches, r_p, target, q)
}

/// The 90 % upper confidence factor `dof / chi2_dof(0.1)` of a variance
/// estimated with `dof` degrees of freedom (1.446 for 31).
pub fn variance_margin(dof: f64) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    dof / ChiSquared::new(dof).expect("positive dof").inverse_cdf(0.1)
}

/// [`planned_batches`] with the margin `q` given.
pub(super) fn planned_batches_with(pilot_batches: u64, r_p: f64, target: f64, q: f64) -> u64 {
    if !r_p.is_finite() {
        return u64::MAX;
    }
    let b = (pilot_batches as f64 * (r_p / target).powi(2) * q).ceil();
    if b >= u64::MAX as f64 {
        u64::MAX
    } else {
        (b as u64).max(MIN_BATCHES)
    }
}

/// Chains the run proper needs after a pilot of `pilot_batches` batches of
/// `pilot_bs` chains whose largest (or RMS) relative error is `r_p`: the
/// count of [`planned_batches`] expressed in chains, `B_p pilot_bs (r_p /
/// target)^2 q` (no minimum of batches); `u64::MAX` when no plan can be made.
pub fn planned_chains(pilot_batches: u64, pilot_bs: u64, r_p: f64, target: f64) -> u64 {
    let q = variance_margin((pilot_batches.max(2) - 1) as f64);
    planned_chains_with(pilot_batches, pilot_bs, r_p, target, q)
}

/// [`planned_chains`] with the margin `q` given.
fn planned_chains_with(pilot_batches: u64, pilot_bs: u64, r_p: f64, target: f64, q: f64) -> u64 {
    let c = (pilot_batches as f64 * pilot_bs as f64 * (r_p / target).powi(2) * q).ceil();
    if !c.is_finite() || c >= u64::MAX as f64 {
        u64::MAX
    } else {
        (c as u64).max(1)
    }
}

/// Chains per batch of a `--rel-error` run that needs `chains` chains, for
/// work whose default batch holds `default_bs` chains and whose pilot's
/// batches held `min_bs`: the largest power of two that still gives
/// [`MIN_BATCHES`] batches, between `min_bs` and `default_bs`. So a run that
/// needs fewer than `MIN_BATCHES` default batches does not overshoot to
/// them (one point at 0.1 %: 32 batches of 16,384 chains where about
/// 20,000 chains do), and one that needs more keeps the default size.
/// Larger batches are never worse here: with stratified batches the
/// variance per chain falls as batches grow, and the count of batches
/// stays at least 32 for the error bars.
pub fn plan_batch_size(chains: u64, min_bs: u64, default_bs: u64) -> u64 {
    let per_batch = (chains / MIN_BATCHES).max(1);
    // The largest power of two <= per_batch.
    let pow2 = 1u64 << (63 - per_batch.leading_zeros());
    pow2.clamp(min_bs.min(default_bs), default_bs)
}

/// Chains per batch of a run planned on its own first batches (module
/// docs): the largest power of two from the pilot stage's batches up to
/// `default_bs` (or `default_bs` itself) at which [`MIN_BATCHES`] batches
/// are still fewer than the target needs even if the variance per chain
/// fell as steeply as a plan allows ([`MAX_VARIANCE_FALL`]) from the
/// stage's batches. Batches too large would force 32 of them, more than
/// the target needs (up to twice the chains for one doubling too many);
/// one doubling too few costs at most the fall's factor over it (`2^alpha`,
/// 1.2-1.3 on the Sobolev grid), and usually nothing, as the sizes agree
/// once rounded to powers of two. No second pilot stage is needed.
pub fn calibrated_batch_size(stage: &Stage, target: f64, default_bs: u64) -> u64 {
    let b1 = stage.batch_size.min(default_bs).max(1);
    let central = (stage.batches * stage.batch_size) as f64 * (stage.r / target).powi(2);
    if !central.is_finite() {
        return default_bs;
    }
    let enough = |b: u64| {
        central * (b as f64 / b1 as f64).powf(-MAX_VARIANCE_FALL) >= (MIN_BATCHES * b) as f64
    };
    let mut bs = b1;
    loop {
        let next = (2 * bs).min(default_bs);
        if next == bs || !enough(next) {
            return bs;
        }
        bs = next;
    }
}
