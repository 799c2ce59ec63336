//! Threads, seeds, batches, stopping rules and timing. The runner knows
//! batches, not physics: it drives any [`BatchWork`], a work item that turns
//! a batch index into per-receiver sums (the local estimator in
//! [`crate::estimator::local`], the backward one in [`crate::backward`]).
//!
//! Work is cut into batches of `batch_size` chains. Chain `c` draws from the
//! Philox stream `(seed, c)` and batch `b` holds chains `b*batch_size ..
//! (b+1)*batch_size`, so a batch's sums depend only on `(seed, b)`. Worker
//! threads take batch indices from a shared counter; the calling thread folds
//! finished batches into the tallies strictly in index order. Hence results
//! are bit-identical for any thread count whenever the set of batches is the
//! same: always with `--chains` and with `--rel-error` (below). Only a run
//! stopped by `--time` depends on the machine's speed.
//!
//! # The `--rel-error` and `--rms-error` rules
//!
//! A run aimed at an error target grows its 32 batches stage by stage until
//! their own error meets it ([`grow`]: `--rel-error` and `--rms-error` on
//! the local estimator, in one process or over MPI ranks). Where batches
//! cannot grow (`--batch-size`, shards run apart, `--figure-target`, the
//! backward estimator, more than 2^24 sums at once) it is planned from a
//! pilot (or from its own first batches) by the rule of [`plan`]: [`drive`]
//! runs the stages and the run proper, [`plan`] holds the statistics that
//! size them.
//!
//! Why batches rather than per-chain tallies: a chain scores into every point
//! at every collision, so per-chain squares would cost as much as the scores
//! themselves; batch means are independent realisations and give the standard
//! error with `B - 1` degrees of freedom.

pub mod grow;
pub mod plan;

use crate::chain::ChainParams;
use crate::sampling::qmc::Qmc;
use crate::tally::bucket_count;
pub use crate::tally::{Batch, Tallies};
pub use plan::{
    CALIBRATION_BATCHES, CALIBRATION_RECEIVERS, DEFAULT_REL_ERROR_CAP, MAX_VARIANCE_FALL,
    PILOT_BATCHES, Pilot, Stage, calibrated_batch_size, extrapolated_dof, pilot_batch_size,
    plan_batch_size, planned_batches, planned_chains, variance_fall, variance_margin,
};
use plan::{
    PILOT_KEY, PRECISE_DOF, RMS_PRECISION_VALUES, SECOND_KEY, planned_batches_with, rms_dof,
};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// When to stop. At least one rule must be set; the first one met stops the run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stop {
    /// Number of chains (rounded up to whole batches).
    pub chains: Option<u64>,
    /// Wall-clock limit \[s\]. Soft: a run always completes at least
    /// [`MIN_BATCHES`] batches, so a very short limit may be exceeded.
    pub time: Option<f64>,
    /// Target for the largest relative standard error of `E` over the
    /// points (the RMS with `rms`), met by batches grown to it ([`grow`])
    /// or, where they cannot grow, by a pilot and a fixed count of fresh
    /// batches (see the [`plan`] docs).
    pub rel_error: Option<f64>,
    /// Time limit \[s\] of a `rel_error` run given no `time`; `None`:
    /// [`DEFAULT_REL_ERROR_CAP`].
    pub rel_error_cap: Option<f64>,
    /// The `rel_error` target is on the root mean square of the points'
    /// relative errors (`--rms-error`) rather than on the largest.
    pub rms: bool,
}

/// Fewest batches for a standard error (and for the `--rel-error` rule).
pub const MIN_BATCHES: u64 = 32;

