//! The `--rel-error` stopping rule (a pilot, then a fixed count of fresh
//! batches; see `lumest::run`) keeps the mean unbiased and the 95 % interval
//! calibrated when batch means are skewed, where stopping at the first
//! batch prefix that meets the target does not.
//!
//! The work is synthetic, so that thousands of independent runs take
//! seconds and the exact mean is known: one receiver whose batch means are
//! lognormal (`sigma = 0.6`, mean exactly 1, skewness 2.3), drawn from the
//! Philox stream of the batch, driven by the real runner. The target 8 %
//! needs about 60 batches. Simulated beforehand (3,000 runs each): the
//! first-prefix rule gives a mean 0.85 % low and 92.4 % coverage; the
//! pilot rule 0.2 % (within noise) and 94.9 %.

use lumest::run::{Batch, BatchWork, RunConfig, Stop, StopReason, drive};
use lumest::sampling::Philox4x32;
use lumest::tally::{Welford, t_factor};

const SIGMA: f64 = 0.6;
const TARGET: f64 = 0.08;
const RUNS: u64 = 4000;

/// A standard normal draw from `rng` (Box-Muller; 1 - u1 lies in (0, 1]).
fn normal(rng: &mut Philox4x32) -> f64 {
    let [u1, u2] = rng.next_2d();
    (-2.0 * (1.0 - u1).ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The lognormal batch mean (mean exactly 1) of the standard normal `z`.
fn lognormal_of(z: f64) -> f64 {
    (SIGMA * z - 0.5 * SIGMA * SIGMA).exp()
}

/// Lognormal batch mean of batch `b` on the stream of `seed`: mean 1.
fn lognormal(seed: u64, b: u64) -> f64 {
    lognormal_of(normal(&mut Philox4x32::new(seed, b)))
}

/// One receiver with lognormal batch means and no exact part.
struct Skewed;

impl BatchWork for Skewed {
    fn len(&self) -> usize {
        1
    }
    fn direct(&self) -> &[f64] {
        &[0.0]
    }
    fn emits(&self) -> bool {
        true
    }
    fn scratch_len(&self, _buckets: usize) -> usize {
        0
    }
    fn default_batch_size(&self, _chains: Option<u64>) -> u64 {
        1
    }
    fn run_batch(&self, cfg: &RunConfig, b: u64, bs: u64, _k: usize, _s: &mut [f64]) -> Batch {
        Batch {
            index: b,
            chains: bs,
            sums: vec![bs as f64 * lognormal(cfg.seed, b)],
            collisions: 0,
            scores: 0,
            near_hits: Vec::new(),
            direct_sums: Vec::new(),
        }
    }
}

/// Mean error, its standard error over the runs, and the coverage of the 95 % interval.
struct Outcome {
    bias: f64,
    bias_se: f64,
    coverage: f64,
}

fn judge(runs: &[(f64, f64, u64)]) -> Outcome {
    let mut err = Welford::new();
    let mut covered = 0;
    for &(mean, se, b) in runs {
        err.push(mean - 1.0);
        if (mean - 1.0).abs() <= t_factor(0.95, b) * se {
            covered += 1;
        }
    }
    Outcome {
        bias: err.mean(),
        bias_se: err.std_error(),
        coverage: covered as f64 / runs.len() as f64,
    }
}

/// The rule's outcome passes: unbiased within 3.5 standard errors, and the
/// 95 % interval covers 95 +- 2.5 % of the runs.
fn passes(o: &Outcome) -> bool {
    o.bias.abs() <= 3.5 * o.bias_se && (0.925..=0.975).contains(&o.coverage)
}

#[test]
fn pilot_rule_is_unbiased_and_calibrated_on_skewed_batch_means() {
    let runs: Vec<(f64, f64, u64)> = (0..RUNS)
        .map(|r| {
            let cfg = RunConfig {
                seed: 1000 + r,
                threads: 1,
                stop: Stop {
                    rel_error: Some(TARGET),
                    ..Stop::default()
                },
                ..RunConfig::default()
            };
            let res = drive(&Skewed, &cfg, &mut |_| true);
            assert_eq!(res.reason, StopReason::RelError);
            let pilot = res.pilot.expect("a --rel-error run has a pilot");
            assert_eq!(pilot.batches, 32);
            assert_eq!(res.tallies.batches(), pilot.planned);
            let w = &res.tallies.estimated[0];
            (w.mean(), w.std_error(), w.count())
        })
        .collect();
    let o = judge(&runs);
    let mean_batches = runs.iter().map(|r| r.2 as f64).sum::<f64>() / RUNS as f64;
    let met = runs.iter().filter(|r| r.1 / r.0 <= TARGET).count() as f64 / RUNS as f64;
    println!(
        "pilot rule: bias {:.4} +- {:.4}, coverage {:.4}, {mean_batches:.1} batches, target met in {met:.3}",
        o.bias, o.bias_se, o.coverage
    );
    assert!(
        passes(&o),
        "bias {} +- {}, coverage {}",
        o.bias,
        o.bias_se,
        o.coverage
    );
    // The margin meets the target in most runs: about 90 % for one receiver
    // with normal batch means; measured 77.6 % with these skewed ones (the
    // pilot's variance is then noisier than chi-square says).
    assert!(met > 0.7, "target met in only {met}");
}

/// An RMS target (`--rms-error`) over one receiver keeps the pilot's plan:
/// fewer than `CALIBRATION_RECEIVERS` effective receivers, so the count is
/// never planned on batches the estimate keeps. Judged as the pilot rule
/// above; measured with the gate off (every run calibrated on its own
/// first 32 batches): the mean 0.66 % +- 0.11 % low and 92.0 % coverage,
/// which fails this judgement, as does the first assertion.
#[test]
fn an_rms_target_over_one_receiver_keeps_the_pilot_plan() {
    let runs: Vec<(f64, f64, u64)> = (0..RUNS)
        .map(|r| {
            let cfg = RunConfig {
                seed: 1000 + r,
                threads: 1,
                stop: Stop {
                    rel_error: Some(TARGET),
                    rms: true,
                    ..Stop::default()
                },
                ..RunConfig::default()
            };
            let res = drive(&Skewed, &cfg, &mut |_| true);
            assert_eq!(res.reason, StopReason::RelError);
            let pilot = res.pilot.expect("a pilot");
            assert_eq!(pilot.calibration, 0, "{pilot:?}");
            assert_eq!(res.tallies.batches(), pilot.planned);
            let w = &res.tallies.estimated[0];
            (w.mean(), w.std_error(), w.count())
        })
        .collect();
    let o = judge(&runs);
    println!(
        "RMS over one receiver: bias {:.4} +- {:.4}, coverage {:.4}",
        o.bias, o.bias_se, o.coverage
    );
    assert!(
        passes(&o),
        "bias {} +- {}, coverage {}",
        o.bias,
        o.bias_se,
        o.coverage
    );
}

/// The test above has the power to see the old rule's fault: the same
/// judgement of the first-prefix rule (stop at the first `B >= 32` whose
/// estimated relative error meets the target) on the same kind of runs fails.
#[test]
fn first_prefix_rule_fails_the_same_judgement() {
    let runs: Vec<(f64, f64, u64)> = (0..RUNS)
        .map(|r| {
            let mut w = Welford::new();
            for b in 0.. {
                w.push(lognormal(5000 + r, b));
                if w.count() >= 32 && w.std_error() / w.mean() <= TARGET {
                    break;
                }
            }
            (w.mean(), w.std_error(), w.count())
        })
        .collect();
    let o = judge(&runs);
    println!(
        "first-prefix rule: bias {:.4} +- {:.4}, coverage {:.4}",
        o.bias, o.bias_se, o.coverage
    );
    assert!(
        !passes(&o),
        "bias {} +- {}, coverage {}",
        o.bias,
        o.bias_se,
        o.coverage
    );
}

/// An unreachable target without `--time` stops at the default time cap
/// (here set to 0.3 s) instead of running forever, and the pilot says how
/// long the target would take.
#[test]
fn an_unreachable_target_stops_at_the_time_cap() {
    let cfg = RunConfig {
        seed: 3,
        threads: 1,
        stop: Stop {
            chains: None,
            time: None,
            rel_error: Some(1e-7),
            rel_error_cap: Some(0.3),
            rms: false,
        },
        ..RunConfig::default()
    };
    let t = std::time::Instant::now();
    let r = drive(&Skewed, &cfg, &mut |_| true);
    let wall = t.elapsed().as_secs_f64();
    assert_eq!(r.reason, StopReason::Time);
    assert!(wall < 5.0, "took {wall} s");
    let p = r.pilot.expect("a pilot");
    assert_eq!(p.default_cap, Some(0.3));
    assert!(p.planned > 1_000_000_000 && p.estimated_time > 1e3, "{p:?}");
    assert!(r.tallies.batches() >= 32);
}

/// Work whose chains cost 20 microseconds each, with a large default batch.
struct Slow;

impl BatchWork for Slow {
    fn len(&self) -> usize {
        1
    }
    fn direct(&self) -> &[f64] {
        &[0.0]
    }
    fn emits(&self) -> bool {
        true
    }
    fn scratch_len(&self, _buckets: usize) -> usize {
        0
    }
    fn default_batch_size(&self, _chains: Option<u64>) -> u64 {
        1 << 16
    }
    fn run_batch(&self, cfg: &RunConfig, b: u64, bs: u64, _k: usize, _s: &mut [f64]) -> Batch {
        std::thread::sleep(std::time::Duration::from_micros(20 * bs));
        Batch {
            index: b,
            chains: bs,
            sums: vec![bs as f64 * lognormal(cfg.seed, b)],
            collisions: 0,
            scores: 0,
            near_hits: Vec::new(),
            direct_sums: Vec::new(),
        }
    }
}

/// `--time 1` on work whose 32 default batches take 42 s: the batches
/// shrink so that the run ends near the limit, with at least 32 batches.
#[test]
fn a_short_time_limit_shrinks_the_batches_instead_of_overrunning() {
    let cfg = RunConfig {
        seed: 9,
        threads: 2,
        stop: Stop {
            chains: None,
            time: Some(1.0),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let t = std::time::Instant::now();
    let r = drive(&Slow, &cfg, &mut |_| true);
    let wall = t.elapsed().as_secs_f64();
    let sizing = r.time_sizing.expect("sized by time");
    assert!(
        sizing.batch_size < 1 << 16 && sizing.batch_size >= 256,
        "{sizing:?}"
    );
    assert!(r.tallies.batches() >= 32);
    // Generous for a loaded machine; the old sizing took 42 s.
    assert!(wall < 6.0, "took {wall} s");
}

/// Receivers of the calibrated RMS test: lognormal batch means like
/// [`lognormal`]'s (mean exactly 1), with a tenth of the log-variance
/// common to all of them (points scored by the same chains).
struct SkewedMany;

const MANY: usize = 256;
const SHARED: f64 = 0.1;

impl BatchWork for SkewedMany {
    fn len(&self) -> usize {
        MANY
    }
    fn direct(&self) -> &[f64] {
        &[0.0; MANY]
    }
    fn emits(&self) -> bool {
        true
    }
    fn scratch_len(&self, _buckets: usize) -> usize {
        0
    }
    fn default_batch_size(&self, _chains: Option<u64>) -> u64 {
        1
    }
    fn run_batch(&self, cfg: &RunConfig, b: u64, bs: u64, _k: usize, _s: &mut [f64]) -> Batch {
        let mut rng = Philox4x32::new(cfg.seed, b);
        let common = normal(&mut rng);
        let sums = (0..MANY)
            .map(|_| {
                let z = SHARED.sqrt() * common + (1.0 - SHARED).sqrt() * normal(&mut rng);
                bs as f64 * lognormal_of(z)
            })
            .collect();
        Batch {
            index: b,
            chains: bs,
            sums,
            collisions: 0,
            scores: 0,
            near_hits: Vec::new(),
            direct_sums: Vec::new(),
        }
    }
}

/// An RMS target over many receivers (`--rms-error`) is planned from the
/// run's own first 32 batches, which the estimate keeps (in the spirit of
/// Stein's two-stage rule): the plan then leans a little on the noise of
/// the batches it keeps. With 256 skewed receivers (lognormal batch means,
/// skewness 2.3, a tenth of the log-variance shared) the tails cut the
/// effective receivers, so the pilot lets most runs but not all calibrate
/// (at least 80 %). Over the calibrated runs the mean error is within 3.5
/// standard errors of 0 (the error of each run's mean over its receivers,
/// over 1,500 runs: a bias of about 1/m of one receiver's 0.66 %, below
/// what this test resolves, is expected; see `lumest::run`), the 95 %
/// intervals cover 95 +- 2.5 % of the receivers and within 0.5 % of what
/// runs of a fixed count cover, and most runs meet the target.
#[test]
fn calibrated_rms_rule_is_unbiased_and_calibrated_on_skewed_batch_means() {
    const CAL_RUNS: u64 = 1500;
    let target = 0.08;
    let mut bias = Welford::new();
    let (mut covered, mut met, mut batches, mut calibrated) = (0u64, 0u64, 0u64, 0u64);
    for r in 0..CAL_RUNS {
        let cfg = RunConfig {
            seed: 20_000 + r,
            threads: 1,
            stop: Stop {
                rel_error: Some(target),
                rms: true,
                ..Stop::default()
            },
            ..RunConfig::default()
        };
        let res = drive(&SkewedMany, &cfg, &mut |_| true);
        assert_eq!(res.reason, StopReason::RelError);
        let pilot = res.pilot.expect("a pilot");
        assert_eq!(res.tallies.batches(), pilot.planned);
        // The gate is decided by the pilot, on streams of its own: judging
        // the calibrated runs alone selects nothing of the run's batches.
        if pilot.calibration == 0 {
            continue;
        }
        assert_eq!(pilot.calibration, 32);
        calibrated += 1;
        batches += pilot.planned;
        let mut run_err = 0.0;
        for w in &res.tallies.estimated {
            run_err += (w.mean() - 1.0) / MANY as f64;
            if (w.mean() - 1.0).abs() <= t_factor(0.95, w.count()) * w.std_error() {
                covered += 1;
            }
        }
        bias.push(run_err);
        if res.tallies.rms_rel_error(&res.direct) <= target {
            met += 1;
        }
    }
    let coverage = covered as f64 / (calibrated * MANY as u64) as f64;
    let met = met as f64 / calibrated as f64;
    println!(
        "calibrated RMS rule: {calibrated} of {CAL_RUNS} runs calibrated: bias {:.5} +- {:.5}, \
         coverage {coverage:.4}, {:.1} batches, met in {met:.3}",
        bias.mean(),
        bias.std_error(),
        batches as f64 / calibrated as f64
    );
    assert!(
        calibrated >= CAL_RUNS * 4 / 5,
        "{calibrated} runs calibrated"
    );
    // The reference: runs of a fixed count of batches (the calibrated
    // runs' mean), whose t intervals undercover these skewed means a little
    // by themselves (measured 93.8 %); the calibration adds nothing to it.
    let fixed = (batches as f64 / calibrated as f64).round() as u64;
    let mut fixed_covered = 0u64;
    for r in 0..CAL_RUNS {
        let cfg = RunConfig {
            seed: 40_000 + r,
            threads: 1,
            stop: Stop {
                chains: Some(fixed),
                ..Stop::default()
            },
            batch_size: Some(1),
            ..RunConfig::default()
        };
        let res = drive(&SkewedMany, &cfg, &mut |_| true);
        for w in &res.tallies.estimated {
            if (w.mean() - 1.0).abs() <= t_factor(0.95, w.count()) * w.std_error() {
                fixed_covered += 1;
            }
        }
    }
    let fixed_coverage = fixed_covered as f64 / (CAL_RUNS * MANY as u64) as f64;
    println!("{fixed} fixed batches: coverage {fixed_coverage:.4}");
    assert!(
        (coverage - fixed_coverage).abs() <= 0.005,
        "coverage {coverage}, fixed-count runs {fixed_coverage}"
    );
    assert!(
        bias.mean().abs() <= 3.5 * bias.std_error(),
        "bias {} +- {}",
        bias.mean(),
        bias.std_error()
    );
    assert!((0.925..=0.975).contains(&coverage), "coverage {coverage}");
    assert!(met > 0.7, "target met in only {met}");
}
