//! Options and budget of a stress run.

use crate::run::{RunConfig, Stop};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `lumest validate stress`.
#[derive(Args, Clone, Debug)]
pub struct StressArgs {
    /// Run only the quick subset, each case with its own fixed number of chains.
    #[arg(long)]
    pub quick: bool,
    /// Wall-clock time per case (s) (default 2; with `--quick`, fixed chains instead).
    #[arg(long = "time-per-case", allow_negative_numbers = true)]
    pub time_per_case: Option<f64>,
    /// Chains per case instead of a time (paths per point for the backward
    /// estimator); at least 8192 (32 batches of 256).
    #[arg(long, conflicts_with = "time_per_case", allow_negative_numbers = true)]
    pub chains: Option<u64>,
    /// Seed.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Worker threads (0: all cores).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub threads: usize,
    /// Folder for `stress.csv`, `stress_summary.csv` and the convergence tables and plots.
    #[arg(long, default_value = "validation_report")]
    pub report: PathBuf,
    /// Family-wise false-alarm rate of the z test over all rows.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub alpha: f64,
}

/// How long each case runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Wall-clock seconds per Monte Carlo run (soft: at least 32 batches).
    Time(f64),
    /// The same number of chains for every run (paths per point for the
    /// backward estimator), at least [`MIN_CHAINS`], rounded up to whole
    /// batches.
    Chains(u64),
    /// Each case's own fixed number of chains (at least [`MIN_CHAINS`]), a
    /// few seconds at most on two cores (the quick subset's budget).
    Tuned,
}

/// Options of a stress run (the library form of [`StressArgs`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StressOptions {
    /// Only the quick subset.
    pub quick: bool,
    /// How long each case runs.
    pub budget: Budget,
    /// Seed of every run (the independent reference runs derive their own).
    pub seed: u64,
    /// Worker threads (0: all cores).
    pub threads: usize,
    /// Family-wise false-alarm rate of the z test over all rows.
    pub alpha: f64,
}

impl StressOptions {
    /// The options of `args`, checked.
    pub fn from_args(a: &StressArgs) -> anyhow::Result<Self> {
        if let Some(t) = a.time_per_case {
            anyhow::ensure!(
                t.is_finite() && t > 0.0,
                "--time-per-case must be a positive number of seconds, got {t}"
            );
        }
        if let Some(c) = a.chains {
            anyhow::ensure!(c > 0, "--chains must be positive");
        }
        anyhow::ensure!(
            a.alpha > 0.0 && a.alpha < 1.0,
            "--alpha must lie in (0, 1), got {}",
            a.alpha
        );
        let budget = match (a.chains, a.time_per_case, a.quick) {
            (Some(c), _, _) => Budget::Chains(c),
            (None, Some(t), _) => Budget::Time(t),
            (None, None, true) => Budget::Tuned,
            (None, None, false) => Budget::Time(2.0),
        };
        Ok(Self {
            quick: a.quick,
            budget,
            seed: a.seed,
            threads: a.threads,
            alpha: a.alpha,
        })
    }

    /// Run configuration for one run with seed `seed`; `tuned` chains under
    /// [`Budget::Tuned`]; the plain local estimate (no near/far split).
    pub(super) fn config(&self, seed: u64, tuned: u64) -> RunConfig {
        let chains = match self.budget {
            Budget::Time(_) => None,
            Budget::Chains(c) => Some(c.max(MIN_CHAINS)),
            Budget::Tuned => Some(tuned.max(MIN_CHAINS)),
        };
        let stop = Stop {
            time: match self.budget {
                Budget::Time(t) => Some(t),
                _ => None,
            },
            chains,
            ..Stop::default()
        };
        RunConfig {
            seed,
            threads: self.threads,
            stop,
            // A chain budget gets up to 128 batches (more degrees of freedom
            // for the t bound than the runner's 32), but never batches of
            // fewer than `MIN_BATCH_CHAINS` chains: the runner's own rule
            // (batch means of fewer chains are too skewed for the checks
            // and the t bound). A timed run keeps the runner's batch size,
            // which obeys the same rule.
            batch_size: chains.map(|c| (c / 128).clamp(MIN_BATCH_CHAINS, 1 << 16)),
            // The plain local estimate, whatever the library default: the
            // remedy rows turn the split on themselves.
            near: (0.0, 0),
            near_auto: false,
            ..RunConfig::default()
        }
    }
}

/// Fewest chains per batch of a run with a chain budget: the runner's
/// own rule for its default batch size (`LocalWork::default_batch_size` in
/// `src/estimator/local.rs`).
pub const MIN_BATCH_CHAINS: u64 = 256;

/// Fewest chains of a run with a chain budget: [`crate::run::MIN_BATCHES`]
/// (32) batches of [`MIN_BATCH_CHAINS`]; smaller budgets are raised to it.
pub const MIN_CHAINS: u64 = crate::run::MIN_BATCHES * MIN_BATCH_CHAINS;
