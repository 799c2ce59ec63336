//! `lumest validate`: Monte Carlo against exact solutions, error against run time.

use super::sobolev::SobolevParams;
use super::{progress_bar, tick};
use crate::estimator::{Receiver, Receivers, ViewTarget, view_target};
use crate::geometry::Plane;
use crate::io::csvio::to_csv;
use crate::io::plot::{Series, loglog_svg};
use crate::io::{format_number, write_atomic};
use crate::light::Light;
use crate::material::Material;
use crate::reference::{Sobolev, SobolevValue};
use crate::run::{MIN_BATCHES, Progress, RunConfig, RunResult, run};
use crate::scene::Scene;
use crate::tally::{figure_of_merit, relative_error, sidak_bound, zcheck};
use anyhow::Context;
use clap::{Args, Subcommand};
use glam::DVec3;
use rayon::prelude::*;
use std::ops::Range;
use std::path::Path;

/// Validation cases.
#[derive(Subcommand, Clone, Debug)]
pub enum ValidateCase {
    /// Two infinite Lambertian planes and a point source, against the exact solution.
    Sobolev(ValidateSobolevArgs),
    /// Integrating sphere with an off-centre point source: uniform indirect illuminance.
    #[command(name = "integrating-sphere")]
    IntegratingSphere(super::cases::SphereArgs),
    /// Point source above a square Lambertian plate, against 2-D quadrature
    /// (checked itself against the closed-form corner form factor).
    Plate(super::cases::PlateArgs),
    /// Flux balance in a closed box room: absorbed flux equals emitted flux, no leaks.
    #[command(name = "box")]
    BoxFlux(super::cases::BoxArgs),
    /// Stress matrix: extreme reflectances, distances, scales; points touching walls and sources.
    Stress(super::stress::StressArgs),
}

/// Run a validation case.
pub fn validate(case: &ValidateCase) -> anyhow::Result<()> {
    match case {
        ValidateCase::Sobolev(a) => validate_sobolev(a),
        ValidateCase::IntegratingSphere(a) => super::cases::validate_sphere(a),
        ValidateCase::Plate(a) => super::cases::validate_plate(a),
        ValidateCase::BoxFlux(a) => super::cases::validate_box(a),
        ValidateCase::Stress(a) => super::stress::validate_stress(a),
    }
}

/// Arguments of `lumest validate sobolev`.
#[derive(Args, Clone, Debug)]
pub struct ValidateSobolevArgs {
    #[command(flatten)]
    pub params: SobolevParams,
    /// Number of points, half on each plane.
    #[arg(long, default_value_t = 100)]
    pub points: usize,
    /// Number of views (luminance), half looking at each plane.
    #[arg(long, default_value_t = 50)]
    pub views: usize,
    /// Largest horizontal distance of the points [m].
    #[arg(long = "r-max", default_value_t = 3.0)]
    pub r_max: f64,
    #[command(flatten)]
    pub case: super::cases::CaseArgs,
}

/// The Sobolev problem as a scene with points on both planes and exact values.
///
/// Plane 1 is `z = 0` (normal +z), the source is at `z = h1`, plane 2 is
/// `z = h1 + h2` (normal -z). Points alternate between the planes with `r`
/// evenly spaced in `[0, r_max]` on each, at azimuths spread by the golden angle.
pub struct SobolevCase {
    pub scene: Scene,
    pub points: Vec<(DVec3, DVec3)>,
    pub plane: Vec<u8>,
    pub r: Vec<f64>,
    pub exact: Vec<SobolevValue>,
}

/// Layout of item `j` of `n` spread over both planes: its plane (1 or 2,
/// alternating), its horizontal distance (evenly spaced in `[0, r_max]` on
/// each plane) and an azimuth spread by the golden angle.
fn layout(j: usize, n: usize, r_max: f64) -> (u8, f64, f64) {
    let per_plane = [n.div_ceil(2), n / 2];
    let pl = (j % 2) as u8 + 1;
    let m = per_plane[(pl - 1) as usize];
    let rk = if m > 1 {
        r_max * (j / 2) as f64 / (m - 1) as f64
    } else {
        0.0
    };
    (
        pl,
        rk,
        std::f64::consts::PI * (3.0 - 5f64.sqrt()) * j as f64,
    )
}

