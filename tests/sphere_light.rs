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
        // Below a nanometre I / (pi r^2) overflows (1e-300 m read NaN).
        (
            "center = [0.0, 0.0, 0.5]\nradius = 1e-300\nintensity = 1.0\n",
            ":10:",
            "at least 1e-9 m",
        ),
    ] {
        let err = lumest::scene::parse(&format!("{base}{tail}"), path)
            .unwrap_err()
            .to_string();
        assert!(err.contains(line) && err.contains(field), "{tail}: {err}");
    }
}

/// Views of a glossy (Phong) floor under a sphere light, the floor the
/// scene's only surface (planes only, where the sphere's direct light has a
/// closed form at illuminance points): the luminance is the first order
/// alone, against the reference's quadrature over the sphere's cone
/// (`common::direct`, sharing no code with the estimators). The old build
/// summed the sphere's light at the views at set-up and sampled it per
/// batch as well: twice the luminance (289 for 144 cd/m^2).
#[test]
fn glossy_views_of_a_sphere_light_count_it_once() {
    use common::direct::{Occluder, RefLight, RefResponse, first_order};
    use lumest::estimator::{ViewTarget, view_target};
    let (kd, ks, ne) = (0.05, 0.9, 10.0);
    let (c, radius, i) = (DVec3::new(0.0, 0.0, 1.0), 0.2, 100.0);
    let scene = Scene::from_parts(
        vec![(
            "glossy floor".into(),
            Plane::new(DVec3::ZERO, DVec3::Z),
            Material::Phong { kd, ks, n: ne },
        )],
        vec![Light::Sphere { c, r: radius, i }],
    )
    .unwrap();
    let mut rec = Vec::new();
    let mut want = Vec::new();
    for (o, d) in [
        (DVec3::new(0.5, 0.0, 1.0), DVec3::new(-0.25, 0.0, -1.0)),
        (DVec3::new(0.5, 0.0, 1.0), DVec3::new(-0.3, 0.05, -1.0)),
        (DVec3::new(1.0, 0.3, 1.2), DVec3::new(-0.6, -0.2, -1.2)),
        (DVec3::new(-0.8, 0.4, 0.6), DVec3::new(0.3, -0.1, -0.5)),
    ] {
        let d = d.normalize();
        let ViewTarget::Front(r) = view_target(&scene, o, d) else {
            panic!("the view from {o} misses the floor")
        };
        let resp = RefResponse::Phong {
            kd,
            ks,
            n: ne,
            wo: -d,
        };
        let occ = [Occluder::Plane {
            p: DVec3::ZERO,
            n: DVec3::Z,
        }];
        want.push(first_order(
            &[RefLight::Sphere { c, r: radius, i }],
            &occ,
            r.p,
            r.n,
            resp,
            64,
        ));
        rec.push(r);
    }
    let receivers = Receivers::from_receivers(&scene, &rec).unwrap();
    let r = run(
        &scene,
        &receivers,
        &common::chains_cfg(1 << 17, 9, 2),
        &mut |_| true,
    );
    let bound = sidak_bound(1e-3, rec.len(), Some(r.tallies.batches()));
    for (j, &e) in want.iter().enumerate() {
        let w = &r.tallies.estimated[j];
        let (got, se) = (r.direct[j] + w.mean(), w.std_error());
        assert!(e > 0.0 && 0.02 * e > bound * se, "view {j}: {e} +- {se}");
        let z = (got - e) / se;
        assert!(
            z.abs() < bound,
            "view {j}: {got} +- {se} vs {e} (z = {z:.2})"
        );
    }
}
