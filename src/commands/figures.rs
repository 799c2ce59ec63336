//! Grid figures after an illuminance run: points grouped by the points
//! CSV's `grid` column (weighted by its `area` column), their figures with
//! uncertainty ([`crate::tally::surface_figures`]) and the verdicts on the
//! requirements of the scene's `[[grid]]` of the same name.

use crate::estimator::solid::Solid;
use crate::grid::Grid;
use crate::io::csvio::{InputError, display_name, number};
use crate::io::{PointTable, format_number};
use crate::run::RunResult;
use crate::tally::surface_figures::{Figure, SurfaceFigures, Verdict, surface_figures, verdict};

/// The points of one grid in a points table.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// The grid's name (the `grid` column).
    pub name: String,
    /// Its rows (receiver indices), in file order.
    pub rows: Vec<usize>,
    /// Their area weights [m^2] (1 each without an `area` column).
    pub weights: Vec<f64>,
}

/// The grids of a points table, in order of first appearance; `None`
/// without a `grid` column. A row with an empty `grid` cell belongs to no
/// grid. `area` cells must be positive and at most `(2 MAX_COORD)^2`.
pub fn grid_groups(t: &PointTable, input: &str) -> Result<Option<(Vec<Group>, bool)>, InputError> {
    let Some(gc) = t.headers.iter().position(|h| h == "grid") else {
        return Ok(None);
    };
    let ac = t.headers.iter().position(|h| h == "area");
    let rc = t.headers.iter().position(|h| h == "receiver");
    let file = || display_name(input);
    let mut groups: Vec<Group> = Vec::new();
    // Per grid: its receiver type (an unknown one is refused with the
    // receivers) and the line that set it.
    let mut kinds: Vec<(Option<Solid>, u64, &str)> = Vec::new();
    for (j, (row, &line)) in t.rows.iter().zip(&t.lines).enumerate() {
        let name = row.get(gc).map_or("", |s| s.as_str());
        if name.is_empty() {
            continue;
        }
        // One receiver type per grid: its E_avg, E_min and U0 average one
        // quantity (a grid of planar and cylindrical points gave a mean of
        // E_h and E_z, with verdicts, where the plain figures refused).
        let cell = rc.and_then(|c| row.get(c)).map_or("", String::as_str);
        let kind = Solid::parse(cell).ok().flatten();
        let at = groups.iter().position(|g| g.name == name);
        if let Some(k) = at
            && kinds[k].0 != kind
        {
            let (_, first_line, first) = kinds[k];
            let shown = |c: &str| if c.is_empty() { "planar" } else { c }.to_string();
            return Err(InputError::Field {
                file: file(),
                line,
                field: "receiver".into(),
                message: format!(
                    "grid `{name}` mixes receiver types (`{}` here, `{}` on line {first_line}): its \
                     figures would average different quantities; give each type a grid of its own",
                    shown(cell),
                    shown(first)
                ),
            });
        }
        if at.is_none() {
            kinds.push((kind, line, cell));
        }
        let w = match ac {
            Some(c) => {
                let w = number(row.get(c).map_or("", String::as_str), input, line, "area")?;
                // At most the square of the coordinate bound: sums of a
                // million cells stay finite (two cells of 1e308 m^2 made
                // the grid's area inf and its E_avg NaN).
                let max = (2.0 * crate::scene::MAX_COORD).powi(2);
                if !(w > 0.0 && w <= max) {
                    return Err(InputError::Field {
                        file: file(),
                        line,
                        field: "area".into(),
                        message: format!(
                            "an area weight must be positive and at most {max:e} [m^2], got {}",
                            format_number(w)
                        ),
                    });
                }
                w
            }
            None => 1.0,
        };
        match groups.iter_mut().find(|g| g.name == name) {
            Some(g) => {
                g.rows.push(j);
                g.weights.push(w);
            }
            None => groups.push(Group {
                name: name.to_string(),
                rows: vec![j],
                weights: vec![w],
            }),
        }
    }
    Ok(Some((groups, ac.is_none())))
}

