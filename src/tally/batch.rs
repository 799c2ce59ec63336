//! One batch's sums: what a work item hands the runner, what the runner
//! folds into the [`super::Tallies`], and what a shard keeps unfolded.

/// The sums of one batch, produced by a [`crate::run::BatchWork`].
#[derive(Clone, Debug)]
pub struct Batch {
    /// Batch index.
    pub index: u64,
    /// Chains (or paths) traced in the batch.
    pub chains: u64,
    /// `sums[k * n + j]`: sum over the batch's chains of bucket `k`'s score at receiver `j`.
    pub sums: Vec<f64>,
    /// Surface collisions (or path vertices) in the batch.
    pub collisions: u64,
    /// Receiver scores evaluated in the batch.
    pub scores: u64,
    /// Per receiver: the batch's sampled direct light times its chains
    /// (summed like `sums`; see [`crate::estimator::Receivers::sampled_direct`]);
    /// empty when no receiver has any.
    pub direct_sums: Vec<f64>,
    /// Per receiver: events counted for the `sparse` check
    /// ([`crate::tally::Diagnostics::near_hits`]); empty when it does not
    /// apply. Length `3 n` when some receiver has [`crate::run::Checks::near_reach`]:
    /// then `near_hits[n + j]` and `near_hits[2 n + j]` are the near part's
    /// exposed and reached path vertices at receiver `j`
    /// ([`crate::tally::Diagnostics::near_reach`]).
    pub near_hits: Vec<u64>,
}

impl Batch {
    /// Add `part`, the sums of further chains of the same batch (a batch
    /// that grows part by part, [`crate::run::BatchWork::run_part`]).
    pub fn extend(&mut self, part: &Batch) {
        debug_assert_eq!(self.index, part.index);
        self.chains += part.chains;
        self.collisions += part.collisions;
        self.scores += part.scores;
        for (s, p) in self.sums.iter_mut().zip(&part.sums) {
            *s += p;
        }
        for (s, p) in self.direct_sums.iter_mut().zip(&part.direct_sums) {
            *s += p;
        }
        for (s, p) in self.near_hits.iter_mut().zip(&part.near_hits) {
            *s += p;
        }
    }
}
