//! Threads, seeds, batches, stopping rules and timing.
//!
//! Work is cut into batches of `batch_size` chains. Chain `c` draws from the
//! Philox stream `(seed, c)` and batch `b` holds chains `b*batch_size ..
//! (b+1)*batch_size`, so a batch's sums depend only on `(seed, b)`. Worker
//! threads take batch indices from a shared counter; the calling thread folds
//! finished batches into the tallies strictly in index order. Hence results
//! are bit-identical for any thread count whenever the set of batches is the
//! same: always with `--chains`, and with `--rel-error` (the run keeps exactly
//! the shortest prefix of batches that meets the target). Only a run stopped
//! by `--time` depends on the machine's speed.
//!
//! Why batches rather than per-chain tallies: a chain scores into every point
//! at every collision, so per-chain squares would cost as much as the scores
//! themselves; batch means are independent realisations and give the standard
//! error with `B - 1` degrees of freedom.

use crate::chain::{self, ChainParams};
use crate::estimator::Receivers;
use crate::sampling::Philox4x32;
use crate::sampling::qmc::{DigitalShift, shifted_sobol_2d, shifted_sobol_34};
use crate::scene::Scene;
use crate::tally::{Diagnostics, Welford, relative_error};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// When to stop. At least one rule must be set; the first one met stops the run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stop {
    /// Number of chains (rounded up to whole batches).
    pub chains: Option<u64>,
    /// Wall-clock limit [s]. Soft: a run always completes at least
    /// [`MIN_BATCHES`] batches, so a very short limit may be exceeded.
    pub time: Option<f64>,
    /// Target for the largest relative standard error of `E` over the points.
    pub rel_error: Option<f64>,
}

/// Fewest batches for a standard error (and for the `--rel-error` rule).
pub const MIN_BATCHES: u64 = 32;

/// Run configuration.
///
/// With `stratify`, the emitted directions of a batch's chains form a
/// randomly shifted Sobol' (0,2)-net, and the first reflections use Sobol'
/// dimensions 3-4 of the same points (see [`crate::sampling::qmc`]): each
/// batch mean stays unbiased and batches stay independent, while the first
/// collisions cover the surfaces evenly. Chain `c` then depends on `(seed, c)`
/// and on its batch's shift, i.e. on `(seed, c, batch_size)`; still never on
/// the thread count.
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
    /// Stratify emitted directions over each batch (randomised Sobol' net).
    pub stratify: bool,
    /// Near/far split: radius [m] (0: off) and backward paths per receiver
    /// for every 256 chains of a batch, for the near part (see
    /// [`Receivers::with_near_field`]).
    pub near: (f64, u32),
    /// With `near.0 == 0`: choose the split per receiver where it is needed
    /// ([`Receivers::with_auto_near_field`]), with `near.1` paths.
    pub near_auto: bool,
}

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
            stratify: true,
            near: (0.0, 0),
            near_auto: false,
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

/// Per-point tallies over batch means of the indirect illuminance [lx].
#[derive(Clone, Debug)]
pub struct Tallies {
    /// Indirect illuminance (all orders >= 1) per point.
    pub indirect: Vec<Welford>,
    /// `orders[k][j]`: order `k+1` for `k < K`, and all orders above `K` for `k = K`.
    pub orders: Vec<Vec<Welford>>,
    /// `R^2 B` of each point's total at batch counts 32, 64, 128, ... (for the FOM check).
    pub snapshots: Vec<(u64, Vec<f64>)>,
    /// Per point: collisions that scored into it from its watched
    /// neighbourhood, over the run (the `sparse` check).
    pub near_hits: Vec<u64>,
    /// Per point: whether the `sparse` check applies ([`Receivers::watched`]).
    pub watched: Vec<bool>,
}

impl Tallies {
    fn new(n: usize, orders: u32) -> Self {
        let buckets = if orders == 0 { 0 } else { orders as usize + 1 };
        Self {
            indirect: vec![Welford::new(); n],
            orders: vec![vec![Welford::new(); n]; buckets],
            snapshots: Vec::new(),
            near_hits: vec![0; n],
            watched: vec![false; n],
        }
    }

