//! The batch nets of `--qmc` (issue 15 item 4): every method stays unbiased
//! and its error bars stay honest on the Sobolev problem against its exact
//! solution, and the methods differ where they should.
//!
//! Per method, `R` runs (seeds) of `P` points with `B` batches each:
//!
//! * bias: per point, the mean over runs of `E - E_exact` against its
//!   standard error from the spread across runs, `|z|` within the Sidak
//!   bound for `P` points (family-wise false alarms 1e-3 per method);
//! * calibration: mean `z^2` with `z = (E - E_exact) / se` follows from
//!   Student t with `B - 1` degrees of freedom, `E[z^2] = (B-1)/(B-3)`, and
//!   the 95 % Student-t interval covers with 0.95; both within `k` standard
//!   errors of the per-run values' spread (`k` the t quantile at 1e-3/4),
//!   and the same bound rejects error bars scaled by 0.8 (so it resolves a
//!   20 % miscalibration on these data).
//!
//! Cost: about 2 CPU-s per method in release.

use lumest::cases::sobolev::sobolev_case;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, Stop};
use lumest::sampling::qmc::Qmc;
use lumest::tally::{sidak_bound, t_factor};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// `runs` runs of `chains` chains with `qmc` on a Sobolev case (8 points):
/// `(E, se)` per run and point, the exact values and the batch count.
/// `(E, se)` \[lx\] per run and point.
type Runs = Vec<Vec<(f64, f64)>>;

fn sobolev_runs(qmc: Qmc, chains: u64, runs: u64) -> (Runs, Vec<f64>, u64) {
    let s = Sobolev::new(0.5, 0.5, 0.7, 0.7, 1.0).unwrap();
    let case = sobolev_case(&s, 8, 3.0);
    let exact: Vec<f64> = case.exact.iter().map(|v| v.e).collect();
    let rec = Receivers::new(&case.scene, &case.points).unwrap();
    let mut out = Vec::new();
    let mut batches = 0;
    for seed in 500..500 + runs {
        let cfg = RunConfig {
            seed,
            stop: Stop {
                chains: Some(chains),
                ..Stop::default()
            },
            qmc,
            ..RunConfig::default()
        };
        let r = run(&case.scene, &rec, &cfg, &mut |_| true);
        batches = r.tallies.batches();
        out.push(
            (0..r.direct.len())
                .map(|j| {
                    let w = &r.tallies.estimated[j];
                    (r.direct[j] + w.mean(), w.std_error())
                })
                .collect(),
        );
    }
    (out, exact, batches)
}

fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Mean `z^2` and coverage with every standard error scaled by `s`:
/// `Ok` when both lie within the bound, `Err` otherwise (with the figures).
fn calibration(runs: &[Vec<(f64, f64)>], exact: &[f64], b: u64, s: f64) -> Result<String, String> {
    let q = t_factor(0.95, b);
    let (mut z2, mut cov) = (Vec::new(), Vec::new());
    for run in runs {
        let z: Vec<f64> = run
            .iter()
            .zip(exact)
            .map(|(&(e, se), &x)| (e - x) / (s * se))
            .collect();
        assert!(z.iter().all(|z| z.is_finite()), "non-finite z: {z:?}");
        z2.push(z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64);
        cov.push(z.iter().filter(|z| z.abs() <= q).count() as f64 / z.len() as f64);
    }
    let k = StudentsT::new(0.0, 1.0, (runs.len() - 1) as f64)
        .unwrap()
        .inverse_cdf(1.0 - 1e-3 / 4.0);
    let ((mz, sz), (mc, sc)) = (mean_se(&z2), mean_se(&cov));
    let ez = (b as f64 - 1.0) / (b as f64 - 3.0);
    let text = format!(
        "se x {s}: mean z^2 {mz:.4} +- {sz:.4} (expected {ez:.4}), coverage {mc:.4} +- {sc:.4}"
    );
    if (mz - ez).abs() <= k * sz && (mc - 0.95).abs() <= k * sc {
        Ok(text)
    } else {
        Err(text)
    }
}

