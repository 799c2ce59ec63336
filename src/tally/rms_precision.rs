//! How precisely a pilot measured the mean square relative error over many
//! receivers: the effective number of independent receivers behind
//! `Q = mean_j R_j^2`.
//!
//! One receiver's `R^2` from `B` normal batch means is a chi-square
//! variate with `B - 1` degrees of freedom, `var(R^2) / R^4 = 2 / (B - 1)`.
//! The mean over `n` receivers is more precise, by how much depending on how
//! the receivers' errors move together (they share chains). For normal
//! batch means `cov(s_j^2, s_k^2) = 2 sigma_j^2 sigma_k^2 rho_jk^2 / (B -
//! 1)`, so with weights `w_j = R_j^2`
//!
//! `var(Q) / Q^2 = 2 / ((B - 1) m)`, `m = (sum_j w_j)^2 / sum_jk w_j w_k rho_jk^2`,
//!
//! `m` between 1 (all alike) and `n` (independent, equal weights): `Q` has
//! `m (B - 1)` degrees of freedom. The correlations come from the batch
//! means, `r_jk = sum_b z_bj z_bk / (B - 1)` with `z` the standardised
//! deviations, and the double sum costs `O(B^2 n)`, not `O(n^2)`:
//! `sum_jk w_j w_k r_jk^2 = sum_bc G_bc^2 / (B - 1)^2` with the `B x B`
//! matrix `G_bc = sum_j w_j z_bj z_cj`. `r^2` is biased up by about
//! `(1 - rho^2) / (B - 1)`; the adjusted `1 - (1 - r^2) (B - 1) / (B - 2)`
//! (exact in the mean for independent receivers) corrects it. Second
//! moments only: steadier than a jackknife of `Q`, which needs the fourth.
//! `m` depends on how the receivers share chains, not on the batch size, so
//! a later pilot stage with other batches keeps it.

use super::BatchMeans;