    /// Record `R^2 B` of every point (total = `direct` + indirect).
    fn snapshot(&mut self, direct: &[f64]) {
        let b = self.batches();
        let v = self
            .indirect
            .iter()
            .zip(direct)
            .map(|(w, d)| relative_error(d + w.mean(), w.std_error()).powi(2) * b as f64)
            .collect();
        self.snapshots.push((b, v));
    }

    /// Statistical checks of point `j` whose exact part is `direct`.
    pub fn diagnostics(&self, j: usize, direct: f64) -> Diagnostics {
        let b = self.batches();
        let half = self
            .snapshots
            .iter()
            .rev()
            .find(|(n, _)| 2 * n <= b)
            .map(|(_, v)| v[j]);
        let mut d = Diagnostics::of(&self.indirect[j], direct, half);
        d.near_hits = self
            .watched
            .get(j)
            .copied()
            .unwrap_or(false)
            .then(|| self.near_hits[j]);
        d
    }

    /// Number of batches folded in.
    pub fn batches(&self) -> u64 {
        self.indirect.first().map_or(0, Welford::count)
    }

    /// Largest relative standard error of the total `E = direct + indirect` over the points.
    pub fn max_rel_error(&self, direct: &[f64]) -> f64 {
        self.indirect
            .iter()
            .zip(direct)
            .map(|(w, d)| relative_error(d + w.mean(), w.std_error()))
            .fold(0.0, f64::max)
    }

    /// Root mean square of the relative standard error of `E` over the points.
    pub fn rms_rel_error(&self, direct: &[f64]) -> f64 {
        let n = self.indirect.len().max(1) as f64;
        let s: f64 = self
            .indirect
            .iter()
            .zip(direct)
            .map(|(w, d)| relative_error(d + w.mean(), w.std_error()).powi(2))
            .sum();
        (s / n).sqrt()
    }
}

/// What stopped a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    Chains,
    Time,
    RelError,
    /// The scene emits no light: the answer is exactly zero.
    NoLight,
}

/// A view of a run in progress, handed to the observer after each batch.
pub struct Progress<'a> {
    /// Tallies so far.
    pub tallies: &'a Tallies,
    /// Exact direct illuminance per point [lx].
    pub direct: &'a [f64],
    /// Chains folded in.
    pub chains: u64,
    /// Point scores evaluated in folded batches.
    pub scores: u64,
    /// Wall time since the start [s].
    pub elapsed: f64,
}

/// The outcome of a run.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// Exact direct illuminance per point [lx].
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
    /// Wall time [s].
    pub wall: f64,
    /// Threads used.
    pub threads: usize,
    /// What stopped the run.
    pub reason: StopReason,
}

impl RunResult {
    /// The final state as a [`Progress`] view.
    pub fn progress(&self) -> Progress<'_> {
        Progress {
            tallies: &self.tallies,
            direct: &self.direct,
            chains: self.chains,
            scores: self.scores,
            elapsed: self.wall,
        }
    }
}

/// The sums of one batch, produced by a [`BatchWork`].
pub struct Batch {
    /// Batch index.
    pub index: u64,
    /// Chains (or paths) traced in the batch.
    pub chains: u64,
    /// `sums[k * n + j]`: sum over the batch's chains of bucket `k`'s score at point `j`.
    pub sums: Vec<f64>,
    /// Surface collisions (or path vertices) in the batch.
    pub collisions: u64,
    /// Receiver scores evaluated in the batch.
    pub scores: u64,
    /// Per point: collisions that scored into it from within its watched
    /// neighbourhood ([`Receivers::view_radius`]); empty for the backward estimator.
    pub near_hits: Vec<u64>,
}

/// A source of independent batches: the local estimator (chains from the
/// lights) or the backward one (paths from the receivers).
pub trait BatchWork: Sync {
    /// The scene traced.
    fn scene(&self) -> &Scene;
    /// The receivers scored.
    fn receivers(&self) -> &Receivers;
    /// Number of receivers.
    fn len(&self) -> usize {
        self.receivers().len()
    }
    /// True when there are no receivers.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Exact first-order values per receiver.
    fn direct(&self) -> &[f64] {
        self.receivers().direct()
    }
    /// Length of the per-thread scratch buffer for `buckets` buckets.
    fn scratch_len(&self, buckets: usize) -> usize;
    /// Per point: whether the `sparse` check applies (local estimates only).
    fn watched(&self) -> Vec<bool> {
        vec![false; self.receivers().len()]
    }
    /// Default batch size for `n` receivers and an optional chain count.
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
}

