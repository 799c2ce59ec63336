//! `lumest illuminance` and `lumest luminance`: illuminance at CSV points and
//! luminance along CSV views, from one pass of chains.
//!
//! Mixing: `illuminance --points P --out R --views V --views-out W` (or
//! `luminance --views V --out W --points P --points-out R`) scores both lists
//! with the same chains.

use super::outputs::check_outputs;
use super::{MAX_VIEWS, RunArgs, check_tally_size, progress_bar, tick};
use crate::estimator::local::run;
use crate::estimator::{Receiver, Receivers, Solid, ViewTarget, emitted_luminance, view_target};
use crate::io::InputError;
use crate::io::csvio::{Staged, stage_csv};
use crate::io::{PointTable, ViewTable, format_fixed, format_number, read_points, read_views};
use crate::run::{RunConfig, RunResult};
use crate::scene::{self, Scene};
use crate::tally::{figure_of_merit, relative_error, t_factor};
use anyhow::Context;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};

/// Which estimator computes the reflected light.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum EstimatorKind {
    /// Light-tracing chains with the local and double local estimates.
    #[default]
    Local,
    /// Backward path tracing from each point with next-event estimation.
    Backward,
}

/// The part of the luminance a fan's polar plot shows.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotPart {
    /// Everything: emitted, first order and reflected.
    Total,
    /// Light reflected at least twice (the double local estimate's part).
    Indirect,
}

/// Arguments of `lumest illuminance`.
#[derive(Args, Clone, Debug)]
pub struct IlluminanceArgs {
    /// Scene file (TOML).
    #[arg(long)]
    pub scene: PathBuf,
    /// Points CSV with at least x,y,z,nx,ny,nz (`-`: standard input).
    #[arg(long)]
    pub points: String,
    /// Output CSV (`-`: standard output).
    #[arg(long)]
    pub out: String,
    /// Also compute luminance along these views (CSV x,y,z,dx,dy,dz) in the same run.
    #[arg(long, requires = "views_out")]
    pub views: Option<String>,
    /// Output CSV for `--views`.
    #[arg(long = "views-out", requires = "views")]
    pub views_out: Option<String>,
    /// Estimator of the reflected light.
    #[arg(long, value_enum, default_value_t = EstimatorKind::Local)]
    pub estimator: EstimatorKind,
    /// Run shard `I/M` of a `--chains` run (batches I, I+M, I+2M, ...) and
    /// write its state to `--out` for `lumest merge` (shards 0 to M-1 merge
    /// into the single run's CSV, byte for byte).
    #[arg(long, conflicts_with_all = ["views", "time", "mpi", "daylight_factor"])]
    pub shard: Option<String>,
    /// Run over the MPI ranks this process was started with (`mpirun -np R
    /// lumest illuminance ... --mpi`): rank r traces the batches of shard
    /// r/R, rank 0 folds them in batch order and writes `--out`, the same
    /// bytes as one process. Needs a binary built with `--features mpi`.
    #[arg(long, conflicts_with_all = ["views", "time", "daylight_factor"])]
    pub mpi: bool,
    /// Write the grid figures (points grouped by the `grid` column, see
    /// `lumest grid`) with their errors and verdicts to this CSV.
    #[arg(long = "figures-out", conflicts_with_all = ["shard", "mpi"])]
    pub figures_out: Option<String>,
    /// Write a self-contained HTML report of the run (scene, luminaires,
    /// grid figures with intervals and verdicts, isolux plots, run
    /// statistics and flags) to this file.
    #[arg(long, conflicts_with_all = ["shard", "mpi"])]
    pub report: Option<String>,
    /// Write the isolux plot of every grid, `isolux_K_NAME.png` and `.svg`,
    /// into this (existing) folder.
    #[arg(long = "isolux-dir", conflicts_with_all = ["shard", "mpi"])]
    pub isolux_dir: Option<String>,
    /// Plan the run for a grid figure's precision: `GRID:FIGURE:H` (FIGURE
    /// one of E_avg, E_min, E_max, U0, Ud) asks that its 95 % interval be
    /// at most +-H wide (lx, or 1 for U0 and Ud), by the two-stage pilot
    /// rule of --rel-error; repeatable (all targets at once). Needs points
    /// with a `grid` column.
    #[arg(long = "figure-target", conflicts_with_all = ["shard", "mpi"])]
    pub figure_target: Vec<String>,
    #[command(flatten)]
    pub run: RunArgs,
}

/// Arguments of `lumest luminance`.
#[derive(Args, Clone, Debug)]
pub struct LuminanceArgs {
    /// Scene file (TOML).
    #[arg(long)]
    pub scene: PathBuf,
    /// Views CSV with at least x,y,z (observer) and dx,dy,dz (looking direction).
    #[arg(long, required_unless_present = "fan_at", conflicts_with = "fan_at")]
    pub views: Option<String>,
    /// Generate views over the hemisphere at one point instead: `x,y,z,nx,ny,nz`.
    #[arg(long = "fan-at", requires = "fan", allow_hyphen_values = true)]
    pub fan_at: Option<String>,
    /// Angular steps of the fan in degrees: `THETA_STEP,PHI_STEP` (theta from
    /// the normal, at the centres of the steps; phi from the local x axis).
    #[arg(long, requires = "fan_at")]
    pub fan: Option<String>,
    /// With `--fan`: also draw a polar plot of L(theta, phi) to this PNG file.
    #[arg(long, requires = "fan")]
    pub plot: Option<String>,
    /// What the polar plot shows: `total` L, or `indirect` (light reflected at
    /// least twice, as in the seed paper's Figure 6).
    #[arg(long = "plot-part", value_enum, default_value_t = PlotPart::Total, requires = "plot")]
    pub plot_part: PlotPart,
    /// Output CSV (`-`: standard output).
    #[arg(long)]
    pub out: String,
    /// Also compute illuminance at these points in the same run.
    #[arg(long, requires = "points_out")]
    pub points: Option<String>,
    /// Output CSV for `--points`.
    #[arg(long = "points-out", requires = "points")]
    pub points_out: Option<String>,
    /// Estimator of the reflected light.
    #[arg(long, value_enum, default_value_t = EstimatorKind::Local)]
    pub estimator: EstimatorKind,
    #[command(flatten)]
    pub run: RunArgs,
}

/// Result columns for quantity `q` (`E` \[lx\] or `L` [cd/m^2]).
///
/// Orders: for illuminance `E_order{k}` is light reflected `k` times
/// (`E_direct` is order 0); for luminance `L_direct` is light reflected once
/// (at the sub-point) and `L_order{k}` light reflected `k` times, `k >= 2`.
/// `_rest` holds all higher orders.
pub fn result_headers(q: &str, orders: u32) -> Vec<String> {
    let mut h: Vec<String> = ["", "_stderr", "_direct", "_indirect", "_rel_err", "_ci95"]
        .iter()
        .map(|s| format!("{q}{s}"))
        .collect();
    let shift = u32::from(q == "L");
    for k in 1..=orders {
        h.push(format!("{q}_order{}", k + shift));
        h.push(format!("{q}_order{}_stderr", k + shift));
    }
    if orders > 0 {
        h.push(format!("{q}_rest"));
        h.push(format!("{q}_rest_stderr"));
    }
    h.extend(
        ["_vov", "_fom_ratio", "_flag"]
            .iter()
            .map(|s| format!("{q}{s}")),
    );
    h
}

/// Result cells of receiver `j`.
pub fn result_cells(r: &RunResult, j: usize) -> Vec<String> {
    result_cells_plus(r, j, 0.0)
}

/// Result cells of receiver `j`, with an exact term `extra` (emitted
/// luminance seen straight on) added to the total and to the direct part.
pub fn result_cells_plus(r: &RunResult, j: usize, extra: f64) -> Vec<String> {
    let w = &r.tallies.estimated[j];
    // The exact part, and the direct light of sampled sources (which the
    // estimated part holds) shown with the direct column.
    let direct = r.direct[j] + extra;
    let sampled = r.tallies.sampled_direct_mean(j);
    let e = direct + w.mean();
    let se = w.std_error();
    let ci = if se > 0.0 {
        t_factor(0.95, w.count()) * se
    } else {
        0.0
    };
    let mut c = vec![
        format_number(e),
        format_number(se),
        format_number(direct + sampled),
        format_number(w.mean() - sampled),
        format_number(relative_error(e, se)),
        format_number(ci),
    ];
    for bucket in &r.tallies.orders {
        c.push(format_number(bucket[j].mean()));
        c.push(format_number(bucket[j].std_error()));
    }
    let d = r.tallies.diagnostics(j, direct);
    c.push(format_number(d.vov));
    c.push(d.fom_ratio.map_or(String::new(), format_number));
    c.push(d.flag());
    c
}

