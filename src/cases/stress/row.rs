//! A row of the stress matrix, its reference, and the tables (`stress.csv`,
//! `stress_summary.csv`, the terminal table).

use super::verdict::{ExpectedFlag, Verdict, expected_flag};
use crate::cases::report::Checkpoint;
use crate::io::csvio::to_csv;
use crate::io::format_number;
use crate::run::RunResult;
use crate::tally::{Diagnostics, figure_of_merit, zcheck};

/// One row of the stress matrix: one point of one case.
#[derive(Clone, Debug)]
pub struct StressRow {
    /// Family (`sobolev`, `integrating-sphere`, `near-wall`, `near-source`, `scaled`).
    pub family: String,
    /// Case within the family, e.g. `rho1rho2=0.999 h1=0.001`.
    pub case: String,
    /// The point, e.g. `plane 1 r=100`.
    pub point: String,
    /// Estimated illuminance `E` \[lx\] (exact first order plus the estimate of the rest).
    pub estimate: f64,
    /// Standard error of `estimate` \[lx\].
    pub std_error: f64,
    /// Exact first order (direct illuminance) included in `estimate` \[lx\].
    pub direct: f64,
    /// Exact value \[lx\], when known.
    pub exact: Option<f64>,
    /// What the estimate is compared with: `exact`, `backward` or
    /// `unscaled run / s^2`; empty (like the other reference fields) for a
    /// case that failed before its run gave a number.
    pub reference_kind: String,
    /// The value compared with \[lx\] (the exact value, or the other estimate).
    pub reference: Option<f64>,
    /// Standard error of a Monte Carlo reference \[lx\] (0 for an exact one).
    pub reference_std_error: f64,
    /// `(estimate - reference) / |reference|` \[1\].
    pub rel_err: Option<f64>,
    /// `(estimate - reference) / sqrt(std_error^2 + reference_std_error^2 + allowance^2)`
    /// with the rounding allowance of the module doc \[1\].
    pub z: Option<f64>,
    /// Wall time of the run that produced the estimate \[s\].
    pub time: f64,
    /// Chains of that run.
    pub chains: u64,
    /// Batches of that run (the fewer of the two with a Monte Carlo reference).
    pub batches: u64,
    /// Chains per batch of the run that produced the estimate; 0 for a
    /// case that failed.
    pub batch_chains: u64,
    /// `ok`, or the failed checks of the estimate's tally (and `ref:` those of a Monte Carlo reference).
    pub flag: String,
    /// The statistical checks behind `flag`: the estimate's and a Monte
    /// Carlo reference's tally, if any (`reflag` holds them over the
    /// whole matrix before the rows are judged).
    pub checks: (Option<Diagnostics>, Option<Diagnostics>),
    /// The flag that excuses this row from the z test, if any ([`expected_flag`]).
    pub expected: Option<ExpectedFlag>,
    /// Sidak bound the row's `|z|` is tested against (0 until judged).
    pub bound: f64,
    /// The verdict.
    pub verdict: Verdict,
    /// Explanation: why a row fails or is flagged, errors, remarks.
    pub note: String,
}

/// Every row with its verdict, and the convergence tables of the runs with exact references.
#[derive(Clone, Debug)]
pub struct StressReport {
    /// The rows, judged.
    pub rows: Vec<StressRow>,
    /// `(file stem, title, checkpoints)` of each run against exact values.
    pub convergence: Vec<(String, String, Vec<Checkpoint>)>,
    /// Wall time of the whole matrix \[s\].
    pub wall: f64,
}

/// The reference of a row before it is judged.
#[derive(Clone)]
pub(super) struct Reference {
    pub(super) kind: &'static str,
    pub(super) value: f64,
    /// The exact value as (direct, reflected) \[lx\]: the difference is then
    /// taken part by part, so that a huge direct term (a point next to the
    /// source) does not swamp the reflected one in rounding.
    pub(super) parts: Option<(f64, f64)>,
    pub(super) std_error: f64,
    pub(super) exact: bool,
    pub(super) batches: u64,
    /// The statistical checks of a Monte Carlo reference's tally.
    pub(super) checks: Option<Diagnostics>,
}

