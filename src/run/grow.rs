//! A `--rel-error` run that grows its batches instead of planning them
//! from a pilot ([`super::plan`]): [`GROWN_BATCHES`] batches, each one
//! Owen-scrambled Sobol' net, all extended part by part until their own
//! error meets the target.
//!
//! # Why
//!
//! A pilot on streams of its own costs chains the estimate never uses, and
//! on one Sobolev point at 0.1 % it costs as much as the run it plans: the
//! least fixed run there is 32 batches of about 512 chains, and the pilot
//! is 32 batches of 256. Batches that are nets also gain with their size:
//! on that point the variance per chain of a batch of 512 is half that of
//! one of 256, so a pilot of small batches misjudges the run's, and a
//! stopping rule that adds batches of a fixed size never reaches the
//! variance of larger nets. A net can grow: its first `m` points are a
//! good set for every `m`, best at powers of two (up to the net's 2^16
//! points, below). So the run keeps its 32
//! batches and extends each (chains `n_k .. n_{k+1}` of the same
//! scrambled net, [`super::BatchWork::run_part`]):
//!
//! 1. the first part gives each batch [`super::MIN_TIMED_BATCH`] chains;
//! 2. after each stage the 32 batches measure the largest (or RMS)
//!    relative error `R_k` at size `n_k`; the run stops where `R_k <=
//!    target`;
//! 3. otherwise the next size is `n_k (R_k / target)^(2 / (1 + alpha))`
//!    times [`STAGE_MARGIN`], at least [`MIN_GROWTH`] times `n_k`, rounded
//!    up to [`GRAIN`] chains, where `alpha` is the fall of the variance per
//!    chain with the size, `v(n) ~ n^-alpha`, measured between the first
//!    stage and the last (assumed [`FIRST_FALL`] after the first), clamped
//!    to `0 ..= 1`: an error that falls faster than planned only costs a
//!    further stage, never chains already traced.
//!
//! Every chain traced is in the estimate, so the run costs its final size
//! and the rounding: on the Sobolev point at 0.1 % about the least fixed
//! run's chains (module tests and `tests/grown_batches.rs`).
//!
//! # What it costs in bias
//!
//! The stopping rule looks at the batches the estimate keeps. Where batch
//! means are normal, their mean is independent of their spread at every
//! stage (the sample mean vector of i.i.d. normal vectors is independent of
//! the sample covariance). The stop does not depend on the spreads alone,
//! though: the relative error divides by the estimate, so a run whose mean
//! is high stops a little early and the mean is biased up, by about `X`
//! standard errors at a target `X` (a reviewer's simulation of this rule
//! with normal parts, 20,000 runs each: mean z +0.002 +- 0.007 at `X` =
//! 1e-2, +0.073 at 0.05, +0.106 at 0.1, +0.215 at 0.2), `X^2` relative:
//! nothing at the targets lighting work asks for. A run also stops at the
//! first stage whose measured spread is under the target, so the spread it
//! reports is a little low when the true error sits near the target. And
//! skewed batch means add a bias (a low batch mean tends to come with a
//! small spread). These are measured on the Sobolev point against its
//! exact value (`tests/grown_batches.rs`: coverage of the 95 % interval and
//! mean `z^2` over independent runs), and on skewed synthetic work. The
//! skew's bias is downward where the skewed point decides the stop: a
//! reviewer's Sobolev floor point at r = 10 m (the largest R of 9 points)
//! read -2.2 % at `--rel-error 0.1` and -1.4 % at 0.05 (about 0.2 standard
//! errors, coverage 87.6 % against 91.7 % for fixed runs of the same
//! length), nothing significant at 0.03 (README, "Stopping rules"). Where
//! the pilot rule's unbiased fresh batches matter more than the chains,
//! `--batch-size` keeps it.
//!
//! A batch past [`crate::sampling::owen::MAX_POINTS`] chains is several
//! independent scrambles of that net in a row, still unbiased; its
//! variance per chain then stops falling with its size, which the fall
//! measured between the stages follows.
//!
//! A stage's part of a batch longer than [`CHUNK`] chains is traced in
//! chunks of it, each a part of its own (its own streams for near paths,
//! pool and sampled direct light), so that a long stage is more than 32
//! tasks; the chunks depend on the sizes alone, so the result does not
//! depend on the threads.
//!
//! An interrupt (the observer saying stop) within a stage keeps the
//! stage's chunks folded by then, a prefix in task order, which is
//! chunk-major (so the batches differ by at most one chunk: each mean is
//! unbiased for its size); shards that share their parts vote at every
//! stage's end and all stop there together.
//!
//! # Where it applies
//!
//! Runs with a `--rel-error` or `--rms-error` target and no
//! `--batch-size`, on work that grows its batches (the local estimator;
//! [`super::BatchWork::grows`]), when the 32 batches' sums fit in
//! [`GROWN_VALUES`], in one process or over MPI ranks, which trace their
//! own batches' parts and exchange them at every stage
//! ([`super::RunConfig::share`]) so that all plan alike and rank 0 folds
//! the single process's batches. Shards run apart (`--shard`) cannot
//! exchange: they plan from the pilot, or an RMS target over many receivers
//! from the run's own first batches ([`super::plan`]). Measured against
//! that plan on the 100 x 100 Sobolev grid at `--rms-error 1e-3` (seeds
//! 1-3): 272,384-288,768 chains against 278,528-315,392; on the office's
//! 66 points at 4e-3: 18,432 chains against 24,576-25,600 and the pilot's
//! 8,192.