/// The daylight-factor columns (`--daylight-factor`), in percent.
pub const DAYLIGHT_COLUMNS: [&str; 4] = ["DF", "DF_stderr", "DF_sky", "DF_sky_stderr"];

/// Daylight factor cells of receiver `j` for the unobstructed horizontal
/// illuminance `e_h` \[lx\] (exact): `100 E / e_h` and the sky component
/// `100 E_direct / e_h` (the direct light: exact plus sampled), with their
/// standard errors (those of `E` and of the sampled direct light, scaled).
fn daylight_cells(r: &RunResult, j: usize, e_h: f64) -> Vec<String> {
    let w = &r.tallies.estimated[j];
    let k = 100.0 / e_h;
    let sampled = r.tallies.sampled_direct.get(j);
    let direct = r.direct[j] + sampled.map_or(0.0, |s| s.mean());
    vec![
        format_number(k * (r.direct[j] + w.mean())),
        format_number(k * w.std_error()),
        format_number(k * direct),
        format_number(k * sampled.map_or(0.0, |s| s.std_error())),
    ]
}

/// The illuminance \[lx\] the scene's daylight (sky, sun, environment and
/// other distant lights) gives on an unobstructed horizontal plane facing
/// up, exactly; `None` when the scene has none.
pub fn daylight_reference(scene: &Scene) -> Option<f64> {
    use crate::light::Light;
    let parts: Vec<f64> = scene
        .lights
        .iter()
        .filter_map(|l| match l {
            Light::Environment(env) => Some(env.horizontal_illuminance()),
            Light::Distant(_) => Some(l.direct_illuminance(glam::DVec3::ZERO, glam::DVec3::Z)),
            _ => None,
        })
        .collect();
    (!parts.is_empty()).then(|| parts.iter().sum())
}

/// Cells of an exact result `l` with no reflected light (a view that sees
/// nothing or a black back side, possibly through an emitting sphere).
fn exact_cells(l: f64, orders: u32) -> Vec<String> {
    let n = 6 + if orders > 0 {
        2 * orders as usize + 2
    } else {
        0
    };
    let mut c = vec!["0".to_string(); n];
    c[0] = format_number(l);
    c[2] = format_number(l);
    c.extend(["0".to_string(), String::new(), "ok".to_string()]);
    c
}

/// How many batches a `--rel-error` plan holds, in words (`what`: which
/// batches, e.g. "fresh batches were planned"): none could be made where
/// the measured error `r` was not finite.
fn planned_text(planned: u64, r: f64, what: &str) -> String {
    if !r.is_finite() {
        format!(
            "no plan could be made (the error is not finite: a receiver's estimate is not a number), \
             and the least {} batches ran",
            crate::run::MIN_BATCHES
        )
    } else {
        format!("{} {what}", format_number(planned as f64))
    }
}

/// The run summary printed to standard error.
pub fn summary(r: &RunResult) -> String {
    summary_seen(r, false)
}