/// Build a row from point `j` of run `res` and its reference `r`.
pub(super) fn make_row(
    family: &str,
    case: &str,
    label: &str,
    res: &RunResult,
    j: usize,
    r: Reference,
) -> StressRow {
    let w = &res.tallies.estimated[j];
    let estimate = res.direct[j] + w.mean();
    let se = w.std_error();
    let checks = (Some(res.tallies.diagnostics(j, res.direct[j])), r.checks);
    let flag = joined_flag(checks);
    let diff = match r.parts {
        Some((d, refl)) => (res.direct[j] - d) + (w.mean() - refl),
        None => estimate - r.value,
    };
    let rel_err = if r.value != 0.0 {
        diff / r.value.abs()
    } else if diff == 0.0 {
        0.0
    } else {
        f64::INFINITY
    };
    // Rounding allowance: the direct parts are closed forms of a few
    // operations, each good to eps/2, so two of them differ by at most about
    // 6 eps |d| (next to a source that dwarfs the Monte Carlo error); the
    // Sobolev reflected part is good to about 1e-13 (its module doc).
    let allowance = match r.parts {
        Some((d, refl)) => zcheck::rounding_allowance(res.direct[j], d) + 1e-12 * refl.abs(),
        None => zcheck::rounding_allowance(estimate, r.value),
    };
    let mc = se.hypot(r.std_error);
    let note = if allowance > 0.1 * mc {
        format!(
            "z includes a rounding allowance of {} lx",
            format_number(allowance)
        )
    } else {
        String::new()
    };
    // Zero error with the allowance 0 counts only when exact (`zcheck`).
    let z = zcheck::z_of_difference(diff, mc.hypot(allowance));
    StressRow {
        family: family.into(),
        case: case.into(),
        point: label.into(),
        estimate,
        std_error: se,
        direct: res.direct[j],
        exact: r.exact.then_some(r.value),
        reference_kind: r.kind.to_string(),
        reference: Some(r.value),
        reference_std_error: r.std_error,
        rel_err: Some(rel_err),
        z: Some(z),
        time: res.wall,
        chains: res.chains,
        batches: res.tallies.batches().min(r.batches),
        batch_chains: res.chains / res.tallies.batches().max(1),
        flag,
        checks,
        expected: expected_flag(family, case, label),
        bound: 0.0,
        verdict: Verdict::Pass,
        note,
    }
}

/// A row's flag from its checks: the estimate's failed checks, then a
/// Monte Carlo reference's prefixed `ref:`; `ok` when none fails.
pub(super) fn joined_flag((own, reference): (Option<Diagnostics>, Option<Diagnostics>)) -> String {
    let own = own.map_or_else(|| "ok".to_string(), |d| d.flag());
    match reference.map(|d| d.flag()).filter(|f| f != "ok") {
        Some(rf) if own == "ok" => format!("ref:{rf}"),
        Some(rf) => format!("{own};ref:{rf}"),
        None => own,
    }
}

/// Hold the statistical checks of every row (and of its Monte Carlo
/// reference) over the whole matrix, the family the verdicts judge: a
/// flag can cost a row its excuse or its remedy ([`super::verdict`]), so
/// per-run bounds would raise false alarms in about 0.1 % of the matrix's
/// runs each, per check. Rows without checks (errors) keep their flag.
pub(super) fn reflag(rows: &mut [StressRow]) {
    let family = rows
        .iter()
        .map(|r| usize::from(r.checks.0.is_some()) + usize::from(r.checks.1.is_some()))
        .sum();
    for r in rows.iter_mut() {
        if r.checks.0.is_none() && r.checks.1.is_none() {
            continue;
        }
        let among = |d: Option<Diagnostics>| d.map(|d| d.among(family));
        r.checks = (among(r.checks.0), among(r.checks.1));
        r.flag = joined_flag(r.checks);
    }
}

/// Format an optional number for a table cell (empty when absent).
fn cell(x: Option<f64>) -> String {
    x.map_or(String::new(), format_number)
}

/// The rows as CSV text (the columns of `stress.csv`).
pub fn stress_csv(rows: &[StressRow]) -> Vec<u8> {
    let headers: Vec<String> = [
        "family",
        "case",
        "point",
        "estimate",
        "std_error",
        "direct",
        "exact",
        "reference_kind",
        "reference",
        "reference_std_error",
        "rel_err",
        "z",
        "sidak_bound",
        "time_s",
        "chains",
        "batches",
        "batch_chains",
        "flag",
        "expected_flag",
        "verdict",
        "note",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.family.clone(),
                r.case.clone(),
                r.point.clone(),
                format_number(r.estimate),
                format_number(r.std_error),
                format_number(r.direct),
                cell(r.exact),
                r.reference_kind.clone(),
                cell(r.reference),
                format_number(r.reference_std_error),
                cell(r.rel_err),
                cell(r.z),
                format_number(r.bound),
                format_number(r.time),
                r.chains.to_string(),
                r.batches.to_string(),
                r.batch_chains.to_string(),
                r.flag.clone(),
                r.expected.map_or(String::new(), |e| e.flag.to_string()),
                r.verdict.as_str().to_string(),
                r.note.clone(),
            ]
        })
        .collect();
    to_csv(&headers, &cells)
}