use super::{
    Batch, BatchWork, Part, Pilot, Progress, RunConfig, RunResult, StopReason, drive_batches,
    empty_tallies, fold_batches,
};
use crate::tally::bucket_count;
use std::time::Instant;

/// Batches of a grown run.
pub const GROWN_BATCHES: u64 = super::MIN_BATCHES;

/// Least growth of a batch from one stage to the next.
pub const MIN_GROWTH: f64 = 1.2;

/// Factor on the size a stage plans, so that about two runs in three end
/// at the planned stage rather than one after it.
pub const STAGE_MARGIN: f64 = 1.05;

/// Fall of the variance per chain with a batch's size assumed after the
/// first stage (`v(n) ~ n^-1`, a smooth integrand's net; measured 1.0 on a
/// Sobolev point): too steep a fall costs a further stage, too shallow
/// one chains beyond the target.
pub const FIRST_FALL: f64 = 1.0;

/// A batch's size is a multiple of this many chains after its first part.
pub const GRAIN: u64 = 64;

/// Most chains a grown batch has (its chains' streams are numbered within
/// 32 bits, [`super::BatchWork::run_part`]).
pub const MAX_GROWN_CHAINS: u64 = 1 << 32;

/// The batch index of a shard's vote to stop, in the exchange at a stage's
/// end.
const STOP_VOTE: u64 = u64::MAX;

/// Most sums (receivers times buckets times [`GROWN_BATCHES`]) a grown run
/// keeps: 128 MB of sums. Each batch (and each chunk of a stage, held
/// until the stage ends) also keeps per receiver its near-hit counts (one,
/// or three with reach counts) and its sampled direct sum, 8 bytes each;
/// the batches grown so far and a stage's chunks (sized so that their sums
/// stay within the bound too) are held at once. So at the bound, with one
/// order, a run holds up to about six times 128 MB (not measured), more
/// with reach counts or MPI's exchange buffers.
pub const GROWN_VALUES: u64 = 1 << 24;

/// Whether a run aiming at an error target grows its batches (module docs).
pub(super) fn applies(work: &dyn BatchWork, cfg: &RunConfig) -> bool {
    let n = work.len() as u64;
    let values = n
        .saturating_mul(bucket_count(cfg.orders) as u64)
        .saturating_mul(GROWN_BATCHES);
    work.grows()
        && cfg.batch_size.is_none()
        && cfg.pilot_measure.is_none()
        && cfg.resume.is_none()
        && (cfg.shard.is_none() || cfg.share.is_some())
        && values <= GROWN_VALUES
}

/// Chains a batch's part holds at most: a stage's part of each batch
/// longer than this is traced in chunks of it, each a part of its own, so
/// that a stage is more than 32 tasks where it is long (on more than 32
/// threads, or over ranks); fewer, larger chunks where the stage's chunks
/// would hold more than [`GROWN_VALUES`] sums. The chunks depend only on
/// the sizes and the receivers, never on the threads.
pub const CHUNK: u64 = 4096;

