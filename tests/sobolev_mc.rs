//! Monte Carlo against the exact Sobolev solution: statistical agreement
//! (Sidak-corrected z bounds), calibration of the error bars, and order by
//! order agreement. Fixed seeds; fast in release mode.

mod common;
use common::{chains_cfg, sobolev_run, z, zcheck};
use lumest::reference::Sobolev;
use lumest::run::RunConfig;
use lumest::tally::sidak_bound;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Family-wise false-alarm rate of each test.
const ALPHA: f64 = 1e-3;

#[test]
fn agrees_with_exact_solution_on_both_planes() {
    // (h1, h2, rho1, rho2): the seed paper's case, an asymmetric one, and rho = 0.9.
    let configs = [
        (0.5, 0.5, 0.5, 0.5),
        (0.3, 0.7, 0.2, 0.8),
        (0.5, 0.5, 0.9, 0.9),
    ];
    let n = 24;
    let mut worst: f64 = 0.0;
    let mut batches = u64::MAX;
    for (k, &p) in configs.iter().enumerate() {
        let (case, r) = sobolev_run(p, n, 2.5, &chains_cfg(200_000, 11 + k as u64, 0));
        batches = batches.min(r.tallies.batches());
        for j in 0..n {
            let zj = z(&r, j, case.exact[j].e);
            assert!(zj.is_finite());
            worst = zcheck::max_abs(worst, zj);
        }
    }
    let bound = sidak_bound(ALPHA, configs.len() * n, Some(batches));
    assert!(
        worst < bound,
        "max |z| = {worst} exceeds the Sidak bound {bound}"
    );
}

#[test]
fn orders_agree_with_neumann_terms() {
    let p = (0.5, 0.5, 0.5, 0.5);
    let s = Sobolev::new(p.0, p.1, p.2, p.3, 1.0).unwrap();
    let cfg = RunConfig {
        orders: 3,
        ..chains_cfg(200_000, 5, 0)
    };
    let n = 12;
    let (case, r) = sobolev_run(p, n, 2.0, &cfg);
    let mut worst: f64 = 0.0;
    for j in 0..n {
        for k in 0..3 {
            let w = &r.tallies.orders[k][j];
            let exact = s.order(case.plane[j], case.r[j], k as u32 + 1);
            worst = zcheck::max_abs(worst, zcheck::z_score(w.mean(), w.std_error(), exact));
        }
        // The buckets add up to the indirect total.
        let sum: f64 = r.tallies.orders.iter().map(|b| b[j].mean()).sum();
        let ind = r.tallies.estimated[j].mean();
        assert!((sum - ind).abs() <= 1e-12 * ind, "{sum} vs {ind}");
    }
    let bound = sidak_bound(ALPHA, 3 * n, Some(r.tallies.batches()));
    assert!(worst < bound, "max |z| = {worst} exceeds {bound}");
}

#[test]
fn error_bars_are_calibrated() {
    // Independent runs (seeds); one point per run so the z values are
    // independent. Under honest error bars each z follows Student t with
    // B - 1 degrees of freedom: test the mean of z^2 (CLT bound from the
    // F(1, B-1) moments) and the whole distribution (Kolmogorov-Smirnov).
    let runs = 80;
    let n = 8;
    let mut zs = Vec::with_capacity(runs);
    let mut b = 0;
    for seed in 0..runs as u64 {
        let (case, r) = sobolev_run(
            (0.5, 0.5, 0.7, 0.7),
            n,
            3.0,
            &chains_cfg(8_192, 1000 + seed, 0),
        );
        let j = seed as usize % n;
        zs.push(z(&r, j, case.exact[j].e));
        b = r.tallies.batches();
    }
    let d = (b - 1) as f64;
    let mean_f = d / (d - 2.0);
    let var_f = 2.0 * d * d * (d - 1.0) / ((d - 2.0).powi(2) * (d - 4.0));
    let mean_z2 = zs.iter().map(|z| z * z).sum::<f64>() / runs as f64;
    let k = sidak_bound(ALPHA, 1, None) * (var_f / runs as f64).sqrt();
    assert!(
        (mean_z2 - mean_f).abs() < k,
        "mean z^2 = {mean_z2}, expected {mean_f} +- {k}"
    );

    let t = StudentsT::new(0.0, 1.0, d).unwrap();
    zs.sort_by(f64::total_cmp);
    let m = runs as f64;
    let ks = zs
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let c = t.cdf(x);
            (c - i as f64 / m).abs().max(((i + 1) as f64 / m - c).abs())
        })
        .fold(0.0, zcheck::max_abs);
    // Asymptotic KS critical value at level ALPHA: sqrt(-ln(ALPHA/2)/2) / sqrt(m).
    let crit = (-(ALPHA / 2.0).ln() / 2.0).sqrt() / m.sqrt();
    assert!(ks < crit, "KS distance {ks} >= {crit}");
}
