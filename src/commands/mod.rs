//! The command-line jobs, as library functions (the binary only parses
//! arguments and maps errors to exit codes).

pub mod bench;
pub mod bench_bound;
pub mod bench_many_lights;
pub mod figure_target;
pub mod figures;
pub mod glare;
pub mod grid;
pub mod illuminance;
pub mod merge;
pub mod modelling;
pub mod mpi_run;
pub mod outputs;
pub mod peak_rss;
pub mod photometry;
pub mod render;
pub mod report;
pub mod run_state;
pub mod shfit;
pub mod sobolev;
pub mod ugr_table;
pub mod validate;

use crate::chain::ChainParams;
use crate::run::{RunConfig, Stop};
use crate::sampling::qmc::Qmc;
use clap::Args;

/// Write `line` and a newline to standard error in one write: a shard's
/// messages under `mpirun` share one stream with the other ranks', and
/// `eprintln!` writes its pieces one by one, so two ranks' lines could
/// interleave mid-line (seen in the MPI test: "traced 16 of the lumest:
/// shard 1/322: traced ..."). One write of a line under 4 KiB to a pipe is
/// atomic (POSIX `PIPE_BUF`).
pub(crate) fn say(line: &str) {
    use std::io::Write;
    let mut text = String::with_capacity(line.len() + 1);
    text.push_str(line);
    text.push('\n');
    // (Nothing to do if standard error is gone.)
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

/// Most reflection orders `--orders` resolves.
pub const MAX_ORDERS: u32 = 100;

/// Most order tallies a run keeps, `(orders + 2) x receivers` (about 3 GB at
/// 32 bytes a tally on one thread).
pub const MAX_ORDER_TALLIES: u64 = 100_000_000;

/// Most views a generated view list (`--fan`, a camera) may have.
pub const MAX_VIEWS: u64 = 4_000_000;

/// Refuse a run whose order tallies would not fit: `(orders + 2)` tallies
/// per receiver, checked before anything is allocated.
pub(crate) fn check_tally_size(orders: u32, receivers: usize) -> anyhow::Result<()> {
    let tallies = (u64::from(orders) + 2).saturating_mul(receivers as u64);
    anyhow::ensure!(
        tallies <= MAX_ORDER_TALLIES,
        "--orders {orders} with {receivers} receivers needs {tallies} tallies; at most \
         {MAX_ORDER_TALLIES} (resolve fewer orders or split the points)"
    );
    Ok(())
}

/// Run controls shared by every Monte Carlo command.
#[derive(Args, Clone, Debug)]
pub struct RunArgs {
    /// Number of chains (rounded up to whole batches). Default 100000 when no
    /// other stopping rule is given.
    #[arg(long, value_parser = parse_count, allow_negative_numbers = true)]
    pub chains: Option<u64>,
    /// Wall-clock limit (s). Soft: a run completes at least 32 batches, and
    /// its summary says when they need longer than the limit.
    #[arg(long, allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Stop when the largest relative standard error of E over the points is below this.
    #[arg(
        long = "rel-error",
        allow_negative_numbers = true,
        conflicts_with = "rms_error"
    )]
    pub rel_error: Option<f64>,
    /// Aim at a root mean square of the points' relative standard errors
    /// below this: the run's 32 batches grow stage by stage until their own
    /// RMS meets it (as `--rel-error` does for the largest); with
    /// `--batch-size`, shards run apart, `--figure-target`, the backward
    /// estimator or more than 2^24 sums at once, a count planned on the
    /// run's own first 32 batches or the pilot rule (see `lumest::run`).
    #[arg(long = "rms-error", allow_negative_numbers = true)]
    pub rms_error: Option<f64>,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Worker threads (0: all cores). Results do not depend on it.
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub threads: usize,
    /// Resolve K reflection orders and the rest in the output: illuminance
    /// `E_order1..E_orderK` (light reflected k times before it arrives);
    /// luminance `L_order2..L_order{K+1}` (the reflection at the sub-point
    /// counted: order 1 is `L_direct`).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub orders: u32,
    /// Truncate chains after this many reflections (biased; for order studies only).
    #[arg(long = "max-order", allow_negative_numbers = true)]
    pub max_order: Option<u32>,
    /// Chains per batch (default: from the number of points; see docs).
    #[arg(long = "batch-size", allow_negative_numbers = true)]
    pub batch_size: Option<u64>,
    /// Russian-roulette weight, relative to the starting weight, in (0, 1].
    #[arg(long = "rr-weight", default_value_t = ChainParams::default().rr_weight, allow_negative_numbers = true)]
    pub rr_weight: f64,
    /// Near/far split against the singular kernel and for far points: `auto`
    /// (the default: where a point has a surface closer than a tenth of its
    /// distance to the nearest light, with a quarter of that distance; lit
    /// from infinity alone, the scale of the chains' start density there, or
    /// in a room the median distance of its surroundings), a radius (m) for
    /// every point, or `0` (off: the plain local estimate). Collisions closer
    /// than the radius leave their share to backward paths from the point
    /// (unbiased; keeps the variance finite next to walls and in corners, and
    /// brings the light piled up around the sources to far points).
    /// Local estimator only. [default: auto]
    #[arg(long = "near-radius", allow_negative_numbers = true)]
    pub near_radius: Option<String>,
    /// Backward paths per point for every 256 chains, for the near part
    /// (with `--near-radius`): `auto` (the default: each point its own
    /// count, 16 to 256, from a fixed pilot, for the least RMS relative
    /// error per unit of work) or one count for every point. Local
    /// estimator only. [default: auto]
    #[arg(long = "near-paths", allow_negative_numbers = true)]
    pub near_paths: Option<String>,
    /// Backward paths (`--estimator backward`, the near part of the split):
    /// plain next-event estimation only, without the light-guided connection
    /// and its multiple importance sampling.
    #[arg(long = "no-guide")]
    pub no_guide: bool,
    /// How the direct light is summed over the sources, at the points and
    /// at backward-path vertices: `exact` (every source at every point:
    /// closed forms computed once, one shadow test per source and point),
    /// `ris` (the light array: each sample keeps one source of
    /// `--ris-candidates` drawn by power, by resampled importance sampling;
    /// unbiased, one shadow test per sample) or `auto` (exact below the
    /// threshold in README "Many lights", RIS above). The run summary says
    /// which.
    #[arg(long = "direct-lights", default_value = "auto", value_parser = parse_direct_lights)]
    pub direct_lights: crate::light::array::DirectLights,
    /// Candidates per RIS pick (1 to 64).
    #[arg(long = "ris-candidates", default_value_t = crate::light::array::RIS_CANDIDATES, value_parser = parse_ris_candidates)]
    pub ris_candidates: usize,
    /// Draw emitted directions independently instead of stratifying them
    /// over each batch (`--qmc off`). Local estimator only.
    #[arg(long = "no-stratify", conflicts_with = "qmc")]
    pub no_stratify: bool,
    /// How each batch stratifies its chains' leading uniforms: `owen`
    /// (an Owen-scrambled Sobol' net over the light pick, emission position
    /// and direction and the first three reflections), `shift` (a digitally
    /// shifted Sobol' net over the emitted direction and the first
    /// reflection) or `off`. Local estimator only. [default: owen]
    #[arg(long, value_enum)]
    pub qmc: Option<QmcArg>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Write a checkpoint of a `--chains` run to this file every
    /// `--checkpoint-every` seconds (atomically); an interrupted run writes
    /// one too (here, or next to `--out`).
    #[arg(long)]
    pub checkpoint: Option<String>,
    /// Seconds between checkpoints.
    #[arg(
        long = "checkpoint-every",
        default_value_t = 60.0,
        allow_negative_numbers = true
    )]
    pub checkpoint_every: f64,
    /// Add daylight factors to the points' results: `DF = 100 E / E_h` [%]
    /// with `E_h` the illuminance the scene's sky and environment lights
    /// give on an unobstructed horizontal plane (exact), and the sky
    /// component `DF_sky` from the direct light alone, each with its
    /// standard error. The run counts the sky's light alone (CIE S 017):
    /// `sun`, `distant` and electric lights are left out, of `E` too.
    #[arg(long = "daylight-factor")]
    pub daylight_factor: bool,
    /// Continue the run whose checkpoint this is (same scene, points, seed,
    /// `--chains` and settings): the result is the uninterrupted run's, bit
    /// for bit.
    #[arg(long)]
    pub resume: Option<String>,
}