/// Build the Sobolev validation case.
pub fn sobolev_case(s: &Sobolev, n_points: usize, r_max: f64) -> SobolevCase {
    let h = s.h1 + s.h2;
    let scene = Scene::from_parts(
        vec![
            (
                "plane 1".into(),
                Plane::new(DVec3::ZERO, DVec3::Z),
                Material::Lambertian { rho: s.rho1 },
            ),
            (
                "plane 2".into(),
                Plane::new(DVec3::new(0.0, 0.0, h), -DVec3::Z),
                Material::Lambertian { rho: s.rho2 },
            ),
        ],
        vec![Light::Point {
            p: DVec3::new(0.0, 0.0, s.h1),
            i: s.intensity,
        }],
    )
    .expect("a valid programmatic scene");
    let mut points = Vec::with_capacity(n_points);
    let mut plane = Vec::with_capacity(n_points);
    let mut r = Vec::with_capacity(n_points);
    for j in 0..n_points {
        let (pl, rk, phi) = layout(j, n_points, r_max);
        let (z, n) = if pl == 1 {
            (0.0, DVec3::Z)
        } else {
            (h, -DVec3::Z)
        };
        points.push((DVec3::new(rk * phi.cos(), rk * phi.sin(), z), n));
        plane.push(pl);
        r.push(rk);
    }
    let exact = plane
        .par_iter()
        .zip(r.par_iter())
        .map(|(&pl, &rk)| s.illuminance(pl, rk))
        .collect();
    SobolevCase {
        scene,
        points,
        plane,
        r,
        exact,
    }
}

