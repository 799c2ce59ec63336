//! `lumest glare`: the Unified Glare Rating (CIE 117) at observers given
//! by a CSV of eye positions and lines of sight, with the background
//! luminance from the local estimate of the indirect illuminance at each
//! eye ([`crate::glare`]).

use super::outputs::check_outputs;
use super::{RunArgs, progress_bar, tick};
use crate::estimator::{Receiver, Receivers};
use crate::glare::{
    GlareTerm, LuminousArea, OMEGA_RANGE, Observer, Ugr, glare_term, luminous_area,
};
use crate::io::csvio::stage_csv;
use crate::io::{format_number, read_views};
use crate::run::RunResult;
use crate::scene::{self, Scene};
use crate::tally::t_factor;
use anyhow::Context;
use clap::Args;
use std::path::Path;

/// Arguments of `lumest glare`.
#[derive(Args, Clone, Debug)]
pub struct GlareArgs {
    /// Scene file (TOML).
    #[arg(long)]
    pub scene: std::path::PathBuf,
    /// Observers CSV: eye position `x,y,z` (m) and line of sight
    /// `dx,dy,dz` (not vertical), optionally a `name` column (`-`: stdin).
    /// Without it, the scene file's `[[observer]]` tables (`name`, `eye`,
    /// `view`).
    #[arg(long)]
    pub observers: Option<String>,
    /// Output CSV, one row per observer (`-`: standard output).
    #[arg(long)]
    pub out: String,
    /// Also write each luminaire's share per observer (L, omega, the seen fraction of its luminous area, p) to this CSV.
    #[arg(long = "terms-out")]
    pub terms_out: Option<String>,
    /// A UGR limit (EN 12464-1: 19 for offices): adds a `UGR_verdict`
    /// column, `met` when the 95 % interval lies wholly at or below it,
    /// `not met` when wholly above, else `undecided`.
    #[arg(long = "ugr-limit", allow_negative_numbers = true)]
    pub ugr_limit: Option<f64>,
    #[command(flatten)]
    pub run: RunArgs,
}

/// Result columns of `lumest glare`.
pub const GLARE_COLUMNS: [&str; 12] = [
    "UGR",
    "UGR_stderr",
    "UGR_ci95_low",
    "UGR_ci95_high",
    "Lb",
    "Lb_stderr",
    "E_ind",
    "E_ind_stderr",
    "E_direct",
    "luminaires",
    "glare_sum",
    "UGR_flag",
];

/// The glare of one observer.
#[derive(Clone, Debug)]
pub struct ObserverGlare {
    /// The rating with its uncertainty.
    pub ugr: Ugr,
    /// Indirect vertical illuminance at the eye \[lx\] and its standard error.
    pub e_ind: (f64, f64),
    /// Direct vertical illuminance at the eye \[lx\] (exact plus sampled).
    pub e_direct: f64,
    /// The luminaires that count.
    pub terms: Vec<GlareTerm>,
    /// `ok`, or the reasons to doubt the rating, `;`-separated.
    pub flag: String,
}

/// The luminous area of every light (None: not a luminaire), refusing
/// lights without one by name.
pub fn luminaires(scene: &Scene) -> anyhow::Result<Vec<Option<LuminousArea>>> {
    scene
        .lights
        .iter()
        .zip(&scene.light_names)
        .map(|(l, name)| luminous_area(l).map_err(|e| anyhow::anyhow!("{name}: {e}")))
        .collect()
}

/// The glare at every observer from a run whose receivers `0..n` are the
/// observers' eyes facing their lines of sight.
pub fn observer_glare(
    scene: &Scene,
    areas: &[Option<LuminousArea>],
    observers: &[Observer],
    r: &RunResult,
) -> Vec<ObserverGlare> {
    let t = &r.tallies;
    observers
        .iter()
        .enumerate()
        .map(|(j, obs)| {
            let w = &t.estimated[j];
            let sampled = t.sampled_direct.get(j);
            // The indirect part is the estimate less the sampled direct
            // light; without per-batch values of the difference its error
            // is bounded by the sum of the two (sd(X - Y) <= sd X + sd Y).
            let e_ind = w.mean() - sampled.map_or(0.0, |s| s.mean());
            let se = w.std_error() + sampled.map_or(0.0, |s| s.std_error());
            let e_direct = r.direct[j] + sampled.map_or(0.0, |s| s.mean());
            let terms: Vec<GlareTerm> = areas
                .iter()
                .enumerate()
                .filter_map(|(k, a)| a.as_ref().and_then(|a| glare_term(scene, k, a, obs)))
                .collect();
            let sum: f64 = terms.iter().map(GlareTerm::value).sum();
            let ugr = Ugr::from_parts(sum, e_ind, se, t_factor(0.95, w.count()));
            let mut flags = Vec::new();
            let diag = t.diagnostics(j, r.direct[j]).flag();
            if diag != "ok" {
                flags.push(diag);
            }
            if terms.is_empty() {
                flags.push("no_luminaire".to_string());
            }
            if e_ind <= 0.0 {
                flags.push("no_background".to_string());
            }
            if ugr.ci95.is_some_and(|c| c.1.is_none()) {
                flags.push("unbounded".to_string());
            }
            if terms.iter().any(|x| x.omega < OMEGA_RANGE.0) {
                flags.push("small_source".to_string());
            }
            if terms.iter().any(|x| x.omega > OMEGA_RANGE.1) {
                flags.push("large_source".to_string());
            }
            ObserverGlare {
                ugr,
                e_ind: (e_ind, se),
                e_direct,
                terms,
                flag: if flags.is_empty() {
                    "ok".to_string()
                } else {
                    flags.join(";")
                },
            }
        })
        .collect()
}