/// Run configuration.
///
/// With `qmc` [`Qmc::Shift`], the emitted directions of a batch's chains
/// form a randomly shifted Sobol' (0,2)-net, and the first reflections use
/// Sobol' dimensions 3-4 of the same points (see [`crate::sampling::qmc`]);
/// with [`Qmc::Owen`], the light pick, emission position and direction and
/// the first three reflections are the coordinates of an Owen-scrambled
/// Sobol' net drawn afresh for every batch ([`crate::sampling::owen`],
/// [`crate::chain::LeadingUniforms::from_point`]). Either way each batch
/// mean stays unbiased and batches stay independent, while the first
/// collisions cover the surfaces evenly. Chain `c` then depends on `(seed, c)`
/// and on its batch's scramble, i.e. on `(seed, c, batch_size)`; in a batch
/// that grows ([`grow`]), chain `i` of batch `b` on `(seed, b, i)` and the
/// streams of its part; still never on the thread count.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// Seed of every random stream.
    pub seed: u64,
    /// Worker threads (0: all available cores).
    pub threads: usize,
    /// Stopping rules.
    pub stop: Stop,
    /// Resolve reflection orders `1..=orders` and the rest (0: indirect only).
    pub orders: u32,
    /// Random-walk parameters.
    pub chain: ChainParams,
    /// Chains per batch; `None` picks it from the number of points and `stop.chains`.
    pub batch_size: Option<u64>,
    /// How each batch stratifies its chains' leading uniforms (randomised Sobol' nets).
    pub qmc: Qmc,
    /// Near/far split of the local estimator: radius \[m\] (0: off) and
    /// backward paths per receiver for every 256 chains of a batch, for the
    /// near part (see [`crate::estimator::Receivers::with_near_field`]).
    pub near: (f64, u32),
    /// With `near.0 == 0`: choose the split per receiver where it is needed
    /// ([`crate::estimator::Receivers::with_auto_near_field`]), with
    /// `near.1` paths.
    pub near_auto: bool,
    /// With the split: each receiver's paths chosen by a fixed pilot
    /// ([`crate::estimator::near_paths`]) instead of `near.1` for all.
    pub near_paths_auto: bool,
    /// Run only shard `i` of `m` (batches `i, i + m, i + 2m, ...` of a
    /// `--chains` run) and keep the batches unfolded in
    /// [`RunResult::batches`], for [`fold_batches`] to merge later; `None`:
    /// the whole run.
    pub shard: Option<(u64, u64)>,
    /// Continue a `--chains` run from this checkpoint: its tallies after
    /// its first batches, then the batches after them (the result is the
    /// uninterrupted run's, bit for bit); `None`: start afresh.
    pub resume: Option<std::sync::Arc<crate::tally::checkpoint::Checkpoint>>,
    /// Keep the per-batch means of receivers `0 .. keep_batch_means` in
    /// [`Tallies::batch_means`] (for grid figures: 8 bytes per receiver
    /// and batch); 0: none.
    pub keep_batch_means: usize,
    /// What the `rel_error` rule's pilot measures, in place of the largest
    /// (or RMS) relative error; `None`: that error.
    pub pilot_measure: Option<PilotMeasure>,
    /// With `shard`: how the shards share the batches an RMS plan is
    /// measured on ([`plan`] docs), each tracing its own among them, and
    /// the parts of a run that grows its batches ([`grow`]); `None`: every
    /// shard traces the RMS plan's batches, and plans a target from a pilot.
    pub share: Option<Share>,
}

/// How shards that run at once (MPI ranks) share the batches a plan is
/// measured on: given this shard's own batches among them, the function
/// returns every shard's (in any order). It is called on the thread that
/// called [`drive`], by every shard alike: once for an RMS plan measured
/// on the run's first batches ([`plan`]), and once per stage, with the
/// stage's parts, for a run that grows its batches ([`grow`]).
#[derive(Clone)]
pub struct Share(pub std::sync::Arc<dyn Fn(Vec<Batch>) -> Vec<Batch> + Send + Sync>);

impl std::fmt::Debug for Share {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Share(..)")
    }
}

/// A caller's measure of a pilot run's precision for the two-stage
/// `rel_error` rule ([`plan`] docs), for targets that are not a receiver's
/// relative error: for example the half-width of a grid figure's 95 %
/// interval over its target (`--figure-target`, then `stop.rel_error = 1`).
/// It must fall like `1 / sqrt(chains)`, as a standard error does, for the
/// plan to hold; a non-finite value makes no plan (the run stops at its
/// time cap or chain count).
#[derive(Clone)]
pub struct PilotMeasure(pub std::sync::Arc<dyn Fn(&RunResult) -> f64 + Send + Sync>);

impl std::fmt::Debug for PilotMeasure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PilotMeasure(..)")
    }
}

/// The command line's defaults: 100,000 chains, stratified, the near/far
/// split where it is needed (`--near-radius auto`, each point's paths from
/// a pilot, `--near-paths auto`), light-guided
/// backward paths, Russian roulette at 0.1 of the starting weight.
impl Default for RunConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            threads: 0,
            stop: Stop {
                chains: Some(100_000),
                ..Stop::default()
            },
            orders: 0,
            chain: ChainParams::default(),
            batch_size: None,
            qmc: Qmc::default(),
            near: (0.0, 16),
            near_auto: true,
            near_paths_auto: true,
            shard: None,
            resume: None,
            keep_batch_means: 0,
            pilot_measure: None,
            share: None,
        }
    }
}

impl RunConfig {
    /// Defaults, stopped by wall time `seconds` only.
    pub fn timed(seed: u64, threads: usize, seconds: f64) -> Self {
        Self {
            seed,
            threads,
            stop: Stop {
                time: Some(seconds),
                ..Stop::default()
            },
            ..Self::default()
        }
    }
}

/// What stopped a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The requested number of chains (or the `--rel-error` plan capped by it).
    Chains,
    /// The wall-clock limit.
    Time,
    /// The batches planned by the `--rel-error` pilot.
    RelError,
    /// The observer asked to stop (an interrupt, a caller's own rule).
    Observer,
    /// The scene emits no light: the answer is exactly zero.
    NoLight,
}

/// A view of a run in progress, handed to the observer after each batch.
pub struct Progress<'a> {
    /// Tallies so far.
    pub tallies: &'a Tallies,
    /// Exact direct illuminance per point \[lx\].
    pub direct: &'a [f64],
    /// Chains folded in.
    pub chains: u64,
    /// Point scores evaluated in folded batches.
    pub scores: u64,
    /// Collisions in folded batches.
    pub collisions: u64,
    /// Wall time since the start \[s\] (of the first session, when resumed).
    pub elapsed: f64,
}