/// The figures of one grid and the verdicts on its requirements.
#[derive(Clone, Debug)]
pub struct GridFigures {
    /// The grid's name.
    pub name: String,
    /// Points used.
    pub points: usize,
    /// Points left out (flagged `enclosed`).
    pub left_out: usize,
    /// Points used whose estimate is flagged (then no verdict is given).
    pub flagged: usize,
    /// Total weight of the points used [m^2].
    pub area: f64,
    /// Maintenance factor applied.
    pub maintenance_factor: f64,
    /// Whether the scene has a `[[grid]]` of this name (else factor 1, no requirements).
    pub in_scene: bool,
    /// The figures (None when every point was left out).
    pub figures: Option<SurfaceFigures>,
    /// Required `E_avg` \[lx\] and its verdict.
    pub em: Option<(f64, Verdict)>,
    /// Required `U0` and its verdict.
    pub u0: Option<(f64, Verdict)>,
}

/// A verdict, withheld (undecided) when some point is flagged.
fn judged(f: &Figure, required: f64, flagged: usize) -> Verdict {
    match verdict(f.ci95, required) {
        _ if flagged > 0 => Verdict::Undecided,
        v => v,
    }
}

/// The figures of every group of a run whose first receivers are the points.
pub fn grid_figures(r: &RunResult, groups: &[Group], grids: &[Grid]) -> Vec<GridFigures> {
    let bm = &r.tallies.batch_means;
    groups
        .iter()
        .enumerate()
        .map(|(gi, g)| {
            let spec = grids.iter().find(|s| s.name == g.name);
            let factor = spec.map_or(1.0, |s| s.maintenance_factor);
            let enclosed = |j: usize| r.tallies.enclosed.get(j).copied().unwrap_or(false);
            let (rows, weights): (Vec<usize>, Vec<f64>) = g
                .rows
                .iter()
                .zip(&g.weights)
                .filter(|(j, _)| !enclosed(**j))
                .map(|(&j, &w)| (j, w))
                .unzip();
            let flagged = rows
                .iter()
                .filter(|&&j| r.tallies.diagnostics(j, r.direct[j]).flag() != "ok")
                .count();
            let figures = (!rows.is_empty())
                .then(|| surface_figures(bm, &r.direct, &rows, &weights, factor, gi as u64));
            let em = spec
                .and_then(|s| s.em)
                .zip(figures.as_ref())
                .map(|(em, f)| (em, judged(&f.e_avg, em, flagged)));
            let u0 = spec
                .and_then(|s| s.u0)
                .zip(figures.as_ref())
                .map(|(u0, f)| {
                    // No light at all: U0 = 0/0, which no longer run decides
                    // ("undecided" said to run longer).
                    let none = f.e_avg.value == 0.0 && f.e_avg.std_error == 0.0;
                    let v = if none {
                        Verdict::Undefined
                    } else {
                        judged(&f.u0, u0, flagged)
                    };
                    (u0, v)
                });
            GridFigures {
                name: g.name.clone(),
                points: rows.len(),
                left_out: g.rows.len() - rows.len(),
                flagged,
                area: weights.iter().sum(),
                maintenance_factor: factor,
                in_scene: spec.is_some(),
                figures,
                em,
                u0,
            }
        })
        .collect()
}

/// `x` to `n` significant digits, fixed notation where that is short.
pub(crate) fn sig(x: f64, n: i32) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let mag = x.abs().log10().floor() as i32;
    if !(-4..15).contains(&mag) {
        return format!("{:.*e}", (n - 1).max(0) as usize, x);
    }
    format!("{:.*}", (n - 1 - mag).max(0) as usize, x)
}