/// [`summary`], where `sees_lights` tells that some view sees a light
/// source itself (its emitted luminance is added outside the run), so that
/// a run whose receivers get no light is not reported as lighting nothing.
pub fn summary_seen(r: &RunResult, sees_lights: bool) -> String {
    let rms = r.tallies.rms_rel_error(&r.direct);
    let max = r.tallies.max_rel_error(&r.direct);
    let mut counts = std::collections::BTreeMap::new();
    for j in 0..r.direct.len() {
        let flag = r.tallies.diagnostics(j, r.direct[j]).flag();
        if flag != "ok" {
            for f in flag.split(';') {
                *counts.entry(f.to_string()).or_insert(0usize) += 1;
            }
        }
    }
    let flags = if counts.is_empty() {
        "statistical checks: all receivers pass (R <= 0.1; VOV, FOM stability where 64 or more batches allow it, and heavy tail within their bounds at 0.1 % false alarms per run; not sparse)"
            .to_string()
    } else {
        let list: Vec<String> = counts.iter().map(|(k, v)| format!("{k}: {v}")).collect();
        let mut sparse = String::new();
        if counts.contains_key("sparse") {
            sparse += "; `sparse`: almost none of the run's samples reach the region that \
             carries those points' light (local estimate: collisions near the point; backward \
             estimator: path vertices near a light), so their estimate misses most of it \
             whatever the error bar says (local estimate far from the sources: use \
             --near-radius auto, the default; scenes with glass panes run without the near/far \
             split, and the backward estimator does not take them yet)";
        }
        if counts.contains_key("enclosed") {
            sparse += "; `enclosed`: those points see the back of a surface in most directions \
             (inside a solid, behind a wall, outside a closed room), lie inside a closed mesh \
             that holds no light or face the black side of the surface they lie on: check their \
             position and normal; they are left out of the grid figures";
        }
        if counts.contains_key("approx") {
            sparse += "; `approx`: the scene's lights approximate what it describes (median \
             cut: an environment map replaced by distant lights), with a bias no error bar \
             holds (README: median cut; unobstructed, 0.02-12 % at 16-256 lights, and much \
             more where an obstacle cuts a bright feature): use `sampling = \"importance\"` \
             for an estimate with an honest error bar";
        }
        if counts.contains_key("near") {
            sparse += "; `near`: a surface lies closer to those points than a tenth of their \
             distance to the nearest light (in a scene lit from infinity alone, of the scale \
             of the chains' start density there, or in a room of the median distance of the \
             surfaces around them) while the near/far split is off there, so \
             the plain local estimate can miss a large part of E with a small error bar (use \
             --near-radius auto, the default; scenes with glass panes run without the split, \
             and the backward estimator does not take them yet)";
        }
        format!(
            "statistical checks FAILED or points flagged ({}); see the _flag column{sparse}",
            list.join(", ")
        )
    };
    let text = format!(
        "{} receivers, {} chains in {} batches of {}, {:.3} s{}, stopped by {:?}\n\
         {} chains/s, {} scores/s, {:.3} collisions/chain\n\
         relative standard error: RMS {:.3e}, max {:.3e}; FOM = 1/(R_rms^2 T) = {}",
        r.direct.len(),
        r.chains,
        r.tallies.batches(),
        if r.pilot.as_ref().is_some_and(|p| p.cut) {
            format!("up to {}", r.batch_size)
        } else {
            r.batch_size.to_string()
        },
        r.wall,
        // (0 where no thread traced this process's chains: a merge of
        // shards, whose wall times are summed, or a run no light reaches.)
        if r.threads > 0 {
            format!(" on {} thread(s)", r.threads)
        } else {
            String::new()
        },
        r.reason,
        per_second(r.chains as f64, r.wall),
        per_second(r.scores as f64, r.wall),
        r.collisions as f64 / r.chains.max(1) as f64,
        rms,
        max,
        if rms > 0.0 && r.wall > 0.0 {
            format!("{:.4e} 1/s", figure_of_merit(rms, r.wall))
        } else if r.direct.is_empty() {
            // Views that all leave the scene (they see only lights at
            // infinity, computed exactly) or meet back sides.
            "undefined (no receivers: every view leaves the scene or meets a back side)".to_string()
        } else if !sees_lights
            && (0..r.direct.len()).all(|j| r.direct[j] + r.tallies.estimated[j].mean() == 0.0)
        {
            "undefined\nWARNING: no light reaches any point (a light sealed inside a solid, \
             points behind walls, or lights facing away): every result is 0"
                .to_string()
        } else if counts.contains_key("batches") {
            "undefined (every error bar is 0 after fewer than 32 batches: see the `batches` \
             flag)"
                .to_string()
        } else if r.tallies.approximate {
            "undefined (zero sampling error, but the median-cut lights only approximate the map: \
             see the `approx` flag)"
                .to_string()
        } else {
            "undefined (zero error: every estimate is exact)".to_string()
        },
    );
    // Exact points (R = 0: no light reaches them, or their light is all
    // exact direct light) count in the RMS as 0; said, so that an RMS
    // below a target is not read as every point's.
    let exact = r
        .tallies
        .rel_errors(&r.direct)
        .filter(|e| *e == 0.0)
        .count();
    let mut text = if exact > 0 && exact < r.direct.len() {
        format!(
            "{text}\n{exact} of the {} receivers are exact (R = 0: no light reaches them, or only \
             exact direct light) and count as 0 in the RMS; over the other {} it is {:.3e}\n{flags}",
            r.direct.len(),
            r.direct.len() - exact,
            rms * (r.direct.len() as f64 / (r.direct.len() - exact) as f64).sqrt()
        )
    } else {
        format!("{text}\n{flags}")
    };
    if let Some(t) = &r.time_sizing {
        if t.minimum_time > t.left {
            // The limit is soft: the least run goes on past it.
            text += &format!(
                "\n--time: the least run, {} batches of {} chains, needs about {:.3} s at the \
                 measured {:.3e} chains/s, more than the {:.3} s left of the limit, which is soft: \
                 the run completes them all the same (give more time, or --chains)",
                crate::run::MIN_BATCHES,
                t.batch_size,
                t.minimum_time,
                t.rate,
                t.left
            );
        } else if t.batch_size < t.default_batch_size {
            text += &format!(
                "\n--time: batches of {} chains (default {}) so that {} batches, and the batches \
                 every thread holds at the limit, fit at the measured {:.3e} chains/s",
                t.batch_size,
                t.default_batch_size,
                crate::run::MIN_BATCHES,
                t.rate,
            );
        }
    }
    if let Some(p) = r.pilot.as_ref().filter(|p| p.custom) {
        text += &format!(
            "\n--figure-target: a pilot of {} batches of {} chains ({:.3} s, own streams) gave a \
             largest ratio of interval half-width to target of {:.3e} per batch of {}, so {} fresh \
             batches were planned{}",
            p.batches,
            p.batch_size,
            p.wall,
            p.rel_error,
            r.batch_size,
            format_number(p.planned as f64),
            if r.reason == crate::run::StopReason::Time {
                format!(
                    "; stopped by {} before the plan was done (about {:.3e} s needed)",
                    p.default_cap.map_or_else(
                        || "--time".to_string(),
                        |c| format!("the default time limit of {c:.0} s (no --time was given)")
                    ),
                    p.estimated_time
                )
            } else if r.reason == crate::run::StopReason::Chains {
                " (capped by --chains)".to_string()
            } else {
                String::new()
            }
        );
    } else if let Some(p) = &r.pilot {
        let target = p.target;
        // An RMS target (`--rms-error`) is judged by the RMS, a max target by the max.
        let (flag, what, max) = if p.rms {
            ("--rms-error", "RMS", rms)
        } else {
            ("--rel-error", "max", max)
        };
        let measured = if p.grown > 0 {
            format!(
                "\n{flag} {target:.3e}: no pilot; the run's {} batches grew in {} stage(s) to {} \
                 chains each, each stage's own {what} R sizing the next{}",
                p.batches,
                p.grown,
                if p.cut {
                    // (Stopped within the last stage: the batches differ.)
                    format!(
                        "up to {} (stopped within the last stage; {:.0} on average)",
                        p.batch_size,
                        r.chains as f64 / p.batches.max(1) as f64
                    )
                } else {
                    p.batch_size.to_string()
                },
                if p.fall.is_finite() {
                    // (The plan takes the fall within 0 ..= 1: `run::grow`.)
                    let planned = p.fall.clamp(0.0, 1.0);
                    format!(
                        " (variance per chain went like batch size^{:.2}{})",
                        -p.fall,
                        if (planned - p.fall).abs() < 0.005 {
                            String::new()
                        } else {
                            format!(", planned with ^{:.0}", 0.0 - planned)
                        }
                    )
                } else {
                    String::new()
                },
            )
        } else if p.calibration > 0 {
            format!(
                "\n{flag} {target:.3e}: the run's first {} batches of {} chains (sized by a pilot of \
                 {} chains on their own streams, {:.3} s) gave {what} R {:.3e} (margin {:.3} for {:.0} \
                 degrees of freedom), so {}, those {} included",
                p.calibration,
                p.batch_size,
                format_number(p.pilot_chains as f64),
                p.wall,
                p.rel_error,
                crate::run::variance_margin(p.dof),
                p.dof,
                planned_text(p.planned, p.rel_error, "batches were planned in all"),
                p.calibration,
            )
        } else {
            format!(
                "\n{flag} {target:.3e}: a pilot of {} batches of {} chains ({:.3} s, own streams{}) \
                 gave {what} R {:.3e} per batch of {} (margin {:.3} for {:.0} degrees of freedom), so \
                 {}",
                p.batches,
                p.batch_size,
                p.wall,
                if p.stages > 1 {
                    format!(
                        ", after a first stage of batches of {} chains that sized it; variance per \
                         chain taken to fall like batch size^-{:.3}",
                        crate::run::MIN_TIMED_BATCH,
                        p.fall
                    )
                } else {
                    String::new()
                },
                p.rel_error,
                r.batch_size,
                crate::run::variance_margin(p.dof),
                p.dof,
                planned_text(p.planned, p.rel_error, "fresh batches were planned"),
            )
        };
        text += &format!(
            "{measured}; achieved {what} R {max:.3e}{}",
            if max <= target {
                " (target met)".to_string()
            } else if max.is_nan() {
                " (target MISSED: the error is not a number; see the flagged rows)".to_string()
            } else if max.is_infinite() {
                // (An estimate of 0 with a nonzero error bar: no count of
                // chains can be read off it.)
                " (target MISSED: a relative error is infinite, an estimate of 0 with a nonzero \
                 error bar; see the flagged rows)"
                    .to_string()
            } else if r.reason == crate::run::StopReason::Time {
                let by = p.default_cap.map_or_else(
                    || "--time".to_string(),
                    |c| format!("the default time limit of {c:.0} s (no --time was given)"),
                );
                if p.grown > 0 {
                    // (As a power of ten: a tiny target's factor overflows.)
                    format!(
                        " (target MISSED: stopped by {by}; it needs about 10^{:.1} times the chains \
                         traced; the estimate and its error bar hold)",
                        2.0 * (max.log10() - target.log10())
                    )
                } else {
                    format!(
                        " (target MISSED: stopped by {by}; the {} planned batches need about {:.3e} \
                         s at the pace of {}; the estimate and its error bar hold)",
                        format_number(p.planned as f64),
                        p.estimated_time,
                        if p.calibration > 0 {
                            "the run's first batches"
                        } else {
                            "the pilot"
                        }
                    )
                }
            } else {
                format!(
                    " (target MISSED by {:.1} %; the estimate and its error bar are still unbiased: \
                     run again with --chains {} for the target)",
                    100.0 * (max / target - 1.0),
                    (r.chains as f64 * (max / target).powi(2) * 1.1).ceil()
                )
            }
        );
    }
    text
}

/// The summary lines of the modelling ratio `E_z / E_h` at the pairs of
/// points (see [`super::modelling`]): each pair with its rows, up to 10;
/// beyond, the smallest and the largest ratio.
fn modelling_lines(
    r: &RunResult,
    pairs: &[super::modelling::Pair],
    t: &PointTable,
    input: &str,
) -> Vec<String> {
    if pairs.is_empty() {
        return Vec::new();
    }
    let at = |p: &super::modelling::Pair| format!("{input}:{}+{}", t.lines[p.h], t.lines[p.z]);
    let values: Vec<(String, Option<(f64, f64)>)> = pairs
        .iter()
        .map(|p| {
            (
                at(p),
                super::modelling::ratio(&r.tallies.batch_means, &r.direct, *p),
            )
        })
        .collect();
    let show = |v: &Option<(f64, f64)>| match v {
        Some((m, se)) => format!("{m:.4} +- {se:.4}"),
        None => "undefined (E_h = 0 or fewer than 2 batches)".to_string(),
    };
    let mut out = vec![format!(
        "modelling E_z/E_h (EN 12464-1: 0.30-0.60 for good modelling) at {} point(s) listed planar up and cylindrical (rows file:line_h+line_z; standard errors with the covariance of E_z and E_h):",
        pairs.len()
    )];
    if values.len() <= 10 {
        out.extend(values.iter().map(|(w, v)| format!("  {w}: {}", show(v))));
    } else {
        let defined: Vec<&(String, Option<(f64, f64)>)> =
            values.iter().filter(|v| v.1.is_some()).collect();
        let by = |a: &&(String, Option<(f64, f64)>), b: &&(String, Option<(f64, f64)>)| {
            a.1.map_or(0.0, |x| x.0)
                .total_cmp(&b.1.map_or(0.0, |x| x.0))
        };
        if let (Some(lo), Some(hi)) = (
            defined.iter().copied().min_by(by),
            defined.iter().copied().max_by(by),
        ) {
            out.push(format!("  smallest {}: {}", lo.0, show(&lo.1)));
            out.push(format!("  largest {}: {}", hi.0, show(&hi.1)));
        }
        let undefined = values.len() - defined.len();
        if undefined > 0 {
            out.push(format!("  {undefined} undefined (E_h = 0)"));
        }
    }
    out
}

