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

/// A `--rel-error` shard run apart (here the whole run as shard 0 of 1),
/// which cannot grow its batches with the others and so plans them from a
/// pilot that sizes them (two pilot stages here), plans alike on any
/// thread count, and its batches fold to a `--chains` run of the planned
/// batches at the planned size.
#[test]
fn planned_batch_size_is_reproducible() {
    let p = (0.5, 0.5, 0.5, 0.5);
    let cfg = |t| RunConfig {
        seed: 11,
        threads: t,
        stop: Stop {
            rel_error: Some(5e-4),
            ..Stop::default()
        },
        shard: Some((0, 1)),
        ..RunConfig::default()
    };
    let (_, one) = sobolev_run(p, 4, 1.0, &cfg(1));
    let (_, three) = sobolev_run(p, 4, 1.0, &cfg(3));
    assert_eq!(one.reason, lumest::run::StopReason::RelError);
    let pilot = one.pilot.expect("a pilot");
    assert_eq!((pilot.stages, pilot.grown), (2, 0), "{pilot:?}");
    assert!(one.batch_size > 256 && one.batches.len() >= 32);
    let fixed = RunConfig {
        batch_size: Some(one.batch_size),
        ..chains_cfg(one.chains, 11, 2)
    };
    let (_, again) = sobolev_run(p, 4, 1.0, &fixed);
    let fold = |r: &lumest::run::RunResult| {
        let mut t = lumest::run::Tallies::new(4, 0);
        t.watched = again.tallies.watched.clone();
        let folded = lumest::run::fold_batches(t, &r.direct, r.batch_size, &r.batches);
        lumest::run::RunResult {
            tallies: folded,
            batches: Vec::new(),
            ..r.clone()
        }
    };
    assert_eq!(bits(&fold(&one)), bits(&fold(&three)));
    assert_eq!(bits(&fold(&one)), bits(&again));
    assert!(again.tallies.max_rel_error(&again.direct) <= 5e-4);
}

/// An `--rms-error` run over many points whose batches do not grow (here:
/// `--batch-size` given) plans from its own first 32 batches: it plans
/// alike on any thread count, its result is that of a `--chains` run of
/// the planned batches, and its shards (each runs the first 32 batches to
/// plan, and keeps its own, or they share those out) fold to the same
/// result.
#[test]
fn calibrated_rms_plan_is_reproducible_and_shards_alike() {
    let p = (0.5, 0.5, 0.5, 0.5);
    let cfg = |t| RunConfig {
        seed: 13,
        threads: t,
        stop: Stop {
            rel_error: Some(1e-3),
            rms: true,
            time: Some(120.0),
            ..Stop::default()
        },
        batch_size: Some(1024),
        ..RunConfig::default()
    };
    let n = 60;
    let (case, one) = sobolev_run(p, n, 3.0, &cfg(1));
    let (_, three) = sobolev_run(p, n, 3.0, &cfg(3));
    assert_eq!(one.reason, lumest::run::StopReason::RelError);
    let pilot = one.pilot.expect("a pilot");
    assert_eq!(pilot.calibration, 32, "{pilot:?}");
    assert!(pilot.planned > 32, "{pilot:?}");
    assert_eq!(one.tallies.batches(), pilot.planned);
    assert!(one.tallies.rms_rel_error(&one.direct) <= 1e-3);
    assert_eq!(bits(&one), bits(&three));
    let fixed = RunConfig {
        batch_size: Some(one.batch_size),
        ..chains_cfg(one.chains, 13, 2)
    };
    let (_, again) = sobolev_run(p, n, 3.0, &fixed);
    assert_eq!(bits(&one), bits(&again));
    // Three shards, folded in batch order.
    let rec = lumest::estimator::Receivers::new(&case.scene, &case.points).unwrap();
    let mut batches = Vec::new();
    let mut checks = None;
    for i in 0..3 {
        let shard = RunConfig {
            shard: Some((i, 3)),
            stop: Stop {
                time: None,
                ..cfg(2).stop
            },
            ..cfg(2)
        };
        let r = lumest::estimator::local::run(&case.scene, &rec, &shard, &mut |_| true);
        assert_eq!(r.total_batches, pilot.planned);
        assert_eq!(r.pilot.as_ref().map(|p| p.calibration_traced), Some(32));
        batches.extend(r.batches);
        checks.get_or_insert(r.tallies);
    }
    batches.sort_by_key(|b| b.index);
    assert_eq!(batches.len() as u64, pilot.planned);
    let folded = lumest::run::fold_batches(
        checks.clone().unwrap(),
        &one.direct,
        one.batch_size,
        &batches,
    );
    assert_eq!(folded.estimated.len(), one.tallies.estimated.len());
    for (a, b) in folded.estimated.iter().zip(&one.tallies.estimated) {
        assert_eq!(a.mean().to_bits(), b.mean().to_bits());
        assert_eq!(a.std_error().to_bits(), b.std_error().to_bits());
    }
    // Three shards at once that share the planning batches (as MPI ranks
    // do, here through memory): each traces its own 10 or 11 of the 32,
    // and the fold is the same again.
    let share = common::share_through_memory(3);
    let shared: Vec<lumest::run::RunResult> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..3)
            .map(|i| {
                let shard = RunConfig {
                    shard: Some((i, 3)),
                    share: Some(share.clone()),
                    stop: Stop {
                        time: None,
                        ..cfg(1).stop
                    },
                    ..cfg(1)
                };
                let (scene, rec) = (&case.scene, &rec);
                s.spawn(move || lumest::estimator::local::run(scene, rec, &shard, &mut |_| true))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let mut batches = Vec::new();
    for (i, r) in shared.into_iter().enumerate() {
        let p = r.pilot.expect("a pilot");
        assert_eq!(p.calibration_traced, if i < 2 { 11 } else { 10 }, "{p:?}");
        batches.extend(r.batches);
    }
    batches.sort_by_key(|b| b.index);
    let again = lumest::run::fold_batches(checks.unwrap(), &one.direct, one.batch_size, &batches);
    for (a, b) in again.estimated.iter().zip(&one.tallies.estimated) {
        assert_eq!(a.mean().to_bits(), b.mean().to_bits());
        assert_eq!(a.std_error().to_bits(), b.std_error().to_bits());
    }
}