/// The outcome of a run.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// Exact direct illuminance per point \[lx\].
    pub direct: Vec<f64>,
    /// Indirect tallies per point.
    pub tallies: Tallies,
    /// Chains traced in the kept batches.
    pub chains: u64,
    /// Chains per batch.
    pub batch_size: u64,
    /// Collisions in the kept batches.
    pub collisions: u64,
    /// Point scores evaluated in the kept batches.
    pub scores: u64,
    /// Wall time of the whole run \[s\], the `--rel-error` pilot included.
    pub wall: f64,
    /// Threads used.
    pub threads: usize,
    /// What stopped the run.
    pub reason: StopReason,
    /// The `--rel-error` pilot, if the run had one (its batches are not in
    /// the tallies; its time is in `wall`).
    pub pilot: Option<Pilot>,
    /// How a `--time` run sized its batches from a timing probe, if it did
    /// (see [`time_batch_size`]).
    pub time_sizing: Option<TimeSizing>,
    /// A shard's batches, unfolded, in index order (empty unless
    /// [`RunConfig::shard`]); its tallies are then empty but for the checks.
    pub batches: Vec<Batch>,
    /// Batches of the whole run a shard belongs to (0 for a whole run).
    pub total_batches: u64,
}

/// The timing probe of a `--time` run: batches are sized so that at least
/// [`MIN_BATCHES`] of them fit in the time limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeSizing {
    /// Chains per second measured by the probe (all threads).
    pub rate: f64,
    /// The batch size the work would use by default.
    pub default_batch_size: u64,
    /// The batch size chosen.
    pub batch_size: u64,
    /// Estimated time of [`MIN_BATCHES`] batches at the chosen size \[s\]:
    /// above [`Self::left`] when even the smallest batches cannot fit.
    pub minimum_time: f64,
    /// Time left of the limit when the batches were sized \[s\].
    pub left: f64,
}

/// Smallest batch a `--time` run shrinks to, and the batch size of the
/// first stage of a `--rel-error` pilot (batch means of fewer chains are
/// too skewed for the checks).
pub const MIN_TIMED_BATCH: u64 = 256;

/// Fewest chains a batch of the `--rel-error` pilot has where the work's
/// own batch is small (see `drive`).
const MIN_PILOT_BATCH: u64 = 8;

/// Seed offset of the timing probe's streams.
const PROBE_KEY: u64 = 0x7072_6f62_6554_494d; // "probeTIM"

/// Batch size for a run limited by `seconds` of wall time, on `threads`
/// threads that each add pace (at most the cores) and with `in_flight`
/// batches in hand at once (one per thread asked for): one probe batch of
/// [`MIN_TIMED_BATCH`] chains (its own streams, not kept) measures the
/// pace, and the default size `bs` is halved until [`MIN_BATCHES`]
/// batches fit in 80 % of the time left and the batches in flight (those
/// the limit finds in hand, all folded) in 10 %, down to
/// [`MIN_TIMED_BATCH`]. Timed runs depend on the machine anyway (their
/// chain count does); runs with `--rel-error` never use this, and a run
/// whose `chains` fit in 80 % of the time left keeps `bs`.
pub fn time_batch_size(
    work: &dyn BatchWork,
    cfg: &RunConfig,
    bs: u64,
    (seconds, chains): (f64, Option<u64>),
    (threads, in_flight): (usize, u64),
    start: Instant,
) -> TimeSizing {
    let probe_cfg = RunConfig {
        seed: cfg.seed ^ PROBE_KEY,
        ..cfg.clone()
    };
    let probe = MIN_TIMED_BATCH.min(bs);
    let mut scratch = vec![0.0; work.scratch_len(bucket_count(cfg.orders))];
    let t = Instant::now();
    work.run_batch(&probe_cfg, 0, probe, bucket_count(cfg.orders), &mut scratch);
    let rate = probe as f64 / t.elapsed().as_secs_f64().max(1e-9) * threads.max(1) as f64;
    let left = (seconds - start.elapsed().as_secs_f64()).max(0.0);
    // A `--chains` run that fits in the time keeps its batches (and so its
    // bytes); one that may not reach its chains is sized by the time.
    let fits = chains.is_some_and(|c| c as f64 / rate <= 0.8 * left);
    let mut chosen = bs;
    let too_long = |c: u64| {
        (MIN_BATCHES * c) as f64 / rate > 0.8 * left || (in_flight * c) as f64 / rate > 0.1 * left
    };
    while !fits && chosen > MIN_TIMED_BATCH && too_long(chosen) {
        chosen /= 2;
    }
    let chosen = chosen.max(MIN_TIMED_BATCH.min(bs));
    TimeSizing {
        rate,
        default_batch_size: bs,
        batch_size: chosen,
        minimum_time: (MIN_BATCHES * chosen) as f64 / rate,
        left,
    }
}

impl RunResult {
    /// The final state as a [`Progress`] view.
    pub fn progress(&self) -> Progress<'_> {
        Progress {
            tallies: &self.tallies,
            direct: &self.direct,
            chains: self.chains,
            scores: self.scores,
            collisions: self.collisions,
            elapsed: self.wall,
        }
    }
}