/// Points and views of one run, compiled into receivers.
pub struct Job {
    /// Illuminance points, if any.
    pub points: Option<PointTable>,
    /// Views, if any, with where each one ends.
    pub views: Option<(ViewTable, Vec<ViewTarget>)>,
    /// Receiver index of each view (None: the view sees nothing or a back side).
    pub view_receiver: Vec<Option<usize>>,
    /// Luminance of sphere lights seen straight along each view [cd/m^2].
    pub emitted: Vec<f64>,
    /// The compiled receivers: points first, then the views that meet a front side.
    pub receivers: Receivers,
    /// With `--daylight-factor`: the unobstructed horizontal illuminance
    /// \[lx\] that daylight factors divide by.
    pub daylight: Option<f64>,
}

/// The receivers of a point table `t` read from `path`: each row's
/// position and normal, of the type its optional `receiver` column names
/// (`planar` when the column is absent or the cell empty).
pub fn point_receivers(t: &PointTable, path: &str) -> Result<Vec<Receiver>, InputError> {
    let col = t.headers.iter().position(|h| h == "receiver");
    let mut rec = Vec::with_capacity(t.points.len());
    for (k, (&(p, n), &line)) in t.points.iter().zip(&t.lines).enumerate() {
        let name = col.map_or("", |c| t.rows[k][c].as_str());
        let kind = Solid::parse(name).map_err(|message| InputError::Field {
            file: if path == "-" {
                "<stdin>".into()
            } else {
                path.to_string()
            },
            line,
            field: "receiver".into(),
            message,
        })?;
        rec.push(match kind {
            None => Receiver::illuminance(p, n),
            Some(kind) => Receiver::solid(p, n, kind),
        });
    }
    Ok(rec)
}

impl Job {
    /// Read the lists and compile them against `scene`.
    pub fn new(scene: &Scene, points: Option<&str>, views: Option<&str>) -> anyhow::Result<Job> {
        let views_t = views.map(read_views).transpose()?;
        Self::with_views(scene, points, views_t, views.unwrap_or("-"))
    }

    /// As [`Job::new`], with a view table already built (`views_name` names it in messages).
    pub fn with_views(
        scene: &Scene,
        points: Option<&str>,
        views_t: Option<ViewTable>,
        views_name: &str,
    ) -> anyhow::Result<Job> {
        let points_t = points.map(read_points).transpose()?;
        let mut rec: Vec<Receiver> = Vec::new();
        // File and line of each receiver, for error messages.
        let mut origin: Vec<(&str, u64)> = Vec::new();
        if let (Some(t), Some(path)) = (&points_t, points) {
            rec = point_receivers(t, path)?;
            origin.extend(t.lines.iter().map(|&line| (path, line)));
        }
        let mut view_receiver = Vec::new();
        let mut emitted = Vec::new();
        let views = views_t.map(|t| {
            for (&(o, d), &line) in t.views.iter().zip(&t.lines) {
                let t_max = scene.observer_hit(o, d).map_or(f64::INFINITY, |h| h.t);
                // A view through glass would see the scene behind the pane
                // dimmed and the mirror image in it: not supported yet.
                if let Some(ph) = scene.next_pane(&crate::geometry::Ray { o, d }, t_max) {
                    let s = scene.panes()[ph.pane as usize].surface;
                    anyhow::bail!(
                        "{views_name}:{line}: the view looks through the glass pane `{}` at {} m from the observer: views through glazing are not supported yet",
                        scene.surfaces[s as usize].name,
                        crate::io::format_number(ph.t)
                    );
                }
                emitted.push(emitted_luminance(scene, o, d, t_max));
            }
            let targets: Vec<ViewTarget> = t
                .views
                .iter()
                .map(|&(o, d)| view_target(scene, o, d))
                .collect();
            for (target, &line) in targets.iter().zip(&t.lines) {
                if let ViewTarget::Front(r) = target {
                    view_receiver.push(Some(rec.len()));
                    rec.push(*r);
                    origin.push((views_name, line));
                } else {
                    view_receiver.push(None);
                }
            }
            Ok((t, targets))
        });
        let views = views.transpose()?;
        let receivers = Receivers::from_receivers(scene, &rec).map_err(|e| {
            let (file, line) = origin[e.index];
            anyhow::anyhow!("{file}:{line}: {}", e.message)
        })?;
        if let Some(&first) = receivers.lifted().first() {
            let (file, line) = origin[first as usize];
            eprintln!(
                "lumest: {} point(s) lie on a surface they do not face along (on an edge or a corner; first {file}:{line}): each reads the limit from the side its normal faces (the surface's reflecting side where the normal lies along it, the lit side of a closed two-sided mesh)",
                receivers.lifted().len()
            );
        }
        Ok(Job {
            points: points_t,
            views,
            view_receiver,
            emitted,
            receivers,
            daylight: None,
        })
    }

    /// Stream the points' results to the temporary file of `out` (input
    /// columns, then result columns); returns it staged, with the number of
    /// rows written (None without points).
    /// The modelling ratio's columns follow where `pairs` (the points
    /// listed planar up and cylindrical at one position) is not empty.
    pub fn write_points(
        &self,
        r: &RunResult,
        orders: u32,
        out: &str,
        pairs: &[super::modelling::Pair],
    ) -> anyhow::Result<Option<(Staged, usize)>> {
        let Some(t) = self.points.as_ref() else {
            return Ok(None);
        };
        let mut headers = t.headers.clone();
        headers.extend(result_headers("E", orders));
        if self.daylight.is_some() {
            headers.extend(DAYLIGHT_COLUMNS.map(String::from));
        }
        let modelling = (!pairs.is_empty()).then(|| {
            headers.extend(super::modelling::COLUMNS.map(String::from));
            super::modelling::cells(&r.tallies.batch_means, &r.direct, pairs, t.rows.len())
        });
        let rows = t.rows.iter().enumerate().map(|(j, row)| {
            let mut c = row.clone();
            c.resize(t.headers.len(), String::new());
            c.extend(result_cells(r, j));
            if let Some(e_h) = self.daylight {
                c.extend(daylight_cells(r, j, e_h));
            }
            if let Some(m) = &modelling {
                c.extend(m[j].clone());
            }
            c
        });
        stage_csv(out, &headers, rows)
            .map(Some)
            .with_context(|| format!("writing {out}"))
    }

    /// Stream the views' results to the temporary file of `out`, with the
    /// sub-point `sx,sy,sz` (empty when the ray leaves the scene); returns it
    /// staged, with the number of rows written (None without views).
    pub fn write_views(
        &self,
        r: &RunResult,
        orders: u32,
        out: &str,
    ) -> anyhow::Result<Option<(Staged, usize)>> {
        let Some((t, targets)) = self.views.as_ref() else {
            return Ok(None);
        };
        let mut headers = t.headers.clone();
        headers.extend(result_headers("L", orders));
        headers.extend(["sx", "sy", "sz"].map(String::from));
        let rows = t.rows.iter().enumerate().map(|(k, row)| {
            let mut c = row.clone();
            c.resize(t.headers.len(), String::new());
            match self.view_receiver[k] {
                Some(j) => c.extend(result_cells_plus(r, j, self.emitted[k])),
                None => c.extend(exact_cells(self.emitted[k], orders)),
            }
            match targets[k].sub_point() {
                Some(s) => c.extend([s.x, s.y, s.z].map(format_number)),
                None => c.extend(["", "", ""].map(String::from)),
            }
            c
        });
        stage_csv(out, &headers, rows)
            .map(Some)
            .with_context(|| format!("writing {out}"))
    }
}

