//! Calibration of the error bars on the default path, the one the CLI runs
//! (`--near-radius auto`, 16 near paths, stratified batches, default batch
//! size): the Sobolev problem against its exact solution, the furnished box
//! room of `validate box` and the office example (`data/office.toml`) against
//! the pooled mean of the other runs.
//!
//! Statistics, over `R` independent runs (seeds) of `P` points each:
//!
//! * mean `z^2` over points and runs. With normal batch means,
//!   `z = (E - E_exact) / se` follows Student t with `B - 1` degrees of
//!   freedom (`B` batches), so `E[z^2] = (B-1)/(B-3)`; against the pooled mean
//!   of the other `R - 1` runs with both errors,
//!   `z = (E_r - Ebar) / sqrt(se_r^2 + se_pool^2)` has
//!   `E[z^2] = (1 + c) * int_0^inf (1 + 2t/n1)^(-n1/2) (1 + 2tc/n2)^(-n2/2) dt`
//!   with `c = 1/(R-1)`, `n1 = B-1`, `n2 = (R-1)(B-1)` (from
//!   `1/x = int_0^inf exp(-tx) dt` and the chi-square moment generating
//!   function); [`expected_z2`] integrates it.
//! * coverage of the 95 % Student-t interval `E +- t_{0.975,B-1} se` (with
//!   `sqrt(se_r^2 + se_pool^2)` against the pooled mean): exactly 0.95 against
//!   an exact reference; against the pool see [`expected_coverage`].
//!
//! Points of one run are strongly correlated (they share the chains: the
//! whole grid of one office run moves together), so the standard error of each
//! statistic is taken from the spread of its per-run values across runs, and
//! the bound is `expected +- k * se` with `k` the Student t quantile (`R - 1`
//! degrees of freedom) at the two-sided level [`ALPHA`] / 2 per statistic
//! (false-alarm rate <= [`ALPHA`] per case and re-seeding, up to the normal
//! approximation of the per-run means). Each case also checks, on its own
//! data, that the bound rejects the same runs with every standard error
//! scaled by 0.8 (error bars 20 % too small, `E[z^2]` about 1.67) and by 1.2
//! (20 % too large, about 0.74). The run counts put the standard error of
//! mean `z^2` near 0.05 (measured spread of the per-run means: 0.56 Sobolev,
//! 0.68 room, 0.70 office), so that a 20 % scale lies more than 3.3 standard
//! errors beyond the bound and each of these checks misses with probability
//! below about 5e-4: the case's total false-alarm rate is below about 2e-3.
//!
//! Cost: about 43 CPU-s in release (Sobolev 3, room 14, office 26), 48 s wall
//! on two cores shared with other jobs.

use glam::DVec3;
use lumest::cases::box_room::box_room;
use lumest::cases::sobolev::sobolev_case;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, RunResult, Stop};
use lumest::sampling::Philox4x32;
use lumest::scene::Scene;
use lumest::tally::t_factor;
use statrs::distribution::{ChiSquared, Continuous, ContinuousCDF, Normal, StudentsT};
use std::path::Path;

/// Family-wise false-alarm rate of each case (two two-sided bounds).
const ALPHA: f64 = 1e-3;

/// The CLI's default configuration (`lumest illuminance --chains N --seed S`),
/// which is the library's default: the test below checks that they agree.
fn cli_default(chains: u64, seed: u64) -> RunConfig {
    RunConfig {
        seed,
        stop: Stop {
            chains: Some(chains),
            ..Stop::default()
        },
        ..RunConfig::default()
    }
}

#[test]
fn library_default_is_the_command_lines() {
    use clap::Parser;
    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        run: lumest::commands::RunArgs,
    }
    let cli = Cli::parse_from(["lumest", "--chains", "4096", "--seed", "9"])
        .run
        .config()
        .unwrap();
    assert_eq!(format!("{cli:?}"), format!("{:?}", cli_default(4096, 9)));
}

/// Estimates `(E, se)` \[lx\] of every point of one run.
fn estimates(r: &RunResult) -> Vec<(f64, f64)> {
    (0..r.direct.len())
        .map(|j| {
            let w = &r.tallies.estimated[j];
            (r.direct[j] + w.mean(), w.std_error())
        })
        .collect()
}