/// A count given as a whole number, also in scientific notation (`1e5`).
fn parse_count(s: &str) -> Result<u64, String> {
    if let Ok(n) = s.parse::<u64>() {
        return Ok(n);
    }
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 && x.fract() == 0.0 && x < 1.8e19 => Ok(x as u64),
        _ => Err(format!(
            "`{s}` is not a whole number of chains (like 100000 or 1e5)"
        )),
    }
}

impl RunArgs {
    /// Validate and turn into a run configuration.
    pub fn config(&self) -> anyhow::Result<RunConfig> {
        let mut stop = Stop {
            chains: self.chains,
            time: self.time,
            rel_error: self.rel_error.or(self.rms_error),
            rel_error_cap: None,
            rms: self.rms_error.is_some(),
        };
        if let Some(t) = stop.time {
            anyhow::ensure!(
                t.is_finite() && t > 0.0,
                "--time must be a positive number of seconds, got {}",
                crate::io::format_number(t)
            );
        }
        if let Some(r) = stop.rel_error {
            anyhow::ensure!(
                r.is_finite() && r > 0.0,
                "{} must be positive, got {}",
                if stop.rms {
                    "--rms-error"
                } else {
                    "--rel-error"
                },
                crate::io::format_number(r)
            );
        }
        anyhow::ensure!(
            self.max_order.is_none_or(|m| m >= 1),
            "--max-order must be at least 1 (chains stop after that many reflections; \
             0 would still score the first reflection)"
        );
        if let Some(c) = stop.chains {
            anyhow::ensure!(c > 0, "--chains must be positive");
        }
        anyhow::ensure!(
            self.checkpoint_every.is_finite() && self.checkpoint_every > 0.0,
            "--checkpoint-every must be a positive number of seconds, got {}",
            crate::io::format_number(self.checkpoint_every)
        );
        if self.checkpoint.is_some() || self.resume.is_some() {
            anyhow::ensure!(
                stop.time.is_none() && stop.rel_error.is_none(),
                "--checkpoint and --resume go with a run of a fixed number of chains \
                 (--chains, or the default), not with --time or --rel-error: those depend on \
                 the run's own pace and batches"
            );
        }
        anyhow::ensure!(
            self.orders <= MAX_ORDERS,
            "--orders must be at most {MAX_ORDERS} (each resolved order adds a tally per \
             receiver and two output columns), got {}",
            self.orders
        );
        if stop == Stop::default() {
            stop.chains = Some(100_000);
        }
        anyhow::ensure!(
            self.rr_weight > 0.0 && self.rr_weight <= 1.0,
            "--rr-weight must lie in (0, 1], got {}",
            self.rr_weight
        );
        let (near_radius, near_auto) = match self.near_radius.as_deref().unwrap_or("auto").trim() {
            "auto" => (0.0, true),
            s => {
                let r: f64 = s.parse().map_err(|_| {
                    anyhow::anyhow!("--near-radius must be `auto` or a length >= 0 [m], got `{s}`")
                })?;
                anyhow::ensure!(
                    r.is_finite() && r >= 0.0,
                    "--near-radius must be `auto` or a finite length >= 0 [m], got {r}"
                );
                (r, false)
            }
        };
        let near_paths = match self.near_paths.as_deref().unwrap_or("auto").trim() {
            "auto" => None,
            s => Some(s.parse::<u32>().map_err(|_| {
                anyhow::anyhow!("--near-paths must be `auto` or a whole number >= 0, got `{s}`")
            })?),
        };
        anyhow::ensure!(
            self.batch_size.is_none_or(|b| b > 0 && b <= 1 << 32),
            "--batch-size must lie in [1, 2^32] (chains of a batch index one Sobol' net)"
        );
        Ok(RunConfig {
            seed: self.seed,
            threads: self.threads,
            stop,
            orders: self.orders,
            chain: ChainParams {
                rr_weight: self.rr_weight,
                max_order: self.max_order,
                guide: !self.no_guide,
            },
            batch_size: self.batch_size,
            qmc: if self.no_stratify {
                Qmc::Off
            } else {
                self.qmc.map_or(Qmc::default(), QmcArg::into)
            },
            near: (near_radius, near_paths.unwrap_or(16)),
            near_auto,
            near_paths_auto: near_paths.is_none(),
            shard: None,
            resume: None,
            keep_batch_means: 0,
            pilot_measure: None,
            share: None,
        })
    }
}

