//! `lumest illuminance ... --report R.html --isolux-dir DIR`: the run's
//! HTML report ([`crate::report`]) and the isolux plot of every grid
//! ([`crate::io::isolux`]), staged with the run's other outputs.
//!
//! A grid's plot shows the maintained illuminance (the estimate times the
//! grid's maintenance factor, as its figures), its points placed on their
//! lattice in the grid's plane ([`crate::grid::lattice`]); points flagged
//! `enclosed`, which the figures leave out, are holes. Points that do not
//! form a flat rectilinear lattice get no plot, and the report says why.

use super::figures::{GridFigures, Group, sig};
use super::illuminance::Job;
use crate::grid::lattice::{Lattice, lattice};
use crate::io::csvio::{Staged, stage_bytes};
use crate::io::format_number;
use crate::io::isolux::IsoluxPlot;
use crate::report::{FigureRow, GridSection, Luminaire, Report, VerdictRow, outline};
use crate::run::{RunConfig, RunResult};
use crate::scene::Scene;
use crate::scene::desc::SceneDesc;
use anyhow::Context;
use std::path::{Path, PathBuf};

/// The report and plot outputs asked for.
#[derive(Clone, Debug, Default)]
pub struct ReportOutputs {
    /// The HTML report's path.
    pub report: Option<String>,
    /// The folder for the isolux plots.
    pub isolux_dir: Option<String>,
    /// The run's inputs (the plots' names are checked against them).
    pub inputs: Vec<PathBuf>,
    /// The outputs named on the command line.
    pub outputs: Vec<PathBuf>,
}