/// The local estimator as batch work.
struct LocalWork<'a> {
    scene: &'a Scene,
    receivers: &'a Receivers,
}

impl BatchWork for LocalWork<'_> {
    fn scene(&self) -> &Scene {
        self.scene
    }
    fn receivers(&self) -> &Receivers {
        self.receivers
    }
    fn scratch_len(&self, buckets: usize) -> usize {
        // One accumulator per bucket and one for the watched-neighbourhood counts.
        (buckets + 1) * self.receivers.accumulator_len()
    }
    fn watched(&self) -> Vec<bool> {
        (0..self.receivers.len())
            .map(|j| self.receivers.watched(j))
            .collect()
    }
    /// Chains per batch when not given: about 2^20 receiver scores per
    /// batch (weighted by [`Scene::score_cost`]), a power of two between 256
    /// and 65536, and at least `MIN_BATCHES` batches for a `--chains` run.
    /// The cost of a chain is measured by a fixed pilot of 256 chains (its
    /// own streams, so the batch size depends only on the scene and the
    /// receivers, never on the machine, the thread count or the seed): long
    /// chains (reflectances near 1) get smaller batches.
    fn default_batch_size(&self, chains: Option<u64>) -> u64 {
        const PILOT: u64 = 256;
        const PILOT_KEY: u64 = 0x0050_494c_4f54; // "PILOT"
        let n = self.receivers.len() as u64;
        let mut cost = 0u64;
        if self.scene.total_power() > 0.0 {
            let params = crate::chain::ChainParams::default();
            let per_score = self.scene.score_cost();
            for c in 0..PILOT {
                let mut rng = Philox4x32::new(PILOT_KEY, c);
                let u = [rng.next_2d(), rng.next_2d()];
                crate::chain::trace(self.scene, &mut rng, &params, u, |col| {
                    cost += 16 + per_score * self.receivers.list_len(col.surface) as u64;
                });
            }
        }
        let per_chain = (cost / PILOT).max(n + 16);
        // At least 256 chains a batch: batch means of fewer chains are too
        // skewed for the checks that assume near-normal batch means (the
        // `tail` check fired on most points of the office with 32).
        let mut bs = ((1u64 << 20) / per_chain)
            .clamp(256, 1 << 16)
            .next_power_of_two();
        if let Some(c) = chains {
            bs = bs.min(c.div_ceil(MIN_BATCHES)).max(1);
        }
        bs
    }
    fn run_batch(
        &self,
        cfg: &RunConfig,
        b: u64,
        bs: u64,
        buckets: usize,
        scratch: &mut [f64],
    ) -> Batch {
        run_batch(self.scene, self.receivers, cfg, b, bs, buckets, scratch)
    }
}

/// Run the chains and tally. `observe` is called after every folded batch and
/// may return `false` to stop early (the batches folded so far are kept).
pub fn run(
    scene: &Scene,
    receivers: &Receivers,
    cfg: &RunConfig,
    observe: &mut dyn FnMut(&Progress) -> bool,
) -> RunResult {
    let wanted = cfg.near.1 > 0 && (cfg.near.0 > 0.0 || cfg.near_auto);
    if wanted && receivers.near_field().0 == 0 {
        let near = if cfg.near.0 > 0.0 {
            receivers.clone().with_near_field(cfg.near.0, cfg.near.1)
        } else {
            receivers.clone().with_auto_near_field(scene, cfg.near.1)
        };
        return drive(
            &LocalWork {
                scene,
                receivers: &near,
            },
            cfg,
            observe,
        );
    }
    drive(&LocalWork { scene, receivers }, cfg, observe)
}

/// The exact answer of a scene that emits nothing: zero batches.
fn no_light(direct: &[f64], cfg: &RunConfig) -> RunResult {
    let mut tallies = Tallies::new(direct.len(), cfg.orders);
    for _ in 0..MIN_BATCHES {
        for w in tallies
            .indirect
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
    }
}