/// Refuse a points column named like a column the output adds (results
/// with `orders` resolved, daylight factors, the modelling ratio).
pub fn reserved_point_columns(t: &PointTable, orders: u32, input: &str) -> anyhow::Result<()> {
    let mut names = result_headers("E", orders);
    names.extend(DAYLIGHT_COLUMNS.map(String::from));
    names.extend(super::modelling::COLUMNS.map(String::from));
    reserved_columns(&t.headers, &names, input)
}

/// Refuse an input column that has the name of a result column.
fn reserved_columns(headers: &[String], results: &[String], input: &str) -> anyhow::Result<()> {
    if let Some(h) = headers.iter().find(|h| results.contains(h)) {
        let input = if input == "-" { "<stdin>" } else { input };
        anyhow::bail!(
            "{input}: column `{h}` has the name of a result column, which the output adds \
             (the output would have two `{h}` columns); rename it"
        );
    }
    Ok(())
}

/// The rows-in, rows-out line of the run summary for one list.
fn rows_line(
    what: &str,
    input: &str,
    rows_in: usize,
    comments: u64,
    out: &str,
    rows_out: usize,
) -> String {
    let input = if input == "-" { "<stdin>" } else { input };
    let out = if out == "-" { "<stdout>" } else { out };
    let comments = match comments {
        0 => String::new(),
        1 => " (and 1 comment line before the header)".to_string(),
        n => format!(" (and {n} comment lines before the header)"),
    };
    format!("{what}: {rows_in} rows read from {input}{comments}, {rows_out} rows written to {out}")
}

/// Run a job with the chosen estimator.
pub fn run_job(
    scene: &Scene,
    job: &Job,
    cfg: &RunConfig,
    estimator: EstimatorKind,
    quiet: bool,
    mut checkpoint: Option<super::run_state::Checkpointer>,
) -> RunResult {
    let pb = progress_bar(cfg, quiet);
    // A first Ctrl-C (or SIGTERM) stops the run after the batches in hand;
    // what was folded is kept and written, with a checkpoint to resume from.
    let mut observe = |p: &crate::run::Progress| {
        tick(&pb, cfg, p);
        let stop = crate::io::interrupt::interrupted();
        if let Some(c) = checkpoint.as_mut() {
            c.offer(p, stop);
        }
        !stop
    };
    let result = match estimator {
        EstimatorKind::Local => run(scene, &job.receivers, cfg, &mut observe),
        EstimatorKind::Backward => crate::backward::run(scene, &job.receivers, cfg, &mut observe),
    };
    pb.finish_and_clear();
    result
}

/// Number of theta and phi steps of a fan with steps of `dt` and `dp` degrees.
fn fan_steps(dt: f64, dp: f64) -> (u64, u64) {
    (
        (90.0 / dt).round().max(1.0) as u64,
        (360.0 / dp).round().max(1.0) as u64,
    )
}

/// Views over the hemisphere about `n` at `p`: theta at the centres of steps
/// of `dt` degrees in [0, 90), phi at multiples of `dp` degrees in [0, 360).
/// Columns `theta_deg,phi_deg,x,y,z,dx,dy,dz`.
pub fn fan_views(p: glam::DVec3, n: glam::DVec3, dt: f64, dp: f64) -> ViewTable {
    let frame = crate::sampling::warp::Frame::from_normal(n);
    let mut t = ViewTable {
        headers: ["theta_deg", "phi_deg", "x", "y", "z", "dx", "dy", "dz"]
            .map(String::from)
            .to_vec(),
        ..ViewTable::default()
    };
    let (nt, np) = fan_steps(dt, dp);
    let (nt, np) = (nt as usize, np as usize);
    for i in 0..nt {
        let theta = (i as f64 + 0.5) * 90.0 / nt as f64;
        for k in 0..np {
            let phi = k as f64 * 360.0 / np as f64;
            let (st, ct) = theta.to_radians().sin_cos();
            let (sp, cp) = phi.to_radians().sin_cos();
            let d = frame.to_world(glam::DVec3::new(st * cp, st * sp, ct));
            t.rows.push(
                [theta, phi, p.x, p.y, p.z, d.x, d.y, d.z]
                    .map(format_number)
                    .to_vec(),
            );
            t.lines.push(t.rows.len() as u64 + 1);
            t.views.push((p, d));
        }
    }
    t
}

/// Parse `a,b,c,...` into exactly `n` finite numbers.
fn numbers(s: &str, n: usize, what: &str) -> anyhow::Result<Vec<f64>> {
    let v = super::sobolev::parse_list(s).map_err(|e| anyhow::anyhow!("{what}: {e}"))?;
    anyhow::ensure!(
        v.len() == n,
        "{what}: expected {n} comma-separated numbers, got `{s}`"
    );
    Ok(v)
}

fn measure(
    scene_path: &std::path::Path,
    points: Option<(&str, &str)>,
    views: Option<(&str, &str)>,
    estimator: EstimatorKind,
    run_args: &RunArgs,
) -> anyhow::Result<()> {
    measure_with(
        scene_path,
        points,
        views.map(|v| (v.0, None, v.1)),
        estimator,
        run_args,
    )
    .map(|_| ())
}

pub(crate) fn measure_with(
    scene_path: &std::path::Path,
    points: Option<(&str, &str)>,
    views: Option<(&str, Option<ViewTable>, &str)>,
    estimator: EstimatorKind,
    run_args: &RunArgs,
) -> anyhow::Result<(Job, RunResult)> {
    measure_full(
        scene_path,
        points,
        views,
        estimator,
        run_args,
        &GridOutputs::default(),
    )
}

/// What a run on grid points adds: the figures' CSV, the report and
/// plots, and the figures the plan aims at (`--figure-target`).
#[derive(Default)]
pub(crate) struct GridOutputs<'a> {
    /// `--figures-out`.
    pub figures_out: Option<&'a str>,
    /// `--report`, `--isolux-dir`.
    pub report: Option<super::report::ReportOutputs>,
    /// `--figure-target`.
    pub targets: Vec<super::figure_target::FigureTarget>,
}

