//! Spot lights: the exact direct light inside, between and outside the
//! cones (against `I(theta) cos / d^2` written here), the flux key, the
//! isotropic limit, and the chains against the backward estimator.

mod common;

use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::scene::parse;
use std::f64::consts::PI;
use std::path::Path;

fn scene(light: &str) -> lumest::scene::Scene {
    let src = format!(
        r#"
[[surface]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = {{ type = "lambertian", reflectance = 0.5 }}

[[surface]]
name = "ceiling"
type = "plane"
point = [0.0, 0.0, 3.0]
normal = [0.0, 0.0, -1.0]
material = {{ type = "lambertian", reflectance = 0.5 }}

[[light]]
{light}
"#
    );
    parse(&src, Path::new("spot.toml")).unwrap()
}

/// Smoothstep falloff in the cosine, written here from its definition.
fn falloff(c: f64, ci: f64, co: f64) -> f64 {
    if c >= ci {
        1.0
    } else if c <= co {
        0.0
    } else {
        let t = (c - co) / (ci - co);
        3.0 * t * t - 2.0 * t * t * t
    }
}

#[test]
fn direct_light_inside_between_and_outside_the_cones() {
    let s = scene(
        "type = \"spot\"\nposition = [0.0, 0.0, 2.5]\ndirection = [0.0, 0.0, -1.0]\ninner = 20.0\nouter = 40.0\nintensity = 300.0",
    );
    let (ci, co) = (20f64.to_radians().cos(), 40f64.to_radians().cos());
    let mut pts = Vec::new();
    for k in 0..30 {
        let r = 0.1 * k as f64; // angles 0 .. 50 degrees from 2.5 m
        pts.push((DVec3::new(r, 0.3 * r, 0.0), DVec3::Z));
    }
    let rec = Receivers::new(&s, &pts).unwrap();
    let (mut inside, mut between, mut outside) = (0, 0, 0);
    for (j, &(x, n)) in pts.iter().enumerate() {
        let v = DVec3::new(0.0, 0.0, 2.5) - x;
        let d = v.length();
        let c = v.z / d; // cos to the axis (down) = cos at the floor
        let exact = 300.0 * falloff(c, ci, co) * n.dot(v / d) / (d * d);
        let got = rec.direct()[j];
        assert!(
            (got - exact).abs() <= 1e-13 * exact.max(1e-300),
            "point {j}: {got} vs {exact}"
        );
        if c >= ci {
            inside += 1
        } else if c > co {
            between += 1
        } else {
            outside += 1;
            assert_eq!(got, 0.0)
        }
    }
    assert!(
        inside > 3 && between > 3 && outside > 3,
        "{inside} {between} {outside}"
    );
}

#[test]
fn flux_key_and_the_isotropic_limit() {
    let s = scene(
        "type = \"spot\"\nposition = [0.0, 0.0, 2.5]\ndirection = [0.2, 0.0, -1.0]\ninner = 10.0\nouter = 30.0\nflux = 1000.0",
    );
    assert!((s.total_power() - 1000.0).abs() < 1e-9);
    // 2 pi I0 [(1 - ci) + (ci - co)/2] = 1000 lm.
    let (ci, co) = (10f64.to_radians().cos(), 30f64.to_radians().cos());
    let i0 = 1000.0 / (2.0 * PI * ((1.0 - ci) + 0.5 * (ci - co)));
    let axis = DVec3::new(0.2, 0.0, -1.0).normalize();
    assert!((s.lights[0].intensity(axis) - i0).abs() < 1e-9 * i0);
    // 180/180 degrees: the isotropic point light, to rounding.
    let spot = scene(
        "type = \"spot\"\nposition = [0.3, 0.0, 1.5]\ndirection = [0.0, 0.0, -1.0]\ninner = 180.0\nouter = 180.0\nintensity = 5.0",
    );
    let point = scene("type = \"point\"\nposition = [0.3, 0.0, 1.5]\nintensity = 5.0");
    let pts: Vec<_> = (0..20)
        .map(|k| (DVec3::new(0.2 * k as f64, 0.1, 0.0), DVec3::Z))
        .collect();
    let (a, b) = (
        Receivers::new(&spot, &pts).unwrap(),
        Receivers::new(&point, &pts).unwrap(),
    );
    for j in 0..pts.len() {
        assert!((a.direct()[j] - b.direct()[j]).abs() <= 1e-14 * b.direct()[j]);
    }
    let cfg = common::chains_cfg(50_000, 3, 2);
    let ra = lumest::estimator::local::run(&spot, &a, &cfg, &mut |_| true);
    let rb = lumest::estimator::local::run(&point, &b, &cfg, &mut |_| true);
    for j in 0..pts.len() {
        let (x, y) = (
            ra.tallies.estimated[j].mean(),
            rb.tallies.estimated[j].mean(),
        );
        let se = (ra.tallies.estimated[j].std_error().powi(2)
            + rb.tallies.estimated[j].std_error().powi(2))
        .sqrt();
        assert!(((x - y) / se).abs() < 4.5, "point {j}: {x} vs {y} +- {se}");
    }
}

#[test]
fn both_estimators_agree_under_a_tilted_spot() {
    let s = scene(
        "type = \"spot\"\nposition = [0.0, 0.0, 2.0]\ndirection = [0.5, 0.0, -1.0]\ninner = 15.0\nouter = 30.0\nflux = 500.0",
    );
    let pts = [
        (DVec3::new(1.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(-1.0, 0.5, 0.0), DVec3::Z),
        (DVec3::new(0.5, 0.0, 3.0), -DVec3::Z),
    ];
    let rec = Receivers::new(&s, &pts).unwrap();
    let a =
        lumest::estimator::local::run(&s, &rec, &common::chains_cfg(200_000, 5, 2), &mut |_| true);
    let b = lumest::backward::run(&s, &rec, &common::chains_cfg(4_000, 6, 2), &mut |_| true);
    for j in 0..pts.len() {
        let ea = a.direct[j] + a.tallies.estimated[j].mean();
        let eb = b.direct[j] + b.tallies.estimated[j].mean();
        let se = (a.tallies.estimated[j].std_error().powi(2)
            + b.tallies.estimated[j].std_error().powi(2))
        .sqrt();
        assert!(
            ea > 0.0 && ((ea - eb) / se).abs() < 4.0,
            "point {j}: local {ea} vs backward {eb} +- {se}"
        );
    }
}

#[test]
fn bad_spot_keys_name_the_field() {
    for (light, field) in [
        (
            "type = \"spot\"\nposition = [0, 0, 2]\ndirection = [0, 0, 0]\ninner = 10.0\nouter = 20.0\nintensity = 1.0",
            "direction",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 30.0\nouter = 20.0\nintensity = 1.0",
            "outer",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 10.0\nouter = 200.0\nintensity = 1.0",
            "outer",
        ),
        (
            "type = \"spot\"\nposition = [0, 0, 2]\ndirection = [0, 0, -1]\nouter = 20.0\nintensity = 1.0",
            "inner",
        ),
        (
            "type = \"point\"\nposition = [0, 0, 2]\ninner = 10.0\nintensity = 1.0",
            "inner",
        ),
    ] {
        let src = format!("[[light]]\n{light}\n");
        let e = parse(&src, Path::new("spot.toml")).unwrap_err().to_string();
        assert!(
            e.contains(field) && e.contains("spot.toml:"),
            "{light}: {e}"
        );
    }
}