/// `int_0^1 f(u) du` by composite Simpson with `n` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, n: usize) -> f64 {
    let h = 1.0 / n as f64;
    let mut s = f(0.0) + f(1.0);
    for i in 1..n {
        s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// `E[z^2]` for `B` batches against an exact reference (`pool: None`) or
/// against the pooled mean of `R - 1` other runs with both errors
/// (`pool: Some(R)`), normal batch means (formula in the module docs).
fn expected_z2(batches: u64, pool: Option<usize>) -> f64 {
    let n1 = (batches - 1) as f64;
    let Some(runs) = pool else {
        return n1 / (n1 - 2.0);
    };
    let c = 1.0 / (runs - 1) as f64;
    let n2 = (runs - 1) as f64 * n1;
    // t = u / (1 - u) maps [0, 1) onto [0, inf); the integrand decays as t^(-n1/2).
    let g = |u: f64| {
        if u >= 1.0 {
            return 0.0;
        }
        let t = u / (1.0 - u);
        (1.0 + 2.0 * t / n1).powf(-n1 / 2.0) * (1.0 + 2.0 * t * c / n2).powf(-n2 / 2.0)
            / (1.0 - u).powi(2)
    };
    (1.0 + c) * simpson(g, 20_000)
}

/// Expected coverage of the interval `+- t_{0.975,B-1} sqrt(se_r^2 + se_pool^2)`
/// around the pooled mean of `R - 1` other runs: with `U ~ chi2(B-1)/(B-1)`,
/// `P = E[2 Phi(q sqrt((U + c)/(1 + c))) - 1]`, `c = 1/(R-1)`, the pooled
/// error taken as exact (it has `(R-1)(B-1)` degrees of freedom; its spread
/// changes `P` by `O(c / sqrt((R-1)(B-1)))`, below 1e-4 here). `None`: an
/// exact reference, where the interval covers with probability 0.95 exactly.
fn expected_coverage(batches: u64, pool: Option<usize>) -> f64 {
    let Some(runs) = pool else {
        return 0.95;
    };
    let n1 = (batches - 1) as f64;
    let c = 1.0 / (runs - 1) as f64;
    let q = t_factor(0.95, batches);
    let chi = ChiSquared::new(n1).unwrap();
    let phi = Normal::standard();
    // U = x / n1 with x ~ chi2(n1); x over [0, 8 n1] holds all but ~1e-30 of the mass.
    let top = 8.0 * n1;
    let g = |u: f64| {
        let x = u * top;
        let w = ((x / n1 + c) / (1.0 + c)).sqrt();
        chi.pdf(x) * (2.0 * phi.cdf(q * w) - 1.0) * top
    };
    simpson(g, 20_000)
}

/// Per-run values of `z^2` (mean over points) and of coverage (fraction of
/// points inside the 95 % interval), with every standard error scaled by `s`.
/// `runs[r][j] = (E, se)`; `exact`: the references, or `None` for the
/// pooled mean of the other runs.
fn per_run(
    runs: &[Vec<(f64, f64)>],
    exact: Option<&[f64]>,
    batches: u64,
    s: f64,
) -> (Vec<f64>, Vec<f64>) {
    let q = t_factor(0.95, batches);
    let n_runs = runs.len();
    let mut z2 = Vec::with_capacity(n_runs);
    let mut cov = Vec::with_capacity(n_runs);
    for (r, run) in runs.iter().enumerate() {
        let (mut sum_z2, mut inside) = (0.0, 0usize);
        for (j, &(e, se)) in run.iter().enumerate() {
            let (reference, se_ref) = match exact {
                Some(x) => (x[j], 0.0),
                None => {
                    let others = runs.iter().enumerate().filter(|&(k, _)| k != r);
                    let m = (n_runs - 1) as f64;
                    let (sum, var) = others.fold((0.0, 0.0), |(a, v), (_, o)| {
                        (a + o[j].0, v + o[j].1 * o[j].1)
                    });
                    (sum / m, var.sqrt() / m)
                }
            };
            let z = (e - reference) / (s * (se * se + se_ref * se_ref).sqrt());
            // A non-finite z (zero or NaN error) is a failure, never dropped.
            assert!(z.is_finite(), "run {r} point {j}: z = {z} (E {e}, se {se})");
            sum_z2 += z * z;
            inside += usize::from(z.abs() <= q);
        }
        z2.push(sum_z2 / run.len() as f64);
        cov.push(inside as f64 / run.len() as f64);
    }
    (z2, cov)
}

/// Mean and standard error (from the spread across runs) of per-run values.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// The calibration verdict of one case: `Err` with the reason when mean
/// `z^2` or coverage lies outside `expected +- k se`.
fn verdict(
    name: &str,
    runs: &[Vec<(f64, f64)>],
    exact: Option<&[f64]>,
    batches: u64,
    s: f64,
) -> Result<String, String> {
    let pool = exact.is_none().then_some(runs.len());
    let (z2, cov) = per_run(runs, exact, batches, s);
    let k = StudentsT::new(0.0, 1.0, (runs.len() - 1) as f64)
        .unwrap()
        .inverse_cdf(1.0 - ALPHA / 4.0);
    let (mz, sz) = mean_se(&z2);
    let (mc, sc) = mean_se(&cov);
    let (ez, ec) = (expected_z2(batches, pool), expected_coverage(batches, pool));
    let text = format!(
        "{name} (se x {s}): {} runs x {} points, B = {batches}: mean z^2 = {mz:.4} +- {sz:.4} \
         (expected {ez:.4}, bound +- {:.4}); coverage = {mc:.4} +- {sc:.4} (expected {ec:.4}, \
         bound +- {:.4})",
        runs.len(),
        runs[0].len(),
        k * sz,
        k * sc
    );
    if (mz - ez).abs() <= k * sz && (mc - ec).abs() <= k * sc {
        Ok(text)
    } else {
        Err(text)
    }
}

/// Check a case: calibrated as run, and the bound rejects error bars 20 %
/// too small or too large on the same data (all three lines are printed).
fn check(name: &str, runs: &[Vec<(f64, f64)>], exact: Option<&[f64]>, batches: u64) {
    let [ok, small, large] = [1.0, 0.8, 1.2].map(|s| verdict(name, runs, exact, batches, s));
    for v in [&ok, &small, &large] {
        eprintln!("{}", v.as_ref().unwrap_or_else(|e| e));
    }
    assert!(ok.is_ok(), "error bars miscalibrated: {}", ok.unwrap_err());
    for (s, bad) in [(0.8, small), (1.2, large)] {
        assert!(
            bad.is_err(),
            "the calibration bound does not resolve error bars scaled by {s}: {}",
            bad.unwrap()
        );
    }
}

/// `runs` runs of `chains` chains (seeds `seed0..`) on the default path.
fn runs_of(
    scene: &Scene,
    points: &[(DVec3, DVec3)],
    chains: u64,
    runs: u64,
    seed0: u64,
) -> (Vec<Vec<(f64, f64)>>, u64) {
    let rec = Receivers::new(scene, points).unwrap();
    let mut out = Vec::new();
    let mut batches = None;
    for seed in seed0..seed0 + runs {
        let r = run(scene, &rec, &cli_default(chains, seed), &mut |_| true);
        // The runner's own rule: at least 32 batches of at least 256 chains.
        assert!(r.tallies.batches() >= 32 && r.batch_size >= 256);
        assert_eq!(
            *batches.get_or_insert(r.tallies.batches()),
            r.tallies.batches()
        );
        out.push(estimates(&r));
    }
    (out, batches.unwrap())
}

#[test]
fn expected_values_are_student_t() {
    // Against an exact reference the integral reduces to (B-1)/(B-3); a
    // large pool approaches it, and B = 32 gives 31/29.
    assert!((expected_z2(32, None) - 31.0 / 29.0).abs() < 1e-15);
    let big = expected_z2(32, Some(1_000_000));
    assert!((big - 31.0 / 29.0).abs() < 1e-5, "{big}");
    // The pooled case against a brute-force simulation: R = 8 runs of B = 32
    // normal batch means, z of run 0 against the other seven.
    let (runs, b, trials) = (8usize, 32usize, 20_000usize);
    let mut rng = Philox4x32::new(99, 0);
    let mut normal = || {
        let [u, v] = rng.next_2d();
        (-2.0 * (1.0 - u).ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    let mut z2 = Vec::with_capacity(trials);
    let mut inside = 0usize;
    for _ in 0..trials {
        let sim: Vec<Vec<(f64, f64)>> = (0..runs)
            .map(|_| {
                let x: Vec<f64> = (0..b).map(|_| normal()).collect();
                let (m, se) = mean_se(&x);
                vec![(m, se)]
            })
            .collect();
        let (z, c) = per_run(&sim[..], None, b as u64, 1.0);
        z2.push(z[0]);
        inside += usize::from(c[0] == 1.0);
    }
    let (m, se) = mean_se(&z2);
    let e = expected_z2(b as u64, Some(runs));
    assert!(
        (m - e).abs() < 4.0 * se,
        "simulated {m} +- {se}, integral {e}"
    );
    let p = inside as f64 / trials as f64;
    let ec = expected_coverage(b as u64, Some(runs));
    let sp = (p * (1.0 - p) / trials as f64).sqrt();
    assert!(
        (p - ec).abs() < 4.0 * sp,
        "simulated coverage {p} +- {sp}, integral {ec}"
    );
    let cov = expected_coverage(32, Some(1_000_000));
    assert!((cov - 0.95).abs() < 1e-4, "{cov}");
}

#[test]
fn sobolev_error_bars_are_calibrated() {
    let s = Sobolev::new(0.5, 0.5, 0.7, 0.7, 1.0).unwrap();
    let case = sobolev_case(&s, 8, 3.0);
    let exact: Vec<f64> = case.exact.iter().map(|v| v.e).collect();
    let (runs, b) = runs_of(&case.scene, &case.points, 8192, 200, 7000);
    check("Sobolev", &runs, Some(&exact), b);
}

#[test]
fn box_room_error_bars_are_calibrated() {
    // `validate box`'s furnished room; points on the work plane, and where
    // `auto` splits off a near part: 5 cm above the desk facing it, 5 cm from
    // the glossy partition, 2 cm from a wall facing it, 1 cm from a ceiling
    // corner, 2 cm from a wall with the wall at grazing incidence.
    let scene = box_room(0.8);
    let up = DVec3::Z;
    let points = vec![
        (DVec3::new(0.5, 0.5, 0.8), up),
        (DVec3::new(2.0, 1.4, 0.8), -up),
        (DVec3::new(3.0, 3.0, 0.8), up),
        (DVec3::new(4.5, 1.0, 0.8), up),
        (DVec3::new(3.45, 1.0, 0.8), up),
        (DVec3::new(0.02, 2.0, 1.5), -DVec3::X),
        (
            DVec3::new(4.99, 3.99, 2.99),
            DVec3::new(-1.0, -1.0, -1.0).normalize(),
        ),
        (DVec3::new(2.0, 0.02, 0.8), up),
    ];
    // The default path really splits the points close to a surface.
    let split = Receivers::new(&scene, &points)
        .unwrap()
        .with_auto_near_field(&scene, 16);
    let radii = split.near_field().1;
    let split: Vec<bool> = radii.iter().map(|&r| r > 0.0).collect();
    assert_eq!(
        split,
        [false, true, false, false, true, true, true, true],
        "{radii:?}"
    );
    let (runs, b) = runs_of(&scene, &points, 8192, 200, 8000);
    check("box room", &runs, None, b);
}

#[test]
fn office_error_bars_are_calibrated() {
    // The office example and every fourth point of its work-plane grid (17
    // points: desk tops and edges, the partition, the column 0.5 m from the
    // glossy whiteboard).
    // The office as it was with six point lights (tests/data/office_points.toml).
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let scene = lumest::scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/office_points.toml"),
    )
    .unwrap();
    let grid = lumest::io::read_points(dir.join("office_grid.csv").to_str().unwrap()).unwrap();
    let points: Vec<_> = grid.points.iter().copied().step_by(4).collect();
    let (runs, b) = runs_of(&scene, &points, 8192, 192, 9000);
    check("office", &runs, None, b);
}
