//! How many backward paths each receiver's near part gets (the near/far
//! split, [`Receivers::with_near_field`]): where the near part adds little
//! variance, the fixed default's 16 for every 256 chains; where it decides
//! the error (a wall point in the gap behind a cabinet), more.
//!
//! A batch of `bs` chains gives receiver `j` the far part from its chains
//! and the near part from `p_j bs / 256` paths. With `V_f` the variance of
//! one chain's far score, `V_n` that of one path's value, both relative to
//! `E_j^2` (`a_j`, `b_j`), `C` the cost of a chain and `c_j` that of a
//! path, the squared relative errors summed over the receivers times the
//! run's cost is, per batch,
//!
//! `(sum_j a_j + b_j / q_j) (C + sum_j q_j c_j)` with `q_j = p_j / 256`,
//!
//! least (setting its derivatives to 0) at `q_j = sqrt(C b_j / (A c_j))`,
//! `A = sum_j a_j`: the figure of merit of the RMS relative error, the one
//! `lumest bench` reports. A fixed pilot measures `a_j`, `b_j`, `C` and
//! `c_j` on streams of its own, so the counts depend on the scene and the
//! receivers only, never on the seed, the thread count or the machine
//! (shards and MPI ranks all allocate alike). Costs are counted, not
//! timed: a chain costs its collisions and `score_cost / 16` per score, a
//! path its rays (`backward::Walk::rays`).
//!
//! The pilot's chains are independent, while the run's batches are
//! stratified nets, whose far part has a smaller variance per chain: the
//! counts lean towards fewer paths than the run's optimum, but not far (on
//! the office, with a floor of 1 path then, scaling every count by 0.5 or
//! 2 lowered the FOM, by 26-33 % and 9-13 %).
//! Each count lies in [[`MIN_PATHS`], [`MAX_PATHS`]] per 256 chains: never
//! fewer than the fixed default (see [`MIN_PATHS`] for why), and the
//! pilot's noise cannot make one receiver swallow the run. So the
//! allocation only adds paths where the near part decides the error.
//!
//! Two approximations, which cost efficiency only, never bias: the pilot's
//! pool holds its 512 chains' collisions while a run's holds its batch's
//! (a pool's noise is shared by the batch's paths, so it falls with the
//! batch size, not with the paths: `b_j / q_j` is the paths' own share);
//! and the far part's variance leaves out the sampled direct light's.
//! The counts are rounded from floating-point measures, so like the
//! estimates themselves they are bit-identical where the maths library is.
//!
//! Measured on the office's 506 planar grid points (`lumest illuminance
//! --scene data/office.toml`, 262,144 chains, seeds 1-3, 2 threads, the
//! build before interleaved): 22 of the 42 points with a near part get
//! more than 16 paths (up to 44: the wall points in the gap behind the
//! cabinet and behind the whiteboard); the RMS relative error falls from
//! 3.6e-3-3.8e-3 to 2.9e-3-3.0e-3 and the largest from 3.0e-2-3.6e-2 to
//! 2.3e-2-2.7e-2, at 1.15-1.25 times the time: FOM x 1.27-1.42. The
//! pilot takes about 0.05 s there.

use super::Receivers;
use crate::backward::{self, PathSetup, Pool};
use crate::chain;
use crate::run::RunConfig;
use crate::sampling::Philox4x32;
use rayon::prelude::*;

/// Fewest and most paths per receiver for every 256 chains: never fewer
/// than the fixed default (`--near-paths 16`). Fewer would spend less on
/// near parts that add little variance, but a near part is often
/// heavy-tailed (a point 1 mm above a lit floor: most of its light, from
/// the few paths that bounce there), and with 6 paths per 256 chains
/// there its 95 % intervals covered 36 of 40 runs (mean z^2 1.55) against
/// 38 of 40 (1.07) with 16.
pub const MIN_PATHS: u32 = 16;
/// See [`MIN_PATHS`].
pub const MAX_PATHS: u32 = 256;