fn check_unbiased_and_calibrated(qmc: Qmc) {
    let (runs, exact, b) = sobolev_runs(qmc, 8192, 160);
    assert!(b >= 32, "{b} batches");
    // Bias: per point, the mean over runs against the exact value.
    let bound = sidak_bound(1e-3, exact.len(), None);
    for (j, &x) in exact.iter().enumerate() {
        let e: Vec<f64> = runs.iter().map(|r| r[j].0).collect();
        let (m, se) = mean_se(&e);
        let z = (m - x) / se;
        assert!(
            z.abs() < bound,
            "{qmc:?} point {j}: mean {m} +- {se} against exact {x}: z = {z:.2} (bound {bound:.2})"
        );
    }
    let ok = calibration(&runs, &exact, b, 1.0);
    let small = calibration(&runs, &exact, b, 0.8);
    eprintln!("{qmc:?}: {}", ok.as_ref().unwrap_or_else(|e| e));
    assert!(
        ok.is_ok(),
        "{qmc:?} error bars miscalibrated: {}",
        ok.unwrap_err()
    );
    assert!(
        small.is_err(),
        "{qmc:?}: bound does not resolve se x 0.8: {}",
        small.unwrap()
    );
}

#[test]
fn owen_nets_are_unbiased_with_honest_error_bars() {
    check_unbiased_and_calibrated(Qmc::Owen);
}

#[test]
fn shifted_nets_are_unbiased_with_honest_error_bars() {
    check_unbiased_and_calibrated(Qmc::Shift);
}

#[test]
fn stratified_batches_beat_independent_chains() {
    // The spread of E over runs at the point under the source (plane 1,
    // r = 0), relative: both nets reduce it against independent chains
    // (measured at 8192 chains, 256-chain batches: shift 0.27, owen 0.39).
    let spread = |qmc| {
        let (runs, _, _) = sobolev_runs(qmc, 8192, 40);
        let e: Vec<f64> = runs.iter().map(|r| r[0].0).collect();
        let (m, se) = mean_se(&e);
        se * (e.len() as f64).sqrt() / m
    };
    let off = spread(Qmc::Off);
    for q in [Qmc::Shift, Qmc::Owen] {
        let s = spread(q);
        eprintln!("{q:?}: relative spread {s:e} against off {off:e}");
        assert!(
            s < 0.7 * off,
            "{q:?}: relative spread {s:e} against off {off:e}"
        );
    }
}

#[test]
fn the_command_line_selects_the_method() {
    let out = |extra: &[&str]| {
        assert_cmd::Command::cargo_bin("lumest")
            .unwrap()
            .args([
                "illuminance",
                "--scene",
                "data/sobolev.toml",
                "--points",
                "data/sobolev_points.csv",
                "--out",
                "-",
                "--chains",
                "2048",
                "--quiet",
            ])
            .args(extra)
            .output()
            .unwrap()
    };
    let csv = |extra: &[&str]| {
        let o = out(extra);
        assert!(
            o.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        o.stdout
    };
    // `--no-stratify` is `--qmc off`, the default is `--qmc owen`, and the
    // three methods give three different runs.
    let csv2 = |extra: &[&str]| csv(&[extra, &["--threads", "2"][..]].concat());
    let (off, shift, owen) = (
        csv2(&["--qmc", "off"]),
        csv2(&["--qmc", "shift"]),
        csv2(&["--qmc", "owen"]),
    );
    assert_eq!(csv2(&["--no-stratify"]), off);
    assert_eq!(csv2(&[]), owen);
    assert!(off != shift && shift != owen && owen != off);
    // Bit for bit whatever the thread count.
    assert_eq!(csv(&["--qmc", "owen", "--threads", "1"]), owen);
    // Both at once, or an unknown method, are refused.
    for bad in [
        &["--no-stratify", "--qmc", "owen"][..],
        &["--qmc", "sobol"][..],
    ] {
        let o = out(bad);
        assert!(!o.status.success(), "{bad:?} was accepted");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("--qmc"),
            "{bad:?}"
        );
    }
}
