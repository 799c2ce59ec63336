//! Finite geometry against exact answers: the integrating sphere (any source
//! position, rho up to 0.99), a point source over a square plate (quadrature
//! reference, occlusion under the plate), flux balance in a closed furnished
//! box, scale invariance from millimetres to 10 km, and agreement of the
//! forward and backward estimators where shapes occlude.

mod common;
use common::{chains_cfg, z};
use glam::DVec3;
use lumest::commands::cases::{Case, box_room, flux_balance, plate_case, sphere_case};
use lumest::estimator::{Receiver, Receivers};
use lumest::run::{RunResult, run};
use lumest::tally::sidak_bound;

fn run_case(case: &Case, chains: u64, seed: u64) -> RunResult {
    let rec = Receivers::from_receivers(&case.scene, &case.receivers).unwrap();
    run(&case.scene, &rec, &chains_cfg(chains, seed, 0), &mut |_| {
        true
    })
}

/// Max |z| over the receivers with a non-zero error bar; receivers with a
/// zero error bar must be exact.
fn max_z(case: &Case, r: &RunResult) -> f64 {
    let mut m: f64 = 0.0;
    for (j, &ex) in case.exact.iter().enumerate() {
        if r.tallies.indirect[j].std_error() == 0.0 {
            let e = r.direct[j] + r.tallies.indirect[j].mean();
            assert!(
                (e - ex).abs() <= 1e-12 * ex.abs(),
                "point {j}: {e} vs exact {ex}"
            );
            continue;
        }
        let zz = z(r, j, ex);
        assert!(zz.is_finite());
        m = m.max(zz.abs());
    }
    m
}

#[test]
fn integrating_sphere_is_uniform_and_exact_for_rho_up_to_0_99() {
    let cases = [
        (0.5, DVec3::new(0.3, -0.2, 0.45), 20_000),
        (0.9, DVec3::new(-0.6, 0.1, 0.2), 20_000),
        (0.99, DVec3::new(0.0, 0.0, -0.9), 4_000),
    ];
    for (k, (rho, src, chains)) in cases.into_iter().enumerate() {
        let case = sphere_case(rho, 1.7, src, 30, false);
        let r = run_case(&case, chains, 11 + k as u64);
        let bound = sidak_bound(
            1e-3,
            case.exact.len() * cases.len(),
            Some(r.tallies.batches()),
        );
        let m = max_z(&case, &r);
        assert!(m < bound, "rho {rho}: max |z| {m} >= {bound}");
        // No truncation: the chains run to their natural length ~ 1/(1 - rho) and beyond.
        let per_chain = r.collisions as f64 / r.chains as f64;
        assert!(
            per_chain > 1.0 / (1.0 - rho),
            "rho {rho}: {per_chain} collisions per chain"
        );
    }
}

#[test]
fn plate_matches_its_quadrature_reference_with_occlusion_underneath() {
    let case = plate_case(1.0, 0.8, 30);
    let r = run_case(&case, 400_000, 5);
    let bound = sidak_bound(1e-3, case.exact.len(), Some(r.tallies.batches()));
    let m = max_z(&case, &r);
    assert!(m < bound, "max |z| {m} >= {bound}");
    // The last receiver lies in the plate's shadow: exactly zero.
    let last = case.exact.len() - 1;
    assert_eq!(case.exact[last], 0.0);
    assert_eq!(r.direct[last] + r.tallies.indirect[last].mean(), 0.0);
}

#[test]
fn closed_box_room_absorbs_exactly_what_is_emitted_and_leaks_nothing() {
    let scene = box_room(0.8);
    let fb = flux_balance(&scene, 100_000, 32, 3);
    assert_eq!(fb.escaped, 0, "light leaked out of the closed room");
    assert_eq!(fb.back_side, 0, "light reached a black back side");
    let zz = (fb.total.mean() - fb.emitted) / fb.total.std_error();
    assert!(
        zz.abs() < sidak_bound(1e-3, 1, Some(fb.total.count())),
        "z = {zz}"
    );
}

#[test]
fn plate_answers_follow_the_scale_law_from_millimetres_to_ten_kilometres() {
    let base = plate_case(1.0, 0.8, 12);
    let r1 = run_case(&base, 100_000, 9);
    for s in [1e-3, 1e4] {
        let case = plate_case(s, 0.8, 12);
        let r = run_case(&case, 100_000, 9);
        let bound = sidak_bound(1e-3, case.exact.len(), Some(r.tallies.batches()));
        let m = max_z(&case, &r);
        assert!(m < bound, "scale {s}: max |z| {m} >= {bound}");
        // Same chains, scaled geometry: the estimates agree up to s^2 to rounding.
        for j in 0..case.exact.len() {
            let e1 = r1.direct[j] + r1.tallies.indirect[j].mean();
            let es = (r.direct[j] + r.tallies.indirect[j].mean()) * s * s;
            let ex = (case.exact[j] * s * s - base.exact[j]).abs() / base.exact[j].max(1e-300);
            assert!(
                ex < 1e-11 || base.exact[j] == 0.0,
                "scale {s}: exact {j} differs by {ex}"
            );
            assert!(
                (es - e1).abs() <= 1e-6 * e1.abs(),
                "scale {s}, point {j}: {es} vs {e1}"
            );
        }
    }
}

#[test]
fn forward_and_backward_agree_in_the_furnished_box() {
    let scene = box_room(0.7);
    // Points on the work plane, on the desk top, on the desk's side, on the
    // floor, on the partition's both sides, on a wall and the ceiling.
    let pts = [
        (DVec3::new(0.5, 0.5, 0.75), DVec3::Z),
        (DVec3::new(1.8, 1.4, 0.75), DVec3::Z),
        (DVec3::new(2.6, 1.4, 0.4), DVec3::X),
        (DVec3::new(3.0, 3.0, 0.0), DVec3::Z),
        (DVec3::new(3.5, 1.0, 1.0), DVec3::X),
        (DVec3::new(3.5, 1.0, 1.0), -DVec3::X),
        (DVec3::new(4.5, 3.5, 1.5), -DVec3::Y),
        (DVec3::new(2.5, 2.0, 3.0), -DVec3::Z),
    ];
    let recs: Vec<Receiver> = pts
        .iter()
        .map(|&(p, n)| Receiver::illuminance(p, n))
        .collect();
    let rec = Receivers::from_receivers(&scene, &recs).unwrap();
    let fwd = run(&scene, &rec, &chains_cfg(200_000, 21, 0), &mut |_| true);
    let bwd = lumest::backward::run(&scene, &rec, &chains_cfg(20_000, 22, 0), &mut |_| true);
    let bound = sidak_bound(1e-3, pts.len(), None);
    for j in 0..pts.len() {
        assert_eq!(fwd.direct[j], bwd.direct[j]);
        let (a, b) = (&fwd.tallies.indirect[j], &bwd.tallies.indirect[j]);
        let zz = (a.mean() - b.mean()) / (a.std_error().powi(2) + b.std_error().powi(2)).sqrt();
        assert!(
            zz.abs() < bound,
            "point {j}: forward {} backward {} z {zz}",
            a.mean(),
            b.mean()
        );
    }
}
