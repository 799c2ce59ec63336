//! Calibration of the grid figures' errors (issue 14 item 3): many
//! independent small runs of one grid, against the spread of the runs and
//! against the pooled run.
//!
//! The room is symmetric about its light, so the grid's four corner
//! points tie for the minimum: the minimum of their noisy means is biased
//! low, the case the bootstrap's basic interval is there for.

use lumest::estimator::{Receiver, Receivers};
use lumest::run::{RunConfig, Stop};
use lumest::tally::surface_figures::{SurfaceFigures, surface_figures};
use std::path::Path;

const SCENE: &str = r#"[[surface]]
type = "box"
name = "room"
min = [0, 0, 0]
max = [4, 4, 2.5]
material = { type = "lambertian", reflectance = 0.6 }

[[light]]
type = "point"
position = [2, 2, 2.3]
intensity = 200

[[grid]]
name = "work plane"
surface = "room.z_min"
offset = 0.8
border = 0.5
spacing = 0.6
"#;

/// Runs of the calibration (the environment variable `LUMEST_GRID_RUNS`
/// overrides it for a longer check).
fn runs() -> u64 {
    std::env::var("LUMEST_GRID_RUNS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(400)
}

/// One run's figures and its point means (direct part included) \[lx\].
fn one_run(seed: u64) -> (SurfaceFigures, Vec<f64>) {
    let file = Path::new("calib.toml");
    let scene = lumest::scene::parse(SCENE, file).unwrap();
    let grid = lumest::grid::parse(SCENE, file).unwrap().remove(0);
    let rec: Vec<Receiver> = grid
        .points
        .iter()
        .map(|q| Receiver::illuminance(q.p, q.n))
        .collect();
    let receivers = Receivers::from_receivers(&scene, &rec).unwrap();
    let n = rec.len();
    let cfg = RunConfig {
        seed,
        threads: 0,
        stop: Stop {
            chains: Some(32 * 256),
            ..Stop::default()
        },
        batch_size: Some(256),
        keep_batch_means: n,
        ..RunConfig::default()
    };
    let r = lumest::estimator::local::run(&scene, &receivers, &cfg, &mut |_| true);
    let weights: Vec<f64> = grid.points.iter().map(|q| q.area).collect();
    let idx: Vec<usize> = (0..n).collect();
    let f = surface_figures(&r.tallies.batch_means, &r.direct, &idx, &weights, 1.0, 0);
    let means = (0..n)
        .map(|j| r.direct[j] + r.tallies.estimated[j].mean())
        .collect();
    (f, means)
}

#[test]
fn grid_figure_intervals_cover() {
    let m = runs();
    let results: Vec<(SurfaceFigures, Vec<f64>)> = (1..=m).map(|s| one_run(1000 + s)).collect();
    let n = results[0].1.len();
    assert_eq!(n, 25);
    // The pooled run: all runs' batches together (equal batch counts, so
    // its point means are the mean of the runs' point means).
    let pooled: Vec<f64> = (0..n)
        .map(|j| results.iter().map(|r| r.1[j]).sum::<f64>() / m as f64)
        .collect();
    let avg_ref = pooled.iter().sum::<f64>() / n as f64; // equal cells
    let min_ref = pooled.iter().copied().fold(f64::INFINITY, f64::min);
    let u0_ref = min_ref / avg_ref;
    let covers = |lo: f64, hi: f64, x: f64| lo <= x && x <= hi;
    let mut c_avg = 0;
    let mut c_u0 = 0;
    let mut c_u0_basic = 0;
    let mut width_u0 = 0.0;
    let mut c_min = 0;
    let mut se2 = 0.0;
    let mut se2_u0 = 0.0;
    let avgs: Vec<f64> = results.iter().map(|r| r.0.e_avg.value).collect();
    let u0s: Vec<f64> = results.iter().map(|r| r.0.u0.value).collect();
    for (f, _) in &results {
        c_avg += usize::from(covers(f.e_avg.ci95.0, f.e_avg.ci95.1, avg_ref));
        c_u0 += usize::from(covers(f.u0.ci95.0, f.u0.ci95.1, u0_ref));
        // The bootstrap's basic interval, for comparison.
        c_u0_basic += usize::from(covers(f.u0.basic_ci95.0, f.u0.basic_ci95.1, u0_ref));
        width_u0 += (f.u0.ci95.1 - f.u0.ci95.0) / m as f64;
        c_min += usize::from(covers(f.e_min.ci95.0, f.e_min.ci95.1, min_ref));
        se2 += f.e_avg.std_error.powi(2) / m as f64;
        se2_u0 += f.u0.std_error.powi(2) / m as f64;
    }
    let var = |x: &[f64]| {
        let mu = x.iter().sum::<f64>() / x.len() as f64;
        x.iter().map(|v| (v - mu).powi(2)).sum::<f64>() / (x.len() - 1) as f64
    };
    let ratio = var(&avgs) / se2;
    let ratio_u0 = var(&u0s) / se2_u0;
    let mean_u0 = u0s.iter().sum::<f64>() / m as f64;
    eprintln!(
        "{m} runs: E_avg covered {c_avg}, var(E_avg)/mean se^2 = {ratio:.3}; U0 (ref {u0_ref:.5}, \
         mean of runs {mean_u0:.5}) covered {c_u0} (bootstrap basic interval: {c_u0_basic}), \
         var/se^2 = {ratio_u0:.3}, mean interval width / sd of runs = {:.2}; E_min covered {c_min}",
        width_u0 / var(&u0s).sqrt()
    );
    // Binomial(m, 0.95): 99.9 % of coverage counts lie within 3.3 sd.
    let p = |c: usize| c as f64 / m as f64;
    let sd = (0.95 * 0.05 / m as f64).sqrt();
    assert!(
        (p(c_avg) - 0.95).abs() <= 3.3 * sd,
        "E_avg coverage {c_avg}/{m}"
    );
    // The extremes' t-bound intervals are conservative by construction
    // (at least 95 %; 99.6 % measured over 2000 runs): only too low a
    // coverage fails, and too wide an interval (the measured width is 8.5
    // times the spread of U0 over the runs, against 3.9 for an exact 95 %
    // normal interval).
    // (At 400 runs the bound is 91.4 %: the bootstrap's basic interval,
    // 88.4 % over 2000 runs and 363/400 here, would fail it.)
    assert!(p(c_u0) >= 0.95 - 3.3 * sd, "U0 coverage {c_u0}/{m}");
    assert!(p(c_min) >= 0.95 - 3.3 * sd, "E_min coverage {c_min}/{m}");
    assert!(width_u0 / var(&u0s).sqrt() < 12.0, "U0 interval too wide");
    // var/se^2 of m runs: about 1 +- sqrt(2/(m-1)) (0.07 at m = 400).
    let tol = 3.3 * (2.0 / (m - 1) as f64).sqrt();
    assert!((ratio - 1.0).abs() <= tol, "E_avg variance ratio {ratio}");
    // The bootstrap's standard error of U0 is too large where extremes tie
    // (0.71 measured over 2000 runs: 19 % too large), never too small.
    assert!(
        ratio_u0 <= 1.0 + tol && ratio_u0 > 0.5,
        "U0 variance ratio {ratio_u0}"
    );
}