/// Per-receiver checks a work item knows before it runs (see
/// [`crate::tally::Diagnostics`]).
#[derive(Clone, Debug, Default)]
pub struct Checks {
    /// Whether the `sparse` check applies to the receiver.
    pub watched: Vec<bool>,
    /// Whether the `near` check flags the receiver.
    pub near_plain: Vec<bool>,
    /// Whether the receiver has a near part whose reach is counted
    /// ([`crate::tally::Diagnostics::near_reach`]).
    pub near_reach: Vec<bool>,
    /// Whether the receiver is enclosed (flag `enclosed`; empty: none is).
    pub enclosed: Vec<bool>,
    /// Whether every result is an approximation (flag `approx`:
    /// [`crate::scene::Scene::approximate`]).
    pub approximate: bool,
}

/// A source of independent batches: a work item that turns a batch index
/// into per-receiver sums. The local estimator (chains from the lights,
/// [`crate::estimator::local`]) and the backward one (paths from the
/// receivers, [`crate::backward`]) are such items; the runner knows nothing
/// else of them.
pub trait BatchWork: Sync {
    /// Number of receivers.
    fn len(&self) -> usize;
    /// True when there are no receivers.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Exact part per receiver (the first order), added to every estimate.
    fn direct(&self) -> &[f64];
    /// False when the work can only ever score zero (no light is emitted):
    /// the answer is then exact and no batch is run.
    fn emits(&self) -> bool;
    /// Length of the per-thread scratch buffer for `buckets` buckets.
    fn scratch_len(&self, buckets: usize) -> usize;
    /// The per-receiver checks (none by default).
    fn checks(&self) -> Checks {
        Checks {
            watched: vec![false; self.len()],
            near_plain: vec![false; self.len()],
            near_reach: vec![false; self.len()],
            enclosed: Vec::new(),
            approximate: false,
        }
    }
    /// Default batch size for an optional chain count; must not depend on
    /// the seed, the thread count or the machine.
    fn default_batch_size(&self, chains: Option<u64>) -> u64;
    /// Run batch `b` of `bs` chains; `sums[k * n + j]` over the batch for bucket `k`, receiver `j`.
    fn run_batch(
        &self,
        cfg: &RunConfig,
        b: u64,
        bs: u64,
        buckets: usize,
        scratch: &mut [f64],
    ) -> Batch;

    /// Whether the work can grow a batch part by part ([`Self::run_part`]),
    /// for a `--rel-error` run that grows its batches ([`grow`]); false
    /// by default (the run then plans from a pilot, [`plan`]).
    fn grows(&self) -> bool {
        false
    }
    /// The sums over chains `part.lo .. part.hi` of batch `b`, for a
    /// batch that grows ([`grow`]): added part by part in order, they are a
    /// batch of `hi` chains whose net (the stratified leading uniforms) is
    /// one net of that size (up to the largest net; beyond, independent
    /// nets in a row). Called only where [`Self::grows`].
    fn run_part(
        &self,
        _cfg: &RunConfig,
        _b: u64,
        _part: Part,
        _buckets: usize,
        _scratch: &mut [f64],
    ) -> Batch {
        unreachable!("run_part on work that does not grow its batches")
    }
}

/// Chains `lo .. hi` of a batch that grows, its `index`-th part
/// ([`BatchWork::run_part`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Part {
    /// First chain of the part in its batch.
    pub lo: u64,
    /// One past its last.
    pub hi: u64,
    /// Parts before it in its batch.
    pub index: u32,
}

/// A default batch size `bs` capped so that a run of `chains` chains (if
/// given) still has at least [`MIN_BATCHES`] batches.
pub fn cap_batch_size(bs: u64, chains: Option<u64>) -> u64 {
    match chains {
        Some(c) => bs.min(c.div_ceil(MIN_BATCHES)).max(1),
        None => bs,
    }
}

/// The exact answer of work that emits nothing: zero batches (a merge of
/// such a run's shards, which hold none, gives the same).
pub fn no_light(direct: &[f64], cfg: &RunConfig) -> RunResult {
    let mut tallies = Tallies::new(direct.len(), cfg.orders);
    tallies.batch_means = crate::tally::BatchMeans::new(cfg.keep_batch_means.min(direct.len()));
    for _ in 0..MIN_BATCHES {
        for j in 0..direct.len() {
            tallies.batch_means.record(j, 0.0);
        }
        for w in tallies
            .estimated
            .iter_mut()
            .chain(tallies.orders.iter_mut().flatten())
        {
            w.push(0.0);
        }
    }
    RunResult {
        direct: direct.to_vec(),
        tallies,
        chains: 0,
        batch_size: 0,
        collisions: 0,
        scores: 0,
        wall: 0.0,
        threads: 0,
        reason: StopReason::NoLight,
        pilot: None,
        time_sizing: None,
        batches: Vec::new(),
        total_batches: 0,
    }
}

