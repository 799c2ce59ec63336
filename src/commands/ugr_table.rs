//! `lumest ugr-table FILE`: a luminaire's UGR table by the tabular method
//! of CIE 117 ([`crate::glare::tabular`]), as luminaire data sheets print
//! it: 19 standard rooms by 5 reflectance sets, viewed crosswise and
//! endwise.

use crate::glare::LuminousArea;
use crate::glare::tabular::{REFLECTANCES, UgrRow, ugr_table};
use crate::io::photometry::PhotometricType;
use crate::io::write_atomic;
use crate::light::Goniometric;
use anyhow::Context;
use clap::Args;
use std::path::Path;

/// Arguments of `lumest ugr-table`.
#[derive(Args, Clone, Debug)]
pub struct UgrTableArgs {
    /// An IES (`.ies`) or EULUMDAT (`.ldt`) file of type C with a luminous
    /// opening.
    pub file: std::path::PathBuf,
    /// Luminaire spacing as a multiple of `H` (CIE 117's tables: 0.25;
    /// from 0.05 to 2).
    #[arg(long, default_value_t = 0.25)]
    pub spacing: f64,
    /// Also write the table as CSV here (`-`: standard output instead of
    /// the printed table).
    #[arg(long)]
    pub out: Option<String>,
}

/// The CSV column of reflectance set `rho` viewed `view`, e.g.
/// `crosswise_70_50_20`.
fn column(view: &str, rho: &[f64; 3]) -> String {
    format!(
        "{view}_{:.0}_{:.0}_{:.0}",
        rho[0] * 100.0,
        rho[1] * 100.0,
        rho[2] * 100.0
    )
}

/// The table as CSV: `X_H,Y_H` and one column per reflectance set and
/// view, ratings to 2 decimals.
pub fn table_csv(rows: &[UgrRow]) -> String {
    let mut s = String::from("X_H,Y_H");
    for view in ["crosswise", "endwise"] {
        for rho in &REFLECTANCES {
            s += ",";
            s += &column(view, rho);
        }
    }
    s += "\n";
    for r in rows {
        s += &format!("{},{}", r.x, r.y);
        for v in r.crosswise.iter().chain(&r.endwise) {
            s += &format!(",{v:.2}");
        }
        s += "\n";
    }
    s
}

/// The table as data sheets print it, ratings to 1 decimal.
pub fn table_text(rows: &[UgrRow]) -> String {
    let line = |label: &str, k: usize| {
        let v: Vec<String> = REFLECTANCES
            .iter()
            .map(|r| format!("{:5.2}", r[k]))
            .collect();
        format!("{label:<10}{}  |{}\n", v.join(" "), v.join(" "))
    };
    let mut s = line("ceiling", 0) + &line("walls", 1) + &line("floor", 2);
    s += &format!(
        "{:<10}{:<29}  |{}\n",
        "X   Y", " viewed crosswise", " viewed endwise"
    );
    for r in rows {
        let f = |a: &[f64; 5]| {
            a.iter()
                .map(|v| format!("{v:5.1}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        s += &format!(
            "{:<10}{}  |{}\n",
            format!("{}H {}H", r.x, r.y),
            f(&r.crosswise),
            f(&r.endwise)
        );
    }
    s
}

/// The smallest `--spacing` \[H\] accepted.
const MIN_SPACING: f64 = 0.05;

/// The first entry of the table that is not a finite rating, in words
/// (room, view, reflectances); `None` when all are finite.
fn first_undefined(rows: &[UgrRow]) -> Option<String> {
    rows.iter().find_map(|r| {
        [("crosswise", &r.crosswise), ("endwise", &r.endwise)]
            .into_iter()
            .find_map(|(view, v)| {
                let k = v.iter().position(|u| !u.is_finite())?;
                Some(format!(
                    "the {}H x {}H room viewed {view}, reflectances {}",
                    r.x,
                    r.y,
                    column(view, &REFLECTANCES[k])
                        .trim_start_matches(view)
                        .trim_start_matches('_')
                        .replace('_', "/")
                ))
            })
    })
}

/// Run `lumest ugr-table`.
pub fn ugr_table_command(a: &UgrTableArgs) -> anyhow::Result<()> {
    if let Some(out) = &a.out {
        super::outputs::check_outputs(&[a.file.as_path()], &[("--out", Path::new(out))])?;
    }
    anyhow::ensure!(
        a.spacing.is_finite() && a.spacing > 0.0,
        "--spacing {}: must be a positive number",
        crate::io::format_number(a.spacing)
    );
    // Below 0.05 H the grid grows as 1 / spacing^2 and the floor's offset
    // integral as 1 / spacing^4 (measured: 0.24 s at 0.25 H, 3.2 s at
    // 0.05 H, 23 s at 0.02 H; 0.001 H would need 3.5 GB of positions).
    anyhow::ensure!(
        (MIN_SPACING..=2.0).contains(&a.spacing),
        "--spacing {}: the tabular method here covers spacings from {MIN_SPACING} H to 2 H",
        crate::io::format_number(a.spacing)
    );
    let p = crate::io::photometry::read(&a.file)?;
    let shown = a.file.display();
    anyhow::ensure!(
        p.kind == PhotometricType::C,
        "{shown}: type {:?} photometry: UGR tables are for indoor luminaires of type C",
        p.kind
    );
    let area = LuminousArea::of_file(&p.opening).map_err(|e| anyhow::anyhow!("{shown}: {e}"))?;
    // The upright luminaire (a tilt table's factor at tilt 0).
    let g = Goniometric::new(&p, p.upright_tilt_factor());
    let rows = ugr_table(&g, &area, a.spacing);
    if let Some(bad) = first_undefined(&rows) {
        anyhow::bail!(
            "{shown}: no finite UGR for {bad}: the luminaire sends no light towards the eye \
             there (all of it upwards, or a beam too narrow), or its intensities overflow"
        );
    }
    if a.out.as_deref() != Some("-") {
        println!(
            "UGR table of {shown} (CIE 117 tabular method, Guth's position index by its \
             closed form): luminaire flux {:.1} lm, spacing {} H, with H the luminaires' height \
             above the eye (their height above the floor less 1.2 m seated, 1.7 m standing); X \
             across the line of sight, Y along it; crosswise: the line of sight across C0-C180 \
             (the luminaire's length). For a flux Phi instead, add 8 log10(Phi / {:.1}).",
            g.power(),
            a.spacing,
            g.power()
        );
        print!("{}", table_text(&rows));
    }
    if let Some(out) = &a.out {
        write_atomic(out, table_csv(&rows).as_bytes()).with_context(|| format!("writing {out}"))?;
    }
    Ok(())
}