/// Error of a Monte Carlo estimate against exact values at one moment.
#[derive(Clone, Copy, Debug)]
pub struct Checkpoint {
    /// Wall time [s].
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

/// Compare the current estimate with exact totals ([lx] or [cd/m^2]) over
/// the receivers `range`.
pub fn checkpoint(p: &Progress, exact: &[f64], range: Range<usize>) -> Checkpoint {
    let n = range.len() as f64;
    let (mut se2, mut emax, mut r2, mut zmax) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for j in range {
        let ex = exact[j];
        let w = &p.tallies.indirect[j];
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

/// Views of the Sobolev case with exact luminance [cd/m^2].
///
/// View `k` looks from a point of one plane at a sub-point of the other
/// plane at horizontal distance `r'` (evenly spaced in `[0, r_max]`), from a
/// horizontal offset of `0.8 H` so that the views are oblique. For
/// Lambertian planes the exact luminance is `rho_j E_j(r') / pi` on the
/// plane `j` of the sub-point.
pub fn sobolev_views(
    s: &Sobolev,
    scene: &Scene,
    n_views: usize,
    r_max: f64,
) -> (Vec<(DVec3, DVec3)>, Vec<Receiver>, Vec<f64>) {
    let h = s.h1 + s.h2;
    let mut views = Vec::with_capacity(n_views);
    let mut receivers = Vec::with_capacity(n_views);
    let mut exact = Vec::with_capacity(n_views);
    for j in 0..n_views {
        let (target_plane, rk, phi) = layout(j, n_views, r_max);
        let phi = phi + 1.0;
        let (z_t, z_o) = if target_plane == 2 {
            (h, 0.0)
        } else {
            (0.0, h)
        };
        let target = DVec3::new(rk * phi.cos(), rk * phi.sin(), z_t);
        let offset = DVec3::new((phi + 2.0).cos(), (phi + 2.0).sin(), 0.0) * 0.8 * h;
        let o = DVec3::new(target.x, target.y, z_o) + offset;
        let d = (target - o).normalize();
        let ViewTarget::Front(rec) = view_target(scene, o, d) else {
            unreachable!("a view between the planes always meets the front side of the other plane")
        };
        let rho = if target_plane == 1 { s.rho1 } else { s.rho2 };
        views.push((o, d));
        receivers.push(rec);
        exact.push(rho * s.illuminance(target_plane, rk).e / std::f64::consts::PI);
    }
    (views, receivers, exact)
}

/// Points then views of the Sobolev case as receivers, with the exact value
/// of each (E [lx] for points, L [cd/m^2] for views).
pub fn sobolev_receivers(
    s: &Sobolev,
    n_points: usize,
    n_views: usize,
    r_max: f64,
) -> (SobolevCase, Vec<Receiver>, Vec<f64>) {
    let case = sobolev_case(s, n_points, r_max);
    let (_, views, lum) = sobolev_views(s, &case.scene, n_views, r_max);
    let mut all: Vec<Receiver> = case
        .points
        .iter()
        .map(|&(p, n)| Receiver::illuminance(p, n))
        .collect();
    all.extend(views);
    let mut exact: Vec<f64> = case.exact.iter().map(|v| v.e).collect();
    exact.extend(lum);
    (case, all, exact)
}

/// Run `lumest validate sobolev`: illuminance at points and luminance along
/// views in one run. Fails when the final max |z| exceeds the Sidak bound.
pub fn validate_sobolev(a: &ValidateSobolevArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        a.points + a.views >= 1,
        "--points plus --views must be at least 1"
    );
    anyhow::ensure!(
        a.case.time > 0.0 && a.case.time.is_finite(),
        "--time must be positive"
    );
    anyhow::ensure!(
        a.r_max >= 0.0 && a.r_max.is_finite(),
        "--r-max must be >= 0"
    );
    let problem = a.params.problem()?;
    let (case, all, exact) = sobolev_receivers(&problem, a.points, a.views, a.r_max);
    let receivers =
        Receivers::from_receivers(&case.scene, &all).map_err(|e| anyhow::anyhow!("{e}"))?;
    let cfg = RunConfig::timed(a.case.seed, a.case.threads, a.case.time);
    println!(
        "Sobolev: h1={} h2={} rho1={} rho2={} I={} cd; {} points and {} views, r in [0, {}] m, {} s",
        problem.h1,
        problem.h2,
        problem.rho1,
        problem.rho2,
        problem.intensity,
        a.points,
        a.views,
        a.r_max,
        a.case.time
    );
    let np = a.points;
    let groups = [0..np, np..np + a.views];
    let (result, tables) =
        convergence(&case.scene, &receivers, &exact, &groups, &cfg, a.case.quiet);
    let names = [
        ("sobolev", "illuminance E [lx]"),
        ("sobolev_luminance", "luminance L [cd/m^2]"),
    ];
    for ((name, what), (rows, range)) in names.iter().zip(tables.iter().zip(&groups)) {
        if range.is_empty() {
            continue;
        }
        report_convergence(
            &a.case.report,
            name,
            rows,
            what,
            &format!("Sobolev problem: relative error of {what} against run time"),
        )?;
    }
    // Per-receiver comparison.
    let headers: Vec<String> = ["kind", "plane", "r", "exact", "estimate", "stderr", "z"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let cells: Vec<Vec<String>> = (0..exact.len())
        .map(|j| {
            let w = &result.tallies.indirect[j];
            let e = result.direct[j] + w.mean();
            let (kind, plane, r) = if j < np {
                ("E", case.plane[j].to_string(), format_number(case.r[j]))
            } else {
                let p = receivers.receivers()[j].p;
                (
                    "L",
                    if p.z > 0.0 { "2" } else { "1" }.to_string(),
                    format_number(p.x.hypot(p.y)),
                )
            };
            vec![
                kind.to_string(),
                plane,
                r,
                format_number(exact[j]),
                format_number(e),
                format_number(w.std_error()),
                format_number(z_against_exact(
                    e,
                    w.std_error(),
                    result.direct[j],
                    exact[j],
                )),
            ]
        })
        .collect();
    write_atomic(
        &a.case.report.join("sobolev_points.csv").to_string_lossy(),
        &to_csv(&headers, &cells),
    )?;
    let last = result.progress();
    let fin = checkpoint(&last, &exact, 0..exact.len());
    let bound = sidak_bound(a.case.alpha, exact.len(), Some(fin.batches));
    let pass = zcheck::within(fin.max_z, bound);
    println!(
        "max |z| = {:.3} against the Sidak bound {:.3} (alpha {}, {} receivers, {} batches): {}",
        fin.max_z,
        bound,
        a.case.alpha,
        exact.len(),
        fin.batches,
        if pass { "PASS" } else { "FAIL" }
    );
    anyhow::ensure!(
        pass,
        "Monte Carlo disagrees with the exact Sobolev solution"
    );
    Ok(())
}
