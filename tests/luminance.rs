//! Luminance by the double local estimate and the backward estimator against
//! the exact Sobolev luminance `rho_j E_j(r') / pi`; views that see nothing.

mod common;
use common::{chains_cfg, max_abs_z, z, zcheck};
use glam::DVec3;
use lumest::cases::sobolev::{sobolev_case, sobolev_receivers};
use lumest::estimator::local::run;
use lumest::estimator::{Receivers, ViewTarget, view_target};
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, Stop};
use lumest::tally::sidak_bound;

#[test]
fn double_local_estimate_matches_exact_luminance_with_points_in_the_same_run() {
    let mut worst: f64 = 0.0;
    let mut m = 0;
    let mut batches = u64::MAX;
    for (k, p) in [(0.5, 0.5, 0.5, 0.5), (0.3, 0.7, 0.9, 0.6)]
        .into_iter()
        .enumerate()
    {
        let s = Sobolev::new(p.0, p.1, p.2, p.3, 1.0).unwrap();
        let (case, all, exact) = sobolev_receivers(&s, 10, 16, 2.0);
        let rec = Receivers::from_receivers(&case.scene, &all).unwrap();
        let r = run(
            &case.scene,
            &rec,
            &chains_cfg(200_000, 70 + k as u64, 0),
            &mut |_| true,
        );
        batches = batches.min(r.tallies.batches());
        for (j, &e) in exact.iter().enumerate() {
            worst = zcheck::max_abs(worst, z(&r, j, e));
        }
        m += exact.len();
    }
    let bound = sidak_bound(1e-3, m, Some(batches));
    assert!(worst < bound, "max |z| {worst} >= {bound}");
}

#[test]
fn backward_estimator_matches_exact_values() {
    let s = Sobolev::new(0.5, 0.5, 0.6, 0.7, 1.0).unwrap();
    let (case, all, exact) = sobolev_receivers(&s, 6, 6, 2.0);
    let rec = Receivers::from_receivers(&case.scene, &all).unwrap();
    let cfg = RunConfig {
        seed: 9,
        stop: Stop {
            chains: Some(20_000),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let r = lumest::backward::run(&case.scene, &rec, &cfg, &mut |_| true);
    let worst = max_abs_z((0..exact.len()).map(|j| z(&r, j, exact[j])));
    let bound = sidak_bound(1e-3, exact.len(), Some(r.tallies.batches()));
    assert!(worst < bound, "max |z| {worst} >= {bound}");
    // Thread count does not matter for the backward estimator either.
    let r1 = lumest::backward::run(
        &case.scene,
        &rec,
        &RunConfig {
            threads: 1,
            ..cfg.clone()
        },
        &mut |_| true,
    );
    let r2 = lumest::backward::run(
        &case.scene,
        &rec,
        &RunConfig { threads: 2, ..cfg },
        &mut |_| true,
    );
    for j in 0..exact.len() {
        assert_eq!(
            r1.tallies.estimated[j].mean().to_bits(),
            r2.tallies.estimated[j].mean().to_bits()
        );
    }
}

#[test]
fn views_that_miss_or_meet_a_back_side_see_nothing() {
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    // Parallel to the planes: leaves the scene.
    assert_eq!(
        view_target(&case.scene, DVec3::new(0.0, 0.0, 0.5), DVec3::X),
        ViewTarget::Miss
    );
    // From below the floor looking up: meets the floor's back side.
    match view_target(&case.scene, DVec3::new(0.0, 0.0, -1.0), DVec3::Z) {
        ViewTarget::Back { p } => assert_eq!(p, DVec3::ZERO),
        t => panic!("expected a back side, got {t:?}"),
    }
    // An observer standing on the floor looking up sees the ceiling, not the floor.
    match view_target(&case.scene, DVec3::new(0.3, 0.0, 0.0), DVec3::Z) {
        ViewTarget::Front(r) => assert!((r.p - DVec3::new(0.3, 0.0, 1.0)).length() < 1e-15),
        t => panic!("expected the ceiling, got {t:?}"),
    }
}