/// Per family: rows, the count of each verdict ([`Verdict::ALL`]: `pass`,
/// `expected-flag`, `flagged`, `explained`, `FAIL`, which add up to the
/// rows), RMS and largest `|rel_err|` against
/// exact values, RMS relative standard error `R`, run time \[s\] (each run once)
/// and `FOM = 1 / (R_rms^2 T)` [1/s].
pub fn summary_csv(rows: &[StressRow]) -> Vec<u8> {
    let mut headers: Vec<String> = vec!["family".into(), "rows".into()];
    headers.extend(Verdict::ALL.iter().map(|v| v.as_str().to_string()));
    headers.extend(
        [
            "rms_rel_err_exact",
            "max_rel_err_exact",
            "rms_rel_stderr",
            "time_s",
            "fom",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    let mut families: Vec<&str> = Vec::new();
    for r in rows {
        if !families.contains(&r.family.as_str()) {
            families.push(&r.family);
        }
    }
    let cells = families
        .iter()
        .map(|f| {
            let fr: Vec<&StressRow> = rows.iter().filter(|r| r.family == *f).collect();
            let count = |v: &Verdict| fr.iter().filter(|r| r.verdict == *v).count().to_string();
            let errs: Vec<f64> = fr
                .iter()
                .filter(|r| r.exact.is_some())
                .filter_map(|r| r.rel_err.map(f64::abs))
                .collect();
            let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
            let rr: Vec<f64> = fr
                .iter()
                .filter(|r| r.batches > 0)
                .map(|r| crate::tally::relative_error(r.estimate, r.std_error))
                .collect();
            let mut cases: Vec<(&str, f64)> =
                fr.iter().map(|r| (r.case.as_str(), r.time)).collect();
            cases.dedup_by(|a, b| a.0 == b.0);
            let time: f64 = cases.iter().map(|c| c.1).sum();
            let r_rms = rms(&rr);
            let mut cells = vec![f.to_string(), fr.len().to_string()];
            cells.extend(Verdict::ALL.iter().map(count));
            cells.extend([
                if errs.is_empty() {
                    String::new()
                } else {
                    format_number(rms(&errs))
                },
                errs.iter()
                    .copied()
                    .reduce(zcheck::max_abs)
                    .map_or(String::new(), format_number),
                format_number(r_rms),
                format_number(time),
                format_number(figure_of_merit(r_rms, time)),
            ]);
            cells
        })
        .collect::<Vec<_>>();
    to_csv(&headers, &cells)
}

/// Print the table of rows.
pub fn print_rows(rows: &[StressRow]) {
    println!(
        "{:<19} {:<24} {:<42} {:>11} {:>9} {:>11} {:>10} {:>8} {:>7} {:>9} {:<14} {:<13}",
        "family",
        "case",
        "point",
        "estimate",
        "stderr",
        "reference",
        "rel_err",
        "z",
        "time_s",
        "chains",
        "flag",
        "verdict"
    );
    let opt = |x: Option<f64>, p: usize| x.map_or("-".to_string(), |v| format!("{v:.p$e}"));
    for r in rows {
        println!(
            "{:<19} {:<24} {:<42} {:>11.4e} {:>9.2e} {:>11} {:>10} {:>8} {:>7.2} {:>9} {:<14} {:<13}",
            r.family,
            r.case,
            r.point,
            r.estimate,
            r.std_error,
            opt(r.reference, 4),
            opt(r.rel_err, 2),
            r.z.map_or("-".to_string(), |z| format!("{z:.2}")),
            r.time,
            r.chains,
            r.flag,
            r.verdict.as_str()
        );
    }
    let notes: Vec<&StressRow> = rows.iter().filter(|r| !r.note.is_empty()).collect();
    if !notes.is_empty() {
        println!("notes:");
        for r in notes {
            println!(
                "  {} / {} / {}: {}: {}",
                r.family,
                r.case,
                r.point,
                r.verdict.as_str(),
                r.note
            );
        }
    }
}
