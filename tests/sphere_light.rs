//! The spherical source: in the Sobolev geometry its exact answer equals the
//! point source's (every plane point sees the whole sphere above its horizon,
//! and the sphere does not block reflected light), for illuminance and for
//! luminance, with both estimators. A view straight at it sees its luminance.

mod common;
use glam::DVec3;
use lumest::cases::sobolev::sobolev_receivers;
use lumest::estimator::local::run;
use lumest::estimator::{Receivers, emitted_luminance};
use lumest::geometry::Plane;
use lumest::light::Light;
use lumest::material::Material;
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, Stop};
use lumest::scene::Scene;
use lumest::tally::sidak_bound;

fn sphere_scene(s: &Sobolev, radius: f64) -> Scene {
    let h = s.h1 + s.h2;
    Scene::from_parts(
        vec![
            (
                "floor".into(),
                Plane::new(DVec3::ZERO, DVec3::Z),
                Material::Lambertian { rho: s.rho1 },
            ),
            (
                "ceiling".into(),
                Plane::new(DVec3::new(0.0, 0.0, h), -DVec3::Z),
                Material::Lambertian { rho: s.rho2 },
            ),
        ],
        vec![Light::Sphere {
            c: DVec3::new(0.0, 0.0, s.h1),
            r: radius,
            i: s.intensity,
        }],
    )
    .expect("a valid programmatic scene")
}

#[test]
fn sphere_source_matches_the_exact_sobolev_solution() {
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.7, 1.0).unwrap();
    let scene = sphere_scene(&s, 0.2);
    let (_, all, exact) = sobolev_receivers(&s, 12, 8, 2.0);
    let rec = Receivers::from_receivers(&scene, &all).unwrap();
    // The exact direct term equals the point source's.
    for (j, d) in rec.direct().iter().enumerate().take(12) {
        let p = all[j].p;
        let plane = if p.z > 0.5 { 2 } else { 1 };
        let want = s.illuminance(plane, p.x.hypot(p.y)).e_direct;
        assert!((d / want - 1.0).abs() < 1e-12, "{d} vs {want}");
    }
    let cfg = |n| RunConfig {
        seed: 5,
        stop: Stop {
            chains: Some(n),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let local = run(&scene, &rec, &cfg(300_000), &mut |_| true);
    let back = lumest::backward::run(&scene, &rec, &cfg(20_000), &mut |_| true);
    for r in [&local, &back] {
        let bound = sidak_bound(1e-3, 2 * exact.len(), Some(r.tallies.batches()));
        for (j, &e) in exact.iter().enumerate() {
            let w = &r.tallies.estimated[j];
            let z = (r.direct[j] + w.mean() - e) / w.std_error();
            assert!(z.abs() < bound, "receiver {j}: z = {z}");
        }
    }
}

#[test]
fn a_view_through_the_sphere_sees_its_luminance() {
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let scene = sphere_scene(&s, 0.1);
    let l_e = 1.0 / (std::f64::consts::PI * 0.01);
    assert!((emitted_luminance(&scene, DVec3::ZERO, DVec3::Z, 1.0) - l_e).abs() < 1e-12);
    assert_eq!(
        emitted_luminance(&scene, DVec3::ZERO, DVec3::X, f64::INFINITY),
        0.0
    );
    assert_eq!(emitted_luminance(&scene, DVec3::ZERO, DVec3::Z, 0.3), 0.0);
}

#[test]
fn sphere_lights_are_validated() {
    let base = "[[surface]]\ntype = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmaterial = { type = \"lambertian\", reflectance = 0.5 }\n\n[[light]]\ntype = \"sphere\"\n";
    let path = std::path::Path::new("s.toml");
    let ok = format!("{base}center = [0.0, 0.0, 0.5]\nradius = 0.1\nflux = 12.566370614359172\n");
    let scene = lumest::scene::parse(&ok, path).unwrap();
    assert!(matches!(scene.lights[0], Light::Sphere { i, .. } if (i - 1.0).abs() < 1e-15));
    for (tail, line, field) in [
        (
            "center = [0.0, 0.0, 0.5]\nradius = 0.0\nintensity = 1.0\n",
            ":10:",
            "radius",
        ),
        (
            "center = [0.0, 0.0, 0.05]\nradius = 0.1\nintensity = 1.0\n",
            ":10:",
            "radius",
        ),
        (
            "center = [0.0, 0.0, 0.5]\nposition = [0.0, 0.0, 0.5]\nradius = 0.1\nintensity = 1.0\n",
            ":10:",
            "position",
        ),
        ("radius = 0.1\nintensity = 1.0\n", ":7:", "center"),
    ] {
        let err = lumest::scene::parse(&format!("{base}{tail}"), path)
            .unwrap_err()
            .to_string();
        assert!(err.contains(line) && err.contains(field), "{tail}: {err}");
    }
}
