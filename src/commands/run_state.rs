//! What names a run in its state files (shards, checkpoints), and the
//! periodic checkpoint of a run in progress (`--checkpoint`, `--resume`).

use super::illuminance::{EstimatorKind, Job};
use crate::io::csvio::write_atomic_with;
use crate::run::{Progress, RunConfig};
use crate::scene::Scene;
use crate::tally::checkpoint::Checkpoint;
use crate::tally::shard::{RunIdentity, fnv1a};
use std::time::Instant;

/// FNV-1a of a table's header and rows (unit and record separators between
/// cells and rows, so that no two tables hash alike by concatenation).
pub fn table_hash(headers: &[String], rows: &[Vec<String>]) -> u64 {
    let mut text = headers.join("\u{1f}");
    for row in rows {
        text.push('\u{1e}');
        text.push_str(&row.join("\u{1f}"));
    }
    fnv1a(text.as_bytes())
}

/// The identity of a `--chains` run of `job` on `scene` with batches of
/// `bs` chains: the hash of the compiled scene (so every file it read
/// counts), of the points and views, the build (its git commit, `build.rs`:
/// another build's numbers need not agree bit for bit), and every setting
/// that changes the numbers (not the threads, the shard, the resume state or how the batch
/// size was chosen, which is compared as a number).
pub fn identity(
    scene: &Scene,
    job: &Job,
    cfg: &RunConfig,
    estimator: EstimatorKind,
    bs: u64,
) -> RunIdentity {
    let chains = cfg.stop.chains.unwrap_or(0);
    let mut points = 0u64;
    if let Some(t) = &job.points {
        points ^= table_hash(&t.headers, &t.rows);
    }
    if let Some((t, _)) = &job.views {
        points ^= table_hash(&t.headers, &t.rows).rotate_left(1);
    }
    // (The seed and the chain count are compared on their own, so that a
    // mismatch names them and not the settings too.)
    let settings = RunConfig {
        seed: 0,
        stop: crate::run::Stop {
            chains: None,
            ..cfg.stop
        },
        threads: 0,
        shard: None,
        resume: None,
        batch_size: None,
        share: None,
        ..cfg.clone()
    };
    RunIdentity {
        batches: chains.div_ceil(bs.max(1)).max(2),
        batch_size: bs,
        chains,
        seed: cfg.seed,
        orders: cfg.orders,
        receivers: job.receivers.len() as u64,
        scene: fnv1a(format!("{scene:?}").as_bytes()),
        points,
        config: format!(
            "lumest {} build {} estimator {estimator:?} {settings:?}",
            env!("CARGO_PKG_VERSION"),
            env!("LUMEST_BUILD")
        ),
        approximate: scene.approximate.is_some(),
    }
}

/// `settings`, naming the first setting in which two runs' `config` texts
/// ([`RunIdentity::config`]) differ: the option that sets it (`settings
/// (--orders)`), else the field of the run's configuration, or the build.
pub fn settings_differ(a: &str, b: &str) -> String {
    if a == b {
        return "settings".to_string();
    }
    let k = a
        .char_indices()
        .zip(b.chars())
        .find(|((_, x), y)| x != y)
        .map_or(a.len().min(b.len()), |((k, _), _)| k);
    let before = &a[..k];
    // The text is `lumest V build B estimator E RunConfig { field: value, .. }`.
    if !before.contains('{') {
        return "settings (the lumest build or the estimator)".to_string();
    }
    let field = before.rfind(": ").map(|end| {
        let start = before[..end]
            .rfind(|c: char| !(c.is_alphanumeric() || c == '_'))
            .map_or(0, |i| i + 1);
        &before[start..end]
    });
    // The options that set the configuration's fields, where one does.
    const OPTIONS: [(&str, &str); 12] = [
        ("time", "--time"),
        ("rel_error", "--rel-error or --rms-error"),
        ("rms", "--rms-error"),
        ("orders", "--orders"),
        ("rr_weight", "--rr-weight"),
        ("max_order", "--max-order"),
        ("guide", "--no-guide"),
        ("qmc", "--qmc or --no-stratify"),
        ("near", "--near-radius or --near-paths"),
        ("near_auto", "--near-radius"),
        ("near_paths_auto", "--near-paths"),
        ("pilot_measure", "--figure-target"),
    ];
    match field {
        Some(f) if !f.is_empty() => {
            let shown = OPTIONS.iter().find(|(k, _)| *k == f).map_or(f, |(_, o)| o);
            format!("settings ({shown})")
        }
        _ => "settings".to_string(),
    }
}

/// Writes a run's checkpoint every `every` seconds, and when it is
/// interrupted.
pub struct Checkpointer<'a> {
    /// Where.
    pub path: String,
    /// Seconds between checkpoints.
    pub every: f64,
    scene: &'a Scene,
    job: &'a Job,
    cfg: &'a RunConfig,
    estimator: EstimatorKind,
    last: Instant,
}

