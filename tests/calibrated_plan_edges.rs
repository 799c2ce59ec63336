//! Edge cases of an `--rms-error` run planned on its own first 32 batches
//! (`lumest::run`, module docs): its result must be, bit for bit, that of
//! `--chains B*bs --batch-size bs` with the same seed, the same kept batch
//! means and the same order buckets, for any thread count and for its
//! shards folded; an interrupted or time-capped run keeps what a plain run
//! keeps. Synthetic work, so that each run takes milliseconds.

use lumest::run::{
    Batch, BatchWork, RunConfig, RunResult, Stop, StopReason, Tallies, drive, fold_batches,
};
use lumest::sampling::Philox4x32;

/// `N` receivers with normal batch means (a tenth of the variance common
/// to all), relative variance per chain 1, split over the order buckets.
struct Grid;

const N: usize = 48;
const DIRECT: [f64; N] = [0.5; N];

impl BatchWork for Grid {
    fn len(&self) -> usize {
        N
    }
    fn direct(&self) -> &[f64] {
        &DIRECT
    }
    fn emits(&self) -> bool {
        true
    }
    fn scratch_len(&self, _buckets: usize) -> usize {
        0
    }
    fn default_batch_size(&self, chains: Option<u64>) -> u64 {
        lumest::run::cap_batch_size(4096, chains)
    }
    fn run_batch(&self, cfg: &RunConfig, b: u64, bs: u64, k: usize, _s: &mut [f64]) -> Batch {
        let mut rng = Philox4x32::new(cfg.seed, b);
        let mut normal = || {
            let [u1, u2] = rng.next_2d();
            (-2.0 * (1.0 - u1).ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        };
        let common = normal();
        let mut sums = vec![0.0; k * N];
        for j in 0..N {
            let z = 0.1f64.sqrt() * common + 0.9f64.sqrt() * normal();
            let total = bs as f64 * (1.0 + z / (bs as f64).sqrt());
            for q in 0..k {
                sums[q * N + j] = total * (q + 1) as f64 / (k * (k + 1) / 2) as f64;
            }
        }
        Batch {
            index: b,
            chains: bs,
            sums,
            collisions: 3 * bs,
            scores: 5 * bs,
            near_hits: Vec::new(),
            direct_sums: Vec::new(),
        }
    }
}

const TARGET: f64 = 1e-3;

fn rms_cfg(seed: u64, threads: usize) -> RunConfig {
    RunConfig {
        seed,
        threads,
        stop: Stop {
            rel_error: Some(TARGET),
            rms: true,
            ..Stop::default()
        },
        orders: 2,
        keep_batch_means: 5,
        ..RunConfig::default()
    }
}

fn plain_cfg(seed: u64, threads: usize, chains: u64, bs: u64) -> RunConfig {
    RunConfig {
        stop: Stop {
            chains: Some(chains),
            ..Stop::default()
        },
        batch_size: Some(bs),
        ..rms_cfg(seed, threads)
    }
}

/// Everything a run's tallies hold, bit for bit (Debug prints each f64
/// exactly).
fn state(t: &Tallies) -> String {
    format!("{t:?}")
}

fn run(cfg: &RunConfig) -> RunResult {
    drive(&Grid, cfg, &mut |_| true)
}

#[test]
fn calibrated_run_equals_the_plain_run_with_kept_means_and_orders() {
    let one = run(&rms_cfg(3, 1));
    let p = one.pilot.expect("a pilot");
    assert_eq!(p.calibration, 32, "{p:?}");
    assert!(p.planned > 40, "{p:?}");
    assert_eq!(one.reason, StopReason::RelError);
    assert_eq!(one.tallies.batches(), p.planned);
    assert_eq!(one.tallies.batch_means.receivers(), 5);
    assert_eq!(one.tallies.batch_means.batches() as u64, p.planned);
    let three = run(&rms_cfg(3, 3));
    assert_eq!(state(&one.tallies), state(&three.tallies));
    let plain = run(&plain_cfg(3, 2, one.chains, one.batch_size));
    assert_eq!(state(&one.tallies), state(&plain.tallies));
    assert_eq!(
        (one.chains, one.collisions, one.scores),
        (plain.chains, plain.collisions, plain.scores)
    );
}

/// Shards (a few, and more than 32, so that some hold no calibrating batch
/// and some no batch at all) fold to the whole run.
#[test]
fn calibrated_shards_fold_to_the_whole_run() {
    let whole = run(&rms_cfg(5, 2));
    let p = whole.pilot.unwrap();
    assert_eq!(p.calibration, 32);
    for m in [3, 40, p.planned + 7] {
        let mut batches = Vec::new();
        let mut chains = 0;
        for i in 0..m {
            let cfg = RunConfig {
                shard: Some((i, m)),
                ..rms_cfg(5, 2)
            };
            let r = run(&cfg);
            assert_eq!(r.total_batches, p.planned, "shard {i}/{m}");
            assert!(r.batches.iter().all(|b| b.index % m == i), "shard {i}/{m}");
            assert_eq!(r.chains, r.batches.iter().map(|b| b.chains).sum::<u64>());
            chains += r.chains;
            batches.extend(r.batches);
        }
        batches.sort_by_key(|b| b.index);
        assert_eq!(batches.len() as u64, p.planned, "m = {m}");
        let mut t = Tallies::new(N, 2);
        t.batch_means = lumest::tally::BatchMeans::new(5);
        let folded = fold_batches(t, &whole.direct, whole.batch_size, &batches);
        assert_eq!(state(&folded), state(&whole.tallies), "m = {m}");
        assert_eq!(chains, whole.chains, "m = {m}");
    }
}

/// `--chains` below the plan caps it, calibration included: the run is the
/// plain `--chains` run of that size.
#[test]
fn chains_cap_below_the_calibration() {
    let whole = run(&rms_cfg(7, 2));
    let bs = whole.batch_size;
    for batches in [2, 9, 32, 33] {
        let cfg = RunConfig {
            stop: Stop {
                chains: Some(batches * bs),
                ..rms_cfg(7, 2).stop
            },
            ..rms_cfg(7, 2)
        };
        let r = run(&cfg);
        let p = r.pilot.expect("a pilot");
        println!(
            "{batches} x {bs}: {} x {}, {p:?}",
            r.tallies.batches(),
            r.batch_size
        );
        assert_eq!(r.chains, r.tallies.batches() * r.batch_size, "{batches}");
        assert!(r.chains >= batches * bs, "{batches}");
        if p.calibration > 0 {
            assert!(p.planned > r.tallies.batches(), "{batches}");
            assert_eq!(r.reason, StopReason::Chains, "{batches}");
        }
        let plain = run(&plain_cfg(7, 1, r.chains, r.batch_size));
        assert_eq!(state(&r.tallies), state(&plain.tallies), "{batches}");
        // With --batch-size, fewer than 32 batches.
        let fixed = RunConfig {
            batch_size: Some(bs),
            ..cfg
        };
        let r = run(&fixed);
        let p = r.pilot.expect("a pilot");
        assert_eq!(p.calibration, batches.min(32), "{batches}: {p:?}");
        assert_eq!(r.tallies.batches(), batches, "{batches}");
        assert_eq!(r.reason, StopReason::Chains, "{batches}");
        let plain = run(&plain_cfg(7, 3, batches * bs, bs));
        assert_eq!(state(&r.tallies), state(&plain.tallies), "{batches}");
    }
}

/// Interrupted (the observer says stop) during the calibration or after
/// it, the run keeps what a plain run interrupted at the same batch keeps.
#[test]
fn an_interrupted_calibrated_run_keeps_what_a_plain_run_keeps() {
    let whole = run(&rms_cfg(9, 1));
    let bs = whole.batch_size;
    let pilot_batches = 32; // the pilot's observer calls come first
    for stop_after in [1u64, 5, 31, 32, 33, 50] {
        let mut calls = 0u64;
        let r = drive(&Grid, &rms_cfg(9, 3), &mut |_| {
            calls += 1;
            calls < pilot_batches + stop_after
        });
        assert_eq!(r.reason, StopReason::Observer, "{stop_after}");
        assert_eq!(r.tallies.batches(), stop_after, "{stop_after}");
        assert_eq!(r.tallies.batch_means.receivers(), 5, "{stop_after}");
        let mut calls = 0u64;
        let plain = drive(&Grid, &plain_cfg(9, 3, whole.chains, bs), &mut |_| {
            calls += 1;
            calls < stop_after
        });
        assert_eq!(state(&r.tallies), state(&plain.tallies), "{stop_after}");
        assert_eq!(r.chains, plain.chains, "{stop_after}");
    }
}

/// Stopped by `--time` at once, the run still folds the 32 calibrating
/// batches (a soft limit) and keeps only the kept receivers' means.
#[test]
fn a_time_capped_calibrated_run_is_consistent() {
    let cfg = RunConfig {
        stop: Stop {
            time: Some(1e-9),
            ..rms_cfg(11, 2).stop
        },
        ..rms_cfg(11, 2)
    };
    let r = run(&cfg);
    assert_eq!(r.reason, StopReason::Time);
    let p = r.pilot.unwrap();
    assert_eq!(p.calibration, 32);
    let b = r.tallies.batches();
    assert!(b >= 32, "{b}");
    assert_eq!(r.tallies.batch_means.receivers(), 5);
    assert_eq!(r.tallies.batch_means.batches() as u64, b);
    assert_eq!(r.chains, b * r.batch_size);
    let plain = run(&plain_cfg(11, 1, r.chains, r.batch_size));
    assert_eq!(state(&r.tallies), state(&plain.tallies));
}

/// Interrupted during its calibrating batches, the run reports the plan
/// those batches give: `B = k (R_k / target)^2 q` from the `k` measured,
/// near the whole calibration's plan, not the count of 32 batches at the
/// error of `k` (about 32 / k times too many).
#[test]
fn an_interrupted_calibration_reports_the_plan_its_batches_give() {
    let whole = run(&rms_cfg(13, 1)).pilot.unwrap();
    for k in [8u64, 16] {
        let mut calls = 0u64;
        let r = drive(&Grid, &rms_cfg(13, 2), &mut |_| {
            calls += 1;
            calls < 32 + k
        });
        let p = r.pilot.unwrap();
        assert_eq!(p.calibration, k);
        let ratio = p.planned as f64 / whole.planned as f64;
        println!(
            "{k} of 32 calibrating batches: planned {} (whole {})",
            p.planned, whole.planned
        );
        assert!(
            (0.6..=1.6).contains(&ratio),
            "{k}: planned {} against {}",
            p.planned,
            whole.planned
        );
    }
}

/// A shard stopped by its observer during the calibrating batches (which
/// it runs for every shard) returns only its own batches, with their
/// chains, as a shard stopped later does.
#[test]
fn an_interrupted_calibrating_shard_returns_only_its_own_batches() {
    for stop_after in [10u64, 40] {
        let mut calls = 0u64;
        let cfg = RunConfig {
            shard: Some((1, 3)),
            ..rms_cfg(15, 2)
        };
        let r = drive(&Grid, &cfg, &mut |_| {
            calls += 1;
            calls < 32 + stop_after
        });
        assert_eq!(r.reason, StopReason::Observer, "{stop_after}");
        assert!(!r.batches.is_empty(), "{stop_after}");
        assert!(
            r.batches.iter().all(|b| b.index % 3 == 1),
            "{stop_after}: {:?}",
            r.batches.iter().map(|b| b.index).collect::<Vec<_>>()
        );
        assert_eq!(
            r.chains,
            r.batches.iter().map(|b| b.chains).sum::<u64>(),
            "{stop_after}"
        );
    }
}
