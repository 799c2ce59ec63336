//! Per-receiver tallies over batch means: what the runner folds each batch
//! into, in batch order.

use super::{BatchMeans, Diagnostics, Welford, relative_error};

/// Per-receiver tallies over batch means of the estimated quantity (the
/// indirect illuminance \[lx\], or luminance [cd/m^2], per receiver).
#[derive(Clone, Debug)]
pub struct Tallies {
    /// The estimated part per receiver: all reflection orders >= 1, plus
    /// the direct light of sources that are sampled rather than exact.
    pub estimated: Vec<Welford>,
    /// The sampled direct light per receiver (part of `estimated`); empty
    /// when no source is sampled.
    pub sampled_direct: Vec<Welford>,
    /// `orders[k][j]`: order `k+1` for `k < K`, and all orders above `K` for `k = K`.
    pub orders: Vec<Vec<Welford>>,
    /// `R^2 B` of each receiver's total at batch counts 32, 64, 128, ... (for the FOM check).
    pub snapshots: Vec<(u64, Vec<f64>)>,
    /// Per receiver: events that the `sparse` check counts over the run
    /// (see [`crate::tally::Diagnostics::near_hits`]).
    pub near_hits: Vec<u64>,
    /// Per receiver: whether the `sparse` check applies.
    pub watched: Vec<bool>,
    /// Per receiver: whether the `near` check flags it (a surface much
    /// closer than the nearest light, on the plain local estimate).
    pub near_plain: Vec<bool>,
    /// Per receiver: whether its near part's reach is counted.
    pub near_reach: Vec<bool>,
    /// Per receiver: whether it is enclosed (flag `enclosed`; empty: none).
    pub enclosed: Vec<bool>,
    /// Whether the scene's lights approximate it (flag `approx` on every
    /// receiver: [`crate::scene::Scene::approximate`]).
    pub approximate: bool,
    /// Per receiver: the near part's exposed and reached path vertices over
    /// the run (see [`crate::tally::Diagnostics::near_reach`]).
    pub near_vertices: Vec<[u64; 2]>,
    /// The per-batch means of the estimated part of the first receivers
    /// (none by default; see [`crate::run::RunConfig::keep_batch_means`]).
    pub batch_means: BatchMeans,
}

/// The order bucket of light reflected `order >= 1` times when `orders`
/// orders are resolved: `order - 1` up to `orders`, then the last bucket
/// (`orders`) for all higher orders; always 0 when `orders == 0`.
#[inline]
pub fn bucket(order: u32, orders: u32) -> usize {
    if orders == 0 {
        0
    } else {
        (order.clamp(1, orders + 1) - 1) as usize
    }
}

/// Number of order buckets for `orders` resolved orders (1 when none are).
pub fn bucket_count(orders: u32) -> usize {
    if orders == 0 { 1 } else { orders as usize + 1 }
}

impl Tallies {
    /// Empty tallies for `n` receivers with `orders` resolved orders.
    pub fn new(n: usize, orders: u32) -> Self {
        let buckets = if orders == 0 { 0 } else { orders as usize + 1 };
        Self {
            estimated: vec![Welford::new(); n],
            sampled_direct: Vec::new(),
            orders: vec![vec![Welford::new(); n]; buckets],
            snapshots: Vec::new(),
            near_hits: vec![0; n],
            watched: vec![false; n],
            near_plain: vec![false; n],
            near_reach: vec![false; n],
            enclosed: Vec::new(),
            approximate: false,
            near_vertices: vec![[0; 2]; n],
            batch_means: BatchMeans::default(),
        }
    }

