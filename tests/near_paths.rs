//! Each receiver's near-part paths chosen by a fixed pilot
//! (`lumest::estimator::near_paths`): more where the near part decides the
//! error, the least `(sum a + b / q)(C + sum q c)` of the module docs, the
//! same counts for any thread count, and estimates that stay right with
//! them (the paths' weights follow each receiver's own count).

mod common;
use common::{chains_cfg, from_floor};
use glam::DVec3;
use lumest::cases::sobolev::sobolev_case;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::estimator::near_paths::{Allocation, MAX_PATHS, MIN_PATHS};
use lumest::reference::Sobolev;
use lumest::run::RunConfig;
use lumest::tally::sidak_bound;

/// Two planes (h = 0.5, rho = 0.5); points facing the floor at these
/// heights above the source's foot, every one with a 5 cm split.
fn setup(heights: &[f64]) -> (Sobolev, lumest::cases::sobolev::SobolevCase, Receivers) {
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let pts: Vec<_> = heights
        .iter()
        .map(|&z| (DVec3::new(0.0, 0.0, z), -DVec3::Z))
        .collect();
    let rec = Receivers::new(&case.scene, &pts)
        .unwrap()
        .with_near_field(0.05, 16);
    (s, case, rec)
}

/// The module's objective, the RMS relative variance times the cost per
/// batch (up to constant factors), at paths `q_j` per chain.
fn objective(a: &Allocation, q: &[f64]) -> f64 {
    let var: f64 = a.far_var.iter().sum::<f64>()
        + (0..q.len())
            .filter(|&j| q[j] > 0.0)
            .map(|j| a.near_var[j] / q[j])
            .sum::<f64>();
    let cost = a.chain_cost + (0..q.len()).map(|j| q[j] * a.path_cost[j]).sum::<f64>();
    var * cost
}

#[test]
fn the_counts_are_the_least_of_the_objective_and_follow_the_near_parts_variance() {
    // 1 mm above the floor (the near part carries nearly all the light, the
    // far part almost none), 3 cm (both parts weigh) and 25 cm (no surface
    // within the radius: an empty near part).
    let (_, case, rec) = setup(&[1e-3, 0.03, 0.25]);
    let (rec, a) = rec.with_allocated_near_paths(&case.scene, &RunConfig::default());
    eprintln!("{a:?}");
    assert!(a.near_var[0] > 0.0 && a.near_var[1] > 0.0 && a.near_var[2] == 0.0);
    assert_eq!(
        a.paths[2], MIN_PATHS,
        "an empty near part gets the fewest paths"
    );
    assert!(
        a.paths
            .iter()
            .all(|&p| (MIN_PATHS..=MAX_PATHS).contains(&p))
    );
    for j in 0..3 {
        assert_eq!(rec.near_paths_at(j), a.paths[j]);
    }
    // The least of the objective over every whole count in the bounds
    // (up to the rounding of the continuous optimum to a whole path).
    let q: Vec<f64> = a.paths.iter().map(|&p| f64::from(p) / 256.0).collect();
    let best = objective(&a, &q);
    let mut least = f64::INFINITY;
    for p0 in MIN_PATHS..=MAX_PATHS {
        for p1 in MIN_PATHS..=MAX_PATHS {
            for p2 in [MIN_PATHS, MIN_PATHS + 1, MAX_PATHS] {
                let o = objective(&a, &[p0, p1, p2].map(|p| f64::from(p) / 256.0));
                least = least.min(o);
            }
        }
    }
    assert!(
        best <= least * (1.0 + 1e-3),
        "{best} vs the grid's least {least}"
    );
    assert!(best < objective(&a, &[16.0 / 256.0; 3]));
    // Where both parts weigh (3 cm) the count rises above the fixed 16; at
    // 1 mm the near part is nearly exact from 16 and stays at the bound,
    // as does the empty one.
    assert!(
        a.paths[1] > MIN_PATHS && a.paths[1] < MAX_PATHS,
        "{:?}",
        a.paths
    );
    assert_eq!(a.paths[0], MIN_PATHS, "{:?}", a.paths);
}