/// Drive any batch work: threads, ordered folding, stopping rules.
pub fn drive(
    work: &dyn BatchWork,
    cfg: &RunConfig,
    observe: &mut dyn FnMut(&Progress) -> bool,
) -> RunResult {
    if !work.emits() {
        return no_light(work.direct(), cfg);
    }
    let start = Instant::now();
    let stop = cfg.stop;
    assert!(
        cfg.shard.is_none() || stop.time.is_none(),
        "a shard needs a run of a fixed number of chains, or a --rel-error plan"
    );
    // Without a time limit the run proper stops at a default cap. (A shard
    // has no time cap: its batches must all be there to merge.)
    let default_cap = (stop.time.is_none() && cfg.shard.is_none())
        .then_some(stop.rel_error_cap.unwrap_or(DEFAULT_REL_ERROR_CAP));
    let capped = RunConfig {
        stop: Stop {
            time: stop.time.or(default_cap),
            ..stop
        },
        ..cfg.clone()
    };
    if let Some(target) = stop.rel_error.filter(|_| grow::applies(work, cfg)) {
        let cap = stop
            .chains
            .map_or(u64::MAX, |c| c.div_ceil(grow::GROWN_BATCHES))
            .min(grow::MAX_GROWN_CHAINS);
        return grow::grown_run(work, &capped, target, cap, default_cap, start, observe);
    }
    let mut bs = cfg
        .batch_size
        .unwrap_or_else(|| work.default_batch_size(stop.chains))
        .max(1);
    // A run limited by time (and perhaps by a chain count it may not
    // reach) sizes its batches so that the minimum of batches fits in the
    // limit; where the chains' batches fit, they stay as they are.
    let mut time_sizing = None;
    if let (Some(seconds), None, None) = (stop.time, stop.rel_error, cfg.batch_size) {
        // Threads beyond the cores add no pace (the probe's rate times
        // 64 threads on 2 cores planned batches 30 times too large).
        let cores = std::thread::available_parallelism().map_or(1, |p| p.get());
        // At the limit every thread's batch in hand is folded: that many
        // batches must fit too; only the threads up to the cores add pace.
        let asked = if cfg.threads == 0 { cores } else { cfg.threads };
        let sizing = time_batch_size(
            work,
            cfg,
            bs,
            (seconds, stop.chains),
            (asked.min(cores), asked as u64),
            start,
        );
        bs = sizing.batch_size;
        time_sizing = Some(sizing);
    }
    // At least two batches, so that every standard error exists.
    let by_chains = stop.chains.map_or(u64::MAX, |c| c.div_ceil(bs).max(2));
    let Some(target) = stop.rel_error else {
        let mut r = drive_batches(work, cfg, bs, by_chains, start, observe, None);
        r.time_sizing = time_sizing;
        return r;
    };
    // Every shard runs the whole pilot (deterministic), so all plan alike.
    // The first stage runs at the smallest batch size; a second stage runs
    // where the first plans batches more than 8 times larger (`plan` docs).
    // An RMS target over many receivers is measured more precisely than
    // one receiver's error: the pilot keeps the batch means to count the
    // effective receivers (`plan` docs), where they fit in
    // RMS_PRECISION_VALUES.
    let n = work.len();
    let correlations = stop.rms
        && cfg.pilot_measure.is_none()
        && (n as u64).saturating_mul(PILOT_BATCHES) <= RMS_PRECISION_VALUES;
    let pilot_at =
        |key: u64, pilot_bs: u64, batches: u64, observe: &mut dyn FnMut(&Progress) -> bool| {
            let pilot_cfg = RunConfig {
                seed: cfg.seed ^ key,
                shard: None,
                keep_batch_means: if correlations {
                    n
                } else {
                    cfg.keep_batch_means
                },
                ..cfg.clone()
            };
            let cap = by_chains.saturating_mul(bs);
            let batches = batches.min(cap / pilot_bs);
            let pilot = drive_batches(work, &pilot_cfg, pilot_bs, batches, start, observe, None);
            let r_p = match &cfg.pilot_measure {
                Some(m) => (m.0)(&pilot),
                None if stop.rms => pilot.tallies.rms_rel_error(&pilot.direct),
                None => pilot.tallies.max_rel_error(&pilot.direct),
            };
            let dof = if correlations {
                rms_dof(&pilot.tallies, &pilot.direct)
            } else {
                (pilot.tallies.batches().max(2) - 1) as f64
            };
            let stage = Stage {
                batches: pilot.tallies.batches(),
                batch_size: pilot_bs,
                r: r_p,
                dof,
            };
            (pilot, stage)
        };
    let fixed = cfg.batch_size.is_some();
    let first_bs = if fixed {
        pilot_batch_size(bs)
    } else if bs > MIN_TIMED_BATCH {
        MIN_TIMED_BATCH
    } else {
        // Work whose own batch is at most the pilot's size (costly chains:
        // the backward estimator's paths) pilots at a quarter of it, so
        // that the pilot costs a quarter of a minimum run, not a whole one
        // (the office at `--rel-error 1e-2` planned 32 batches of 110 after
        // a pilot of 32 more, 5.1 s, where 32 of 32 met it in 0.86 s).
        (bs / 4).max(MIN_PILOT_BATCH.min(bs))
    };
    let (mut pilot, mut stage) = pilot_at(PILOT_KEY, first_bs, PILOT_BATCHES, observe);
    if pilot.reason == StopReason::Observer {
        return pilot;
    }
    let mut pilot_chains = pilot.chains;
    // An RMS over several effective receivers is planned from the run's
    // own first batches (`plan` docs).
    let calibrate =
        correlations && stage.dof / (stage.batches.max(2) - 1) as f64 >= CALIBRATION_RECEIVERS;
    let mut stages = 1;
    let mut first_wall = 0.0;
    let (mut fall, mut fall_sd) = (0.0, 0.0);
    if !fixed {
        let sized = plan_batch_size(stage.chains(target), stage.batch_size, bs);
        if sized > 8 * stage.batch_size && !calibrate {
            let first = stage;
            first_wall = pilot.wall;
            // A precise first stage (an RMS over many receivers) affords
            // half the batches at twice the size for the same chains: the
            // fall is then measured over two doublings and extrapolated
            // over two.
            let (second_bs, second_batches) = if first.dof >= PRECISE_DOF {
                (2 * pilot_batch_size(sized), PILOT_BATCHES / 2)
            } else {
                (pilot_batch_size(sized), PILOT_BATCHES)
            };
            (pilot, stage) = pilot_at(PILOT_KEY ^ SECOND_KEY, second_bs, second_batches, observe);
            if pilot.reason == StopReason::Observer {
                return pilot;
            }
            pilot_chains += pilot.chains;
            stages = 2;
            // The effective receivers depend on how they share chains,
            // which the first stage's 32 batches count more steadily; the
            // fewer of the two stages' counts is kept.
            let receivers = |s: &Stage| s.dof / (s.batches.max(2) - 1) as f64;
            stage.dof =
                receivers(&first).min(receivers(&stage)) * (stage.batches.max(2) - 1) as f64;
            if correlations {
                (fall, fall_sd) = variance_fall(&first, &stage);
            }
        }
        bs = if calibrate {
            calibrated_batch_size(&stage, target, bs)
        } else {
            plan_batch_size(stage.chains(target), stage.batch_size, bs)
        };
        stage.dof = extrapolated_dof(stage.dof, fall_sd, stage.batch_size, bs);
    }
    let pilot_bs = stage.batch_size;
    let by_chains = stop.chains.map_or(u64::MAX, |c| c.div_ceil(bs).max(2));
    let mut plan = Pilot {
        target,
        batches: pilot.tallies.batches(),
        batch_size: pilot_bs,
        wall: pilot.wall,
        rel_error: stage.r,
        rms: stop.rms,
        custom: cfg.pilot_measure.is_some(),
        dof: stage.dof,
        fall: 0.0,
        planned: 0,
        estimated_time: f64::INFINITY,
        default_cap,
        stages,
        pilot_chains,
        calibration: 0,
        calibration_traced: 0,
        grown: 0,
        cut: false,
    };
    if calibrate {
        return calibrated_run(work, &capped, bs, by_chains, start, observe, plan);
    }
    // R^2 falls like 1 / chains, and with the variance per chain like
    // (batch size)^-fall: rescale the pilot's error to batches of `bs`.
    let r_p = stage.r * (pilot_bs as f64 / bs as f64).powf(0.5 * (1.0 + fall));
    let planned = planned_batches_with(stage.batches, r_p, target, variance_margin(stage.dof));
    // The pilot's pace per chain gives the run proper's time.
    let per_chain = (pilot.wall - first_wall) / pilot.chains.max(1) as f64;
    let mut result = drive_batches(
        work,
        &capped,
        bs,
        run_length(planned, by_chains, 0, r_p),
        start,
        observe,
        None,
    );
    if result.reason == StopReason::Chains && planned <= by_chains {
        result.reason = StopReason::RelError;
    }
    plan.rel_error = r_p;
    plan.fall = fall;
    plan.planned = planned;
    plan.estimated_time = per_chain * planned as f64 * bs as f64;
    result.pilot = Some(plan);
    result
}