    /// Fold one batch: `sums[k * n + j]` is the batch's sum over its `chains`
    /// chains of bucket `k` at receiver `j`; `direct_sums[j]` (empty: none)
    /// the batch's sampled direct light at `j` times `chains`; `near_hits` the batch's counts
    /// for the `sparse` check (may be empty; with `3 n` entries, the near
    /// part's exposed and reached vertices follow the `n` collision counts,
    /// see [`crate::run::Batch::near_hits`]). `means` is scratch of the
    /// length of `sums`.
    pub fn fold(
        &mut self,
        sums: &[f64],
        direct_sums: &[f64],
        chains: u64,
        near_hits: &[u64],
        means: &mut [f64],
    ) {
        let n = self.estimated.len();
        let buckets = sums.len() / n.max(1);
        let inv = 1.0 / chains as f64;
        for (m, s) in means.iter_mut().zip(sums) {
            *m = s * inv;
        }
        if !direct_sums.is_empty() && self.sampled_direct.is_empty() {
            self.sampled_direct = vec![Welford::new(); n];
        }
        for j in 0..n {
            let d = direct_sums.get(j).map_or(0.0, |s| s * inv);
            let total: f64 = (0..buckets).map(|k| means[k * n + j]).sum::<f64>() + d;
            self.estimated[j].push(total);
            self.batch_means.record(j, total);
            if let Some(w) = self.sampled_direct.get_mut(j) {
                w.push(d);
            }
        }
        for (t, h) in self.near_hits.iter_mut().zip(near_hits) {
            *t += h;
        }
        if near_hits.len() == 3 * n {
            for (j, v) in self.near_vertices.iter_mut().enumerate() {
                v[0] += near_hits[n + j];
                v[1] += near_hits[2 * n + j];
            }
        }
        for (k, bucket) in self.orders.iter_mut().enumerate() {
            for (j, w) in bucket.iter_mut().enumerate() {
                w.push(means[k * n + j]);
            }
        }
    }

    /// Record `R^2 B` of every receiver (total = `direct` + estimated part).
    pub fn snapshot(&mut self, direct: &[f64]) {
        let b = self.batches();
        let v = self
            .estimated
            .iter()
            .zip(direct)
            .map(|(w, d)| relative_error(d + w.mean(), w.std_error()).powi(2) * b as f64)
            .collect();
        self.snapshots.push((b, v));
    }

    /// Statistical checks of receiver `j` whose exact part is `direct`, at
    /// [`super::check_bounds::FALSE_ALARM`] per check over this run's
    /// receivers.
    pub fn diagnostics(&self, j: usize, direct: f64) -> Diagnostics {
        let b = self.batches();
        let half = self
            .snapshots
            .iter()
            .rev()
            .find(|(n, _)| 2 * n <= b)
            .map(|(n, v)| (*n, v[j]));
        let mut d = Diagnostics::of(&self.estimated[j], direct, half, self.estimated.len());
        // The reflected part is exactly 0 where every batch's total was its
        // sampled direct light alone (reflected scores are never negative,
        // and a batch adds nothing to its direct light exactly then): the
        // `sparse` check has no reflected light to judge.
        d.indirect_zero = self.estimated[j].mean() == self.sampled_direct_mean(j);
        d.near_hits = self
            .watched
            .get(j)
            .copied()
            .unwrap_or(false)
            .then(|| self.near_hits[j]);
        d.near = self.near_plain.get(j).copied().unwrap_or(false);
        d.enclosed = self.enclosed.get(j).copied().unwrap_or(false);
        d.approximate = self.approximate;
        d.near_reach = (self.near_reach.get(j).copied().unwrap_or(false)
            && self.near_vertices[j][0] > 0)
            .then(|| self.near_vertices[j][1]);
        d
    }

    /// [`Self::diagnostics`] with the false-alarm rate held over a family
    /// of `family` receivers (at least this run's): a gate that judges the
    /// rows of several runs together (`lumest validate daylight`) passes
    /// them all, so that a sound gate fails in at most
    /// [`super::check_bounds::FALSE_ALARM`] of its runs per check, however
    /// many runs it makes.
    pub fn diagnostics_among(&self, j: usize, direct: f64, family: usize) -> Diagnostics {
        self.diagnostics(j, direct).among(family)
    }

    /// Mean sampled direct light at receiver `j` (0 when none is sampled).
    pub fn sampled_direct_mean(&self, j: usize) -> f64 {
        self.sampled_direct.get(j).map_or(0.0, Welford::mean)
    }

    /// Number of batches folded in.
    pub fn batches(&self) -> u64 {
        self.estimated.first().map_or(0, Welford::count)
    }