#[test]
fn the_counts_are_the_same_for_any_thread_count() {
    let (_, case, rec) = setup(&[1e-3, 0.03, 0.25]);
    let alloc = |t: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(|| {
                rec.clone()
                    .with_allocated_near_paths(&case.scene, &RunConfig::default())
                    .1
            })
    };
    let (one, two) = (alloc(1), alloc(2));
    assert_eq!(one, two);
    assert_eq!(format!("{one:?}"), format!("{two:?}"));
}

#[test]
fn estimates_with_allocated_counts_agree_with_the_exact_values() {
    let heights = [1e-3, 0.03, 0.25];
    let (s, case, rec) = setup(&heights);
    let exact: Vec<f64> = heights
        .iter()
        .map(|&z| from_floor(0.5, z, |x| s.illuminance(1, x).e))
        .collect();
    let (_, a) = rec
        .clone()
        .with_allocated_near_paths(&case.scene, &RunConfig::default());
    // The count at 3 cm differs from the fixed 16, so that weights taken
    // from the wrong count would show (its near part is about 64 % of E).
    assert!(a.paths[1] > 16, "{:?}", a.paths);
    // Default batches (4096 chains here) and batches of 256.
    let runs = [None, Some(256)];
    let bound = sidak_bound(1e-3, heights.len() * runs.len(), None);
    for bs in runs {
        let cfg = RunConfig {
            batch_size: bs,
            ..chains_cfg(524_288, 3, 0)
        };
        // `run` allocates itself: the defaults have `near_paths_auto`, and
        // the receivers carry the split's radius but no counts yet.
        assert!(cfg.near_paths_auto);
        let rec = Receivers::new(
            &case.scene,
            &heights
                .iter()
                .map(|&z| (DVec3::new(0.0, 0.0, z), -DVec3::Z))
                .collect::<Vec<_>>(),
        )
        .unwrap();
        let cfg = RunConfig {
            near: (0.05, 16),
            near_auto: false,
            ..cfg
        };
        let r = run(&case.scene, &rec, &cfg, &mut |_| true);
        for (j, &ex) in exact.iter().enumerate() {
            let w = &r.tallies.estimated[j];
            let z = (w.mean() - ex) / w.std_error();
            eprintln!(
                "bs {bs:?} point {j}: {} +- {} vs {ex} (z {z:.2})",
                w.mean(),
                w.std_error()
            );
            assert!(z.abs() < bound, "bs {bs:?} point {j}: z {z}");
            // Precise enough that a 2 % error lies beyond the bound.
            assert!(0.02 * ex > 4.0 * w.std_error(), "bs {bs:?} point {j}");
            assert_eq!(r.tallies.diagnostics(j, 0.0).flag(), "ok", "point {j}");
        }
    }
}

#[test]
fn the_command_line_takes_auto_or_a_count() {
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_lumest"))
        .args([
            "illuminance",
            "--scene",
            "data/sobolev.toml",
            "--near-paths",
            "many",
        ])
        .args(["--points", "data/sobolev_points.csv", "--out", "/dev/null"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("--near-paths must be `auto` or a whole number"),
        "{err}"
    );
}

/// A command that owns its receivers sets the split on them in place
/// (`local::prepare`, one set of receivers in memory rather than two): the
/// run gives the same bits as the estimator setting it on its own copy.
#[test]
fn receivers_prepared_in_place_give_the_same_bits() {
    let heights = [1e-3, 0.03, 0.25];
    let (_, case, _) = setup(&heights);
    let pts: Vec<_> = heights
        .iter()
        .map(|&z| (DVec3::new(0.0, 0.0, z), -DVec3::Z))
        .collect();
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let cfg = RunConfig {
        near: (0.05, 16),
        near_auto: false,
        ..chains_cfg(65_536, 4, 0)
    };
    let copy = run(&case.scene, &rec, &cfg, &mut |_| true);
    let mut own = rec.clone();
    lumest::estimator::local::prepare(&case.scene, &mut own, &cfg);
    assert!(own.near_prepared() && own.near_field().0 > 0);
    assert!(own.near_paths_at(1) > 16, "the counts are allocated too");
    let prepared = run(&case.scene, &own, &cfg, &mut |_| true);
    for j in 0..pts.len() {
        assert_eq!(
            copy.tallies.estimated[j].mean().to_bits(),
            prepared.tallies.estimated[j].mean().to_bits()
        );
        assert_eq!(
            copy.tallies.estimated[j].std_error().to_bits(),
            prepared.tallies.estimated[j].std_error().to_bits()
        );
    }
}