/// Drive any batch work: threads, ordered folding, stopping rules.
pub fn drive(
    work: &dyn BatchWork,
    cfg: &RunConfig,
    observe: &mut dyn FnMut(&Progress) -> bool,
) -> RunResult {
    if work.scene().total_power() <= 0.0 {
        return no_light(work.direct(), cfg);
    }
    let start = Instant::now();
    let n = work.len();
    let buckets = if cfg.orders == 0 {
        1
    } else {
        cfg.orders as usize + 1
    };
    let stop = cfg.stop;
    let bs = cfg
        .batch_size
        .unwrap_or_else(|| work.default_batch_size(stop.chains))
        .max(1);
    // At least two batches, so that every standard error exists.
    let max_batches = stop.chains.map_or(u64::MAX, |c| c.div_ceil(bs).max(2));
    let threads = if cfg.threads == 0 {
        std::thread::available_parallelism().map_or(1, |p| p.get())
    } else {
        cfg.threads
    };
    let mut tallies = Tallies::new(n, cfg.orders);
    tallies.watched = work.watched();
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
    };
    let next = AtomicU64::new(0);
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
                    let b = next.fetch_add(1, Ordering::Relaxed);
                    if b >= max_batches {
                        break;
                    }
                    let batch = work.run_batch(cfg, b, bs, buckets, &mut acc);
                    if tx.send(batch).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);

        let mut pending: BTreeMap<u64, Batch> = BTreeMap::new();
        let mut folded = 0u64;
        let mut batch_means = vec![0.0; buckets * n];
        loop {
            match rx.recv_timeout(Duration::from_millis(50)) {
                Ok(b) => {
                    pending.insert(b.index, b);
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
            // The time limit is soft: at least MIN_BATCHES batches are always
            // folded, so that every standard error has enough degrees of freedom.
            if stop
                .time
                .is_some_and(|t| start.elapsed().as_secs_f64() >= t)
                && folded >= MIN_BATCHES.min(max_batches)
                && !halt.load(Ordering::Relaxed)
            {
                halt.store(true, Ordering::Relaxed);
                result.reason = StopReason::Time;
            }
            while let Some(b) = pending.remove(&folded) {
                if b.index >= keep_until {
                    folded += 1;
                    continue;
                }
                fold(&mut tallies, &b, bs, buckets, n, &mut batch_means);
                let folded_batches = tallies.batches();
                if folded_batches >= 32 && folded_batches.is_power_of_two() {
                    tallies.snapshot(&direct);
                }
                result.chains += b.chains;
                result.collisions += b.collisions;
                result.scores += b.scores;
                folded += 1;
                let progress = Progress {
                    tallies: &tallies,
                    direct: &direct,
                    chains: result.chains,
                    scores: result.scores,
                    elapsed: start.elapsed().as_secs_f64(),
                };
                let mut done = !observe(&progress);
                if let Some(target) = stop.rel_error
                    && keep_until == u64::MAX
                    && folded >= MIN_BATCHES
                    && tallies.max_rel_error(&direct) <= target
                {
                    result.reason = StopReason::RelError;
                    done = true;
                }
                if done && keep_until == u64::MAX {
                    keep_until = folded;
                    halt.store(true, Ordering::Relaxed);
                }
            }
        }
    });
    result.direct = direct;
    result.tallies = tallies;
    result.wall = start.elapsed().as_secs_f64();
    result
}

/// The chains whose index is a multiple of this count, for the `sparse`
/// check, also count the collisions they score from each point's watched
/// neighbourhood (counting in every chain cost a quarter of the scoring speed).
pub const SPARSE_STRIDE: u64 = 8;

