//! Long chains as the reflectance approaches 1: the analog walk has the
//! geometric length 1/(1 - rho), and the default Russian roulette leaves no
//! truncation bias at rho = 0.99 (against the exact solution).

mod common;
use common::{chains_cfg, sobolev_run, z};
use lumest::chain::ChainParams;
use lumest::run::RunConfig;
use lumest::tally::sidak_bound;

#[test]
fn analog_chain_length_is_geometric() {
    // Between the Sobolev planes every ray meets a plane; with the analog game
    // (rr_weight = 1) each collision survives with probability rho, so the
    // number of collisions is geometric with mean 1/(1-rho), variance rho/(1-rho)^2.
    let rhos = [0.5, 0.9, 0.99];
    let bound = sidak_bound(1e-3, rhos.len(), None);
    for (k, rho) in rhos.into_iter().enumerate() {
        let cfg = RunConfig {
            chain: ChainParams {
                rr_weight: 1.0,
                guide: true,
                max_order: None,
            },
            ..chains_cfg(200_000, 90 + k as u64, 0)
        };
        let (_, r) = sobolev_run((0.5, 0.5, rho, rho), 2, 1.0, &cfg);
        let n = r.chains as f64;
        let mean = r.collisions as f64 / n;
        let se = (rho / (1.0 - rho).powi(2) / n).sqrt();
        let zz = (mean - 1.0 / (1.0 - rho)) / se;
        assert!(
            zz.abs() < bound,
            "rho {rho}: mean length {mean}, expected {} (z = {zz})",
            1.0 / (1.0 - rho)
        );
    }
}

#[test]
fn no_truncation_bias_at_rho_099() {
    let p = (0.5, 0.5, 0.99, 0.99);
    let n = 8;
    let (case, r) = sobolev_run(p, n, 2.0, &chains_cfg(100_000, 7, 0));
    // About ln(0.1)/ln(0.99) + 1/(1 - 0.99) = 329 collisions per chain.
    let length = r.collisions as f64 / r.chains as f64;
    assert!(length > 250.0 && length < 400.0, "{length}");
    let bound = sidak_bound(1e-3, n, Some(r.tallies.batches()));
    for j in 0..n {
        let zz = z(&r, j, case.exact[j].e);
        assert!(zz.abs() < bound, "point {j}: z = {zz}");
    }
}

#[test]
fn integrating_sphere_analog_chains_have_length_one_over_one_minus_rho() {
    // In a closed sphere every ray meets the wall: with the analog game the
    // number of collisions is geometric with mean 1/(1 - rho); with the
    // default roulette the estimate at rho = 0.99 stays exact (no truncation).
    use lumest::cases::integrating_sphere::sphere_case;
    use lumest::estimator::Receivers;
    use lumest::estimator::local::run;
    let rhos = [0.5, 0.9, 0.99];
    let bound = sidak_bound(1e-3, rhos.len(), None);
    for (k, rho) in rhos.into_iter().enumerate() {
        let case = sphere_case(rho, 1.0, glam::DVec3::new(0.2, -0.5, 0.1), 4, false);
        let rec = Receivers::from_receivers(&case.scene, &case.receivers).unwrap();
        let cfg = RunConfig {
            chain: ChainParams {
                rr_weight: 1.0,
                guide: true,
                max_order: None,
            },
            ..chains_cfg(100_000, 40 + k as u64, 0)
        };
        let r = run(&case.scene, &rec, &cfg, &mut |_| true);
        let n = r.chains as f64;
        let mean = r.collisions as f64 / n;
        let se = (rho / (1.0 - rho).powi(2) / n).sqrt();
        let zz = (mean - 1.0 / (1.0 - rho)) / se;
        assert!(zz.abs() < bound, "rho {rho}: mean length {mean} (z = {zz})");
        for j in 0..4 {
            let zj = z(&r, j, case.exact[j]);
            assert!(
                zj.abs() < sidak_bound(1e-3, 12, Some(r.tallies.batches())),
                "rho {rho}, point {j}: z = {zj}"
            );
        }
    }
}