/// The scene and the job of a run as every run of them sees it, a single
/// run and each shard alike: the scene loaded (the sky alone with
/// `--daylight-factor`), its direct-light rule set (`--direct-lights`,
/// `--ris-candidates`), the settings it cannot take refused, the points and
/// views read (a light at infinity's start density fitted to them, with
/// infinite planes), the daylight factor's reference, the tally size and
/// the result columns checked.
pub(crate) fn prepare_job(
    scene_path: &std::path::Path,
    points: Option<(&str, &str)>,
    views: Option<(&str, Option<ViewTable>, &str)>,
    estimator: EstimatorKind,
    run_args: &RunArgs,
    cfg: &RunConfig,
) -> anyhow::Result<(Scene, Job)> {
    // A daylight factor counts the sky's light alone (`DF` and `E` alike).
    let mut scene = if run_args.daylight_factor {
        let (scene, left_out, kept) = scene::load_sky_only(scene_path)?;
        anyhow::ensure!(
            kept > 0,
            "{}: --daylight-factor needs a `sky` or `environment` light: the daylight factor is the \
             light of the sky alone (CIE S 017: direct sunlight excluded; electric light is not \
             daylight), and the scene has none",
            scene_path.display()
        );
        if !left_out.is_empty() {
            eprintln!(
                "lumest: --daylight-factor: E and DF count the light of the sky alone (CIE S 017: \
                 direct sunlight excluded; electric light is not daylight); left out: {}",
                left_out.join(", ")
            );
        }
        scene
    } else {
        scene::load(scene_path)?
    };
    scene.set_direct_lights(run_args.direct_lights, run_args.ris_candidates);
    // A candidate count that nothing uses is said, not silently dropped.
    if run_args.ris_candidates != crate::light::array::RIS_CANDIDATES
        && scene.light_array().is_none()
    {
        eprintln!(
            "lumest: --ris-candidates {} has no effect: RIS is not used here (--direct-lights exact, \
             or auto below its source counts)",
            run_args.ris_candidates
        );
    }
    anyhow::ensure!(
        !(scene.has_panes() && run_args.direct_lights == crate::light::array::DirectLights::Ris),
        "{}: --direct-lights ris is not supported with glass panes (the sampled sources would miss the panes' transmittance and mirror images); the exact sum runs there",
        scene_path.display()
    );
    if scene.has_panes() {
        // Backward paths do not cross or mirror glass yet (their MIS
        // weights assume straight segments): glazed scenes run the local
        // estimate, plain.
        anyhow::ensure!(
            estimator != EstimatorKind::Backward && cfg.near.0 <= 0.0,
            "{}: the scene has glass panes, which the backward estimator and --near-radius do not support yet; the local estimate runs plain there (leave out --estimator backward and --near-radius)",
            scene_path.display()
        );
    }
    let (views, table) = match views {
        Some((name, table, out)) => (Some((name, out)), table),
        None => (None, None),
    };
    let mut job = match table {
        Some(t) => Job::with_views(
            &scene,
            points.map(|p| p.0),
            Some(t),
            views.map_or("-", |v| v.0),
        )?,
        None => Job::new(&scene, points.map(|p| p.0), views.map(|v| v.0))?,
    };
    // With infinite planes the chains of a light at infinity start on a
    // density fitted to the receivers too (exact either way; efficiency).
    if scene.has_directional() && !scene.planes().is_empty() {
        let pts: Vec<glam::DVec3> = job.receivers.receivers().iter().map(|r| r.p).collect();
        scene.fit_directional(&pts);
        let table = job.views.take().map(|v| v.0);
        job = Job::with_views(
            &scene,
            points.map(|p| p.0),
            table,
            views.map_or("-", |v| v.0),
        )?;
    }
    if run_args.daylight_factor {
        anyhow::ensure!(
            job.points.is_some(),
            "--daylight-factor adds columns to the points' results: give --points"
        );
        let e_h = daylight_reference(&scene)
            .filter(|e| *e > 0.0)
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "--daylight-factor needs a `sky` or `environment` light whose unobstructed \
                 horizontal illuminance is positive"
                )
            })?;
        eprintln!(
            "lumest: daylight factors divide by {} lx, the unobstructed horizontal illuminance of the scene's sky (exact)",
            format_number(e_h)
        );
        job.daylight = Some(e_h);
    }
    check_tally_size(
        cfg.orders,
        job.points.as_ref().map_or(0, |t| t.rows.len())
            + job.views.as_ref().map_or(0, |v| v.0.rows.len()),
    )?;
    // The output repeats the input columns and adds the result columns: an
    // input column named like a result column would appear twice.
    if let (Some((input, _)), Some(t)) = (points, &job.points) {
        reserved_point_columns(t, cfg.orders, input)?;
    }
    if let (Some((input, _)), Some((t, _))) = (views, &job.views) {
        let mut names = result_headers("L", cfg.orders);
        names.extend(["sx", "sy", "sz"].map(String::from));
        reserved_columns(&t.headers, &names, input)?;
    }
    Ok((scene, job))
}