fn run_batch(
    scene: &Scene,
    receivers: &Receivers,
    cfg: &RunConfig,
    b: u64,
    bs: u64,
    buckets: usize,
    acc: &mut [f64],
) -> Batch {
    acc.fill(0.0);
    let len = receivers.accumulator_len();
    let k_max = cfg.orders;
    let mut collisions = 0u64;
    let mut scores = 0u64;
    // The net's shift comes from a stream no chain uses (chain indices < 2^63).
    let mut srng = Philox4x32::new(cfg.seed, (1 << 63) | b);
    let shift12 = DigitalShift([srng.next_u32(), srng.next_u32()]);
    let shift34 = DigitalShift([srng.next_u32(), srng.next_u32()]);
    // The recursive near/far split joins the near part's path vertices to
    // the batch's collisions (its own stream for the reservoir choices).
    const POOL_KEY: u64 = 0x706f_6f6c; // "pool"
    let (paths, radii) = receivers.near_field();
    let mut pool = (paths > 0)
        .then(|| crate::backward::Pool::new(bs, Philox4x32::new(cfg.seed ^ POOL_KEY, b)));
    for c in b * bs..(b + 1) * bs {
        let mut rng = Philox4x32::new(cfg.seed, c);
        let u_first = if cfg.stratify {
            let i = (c - b * bs) as u32;
            [
                shifted_sobol_2d(i, shift12, rng.next_2d()),
                shifted_sobol_34(i, shift34, rng.next_2d()),
            ]
        } else {
            [rng.next_2d(), rng.next_2d()]
        };
        collisions += u64::from(chain::trace(scene, &mut rng, &cfg.chain, u_first, |col| {
            let k = if k_max == 0 {
                0
            } else {
                (col.order.min(k_max + 1) - 1) as usize
            };
            if let Some(p) = pool.as_mut() {
                p.offer(col);
            }
            let (acc, near) = acc.split_at_mut(buckets * len);
            // Every `SPARSE_STRIDE`-th chain also counts where it scores from.
            let near = (c % SPARSE_STRIDE == 0).then_some(near);
            scores += receivers.score(scene, col, &mut acc[k * len..(k + 1) * len], near) as u64;
        }));
    }
    let n = receivers.len();
    let mut sums = vec![0.0; buckets * n];
    for k in 0..buckets {
        receivers.reduce(&acc[k * len..(k + 1) * len], &mut sums[k * n..(k + 1) * n]);
    }
    let mut near_hits = vec![0.0; n];
    receivers.reduce(&acc[buckets * len..], &mut near_hits);
    // Near part of the near/far split: backward paths whose first surface
    // lies within the radius, weighted to a per-chain sum over the batch.
    if paths > 0 {
        const NEAR_KEY: u64 = 0x6e65_6172_6669_656c; // "nearfiel"
        // `paths` per point for every 256 chains of the batch, so that both
        // parts shrink their error as the run grows (a `--chains` run has
        // 32 batches of whatever size).
        let paths = u64::from(paths) * bs.div_ceil(256);
        let w = bs as f64 / paths as f64;
        for (j, rec) in receivers.receivers().iter().enumerate() {
            let radius = radii[j];
            if radius <= 0.0 {
                continue;
            }
            let frame = &receivers.frames()[j];
            for s in 0..paths {
                let stream = (b * paths + s) * n as u64 + j as u64;
                let mut rng = Philox4x32::new(cfg.seed ^ NEAR_KEY, stream);
                let pool = pool.as_ref();
                crate::backward::trace(
                    scene,
                    rec,
                    frame,
                    cfg,
                    &mut rng,
                    radius,
                    pool,
                    |order, v| {
                        let k = if k_max == 0 {
                            0
                        } else {
                            (order.min(k_max + 1) - 1) as usize
                        };
                        sums[k * n + j] += v * w;
                    },
                );
            }
        }
    }
    Batch {
        index: b,
        chains: bs,
        sums,
        collisions,
        scores,
        near_hits: near_hits.into_iter().map(|c| c as u64).collect(),
    }
}

fn fold(tallies: &mut Tallies, b: &Batch, bs: u64, buckets: usize, n: usize, means: &mut [f64]) {
    let inv = 1.0 / bs as f64;
    for (m, s) in means.iter_mut().zip(&b.sums) {
        *m = s * inv;
    }
    for j in 0..n {
        let total: f64 = (0..buckets).map(|k| means[k * n + j]).sum();
        tallies.indirect[j].push(total);
    }
    for (t, h) in tallies.near_hits.iter_mut().zip(&b.near_hits) {
        *t += h;
    }
    for (k, bucket) in tallies.orders.iter_mut().enumerate() {
        for (j, w) in bucket.iter_mut().enumerate() {
            w.push(means[k * n + j]);
        }
    }
}