/// The run proper of an RMS target over several effective receivers
/// ([`plan`] docs): its first [`CALIBRATION_BATCHES`] batches of `bs` chains
/// measure the RMS relative error and its degrees of freedom at the run's
/// own batch size, and the plan `B = max(32, ceil(32 (R_c / target)^2
/// q))` counts them; the estimate keeps them. Every shard traces the
/// calibrating batches itself (so that all plan alike) and keeps its own
/// among them, or, with [`RunConfig::share`], traces its own and receives
/// the others'. `plan` holds what the pilot measured; it is completed here.
fn calibrated_run(
    work: &dyn BatchWork,
    capped: &RunConfig,
    bs: u64,
    by_chains: u64,
    start: Instant,
    observe: &mut dyn FnMut(&Progress) -> bool,
    mut plan: Pilot,
) -> RunResult {
    let n = work.len();
    let cal = CALIBRATION_BATCHES.min(by_chains);
    let direct = work.direct();
    let keep = capped.keep_batch_means;
    let finish = |mut r: RunResult, plan: Pilot| {
        r.tallies.batch_means.truncate(keep);
        r.pilot = Some(plan);
        r
    };
    // The calibrating batches: folded with every receiver's batch means
    // (a whole run), or unfolded (a shard): all of them, or the shard's
    // own where the shards share them.
    let shared = capped.shard.and(capped.share.clone());
    let cal_cfg = RunConfig {
        keep_batch_means: n.max(keep),
        shard: capped
            .shard
            .map(|s| if shared.is_some() { s } else { (0, 1) }),
        ..capped.clone()
    };
    let mut first = drive_batches(work, &cal_cfg, bs, cal, start, observe, None);
    plan.calibration_traced = match capped.shard {
        Some(_) => first.batches.len() as u64,
        None => first.tallies.batches(),
    };
    let mut everyone = Vec::new();
    if let Some(share) = shared
        .as_ref()
        .filter(|_| first.reason == StopReason::Chains)
    {
        everyone = (share.0)(first.batches.clone());
        everyone.sort_by_key(|b| b.index);
        assert!(
            everyone.iter().map(|b| b.index).eq(0..cal),
            "the shards shared batches other than 0 .. {cal}"
        );
    }
    let folded;
    let measured = if capped.shard.is_some() {
        let mut t = Tallies::new(n, capped.orders);
        t.batch_means = crate::tally::BatchMeans::new(n);
        let all = if shared.is_some() {
            &everyone
        } else {
            &first.batches
        };
        folded = fold_batches(t, direct, bs, all);
        &folded
    } else {
        &first.tallies
    };
    let r_c = measured.rms_rel_error(direct);
    plan.batches = measured.batches();
    plan.batch_size = bs;
    plan.rel_error = r_c;
    plan.dof = rms_dof(measured, direct);
    plan.calibration = measured.batches();
    // From the batches measured: all `cal` of them, unless the observer
    // stopped the run first.
    plan.planned = planned_batches_with(
        plan.calibration,
        r_c,
        plan.target,
        variance_margin(plan.dof),
    );
    let per_chain = (first.wall - plan.wall) / first.chains.max(1) as f64;
    plan.estimated_time = per_chain * plan.planned as f64 * bs as f64;
    // A shard keeps only its own among the calibrating batches, with their
    // counts (a no-op where the shards shared them out).
    if let Some((i, m)) = capped.shard {
        first.batches.retain(|b| b.index % m == i);
        first.chains = first.batches.iter().map(|b| b.chains).sum();
        first.collisions = first.batches.iter().map(|b| b.collisions).sum();
        first.scores = first.batches.iter().map(|b| b.scores).sum();
    }
    // Stopped early (by the observer): what was done is the result.
    if first.reason != StopReason::Chains {
        return finish(first, plan);
    }
    let mut tallies = first.tallies;
    tallies.batch_means.truncate(keep);
    let prior = Prior {
        folded: cal,
        chains: first.chains,
        collisions: first.collisions,
        scores: first.scores,
        wall: 0.0,
        tallies: capped.shard.is_none().then_some(tallies),
        batches: first.batches,
    };
    let total = run_length(plan.planned, by_chains, cal, r_c);
    let mut result = drive_batches(work, capped, bs, total, start, observe, Some(prior));
    if result.reason == StopReason::Chains && plan.planned <= by_chains {
        result.reason = StopReason::RelError;
    }
    finish(result, plan)
}

