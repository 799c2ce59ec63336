//! Same seed, same result, bit for bit, whatever the thread count.

mod common;
use common::{chains_cfg, sobolev_run};
use lumest::run::{RunConfig, Stop};

fn bits(r: &lumest::run::RunResult) -> Vec<u64> {
    let mut v: Vec<u64> = r
        .tallies
        .estimated
        .iter()
        .flat_map(|w| [w.mean().to_bits(), w.std_error().to_bits()])
        .collect();
    v.extend(
        r.tallies
            .orders
            .iter()
            .flatten()
            .map(|w| w.mean().to_bits()),
    );
    v.push(r.chains);
    v.push(r.collisions);
    v
}

#[test]
fn identical_for_any_thread_count() {
    let p = (0.5, 0.5, 0.5, 0.5);
    let cfg = |t| RunConfig {
        orders: 2,
        ..chains_cfg(50_000, 42, t)
    };
    let (_, one) = sobolev_run(p, 30, 3.0, &cfg(1));
    let (_, two) = sobolev_run(p, 30, 3.0, &cfg(2));
    let (_, three) = sobolev_run(p, 30, 3.0, &cfg(3));
    assert_eq!(bits(&one), bits(&two));
    assert_eq!(bits(&one), bits(&three));
    let (_, other_seed) = sobolev_run(p, 30, 3.0, &chains_cfg(50_000, 43, 2));
    assert_ne!(bits(&one)[0], bits(&other_seed)[0]);
}

#[test]
fn rel_error_stop_is_reproducible() {
    let p = (0.5, 0.5, 0.5, 0.5);
    let cfg = |t| RunConfig {
        seed: 7,
        threads: t,
        stop: Stop {
            rel_error: Some(2e-3),
            time: Some(120.0),
            ..Stop::default()
        },
        batch_size: Some(512),
        ..RunConfig::default()
    };
    let (_, one) = sobolev_run(p, 10, 1.0, &cfg(1));
    let (_, two) = sobolev_run(p, 10, 1.0, &cfg(2));
    assert_eq!(one.reason, lumest::run::StopReason::RelError);
    assert!(one.tallies.max_rel_error(&one.direct) <= 2e-3);
    assert_eq!(bits(&one), bits(&two));
}

#[test]
fn a_short_time_limit_still_gives_enough_batches() {
    let cfg = RunConfig {
        seed: 1,
        stop: Stop {
            time: Some(1e-3),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let (_, r) = sobolev_run(
        (0.5, 0.5, 0.5, 0.5),
        4,
        1.0,
        &RunConfig {
            batch_size: Some(64),
            ..cfg
        },
    );
    assert!(r.tallies.batches() >= lumest::run::MIN_BATCHES);
    assert_eq!(r.reason, lumest::run::StopReason::Time);
}

/// A `--rel-error` run that sizes its own batches (two pilot stages here)
/// plans alike on any thread count, and its result is that of a
/// `--chains` run of the planned batches at the planned size.
#[test]
fn planned_batch_size_is_reproducible() {
    let p = (0.5, 0.5, 0.5, 0.5);
    let cfg = |t| RunConfig {
        seed: 11,
        threads: t,
        stop: Stop {
            rel_error: Some(5e-4),
            time: Some(120.0),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let (_, one) = sobolev_run(p, 4, 1.0, &cfg(1));
    let (_, three) = sobolev_run(p, 4, 1.0, &cfg(3));
    assert_eq!(one.reason, lumest::run::StopReason::RelError);
    let pilot = one.pilot.expect("a pilot");
    assert_eq!(pilot.stages, 2, "{pilot:?}");
    assert!(one.batch_size > 256 && one.tallies.batches() >= 32);
    assert_eq!(bits(&one), bits(&three));
    let fixed = RunConfig {
        batch_size: Some(one.batch_size),
        ..chains_cfg(one.chains, 11, 2)
    };
    let (_, again) = sobolev_run(p, 4, 1.0, &fixed);
    assert_eq!(bits(&one), bits(&again));
}