/// Chains of the pilot (its far-part variances, its chain cost and the pool
/// its paths join), in chunks traced in parallel and summed in order.
const PILOT_CHAINS: u64 = 512;
const CHUNK: u64 = 64;
/// Paths per receiver of the pilot: a first stage of `SCREEN_PATHS`, and
/// the rest only where that stage's count is at least a quarter of the
/// floor [`MIN_PATHS`]. A near part's variance is heavy-tailed: the
/// office's wall points in the 5 cm gap behind the cabinet need the whole
/// pilot to show it (262,144 chains, seeds 1-2: 32 paths for all gave FOM
/// 1.9e4-2.1e4, 128 for all 2.2e4-2.5e4, the fixed 16 1.7e4-1.9e4; with
/// the first stage cut at half the floor one of them stayed at 16, FOM
/// 2.1e4-2.4e4). The first stage keeps the pilot short where the near
/// parts all stay at the floor: a 120 x 80 render of the office (9600
/// views, 1534 with a near part, 8704 chains) spent 0.7 s on 128 paths
/// each, against a run of 4.6 s.
const PILOT_PATHS: u64 = 128;
const SCREEN_PATHS: u64 = 32;
/// The pilot's stream keys ("NEARPATH", and the pool's and paths' own).
const PILOT_KEY: u64 = 0x4e45_4152_5041_5448;
const POOL_KEY: u64 = PILOT_KEY ^ 0x706f_6f6c;
const PATH_KEY: u64 = PILOT_KEY ^ 0x7061_7468;

/// Most receiver scores the pilot's chains may take (their count times the
/// receivers' list entries, [`Receivers::accumulator_len`]), about a
/// second of one thread; above it the counts stay fixed. The pilot's far
/// part scores every entry (all of them are needed for `A`), so its cost
/// grows with the points: in the office, 100,000 work-plane points (1.5
/// million entries) took 5.4 s more set-up with the pilot (17.4 against
/// 12.0 s for a minimal run), 1,000,000 would take minutes.
pub const PILOT_SCORES: usize = 1 << 27;

/// Whether the pilot fits [`PILOT_SCORES`] for `entries` list entries.
pub fn affordable(entries: usize) -> bool {
    (PILOT_CHAINS as usize).saturating_mul(entries) <= PILOT_SCORES
}

/// What the pilot measured and the counts it chose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Allocation {
    /// Per receiver: paths for every 256 chains (0 where it has no near part).
    pub paths: Vec<u32>,
    /// Per receiver: the far part's variance per chain and the near part's
    /// per path, relative to the pilot's `E^2` (0 without a near part).
    pub far_var: Vec<f64>,
    pub near_var: Vec<f64>,
    /// Cost of a chain and, per receiver, of a path \[rays\].
    pub chain_cost: f64,
    pub path_cost: Vec<f64>,
}