/// The summary lines of one grid's figures.
pub fn summary_lines(g: &GridFigures, equal_weights: bool) -> Vec<String> {
    let mut out = Vec::new();
    let Some(f) = &g.figures else {
        out.push(format!(
            "grid `{}`: no figures: all {} point(s) left out (flagged `enclosed`)",
            g.name, g.left_out
        ));
        return out;
    };
    let method = match f.e_min.method {
        crate::tally::surface_figures::Method::Extreme(r) => r,
        _ => 0,
    };
    out.push(format!(
        "grid `{}`: {} points, {} {}, maintenance factor {}, {} batches{}{}{}",
        g.name,
        g.points,
        sig(g.area, 4),
        if equal_weights {
            "(equal weights: no `area` column)"
        } else {
            "m^2"
        },
        format_number(g.maintenance_factor),
        f.batches,
        if g.in_scene {
            ""
        } else {
            " (no [[grid]] of this name in the scene: factor 1, no requirements)"
        },
        if g.left_out > 0 {
            format!("; {} point(s) left out: flagged `enclosed`", g.left_out)
        } else {
            String::new()
        },
        if g.flagged > 0 {
            format!(
                "; {} point(s) FLAGGED (see the _flag column): verdicts withheld",
                g.flagged
            )
        } else {
            String::new()
        },
    ));
    let line = |name: &str, unit: &str, x: &Figure, digits: i32| {
        // A ratio over E_avg or E_max = 0: no light reaches the grid.
        if !x.value.is_finite() {
            return format!("  {name} undefined: no light reaches the grid");
        }
        format!(
            "  {name} = {}{unit} (std error {}, 95 % interval {} .. {}{})",
            sig(x.value, digits),
            sig(x.std_error, 2),
            sig(x.ci95.0, digits),
            sig(x.ci95.1, digits),
            if x.method == crate::tally::surface_figures::Method::BatchMeans {
                String::new()
            } else {
                format!("; bias {}", sig(x.bias, 2))
            }
        )
    };
    out.push(line("E_avg", " lx", &f.e_avg, 5) + " [batch means]");
    out.push(
        line("E_min", " lx", &f.e_min, 5)
            + &format!(
                " [std error and bias: bootstrap over batches, {method} resamples; interval: \
                 per-point t bounds]"
            ),
    );
    out.push(line("E_max", " lx", &f.e_max, 5));
    out.push(line("U0 = E_min/E_avg", "", &f.u0, 4));
    out.push(line("Ud = E_min/E_max", "", &f.ud, 4));
    let mut reqs = Vec::new();
    if let Some((em, v)) = g.em {
        reqs.push(format!("Em >= {} lx: {}", format_number(em), v.name()));
    }
    if let Some((u0, v)) = g.u0 {
        reqs.push(format!("U0 >= {}: {}", format_number(u0), v.name()));
    }
    if !reqs.is_empty() {
        // A verdict over fewer points than the grid has says so.
        let over = if g.left_out > 0 {
            format!(
                " (judged on {} of {} points: {} flagged `enclosed` left out)",
                g.points,
                g.points + g.left_out,
                g.left_out
            )
        } else {
            String::new()
        };
        out.push(format!("  requirements: {}{over}", reqs.join("; ")));
    }
    out
}

/// Columns of the `--figures-out` CSV.
pub const FIGURE_COLUMNS: [&str; 17] = [
    "grid",
    "figure",
    "unit",
    "value",
    "std_error",
    "ci95_low",
    "ci95_high",
    "bias",
    "method",
    "required",
    "verdict",
    "points",
    "left_out",
    "flagged",
    "area",
    "maintenance_factor",
    "batches",
];

/// The `--figures-out` rows: one per figure of each grid.
pub fn figure_rows(all: &[GridFigures]) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for g in all {
        let Some(f) = &g.figures else { continue };
        let figs = [
            ("E_avg", "lx", &f.e_avg, g.em),
            ("E_min", "lx", &f.e_min, None),
            ("E_max", "lx", &f.e_max, None),
            ("U0", "1", &f.u0, g.u0),
            ("Ud", "1", &f.ud, None),
        ];
        for (name, unit, x, req) in figs {
            let mut row = vec![g.name.clone(), name.to_string(), unit.to_string()];
            // An undefined figure (U0 of a grid no light reaches) is an
            // empty cell, never `NaN` written as a number.
            let cell = |v: f64| {
                if v.is_finite() {
                    format_number(v)
                } else {
                    String::new()
                }
            };
            row.extend([x.value, x.std_error, x.ci95.0, x.ci95.1, x.bias].map(cell));
            row.push(x.method.name());
            match req {
                Some((v, verdict)) => {
                    row.push(format_number(v));
                    row.push(verdict.name().to_string());
                }
                None => row.extend([String::new(), String::new()]),
            }
            row.extend([
                g.points.to_string(),
                g.left_out.to_string(),
                g.flagged.to_string(),
                cell(g.area),
                format_number(g.maintenance_factor),
                f.batches.to_string(),
            ]);
            rows.push(row);
        }
    }
    rows
}
