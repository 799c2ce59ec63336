//! `lumest bench --many-lights`: exact summation of the direct light
//! against the light array with resampled importance sampling
//! ([`crate::light::array`]) in a hall of many luminaires.
//!
//! The hall: 50 x 25 m, 5 m high, floor (rho 0.2), ceiling (0.7) and four
//! walls (0.5) as planes; `L` goniometric luminaires (`data/pendant.ies`)
//! on a regular grid 0.5 m below the ceiling, turned by 0..359 degrees;
//! 10,000 illuminance points (100 x 100) on the work plane 0.75 m above
//! the floor. For each mode the local estimator runs to an RMS relative
//! standard error of 1 % (`--rms-error 0.01`: a pilot, then a count
//! planned on the run's own first 32 batches, [`crate::run`]), and the
//! table gives the set-up time (compiling the receivers: the exact direct
//! light is summed there), the run's wall time, their sum (time to 1 %
//! RMS), chains, chains/s, the RMS relative error reached,
//! FOM = 1/(R^2 T) over the total time and the process's peak resident
//! memory after the mode (`VmHWM`: a high-water mark, so it never falls
//! from one row to the next). A run that stops at the cap (`--time`,
//! default 600 s) before 1 % has its time to 1 % projected, `t_1% =
//! setup + run (R / 0.01)^2` (errors fall like `1/sqrt(T)`); `--compare`
//! instead compares next-event estimation at backward-path vertices.

use super::bench::BenchArgs;
use super::sobolev::parse_list;
use crate::estimator::Receivers;
use crate::estimator::local::run;
use crate::light::array::DirectLights;
use crate::run::{RunConfig, Stop};
use glam::DVec3;
use std::time::Instant;

/// Hall size \[m\]: length, width, height.
const HALL: [f64; 3] = [50.0, 25.0, 5.0];