    /// Relative standard error of the total `E = direct + estimated part` per receiver.
    pub fn rel_errors<'a>(&'a self, direct: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
        self.estimated
            .iter()
            .zip(direct)
            .map(|(w, d)| relative_error(d + w.mean(), w.std_error()))
    }

    /// Largest relative standard error of the total over the receivers
    /// (NaN propagates: a receiver without a defined error is never hidden).
    pub fn max_rel_error(&self, direct: &[f64]) -> f64 {
        self.rel_errors(direct)
            .fold(0.0, |m, r| if r.is_nan() || r > m { r } else { m })
    }

    /// Root mean square of the relative standard error of the total over the receivers.
    pub fn rms_rel_error(&self, direct: &[f64]) -> f64 {
        let n = self.estimated.len().max(1) as f64;
        // A fold from +0: an empty f64 sum is -0, which printed as "-0.000e0".
        let s = self.rel_errors(direct).fold(0.0, |a, r| a + r * r);
        (s / n).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One receiver of 40 batch means: 39 at +-1 and one outlier `v`.
    fn one_outlier(v: f64) -> Tallies {
        let mut t = Tallies::new(1, 0);
        let mut means = [0.0];
        for b in 0..40 {
            let x = if b == 17 {
                v
            } else if b % 2 == 0 {
                11.0
            } else {
                9.0
            };
            t.fold(&[x], &[], 1, &[], &mut means);
        }
        t
    }

    /// A gate over many runs' rows widens each run's check bounds to its
    /// family: an outlier flagged among one receiver's bounds passes among
    /// a million receivers', and a family smaller than the run is the run.
    #[test]
    fn diagnostics_among_a_family_widen_to_it() {
        let own = one_outlier(10.0).diagnostics(0, 0.0);
        let many = one_outlier(10.0).diagnostics_among(0, 0.0, 1_000_000);
        assert!(own.deviation_bound < many.deviation_bound);
        assert!(own.vov_bound <= many.vov_bound);
        // The outlier whose deviation lies between the two bounds.
        let v = (0..2000)
            .map(|i| 10.0 + 0.01 * f64::from(i))
            .find(|&v| {
                let d = one_outlier(v).diagnostics(0, 0.0);
                d.max_deviation > d.deviation_bound
            })
            .expect("some outlier flags among one receiver");
        let t = one_outlier(v);
        assert!(t.diagnostics(0, 0.0).flag().contains("tail"));
        assert!(
            !t.diagnostics_among(0, 0.0, 1_000_000)
                .flag()
                .contains("tail")
        );
        // A family below the run's own receivers is the run's.
        let (a, b) = (t.diagnostics(0, 0.0), t.diagnostics_among(0, 0.0, 0));
        assert_eq!(a.deviation_bound, b.deviation_bound);
        assert_eq!(a.flag(), b.flag());
    }

    /// Every check's bound widens with the family (the tail, the VOV and
    /// the FOM range), and a family smaller than the run's receivers is the
    /// run's: a run of 3 receivers (64 batches, FOM snapshot at 32) judged
    /// among 1 keeps the bounds of 3, not those of a lone receiver.
    #[test]
    fn diagnostics_among_widen_every_check_and_never_narrow_the_run() {
        let mut t = Tallies::new(3, 0);
        let mut means = [0.0; 3];
        let mut rng = crate::sampling::Philox4x32::new(7, 0);
        for b in 0..64u64 {
            let x: Vec<f64> = (0..3)
                .map(|j| 10.0 + f64::from(j) + rng.next_f64())
                .collect();
            t.fold(&x, &[], 1, &[], &mut means);
            if b + 1 == 32 {
                t.snapshot(&[0.0; 3]);
            }
        }
        let run = t.diagnostics(1, 0.0);
        let many = t.diagnostics_among(1, 0.0, 1_000_000);
        assert!(run.fom_ratio.is_some(), "the FOM check runs");
        assert!(run.deviation_bound < many.deviation_bound);
        assert!(run.vov_bound < many.vov_bound, "{run:?} {many:?}");
        assert!(many.vov_bound.is_finite(), "{many:?}");
        // (The FOM range's lower end is held at 0.5 for both.)
        assert!(many.fom_bounds.0 <= run.fom_bounds.0);
        assert!(run.fom_bounds.1 < many.fom_bounds.1, "{run:?} {many:?}");
        // Among 1 (or 0): the run's own 3 receivers, wider than a lone
        // receiver's bounds.
        let lone = Diagnostics::of(&t.estimated[1], 0.0, Some((32, t.snapshots[0].1[1])), 1);
        assert!(lone.deviation_bound < run.deviation_bound);
        for family in [0, 1, 3] {
            assert_eq!(t.diagnostics_among(1, 0.0, family), run, "family {family}");
        }
    }
}