/// The paths each receiver of `receivers` (its near/far split already set)
/// gets per 256 chains, from a fixed pilot (module docs); `cfg` gives the
/// chains' and paths' parameters.
pub fn allocate(scene: &crate::scene::Scene, receivers: &Receivers, cfg: &RunConfig) -> Allocation {
    let n = receivers.len();
    let (_, radii) = receivers.near_field();
    // The far part: independent chains, each scored on its own; a chunk's
    // sums and collisions, folded in chunk order (the same bits whatever
    // the thread count).
    let per_score = scene.score_cost() as f64 / 16.0;
    let chunks: Vec<_> = (0..PILOT_CHAINS / CHUNK)
        .into_par_iter()
        .map(|k| {
            let mut acc = vec![0.0; receivers.accumulator_len()];
            let mut y = vec![0.0; n];
            let (mut sum, mut sum2) = (vec![0.0; n], vec![0.0; n]);
            let mut collisions = Vec::new();
            let mut cost = 0.0;
            for c in k * CHUNK..(k + 1) * CHUNK {
                let mut rng = Philox4x32::new(PILOT_KEY, c);
                let u = [rng.next_2d(), rng.next_2d()];
                let mut scores = 0usize;
                let hits = chain::trace(scene, &mut rng, &cfg.chain, u, |col| {
                    collisions.push(*col);
                    scores += receivers.score(scene, col, &mut acc, None);
                });
                cost += f64::from(hits) + per_score * scores as f64;
                y.fill(0.0);
                receivers.reduce(&acc, &mut y);
                acc.fill(0.0);
                for j in 0..n {
                    sum[j] += y[j];
                    sum2[j] += y[j] * y[j];
                }
            }
            (sum, sum2, collisions, cost)
        })
        .collect();
    let mut pool = Pool::new(PILOT_CHAINS, Philox4x32::new(POOL_KEY, 0));
    let (mut sum, mut sum2, mut cost) = (vec![0.0; n], vec![0.0; n], 0.0);
    for (s1, s2, collisions, c) in &chunks {
        for j in 0..n {
            sum[j] += s1[j];
            sum2[j] += s2[j];
        }
        collisions.iter().for_each(|col| pool.offer(col));
        cost += c;
    }
    drop(chunks);
    let chains = PILOT_CHAINS as f64;
    let chain_cost = (cost / chains).max(1.0);
    let far_mean: Vec<f64> = sum.iter().map(|s| s / chains).collect();
    let far_var: Vec<f64> = (0..n)
        .map(|j| ((sum2[j] - sum[j] * sum[j] / chains) / (chains - 1.0)).max(0.0))
        .collect();
    // The direct light sampled per batch (area sources), per chain.
    let mut sampled = vec![0.0; n];
    if receivers.has_sampled_direct() {
        receivers.sampled_direct(scene, PILOT_KEY, 0, PILOT_CHAINS, &mut sampled);
        sampled.iter_mut().for_each(|s| *s /= chains);
    }
    // The near part: each receiver's paths on streams of its own, as sums
    // of the values, their squares and the rays, over paths `s0..s1`.
    let peaked = backward::peaked_lights(scene);
    let paths = |j: usize, s0: u64, s1: u64| -> [f64; 3] {
        let (grazing, vertex_r) = receivers.near_path_setup(j);
        let path = PathSetup {
            first_max: radii[j],
            vertex_r,
            grazing,
            pool: Some(&pool),
            reach: &[],
            peaked,
            first_band: None,
        };
        let (rec, frame) = (&receivers.receivers()[j], &receivers.frames()[j]);
        let mut sums = [0.0; 3];
        for s in s0..s1 {
            let mut rng = Philox4x32::new(PATH_KEY, s * n as u64 + j as u64);
            let mut v = 0.0;
            let walk = backward::trace(scene, rec, frame, cfg, &mut rng, &path, |_, x| v += x);
            sums[0] += v;
            sums[1] += v * v;
            sums[2] += walk.rays as f64;
        }
        sums
    };
    let near_ids: Vec<usize> = (0..n).filter(|&j| radii[j] > 0.0).collect();
    let mut near_sums = vec![[0.0; 3]; n];
    let mut near_count = vec![0u64; n];
    // A first stage of `SCREEN_PATHS` each; the receivers whose count it
    // puts well under the floor keep it (module docs).
    let first: Vec<[f64; 3]> = near_ids
        .par_iter()
        .map(|&j| paths(j, 0, SCREEN_PATHS))
        .collect();
    for (&j, s) in near_ids.iter().zip(first) {
        near_sums[j] = s;
        near_count[j] = SCREEN_PATHS;
    }
    let measure = |near_sums: &[[f64; 3]], near_count: &[u64]| {
        let stats: Vec<(f64, f64, f64)> = (0..n)
            .map(|j| match near_count[j] {
                0 => (0.0, 0.0, 0.0),
                m => {
                    let [s1, s2, rays] = near_sums[j];
                    let m = m as f64;
                    let var = ((s2 - s1 * s1 / m) / (m - 1.0)).max(0.0);
                    (s1 / m, var, (rays / m).max(1.0))
                }
            })
            .collect();
        // Relative to each receiver's E (the pilot's, direct included).
        let direct = receivers.direct();
        let e: Vec<f64> = (0..n)
            .map(|j| (direct[j] + sampled[j] + far_mean[j] + stats[j].0).abs())
            .collect();
        // (NaN-free: each E is a finite sum's magnitude or NaN, and a NaN
        // E gives NaN measures, which the counts treat as 0.)
        let e_floor = 1e-9
            * e.iter()
                .copied()
                .filter(|x| x.is_finite())
                .fold(0.0, f64::max);
        let rel = |v: f64, j: usize| {
            let ej = e[j].max(e_floor);
            if ej > 0.0 { v / (ej * ej) } else { 0.0 }
        };
        let a: Vec<f64> = (0..n).map(|j| rel(far_var[j], j)).collect();
        let b: Vec<f64> = (0..n).map(|j| rel(stats[j].1, j)).collect();
        let cost: Vec<f64> = stats.iter().map(|x| x.2).collect();
        (a, b, cost)
    };
    let (a, b, cost) = measure(&near_sums, &near_count);
    let a_sum: f64 = a.iter().sum();
    let more: Vec<usize> = near_ids
        .iter()
        .copied()
        .filter(|&j| {
            a_sum <= 0.0
                || 256.0 * (chain_cost * b[j] / (a_sum * cost[j])).sqrt()
                    >= 0.25 * f64::from(MIN_PATHS)
        })
        .collect();
    let rest: Vec<[f64; 3]> = more
        .par_iter()
        .map(|&j| paths(j, SCREEN_PATHS, PILOT_PATHS))
        .collect();
    for (&j, s) in more.iter().zip(rest) {
        for k in 0..3 {
            near_sums[j][k] += s[k];
        }
        near_count[j] = PILOT_PATHS;
    }
    let (a, b, cost) = measure(&near_sums, &near_count);
    let on: Vec<bool> = radii.iter().map(|&r| r > 0.0).collect();
    let paths = least_counts(chain_cost, &a, &b, &cost, &on);
    Allocation {
        paths,
        far_var: a,
        near_var: b,
        chain_cost,
        path_cost: cost,
    }
}

