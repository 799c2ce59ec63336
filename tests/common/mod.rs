//! Helpers shared by the integration tests.
#![allow(dead_code)]

use lumest::commands::validate::{SobolevCase, sobolev_case};
use lumest::estimator::Receivers;
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, RunResult, Stop, run};

/// A Sobolev case with `n` points and a run of `chains` chains.
pub fn sobolev_run(
    p: (f64, f64, f64, f64),
    n: usize,
    r_max: f64,
    cfg: &RunConfig,
) -> (SobolevCase, RunResult) {
    let s = Sobolev::new(p.0, p.1, p.2, p.3, 1.0).unwrap();
    let case = sobolev_case(&s, n, r_max);
    let rec = Receivers::new(&case.scene, &case.points).unwrap();
    let r = run(&case.scene, &rec, cfg, &mut |_| true);
    (case, r)
}

/// A configuration with a fixed number of chains.
pub fn chains_cfg(chains: u64, seed: u64, threads: usize) -> RunConfig {
    RunConfig {
        seed,
        threads,
        stop: Stop {
            chains: Some(chains),
            ..Stop::default()
        },
        ..RunConfig::default()
    }
}

/// z score of point `j` against an exact total `exact` [lx].
pub fn z(r: &RunResult, j: usize, exact: f64) -> f64 {
    let w = &r.tallies.indirect[j];
    (r.direct[j] + w.mean() - exact) / w.std_error()
}