/// The result cells of one observer ([`GLARE_COLUMNS`]); undefined values empty.
pub fn glare_cells(g: &ObserverGlare) -> Vec<String> {
    let opt = |x: Option<f64>| x.map_or(String::new(), format_number);
    let u = &g.ugr;
    vec![
        opt(u.value),
        opt(u.std_error),
        opt(u.ci95.map(|c| c.0)),
        opt(u.ci95.and_then(|c| c.1)),
        format_number(u.lb),
        format_number(u.lb_std_error),
        format_number(g.e_ind.0),
        format_number(g.e_ind.1),
        format_number(g.e_direct),
        g.terms.len().to_string(),
        format_number(u.sum),
        g.flag.clone(),
    ]
}

/// The verdict on `UGR <= limit` from the rating's 95 % interval (an
/// undefined rating, or a flagged one, is `undecided`: a flagged result is
/// not a passed one).
pub fn ugr_verdict(g: &ObserverGlare, limit: f64) -> &'static str {
    match g.ugr.ci95 {
        _ if g.flag != "ok" => "undecided",
        Some((lo, _)) if lo > limit => "not met",
        Some((_, Some(hi))) if hi <= limit => "met",
        _ => "undecided",
    }
}

/// Run `lumest glare`.
pub fn glare(a: &GlareArgs) -> anyhow::Result<()> {
    let referenced = scene::referenced_files(&a.scene);
    let mut inputs = vec![a.scene.as_path()];
    if let Some(o) = &a.observers {
        inputs.push(Path::new(o));
    }
    inputs.extend(referenced.iter().map(|p| p.as_path()));
    let mut outputs = vec![("--out", Path::new(&a.out))];
    if let Some(t) = &a.terms_out {
        outputs.push(("--terms-out", Path::new(t)));
    }
    check_outputs(&inputs, &outputs)?;
    if let Some(l) = a.ugr_limit {
        anyhow::ensure!(l.is_finite(), "--ugr-limit must be a finite number");
    }
    anyhow::ensure!(
        a.run.checkpoint.is_none() && a.run.resume.is_none() && !a.run.daylight_factor,
        "lumest glare takes no --checkpoint, --resume or --daylight-factor"
    );
    let cfg = a.run.config()?;
    let scene = scene::load(&a.scene)?;
    let areas = luminaires(&scene)?;
    anyhow::ensure!(
        areas.iter().any(Option::is_some),
        "{}: the scene has no luminaire (only lights at infinity): no glare rating",
        a.scene.display()
    );
    let scene_name = a.scene.display().to_string();
    let (table, name) = match &a.observers {
        Some(o) => {
            let table = read_views(o)?;
            anyhow::ensure!(!table.views.is_empty(), "{o}: no observers");
            (table, if o == "-" { "<stdin>" } else { o.as_str() })
        }
        None => {
            let table = crate::glare::scene_observers::scene_observers(&a.scene)?;
            anyhow::ensure!(
                !table.views.is_empty(),
                "{scene_name}: no observers: give --observers O.csv or [[observer]] tables \
                 (eye, view) in the scene file"
            );
            (table, scene_name.as_str())
        }
    };
    // Result column names in the input are refused before the run (a
    // `UGR_verdict` column with --ugr-limit gave the output two of them).
    let verdict = a.ugr_limit.is_some().then_some("UGR_verdict");
    if let Some(h) = table
        .headers
        .iter()
        .find(|h| GLARE_COLUMNS.contains(&h.as_str()) || verdict == Some(h.as_str()))
    {
        anyhow::bail!("{name}: column `{h}` has the name of a result column; rename it");
    }
    let mut observers = Vec::with_capacity(table.views.len());
    for (&(o, d), &line) in table.views.iter().zip(&table.lines) {
        let obs = Observer::new(o, d).ok_or_else(|| {
            anyhow::anyhow!(
                "{name}:{line}: field `dz`: the line of sight must not be vertical (the position \
                 index is measured from the observer's up direction)"
            )
        })?;
        observers.push(obs);
    }
    let rec: Vec<Receiver> = observers
        .iter()
        .map(|o| Receiver::illuminance(o.eye, o.view))
        .collect();
    let receivers = Receivers::from_receivers(&scene, &rec)
        .map_err(|e| anyhow::anyhow!("{name}:{}: {}", table.lines[e.index], e.message))?;
    eprintln!("lumest: scene {}: {}", a.scene.display(), scene.summary());
    let pb = progress_bar(&cfg, a.run.quiet);
    crate::io::interrupt::install();
    let mut observe = |p: &crate::run::Progress| {
        tick(&pb, &cfg, p);
        !crate::io::interrupt::interrupted()
    };
    let result = crate::estimator::local::run(&scene, &receivers, &cfg, &mut observe);
    pb.finish_and_clear();
    anyhow::ensure!(
        result.tallies.batches() >= 2,
        "interrupted before 2 batches were complete: nothing written"
    );
    let glare = observer_glare(&scene, &areas, &observers, &result);
    let mut headers = table.headers.clone();
    headers.extend(GLARE_COLUMNS.map(String::from));
    if a.ugr_limit.is_some() {
        headers.push("UGR_verdict".to_string());
    }
    let rows = table.rows.iter().zip(&glare).map(|(row, g)| {
        let mut c = row.clone();
        c.resize(table.headers.len(), String::new());
        c.extend(glare_cells(g));
        if let Some(l) = a.ugr_limit {
            c.push(ugr_verdict(g, l).to_string());
        }
        c
    });
    let mut staged = vec![(
        stage_csv(&a.out, &headers, rows)
            .with_context(|| format!("writing {}", a.out))?
            .0,
        a.out.as_str(),
    )];
    if let Some(path) = &a.terms_out {
        let h: Vec<String> = [
            "observer", "light", "L", "omega", "seen", "p", "distance", "term",
        ]
        .map(String::from)
        .to_vec();
        let rows = glare.iter().enumerate().flat_map(|(j, g)| {
            let scene = &scene;
            g.terms.iter().map(move |x| {
                vec![
                    (j + 1).to_string(),
                    scene.light_names[x.light].clone(),
                    format_number(x.l),
                    format_number(x.omega),
                    format_number(x.seen),
                    format_number(x.p),
                    format_number(x.d),
                    format_number(x.value()),
                ]
            })
        });
        let (file, _) = stage_csv(path, &h, rows).with_context(|| format!("writing {path}"))?;
        staged.push((file, path.as_str()));
    }
    for (file, out) in staged {
        file.commit().with_context(|| format!("writing {out}"))?;
    }
    for line in super::illuminance::summary(&result).lines() {
        eprintln!("lumest: {line}");
    }
    let name_col = table.headers.iter().position(|h| h == "name");
    for (j, g) in glare.iter().enumerate() {
        let who = name_col
            .and_then(|c| table.rows[j].get(c).cloned())
            .unwrap_or_else(|| format!("#{}", j + 1));
        let rating = match (g.ugr.value, g.ugr.std_error, g.ugr.ci95) {
            (Some(v), Some(se), Some((lo, hi))) => format!(
                "UGR {v:.2} (std error {se:.2e}, 95 % interval {lo:.2} .. {})",
                hi.map_or("unbounded".to_string(), |h| format!("{h:.2}"))
            ),
            _ => "UGR undefined".to_string(),
        };
        let verdict = a.ugr_limit.map_or(String::new(), |l| {
            format!("; UGR <= {l}: {}", ugr_verdict(g, l))
        });
        eprintln!(
            "lumest: observer {who}: {rating}; Lb {:.4e} cd/m^2 (E_ind {:.4e} +- {:.2e} lx), {} luminaire(s) in view; {}{verdict}",
            g.ugr.lb,
            g.e_ind.0,
            g.e_ind.1,
            g.terms.len(),
            g.flag
        );
    }
    eprintln!("lumest: wrote {}", a.out);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glare_of(e: f64, se: f64, flag: &str) -> ObserverGlare {
        ObserverGlare {
            ugr: Ugr::from_parts(1e5, e, se, 2.0),
            e_ind: (e, se),
            e_direct: 0.0,
            terms: Vec::new(),
            flag: flag.to_string(),
        }
    }

    /// Met only when the whole interval is at or below the limit, not met
    /// when wholly above; flagged or unbounded ratings stay undecided.
    #[test]
    fn verdicts() {
        // UGR = 8 log10(0.25 pi 1e5 / 100) = 23.58, interval about +-0.07.
        let g = glare_of(100.0, 1.0, "ok");
        let (lo, hi) = g.ugr.ci95.unwrap();
        assert_eq!(ugr_verdict(&g, hi.unwrap()), "met");
        assert_eq!(ugr_verdict(&g, hi.unwrap() - 1e-9), "undecided");
        assert_eq!(ugr_verdict(&g, lo - 1e-9), "not met");
        assert_eq!(ugr_verdict(&g, 19.0), "not met");
        assert_eq!(
            ugr_verdict(&glare_of(100.0, 1.0, "small_source"), 30.0),
            "undecided"
        );
        assert_eq!(
            ugr_verdict(&glare_of(1.0, 1.0, "unbounded"), 30.0),
            "undecided"
        );
        assert_eq!(
            ugr_verdict(&glare_of(0.0, 0.0, "no_background"), 30.0),
            "undecided"
        );
    }
}
