//! Heavy statistical validation (minutes): run with `--ignored`.

use lumest_validation::{check_sobolev, passes};

#[test]
#[ignore = "heavy: minutes of CPU"]
fn sobolev_grid_of_configurations() {
    let mut checks = Vec::new();
    let configs = [
        (0.5, 0.5, 0.5, 0.5),
        (0.5, 0.5, 0.9, 0.9),
        (0.1, 0.9, 0.3, 0.95),
        (0.01, 1.0, 0.8, 0.8),
        (2.0, 0.5, 0.99, 0.5),
    ];
    for (k, p) in configs.into_iter().enumerate() {
        let c = check_sobolev(p, 200, 5.0, 4_000_000, 100 + k as u64);
        println!(
            "{p:?}: RMS R = {:.3e}, max |z| = {:.2}",
            c.rms_rel_err,
            c.z.iter().fold(0.0f64, |a, z| a.max(z.abs()))
        );
        checks.push(c);
    }
    let (ok, worst, bound) = passes(&checks, 1e-3);
    assert!(ok, "max |z| {worst} >= Sidak bound {bound}");
}