/// A stage: chains `lo .. hi` of every batch, in chunks of [`CHUNK`], as
/// batch work of their own; its "batch" `k` is chunk `k / GROWN_BATCHES`
/// of batch `k % GROWN_BATCHES`: chunk-major, so that the prefix of tasks
/// an interrupt or a time limit keeps leaves the batches within one chunk
/// of each other (batch-major, it kept some batches whole and the rest at
/// the last stage's size, and their mean lost most of the stage: the
/// office cut by `--time 3` read max R 7.7e-3 to 1.2e-2 where whole
/// stages read 1.6e-3).
struct PartWork<'a> {
    work: &'a dyn BatchWork,
    lo: u64,
    hi: u64,
    /// Chains per chunk: [`CHUNK`], or more where the stage's chunks
    /// would hold more sums than [`GROWN_VALUES`] at once.
    chunk: u64,
    /// Part number of the stage's first chunk.
    first: u32,
}

impl PartWork<'_> {
    /// Chunks per batch in the stage.
    fn chunks(&self) -> u64 {
        (self.hi - self.lo).div_ceil(self.chunk)
    }
}

impl BatchWork for PartWork<'_> {
    fn len(&self) -> usize {
        self.work.len()
    }
    fn direct(&self) -> &[f64] {
        self.work.direct()
    }
    fn emits(&self) -> bool {
        self.work.emits()
    }
    fn scratch_len(&self, buckets: usize) -> usize {
        self.work.scratch_len(buckets)
    }
    fn checks(&self) -> super::Checks {
        self.work.checks()
    }
    fn default_batch_size(&self, chains: Option<u64>) -> u64 {
        self.work.default_batch_size(chains)
    }
    fn run_batch(
        &self,
        cfg: &RunConfig,
        k: u64,
        _bs: u64,
        buckets: usize,
        scratch: &mut [f64],
    ) -> Batch {
        let (b, c) = (k % GROWN_BATCHES, k / GROWN_BATCHES);
        let lo = self.lo + c * self.chunk;
        let part = Part {
            lo,
            hi: (lo + self.chunk).min(self.hi),
            index: self.first + c as u32,
        };
        let mut chunk = self.work.run_part(cfg, b, part, buckets, scratch);
        chunk.index = k;
        chunk
    }
}

/// Add a stage's chunks (`index` counting chunk `c` of batch `b` as `c
/// GROWN_BATCHES + b`, in that order) to the batches grown so far: each
/// batch takes its chunks in chunk order, so its sums do not depend on
/// the numbering.
fn add_chunks(grown: &mut Vec<Batch>, chunks: Vec<Batch>) {
    for mut c in chunks {
        c.index %= GROWN_BATCHES;
        match grown.get_mut(c.index as usize) {
            Some(g) => g.extend(&c),
            None => grown.push(c),
        }
    }
}

/// The next size `next` held to what a time limit leaves: at most `fits`
/// more chains per batch than `size`, in whole grains. Saturating: a time
/// limit far beyond any run (`--time 1e15`) gives `fits` near `u64::MAX`,
/// whose sum with `size` wrapped to a size below `size` before.
fn time_bound(next: u64, size: u64, fits: u64) -> u64 {
    next.min(size.saturating_add(fits / GRAIN * GRAIN))
}

/// The fall of the variance per chain with the size, `v(n) ~ n^-alpha`,
/// between the first stage and the last, `(size, error)`; `None` with one.
pub fn fall(stages: &[(u64, f64)]) -> Option<f64> {
    match stages {
        [(n1, r1), .., (n, r)] if n > n1 => {
            Some(2.0 * (r1 / r).ln() / (*n as f64 / *n1 as f64).ln() - 1.0)
        }
        _ => None,
    }
}

