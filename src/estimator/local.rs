//! The local estimator as batch work: light-tracing chains score into every
//! receiver at every collision ([`Receivers::score`]); with the near/far
//! split, backward paths add the near part ([`crate::backward`]).

use super::Receivers;
use super::first_band::FirstBand;
use crate::backward::{self, PathSetup, Pool};
use crate::chain;
use crate::run::{
    Batch, BatchWork, Checks, Part, Progress, RunConfig, RunResult, cap_batch_size, drive,
};
use crate::sampling::Philox4x32;
use crate::sampling::owen::{MAX_POINTS, OwenSobol};
use crate::sampling::qmc::{DigitalShift, Qmc, shifted_sobol_2d, shifted_sobol_34};
use crate::scene::Scene;
use crate::tally::bucket;
use glam::DVec3;

/// The chains whose index is a multiple of this count, for the `sparse`
/// check, also count the collisions they score from each point's watched
/// neighbourhood (counting in every chain cost a quarter of the scoring speed).
pub const SPARSE_STRIDE: u64 = 8;

/// Smallest default batch size (chains): see `default_batch_size`.
pub const MIN_DEFAULT_BATCH: u64 = 4096;

/// Run the local estimator on `receivers` and tally. `observe` is called
/// after every folded batch and may return `false` to stop early (the
/// batches folded so far are kept). The near/far split of `cfg.near` /
/// `cfg.near_auto` / `cfg.near_paths_auto` is applied to a copy ([`prepare`])
/// unless `receivers` already carry one or were prepared.
pub fn run(
    scene: &Scene,
    receivers: &Receivers,
    cfg: &RunConfig,
    observe: &mut dyn FnMut(&Progress) -> bool,
) -> RunResult {
    if wants_split(scene, cfg) && receivers.near_field().0 == 0 && !receivers.near_prepared() {
        let mut near = receivers.clone();
        prepare(scene, &mut near, cfg);
        return drive(&LocalWork::new(scene, &near), cfg, observe);
    }
    drive(&LocalWork::new(scene, receivers), cfg, observe)
}

/// Whether `cfg` asks for the near/far split in `scene`. Its backward
/// paths reach lights at infinity (the sun, a sky, an environment map) by
/// next-event estimation, as the backward estimator's do; they do not
/// cross or mirror glass, so glazed scenes run the plain local estimate
/// (the `near` check flags receivers that would need the split; the
/// command line refuses `--near-radius` there).
fn wants_split(scene: &Scene, cfg: &RunConfig) -> bool {
    cfg.near.1 > 0 && (cfg.near.0 > 0.0 || cfg.near_auto) && !scene.has_panes()
}

/// Set the near/far split `cfg` asks for on `receivers` in place, as
/// [`run`] would on a copy: a command that owns its receivers calls this
/// first and so holds one set of them, not two (the office at 100,000
/// points: 1.14 GB against 0.65 GB without the split). Receivers that
/// already carry a split are left as they are.
pub fn prepare(scene: &Scene, receivers: &mut Receivers, cfg: &RunConfig) {
    if wants_split(scene, cfg) && receivers.near_field().0 == 0 {
        if cfg.near.0 > 0.0 {
            receivers.set_near_field(cfg.near.0, cfg.near.1);
        } else {
            receivers.set_auto_near_field(scene, cfg.near.1);
        }
        if cfg.near_paths_auto {
            receivers.set_allocated_near_paths(scene, cfg);
        }
    }
    receivers.near_prepared = true;
}

/// The local estimator as batch work.
struct LocalWork<'a> {
    scene: &'a Scene,
    receivers: &'a Receivers,
    /// With the near/far split: each light's core, centre \[m\] and squared
    /// radius [m^2], the radius being the median distance from the light to
    /// the first surface (a tenth of [`backward::light_reach`]), for the
    /// near part's reach count ([`crate::tally::Diagnostics::near_reach`]);
    /// empty without the split.
    reach: Vec<(DVec3, f64)>,
    /// Some light's emission is peaked: the near part's vertices all make
    /// light-guided connections ([`backward::peaked_lights`]).
    peaked: bool,
    /// Per receiver: the width of the grazing band its near paths' first
    /// directions are stratified by (0: none; [`super::first_band`]).
    bands: Vec<f64>,
}

