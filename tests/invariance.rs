//! The engine knows no preferred axis, scale or number of lights: a rotated,
//! shifted and rescaled Sobolev scene with two lights (flux-specified), read
//! from a scene file, must match the exact solution by superposition; also
//! shifted to 0.9 times the largest accepted coordinate (at 3e10 m, within
//! the bound before, the direct light was lost).

use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, Stop};
use lumest::tally::sidak_bound;
use std::f64::consts::PI;

#[test]
fn rotated_scaled_two_light_scene_matches_superposed_exact_solution() {
    let mut worst: f64 = 0.0;
    let mut m = 0;
    let mut batches = u64::MAX;
    let far = DVec3::new(0.9, -0.6, 0.3) * lumest::scene::MAX_COORD;
    let cases = [
        (1e-3, DVec3::ZERO),
        (1.0, DVec3::ZERO),
        (1e4, DVec3::ZERO),
        (1.0, far),
    ];
    for (k, (scale, shift)) in cases.into_iter().enumerate() {
        // Plane 1 through `o` with normal `u`; plane 2 at distance H = 1 * scale.
        let u = DVec3::new(0.3, -0.5, 0.8).normalize();
        let e1 = u.any_orthonormal_vector();
        let o = DVec3::new(2.0, -1.0, 0.5) * scale + shift;
        let (h1, h) = (0.4 * scale, 1.0 * scale);
        let (i1, i2) = (1.0, 2.5);
        let l1 = o + u * h1;
        let l2 = l1 + e1 * 0.7 * scale;
        let text = format!(
            "[[surface]]\ntype = \"plane\"\npoint = {p1:?}\nnormal = {n1:?}\nmaterial = {{ type = \"lambertian\", reflectance = 0.6 }}\n\n\
             [[surface]]\ntype = \"plane\"\npoint = {p2:?}\nnormal = {n2:?}\nmaterial = {{ type = \"lambertian\", reflectance = 0.3 }}\n\n\
             [[light]]\ntype = \"point\"\nposition = {a:?}\nintensity = {i1}\n\n\
             [[light]]\ntype = \"point\"\nposition = {b:?}\nflux = {f2}\n",
            p1 = o.to_array(),
            n1 = u.to_array(),
            p2 = (o + u * h).to_array(),
            n2 = (-u).to_array(),
            a = l1.to_array(),
            b = l2.to_array(),
            f2 = 4.0 * PI * i2,
        );
        let scene = lumest::scene::parse(&text, std::path::Path::new("rotated.toml")).unwrap();
        // Exact: both lights sit at h1 from plane 1; the solution is linear in the sources.
        let s = Sobolev::new(h1, h - h1, 0.6, 0.3, 1.0).unwrap();
        let e2 = u.cross(e1);
        let mut pts = Vec::new();
        let mut exact = Vec::new();
        for j in 0..8 {
            let (a, b) = (0.4 * j as f64 * scale, (j as f64 - 3.0) * 0.3 * scale);
            for (plane, base, n) in [(1u8, o, u), (2u8, o + u * h, -u)] {
                let p = base + e1 * a + e2 * b;
                let foot = |l: DVec3| (p - l) - u * u.dot(p - l);
                let e = i1 * s.illuminance(plane, foot(l1).length()).e
                    + i2 * s.illuminance(plane, foot(l2).length()).e;
                pts.push((p, n));
                exact.push(e);
            }
        }
        let rec = Receivers::new(&scene, &pts).unwrap();
        let cfg = RunConfig {
            seed: 40 + k as u64,
            stop: Stop {
                chains: Some(200_000),
                ..Stop::default()
            },
            ..RunConfig::default()
        };
        let r = run(&scene, &rec, &cfg, &mut |_| true);
        batches = batches.min(r.tallies.batches());
        for (j, &e) in exact.iter().enumerate() {
            let w = &r.tallies.estimated[j];
            let z = (r.direct[j] + w.mean() - e) / w.std_error();
            assert!(z.is_finite(), "scale {scale}, point {j}");
            worst = worst.max(z.abs());
        }
        m += exact.len();
    }
    let bound = sidak_bound(1e-3, m, Some(batches));
    assert!(worst < bound, "max |z| {worst} >= {bound}");
}