/// The size of the next stage from the stages so far, `(size, error)`
/// (module docs), at most `cap`.
pub fn next_size(stages: &[(u64, f64)], target: f64, cap: u64) -> u64 {
    let (n, r) = *stages.last().expect("a stage");
    let alpha = match fall(stages) {
        Some(a) if a.is_nan() => 0.0,
        Some(a) => a.clamp(0.0, 1.0),
        None => FIRST_FALL,
    };
    let growth = ((r / target).powf(2.0 / (1.0 + alpha)) * STAGE_MARGIN).max(MIN_GROWTH);
    // (`as` saturates: an enormous growth is capped below.)
    let want = (n as f64 * growth).ceil() as u64;
    want.div_ceil(GRAIN)
        .saturating_mul(GRAIN)
        .clamp(n + 1, cap.max(n + 1))
}

/// Run the grown batches (module docs) of `work` under `cfg` (with its
/// time cap, the default one being `default_cap`) to `target`, at most
/// `cap` chains a batch.
pub(super) fn grown_run(
    work: &dyn BatchWork,
    cfg: &RunConfig,
    target: f64,
    cap: u64,
    default_cap: Option<f64>,
    start: Instant,
    observe: &mut dyn FnMut(&Progress) -> bool,
) -> RunResult {
    let direct = work.direct();
    let shared = cfg.shard.and(cfg.share.clone());
    // Every part run keeps its batches unfolded (a shard's own, where the
    // shards share them out).
    let part_cfg = RunConfig {
        shard: Some(cfg.shard.unwrap_or((0, 1))),
        ..cfg.clone()
    };
    let mut grown: Vec<Batch> = Vec::new();
    let mut stages: Vec<(u64, f64)> = Vec::new();
    let mut size = 0;
    let mut next = super::MIN_TIMED_BATCH.min(cap).max(1);
    let mut reason = StopReason::RelError;
    // Interrupted within a stage, its parts kept.
    let mut cut = false;
    let mut tallies = empty_tallies(work, cfg);
    let (mut traced, mut stage_wall) = (0u64, 0.0);
    // Parts begun in all batches' nets so far (each chunk one), and the
    // most chunks a batch's part is cut into: a stage holds its chunks'
    // sums until it ends, at most GROWN_VALUES of them.
    let mut part_index = 0u32;
    // Whether the run said that its target lies beyond its time limit.
    let mut warned = false;
    let per_batch = (work.len() * bucket_count(cfg.orders)) as u64 * GROWN_BATCHES;
    let max_chunks = (GROWN_VALUES / per_batch.max(1)).max(1);
    loop {
        let t = Instant::now();
        let part = PartWork {
            work,
            lo: size,
            hi: next,
            chunk: CHUNK.max((next - size).div_ceil(max_chunks)),
            first: part_index,
        };
        let chunks = part.chunks();
        part_index += chunks as u32;
        let tasks = GROWN_BATCHES * chunks;
        // Shards that share their parts finish every stage: an interrupt
        // is noted and put to a vote at the stage's end (below), so that
        // all stop after the same stage rather than one leaving the others
        // waiting in an exchange.
        let mut asked = false;
        // Within a stage the observer sees the run so far: the stages
        // before this one (their tallies, last folded) and this stage's
        // chains folded by now, so that a progress bar never goes back.
        let before = (
            grown.iter().map(|b| b.chains).sum::<u64>(),
            grown.iter().map(|b| b.scores).sum::<u64>(),
            grown.iter().map(|b| b.collisions).sum::<u64>(),
        );
        let mut relay = |p: &Progress| {
            let so_far = Progress {
                tallies: &tallies,
                direct,
                chains: before.0 + p.chains,
                scores: before.1 + p.scores,
                collisions: before.2 + p.collisions,
                elapsed: p.elapsed,
            };
            let go = observe(&so_far);
            asked |= !go;
            go || shared.is_some()
        };
        let r = drive_batches(
            &part,
            &part_cfg,
            next - size,
            tasks,
            start,
            &mut relay,
            None,
        );
        let mut parts = r.batches;
        traced += parts.iter().map(|b| b.chains).sum::<u64>();
        if r.reason != StopReason::Chains {
            // Stopped by the observer (an interrupt) within a stage: the
            // chunks folded by then are kept, a prefix in task order (a
            // chunk traced but after the cut is dropped): chunk-major, so
            // the batches differ by at most one chunk. Each batch
            // mean is unbiased for its size, and where the prefix ends
            // depends on the threads' timing; a chunk's time correlates only
            // weakly with its value (more collisions, more score), a
            // second-order effect confined to the chunks at the cut, so the
            // mean of the batch means is unbiased to that order and their
            // spread estimates its variance. (Shards keep the last whole
            // stage: they cannot agree on what was cut.)
            reason = r.reason;
            if shared.is_none() {
                cut = true;
                add_chunks(&mut grown, parts);
                tallies = empty_tallies(work, cfg);
                let mut means = vec![0.0; bucket_count(cfg.orders) * work.len()];
                for b in &grown {
                    super::fold_batch(&mut tallies, direct, b, b.chains, &mut means);
                }
            }
            break;
        }
        if let Some(share) = &shared {
            parts = (share.0)(parts);
            parts.sort_by_key(|b| b.index);
            assert!(
                parts.iter().map(|b| b.index).eq(0..tasks),
                "the shards shared parts other than 0 .. {tasks}"
            );
        }
        add_chunks(&mut grown, parts);
        size = next;
        stage_wall += t.elapsed().as_secs_f64();
        tallies = fold_batches(empty_tallies(work, cfg), direct, size, &grown);
        let e = if cfg.stop.rms {
            tallies.rms_rel_error(direct)
        } else {
            tallies.max_rel_error(direct)
        };
        stages.push((size, e));
        let chains: u64 = grown.iter().map(|b| b.chains).sum();
        let progress = Progress {
            tallies: &tallies,
            direct,
            chains,
            scores: grown.iter().map(|b| b.scores).sum(),
            collisions: grown.iter().map(|b| b.collisions).sum(),
            elapsed: start.elapsed().as_secs_f64(),
        };
        let mut halt = !observe(&progress) || asked;
        if let Some(share) = &shared {
            // Every shard votes at every stage's end: any one's interrupt
            // stops them all here.
            let vote = halt.then(|| Batch {
                index: STOP_VOTE,
                chains: 0,
                sums: Vec::new(),
                collisions: 0,
                scores: 0,
                direct_sums: Vec::new(),
                near_hits: Vec::new(),
            });
            halt = !(share.0)(vote.into_iter().collect()).is_empty();
        }
        if halt {
            reason = StopReason::Observer;
            break;
        }
        if e <= target {
            break;
        }
        // No error a stage can mend, or the chains' cap reached.
        if !e.is_finite() || size >= cap {
            reason = StopReason::Chains;
            break;
        }
        next = next_size(&stages, target, cap);
        // A time limit (not for shards, which plan alike only from what
        // they share): the next stage fits in what is left at the pace so
        // far, or the run stops.
        if let (Some(limit), None) = (cfg.stop.time, cfg.shard) {
            let left = limit - start.elapsed().as_secs_f64();
            let pace = traced as f64 / stage_wall.max(1e-9);
            let fits = (left * pace / GROWN_BATCHES as f64) as u64;
            if fits < GRAIN {
                reason = StopReason::Time;
                break;
            }
            // Said once, as soon as the pace shows it (a target far out of
            // reach ran silently to the hour's default cap): where what the
            // target needs, without the stage's margins, does not fit.
            let alpha =
                fall(&stages).map_or(
                    FIRST_FALL,
                    |a| {
                        if a.is_nan() { 0.0 } else { a.clamp(0.0, 1.0) }
                    },
                );
            let need = size as f64 * (e / target).powf(2.0 / (1.0 + alpha));
            if need > size.saturating_add(fits) as f64 && !warned {
                warned = true;
                eprintln!(
                    "lumest: at this pace the target {target:.3e} needs at least about {need:.3e} chains a \
                     batch, {:.3e} s more; the run stops at its time limit ({limit} s{}) with the \
                     error it reaches",
                    (need - size as f64) * GROWN_BATCHES as f64 / pace,
                    if default_cap.is_some() {
                        ", the default without --time"
                    } else {
                        ", --time"
                    }
                );
            }
            next = time_bound(next, size, fits);
        }
    }
    // An interrupted stage counts; its batches differ in size, and
    // `batch_size` reports the largest of them (`Pilot::cut`: the summary
    // says "up to").
    if cut {
        size = grown.iter().map(|b| b.chains).max().unwrap_or(size);
    }
    let batches = tallies.batches();
    let plan = Pilot {
        target,
        batches,
        batch_size: size,
        wall: 0.0,
        rel_error: stages.last().map_or(f64::NAN, |s| s.1),
        rms: cfg.stop.rms,
        custom: false,
        dof: (batches.max(2) - 1) as f64,
        fall: fall(&stages).unwrap_or(f64::NAN),
        planned: GROWN_BATCHES,
        estimated_time: stage_wall,
        default_cap,
        stages: 0,
        pilot_chains: 0,
        calibration: 0,
        calibration_traced: 0,
        grown: stages.len() as u32 + u32::from(cut),
        cut,
    };
    let wall = start.elapsed().as_secs_f64();
    let threads = if cfg.threads == 0 {
        std::thread::available_parallelism().map_or(1, |p| p.get())
    } else {
        cfg.threads
    };
    let mut result = RunResult {
        direct: direct.to_vec(),
        tallies,
        chains: 0,
        batch_size: size,
        collisions: 0,
        scores: 0,
        wall,
        threads,
        reason,
        pilot: Some(plan),
        time_sizing: None,
        batches: Vec::new(),
        total_batches: 0,
    };
    if let Some((i, m)) = cfg.shard {
        // A shard's own batches, unfolded, for rank 0 to fold.
        grown.retain(|b| b.index % m == i);
        result.total_batches = GROWN_BATCHES;
        result.tallies = empty_tallies(work, cfg);
    }
    result.chains = grown.iter().map(|b| b.chains).sum();
    result.collisions = grown.iter().map(|b| b.collisions).sum();
    result.scores = grown.iter().map(|b| b.scores).sum();
    if cfg.shard.is_some() {
        result.batches = grown;
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The next size: the error's fall assumed after one stage, measured
    /// after two, the least growth, the grain and the cap.
    #[test]
    fn next_size_follows_the_measured_fall() {
        // One stage at twice the target: the size doubles (fall 1), times
        // the margin, rounded up to the grain: 256 * 2 * 1.05 = 537.6 -> 576.
        assert_eq!(next_size(&[(256, 2e-3)], 1e-3, u64::MAX), 576);
        // Two stages whose error fell like 1 / sqrt(size) (fall 0): the
        // size grows by the square of the ratio, 512 * 2 * 1.05 = 1075.2.
        let s = [(256, 2e-3), (512, 2e-3 / 2f64.sqrt())];
        assert!(fall(&s).unwrap().abs() < 1e-12);
        assert_eq!(next_size(&s, 1e-3, u64::MAX), 1088);
        // A fall of 1 measured: the ratio alone, 1024 * 1.05 -> 1088.
        let s = [(256, 4e-3), (512, 2e-3)];
        assert!((fall(&s).unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(next_size(&s, 1e-3, u64::MAX), 1088);
        // Just above the target: the least growth, 1.2 times.
        assert_eq!(next_size(&[(256, 1.01e-3)], 1e-3, u64::MAX), 320);
        // The cap, and never less than one more chain.
        assert_eq!(next_size(&[(256, 1.0)], 1e-3, 1000), 1000);
        assert_eq!(next_size(&[(256, 1.0)], 1e-3, 100), 257);
    }

    /// A time limit holds the next size to whole grains beyond the current
    /// one, and one far beyond any run (`fits` near `u64::MAX`, as `--time
    /// 1e15` gives) leaves the planned size, never one below the current.
    #[test]
    fn time_bound_saturates() {
        assert_eq!(time_bound(4096, 1024, 1000), 1024 + 960);
        assert_eq!(time_bound(4096, 1024, 1 << 20), 4096);
        assert_eq!(time_bound(4096, 1024, u64::MAX), 4096);
        assert_eq!(time_bound(u64::MAX, u64::MAX - 10, u64::MAX), u64::MAX);
        for fits in [GRAIN, 1 << 40, u64::MAX - 1, u64::MAX] {
            assert!(time_bound(1 << 33, 1 << 32, fits) > 1 << 32);
        }
    }
}