/// Batches a planned run folds in all: the plan capped by `--chains`
/// (`by_chains`); when no plan could be made because the measured error
/// `r` is not finite (a receiver's estimate is not a number, which no run
/// length mends), the least a run has ([`MIN_BATCHES`], or the `least`
/// already folded), so that it neither runs to the time cap nor, as a
/// shard (which has none), forever. (A plan too large to count, from a
/// finite error and a tiny target, runs until a limit stops it.)
fn run_length(planned: u64, by_chains: u64, least: u64, r: f64) -> u64 {
    if r.is_finite() {
        planned.min(by_chains)
    } else {
        least.max(MIN_BATCHES).min(by_chains)
    }
}

/// Batches `0 .. folded` of the run proper, done before [`drive_batches`]
/// continues it: folded into `tallies` (a whole run) or, for a shard, its
/// own among them, unfolded in `batches`; with their counts.
struct Prior {
    folded: u64,
    chains: u64,
    collisions: u64,
    scores: u64,
    /// Wall time before `start` \[s\] (a resumed run's first session).
    wall: f64,
    tallies: Option<Tallies>,
    batches: Vec<Batch>,
}

/// Fold batches `0 .. max_batches` of `bs` chains (fewer when the time
/// limit or the observer stops the run first); `start` is when the run
/// began. With `prior` (or a checkpoint in `cfg.resume`), batches before
/// its `folded` are taken from it rather than run.
fn drive_batches(
    work: &dyn BatchWork,
    cfg: &RunConfig,
    bs: u64,
    max_batches: u64,
    start: Instant,
    observe: &mut dyn FnMut(&Progress) -> bool,
    prior: Option<Prior>,
) -> RunResult {
    let n = work.len();
    let buckets = bucket_count(cfg.orders);
    let threads = if cfg.threads == 0 {
        std::thread::available_parallelism().map_or(1, |p| p.get())
    } else {
        cfg.threads
    };
    let mut tallies = empty_tallies(work, cfg);
    let direct = work.direct().to_vec();
    let mut result = RunResult {
        direct: Vec::new(),
        tallies: Tallies::new(0, 0),
        chains: 0,
        batch_size: bs,
        collisions: 0,
        scores: 0,
        wall: 0.0,
        threads,
        reason: StopReason::Chains,
        pilot: None,
        time_sizing: None,
        batches: Vec::new(),
        total_batches: 0,
    };
    // A shard runs every m-th batch from i: the k-th of its batches is
    // batch i + k m of the whole run.
    let (first, step) = cfg.shard.unwrap_or((0, 1));
    let max_batches = if cfg.shard.is_some() {
        result.total_batches = max_batches;
        max_batches.saturating_sub(first).div_ceil(step)
    } else {
        max_batches
    };
    // A resumed run starts from its checkpoint's tallies and batch.
    let prior = prior.or_else(|| match &cfg.resume {
        Some(c) if cfg.shard.is_none() => Some(Prior {
            folded: c.folded,
            chains: c.chains,
            collisions: c.collisions,
            scores: c.scores,
            wall: c.wall,
            tallies: Some(c.tallies.clone()),
            batches: Vec::new(),
        }),
        _ => None,
    });
    // `resumed` counts in the shard's own batches: its k-th is batch
    // `first + k step`.
    let (resumed, prior_wall) = match prior {
        Some(p) => {
            if let Some(t) = p.tallies {
                tallies = t;
            }
            result.chains = p.chains;
            result.collisions = p.collisions;
            result.scores = p.scores;
            result.batches = p.batches;
            let k = if cfg.shard.is_some() {
                p.folded.saturating_sub(first).div_ceil(step)
            } else {
                p.folded
            };
            (k, p.wall)
        }
        None => (0, 0.0),
    };
    let next = AtomicU64::new(resumed);
    let halt = AtomicBool::new(false);
    let (tx, rx) = mpsc::channel::<Batch>();
    let mut keep_until = u64::MAX; // batches with index >= this are discarded
    std::thread::scope(|s| {
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, halt) = (&next, &halt);
            s.spawn(move || {
                let mut acc = vec![0.0; work.scratch_len(buckets)];
                loop {
                    if halt.load(Ordering::Relaxed) {
                        break;
                    }
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    if k >= max_batches {
                        break;
                    }
                    let batch = work.run_batch(cfg, first + k * step, bs, buckets, &mut acc);
                    if tx.send(batch).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);

        let mut pending: BTreeMap<u64, Batch> = BTreeMap::new();
        let mut folded = resumed;
        let mut batch_means = vec![0.0; buckets * n];
        loop {
            match rx.recv_timeout(Duration::from_millis(50)) {
                Ok(b) => {
                    pending.insert((b.index - first) / step, b);
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
            // The time limit is soft: at least MIN_BATCHES batches are always
            // folded, so that every standard error has enough degrees of freedom.
            if cfg
                .stop
                .time
                .is_some_and(|t| start.elapsed().as_secs_f64() >= t)
                && folded >= MIN_BATCHES.min(max_batches)
                && !halt.load(Ordering::Relaxed)
            {
                halt.store(true, Ordering::Relaxed);
                result.reason = StopReason::Time;
            }
            while let Some(b) = pending.remove(&folded) {
                if folded >= keep_until {
                    folded += 1;
                    continue;
                }
                result.chains += b.chains;
                result.collisions += b.collisions;
                result.scores += b.scores;
                if cfg.shard.is_some() {
                    result.batches.push(b);
                } else {
                    fold_batch(&mut tallies, &direct, &b, bs, &mut batch_means);
                }
                folded += 1;
                let progress = Progress {
                    tallies: &tallies,
                    direct: &direct,
                    chains: result.chains,
                    scores: result.scores,
                    collisions: result.collisions,
                    elapsed: prior_wall + start.elapsed().as_secs_f64(),
                };
                if !observe(&progress) && keep_until == u64::MAX {
                    result.reason = StopReason::Observer;
                    keep_until = folded;
                    halt.store(true, Ordering::Relaxed);
                }
            }
        }
    });
    result.direct = direct;
    result.tallies = tallies;
    result.wall = prior_wall + start.elapsed().as_secs_f64();
    result
}

/// Tallies of `work` with nothing folded: its per-receiver checks, and
/// room for the batch means `cfg` keeps.
fn empty_tallies(work: &dyn BatchWork, cfg: &RunConfig) -> Tallies {
    let n = work.len();
    let mut tallies = Tallies::new(n, cfg.orders);
    let checks = work.checks();
    tallies.watched = checks.watched;
    tallies.near_plain = checks.near_plain;
    tallies.near_reach = checks.near_reach;
    tallies.enclosed = checks.enclosed;
    tallies.approximate = checks.approximate;
    tallies.batch_means = crate::tally::BatchMeans::new(cfg.keep_batch_means.min(n));
    tallies
}

/// Fold one batch of `bs` chains into the tallies, with the snapshots of
/// the FOM check at 32, 64, 128, ... batches: the one place batches are
/// folded, by a run and by [`fold_batches`] alike.
fn fold_batch(tallies: &mut Tallies, direct: &[f64], b: &Batch, bs: u64, means: &mut [f64]) {
    tallies.fold(&b.sums, &b.direct_sums, bs, &b.near_hits, means);
    let folded = tallies.batches();
    if folded >= 32 && folded.is_power_of_two() {
        tallies.snapshot(direct);
    }
}

/// The tallies of a whole run from its batches (the shards' batches in
/// index order `0, 1, 2, ...`) of `bs` chains: `tallies` holds the
/// per-receiver checks and nothing folded yet. Folded as a run folds them,
/// so the result is bit-identical to the run's.
pub fn fold_batches(mut tallies: Tallies, direct: &[f64], bs: u64, batches: &[Batch]) -> Tallies {
    let n = tallies.estimated.len();
    let buckets = batches.first().map_or(1, |b| b.sums.len() / n.max(1));
    let mut means = vec![0.0; buckets * n];
    for b in batches {
        fold_batch(&mut tallies, direct, b, bs, &mut means);
    }
    tallies
}
