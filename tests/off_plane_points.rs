//! Points between and behind the Sobolev planes: the reflected illuminance at
//! a point facing one plane follows from that plane's exact exitance,
//! `E(p) = int rho E_plane(s) / pi * cos cos / d^2 dA`, integrated here in 1-D
//! (independent of the Monte Carlo code); points behind a plane see nothing.

use gauss_quad::legendre::GaussLegendre;
use glam::DVec3;
use lumest::cases::sobolev::sobolev_case;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, Stop};
use lumest::tally::sidak_bound;

/// Reflected illuminance at height `dz` \[m\] straight above (or below) the foot
/// of the source on a plane of reflectance `rho`, whose illuminance is `e(s)`,
/// by Gauss-Legendre panels in the distance `s` along the plane.
fn from_plane(rho: f64, dz: f64, e: impl Fn(f64) -> f64) -> f64 {
    let rule = GaussLegendre::new(std::num::NonZeroUsize::new(30).unwrap());
    let f = |s: f64| {
        rho * e(s) / std::f64::consts::PI * dz * dz / (s * s + dz * dz).powi(2)
            * 2.0
            * std::f64::consts::PI
            * s
    };
    // Beyond s = 40 the integrand is below (r^3 E) dz^2 / s^6: under 1e-9 of the total.
    let edges = [0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 40.0];
    edges
        .windows(2)
        .map(|w| rule.integrate(w[0], w[1], f))
        .sum()
}

#[test]
fn points_between_and_behind_the_planes() {
    let (h1, h2, r1, r2) = (0.5, 0.5, 0.6, 0.7);
    let s = Sobolev::new(h1, h2, r1, r2, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    // Facing the ceiling from z = 0.25 and the floor from z = 0.75, both on the axis;
    // behind the floor; behind the ceiling.
    let pts = [
        (DVec3::new(0.0, 0.0, 0.25), DVec3::Z),
        (DVec3::new(0.0, 0.0, 0.75), -DVec3::Z),
        (DVec3::new(0.0, 0.0, -0.5), DVec3::Z),
        (DVec3::new(0.2, 0.0, 1.5), -DVec3::Z),
    ];
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let cfg = RunConfig {
        seed: 3,
        stop: Stop {
            chains: Some(400_000),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let r = run(&case.scene, &rec, &cfg, &mut |_| true);
    // Direct: I / d^2 from the source 0.25 m away.
    assert!((r.direct[0] - 16.0).abs() < 1e-12 && (r.direct[1] - 16.0).abs() < 1e-12);
    let up = from_plane(r2, 0.75, |x| s.illuminance(2, x).e);
    let down = from_plane(r1, 0.75, |x| s.illuminance(1, x).e);
    let bound = sidak_bound(1e-3, 2, Some(r.tallies.batches()));
    assert!(up > 0.1 && down > 0.1, "{up} {down}");
    for (j, want) in [(0, up), (1, down)] {
        let w = &r.tallies.estimated[j];
        let z = (w.mean() - want) / w.std_error();
        assert!(
            z.abs() < bound,
            "point {j}: {} +- {} vs {want} (z = {z})",
            w.mean(),
            w.std_error()
        );
    }
    for j in [2, 3] {
        assert_eq!(r.direct[j], 0.0);
        assert_eq!(r.tallies.estimated[j].mean(), 0.0);
        assert_eq!(r.tallies.estimated[j].std_error(), 0.0);
    }
}
