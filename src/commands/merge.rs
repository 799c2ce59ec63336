//! Runs beyond one machine: `lumest illuminance ... --chains N --seed K
//! --shard I/M --out PART` runs batches `I, I+M, ...` of the run and writes
//! their state ([`crate::tally::shard`]); `lumest merge PART... --out R.csv`
//! folds the shards' batches in index order, as a single run folds them,
//! and writes the single run's CSV byte for byte.

use super::illuminance::{EstimatorKind, IlluminanceArgs, result_cells, result_headers, run_job};
use super::outputs::check_outputs;
use crate::io::csvio::{stage_csv, write_atomic_with};
use crate::run::{RunResult, StopReason, Tallies, fold_batches};
use crate::tally::shard::{RunIdentity, ShardState};
use anyhow::Context;
use clap::Args;
use std::path::{Path, PathBuf};

/// Most shards of one run.
pub const MAX_SHARDS: u64 = 1_000_000;

/// Arguments of `lumest merge`.
#[derive(Args, Clone, Debug)]
pub struct MergeArgs {
    /// Shard states written by `lumest illuminance ... --shard I/M --out PART`
    /// (every shard of the run, in any order).
    #[arg(required = true)]
    pub parts: Vec<String>,
    /// Output CSV (`-`: standard output): the single run's, byte for byte.
    #[arg(long)]
    pub out: String,
}

/// `I/M` with `0 <= I < M <= MAX_SHARDS`.
fn parse_shard(s: &str) -> anyhow::Result<(u64, u64)> {
    let parsed = s
        .split_once('/')
        .and_then(|(i, m)| Some((i.trim().parse::<u64>().ok()?, m.trim().parse::<u64>().ok()?)));
    match parsed {
        Some((i, m)) if m >= 1 && i < m && m <= MAX_SHARDS => Ok((i, m)),
        _ => anyhow::bail!(
            "--shard must be I/M with 0 <= I < M <= {MAX_SHARDS} (shard I of M), got `{s}`"
        ),
    }
}

/// Run one shard (`lumest illuminance ... --shard I/M`) and write its state.
pub fn run_shard(a: &IlluminanceArgs, shard: &str) -> anyhow::Result<()> {
    let (i, m) = parse_shard(shard)?;
    anyhow::ensure!(
        a.out != "-",
        "--shard writes its state to a file for `lumest merge`, which reads files: give --out a file name, not `-`"
    );
    let inputs = run_inputs(a);
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    check_outputs(&inputs, &[("--out", Path::new(&a.out))])?;
    let state = shard_state(a, i, m, None)?;
    write_atomic_with(&a.out, |w| state.write(w)).with_context(|| format!("writing {}", a.out))?;
    eprintln!(
        "lumest: shard {i}/{m}: {} of {} batches ({} chains each), {:.3} s; state written to {}",
        state.batches.len(),
        state.run.batches,
        state.run.batch_size,
        state.wall,
        a.out
    );
    Ok(())
}

/// The files the run `a` reads: the scene, the points, the files the scene
/// names.
fn run_inputs(a: &IlluminanceArgs) -> Vec<PathBuf> {
    let mut inputs = vec![a.scene.clone(), PathBuf::from(&a.points)];
    inputs.extend(crate::scene::referenced_files(&a.scene));
    inputs
}

