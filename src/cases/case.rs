//! A validation case given as a scene, receivers and exact values, and its
//! run with error against run time and a z test.

use super::report::{convergence, report_convergence, z_against_exact};
use crate::estimator::{Receiver, Receivers};
use crate::io::csvio::to_csv;
use crate::io::{format_number, write_atomic};
use crate::run::RunConfig;
use crate::scene::Scene;
use crate::tally::{sidak_bound, zcheck};
use clap::Args;
use std::path::PathBuf;

/// Run controls and report of a validation case.
#[derive(Args, Clone, Debug)]
pub struct CaseArgs {
    /// Wall-clock time of the run (s).
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub time: f64,
    /// Seed.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Worker threads (0: all cores).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub threads: usize,
    /// Folder for the tables (CSV) and plots (SVG).
    #[arg(long, default_value = "validation_report")]
    pub report: PathBuf,
    /// Family-wise false-alarm rate of the z test over all points.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub alpha: f64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// A scene with receivers and their exact values.
#[derive(Clone, Debug)]
pub struct Case {
    /// The scene.
    pub scene: Scene,
    /// Receivers (illuminance points).
    pub receivers: Vec<Receiver>,
    /// Exact illuminance \[lx\] at each receiver.
    pub exact: Vec<f64>,
    /// Receivers (by index) that carry a diagnostics flag by design, with
    /// that flag, the reason given where the case is built: the one flag
    /// such a row is excused for (its z is tested all the same).
    pub expected_flags: Vec<(usize, &'static str)>,
}

/// Run a case with checkpoints; print the table and the z test, write the
/// report. Returns whether max |z| stays within the Sidak bound and no
/// receiver carries a diagnostics flag.
pub fn run_case(name: &str, title: &str, case: &Case, a: &CaseArgs) -> anyhow::Result<bool> {
    anyhow::ensure!(
        a.time > 0.0 && a.time.is_finite(),
        "--time must be positive"
    );
    let receivers = Receivers::from_receivers(&case.scene, &case.receivers)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    eprintln!("lumest: scene: {}", case.scene.summary());
    let cfg = RunConfig::timed(a.seed, a.threads, a.time);
    let n = case.exact.len();
    // Relative errors need non-zero exact values: those come first, and the
    // table covers them; every receiver enters the z test.
    let nz = case.exact.iter().take_while(|&&e| e != 0.0).count();
    anyhow::ensure!(
        case.exact[nz..].iter().all(|&e| e == 0.0),
        "internal: receivers with exact value 0 must come last"
    );
    let zeros = n - nz;
    let range = 0..nz;
    let groups = std::slice::from_ref(&range);
    let (result, tables) = convergence(&case.scene, &receivers, &case.exact, groups, &cfg, a.quiet);
    report_convergence(
        &a.report,
        name,
        &tables[0],
        title,
        &format!("{title}: relative error against run time"),
    )?;
    let headers: Vec<String> = [
        "x", "y", "z", "nx", "ny", "nz", "exact", "estimate", "stderr", "z_score", "flag",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut max_z: f64 = 0.0;
    // A flagged receiver is not a pass, whatever its z, unless the flag is
    // the one its case expects of it (`Case::expected_flags`; a reviewer's
    // find: the gate judged z alone).
    let mut flagged = Vec::new();
    let cells: Vec<Vec<String>> = (0..n)
        .map(|j| {
            let r = &case.receivers[j];
            let w = &result.tallies.estimated[j];
            let e = result.direct[j] + w.mean();
            let z = z_against_exact(e, w.std_error(), result.direct[j], case.exact[j]);
            max_z = zcheck::max_abs(max_z, z);
            let mut row: Vec<String> = [r.p.x, r.p.y, r.p.z, r.n.x, r.n.y, r.n.z]
                .iter()
                .map(|&v| format_number(v))
                .collect();
            row.extend(
                [case.exact[j], e, w.std_error(), z]
                    .iter()
                    .map(|&v| format_number(v)),
            );
            let flag = result.tallies.diagnostics(j, result.direct[j]).flag();
            let expected = case
                .expected_flags
                .iter()
                .find(|&&(k, _)| k == j)
                .map(|&(_, f)| f);
            if flag != "ok" && Some(flag.as_str()) != expected {
                flagged.push(format!("receiver {j}: {flag}"));
            }
            row.push(flag);
            row
        })
        .collect();
    std::fs::create_dir_all(&a.report)?;
    write_atomic(
        &a.report
            .join(format!("{name}_points.csv"))
            .to_string_lossy(),
        &to_csv(&headers, &cells),
    )?;
    let batches = result.tallies.batches();
    let bound = sidak_bound(a.alpha, n, Some(batches));
    let pass = zcheck::within(max_z, bound) && none_flagged(&flagged);
    if zeros > 0 {
        println!("{zeros} receiver(s) with exact value 0 (checked to be estimated as exactly 0)");
    }
    println!(
        "max |z| = {max_z:.3} against the Sidak bound {bound:.3} (alpha {:.4}, {n} receivers, {batches} batches): {}",
        a.alpha,
        if pass { "PASS" } else { "FAIL" }
    );
    Ok(pass)
}

/// Print the receivers flagged against their case's expectation
/// (`"receiver j: flag"` each), if any; whether there are none (a gate's
/// verdict needs that as well as its z test).
pub(crate) fn none_flagged(flagged: &[String]) -> bool {
    if !flagged.is_empty() {
        println!(
            "{} flagged receiver(s), not passed: {}",
            flagged.len(),
            flagged.join("; ")
        );
    }
    flagged.is_empty()
}