/// `--qmc`: [`Qmc`] on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum QmcArg {
    /// Independent uniforms.
    Off,
    /// Digitally shifted Sobol' net (4 dimensions).
    Shift,
    /// Owen-scrambled Sobol' net (11 dimensions).
    Owen,
}

impl From<QmcArg> for Qmc {
    fn from(q: QmcArg) -> Self {
        match q {
            QmcArg::Off => Qmc::Off,
            QmcArg::Shift => Qmc::Shift,
            QmcArg::Owen => Qmc::Owen,
        }
    }
}

impl RunArgs {
    /// Refuse the options that only the local estimator reads when another
    /// one runs (they would be ignored without a word).
    pub fn check_local_only(&self, estimator: &str) -> anyhow::Result<()> {
        let given: Vec<&str> = [
            ("--near-radius", self.near_radius.is_some()),
            ("--near-paths", self.near_paths.is_some()),
            ("--no-stratify", self.no_stratify),
            ("--qmc", self.qmc.is_some()),
        ]
        .into_iter()
        .filter_map(|(name, set)| set.then_some(name))
        .collect();
        anyhow::ensure!(
            given.is_empty(),
            "{} appl{} to the local estimator only, not to --estimator {estimator}",
            given.join(", "),
            if given.len() == 1 { "ies" } else { "y" }
        );
        Ok(())
    }
}