/// The state of shard `i` of `m` of the run `a` describes (batches `i, i +
/// m, ...` of a `--chains` run; with `--rel-error`, every shard runs the
/// same pilot, which is deterministic, and then its share of the planned
/// batches). `share`: how shards running at once share the batches an RMS
/// plan is measured on ([`crate::run::RunConfig::share`]); `None`: this
/// shard traces them all.
pub fn shard_state(
    a: &IlluminanceArgs,
    i: u64,
    m: u64,
    share: Option<crate::run::Share>,
) -> anyhow::Result<ShardState> {
    anyhow::ensure!(
        a.points != "-",
        "--shard reads the points from a file (every shard must read the same one), not standard input"
    );
    anyhow::ensure!(
        a.run.checkpoint.is_none() && a.run.resume.is_none(),
        "--shard writes its state when done: it takes no --checkpoint or --resume"
    );
    anyhow::ensure!(
        a.run.chains.is_some() || a.run.rel_error.is_some() || a.run.rms_error.is_some(),
        "a sharded run needs --chains (or --rel-error), the same for every shard"
    );
    let mut cfg = a.run.config()?;
    if a.estimator == EstimatorKind::Backward {
        a.run.check_local_only("backward")?;
    }
    anyhow::ensure!(
        cfg.stop.time.is_none(),
        "a sharded run stops by --chains or --rel-error, not by --time (each shard would stop at its own batch)"
    );
    let chains = cfg.stop.chains.unwrap_or(0);
    // The single run's scene and job, the same set-up and checks.
    let (scene, mut job) = super::illuminance::prepare_job(
        &a.scene,
        Some((&a.points, &a.out)),
        None,
        a.estimator,
        &a.run,
        &cfg,
    )?;
    cfg.shard = Some((i, m));
    cfg.share = share;
    // (Each line in one write: under `mpirun` the ranks share the stream.)
    super::say(&format!(
        "lumest: scene {}: {}",
        a.scene.display(),
        scene.summary()
    ));
    if a.estimator == EstimatorKind::Local {
        crate::estimator::local::prepare(&scene, &mut job.receivers, &cfg);
    }
    let r = run_job(&scene, &job, &cfg, a.estimator, a.run.quiet, None);
    let table = job.points.as_ref().context("no points")?;
    anyhow::ensure!(
        !crate::io::interrupt::interrupted(),
        "interrupted: a shard is written whole or not at all (run it again)"
    );
    if let Some(p) = r.pilot.as_ref().filter(|p| p.calibration > 0) {
        super::say(&format!(
            "lumest: shard {i}/{m}: traced {} of the {} batches the --rms-error plan was measured on \
             ({} batches planned)",
            p.calibration_traced, p.calibration, p.planned
        ));
    }
    Ok(ShardState {
        run: RunIdentity {
            batches: r.total_batches,
            chains,
            ..super::run_state::identity(&scene, &job, &cfg, a.estimator, r.batch_size)
        },
        shard: (i, m),
        wall: r.wall,
        direct: r.direct.clone(),
        checks: [
            r.tallies.watched.clone(),
            r.tallies.near_plain.clone(),
            r.tallies.near_reach.clone(),
            r.tallies.enclosed.clone(),
        ],
        headers: table.headers.clone(),
        rows: table.rows.clone(),
        comment_lines: table.comment_lines,
        batches: r.batches,
        inputs: run_inputs(a)
            .iter()
            .map(|p| p.canonicalize().unwrap_or_else(|_| p.to_path_buf()))
            .collect(),
    })
}

/// Refuse a state whose parts do not fit together (one that passed its
/// checksum but was made or edited by hand): the shard `I/M`, the orders
/// and receivers the tallies are sized by, each batch's sums.
fn well_formed(s: &ShardState) -> anyhow::Result<()> {
    let (i, m) = s.shard;
    anyhow::ensure!(
        m >= 1 && i < m && m <= MAX_SHARDS,
        "shard {i}/{m}: expected I/M with 0 <= I < M <= {MAX_SHARDS}"
    );
    let run = &s.run;
    anyhow::ensure!(
        run.orders <= super::MAX_ORDERS,
        "orders {}: at most {}",
        run.orders,
        super::MAX_ORDERS
    );
    super::check_tally_size(run.orders, run.receivers as usize)?;
    let n = run.receivers as usize;
    anyhow::ensure!(
        s.rows.len() <= n && s.direct.len() == n,
        "{} rows and {} direct values for {n} receivers",
        s.rows.len(),
        s.direct.len()
    );
    anyhow::ensure!(
        s.checks.iter().all(|c| c.is_empty() || c.len() == n),
        "its per-point checks are not one per receiver ({n})"
    );
    let sums = n * crate::tally::bucket_count(run.orders);
    for b in &s.batches {
        anyhow::ensure!(
            b.sums.len() == sums
                && [0, n].contains(&b.direct_sums.len())
                && [0, n, 3 * n].contains(&b.near_hits.len()),
            "batch {} holds {} sums, {} direct sums and {} near-hit counts; {n} receivers and \
             orders {} take {sums} sums, 0 or {n} direct sums and 0, {n} or {} counts",
            b.index,
            b.sums.len(),
            b.direct_sums.len(),
            b.near_hits.len(),
            run.orders,
            3 * n
        );
    }
    Ok(())
}