impl<'a> LocalWork<'a> {
    fn new(scene: &'a Scene, receivers: &'a Receivers) -> Self {
        let reach = if receivers.near_field().0 > 0 {
            scene
                .lights
                .iter()
                .map(|l| {
                    if l.is_directional() {
                        // Light from infinity piles up nowhere: no core, so
                        // no vertex is ever in one or exposed to one.
                        (DVec3::INFINITY, 0.0)
                    } else {
                        (
                            l.position(),
                            (backward::light_reach(scene, l) / 10.0).powi(2),
                        )
                    }
                })
                .collect()
        } else {
            Vec::new()
        };
        let bands = receivers.near_bands(scene);
        Self {
            scene,
            receivers,
            reach,
            peaked: backward::peaked_lights(scene),
            bands,
        }
    }

    /// Whether receiver `j` has a near part whose reach is counted.
    fn near_reach(&self, j: usize) -> bool {
        !self.reach.is_empty() && self.receivers.near_field().1[j] > 0.0
    }

    /// Trace the `bs` chains `keys.lo .. keys.lo + bs` of batch `b`'s net
    /// (all of a batch, [`BatchWork::run_batch`], or a part of one,
    /// [`BatchWork::run_part`]) and their near paths and sampled direct
    /// light; the sums over them.
    fn trace_chains(
        &self,
        cfg: &RunConfig,
        b: u64,
        bs: u64,
        keys: Keys,
        buckets: usize,
        acc: &mut [f64],
    ) -> Batch {
        let (scene, receivers) = (self.scene, self.receivers);
        acc.fill(0.0);
        let len = receivers.accumulator_len();
        let mut collisions = 0u64;
        let mut scores = 0u64;
        // The net's shift comes from a stream no chain uses (chain indices < 2^63).
        let mut srng = Philox4x32::new(cfg.seed, (1 << 63) | b);
        let shift12 = DigitalShift([srng.next_u32(), srng.next_u32()]);
        let shift34 = DigitalShift([srng.next_u32(), srng.next_u32()]);
        // An Owen scramble from the same stream, afresh for every
        // `MAX_POINTS` chains of the batch.
        let mut owen = OwenSobol::<{ chain::LEADING_DIMS }>::random(&mut srng);
        // A part that starts past the first net takes its net's scramble.
        for _ in 0..keys.lo / u64::from(MAX_POINTS) {
            owen = OwenSobol::random(&mut srng);
        }
        // The recursive near/far split joins the near part's path vertices to
        // the batch's collisions (its own stream for the reservoir choices).
        const POOL_KEY: u64 = 0x706f_6f6c; // "pool"
        let (paths, radii) = receivers.near_field();
        let mut pool =
            (paths > 0).then(|| Pool::new(bs, Philox4x32::new(keys.part_seed ^ POOL_KEY, b)));
        let mut held = receivers.new_hold();
        for i in keys.lo..keys.lo + bs {
            let c = keys.chain_base + i;
            let mut rng = Philox4x32::new(keys.chain_seed, c);
            let i = i as u32;
            let u_first: chain::LeadingUniforms = match cfg.qmc {
                Qmc::Off => [rng.next_2d(), rng.next_2d()].into(),
                Qmc::Shift => [
                    shifted_sobol_2d(i, shift12, rng.next_2d()),
                    shifted_sobol_34(i, shift34, rng.next_2d()),
                ]
                .into(),
                Qmc::Owen => {
                    if u64::from(i) > keys.lo && i.is_multiple_of(MAX_POINTS) {
                        owen = OwenSobol::random(&mut srng);
                    }
                    let i = i % MAX_POINTS;
                    chain::LeadingUniforms::from_point(|d| owen.unit(i, d, rng.next_u32()))
                }
            };
            collisions += u64::from(chain::trace(scene, &mut rng, &cfg.chain, u_first, |col| {
                let k = bucket(col.order, cfg.orders);
                if let Some(p) = pool.as_mut() {
                    p.offer(col);
                }
                // Every `SPARSE_STRIDE`-th chain also counts where it scores from.
                let counting = c.is_multiple_of(SPARSE_STRIDE);
                scores += receivers.score_held(scene, col, k, acc, counting, &mut held) as u64;
            }));
        }
        receivers.flush_held(&mut held, acc);
        let n = receivers.len();
        let mut sums = vec![0.0; buckets * n];
        for k in 0..buckets {
            receivers.reduce(&acc[k * len..(k + 1) * len], &mut sums[k * n..(k + 1) * n]);
        }
        let mut near_hits = vec![0.0; n];
        receivers.reduce(&acc[buckets * len..], &mut near_hits);
        let mut near_hits: Vec<u64> = near_hits.into_iter().map(|c| c as u64).collect();
        // With a near part: its paths' exposed and reached vertices after
        // the collision counts (see `Batch::near_hits`).
        let reach_counts = !self.reach.is_empty();
        if reach_counts {
            near_hits.resize(3 * n, 0);
        }
        // Near part of the near/far split: backward paths whose first surface
        // lies within the radius, weighted to a per-chain sum over the batch.
        if paths > 0 {
            const NEAR_KEY: u64 = 0x6e65_6172_6669_656c; // "nearfiel"
            for (j, rec) in receivers.receivers().iter().enumerate() {
                let radius = radii[j];
                if radius <= 0.0 {
                    continue;
                }
                // The point's paths for every 256 chains of the batch, so
                // that both parts shrink their error as the run grows (a
                // `--chains` run has 32 batches of whatever size).
                let paths = receivers.near_paths_in_batch(j, bs);
                let w = bs as f64 / paths as f64;
                let frame = &receivers.frames()[j];
                let (grazing, vertex_r) = receivers.near_path_setup(j);
                // Strata of the first direction (`super::first_band`).
                let width = self.bands[j];
                let strata = if width > 0.0 && paths >= 2 {
                    FirstBand::strata(width, paths)
                } else {
                    0
                };
                for s in 0..paths {
                    let first_band = (strata > 0).then(|| {
                        let b = FirstBand {
                            width,
                            strata,
                            paths,
                            index: 0,
                        };
                        FirstBand {
                            index: b.stratum_of_path(s),
                            ..b
                        }
                    });
                    let stream = (b * paths + s) * n as u64 + j as u64;
                    let mut rng = Philox4x32::new(keys.part_seed ^ NEAR_KEY, stream);
                    let path = PathSetup {
                        first_max: radius,
                        vertex_r,
                        grazing,
                        pool: pool.as_ref(),
                        reach: &self.reach,
                        peaked: self.peaked,
                        first_band,
                    };
                    let walk =
                        backward::trace(scene, rec, frame, cfg, &mut rng, &path, |order, v| {
                            sums[bucket(order, cfg.orders) * n + j] += v * w;
                        });
                    if reach_counts {
                        near_hits[n + j] += walk.exposed;
                        near_hits[2 * n + j] += walk.reached;
                    }
                }
            }
        }
        let mut direct_sums = Vec::new();
        if receivers.has_sampled_direct() {
            direct_sums = vec![0.0; n];
            receivers.sampled_direct(scene, keys.part_seed, b, bs, &mut direct_sums);
        }
        Batch {
            index: b,
            chains: bs,
            sums,
            collisions,
            scores,
            near_hits,
            direct_sums,
        }
    }
}

