//! `lumest grid`: the points of a scene's calculation surfaces (`[[grid]]`
//! tables) as a points CSV for `lumest illuminance`.

use super::outputs::check_outputs;
use crate::grid::Grid;
use crate::io::csvio::stage_csv;
use crate::io::format_number;
use anyhow::Context;
use clap::Args;
use std::path::{Path, PathBuf};

/// Arguments of `lumest grid`.
#[derive(Args, Clone, Debug)]
pub struct GridArgs {
    /// Scene file (TOML) with `[[grid]]` tables.
    #[arg(long)]
    pub scene: PathBuf,
    /// Only the grid of this name (default: every grid).
    #[arg(long)]
    pub name: Option<String>,
    /// Output points CSV (`-`: standard output).
    #[arg(long)]
    pub out: String,
}

/// Columns of a grid points CSV: the points reader's `x,y,z,nx,ny,nz`, with
/// `id` (1, 2, ... within each grid), `grid` (its name), `area` (the
/// point's cell [m^2]) and `receiver` (its receiver type).
pub const GRID_COLUMNS: [&str; 10] = [
    "id", "grid", "x", "y", "z", "nx", "ny", "nz", "area", "receiver",
];

/// The CSV rows of grids, in [`GRID_COLUMNS`] order.
pub fn grid_rows(grids: &[Grid]) -> impl Iterator<Item = Vec<String>> + '_ {
    grids.iter().flat_map(|g| {
        g.points.iter().enumerate().map(move |(k, q)| {
            let mut row = vec![(k + 1).to_string(), g.name.clone()];
            row.extend([q.p.x, q.p.y, q.p.z, q.n.x, q.n.y, q.n.z, q.area].map(format_number));
            row.push(g.receiver.clone());
            row
        })
    })
}

/// One summary line for a grid.
pub fn describe(g: &Grid) -> String {
    let mut reqs = Vec::new();
    if let Some(em) = g.em {
        reqs.push(format!("Em >= {} lx", format_number(em)));
    }
    if let Some(u0) = g.u0 {
        reqs.push(format!("U0 >= {}", format_number(u0)));
    }
    format!(
        "grid `{}`: {} points ({} x {} cells of {:.3} m x {:.3} m; {}), {:.4} m^2, receiver {}, maintenance factor {}{}",
        g.name,
        g.points.len(),
        g.cells.0,
        g.cells.1,
        g.cell_size.0,
        g.cell_size.1,
        g.rule,
        g.area(),
        g.receiver,
        format_number(g.maintenance_factor),
        if reqs.is_empty() {
            String::new()
        } else {
            format!(", requires {}", reqs.join(" and "))
        }
    )
}

/// A solid receiver (cylindrical, semicylindrical, hemispherical,
/// spherical) on a surface would lie partly inside it, and `lumest
/// illuminance` refuses it. Grid `g`'s points of such a type that lie on a
/// surface of `scene` (a cylindrical grid at 1.2 m over a cabinet 1.2 m
/// tall) are left out, and the note returned says how many; a grid all of
/// whose points lie on surfaces (a hemispherical grid on the road itself)
/// is refused.
fn leave_out_points_on_surfaces(
    scene: &crate::scene::Scene,
    g: &mut Grid,
) -> anyhow::Result<Option<String>> {
    let Ok(Some(kind)) = crate::estimator::solid::Solid::parse(&g.receiver) else {
        return Ok(None);
    };
    let before = g.points.len();
    g.points.retain(|q| !scene.on_surface(q.p));
    let left_out = before - g.points.len();
    anyhow::ensure!(
        before == 0 || !g.points.is_empty(),
        "{}: field `receiver`: grid `{}`: every point lies on a surface, where a {} receiver would \
         be partly inside it: give the [[grid]] an `offset` (such as 0.001 m) or another height",
        g.receiver_at,
        g.name,
        kind.name()
    );
    Ok((left_out > 0).then(|| {
        format!(
            "grid `{}`: {left_out} of its {before} points lie on a surface (furniture, a wall), \
             where a {} receiver would be partly inside it: left out",
            g.name,
            kind.name()
        )
    }))
}

/// Run `lumest grid`.
pub fn grid(a: &GridArgs) -> anyhow::Result<()> {
    // The scene and every file it names (photometric files, meshes, SH
    // coefficients): `--out pendant.ies` used to replace the luminaire.
    let referenced = crate::scene::referenced_files(&a.scene);
    let mut inputs = vec![a.scene.as_path()];
    inputs.extend(referenced.iter().map(|p| p.as_path()));
    check_outputs(&inputs, &[("--out", Path::new(&a.out))])?;
    // The scene must compile: a grid on a scene that does not is no use.
    let scene = crate::scene::load(&a.scene)?;
    let mut grids = crate::grid::load(&a.scene)?;
    anyhow::ensure!(
        !grids.is_empty(),
        "{}: the scene has no [[grid]] table",
        a.scene.display()
    );
    if let Some(name) = &a.name {
        let names: Vec<String> = grids.iter().map(|g| format!("`{}`", g.name)).collect();
        grids.retain(|g| &g.name == name);
        anyhow::ensure!(
            !grids.is_empty(),
            "--name {name}: no grid of that name in {} (grids: {})",
            a.scene.display(),
            names.join(", ")
        );
    }
    let mut notes = Vec::new();
    for g in &mut grids {
        if let Some(note) = leave_out_points_on_surfaces(&scene, g)? {
            notes.push(note);
        }
    }
    let headers: Vec<String> = GRID_COLUMNS.map(String::from).to_vec();
    let (staged, n) = stage_csv(&a.out, &headers, grid_rows(&grids))
        .with_context(|| format!("writing {}", a.out))?;
    staged
        .commit()
        .with_context(|| format!("writing {}", a.out))?;
    for g in &grids {
        eprintln!("lumest: {}", describe(g));
    }
    for note in notes {
        eprintln!("lumest: {note}");
    }
    let out = if a.out == "-" { "<stdout>" } else { &a.out };
    eprintln!("lumest: {n} points written to {out}");
    Ok(())
}
