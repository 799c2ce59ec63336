//! Calculation surfaces: the `[[grid]]` tables of a scene file, turned into
//! lists of points with their normals and area weights.
//!
//! A grid is a flat patch (a rectangle given by `corner`, `edge1`, `edge2`,
//! or a named rectangle, disc or box face of the scene) shifted by `offset`
//! along its normal, cut into cells by the EN 12464-1 rule ([`spacing`]) or
//! a given `spacing`, less a `border` band along its edges; or a road field
//! cut by the EN 13201-3 rule ([`road`]). The points are the cell centres,
//! each weighted by its cell's area [m^2]. A disc's grid keeps the cells of
//! its bounding square whose centres lie on the disc (less the border).
//!
//! Each grid carries a receiver type name (stored and passed through), and
//! the requirements its figures are checked against: the maintained
//! average illuminance `em` \[lx\], the uniformity `u0`, and the maintenance
//! factor applied to the computed illuminance.

pub mod contour;
pub mod lattice;
pub mod road;
pub mod spacing;
mod surface;

use crate::scene::SceneError;
use crate::scene::compile::SourceCtx;
use crate::scene::desc::{GridDesc, SceneDesc};
use glam::DVec3;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

pub use surface::Patch;

/// Receiver type names a grid may give (the `receiver` column).
pub const RECEIVERS: [&str; 5] = crate::estimator::RECEIVER_TYPES;

/// Most points one grid may have.
pub const MAX_GRID_POINTS: usize = 1_000_000;

/// One calculation point of a grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPoint {
    /// Position \[m\].
    pub p: DVec3,
    /// Unit normal (the side the point faces).
    pub n: DVec3,
    /// Area weight: the area of the point's cell [m^2].
    pub area: f64,
}

/// A compiled calculation surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// The grid's name.
    pub name: String,
    /// Receiver type name of its points (one of [`RECEIVERS`]).
    pub receiver: String,
    /// Where its `receiver` key (or, without one, its `name`) stands in
    /// the scene file, as `file:line:column`, for messages about it.
    pub receiver_at: String,
    /// The points, row by row (along the first edge first).
    pub points: Vec<GridPoint>,
    /// Cells along the first and second edge (before a disc drops corners).
    pub cells: (usize, usize),
    /// Cell sides along the first and second edge \[m\].
    pub cell_size: (f64, f64),
    /// Required maintained average illuminance \[lx\], if any.
    pub em: Option<f64>,
    /// Required uniformity `U0 = E_min / E_avg`, if any.
    pub u0: Option<f64>,
    /// Maintenance factor applied to the computed illuminance (0, 1].
    pub maintenance_factor: f64,
    /// How the cells were sized, for the summary.
    pub rule: String,
}

impl Grid {
    /// Total area of the cells [m^2].
    pub fn area(&self) -> f64 {
        self.points.iter().map(|q| q.area).sum()
    }
}

/// Read the `[[grid]]` tables of a scene file.
pub fn load(path: &Path) -> Result<Vec<Grid>, SceneError> {
    let src = std::fs::read_to_string(path).map_err(|reason| SceneError::Io {
        file: path.to_path_buf(),
        reason,
    })?;
    parse(&src, path)
}

/// The `[[grid]]` tables of scene text `src` (`file` names it in messages).
pub fn parse(src: &str, file: &Path) -> Result<Vec<Grid>, SceneError> {
    let ctx = SourceCtx { src, file };
    let desc = crate::scene::parse_desc(src, file)?;
    let mut grids: Vec<Grid> = Vec::new();
    for g in &desc.grid {
        let grid = compile(&desc, g.get_ref(), &ctx)?;
        if grids.iter().any(|h| h.name == grid.name) {
            return Err(invalid(
                &ctx,
                g.get_ref().name.span(),
                "name",
                format!(
                    "a second grid named `{}`; grid names must be unique",
                    grid.name
                ),
            ));
        }
        grids.push(grid);
    }
    Ok(grids)
}

/// An out-of-range value, with its line and field.
pub(crate) fn invalid(
    ctx: &SourceCtx,
    span: Range<usize>,
    field: &str,
    message: impl Into<String>,
) -> SceneError {
    let (line, column) = ctx.line_col(span.start);
    SceneError::Invalid {
        file: ctx.file.to_path_buf(),
        line,
        column,
        field: field.to_string(),
        message: message.into(),
    }
}