/// Where a run of chains of a batch draws from (see
/// [`LocalWork::trace_chains`]).
#[derive(Clone, Copy)]
struct Keys {
    /// Seed of the chains' streams.
    chain_seed: u64,
    /// Chain `i` of the batch's net draws from stream `chain_base + i`.
    chain_base: u64,
    /// First point of the batch's net traced.
    lo: u64,
    /// Seed of the streams of the near paths, the pool and the sampled
    /// direct light of the chains traced.
    part_seed: u64,
}

/// Spreads part numbers over the seed's bits.
const PART_MIX: u64 = 0x9e37_79b9_7f4a_7c15;

impl BatchWork for LocalWork<'_> {
    fn len(&self) -> usize {
        self.receivers.len()
    }
    fn direct(&self) -> &[f64] {
        self.receivers.direct()
    }
    fn emits(&self) -> bool {
        self.scene.total_power() > 0.0
    }
    fn scratch_len(&self, buckets: usize) -> usize {
        // One accumulator per bucket and one for the watched-neighbourhood counts.
        (buckets + 1) * self.receivers.accumulator_len()
    }
    fn checks(&self) -> Checks {
        let n = self.receivers.len();
        Checks {
            watched: (0..n).map(|j| self.receivers.watched(j)).collect(),
            near_plain: (0..n).map(|j| self.receivers.near_plain(j)).collect(),
            near_reach: (0..n).map(|j| self.near_reach(j)).collect(),
            enclosed: (0..n).map(|j| self.receivers.enclosed(j)).collect(),
            approximate: self.scene.approximate.is_some(),
        }
    }
    /// Chains per batch when not given: about 2^22 units of work per batch
    /// (16 a collision, 1 a receiver score weighted by
    /// [`Scene::score_cost`]), a power of two between [`MIN_DEFAULT_BATCH`]
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
            let params = chain::ChainParams::default();
            let per_score = self.scene.score_cost();
            for c in 0..PILOT {
                let mut rng = Philox4x32::new(PILOT_KEY, c);
                let u = [rng.next_2d(), rng.next_2d()];
                chain::trace(self.scene, &mut rng, &params, u, |col| {
                    cost += 16 + per_score * self.receivers.list_len(col.surface) as u64;
                });
            }
        }
        let per_chain = (cost / PILOT).max(n + 16);
        // At least 4096 chains a batch. Fewer make batch means skewed for
        // the checks that assume near-normal batch means (the `tail` check
        // fired on most points of the office with 32, and on 34-53 of the
        // 10,000 grid points with 256), and a batch is one stratified net:
        // its variance per chain falls as it grows (the 100 x 100 Sobolev
        // grid, 2^20 chains: FOM 1.6e5 with batches of 256, 2.8e5 with 1024,
        // 4.8e5 with 4096). `--chains` still caps it to 32 batches.
        // About 2^22 units of work a batch (a chain costs 16 a collision and
        // 1 a score): larger nets have less variance per chain where the
        // points are few enough for batches of more than 4096 chains
        // (office, 66 points, 15-20 s, seeds 1 and 2: FOM x1.23 and x1.28
        // with 16,384-chain batches against 4096; the daylit office level;
        // the 100 x 100 Sobolev grid stays at 4096).
        let bs = ((1u64 << 22) / per_chain)
            .clamp(MIN_DEFAULT_BATCH, 1 << 16)
            .next_power_of_two();
        cap_batch_size(bs, chains)
    }
    fn run_batch(
        &self,
        cfg: &RunConfig,
        b: u64,
        bs: u64,
        buckets: usize,
        acc: &mut [f64],
    ) -> Batch {
        let keys = Keys {
            chain_seed: cfg.seed,
            chain_base: b * bs,
            lo: 0,
            part_seed: cfg.seed,
        };
        self.trace_chains(cfg, b, bs, keys, buckets, acc)
    }
    fn grows(&self) -> bool {
        true
    }
    fn run_part(
        &self,
        cfg: &RunConfig,
        b: u64,
        part: Part,
        buckets: usize,
        acc: &mut [f64],
    ) -> Batch {
        // Chain `i` of batch `b` on a stream of its own whatever the parts;
        // the streams a part's near paths, pool and sampled direct light
        // draw from are the part's.
        const GROW_KEY: u64 = 0x6772_6f77_6e00; // "grown"
        assert!(
            b < 1 << 31 && part.hi <= 1 << 32,
            "a grown batch has fewer than 2^32 chains"
        );
        let keys = Keys {
            chain_seed: cfg.seed ^ GROW_KEY,
            chain_base: b << 32,
            lo: part.lo,
            part_seed: cfg.seed ^ GROW_KEY ^ (u64::from(part.index) + 1).wrapping_mul(PART_MIX),
        };
        self.trace_chains(cfg, b, part.hi - part.lo, keys, buckets, acc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cases::sobolev::{plane_point, sobolev_scene};
    use crate::reference::Sobolev;

    /// A batch grown over parts is the batch traced in one part: the same
    /// chains on the same nets, across the net's re-scramble at
    /// `MAX_POINTS` chains, with a part that starts inside the second net
    /// and one that starts exactly at it (sums equal up to the order of
    /// the additions; the Sobolev point's direct light is exact, so the
    /// parts' own streams add nothing).
    #[test]
    fn a_batch_grown_over_parts_is_the_batch_in_one_part() {
        let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
        let scene = sobolev_scene(&s);
        let rec = Receivers::new(&scene, &[plane_point(&s, 1, 1.0, 0.0)]).unwrap();
        let work = LocalWork::new(&scene, &rec);
        let cfg = RunConfig::default();
        let mut acc = vec![0.0; work.scratch_len(1)];
        let m = u64::from(MAX_POINTS);
        let end = m + 3000;
        let part = |lo, hi, index| Part { lo, hi, index };
        let whole = work.run_part(&cfg, 3, part(0, end, 0), 1, &mut acc);
        for cuts in [[0, 1000, m + 500], [0, 64, m]] {
            let mut grown = work.run_part(&cfg, 3, part(cuts[0], cuts[1], 0), 1, &mut acc);
            for (k, w) in [cuts[1], cuts[2], end].windows(2).enumerate() {
                let p = work.run_part(&cfg, 3, part(w[0], w[1], k as u32 + 1), 1, &mut acc);
                grown.extend(&p);
            }
            assert_eq!(grown.chains, whole.chains);
            assert_eq!(grown.collisions, whole.collisions);
            let (a, b) = (grown.sums[0], whole.sums[0]);
            assert!((a - b).abs() <= 1e-12 * b.abs(), "{cuts:?}: {a} vs {b}");
        }
        // A scramble taken from the wrong net changes the sum.
        let other = work.run_part(&cfg, 4, part(0, end, 0), 1, &mut acc);
        assert!((other.sums[0] - whole.sums[0]).abs() > 1e-9 * whole.sums[0].abs());
    }
}