/// A progress bar on standard error (hidden when it is not a terminal).
pub(crate) fn progress_bar(cfg: &RunConfig, quiet: bool) -> indicatif::ProgressBar {
    use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = match (cfg.stop.chains, cfg.stop.time) {
        (Some(c), _) => ProgressBar::new(c),
        (None, Some(t)) => ProgressBar::new((t * 1000.0) as u64),
        (None, None) => ProgressBar::no_length(),
    };
    pb.set_draw_target(ProgressDrawTarget::stderr());
    // The time left (to the chain count or the time limit) is indicatif's
    // estimate from the pace so far.
    let tmpl = "{spinner} [{elapsed_precise}] {wide_bar} {msg} (about {eta} left)";
    pb.set_style(ProgressStyle::with_template(tmpl).expect("valid template"));
    pb
}

/// Update a progress bar from a run's progress.
pub(crate) fn tick(pb: &indicatif::ProgressBar, cfg: &RunConfig, p: &crate::run::Progress) {
    if pb.is_hidden() {
        return;
    }
    let pos = match (cfg.stop.chains, cfg.stop.time) {
        (Some(_), _) => p.chains,
        (None, Some(_)) => (p.elapsed * 1000.0) as u64,
        _ => 0,
    };
    pb.set_position(pos);
    if p.tallies.batches() >= 2 {
        pb.set_message(format!(
            "{} chains, max R {:.2e}",
            p.chains,
            p.tallies.max_rel_error(p.direct)
        ));
    } else {
        pb.set_message(format!("{} chains", p.chains));
    }
}

/// Parse `--direct-lights`.
fn parse_direct_lights(s: &str) -> Result<crate::light::array::DirectLights, String> {
    crate::light::array::DirectLights::parse(s)
        .ok_or_else(|| format!("expected `auto`, `exact` or `ris`, got `{s}`"))
}

/// Parse `--ris-candidates`.
fn parse_ris_candidates(s: &str) -> Result<usize, String> {
    let max = crate::light::array::RIS_MAX_CANDIDATES;
    match s.parse::<usize>() {
        Ok(m) if (1..=max).contains(&m) => Ok(m),
        _ => Err(format!(
            "expected a whole number from 1 to {max}, got `{s}`"
        )),
    }
}