/// A finite number, optionally bounded below (strictly or not) and above.
fn number(
    ctx: &SourceCtx,
    v: &Spanned<f64>,
    field: &str,
    ok: impl Fn(f64) -> bool,
    want: &str,
) -> Result<f64, SceneError> {
    let x = *v.get_ref();
    if x.is_finite() && ok(x) {
        Ok(x)
    } else {
        Err(invalid(
            ctx,
            v.span(),
            field,
            format!("must be {want}, got {}", crate::io::format_number(x)),
        ))
    }
}

/// Compile one `[[grid]]` table.
fn compile(scene: &SceneDesc, g: &GridDesc, ctx: &SourceCtx) -> Result<Grid, SceneError> {
    let name = g.name.get_ref().trim().to_string();
    if name.is_empty() {
        return Err(invalid(ctx, g.name.span(), "name", "must not be empty"));
    }
    let kind = g.kind.as_ref().map_or("area", |k| k.get_ref().as_str());
    let offset = g
        .offset
        .as_ref()
        .map(|v| number(ctx, v, "offset", |_| true, "a finite length [m]"))
        .transpose()?
        .unwrap_or(0.0);
    let receiver = match &g.receiver {
        Some(r) if !RECEIVERS.contains(&r.get_ref().as_str()) => {
            return Err(invalid(
                ctx,
                r.span(),
                "receiver",
                format!(
                    "unknown receiver type `{}` (one of {})",
                    r.get_ref(),
                    RECEIVERS.join(", ")
                ),
            ));
        }
        Some(r) => r.get_ref().clone(),
        None => "planar".to_string(),
    };
    let em =
        g.em.as_ref()
            .map(|v| number(ctx, v, "em", |x| x >= 0.0, "an illuminance >= 0 [lx]"))
            .transpose()?;
    let u0 =
        g.u0.as_ref()
            .map(|v| {
                number(
                    ctx,
                    v,
                    "u0",
                    |x| (0.0..=1.0).contains(&x),
                    "a uniformity in [0, 1]",
                )
            })
            .transpose()?;
    let maintenance_factor = g
        .maintenance_factor
        .as_ref()
        .map(|v| {
            number(
                ctx,
                v,
                "maintenance_factor",
                |x| x > 0.0 && x <= 1.0,
                "in (0, 1]",
            )
        })
        .transpose()?
        .unwrap_or(1.0);
    let mut grid = match kind {
        "area" => area_grid(scene, g, ctx, offset)?,
        "road" => road_grid(g, ctx, offset)?,
        other => {
            let span = g.kind.as_ref().map_or(g.name.span(), |k| k.span());
            return Err(invalid(
                ctx,
                span,
                "type",
                format!("unknown grid type `{other}` (`area` or `road`)"),
            ));
        }
    };
    if grid.points.len() > MAX_GRID_POINTS {
        return Err(invalid(
            ctx,
            g.name.span(),
            "spacing",
            format!(
                "grid `{name}` would have {} points; at most {MAX_GRID_POINTS} (take a larger spacing)",
                grid.points.len()
            ),
        ));
    }
    // A semicylindrical point faces a horizontal direction (its normal
    // columns), not the grid's normal.
    match (&g.facing, receiver.as_str()) {
        (Some(f), "semicylindrical") => {
            let d = DVec3::from_array(f.get_ref().0);
            // Any length: the unit direction first (1e200 overflowed to a
            // zero normal, written without an error).
            let u = crate::geometry::unit_direction(d).unwrap_or(DVec3::ZERO);
            let h = DVec3::new(u.x, u.y, 0.0);
            if !(u != DVec3::ZERO && u.z.abs() <= 1e-9) {
                return Err(invalid(
                    ctx,
                    f.span(),
                    "facing",
                    format!(
                        "must be a horizontal direction (z = 0, not zero), got [{}, {}, {}]",
                        crate::io::format_number(d.x),
                        crate::io::format_number(d.y),
                        crate::io::format_number(d.z)
                    ),
                ));
            }
            for pt in &mut grid.points {
                pt.n = h.normalize();
            }
        }
        (None, "semicylindrical") => {
            return Err(invalid(
                ctx,
                g.name.span(),
                "facing",
                "missing field (a semicylindrical grid's points face a horizontal direction, e.g. `facing = [1, 0, 0]`)",
            ));
        }
        (Some(f), _) => {
            return Err(invalid(
                ctx,
                f.span(),
                "facing",
                "only `receiver = \"semicylindrical\"` grids take it",
            ));
        }
        (None, _) => {}
    }
    let at = g.receiver.as_ref().map_or(g.name.span(), Spanned::span);
    let (line, column) = ctx.line_col(at.start);
    grid.receiver_at = format!("{}:{line}:{column}", ctx.file.display());
    grid.name = name;
    grid.receiver = receiver;
    grid.em = em;
    grid.u0 = u0;
    grid.maintenance_factor = maintenance_factor;
    Ok(grid)
}