/// The hall with `n` luminaires on a grid (aspect of the hall).
fn hall(n: usize) -> anyhow::Result<crate::scene::Scene> {
    let ies = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/pendant.ies");
    anyhow::ensure!(ies.exists(), "{} not found", ies.display());
    let dir = std::env::temp_dir().join(format!("lumest-bench-ml-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    std::fs::copy(&ies, dir.join("pendant.ies"))?;
    let [lx, ly, h] = HALL;
    let plane = |p: [f64; 3], n: [f64; 3], rho: f64| {
        format!(
            "[[surface]]\ntype = \"plane\"\npoint = {p:?}\nnormal = {n:?}\n\
             material = {{ type = \"lambertian\", reflectance = {rho} }}\n"
        )
    };
    let mut src = String::new();
    src += &plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 0.2);
    src += &plane([0.0, 0.0, h], [0.0, 0.0, -1.0], 0.7);
    src += &plane([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.5);
    src += &plane([lx, 0.0, 0.0], [-1.0, 0.0, 0.0], 0.5);
    src += &plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.5);
    src += &plane([0.0, ly, 0.0], [0.0, -1.0, 0.0], 0.5);
    // Columns and rows in the hall's aspect ratio.
    let cols = ((n as f64 * lx / ly).sqrt().round() as usize).clamp(1, n);
    let rows = n.div_ceil(cols);
    for k in 0..n {
        let (i, j) = (k % cols, k / cols);
        let x = lx * (i as f64 + 0.5) / cols as f64;
        let y = ly * (j as f64 + 0.5) / rows as f64;
        src += &format!(
            "[[light]]\ntype = \"ies\"\nfile = \"pendant.ies\"\nposition = [{x}, {y}, {}]\nrotate = {}\n",
            h - 0.5,
            k % 360
        );
    }
    let path = dir.join("hall.toml");
    std::fs::write(&path, &src)?;
    let scene = crate::scene::load(&path);
    std::fs::remove_dir_all(&dir).ok();
    scene.map_err(|e| anyhow::anyhow!("{e}"))
}

/// 100 x 100 points on the work plane (0.75 m), facing up.
fn points() -> Vec<(DVec3, DVec3)> {
    let [lx, ly, _] = HALL;
    (0..10_000)
        .map(|k| {
            let (i, j) = ((k % 100) as f64, (k / 100) as f64);
            (
                DVec3::new(lx * (i + 0.5) / 100.0, ly * (j + 0.5) / 100.0, 0.75),
                DVec3::Z,
            )
        })
        .collect()
}

/// Peak resident memory of the process \[MiB\] (`VmHWM`), if the system
/// tells.
fn peak_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// `lumest bench --many-lights [L,...] --compare [--time T]`: next-event
/// estimation at backward-path vertices summed over all sources against
/// one source kept by RIS, in the same hall, on 100 of the points (every
/// 100th), `--estimator backward` for `T` seconds each (default 10):
/// paths/s, RMS relative error and FOM = 1/(R^2 T), and their ratio.
fn backward_nee(a: &BenchArgs, counts: &[f64], pts: &[(DVec3, DVec3)]) -> anyhow::Result<()> {
    let t = match &a.time {
        Some(t) => parse_list(t).map_err(|e| anyhow::anyhow!("--time: {e}"))?[0],
        None => 10.0,
    };
    let pts: Vec<(DVec3, DVec3)> = pts.iter().step_by(100).copied().collect();
    println!(
        "backward paths, {} points, {t} s per run: next-event estimation summed over all sources (exact) or one kept by RIS",
        pts.len()
    );
    println!(
        "{:>6} {:>6} {:>10} {:>11} {:>9} {:>11} {:>9}",
        "lights", "mode", "paths", "paths/s", "rms_R", "FOM", "FOM_ratio"
    );
    for &n in counts {
        let base = hall(n as usize)?;
        let mut fom = Vec::new();
        for mode in [DirectLights::Exact, DirectLights::Ris] {
            // Exact set-up at the points in both runs: only the vertices differ.
            let scene = base.clone().with_direct_lights(mode, a.ris_candidates);
            let exact = base
                .clone()
                .with_direct_lights(DirectLights::Exact, a.ris_candidates);
            let rec = Receivers::new(&exact, &pts).map_err(|e| anyhow::anyhow!("{e}"))?;
            let cfg = RunConfig::timed(a.seed, a.threads, t);
            let r = crate::backward::run(&scene, &rec, &cfg, &mut |_| true);
            let rms = r.tallies.rms_rel_error(&r.direct);
            fom.push(1.0 / (rms * rms * r.wall));
            println!(
                "{:>6} {:>6} {:>10} {:>11.4e} {:>9.3e} {:>11.4e} {:>9}",
                n,
                if mode == DirectLights::Exact {
                    "exact"
                } else {
                    "ris"
                },
                r.chains,
                r.chains as f64 / r.wall,
                rms,
                fom[fom.len() - 1],
                if fom.len() == 2 {
                    format!("{:.3}", fom[1] / fom[0])
                } else {
                    String::new()
                }
            );
        }
    }
    Ok(())
}

/// `lumest bench --many-lights [L,...]`: the table described in the module
/// docs, one pair of rows (exact, RIS) per light count.
pub fn many_lights(a: &BenchArgs, list: &str) -> anyhow::Result<()> {
    let counts = parse_list(list).map_err(|e| anyhow::anyhow!("--many-lights: {e}"))?;
    anyhow::ensure!(
        counts
            .iter()
            .all(|&n| n >= 1.0 && n.fract() == 0.0 && n <= 1e5),
        "--many-lights: every count must be a whole number from 1 to 1e5, got {list}"
    );
    let cap = match &a.time {
        Some(t) => {
            let v = parse_list(t).map_err(|e| anyhow::anyhow!("--time: {e}"))?;
            anyhow::ensure!(
                v.len() == 1 && v[0].is_finite() && v[0] > 0.0,
                "--time: one positive number of seconds (the cap of each run) with --many-lights"
            );
            v[0]
        }
        None => 600.0,
    };
    let pts = points();
    if a.compare {
        return backward_nee(a, &counts, &pts);
    }
    println!(
        "hall {} x {} x {} m (six planes), goniometric luminaires (data/pendant.ies) 0.5 m below the ceiling, \
         {} work-plane points; each run to RMS relative standard error 1 % (cap {cap} s), seed {}",
        HALL[0],
        HALL[1],
        HALL[2],
        pts.len(),
        a.seed
    );
    println!(
        "{:>6} {:>6} {:>9} {:>8} {:>9} {:>10} {:>11} {:>9} {:>11} {:>10} {:>9}",
        "lights",
        "mode",
        "setup_s",
        "run_s",
        "total_s",
        "chains",
        "chains/s",
        "rms_R",
        "FOM_total",
        "E_avg_lx",
        "peak_MiB"
    );
    let modes: Vec<DirectLights> = match a.direct_lights.as_deref() {
        None => vec![DirectLights::Exact, DirectLights::Ris],
        Some("exact") => vec![DirectLights::Exact],
        Some("ris") => vec![DirectLights::Ris],
        Some(o) => anyhow::bail!("--direct-lights: `exact` or `ris` with --many-lights, got `{o}`"),
    };
    for &n in &counts {
        let base = hall(n as usize)?;
        for &mode in &modes {
            let scene = base.clone().with_direct_lights(mode, a.ris_candidates);
            let t0 = Instant::now();
            let rec = Receivers::new(&scene, &pts).map_err(|e| anyhow::anyhow!("{e}"))?;
            let setup = t0.elapsed().as_secs_f64();
            let cfg = RunConfig {
                seed: a.seed,
                threads: a.threads,
                stop: Stop {
                    rel_error: Some(0.01),
                    rms: true,
                    rel_error_cap: Some(cap),
                    ..Stop::default()
                },
                ..RunConfig::default()
            };
            let r = run(&scene, &rec, &cfg, &mut |_| true);
            let rms = r.tallies.rms_rel_error(&r.direct);
            let total = setup + r.wall;
            let e_avg = (0..pts.len())
                .map(|j| r.direct[j] + r.tallies.estimated[j].mean())
                .sum::<f64>()
                / pts.len() as f64;
            println!(
                "{:>6} {:>6} {:>9.3} {:>8.2} {:>9.2} {:>10} {:>11.4e} {:>9.3e} {:>11.4e} {:>10.3} {:>9}",
                n,
                if mode == DirectLights::Exact {
                    "exact"
                } else {
                    "ris"
                },
                setup,
                r.wall,
                total,
                r.chains,
                r.chains as f64 / r.wall,
                rms,
                1.0 / (rms * rms * total),
                e_avg,
                peak_mib().map_or("-".into(), |m| format!("{m:.0}"))
            );
        }
    }
    Ok(())
}