impl<'a> Checkpointer<'a> {
    /// A checkpointer of the run of `job` on `scene` with `cfg`.
    pub fn new(
        path: String,
        every: f64,
        scene: &'a Scene,
        job: &'a Job,
        cfg: &'a RunConfig,
        estimator: EstimatorKind,
    ) -> Self {
        Self {
            path,
            every,
            scene,
            job,
            cfg,
            estimator,
            last: Instant::now(),
        }
    }

    /// Write a checkpoint of `p` if `every` seconds have passed since the
    /// last one, or at once when `now`; an error is reported, not fatal
    /// (the run goes on; the results are still written at its end).
    pub fn offer(&mut self, p: &Progress, now: bool) {
        let b = p.tallies.batches();
        if b == 0 || !(now || self.last.elapsed().as_secs_f64() >= self.every) {
            return;
        }
        self.last = Instant::now();
        let bs = p.chains / b;
        let c = Checkpoint {
            run: identity(self.scene, self.job, self.cfg, self.estimator, bs),
            folded: b,
            chains: p.chains,
            collisions: p.collisions,
            scores: p.scores,
            wall: p.elapsed,
            tallies: p.tallies.clone(),
        };
        let written = write_atomic_with(&self.path, |w| c.write(w));
        if let Err(e) = &written {
            eprintln!("lumest: could not write the checkpoint {}: {e}", self.path);
        }
        LAST_WRITTEN.store(written.is_ok(), std::sync::atomic::Ordering::SeqCst);
    }
}

/// Whether the last checkpoint this process tried to write was written
/// (false before any): an interrupted run tells how to resume only then.
static LAST_WRITTEN: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// See [`LAST_WRITTEN`].
pub fn last_checkpoint_written() -> bool {
    LAST_WRITTEN.load(std::sync::atomic::Ordering::SeqCst)
}

/// Read the checkpoint at `path` for a run of `job` on `scene` with `cfg`:
/// refused unless it names the same run; returns it and the configuration
/// that continues it (its batch size, and the checkpoint to start from).
pub fn resume(
    path: &str,
    scene: &Scene,
    job: &Job,
    cfg: &RunConfig,
    estimator: EstimatorKind,
) -> anyhow::Result<RunConfig> {
    use anyhow::Context;
    let bytes = std::fs::read(path).with_context(|| format!("reading {path}"))?;
    let c = Checkpoint::read(&bytes).with_context(|| path.to_string())?;
    let want = identity(scene, job, cfg, estimator, c.run.batch_size);
    let differ: Vec<String> = [
        (
            "scene (or its --direct-lights, --ris-candidates)",
            want.scene != c.run.scene,
        ),
        (
            "points or views",
            want.points != c.run.points || want.receivers != c.run.receivers,
        ),
        ("seed", want.seed != c.run.seed),
        ("--chains", want.chains != c.run.chains),
        // (A run without --batch-size takes the checkpoint's.)
        (
            "--batch-size",
            cfg.batch_size.is_some_and(|b| b != c.run.batch_size),
        ),
        (
            "settings",
            want.config != c.run.config || want.orders != c.run.orders,
        ),
    ]
    .into_iter()
    .filter(|&(_, d)| d)
    .map(|(what, _)| match what {
        "settings" => settings_differ(&want.config, &c.run.config),
        _ => what.to_string(),
    })
    .collect();
    anyhow::ensure!(
        differ.is_empty(),
        "{path} is the checkpoint of another run: its {} differ(s) from this run's",
        differ.join(", ")
    );
    anyhow::ensure!(
        c.folded < c.run.batches,
        "{path}: the run it belongs to was complete ({} of {} batches)",
        c.folded,
        c.run.batches
    );
    eprintln!(
        "lumest: resuming from {path}: {} of {} batches done ({} chains, {:.3} s)",
        c.folded, c.run.batches, c.chains, c.wall
    );
    Ok(RunConfig {
        batch_size: Some(c.run.batch_size),
        resume: Some(std::sync::Arc::new(c)),
        ..cfg.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::settings_differ;

    #[test]
    fn the_setting_that_differs_is_named() {
        let a = "lumest 0.1 build x estimator Local RunConfig { seed: 0, orders: 2, chain: \
                 ChainParams { rr_weight: 0.1, max_order: None } }";
        let b = a.replace("orders: 2", "orders: 3");
        assert_eq!(settings_differ(a, &b), "settings (--orders)");
        let b = a.replace("max_order: None", "max_order: Some(1)");
        assert_eq!(settings_differ(a, &b), "settings (--max-order)");
        // A field no option sets keeps its name; the build comes first.
        let b = a.replace("seed: 0", "seed: 7");
        assert_eq!(settings_differ(a, &b), "settings (seed)");
        let b = a.replace("build x", "build y");
        assert_eq!(
            settings_differ(a, &b),
            "settings (the lumest build or the estimator)"
        );
        assert_eq!(settings_differ(a, a), "settings");
    }
}