/// Refuse a key that the grid's kind does not read.
fn refuse<T>(
    ctx: &SourceCtx,
    v: &Option<Spanned<T>>,
    field: &str,
    why: &str,
) -> Result<(), SceneError> {
    match v {
        Some(v) => Err(invalid(ctx, v.span(), field, why.to_string())),
        None => Ok(()),
    }
}

/// Refuse a negative `offset` on the named surface `s` (found, so the
/// surface's own errors come first) unless it is two-sided: a one-sided
/// surface's normal points to its lit side, and a negative offset puts the
/// grid behind it (below the floor, inside the desk); a two-sided one
/// (`sides = "both"`, a shelf) is lit on both.
fn behind_surface(
    scene: &SceneDesc,
    g: &GridDesc,
    s: &Spanned<String>,
    offset: f64,
    ctx: &SourceCtx,
) -> Result<(), SceneError> {
    let two_sided = surface::named(scene, s.get_ref())
        .iter()
        .any(|d| d.sides.as_ref().is_some_and(|x| x.get_ref() == "both"));
    match &g.offset {
        Some(v) if offset < 0.0 && !two_sided => Err(invalid(
            ctx,
            v.span(),
            "offset",
            format!(
                "{offset} m puts the grid behind `{}`, on the side its normal does not face: \
                 give an offset >= 0 (along the normal, into the lit side)",
                s.get_ref()
            ),
        )),
        _ => Ok(()),
    }
}

/// A grid over a rectangle or a named surface (EN 12464-1 cells).
fn area_grid(
    scene: &SceneDesc,
    g: &GridDesc,
    ctx: &SourceCtx,
    offset: f64,
) -> Result<Grid, SceneError> {
    refuse(
        ctx,
        &g.lanes,
        "lanes",
        "only a road grid (`type = \"road\"`) has lanes",
    )?;
    let patch = match (&g.surface, &g.corner) {
        (Some(s), None) => {
            for (v, f) in [(&g.edge1, "edge1"), (&g.edge2, "edge2")] {
                refuse(
                    ctx,
                    v,
                    f,
                    "give either `surface` or `corner`, `edge1`, `edge2`",
                )?;
            }
            let patch = surface::patch_of_surface(scene, s, ctx)?;
            behind_surface(scene, g, s, offset, ctx)?;
            patch
        }
        (None, Some(_)) => surface::patch_of_edges(g, ctx, "grid")?,
        (Some(s), Some(_)) => {
            return Err(invalid(
                ctx,
                s.span(),
                "surface",
                "give either `surface` or `corner`, `edge1`, `edge2`, not both",
            ));
        }
        (None, None) => {
            return Err(invalid(
                ctx,
                g.name.span(),
                "surface",
                "a grid needs `surface = \"NAME\"` or `corner`, `edge1`, `edge2`",
            ));
        }
    };
    let spacing = g
        .spacing
        .as_ref()
        .map(|v| number(ctx, v, "spacing", |x| x > 0.0, "a length > 0 [m]"))
        .transpose()?;
    let border = g
        .border
        .as_ref()
        .map(|v| number(ctx, v, "border", |x| x >= 0.0, "a length >= 0 [m]"))
        .transpose()?
        .unwrap_or(0.0);
    let patch = patch.inset(border).ok_or_else(|| {
        let span = g.border.as_ref().map_or(g.name.span(), |b| b.span());
        invalid(
            ctx,
            span,
            "border",
            format!(
                "a border of {} m leaves nothing of the {}",
                crate::io::format_number(border),
                patch.describe()
            ),
        )
    })?;
    // Refuse absurd counts before allocating.
    let (na, nb) = spacing::cell_counts(patch.a, patch.b, spacing);
    if na.saturating_mul(nb) > MAX_GRID_POINTS {
        let span = g.spacing.as_ref().map_or(g.name.span(), |s| s.span());
        return Err(invalid(
            ctx,
            span,
            "spacing",
            format!("{na} x {nb} cells; at most {MAX_GRID_POINTS} points (take a larger spacing)"),
        ));
    }
    let (sa, sb) = (patch.a / na as f64, patch.b / nb as f64);
    let mut points = Vec::with_capacity(na * nb);
    for j in 0..nb {
        for i in 0..na {
            let (x, y) = ((i as f64 + 0.5) * sa, (j as f64 + 0.5) * sb);
            if let Some(p) = patch.point(x, y) {
                let (x0, y0) = (i as f64 * sa, j as f64 * sb);
                points.push(GridPoint {
                    p: p + offset * patch.n,
                    n: patch.n,
                    area: patch.cell_area(x0, x0 + sa, y0, y0 + sb),
                });
            }
        }
    }
    // A disc's cells over the rim carry their part on the disc; the parts
    // of the cells left out (centre beyond the rim) are shared in
    // proportion, so that the weights sum to the disc's area.
    if let Some((_, r)) = patch.disc {
        let total: f64 = points.iter().map(|q| q.area).sum();
        if total > 0.0 {
            let k = std::f64::consts::PI * r * r / total;
            points.iter_mut().for_each(|q| q.area *= k);
        }
    }
    let rule = match spacing {
        Some(p) => format!("given spacing {} m", crate::io::format_number(p)),
        None => {
            let d = spacing::relevant_dimension(patch.a, patch.b);
            format!(
                "EN 12464-1: d = {d:.3} m, p = 0.2 x 5^log10(d) = {:.3} m",
                spacing::max_cell_size(d)
            )
        }
    };
    Ok(Grid {
        name: String::new(),
        receiver: String::new(),
        receiver_at: String::new(),
        points,
        cells: (na, nb),
        cell_size: (sa, sb),
        em: None,
        u0: None,
        maintenance_factor: 1.0,
        rule,
    })
}