/// [`measure_with`], also writing the grid figures, report and plots and
/// planning for figure targets ([`GridOutputs`]).
pub(crate) fn measure_full(
    scene_path: &std::path::Path,
    points: Option<(&str, &str)>,
    views: Option<(&str, Option<ViewTable>, &str)>,
    estimator: EstimatorKind,
    run_args: &RunArgs,
    grid: &GridOutputs,
) -> anyhow::Result<(Job, RunResult)> {
    let (figures_out, report, targets) = (
        grid.figures_out,
        grid.report.as_ref(),
        grid.targets.as_slice(),
    );
    let mut cfg = run_args.config()?;
    if estimator == EstimatorKind::Backward {
        run_args.check_local_only("backward")?;
    }
    let view_paths = views.as_ref().map(|v| (v.0, v.2));
    let (scene, mut job) = prepare_job(scene_path, points, views, estimator, run_args, &cfg)?;
    let views = view_paths;
    // Points grouped by a `grid` column get grid figures, from their
    // per-batch means.
    let groups = match (points, &job.points) {
        (Some((input, _)), Some(t)) => super::figures::grid_groups(t, input)?,
        _ => None,
    };
    anyhow::ensure!(
        figures_out.is_none() || groups.as_ref().is_some_and(|g| !g.0.is_empty()),
        "--figures-out: the points have no `grid` column naming their grids (write them with `lumest grid`)"
    );
    if let Some(rep) = report {
        super::report::check_plot_paths(rep, groups.as_ref())?;
    }
    let grids = if groups.is_some() {
        crate::grid::load(scene_path)?
    } else {
        Vec::new()
    };
    // Points listed as planar and cylindrical at one position get the
    // modelling ratio, whose error needs the batch means too.
    let n_points = job.points.as_ref().map_or(0, |t| t.rows.len());
    let modelling_pairs = super::modelling::pairs(job.receivers.receivers(), n_points);
    if groups.is_some() || !modelling_pairs.is_empty() {
        cfg.keep_batch_means = n_points;
    }
    if !targets.is_empty() {
        let Some((g, _)) = &groups else {
            anyhow::bail!(
                "--figure-target: the points have no `grid` column naming their grids (write them with `lumest grid`)"
            );
        };
        for t in targets {
            anyhow::ensure!(
                g.iter().any(|x| x.name == t.grid),
                "--figure-target: no grid `{}` among the points (grids: {})",
                t.grid,
                g.iter()
                    .map(|x| format!("`{}`", x.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        anyhow::ensure!(
            run_args.rel_error.is_none() && run_args.rms_error.is_none(),
            "--figure-target replaces --rel-error and --rms-error: give one rule"
        );
        anyhow::ensure!(
            run_args.checkpoint.is_none() && run_args.resume.is_none(),
            "--figure-target plans its run from a pilot: no --checkpoint or --resume"
        );
        // The plan sets the chains; --chains, if given, caps them.
        if run_args.chains.is_none() {
            cfg.stop.chains = None;
        }
        cfg.stop.rel_error = Some(1.0);
        cfg.stop.rms = false;
        let (g, gr, t) = (g.clone(), grids.clone(), targets.to_vec());
        cfg.pilot_measure = Some(crate::run::PilotMeasure(std::sync::Arc::new(
            move |r: &RunResult| super::figure_target::measure(r, &g, &gr, &t),
        )));
    }
    eprintln!(
        "lumest: scene {}: {}",
        scene_path.display(),
        scene.summary()
    );
    eprintln!("lumest: {}", scene.direct_lights_note());
    for note in &scene.notes {
        eprintln!("lumest: {note}");
    }
    for (l, name) in scene.lights.iter().zip(&scene.light_names) {
        let region = match l {
            crate::light::Light::Distant(dl) => Some(&dl.region),
            crate::light::Light::Environment(env) => Some(&env.region),
            _ => None,
        };
        if let Some(note) = region.and_then(|r| r.note()) {
            eprintln!("lumest: {name}: {note}");
        }
    }
    let cfg = match &run_args.resume {
        Some(path) => super::run_state::resume(path, &scene, &job, &cfg, estimator)?,
        None => cfg,
    };
    // The near/far split set on the job's own receivers (the estimator
    // would set it on a copy, holding two sets).
    if estimator == EstimatorKind::Local {
        crate::estimator::local::prepare(&scene, &mut job.receivers, &cfg);
    }
    // Checkpoints: every --checkpoint-every seconds to --checkpoint, and at
    // an interrupt (there, or next to the first output) when the run has a
    // fixed number of chains.
    let out = points.map(|p| p.1).or(views.map(|v| v.1)).unwrap_or("-");
    let ckpt_path = run_args.checkpoint.clone().or_else(|| {
        (cfg.stop.time.is_none() && cfg.stop.rel_error.is_none() && out != "-")
            .then(|| format!("{out}.checkpoint"))
    });
    if let Some(ck) = &ckpt_path {
        // The checkpoint is an output too: never over an input or another
        // output (a checkpoint named like `--out` would be lost to it).
        let referenced = scene::referenced_files(scene_path);
        let mut inputs = vec![scene_path];
        inputs.extend(referenced.iter().map(|p| p.as_path()));
        inputs.extend(points.map(|p| Path::new(p.0)));
        inputs.extend(views.map(|v| Path::new(v.0)));
        let name = if run_args.checkpoint.is_some() {
            "--checkpoint"
        } else {
            "the interrupt's checkpoint"
        };
        let mut outputs = vec![(name, Path::new(ck.as_str()))];
        match report {
            // (The report's list holds every output of the command.)
            Some(rep) => outputs.extend(rep.outputs.iter().map(|o| ("an output", o.as_path()))),
            None => {
                outputs.extend(points.map(|p| ("the points' output", Path::new(p.1))));
                outputs.extend(views.map(|v| ("the views' output", Path::new(v.1))));
                outputs.extend(figures_out.map(|f| ("--figures-out", Path::new(f))));
            }
        }
        check_outputs(&inputs, &outputs)?;
    }
    let checkpointer = ckpt_path.as_ref().map(|p| {
        let every = if run_args.checkpoint.is_some() {
            run_args.checkpoint_every
        } else {
            f64::INFINITY
        };
        super::run_state::Checkpointer::new(p.clone(), every, &scene, &job, &cfg, estimator)
    });
    crate::io::interrupt::install();
    let result = run_job(&scene, &job, &cfg, estimator, run_args.quiet, checkpointer);
    if crate::io::interrupt::interrupted() {
        // What the interrupt kept to resume from, said either way.
        let kept = match &ckpt_path {
            Some(p) if super::run_state::last_checkpoint_written() => format!(
                "checkpoint written to {p}: run the same command with `--resume {p}` to finish \
                 the run (the result is the uninterrupted run's, bit for bit)"
            ),
            Some(p) => {
                format!("no checkpoint was written to {p} (see above): the run cannot be resumed")
            }
            None => "no checkpoint was kept (the run has no --checkpoint, and an interrupted run \
                     keeps one next to --out only when --out is a file and the run stops by \
                     --chains): the run cannot be resumed"
                .to_string(),
        };
        anyhow::ensure!(
            result.tallies.batches() >= 2,
            "interrupted before 2 batches were complete: no results written; {kept}"
        );
        eprintln!(
            "lumest: interrupted by a signal after {} batches ({} chains): writing the results so far, \
             with their error bars",
            result.tallies.batches(),
            result.chains
        );
        eprintln!("lumest: {kept}");
    }
    // Every output is staged before any is renamed into place: all or none.
    let mut rows = Vec::new();
    let mut staged = Vec::new();
    if let (Some((input, out)), Some(t)) = (points, &job.points)
        && let Some((file, n)) = job.write_points(&result, cfg.orders, out, &modelling_pairs)?
    {
        let line = rows_line("points", input, t.rows.len(), t.comment_lines, out, n);
        rows.push((line, n == t.rows.len()));
        staged.push((file, out));
    }
    if let (Some((input, out)), Some((t, _))) = (views, &job.views)
        && let Some((file, n)) = job.write_views(&result, cfg.orders, out)?
    {
        let line = rows_line("views", input, t.rows.len(), t.comment_lines, out, n);
        rows.push((line, n == t.rows.len()));
        staged.push((file, out));
    }
    let figures = groups
        .as_ref()
        .map(|(g, _)| super::figures::grid_figures(&result, g, &grids));
    if let (Some(out), Some(f)) = (figures_out, &figures) {
        let headers: Vec<String> = super::figures::FIGURE_COLUMNS.map(String::from).to_vec();
        let (file, _) = stage_csv(out, &headers, super::figures::figure_rows(f))
            .with_context(|| format!("writing {out}"))?;
        staged.push((file, out));
    }
    let report_files = match report {
        Some(rep) => super::report::stage(
            rep,
            scene_path,
            &scene,
            &job,
            &cfg,
            &result,
            groups.as_ref(),
            figures.as_deref(),
        )?,
        None => Vec::new(),
    };
    anyhow::ensure!(
        rows.iter().all(|r| r.1),
        "rows were lost: {}",
        rows.iter()
            .map(|r| r.0.as_str())
            .collect::<Vec<_>>()
            .join("; ")
    );
    for (file, out) in staged {
        file.commit().with_context(|| format!("writing {out}"))?;
    }
    let mut written = Vec::new();
    for (file, out) in report_files {
        file.commit().with_context(|| format!("writing {out}"))?;
        written.push(out);
    }
    for line in summary_seen(&result, job.emitted.iter().any(|l| *l > 0.0)).lines() {
        eprintln!("lumest: {line}");
    }
    for (line, _) in &rows {
        eprintln!("lumest: {line}");
    }
    // An average over different receiver types means nothing.
    let kinds: std::collections::BTreeSet<&str> = job.receivers.receivers()[..n_points]
        .iter()
        .map(|r| r.solid_kind().map_or("planar", |k| k.name()))
        .collect();
    if kinds.len() > 1 {
        eprintln!(
            "lumest: points: no E_avg, E_min, U0 over mixed receiver types ({}): list one type per file, or use grids",
            kinds.into_iter().collect::<Vec<_>>().join(", ")
        );
    } else if let Some((g, _)) = &groups
        && !g.is_empty()
    {
        // Points of grids: their area-weighted figures follow, grid by
        // grid. Unweighted figures over all points would disagree with
        // them (a disc grid's rim cells weigh less), and over several
        // grids together (a work plane, walls and a ceiling: U0 0.003)
        // mean nothing.
        eprintln!(
            "lumest: points: {} grid(s): their area-weighted figures follow, grid by grid",
            g.len()
        );
    } else if let Some(t) = &job.points
        && let Some(line) = grid_summary(&result, t.rows.len())
    {
        eprintln!("lumest: {line}");
    }
    if let (Some(t), Some((input, _))) = (&job.points, points) {
        for line in modelling_lines(&result, &modelling_pairs, t, input) {
            eprintln!("lumest: {line}");
        }
    }
    if let (Some(f), Some((_, equal))) = (&figures, &groups) {
        for g in f {
            for line in super::figures::summary_lines(g, *equal) {
                eprintln!("lumest: {line}");
            }
        }
        for line in super::figure_target::summary_lines(f, targets) {
            eprintln!("lumest: {line}");
        }
    }
    for out in &written {
        eprintln!("lumest: wrote {out}");
    }
    Ok((job, result))
}

/// The lighting engineer's figures over the first `n` receivers (the
/// illuminance points): average, minimum and maximum illuminance \[lx\] and
/// the uniformity `U0 = E_min / E_avg`, with the standard error of `E_avg`.
pub fn grid_summary(r: &RunResult, n: usize) -> Option<String> {
    if n == 0 {
        return None;
    }
    // Enclosed points (inside a solid, behind a wall) are left out of the
    // figures, and said so.
    let kept: Vec<usize> = (0..n)
        .filter(|&j| !r.tallies.enclosed.get(j).copied().unwrap_or(false))
        .collect();
    let left_out = n - kept.len();
    let note = if left_out > 0 {
        format!(
            " ({left_out} of {n} point(s) left out: flagged `enclosed`, they see the back of a surface in most directions or lie inside a closed mesh that holds no light)"
        )
    } else {
        String::new()
    };
    if kept.is_empty() {
        return Some(format!("points: no figures: every point is enclosed{note}"));
    }
    let m = kept.len() as f64;
    let e: Vec<f64> = kept
        .iter()
        .map(|&j| r.direct[j] + r.tallies.estimated[j].mean())
        .collect();
    // Batch means of the average are the average of the batch means, so its
    // error is that of the per-point errors combined with their correlation;
    // bounded above by the mean of the per-point errors (full correlation).
    let avg = e.iter().sum::<f64>() / m;
    let se_bound = kept
        .iter()
        .map(|&j| r.tallies.estimated[j].std_error())
        .sum::<f64>()
        / m;
    // A NaN estimate makes the extremes NaN too (`f64::min` would drop it).
    let pick = |f: fn(f64, f64) -> f64| {
        move |a: f64, b: f64| {
            if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                f(a, b)
            }
        }
    };
    let min = e.iter().copied().fold(f64::INFINITY, pick(f64::min));
    let max = e.iter().copied().fold(f64::NEG_INFINITY, pick(f64::max));
    Some(format!(
        "points: E_avg {} lx (std error <= {se_bound:.2e}), E_min {} lx, E_max {} lx, \
         uniformity U0 = E_min/E_avg = {}{note}",
        format_fixed(avg, 4),
        format_fixed(min, 4),
        format_fixed(max, 4),
        if avg > 0.0 {
            format!("{:.3}", min / avg)
        } else {
            "undefined (no light)".into()
        }
    ))
}

/// A rate per second for the summary: `0` when nothing was counted (a
/// run in which nothing emits traces no chain in no time: not NaN).
fn per_second(count: f64, wall: f64) -> String {
    if count == 0.0 || wall <= 0.0 {
        "0".into()
    } else {
        format!("{:.4e}", count / wall)
    }
}

/// Run `lumest illuminance`.
pub fn illuminance(a: &IlluminanceArgs) -> anyhow::Result<()> {
    if let Some(shard) = &a.shard {
        return super::merge::run_shard(a, shard);
    }
    if a.mpi {
        return super::mpi_run::run(a);
    }
    let views = a.views.as_deref().zip(a.views_out.as_deref());
    anyhow::ensure!(
        !(a.points == "-" && views.is_some_and(|v| v.0 == "-")),
        "--points - and --views -: standard input can be read once; give one of them a file"
    );
    let referenced = scene::referenced_files(&a.scene);
    let mut inputs = vec![a.scene.as_path(), Path::new(&a.points)];
    inputs.extend(referenced.iter().map(|p| p.as_path()));
    let mut outputs = vec![("--out", Path::new(&a.out))];
    if let Some((v, out)) = views {
        inputs.push(Path::new(v));
        outputs.push(("--views-out", Path::new(out)));
    }
    if let Some(f) = &a.figures_out {
        outputs.push(("--figures-out", Path::new(f)));
    }
    if let Some(f) = &a.report {
        outputs.push(("--report", Path::new(f)));
    }
    check_outputs(&inputs, &outputs)?;
    // The checkpoint a run resumes from is an input of its outputs (a
    // later checkpoint may replace it: that is how a run goes on).
    if let Some(r) = &a.run.resume {
        check_outputs(&[Path::new(r)], &outputs)?;
    }
    if let Some(d) = &a.isolux_dir {
        anyhow::ensure!(
            Path::new(d).is_dir(),
            "--isolux-dir {d}: not an existing folder"
        );
    }
    let report =
        (a.report.is_some() || a.isolux_dir.is_some()).then(|| super::report::ReportOutputs {
            report: a.report.clone(),
            isolux_dir: a.isolux_dir.clone(),
            inputs: inputs.iter().map(|p| p.to_path_buf()).collect(),
            outputs: outputs.iter().map(|o| o.1.to_path_buf()).collect(),
        });
    let targets = a
        .figure_target
        .iter()
        .map(|t| super::figure_target::FigureTarget::parse(t))
        .collect::<anyhow::Result<Vec<_>>>()?;
    measure_full(
        &a.scene,
        Some((&a.points, &a.out)),
        views.map(|v| (v.0, None, v.1)),
        a.estimator,
        &a.run,
        &GridOutputs {
            figures_out: a.figures_out.as_deref(),
            report,
            targets,
        },
    )
    .map(|_| ())
}

/// Run `lumest luminance`.
pub fn luminance(a: &LuminanceArgs) -> anyhow::Result<()> {
    let points = a.points.as_deref().zip(a.points_out.as_deref());
    let referenced = scene::referenced_files(&a.scene);
    let mut inputs = vec![a.scene.as_path()];
    inputs.extend(referenced.iter().map(|p| p.as_path()));
    inputs.extend(a.views.as_deref().map(Path::new));
    let mut outputs = vec![("--out", Path::new(&a.out))];
    if let Some((p, out)) = points {
        inputs.push(Path::new(p));
        outputs.push(("--points-out", Path::new(out)));
    }
    if let Some(plot) = &a.plot {
        outputs.push(("--plot", Path::new(plot)));
    }
    // (The run checks the checkpoint against the outputs it knows; the
    // plot is this command's own.)
    if let Some(r) = &a.run.resume {
        check_outputs(&[Path::new(r)], &outputs)?;
    }
    if let Some(ck) = &a.run.checkpoint {
        outputs.push(("--checkpoint", Path::new(ck)));
    }
    check_outputs(&inputs, &outputs)?;
    if let (Some(at), Some(steps)) = (&a.fan_at, &a.fan) {
        let v = numbers(at, 6, "--fan-at")?;
        let st = numbers(steps, 2, "--fan")?;
        anyhow::ensure!(
            st.iter().all(|&x| x > 0.0 && x <= 90.0),
            "--fan: steps must lie in (0, 90] degrees"
        );
        let (nt, np) = fan_steps(st[0], st[1]);
        // (Checked: a product that wraps past 2^64 passed the bound.)
        let n = nt.checked_mul(np);
        anyhow::ensure!(
            n.is_some_and(|n| n <= MAX_VIEWS),
            "--fan {steps}: {nt} x {np} = {} views; at most {MAX_VIEWS} (take larger steps)",
            n.map_or_else(|| "more than 2^64".to_string(), |n| n.to_string())
        );
        let at = glam::DVec3::new(v[0], v[1], v[2]);
        anyhow::ensure!(
            at.abs().max_element() <= crate::scene::MAX_COORD,
            "--fan-at: the point must lie within +-{:e} m",
            crate::scene::MAX_COORD
        );
        let n = crate::geometry::unit_direction(glam::DVec3::new(v[3], v[4], v[5]))
            .ok_or_else(|| anyhow::anyhow!("--fan-at: the normal has zero length"))?;
        let table = fan_views(at, n, st[0], st[1]);
        let (job, result) = measure_with(
            &a.scene,
            points,
            Some(("--fan", Some(table), &a.out)),
            a.estimator,
            &a.run,
        )?;
        if let Some(plot) = &a.plot {
            fan_plot(&job, &result, plot, a.plot_part)?;
        }
        return Ok(());
    }
    let views = a
        .views
        .as_deref()
        .expect("clap requires --views or --fan-at");
    measure(&a.scene, points, Some((views, &a.out)), a.estimator, &a.run)
}

/// Polar plot of a fan's luminance (linear colour scale).
fn fan_plot(job: &Job, r: &RunResult, path: &str, part: PlotPart) -> anyhow::Result<()> {
    let (t, _) = job.views.as_ref().expect("a fan has views");
    let samples: Vec<(f64, f64, f64)> = t
        .rows
        .iter()
        .enumerate()
        .map(|(k, row)| {
            let theta: f64 = row[0].parse().unwrap_or(0.0);
            let phi: f64 = row[1].parse().unwrap_or(0.0);
            let indirect = job.view_receiver[k].map_or(0.0, |j| {
                r.tallies.estimated[j].mean() - r.tallies.sampled_direct_mean(j)
            });
            let l = match part {
                PlotPart::Indirect => indirect,
                PlotPart::Total => {
                    job.view_receiver[k]
                        .map_or(0.0, |j| r.direct[j] + r.tallies.estimated[j].mean())
                        + job.emitted[k]
                }
            };
            (theta.to_radians(), phi.to_radians(), l.max(0.0))
        })
        .collect();
    let values: Vec<f64> = samples.iter().map(|s| s.2).collect();
    let scale = crate::io::image::ColourScale::from_data(&values, false);
    let title = match part {
        PlotPart::Total => "Luminance L(theta, phi)",
        PlotPart::Indirect => "Luminance of multiply reflected light",
    };
    crate::io::image::write_polar_png(path, &samples, scale, title)?;
    eprintln!("lumest: wrote {path}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid line's extremes keep a NaN estimate (principle: aggregates
    /// never drop NaN); finite estimates give their plain min and max.
    #[test]
    fn grid_summary_keeps_nan() {
        let result = |vals: &[f64]| {
            let mut tallies = crate::run::Tallies::new(vals.len(), 0);
            for _ in 0..2 {
                for (w, &v) in tallies.estimated.iter_mut().zip(vals) {
                    w.push(v);
                }
            }
            RunResult {
                direct: vec![0.0; vals.len()],
                tallies,
                chains: 2,
                batch_size: 1,
                collisions: 0,
                scores: 0,
                wall: 1.0,
                threads: 1,
                reason: crate::run::StopReason::Chains,
                pilot: None,
                time_sizing: None,
                batches: Vec::new(),
                total_batches: 0,
            }
        };
        let line = grid_summary(&result(&[1.0, 2.0, 4.0]), 3).unwrap();
        assert!(
            line.contains("E_min 1.0000 lx") && line.contains("E_max 4.0000 lx"),
            "{line}"
        );
        let line = grid_summary(&result(&[1.0, f64::NAN, 4.0]), 3).unwrap();
        assert!(
            line.contains("E_min NaN") && line.contains("E_max NaN"),
            "{line}"
        );
    }
}
