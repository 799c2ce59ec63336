//! Error against run time of a validation run: checkpoints against exact
//! values, their tables (CSV, terminal) and log-log plots (SVG).

use crate::commands::{progress_bar, tick};
use crate::estimator::Receivers;
use crate::estimator::local::run;
use crate::io::csvio::to_csv;
use crate::io::plot::{Series, loglog_svg};
use crate::io::{format_number, write_atomic};
use crate::run::{MIN_BATCHES, Progress, RunConfig, RunResult};
use crate::scene::Scene;
use crate::tally::{figure_of_merit, relative_error, zcheck};
use anyhow::Context;
use std::ops::Range;
use std::path::Path;

/// Error of a Monte Carlo estimate against exact values at one moment.
#[derive(Clone, Copy, Debug)]
pub struct Checkpoint {
    /// Wall time \[s\].
    pub time: f64,
    /// Chains folded in.
    pub chains: u64,
    /// Batches folded in.
    pub batches: u64,
    /// RMS over points of |E_mc - E_exact| / E_exact.
    pub rms_err: f64,
    /// Largest such relative error (NaN if any is NaN).
    pub max_err: f64,
    /// RMS over points of the estimated relative standard error R.
    pub rms_r: f64,
    /// Largest |z| = |E_mc - E_exact| / stderr over the receivers
    /// ([`z_against_exact`]): a receiver with zero standard error counts
    /// as 0 only when its value is exact to rounding (otherwise `inf`), and
    /// a NaN z makes this NaN; so no receiver that never scored where light
    /// falls, or scored NaN, passes.
    pub max_z: f64,
    /// 1 / (rms_r^2 T) [1/s].
    pub fom: f64,
}

/// z score of an estimate `e` with standard error `se`, whose exact first
/// order `direct` is included, against the exact total `exact` (same
/// unit), by the rules of [`zcheck`]: every receiver counts, a NaN stays
/// NaN, and a zero error counts only when `e` is exact up to the rounding
/// allowance of the two closed forms of the direct part
/// ([`zcheck::rounding_allowance`], in quadrature with `se`).
pub fn z_against_exact(e: f64, se: f64, direct: f64, exact: f64) -> f64 {
    let allowance = zcheck::rounding_allowance(direct, exact);
    zcheck::z_score(e, se.hypot(allowance), exact)
}

/// Compare the current estimate with exact totals (\[lx\] or [cd/m^2]) over
/// the receivers `range`.
pub fn checkpoint(p: &Progress, exact: &[f64], range: Range<usize>) -> Checkpoint {
    let n = range.len() as f64;
    let (mut se2, mut emax, mut r2, mut zmax) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for j in range {
        let ex = exact[j];
        let w = &p.tallies.estimated[j];
        let e = p.direct[j] + w.mean();
        let err = (e - ex).abs() / ex;
        se2 += err * err;
        emax = zcheck::max_abs(emax, err);
        r2 += relative_error(e, w.std_error()).powi(2);
        zmax = zcheck::max_abs(zmax, z_against_exact(e, w.std_error(), p.direct[j], ex));
    }
    let rms_r = (r2 / n).sqrt();
    Checkpoint {
        time: p.elapsed,
        chains: p.chains,
        batches: p.tallies.batches(),
        rms_err: (se2 / n).sqrt(),
        max_err: emax,
        rms_r,
        max_z: zmax,
        fom: figure_of_merit(rms_r, p.elapsed),
    }
}

/// Run a case with checkpoints at geometrically spaced times up to
/// `cfg.stop.time`; one table of checkpoints per group of receivers.
pub fn convergence(
    scene: &Scene,
    receivers: &Receivers,
    exact: &[f64],
    groups: &[Range<usize>],
    cfg: &RunConfig,
    quiet: bool,
) -> (RunResult, Vec<Vec<Checkpoint>>) {
    let t_end = cfg.stop.time.unwrap_or(10.0);
    let mut marks: Vec<f64> = (0..12)
        .rev()
        .map(|k| t_end / 2f64.powi(k))
        .filter(|&t| t >= 0.05 && t < 0.99 * t_end)
        .collect();
    marks.reverse(); // pop() yields the earliest
    let mut rows = vec![Vec::new(); groups.len()];
    let pb = progress_bar(cfg, quiet);
    let result = run(scene, receivers, cfg, &mut |p| {
        tick(&pb, cfg, p);
        if p.tallies.batches() >= MIN_BATCHES && marks.last().is_some_and(|&t| p.elapsed >= t) {
            while marks.last().is_some_and(|&t| p.elapsed >= t) {
                marks.pop();
            }
            for (g, range) in groups.iter().enumerate() {
                rows[g].push(checkpoint(p, exact, range.clone()));
            }
        }
        true
    });
    pb.finish_and_clear();
    let last = result.progress();
    for (g, range) in groups.iter().enumerate() {
        let fin = checkpoint(&last, exact, range.clone());
        if rows[g]
            .last()
            .is_none_or(|r: &Checkpoint| r.chains != fin.chains)
        {
            rows[g].push(fin);
        }
    }
    (result, rows)
}

