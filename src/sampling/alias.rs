//! Walker's alias method in Vose's numerically stable construction: draw
//! index `i` with probability `w_i / sum w` in O(1) from one uniform.
//!
//! The table splits `n` equal columns between an index and its alias:
//! column `k` yields `k` with probability `prob[k]` and `alias[k]`
//! otherwise. One uniform `u` picks the column `floor(u n)` and, from its
//! fractional part, the side (Vose 1991, "A linear algorithm for generating
//! random numbers with a given distribution").

/// An alias table over `n` weights.
#[derive(Clone, Debug, PartialEq)]
pub struct AliasTable {
    prob: Vec<f64>,
    alias: Vec<u32>,
    /// The normalised probabilities, for [`Self::pmf`].
    pmf: Vec<f64>,
}

impl AliasTable {
    /// The table of `weights`; `None` when a weight is negative or not
    /// finite, or when all are zero (or there are none).
    pub fn new(weights: &[f64]) -> Option<Self> {
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return None;
        }
        let total: f64 = weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let n = weights.len();
        let pmf: Vec<f64> = weights.iter().map(|w| w / total).collect();
        let mut scaled: Vec<f64> = pmf.iter().map(|p| p * n as f64).collect();
        let mut prob = vec![1.0; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            prob[s] = scaled[s];
            alias[s] = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left holds probability 1 up to rounding.
        for i in small.into_iter().chain(large) {
            prob[i] = 1.0;
        }
        // A zero weight is never drawn, even through rounding.
        for (i, p) in prob.iter_mut().enumerate() {
            if pmf[i] == 0.0 {
                *p = 0.0;
            }
        }
        Some(Self { prob, alias, pmf })
    }

    /// Index drawn with its probability, from one uniform `u` in `[0, 1)`.
    #[inline]
    pub fn sample(&self, u: f64) -> usize {
        let n = self.prob.len();
        let x = u * n as f64;
        let k = (x as usize).min(n - 1);
        if x - (k as f64) < self.prob[k] {
            k
        } else {
            self.alias[k] as usize
        }
    }

    /// Probability of index `i`.
    pub fn pmf(&self, i: usize) -> f64 {
        self.pmf[i]
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.prob.len()
    }

    /// True when the table has no entries (never: [`Self::new`] refuses).
    pub fn is_empty(&self) -> bool {
        self.prob.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;
    use statrs::distribution::{ChiSquared, ContinuousCDF};

    fn chi2_p(counts: &[f64], probs: &[f64], n: f64) -> f64 {
        let mut stat = 0.0;
        let mut dof = 0;
        for (o, p) in counts.iter().zip(probs) {
            if *p > 0.0 {
                let e = p * n;
                stat += (o - e) * (o - e) / e;
                dof += 1;
            } else {
                assert_eq!(*o, 0.0, "a zero weight was drawn");
            }
        }
        1.0 - ChiSquared::new((dof - 1) as f64).unwrap().cdf(stat)
    }

    #[test]
    fn draws_follow_the_weights_and_a_perturbed_table_fails() {
        let w = [5.0, 0.0, 1.0, 12.5, 0.25, 3.0, 7.0, 0.0, 1e-3, 2.0];
        let t = AliasTable::new(&w).unwrap();
        let total: f64 = w.iter().sum();
        let probs: Vec<f64> = w.iter().map(|x| x / total).collect();
        let n = 1_000_000;
        let mut counts = vec![0.0; w.len()];
        let mut rng = Philox4x32::new(1, 0);
        for _ in 0..n {
            counts[t.sample(rng.next_f64())] += 1.0;
        }
        assert!(chi2_p(&counts, &probs, n as f64) > 1e-4);
        // Judged against weights 2 % off in two entries, the same draws fail.
        let mut off = probs.clone();
        off[0] *= 1.02;
        off[3] *= 0.98;
        let s: f64 = off.iter().sum();
        let off: Vec<f64> = off.iter().map(|p| p / s).collect();
        assert!(chi2_p(&counts, &off, n as f64) < 1e-6);
        for (i, p) in probs.iter().enumerate() {
            assert!((t.pmf(i) - p).abs() < 1e-15);
        }
    }

    #[test]
    fn bad_weights_are_refused_and_one_weight_is_always_drawn() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[1.0, -1.0]).is_none());
        assert!(AliasTable::new(&[1.0, f64::NAN]).is_none());
        let t = AliasTable::new(&[0.0, 3.0, 0.0]).unwrap();
        for k in 0..100 {
            assert_eq!(t.sample(k as f64 / 100.0), 1);
        }
        assert_eq!(t.sample(1.0 - f64::EPSILON), 1);
    }
}