/// Effective number of independent receivers `m` in `[1, n]` behind the
/// mean over the receivers of the squared relative error of the total
/// `direct[j] + mean_j` (module docs), from the batch means `bm` of every
/// receiver; 1 where it cannot be measured (fewer than four batches, no
/// receiver kept, an undefined or zero mean square error).
pub fn rms_effective_receivers(bm: &BatchMeans, direct: &[f64]) -> f64 {
    let (b, n) = (bm.batches(), bm.receivers().min(direct.len()));
    if b < 4 || n == 0 {
        return 1.0;
    }
    let bf = b as f64;
    let mut mean = vec![0.0; n];
    for k in 0..b {
        for (m, x) in mean.iter_mut().zip(bm.batch(k)) {
            *m += x;
        }
    }
    mean.iter_mut().for_each(|m| *m /= bf);
    let mut ss = vec![0.0; n];
    for k in 0..b {
        for ((s, x), m) in ss.iter_mut().zip(bm.batch(k)).zip(&mean) {
            *s += (x - m) * (x - m);
        }
    }
    // w_j = R_j^2 (0 for an exact receiver) and 1 / s_j to standardise.
    let mut w = vec![0.0; n];
    let mut inv_sd = vec![0.0; n];
    for j in 0..n {
        let total = direct[j] + mean[j];
        if ss[j] > 0.0 {
            let var = ss[j] / (bf - 1.0);
            w[j] = var / (bf * total * total);
            inv_sd[j] = var.sqrt().recip();
        }
    }
    let total_w: f64 = w.iter().sum();
    if !(total_w.is_finite() && total_w > 0.0) {
        return 1.0;
    }
    // G_bc = sum_j w_j z_bj z_cj, c >= b.
    let z: Vec<Vec<f64>> = (0..b)
        .map(|k| {
            let x = bm.batch(k);
            (0..n).map(|j| (x[j] - mean[j]) * inv_sd[j]).collect()
        })
        .collect();
    let mut sum_g2 = 0.0;
    for k in 0..b {
        for c in k..b {
            let g: f64 = (0..n).map(|j| w[j] * z[k][j] * z[c][j]).sum();
            sum_g2 += if c == k { g * g } else { 2.0 * g * g };
        }
    }
    let raw = sum_g2 / ((bf - 1.0) * (bf - 1.0));
    let c = (bf - 1.0) / (bf - 2.0);
    let adjusted = c * raw - (c - 1.0) * total_w * total_w;
    let m = total_w * total_w / adjusted;
    if adjusted > 0.0 && m.is_finite() {
        m.clamp(1.0, n as f64)
    } else {
        n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;

    fn normal(rng: &mut Philox4x32) -> f64 {
        let [u1, u2] = rng.next_2d();
        (-2.0 * (1.0 - u1).ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Batch means of `n` receivers around 10, each `shared` of a common
    /// normal and `1 - shared` of its own (in variance).
    fn means(n: usize, b: usize, shared: f64, seed: u64) -> BatchMeans {
        let mut rng = Philox4x32::new(seed, 7);
        let mut bm = BatchMeans::new(n);
        for _ in 0..b {
            let common = normal(&mut rng);
            for j in 0..n {
                let own = normal(&mut rng);
                bm.record(
                    j,
                    10.0 + shared.sqrt() * common + (1.0 - shared).sqrt() * own,
                );
            }
        }
        bm
    }

    /// Mean and spread of `m` over seeds.
    fn measured(n: usize, b: usize, shared: f64) -> (f64, f64) {
        let direct = vec![0.0; n];
        let v: Vec<f64> = (0..16)
            .map(|s| rms_effective_receivers(&means(n, b, shared, s), &direct))
            .collect();
        let avg = v.iter().sum::<f64>() / v.len() as f64;
        let sd = (v.iter().map(|x| (x - avg) * (x - avg)).sum::<f64>() / 15.0).sqrt();
        (avg, sd)
    }

    /// `m = 1 / (rho^2 + (1 - rho)^2 / n)` for a common share `rho` of the
    /// variance: 4 for a half, 23 for a fifth of 200 receivers, near `n`
    /// for independent ones, 1 for identical ones. Off by a factor 2 (the
    /// bias of `r^2` left in) these fail.
    #[test]
    fn shared_errors_count_as_fewer_receivers() {
        let want = |n: f64, rho: f64| 1.0 / (rho * rho + (1.0 - rho) * (1.0 - rho) / n);
        for (n, b, rho) in [(400, 32, 0.5), (200, 32, 0.2), (200, 16, 0.2)] {
            let (avg, sd) = measured(n, b, rho);
            let w = want(n as f64, rho);
            println!("n {n} B {b} rho {rho}: m {avg:.2} +- {sd:.2}, want {w:.2}");
            assert!(
                (avg / w - 1.0).abs() < 0.3,
                "n {n} B {b} rho {rho}: {avg} vs {w}"
            );
        }
        let (avg, _) = measured(100, 32, 0.0);
        assert!(avg > 60.0, "independent: {avg}");
        let (avg, _) = measured(100, 32, 1.0);
        assert!(avg < 1.0 + 1e-9, "identical: {avg}");
    }

    #[test]
    fn degenerate_cases_count_one_receiver() {
        assert_eq!(rms_effective_receivers(&BatchMeans::new(3), &[0.0; 3]), 1.0);
        assert_eq!(
            rms_effective_receivers(&means(5, 3, 0.0, 1), &[0.0; 5]),
            1.0
        );
        // Exact receivers (no spread): no measure.
        let mut bm = BatchMeans::new(2);
        for _ in 0..10 {
            bm.record(0, 1.0);
            bm.record(1, 2.0);
        }
        assert_eq!(rms_effective_receivers(&bm, &[0.0; 2]), 1.0);
        // One receiver: exactly 1.
        let m = rms_effective_receivers(&means(1, 32, 0.0, 3), &[0.0]);
        assert!((m - 1.0).abs() < 1e-12, "{m}");
    }
}