/// Run `lumest merge`.
pub fn merge(a: &MergeArgs) -> anyhow::Result<()> {
    let parts: Vec<&Path> = a.parts.iter().map(Path::new).collect();
    check_outputs(&parts, &[("--out", Path::new(&a.out))])?;
    let mut states = Vec::new();
    for p in &a.parts {
        let bytes = std::fs::read(p).with_context(|| format!("reading {p}"))?;
        let s = ShardState::read(&bytes).with_context(|| p.to_string())?;
        states.push((p.clone(), s));
    }
    // Nor over the run's own inputs, as the shards recorded them (the
    // scene, the points, the files the scene names).
    let inputs: Vec<&Path> = states
        .iter()
        .flat_map(|(_, s)| s.inputs.iter().map(PathBuf::as_path))
        .collect();
    check_outputs(&inputs, &[("--out", Path::new(&a.out))])?;
    merge_states(states, &a.out)
}

/// Fold the shards `states` (named for messages) of one run and write the
/// single run's CSV to `out`.
pub fn merge_states(mut states: Vec<(String, ShardState)>, out: &str) -> anyhow::Result<()> {
    for (name, s) in &states {
        well_formed(s).with_context(|| format!("{name}: not a shard state lumest writes"))?;
    }
    let (first_name, first) = &states[0];
    let m = first.shard.1;
    let mut seen: Vec<Option<&str>> = vec![None; m as usize];
    let first_name = first_name.as_str();
    for (name, s) in &states {
        let same = |what: &str, ok: bool| -> anyhow::Result<()> {
            anyhow::ensure!(
                ok,
                "{name} and {first_name} are shards of different runs: their {what} differ"
            );
            Ok(())
        };
        let (r, f) = (&s.run, &first.run);
        same(
            "scenes (the scene file and the files it names, as set up: --direct-lights, --ris-candidates)",
            r.scene == f.scene,
        )?;
        same(
            "points",
            r.points == f.points && s.headers == first.headers && s.rows == first.rows,
        )?;
        same("seeds", r.seed == f.seed)?;
        same("chain counts", r.chains == f.chains)?;
        same(
            "batch sizes (--batch-size)",
            r.batches == f.batches && r.batch_size == f.batch_size,
        )?;
        same(
            &super::run_state::settings_differ(&r.config, &f.config),
            r.config == f.config && r.orders == f.orders && r.receivers == f.receivers,
        )?;
        same("shard counts", s.shard.1 == m)?;
        let slot = &mut seen[s.shard.0 as usize];
        if let Some(other) = slot {
            anyhow::bail!("{name} and {other} are both shard {}/{m}", s.shard.0);
        }
        *slot = Some(name.as_str());
    }
    let missing: Vec<String> = seen
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(k, _)| format!("{k}/{m}"))
        .collect();
    anyhow::ensure!(
        missing.is_empty(),
        "shard(s) {} of the run are missing",
        missing.join(", ")
    );
    // Every batch of the run once, in index order.
    let run = first.run.clone();
    let n = run.receivers as usize;
    // (Not sized by the header's count, which is checked against them.)
    let mut batches = Vec::new();
    let mut wall = 0.0;
    for (_, s) in &mut states {
        wall += s.wall;
        batches.append(&mut s.batches);
    }
    batches.sort_by_key(|b| b.index);
    for (k, b) in batches.iter().enumerate() {
        anyhow::ensure!(
            b.index == k as u64 && b.sums.len() % n.max(1) == 0,
            "the shards do not hold batches 0 to {} once each (found batch {} at position {k})",
            run.batches - 1,
            b.index
        );
    }
    anyhow::ensure!(
        batches.len() as u64 == run.batches,
        "the shards hold {} batches of the run's {}",
        batches.len(),
        run.batches
    );
    let (first_name, first) = &states[0];
    // Points listed planar up and cylindrical at one position get the
    // modelling ratio's columns, as in a single run; its error needs the
    // batch means.
    let table = crate::io::csvio::points_of_rows(&first.headers, &first.rows, first_name)?;
    let pairs = super::modelling::pairs(
        &super::illuminance::point_receivers(&table, first_name)?,
        table.rows.len(),
    );
    let mut tallies = Tallies::new(n, run.orders);
    tallies.approximate = run.approximate;
    [
        tallies.watched,
        tallies.near_plain,
        tallies.near_reach,
        tallies.enclosed,
    ] = first.checks.clone();
    if !pairs.is_empty() {
        tallies.batch_means = crate::tally::BatchMeans::new(table.rows.len().min(n));
    }
    let tallies = fold_batches(tallies, &first.direct, run.batch_size, &batches);
    let result = if run.batches == 0 {
        // A scene that emits nothing: every shard holds no batch, and the
        // single run's exact zeros are the answer.
        let cfg = crate::run::RunConfig {
            orders: run.orders,
            keep_batch_means: if pairs.is_empty() {
                0
            } else {
                table.rows.len()
            },
            ..crate::run::RunConfig::default()
        };
        crate::run::no_light(&first.direct, &cfg)
    } else {
        RunResult {
            direct: first.direct.clone(),
            tallies,
            chains: batches.iter().map(|b| b.chains).sum(),
            batch_size: run.batch_size,
            collisions: batches.iter().map(|b| b.collisions).sum(),
            scores: batches.iter().map(|b| b.scores).sum(),
            wall,
            threads: 0,
            reason: StopReason::Chains,
            pilot: None,
            time_sizing: None,
            batches: Vec::new(),
            total_batches: 0,
        }
    };
    let mut headers = first.headers.clone();
    headers.extend(result_headers("E", run.orders));
    let modelling = (!pairs.is_empty()).then(|| {
        headers.extend(super::modelling::COLUMNS.map(String::from));
        super::modelling::cells(
            &result.tallies.batch_means,
            &result.direct,
            &pairs,
            first.rows.len(),
        )
    });
    let width = first.headers.len();
    let rows = first.rows.iter().enumerate().map(|(j, row)| {
        let mut c = row.clone();
        c.resize(width, String::new());
        c.extend(result_cells(&result, j));
        if let Some(m) = &modelling {
            c.extend(m[j].clone());
        }
        c
    });
    let (staged, written) =
        stage_csv(out, &headers, rows).with_context(|| format!("writing {out}"))?;
    anyhow::ensure!(
        written == first.rows.len(),
        "rows were lost: {} of {} written",
        written,
        first.rows.len()
    );
    staged.commit().with_context(|| format!("writing {out}"))?;
    eprintln!(
        "lumest: merged {m} shard(s): {} batches of {} chains, seed {}; {} rows written to {} \
         (the shards' wall times add up to {wall:.3} s)",
        run.batches,
        run.batch_size,
        run.seed,
        written,
        if out == "-" { "<stdout>" } else { out }
    );
    for line in super::illuminance::summary(&result).lines() {
        eprintln!("lumest: {line}");
    }
    Ok(())
}