/// Least-squares slope of log(y) against log(x).
pub fn loglog_slope(pts: &[(f64, f64)]) -> f64 {
    let v: Vec<(f64, f64)> = pts
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = v.len() as f64;
    let mx = v.iter().map(|p| p.0).sum::<f64>() / n;
    let my = v.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = v.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = v.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// Table of checkpoints as CSV text.
pub fn checkpoint_csv(rows: &[Checkpoint]) -> Vec<u8> {
    let headers: Vec<String> = [
        "time_s",
        "chains",
        "batches",
        "rms_rel_err",
        "max_rel_err",
        "rms_rel_stderr",
        "max_abs_z",
        "fom",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                format_number(r.time),
                r.chains.to_string(),
                r.batches.to_string(),
                format_number(r.rms_err),
                format_number(r.max_err),
                format_number(r.rms_r),
                format_number(r.max_z),
                format_number(r.fom),
            ]
        })
        .collect();
    to_csv(&headers, &cells)
}

pub(crate) fn write_report(
    dir: &Path,
    name: &str,
    rows: &[Checkpoint],
    title: &str,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let csv_path = dir.join(format!("{name}_convergence.csv"));
    write_atomic(&csv_path.to_string_lossy(), &checkpoint_csv(rows))?;
    let err: Vec<(f64, f64)> = rows.iter().map(|r| (r.time, r.rms_err)).collect();
    let est: Vec<(f64, f64)> = rows.iter().map(|r| (r.time, r.rms_r)).collect();
    let last = rows.last().expect("at least one checkpoint");
    let c = last.rms_r * last.time.sqrt();
    let ideal: Vec<(f64, f64)> = rows.iter().map(|r| (r.time, c / r.time.sqrt())).collect();
    let svg = loglog_svg(
        title,
        "wall time T [s]",
        "relative error",
        &[
            Series {
                name: "RMS |X - X_exact| / X_exact".into(),
                points: err,
                dashed: false,
            },
            Series {
                name: "RMS estimated std error R".into(),
                points: est,
                dashed: false,
            },
            Series {
                name: "c / sqrt(T)".into(),
                points: ideal,
                dashed: true,
            },
        ],
    )
    .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    let svg_path = dir.join(format!("{name}_convergence.svg"));
    write_atomic(&svg_path.to_string_lossy(), svg.as_bytes())?;
    eprintln!(
        "lumest: wrote {} and {}",
        csv_path.display(),
        svg_path.display()
    );
    Ok(())
}

/// Print a checkpoint table under `heading` with the log-log slopes of the
/// estimated and actual errors against time, and write it with its plot
/// to `dir` (see [`write_report`]).
pub(crate) fn report_convergence(
    dir: &Path,
    name: &str,
    rows: &[Checkpoint],
    heading: &str,
    plot_title: &str,
) -> anyhow::Result<()> {
    println!("{heading}:");
    print_table(rows);
    let slope = loglog_slope(&rows.iter().map(|r| (r.time, r.rms_r)).collect::<Vec<_>>());
    let slope_err = loglog_slope(&rows.iter().map(|r| (r.time, r.rms_err)).collect::<Vec<_>>());
    println!(
        "log-log slope vs time: estimated R {slope:.3}, actual error {slope_err:.3} (ideal -0.5)"
    );
    write_report(dir, name, rows, plot_title)
}

/// Print a checkpoint table.
pub fn print_table(rows: &[Checkpoint]) {
    println!(
        "{:>9} {:>12} {:>7} {:>12} {:>12} {:>12} {:>8} {:>11}",
        "time_s", "chains", "batches", "rms_rel_err", "max_rel_err", "rms_R", "max|z|", "FOM"
    );
    for r in rows {
        println!(
            "{:>9.3} {:>12} {:>7} {:>12.3e} {:>12.3e} {:>12.3e} {:>8.2} {:>11.3e}",
            r.time, r.chains, r.batches, r.rms_err, r.max_err, r.rms_r, r.max_z, r.fom
        );
    }
}
