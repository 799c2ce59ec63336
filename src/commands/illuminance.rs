//! `lumest illuminance`: illuminance at CSV points by the local estimate.

use super::{RunArgs, progress_bar, tick};
use crate::estimator::Receivers;
use crate::io::csvio::to_csv;
use crate::io::{format_number, read_points, write_atomic};
use crate::run::{RunResult, run};
use crate::scene;
use crate::tally::{figure_of_merit, t_factor};
use anyhow::Context;
use clap::Args;
use std::path::PathBuf;

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
    #[command(flatten)]
    pub run: RunArgs,
}

/// Result columns for one point, in lux.
pub fn result_headers(orders: u32) -> Vec<String> {
    let mut h: Vec<String> = [
        "E",
        "E_stderr",
        "E_direct",
        "E_indirect",
        "E_rel_err",
        "E_ci95",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if orders > 0 {
        for k in 1..=orders {
            h.push(format!("E_order{k}"));
            h.push(format!("E_order{k}_stderr"));
        }
        h.push("E_rest".into());
        h.push("E_rest_stderr".into());
    }
    h
}

/// Result cells of point `j`.
pub fn result_cells(r: &RunResult, j: usize) -> Vec<String> {
    let w = &r.tallies.indirect[j];
    let e = r.direct[j] + w.mean();
    let se = w.std_error();
    let ci = t_factor(0.95, w.count()) * se;
    let mut c = vec![
        format_number(e),
        format_number(se),
        format_number(r.direct[j]),
        format_number(w.mean()),
        format_number(crate::tally::relative_error(e, se)),
        format_number(ci),
    ];
    for bucket in &r.tallies.orders {
        c.push(format_number(bucket[j].mean()));
        c.push(format_number(bucket[j].std_error()));
    }
    c
}

/// The run summary printed to standard error.
pub fn summary(r: &RunResult) -> String {
    let rms = r.tallies.rms_rel_error(&r.direct);
    let max = r.tallies.max_rel_error(&r.direct);
    format!(
        "{} points, {} chains in {} batches of {}, {:.3} s on {} thread(s), stopped by {:?}\n\
         {:.4e} chains/s, {:.4e} scores/s, {:.3} collisions/chain\n\
         relative standard error of E: RMS {:.3e}, max {:.3e}; FOM = 1/(R_rms^2 T) = {:.4e} 1/s",
        r.direct.len(),
        r.chains,
        r.tallies.batches(),
        r.batch_size,
        r.wall,
        r.threads,
        r.reason,
        r.chains as f64 / r.wall,
        r.scores as f64 / r.wall,
        r.collisions as f64 / r.chains.max(1) as f64,
        rms,
        max,
        figure_of_merit(rms, r.wall),
    )
}

/// Run the command.
pub fn illuminance(args: &IlluminanceArgs) -> anyhow::Result<()> {
    let cfg = args.run.config()?;
    let scene = scene::load(&args.scene)?;
    let table = read_points(&args.points)?;
    let receivers = Receivers::new(&scene, &table.points)
        .map_err(|e| anyhow::anyhow!("{}:{}: {}", args.points, table.lines[e.index], e.message))?;
    eprintln!(
        "lumest: scene {}: {}",
        args.scene.display(),
        scene.summary()
    );
    let pb = progress_bar(&cfg, args.run.quiet);
    let result = run(&scene, &receivers, &cfg, &mut |p| {
        tick(&pb, &cfg, p);
        true
    });
    pb.finish_and_clear();
    let mut headers = table.headers.clone();
    headers.extend(result_headers(cfg.orders));
    let rows: Vec<Vec<String>> = table
        .rows
        .iter()
        .enumerate()
        .map(|(j, row)| {
            let mut r = row.clone();
            r.resize(table.headers.len(), String::new());
            r.extend(result_cells(&result, j));
            r
        })
        .collect();
    write_atomic(&args.out, &to_csv(&headers, &rows))
        .with_context(|| format!("writing {}", args.out))?;
    for line in summary(&result).lines() {
        eprintln!("lumest: {line}");
    }
    Ok(())
}
