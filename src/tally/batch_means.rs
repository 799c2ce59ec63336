//! The per-batch means of chosen receivers, kept for statistics that are
//! not linear in the means (the minimum over a grid, uniformity), whose
//! errors come from resampling the batches ([`super::surface_figures`]).

/// Per-batch means of the first `receivers` receivers: row `b` holds batch
/// `b`'s mean of each (the estimated part, in the tally's unit), in batch
/// order. Costs `8 receivers` bytes a batch; empty when `receivers == 0`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BatchMeans {
    receivers: usize,
    values: Vec<f64>,
}

impl BatchMeans {
    /// Keep the batch means of receivers `0 .. receivers`.
    pub fn new(receivers: usize) -> Self {
        Self {
            receivers,
            values: Vec::new(),
        }
    }

    /// The kept values, batch by batch (for a checkpoint).
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The store of `receivers` per batch holding `values` (from
    /// [`Self::values`]).
    pub fn from_values(receivers: usize, values: Vec<f64>) -> Self {
        Self { receivers, values }
    }

    /// Receivers kept per batch.
    pub fn receivers(&self) -> usize {
        self.receivers
    }

    /// Batches kept.
    pub fn batches(&self) -> usize {
        self.values.len().checked_div(self.receivers).unwrap_or(0)
    }

    /// Record batch mean `x` of receiver `j`; a batch is recorded receiver
    /// by receiver in order `0, 1, ...` (receivers beyond
    /// [`Self::receivers`] are not kept).
    #[inline]
    pub fn record(&mut self, j: usize, x: f64) {
        if j < self.receivers {
            debug_assert_eq!(self.values.len() % self.receivers, j);
            self.values.push(x);
        }
    }

    /// Keep only receivers `0 .. receivers` (no change when that is not
    /// fewer): the store a run that kept those from the start would hold.
    pub fn truncate(&mut self, receivers: usize) {
        if receivers >= self.receivers {
            return;
        }
        let batches = self.batches();
        let mut kept = Vec::with_capacity(batches * receivers);
        for b in 0..batches {
            kept.extend_from_slice(&self.batch(b)[..receivers]);
        }
        *self = Self {
            receivers,
            values: kept,
        };
    }

    /// Batch `b`'s means, one per kept receiver.
    pub fn batch(&self, b: usize) -> &[f64] {
        &self.values[b * self.receivers..(b + 1) * self.receivers]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_rows_in_order() {
        let mut m = BatchMeans::new(2);
        for row in [[1.0, 2.0, 9.0], [3.0, 4.0, 9.0]] {
            for (j, x) in row.into_iter().enumerate() {
                m.record(j, x);
            }
        }
        assert_eq!(m.batches(), 2);
        assert_eq!(m.batch(1), &[3.0, 4.0]);
        let mut none = BatchMeans::new(0);
        none.record(0, 1.0);
        assert_eq!(none.batches(), 0);
    }

    /// Truncated to fewer receivers, the store equals one that kept those
    /// receivers from the start; to more or as many, it is unchanged.
    #[test]
    fn truncate_keeps_the_first_receivers() {
        let rows = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]];
        let mut all = BatchMeans::new(3);
        let mut one = BatchMeans::new(1);
        for row in rows {
            for (j, x) in row.into_iter().enumerate() {
                all.record(j, x);
                one.record(j, x);
            }
        }
        let before = all.clone();
        all.truncate(3);
        assert_eq!(all, before);
        all.truncate(1);
        assert_eq!(all, one);
        assert_eq!(all.batch(1), &[4.0]);
    }
}