/// A road field (EN 13201-3): `edge1` along the road between two
/// luminaires, `edge2` across the carriageway, `lanes` equal lanes.
fn road_grid(g: &GridDesc, ctx: &SourceCtx, offset: f64) -> Result<Grid, SceneError> {
    let why = "a road grid places its points by EN 13201-3 (no `surface`, `spacing` or `border`)";
    refuse(ctx, &g.surface, "surface", why)?;
    refuse(ctx, &g.spacing, "spacing", why)?;
    refuse(ctx, &g.border, "border", why)?;
    let patch = surface::patch_of_edges(g, ctx, "road grid")?;
    let lanes = match &g.lanes {
        Some(l) if !(1..=100).contains(l.get_ref()) => {
            return Err(invalid(
                ctx,
                l.span(),
                "lanes",
                format!("must be a whole number in [1, 100], got {}", l.get_ref()),
            ));
        }
        Some(l) => *l.get_ref() as usize,
        None => 1,
    };
    let rows = road::rows_along(patch.a);
    let across = road::POINTS_PER_LANE * lanes;
    // Refuse absurd counts before allocating.
    if rows.saturating_mul(across) > MAX_GRID_POINTS {
        let span = g.edge1.as_ref().map_or(g.name.span(), |e| e.span());
        return Err(invalid(
            ctx,
            span,
            "edge1",
            format!("{rows} x {across} points; at most {MAX_GRID_POINTS} (a shorter field)"),
        ));
    }
    let (sa, sb) = (patch.a / rows as f64, patch.b / across as f64);
    let mut points = Vec::with_capacity(rows * across);
    for j in 0..across {
        for i in 0..rows {
            let p =
                patch.origin + (i as f64 + 0.5) * sa * patch.u + (j as f64 + 0.5) * sb * patch.v;
            points.push(GridPoint {
                p: p + offset * patch.n,
                n: patch.n,
                area: sa * sb,
            });
        }
    }
    Ok(Grid {
        name: String::new(),
        receiver: String::new(),
        receiver_at: String::new(),
        points,
        cells: (rows, across),
        cell_size: (sa, sb),
        em: None,
        u0: None,
        maintenance_factor: 1.0,
        rule: format!(
            "EN 13201-3: S = {:.3} m, N = {rows}, D = {sa:.3} m; {lanes} lane(s), {} points across each, d = {sb:.3} m{}",
            patch.a,
            road::POINTS_PER_LANE,
            if sb > road::MAX_ACROSS + 1e-9 {
                format!(
                    "; WARNING: d exceeds the {} m EN 13201-3 allows across an illuminance field (lanes wider than {} m): give more lanes",
                    road::MAX_ACROSS,
                    road::MAX_ACROSS * road::POINTS_PER_LANE as f64
                )
            } else {
                String::new()
            },
        ) + if patch.n.z < 0.0 {
            // A road's points face edge1 x edge2: written the other way
            // round they face the ground (0 lx, found only when no light
            // reaches any point of the whole run).
            "; WARNING: the points face down (edge1 x edge2 points below the horizon): swap edge1 and edge2"
        } else {
            ""
        },
    })
}
