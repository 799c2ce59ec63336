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
//!
//! `m` is at most `K = (sum_j w_j)^2 / sum_j w_j^2` (independent
//! receivers; `n` for equal weights). Batch means with heavy tails make
//! each `s_j^2` noisier, `var(s^2) / sigma^4 = 2 / (B - 1) + kappa / B`
//! (`kappa` the excess kurtosis), so `m` is divided by `1 + kappa (B - 1)
//! / (2 B)` with `kappa` the `w^2`-weighted sample excess kurtosis of the
//! receivers' batch means (when positive): exact for identical or
//! independent receivers.

use super::BatchMeans;

/// Effective number of independent receivers `m` (at most `K`, and below
/// 1 only for heavy tails) behind the mean over the receivers of the
/// squared relative error of the total `direct[j] + mean_j` (module docs),
/// from the batch means `bm` of every receiver: `Q` has `m (B - 1)`
/// degrees of freedom. 1 where it cannot be measured (fewer than four
/// batches, no receiver kept, an undefined or zero mean square error).
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
    let (mut ss, mut s4) = (vec![0.0; n], vec![0.0; n]);
    for k in 0..b {
        for (((s, f), x), m) in ss.iter_mut().zip(&mut s4).zip(bm.batch(k)).zip(&mean) {
            let d2 = (x - m) * (x - m);
            *s += d2;
            *f += d2 * d2;
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
    // K, and the w^2-weighted sample excess kurtosis.
    let sum_w2: f64 = w.iter().map(|x| x * x).sum();
    let most = total_w * total_w / sum_w2;
    let kurtosis = (0..n)
        .filter(|&j| ss[j] > 0.0)
        .map(|j| w[j] * w[j] * (bf * s4[j] / (ss[j] * ss[j]) - 3.0))
        .sum::<f64>()
        / sum_w2;
    let tails = 1.0 + kurtosis.max(0.0) * (bf - 1.0) / (2.0 * bf);
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
    let m = if adjusted > 0.0 && m.is_finite() {
        m.clamp(1.0, most)
    } else {
        most
    };
    m / tails
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

    /// `m = n / (1 + (n - 1) rho^2) = 1 / (rho^2 + (1 - rho^2) / n)` for a
    /// common share `rho` of the variance (correlation `rho` between
    /// receivers): 3.97 for a half of 400, 22.3 for a fifth of 200
    /// receivers, near `n` for independent ones, 1 for identical ones. With
    /// the bias of `r^2` left in, the fifth-of-200 cases fail.
    #[test]
    fn shared_errors_count_as_fewer_receivers() {
        let want = |n: f64, rho: f64| 1.0 / (rho * rho + (1.0 - rho * rho) / n);
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

    /// Heavy-tailed batch means (lognormal, sigma 0.8: excess kurtosis
    /// about 30) make `Q` noisier than normal ones: `m` falls below one
    /// receiver's for a single receiver, and by the tails' factor for many.
    #[test]
    fn heavy_tails_count_as_fewer_receivers() {
        let lognormal = |n: usize, seed: u64| {
            let mut rng = Philox4x32::new(seed, 9);
            let mut bm = BatchMeans::new(n);
            for _ in 0..32 {
                for j in 0..n {
                    bm.record(j, (0.8 * normal(&mut rng)).exp());
                }
            }
            bm
        };
        let mut one = 0.0;
        let mut many = 0.0;
        for seed in 0..16 {
            one += rms_effective_receivers(&lognormal(1, seed), &[0.0]) / 16.0;
            many += rms_effective_receivers(&lognormal(100, seed), &[0.0; 100]) / 16.0;
        }
        assert!(one < 0.5, "one heavy-tailed receiver: {one}");
        // Independent: 100 receivers less the tails' factor (the sample
        // kurtosis of 32 values: about 5-8, a factor 3.5-5).
        assert!(
            many > 10.0 && many < 40.0,
            "100 heavy-tailed receivers: {many}"
        );
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
        // One receiver: 1, less its tails' factor (normal: sample excess
        // kurtosis near 0, so about 1).
        let m = rms_effective_receivers(&means(1, 32, 0.0, 3), &[0.0]);
        assert!(m <= 1.0 && m > 0.5, "{m}");
        // Weights concentrated on one receiver: K, not n.
        let mut bm = means(50, 32, 0.0, 4);
        let direct: Vec<f64> = (0..50).map(|j| if j == 0 { 0.0 } else { 1e3 }).collect();
        let m = rms_effective_receivers(&bm, &direct);
        assert!(m < 1.5, "{m}");
        bm = means(50, 32, 0.0, 4);
        assert!(rms_effective_receivers(&bm, &[0.0; 50]) > 25.0);
    }
}