/// A file name made of a grid's name: letters, digits, `-` and `_` kept,
/// anything else `_`.
pub fn slug(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The isolux plot files of grid number `k` (from 0) named `name` in `dir`.
pub fn plot_paths(dir: &str, k: usize, name: &str) -> (String, String) {
    let base = Path::new(dir).join(format!("isolux_{}_{}", k + 1, slug(name)));
    let s = base.to_string_lossy().into_owned();
    (format!("{s}.png"), format!("{s}.svg"))
}

/// Check the plot files of the grids in `groups` before the run: none may
/// land on an input or another output, and each can be written.
pub fn check_plot_paths(
    out: &ReportOutputs,
    groups: Option<&(Vec<Group>, bool)>,
) -> anyhow::Result<()> {
    let (Some(dir), Some((groups, _))) = (&out.isolux_dir, groups) else {
        return Ok(());
    };
    let names: Vec<(String, String)> = groups
        .iter()
        .enumerate()
        .map(|(k, g)| plot_paths(dir, k, &g.name))
        .collect();
    let inputs: Vec<&Path> = out.inputs.iter().map(|p| p.as_path()).collect();
    let mut outputs: Vec<(&str, &Path)> = out
        .outputs
        .iter()
        .map(|p| ("an output", p.as_path()))
        .collect();
    for (png, svg) in &names {
        outputs.push(("--isolux-dir", Path::new(png)));
        outputs.push(("--isolux-dir", Path::new(svg)));
    }
    super::outputs::check_outputs(&inputs, &outputs)
}

/// The isolux plot of one grid, or why there is none.
fn grid_plot(
    job: &Job,
    r: &RunResult,
    g: &Group,
    factor: f64,
    desc: Option<&SceneDesc>,
) -> Result<(IsoluxPlot, Lattice), String> {
    let t = job.points.as_ref().ok_or("no points")?;
    let p: Vec<_> = g.rows.iter().map(|&j| t.points[j].0).collect();
    let n: Vec<_> = g.rows.iter().map(|&j| t.points[j].1).collect();
    // Points with their normals (planar receivers), else on the plane they
    // span (a cylindrical or semicylindrical grid's normal columns hold
    // its axis or facing: "not in one plane" before).
    let lat = lattice(&p, &n, &g.weights).or_else(|e| {
        let m = crate::grid::lattice::plane_normal(&p).ok_or(e)?;
        lattice(&p, &vec![m; p.len()], &g.weights)
    })?;
    let values: Vec<f64> = g
        .rows
        .iter()
        .map(|&j| {
            if r.tallies.enclosed.get(j).copied().unwrap_or(false) {
                f64::NAN
            } else {
                factor * (r.direct[j] + r.tallies.estimated[j].mean())
            }
        })
        .collect();
    let (outlines, luminaires) = desc.map_or((Vec::new(), Vec::new()), |d| {
        (outline::outlines(d, &lat), outline::luminaires(d, &lat))
    });
    let plot = IsoluxPlot {
        title: format!(
            "{}: maintained illuminance [lx], maintenance factor {}",
            g.name,
            format_number(factor)
        ),
        x_label: format!("{} [m]", lat.axes[0]),
        y_label: format!("{} [m]", lat.axes[1]),
        xs: lat.xs.clone(),
        ys: lat.ys.clone(),
        z: lat.raster(&values),
        bounds: lat.bounds,
        outlines,
        luminaires,
    };
    Ok((plot, lat))
}

/// The report's figure rows of one grid.
fn figure_rows(g: &GridFigures) -> Vec<FigureRow> {
    let Some(f) = &g.figures else {
        return Vec::new();
    };
    let figs = [
        ("E_avg", "lx", &f.e_avg, g.em, 5),
        ("E_min", "lx", &f.e_min, None, 5),
        ("E_max", "lx", &f.e_max, None, 5),
        ("U0", "1", &f.u0, g.u0, 4),
        ("Ud", "1", &f.ud, None, 4),
    ];
    figs.into_iter()
        .map(|(name, unit, x, req, digits)| {
            // A ratio over E_avg or E_max = 0 (no light reaches the grid).
            let both = |v: f64, d: i32| match v.is_finite() {
                true => (sig(v, d), format_number(v)),
                false => ("undefined".to_string(), String::new()),
            };
            FigureRow {
                figure: name.into(),
                unit: unit.into(),
                value: both(x.value, digits),
                std_error: both(x.std_error, 2),
                ci95_low: both(x.ci95.0, digits),
                ci95_high: both(x.ci95.1, digits),
                method: x.method.name(),
                required: req.map_or(String::new(), |(v, _)| format!(">= {}", format_number(v))),
                verdict: req.map_or(String::new(), |(_, v)| v.name().to_string()),
            }
        })
        .collect()
}

/// Stage the report and the plots asked for in `out`.
#[allow(clippy::too_many_arguments)]
pub fn stage(
    out: &ReportOutputs,
    scene_path: &Path,
    scene: &Scene,
    job: &Job,
    cfg: &RunConfig,
    r: &RunResult,
    groups: Option<&(Vec<Group>, bool)>,
    figures: Option<&[GridFigures]>,
) -> anyhow::Result<Vec<(Staged, String)>> {
    let desc: Option<SceneDesc> = std::fs::read_to_string(scene_path)
        .ok()
        .and_then(|s| toml::from_str(&s).ok());
    let mut staged = Vec::new();
    let mut sections = Vec::new();
    let empty = Vec::new();
    let groups = groups.map_or(&empty, |g| &g.0);
    for (k, g) in groups.iter().enumerate() {
        let fig = figures.and_then(|f| f.iter().find(|f| f.name == g.name));
        let factor = fig.map_or(1.0, |f| f.maintenance_factor);
        let plot = grid_plot(job, r, g, factor, desc.as_ref());
        let mut section = GridSection {
            name: g.name.clone(),
            ..Default::default()
        };
        match &plot {
            Ok((p, lat)) => {
                // Non-finite estimates (not left out) would be silent holes: say so.
                let bad = g
                    .rows
                    .iter()
                    .filter(|&&j| {
                        !r.tallies.enclosed.get(j).copied().unwrap_or(false)
                            && !(r.direct[j] + r.tallies.estimated[j].mean()).is_finite()
                    })
                    .count();
                if bad > 0 {
                    section.notes.push(format!(
                        "{bad} point(s) have a non-finite estimate: holes in the plot ({} x {} lattice).",
                        lat.xs.len(),
                        lat.ys.len()
                    ));
                }
                let svg = p
                    .svg()
                    .map_err(|e| anyhow::anyhow!("isolux plot of `{}`: {e}", g.name))?;
                if let Some(dir) = &out.isolux_dir {
                    let (png_path, svg_path) = plot_paths(dir, k, &g.name);
                    let png = p
                        .png()
                        .map_err(|e| anyhow::anyhow!("isolux plot of `{}`: {e}", g.name))?;
                    staged.push((
                        stage_bytes(&png_path, &png)
                            .with_context(|| format!("writing {png_path}"))?,
                        png_path.clone(),
                    ));
                    staged.push((
                        stage_bytes(&svg_path, svg.as_bytes())
                            .with_context(|| format!("writing {svg_path}"))?,
                        svg_path.clone(),
                    ));
                    section.plot_note = Some(format!("Plot files: {png_path}, {svg_path}"));
                }
                section.svg = Some(svg);
            }
            Err(why) => {
                section.plot_note = Some(format!("No isolux plot: {why}."));
                eprintln!("lumest: grid `{}`: no isolux plot: {why}", g.name);
            }
        }
        if let Some(f) = fig {
            section.facts = vec![
                ("points".into(), f.points.to_string()),
                ("area [m^2]".into(), sig(f.area, 4)),
                (
                    "maintenance factor".into(),
                    format_number(f.maintenance_factor),
                ),
                (
                    "batches".into(),
                    f.figures
                        .as_ref()
                        .map_or(String::new(), |x| x.batches.to_string()),
                ),
            ];
            if let Ok((_, lat)) = &plot {
                section.facts.push((
                    "lattice".into(),
                    format!("{} x {} points", lat.xs.len(), lat.ys.len()),
                ));
            }
            if !f.in_scene {
                section.notes.push(
                    "No [[grid]] of this name in the scene: maintenance factor 1, no requirements."
                        .into(),
                );
            }
            if f.left_out > 0 {
                section.notes.push(format!("{} point(s) left out: flagged `enclosed` (they see the back of a surface in most directions or lie inside a closed mesh that holds no light).", f.left_out));
            }
            if f.flagged > 0 {
                section.notes.push(format!(
                    "{} point(s) FLAGGED by the statistical checks: verdicts withheld (undecided).",
                    f.flagged
                ));
            }
            if f.figures.is_none() {
                section
                    .notes
                    .push("No figures: every point was left out.".into());
            }
            section.figures = figure_rows(f);
            for (what, unit, req) in [("Em", " lx", f.em), ("U0", "", f.u0)] {
                if let Some((v, verdict)) = req {
                    section.verdicts.push(VerdictRow {
                        requirement: format!("{what} >= {}{unit}", format_number(v)),
                        verdict: verdict.name().into(),
                        class: verdict.name().replace(' ', "-"),
                    });
                }
            }
        }
        sections.push(section);
    }
    if let Some(path) = &out.report {
        let report = build(scene_path, scene, job, cfg, r, desc.as_ref(), sections);
        let html = crate::report::render_html(&report)
            .map_err(|e| anyhow::anyhow!("writing {path}: the report template: {e}"))?;
        staged.push((
            stage_bytes(path, html.as_bytes()).with_context(|| format!("writing {path}"))?,
            path.clone(),
        ));
    }
    Ok(staged)
}

/// The report's contents.
fn build(
    scene_path: &Path,
    scene: &Scene,
    job: &Job,
    cfg: &RunConfig,
    r: &RunResult,
    desc: Option<&SceneDesc>,
    grids: Vec<GridSection>,
) -> Report {
    // Reference ratings, once per distinct distribution (the same file
    // at the same flux shares one).
    let mut ugr_cache: Vec<(std::sync::Arc<crate::light::Goniometric>, String)> = Vec::new();
    let mut reference = |l: &crate::light::Light| -> String {
        let crate::light::Light::Gonio { dist, .. } = l else {
            return "-".to_string();
        };
        if let Some((_, v)) = ugr_cache.iter().find(|(d, _)| **d == **dist) {
            return v.clone();
        }
        let v = match crate::glare::LuminousArea::of_file(&dist.file_opening()) {
            Ok(area) if dist.kind() == crate::io::photometry::PhotometricType::C => {
                let (c, e) = crate::glare::tabular::reference_ugr(dist, &area);
                if c.is_finite() && e.is_finite() {
                    format!("{c:.1} / {e:.1}")
                } else {
                    "-".to_string()
                }
            }
            _ => "-".to_string(),
        };
        ugr_cache.push((dist.clone(), v.clone()));
        v
    };
    let luminaires: Vec<Luminaire> = scene
        .lights
        .iter()
        .zip(&scene.light_names)
        .enumerate()
        .map(|(k, (l, name))| {
            // The scene file's entry: the one of this name, else the k-th.
            let d = desc.and_then(|d| {
                d.light
                    .iter()
                    .find(|x| {
                        x.get_ref()
                            .name
                            .as_ref()
                            .is_some_and(|n| n.get_ref() == name)
                    })
                    .or(d.light.get(k))
                    .map(|x| x.get_ref())
            });
            Luminaire {
                name: name.clone(),
                kind: d.map_or(String::new(), |d| d.kind.get_ref().clone()),
                flux: sig(l.power(), 5),
                file: d
                    .and_then(|d| d.file.as_ref())
                    .map_or(String::new(), |f| f.get_ref().clone()),
                ugr_ref: reference(l),
            }
        })
        .collect();
    let total: f64 = scene.lights.iter().map(|l| l.power()).sum();
    let rms = r.tallies.rms_rel_error(&r.direct);
    let max = r.tallies.max_rel_error(&r.direct);
    let mut flags = std::collections::BTreeMap::new();
    for j in 0..r.direct.len() {
        let flag = r.tallies.diagnostics(j, r.direct[j]).flag();
        if flag != "ok" {
            for f in flag.split(';') {
                *flags.entry(f.to_string()).or_insert(0usize) += 1;
            }
        }
    }
    let mut run = vec![
        ("receivers".to_string(), r.direct.len().to_string()),
        ("chains".into(), r.chains.to_string()),
        (
            "batches".into(),
            format!("{} of {} chains", r.tallies.batches(), r.batch_size),
        ),
        ("seed".into(), cfg.seed.to_string()),
        ("wall time [s]".into(), format!("{:.3}", r.wall)),
        ("threads".into(), r.threads.to_string()),
        ("stopped by".into(), format!("{:?}", r.reason)),
        ("relative standard error, RMS".into(), format!("{rms:.3e}")),
        ("relative standard error, max".into(), format!("{max:.3e}")),
    ];
    if let Some(p) = &r.pilot {
        run.push((
            if p.rms {
                "target RMS relative error"
            } else {
                "target max relative error"
            }
            .into(),
            format!("{:.3e}", p.target),
        ));
    }
    Report {
        title: format!("lumest report: {}", scene_path.display()),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        program: format!("lumest {}", env!("CARGO_PKG_VERSION")),
        scene_file: scene_path.display().to_string(),
        scene_summary: format!("{}; {} light(s)", scene.summary(), scene.lights.len()),
        scene_notes: scene.notes.clone(),
        luminaires,
        total_flux: sig(total, 5),
        points_line: job
            .points
            .as_ref()
            .and_then(|t| super::illuminance::grid_summary(r, t.rows.len())),
        grids,
        run,
        run_summary: super::illuminance::summary(r),
        flags: flags.into_iter().collect(),
    }
}