/// The counts per 256 chains that minimise `(A + sum_j b_j / q_j) (C +
/// sum_j q_j c_j)` over the receivers `on` (with a near part), `q_j = p_j /
/// 256` held in [[`MIN_PATHS`], [`MAX_PATHS`]] / 256 (module docs).
///
/// At the least value every count is `q_j = clamp(k r_j, lo, hi)` with
/// `r_j = sqrt(b_j / c_j)` and `k = sqrt(T / V)`, `V` and `T` the two
/// factors at those counts (a free count's derivative vanishes there; a
/// bound one's points outwards, and in `log q` the objective is convex, so
/// this point is the least). `phi(k) = k^2 V(k) - T(k)` never decreases in
/// `k` (its derivative is `2 k (A + sum over the bound counts of b / q)`),
/// so `k` is found by bisection in `log k`: a fixed number of halvings, the
/// same bits on every machine. Rounded to whole paths; 0 where off.
/// Non-finite or negative measures count as 0 (then the floor).
fn least_counts(c: f64, a: &[f64], b: &[f64], cost: &[f64], on: &[bool]) -> Vec<u32> {
    let (lo, hi) = (f64::from(MIN_PATHS) / 256.0, f64::from(MAX_PATHS) / 256.0);
    let clean = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
    let a_sum: f64 = a.iter().map(|&x| clean(x)).sum();
    let c = clean(c);
    // r_j = sqrt(b_j / c_j) for the receivers with a near part.
    let r: Vec<(usize, f64)> = (0..a.len())
        .filter(|&j| on[j])
        .map(|j| {
            let (bj, cj) = (clean(b[j]), clean(cost[j]));
            (j, if cj > 0.0 { (bj / cj).sqrt() } else { 0.0 })
        })
        .collect();
    let q_at = |k: f64, rj: f64| (k * rj).clamp(lo, hi);
    // The sign of phi(k) = k^2 V - T at k = exp(ln_k), compared in logs
    // (k^2 overflows where every r_j is below 1e-154).
    let below = |ln_k: f64| {
        let k = ln_k.exp();
        let (mut v, mut t) = (a_sum, c);
        for &(j, rj) in &r {
            let q = q_at(k, rj);
            v += clean(b[j]) / q;
            t += q * clean(cost[j]);
        }
        2.0 * ln_k + v.ln() < t.ln()
    };
    // Every count is at `lo` below k = lo / max r and at `hi` above
    // k = hi / min r (over r > 0): the root lies between (or beyond, where
    // the counts no longer change).
    let r_pos = r.iter().map(|x| x.1).filter(|&x| x > 0.0);
    let (r_min, r_max) = r_pos.fold((f64::INFINITY, 0.0f64), |(m, x), v| (m.min(v), x.max(v)));
    let k = if r_max > 0.0 {
        let (mut l, mut h) = ((0.5 * lo / r_max).ln(), (2.0 * hi / r_min).ln());
        for _ in 0..200 {
            let mid = 0.5 * (l + h);
            if below(mid) {
                l = mid;
            } else {
                h = mid;
            }
        }
        (0.5 * (l + h)).exp()
    } else {
        0.0
    };
    let mut counts = vec![0; a.len()];
    for &(j, rj) in &r {
        counts[j] = ((256.0 * q_at(k, rj)).round() as u32).clamp(MIN_PATHS, MAX_PATHS);
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The objective at whole counts `p` (per 256 chains).
    fn objective(c: f64, a: &[f64], b: &[f64], cost: &[f64], p: &[u32]) -> f64 {
        let q: Vec<f64> = p.iter().map(|&p| f64::from(p) / 256.0).collect();
        let v = a.iter().sum::<f64>() + (0..q.len()).map(|j| b[j] / q[j]).sum::<f64>();
        let t = c + (0..q.len()).map(|j| q[j] * cost[j]).sum::<f64>();
        v * t
    }

    /// The least objective over every pair of whole counts in the bounds.
    fn brute_force(c: f64, a: &[f64], b: &[f64], cost: &[f64]) -> f64 {
        let mut least = f64::INFINITY;
        for p0 in MIN_PATHS..=MAX_PATHS {
            for p1 in MIN_PATHS..=MAX_PATHS {
                least = least.min(objective(c, a, b, cost, &[p0, p1]));
            }
        }
        least
    }

    /// Two receivers whose near parts carry nearly all the variance (a
    /// reviewer's case): one count at the ceiling, the other well inside
    /// the bounds. Holding both at the ceiling, as a bound set that only
    /// grew did, cost 1.44 times the least objective.
    #[test]
    fn a_count_held_at_a_bound_is_released_when_the_optimum_moves() {
        let (c, a, b, cost) = (6.17, [5e-6, 5e-6], [0.007, 1e-4], [16.6, 16.6]);
        let p = least_counts(c, &a, &b, &cost, &[true, true]);
        let best = objective(c, &a, &b, &cost, &p);
        let least = brute_force(c, &a, &b, &cost);
        assert!(best <= least * (1.0 + 1e-3), "{p:?}: {best} vs {least}");
        assert_eq!(p[0], MAX_PATHS);
        assert!(p[1] > MIN_PATHS && p[1] < MAX_PATHS, "{p:?}");
    }

    /// Random instances over many decades, against the brute force.
    #[test]
    fn the_counts_are_the_least_on_random_instances() {
        let mut rng = crate::sampling::Philox4x32::new(11, 0);
        let mut pow = |lo: f64, hi: f64| 10f64.powf(lo + (hi - lo) * rng.next_f64());
        for _ in 0..40 {
            let c = pow(0.0, 3.0);
            let a = [pow(-7.0, 1.0), pow(-7.0, 1.0)];
            let b = [pow(-5.0, 1.0), pow(-5.0, 1.0)];
            let cost = [pow(0.0, 2.5), pow(0.0, 2.5)];
            let p = least_counts(c, &a, &b, &cost, &[true, true]);
            let best = objective(c, &a, &b, &cost, &p);
            let least = brute_force(c, &a, &b, &cost);
            assert!(
                best <= least * (1.0 + 1e-3),
                "{c} {a:?} {b:?} {cost:?}: {p:?} {best} vs {least}"
            );
        }
    }

    /// The pilot's budget: up to `PILOT_SCORES / PILOT_CHAINS` entries.
    #[test]
    fn the_pilot_runs_within_its_budget_only() {
        let most = PILOT_SCORES / PILOT_CHAINS as usize;
        assert!(affordable(most) && !affordable(most + 1) && !affordable(usize::MAX));
    }

    /// Near parts of subnormal variance (a reviewer's case: k^2 overflowed
    /// and gave 34 paths each where the least objective takes 256).
    #[test]
    fn tiny_variances_do_not_overflow() {
        let (c, a, b, cost) = (1.0, [0.0, 0.0], [1e-310, 1e-310], [1.0, 1.0]);
        let p = least_counts(c, &a, &b, &cost, &[true, true]);
        assert_eq!(p, [MAX_PATHS, MAX_PATHS]);
    }

    /// Receivers without a near part get 0, empty near parts the floor
    /// even when no far variance was measured, and NaN measures the floor.
    #[test]
    fn empty_off_and_nan_receivers() {
        let on = [true, false, true];
        let p = least_counts(5.0, &[0.0; 3], &[0.0, 1.0, 0.0], &[10.0; 3], &on);
        assert_eq!(p, [MIN_PATHS, 0, MIN_PATHS]);
        let p = least_counts(
            5.0,
            &[1.0, 1.0, f64::NAN],
            &[f64::NAN, 1.0, 0.5],
            &[10.0; 3],
            &on,
        );
        assert_eq!(p[0], MIN_PATHS);
        assert!(p[2] > MIN_PATHS, "{p:?}");
    }
}
