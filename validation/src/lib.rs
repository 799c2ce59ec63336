//! Heavy validation of lumest against exact references.
//!
//! The fast subset runs with the test suite (`tests/` of the main crate);
//! the heavy cases here run with
//! `cargo test --release -p lumest-validation -- --ignored`.

use lumest::cases::sobolev::sobolev_case;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, Stop};
use lumest::tally::sidak_bound;

/// Outcome of one Sobolev configuration.
#[derive(Clone, Debug)]
pub struct SobolevCheck {
    /// (h1, h2, rho1, rho2).
    pub params: (f64, f64, f64, f64),
    /// z score per point.
    pub z: Vec<f64>,
    /// Batches behind each z.
    pub batches: u64,
    /// RMS relative standard error of E.
    pub rms_rel_err: f64,
}

/// Run the Monte Carlo solver on a Sobolev configuration and score it against the exact values.
pub fn check_sobolev(
    params: (f64, f64, f64, f64),
    points: usize,
    r_max: f64,
    chains: u64,
    seed: u64,
) -> SobolevCheck {
    let s = Sobolev::new(params.0, params.1, params.2, params.3, 1.0).expect("valid parameters");
    let case = sobolev_case(&s, points, r_max);
    let rec = Receivers::new(&case.scene, &case.points).expect("valid points");
    let cfg = RunConfig {
        seed,
        stop: Stop {
            chains: Some(chains),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let r = run(&case.scene, &rec, &cfg, &mut |_| true);
    let z = (0..points)
        .map(|j| {
            let w = &r.tallies.estimated[j];
            (r.direct[j] + w.mean() - case.exact[j].e) / w.std_error()
        })
        .collect();
    SobolevCheck {
        params,
        z,
        batches: r.tallies.batches(),
        rms_rel_err: r.tallies.rms_rel_error(&r.direct),
    }
}

/// True when the largest |z| over all checks is inside the Sidak bound at family rate `alpha`.
pub fn passes(checks: &[SobolevCheck], alpha: f64) -> (bool, f64, f64) {
    let m: usize = checks.iter().map(|c| c.z.len()).sum();
    let b = checks.iter().map(|c| c.batches).min().unwrap_or(2);
    let worst = checks
        .iter()
        .flat_map(|c| c.z.iter())
        .fold(0.0f64, |a, z| a.max(z.abs()));
    let bound = sidak_bound(alpha, m, Some(b));
    (worst < bound, worst, bound)
}
