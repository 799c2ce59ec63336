//! Receiver types (`cylindrical`, `semicylindrical`, `hemispherical`,
//! `spherical` next to `planar`) against references written here from the
//! geometry, sharing no code with the estimators:
//!
//! - an isotropic point source over a black floor: the exact direct term
//!   equals the lighting engineer's closed forms (`E_h = I cos^3 e / H^2`,
//!   `E_z = I cos^2 e sin e / (pi H^2)`, `E_sz = I (1 + cos a) cos^2 e sin e /
//!   (pi H^2)`, `E_hs = I (1 + cos e) cos^2 e / (4 H^2)`, `E_o = I cos^2 e /
//!   (4 H^2)`);
//! - a small sphere source over the black floor: the sampled direct term
//!   (MIS of the source and the receiver's own lobe) against 2-D quadrature
//!   of the response over the cone the sphere subtends;
//! - an integrating sphere with the source at its centre: the light
//!   reflected by the walls is a uniform field of luminance
//!   `L = rho I / (pi R^2 (1 - rho))`, which every receiver type reads as
//!   `pi L` wherever it stands and however it is turned; local and backward
//!   estimates, z-tested with a Sidak bound over all points.

mod common;
use glam::DVec3;
use lumest::estimator::{Receiver, Receivers, Solid};
use lumest::geometry::Plane;
use lumest::geometry::shapes::Sphere;
use lumest::light::Light;
use lumest::material::Material;
use lumest::scene::{Scene, Sides, SurfaceSpec};
use lumest::tally::sidak_bound;
use std::f64::consts::PI;

const KINDS: [Option<Solid>; 5] = [
    None,
    Some(Solid::Cylindrical),
    Some(Solid::Semicylindrical),
    Some(Solid::Hemispherical),
    Some(Solid::Spherical),
];

fn receiver(p: DVec3, n: DVec3, kind: Option<Solid>) -> Receiver {
    match kind {
        None => Receiver::illuminance(p, n),
        Some(k) => Receiver::solid(p, n, k),
    }
}

/// The response of each type to light from `w` (module docs of
/// `estimator::solid`), written from the geometry here rather than by
/// calling it.
fn response(kind: Option<Solid>, n: DVec3, w: DVec3) -> f64 {
    match kind {
        None => n.dot(w).max(0.0),
        Some(Solid::Cylindrical) => (1.0 - n.dot(w).powi(2)).max(0.0).sqrt() / PI,
        Some(Solid::Semicylindrical) => {
            let sin_t = (1.0 - w.z * w.z).max(0.0).sqrt();
            let h = DVec3::new(w.x, w.y, 0.0);
            let cos_a = if sin_t > 0.0 { n.dot(h) / sin_t } else { 0.0 };
            sin_t * (1.0 + cos_a) / PI
        }
        Some(Solid::Hemispherical) => (1.0 + n.dot(w)) / 4.0,
        Some(Solid::Spherical) => 0.25,
    }
}

fn black_floor(light: Light) -> Scene {
    Scene::from_parts(
        vec![(
            "floor".into(),
            Plane::new(DVec3::ZERO, DVec3::Z),
            Material::Lambertian { rho: 0.0 },
        )],
        vec![light],
    )
    .expect("a valid programmatic scene")
}

/// Receivers at height 0.8 m with the source at `s`, at angles `e` from the
/// vertical and azimuths `a` from the facing direction `+x`: `(receiver,
/// closed form)` for every type (normal up; the half cylinder faces `+x`).
fn point_cases(s: DVec3, i: f64) -> Vec<(Receiver, f64)> {
    let h = s.z - 0.8;
    let mut out = Vec::new();
    for (e, a) in [
        (0.0_f64, 0.0_f64),
        (0.35, 0.0),
        (0.7, 1.0),
        (1.1, 2.5),
        (1.35, 3.1),
        (0.9, -2.0),
    ] {
        // The point from which the source lies at (e, a): p = s - H (tan e cos a, tan e sin a, 1).
        let p = s - h * DVec3::new(e.tan() * a.cos(), e.tan() * a.sin(), 1.0);
        let (c, sn) = (e.cos(), e.sin());
        let k = i / (h * h);
        let exact = [
            k * c.powi(3),
            k * c * c * sn / PI,
            k * (1.0 + a.cos()) * c * c * sn / PI,
            k * (1.0 + c) * c * c / 4.0,
            k * c * c / 4.0,
        ];
        for (kind, want) in KINDS.iter().zip(exact) {
            let n = if *kind == Some(Solid::Semicylindrical) {
                DVec3::X
            } else {
                DVec3::Z
            };
            out.push((receiver(p, n, *kind), want));
        }
    }
    out
}

#[test]
fn point_source_direct_terms_are_the_closed_forms() {
    let (s, i) = (DVec3::new(0.4, -0.3, 3.3), 250.0);
    let scene = black_floor(Light::Point { p: s, i });
    let cases = point_cases(s, i);
    let all: Vec<Receiver> = cases.iter().map(|c| c.0).collect();
    let rec = Receivers::from_receivers(&scene, &all).unwrap();
    assert!(!rec.has_sampled_direct());
    for (j, (r, want)) in cases.iter().enumerate() {
        let got = rec.direct()[j];
        assert!(
            (got - want).abs() <= 1e-12 * want.abs().max(1e-9),
            "{:?} at {}: {got} vs {want}",
            r.response,
            r.p
        );
    }
    // The black floor: a full run adds nothing.
    let r =
        lumest::estimator::local::run(&scene, &rec, &common::chains_cfg(2048, 3, 1), &mut |_| true);
    for j in 0..all.len() {
        assert_eq!(r.tallies.estimated[j].mean(), 0.0);
    }
}

/// `int_cone L r(w) dw` over the cone that a sphere of radius `rad` at `c`
/// subtends from `p`, by the midpoint rule in the cone's own polar angles.
fn cone_quadrature(c: DVec3, rad: f64, l: f64, p: DVec3, r: impl Fn(DVec3) -> f64) -> f64 {
    let v = c - p;
    let dist = v.length();
    let z = v / dist;
    let x = if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = (x - z * x.dot(z)).normalize();
    let y = z.cross(x);
    let alpha = (rad / dist).asin();
    let (nt, np) = (600, 600);
    let mut sum = 0.0;
    for it in 0..nt {
        let t = (it as f64 + 0.5) * alpha / nt as f64;
        for ip in 0..np {
            let ph = (ip as f64 + 0.5) * 2.0 * PI / np as f64;
            let w = z * t.cos() + (x * ph.cos() + y * ph.sin()) * t.sin();
            sum += r(w) * t.sin();
        }
    }
    l * sum * (alpha / nt as f64) * (2.0 * PI / np as f64)
}

#[test]
fn sphere_source_sampled_direct_matches_quadrature() {
    let (c, rad, i) = (DVec3::new(0.0, 0.0, 2.0), 0.3, 100.0);
    let scene = black_floor(Light::Sphere { c, r: rad, i });
    let l = i / (PI * rad * rad);
    let mut all = Vec::new();
    let mut exact = Vec::new();
    for p in [
        DVec3::new(0.5, 0.2, 1.0),
        DVec3::new(-1.2, 0.4, 0.6),
        DVec3::new(0.1, -0.1, 1.4),
    ] {
        for kind in KINDS {
            let n = match kind {
                Some(Solid::Semicylindrical) => DVec3::new(-0.6, 0.8, 0.0),
                Some(Solid::Hemispherical) => DVec3::new(0.3, 0.0, -1.0).normalize(),
                _ => DVec3::new(0.2, 0.5, 1.0).normalize(),
            };
            all.push(receiver(p, n, kind));
            exact.push(cone_quadrature(c, rad, l, p, |w| response(kind, n, w)));
        }
    }
    let rec = Receivers::from_receivers(&scene, &all).unwrap();
    let r = lumest::estimator::local::run(
        &scene,
        &rec,
        &common::chains_cfg(1 << 22, 11, 2),
        &mut |_| true,
    );
    let bound = sidak_bound(1e-3, all.len(), Some(r.tallies.batches()));
    for (j, &e) in exact.iter().enumerate() {
        let w = &r.tallies.estimated[j];
        let (got, se) = (r.direct[j] + w.mean(), w.std_error());
        if rec.direct_set(j).is_none() {
            // Exact (a planar point sees the whole sphere above its
            // horizon): to the quadrature's own error.
            assert!((got / e - 1.0).abs() < 1e-5, "point {j}: {got} vs {e}");
            continue;
        }
        let z = (got - e) / se;
        // A 2 % error must be detectable.
        assert!(
            0.02 * e > bound * se,
            "point {j}: error bar {se} too wide for {e}"
        );
        assert!(
            z.abs() < bound,
            "point {j} {:?}: {got} +- {se} vs {e} (z = {z})",
            all[j].response
        );
    }
}

/// The integrating sphere (radius `rad` about `c`, reflectance `rho`) with
/// an isotropic source of `i` \[cd\] at its centre.
fn integrating_sphere(c: DVec3, rad: f64, rho: f64, i: f64) -> Scene {
    let spec = SurfaceSpec::Sphere(
        "sphere".into(),
        Sphere { c, r: rad },
        Sides::Back,
        Material::Lambertian { rho },
    );
    Scene::build(vec![spec], vec![Light::Point { p: c, i }]).expect("a valid programmatic scene")
}

#[test]
fn every_type_reads_pi_l_in_the_integrating_sphere() {
    let (c, rad, rho, i) = (DVec3::new(0.1, 0.2, 0.3), 1.0, 0.8, 100.0);
    let scene = integrating_sphere(c, rad, rho, i);
    // pi L of the walls' uniform luminance (module docs).
    let ind = rho * i / (rad * rad * (1.0 - rho));
    let spots = [
        (DVec3::new(0.4, 0.1, -0.2), DVec3::new(0.3, -0.2, 0.9)),
        (DVec3::new(-0.3, -0.5, 0.1), DVec3::new(-0.8, 0.1, 0.2)),
        (DVec3::new(0.0, 0.2, 0.6), DVec3::new(0.1, 0.0, -1.0)),
    ];
    let mut all = Vec::new();
    for (off, n) in spots {
        for kind in KINDS {
            let n = match kind {
                Some(Solid::Semicylindrical) => DVec3::new(n.x, n.y, 0.0).normalize(),
                _ => n.normalize(),
            };
            all.push(receiver(c + off * rad, n, kind));
        }
    }
    let rec = Receivers::from_receivers(&scene, &all).unwrap();
    let local = lumest::estimator::local::run(
        &scene,
        &rec,
        &common::chains_cfg(1 << 16, 7, 2),
        &mut |_| true,
    );
    let back = lumest::backward::run(
        &scene,
        &rec,
        &common::chains_cfg(1 << 14, 7, 2),
        &mut |_| true,
    );
    // The near/far split, its radius taking in part of the wall: the near
    // part's backward paths start from each receiver's own lobe.
    let split = rec.clone().with_near_field(0.7 * rad, 128);
    let near = lumest::estimator::local::run(
        &scene,
        &split,
        &common::chains_cfg(1 << 17, 7, 2),
        &mut |_| true,
    );
    for (name, r) in [
        ("local", &local),
        ("backward", &back),
        ("near/far split", &near),
    ] {
        let bound = sidak_bound(1e-3, 3 * all.len(), Some(r.tallies.batches()));
        for (j, rv) in all.iter().enumerate() {
            let w = &r.tallies.estimated[j];
            let (got, se) = (w.mean(), w.std_error());
            let z = (got - ind) / se;
            assert!(
                0.02 * ind > bound * se,
                "{name} point {j}: error bar {se} too wide"
            );
            assert!(
                z.abs() < bound,
                "{name} point {j} {:?}: {got} +- {se} vs {ind} (z = {z})",
                rv.response
            );
        }
    }
}

/// The floor's once-reflected light at `p` (height `h` above a Lambertian
/// floor of reflectance `rho` lit by `i` \[cd\] at `s`), read with response
/// `r`: `int L(x) r(w) dw` over the floor with `L = rho E(x) / pi`,
/// `E(x) = I s_z / |s - x|^3`, in the polar angle `t` and azimuth about
/// the foot of `p` (`dw = sin t dt dphi`).
fn floor_quadrature(p: DVec3, s: DVec3, i: f64, rho: f64, r: impl Fn(DVec3) -> f64) -> f64 {
    let (nt, np) = (1200, 400);
    let mut sum = 0.0;
    for it in 0..nt {
        let t = (it as f64 + 0.5) * (PI / 2.0) / nt as f64;
        for ip in 0..np {
            let ph = (ip as f64 + 0.5) * 2.0 * PI / np as f64;
            let w = DVec3::new(t.sin() * ph.cos(), t.sin() * ph.sin(), -t.cos());
            let x = p + w * (p.z / t.cos());
            let e = i * s.z / (s - x).length().powi(3);
            sum += rho * e / PI * r(w) * t.sin();
        }
    }
    sum * (PI / 2.0 / nt as f64) * (2.0 * PI / np as f64)
}

#[test]
fn light_from_below_the_normal_reaches_solid_receivers() {
    let (s, i, rho) = (DVec3::new(0.0, 0.0, 2.5), 100.0, 0.5);
    let scene = Scene::from_parts(
        vec![(
            "floor".into(),
            Plane::new(DVec3::ZERO, DVec3::Z),
            Material::Lambertian { rho },
        )],
        vec![Light::Point { p: s, i }],
    )
    .expect("a valid programmatic scene");
    let mut all = Vec::new();
    let mut exact = Vec::new();
    for p in [DVec3::new(0.7, 0.2, 0.8), DVec3::new(-1.5, 1.0, 1.4)] {
        for kind in KINDS {
            // Planar facing down (it sees only the floor); the hemisphere's
            // pole up, so the floor lies behind its "normal".
            let n = match kind {
                None => -DVec3::Z,
                Some(Solid::Semicylindrical) => DVec3::new(0.6, 0.8, 0.0),
                _ => DVec3::Z,
            };
            all.push(receiver(p, n, kind));
            exact.push(floor_quadrature(p, s, i, rho, |w| response(kind, n, w)));
        }
    }
    let rec = Receivers::from_receivers(&scene, &all).unwrap();
    // The local estimate only: the backward paths of a point above an
    // open floor mostly escape to the sky (1 % error at 2^14 paths); the
    // integrating sphere checks the backward estimator.
    let local = lumest::estimator::local::run(
        &scene,
        &rec,
        &common::chains_cfg(1 << 17, 5, 2),
        &mut |_| true,
    );
    for (name, r) in [("local", &local)] {
        let bound = sidak_bound(1e-3, all.len(), Some(r.tallies.batches()));
        for (j, &e) in exact.iter().enumerate() {
            let w = &r.tallies.estimated[j];
            let (got, se) = (w.mean(), w.std_error());
            let z = (got - e) / se;
            assert!(
                0.02 * e > bound * se,
                "{name} point {j}: error bar {se} too wide for {e}"
            );
            assert!(
                z.abs() < bound,
                "{name} point {j} {:?}: {got} +- {se} vs {e} (z = {z})",
                all[j].response
            );
        }
    }
}

#[test]
fn the_sun_reaches_every_type() {
    // The sun at 40 degrees elevation towards +x, 100 klx normal to the beam.
    let (el, e_n) = (40f64.to_radians(), 1e5);
    let base = format!(
        "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = {{ type = \"lambertian\", reflectance = 0.0 }}\n\n\
         [[light]]\ntype = \"distant\"\ndirection = [{}, 0, {}]\nilluminance = {e_n}\n",
        -el.cos(),
        -el.sin()
    );
    let (c, s) = (el.cos(), el.sin());
    let cases = [
        (None, DVec3::Z, e_n * s),
        (Some(Solid::Cylindrical), DVec3::Z, e_n * c / PI),
        (Some(Solid::Semicylindrical), DVec3::X, e_n * 2.0 * c / PI),
        (Some(Solid::Semicylindrical), -DVec3::X, 0.0),
        (Some(Solid::Semicylindrical), DVec3::Y, e_n * c / PI),
        (Some(Solid::Hemispherical), DVec3::Z, e_n * (1.0 + s) / 4.0),
        (Some(Solid::Hemispherical), -DVec3::Z, e_n * (1.0 - s) / 4.0),
        (Some(Solid::Spherical), DVec3::Z, e_n / 4.0),
    ];
    let all: Vec<Receiver> = cases
        .iter()
        .map(|&(k, n, _)| receiver(DVec3::new(0.3, 0.2, 1.0), n, k))
        .collect();
    // A point sun: exact.
    let point = lumest::scene::parse(&base, std::path::Path::new("sun.toml")).unwrap();
    let rec = Receivers::from_receivers(&point, &all).unwrap();
    assert!(!rec.has_sampled_direct());
    for (j, &(_, _, want)) in cases.iter().enumerate() {
        let got = rec.direct()[j];
        assert!((got - want).abs() <= 1e-9 * e_n, "{j}: {got} vs {want}");
    }
    // The 0.53 degree disc: sampled for the solid types; the disc changes
    // these smooth responses by a relative ~1e-5, far below the error bars.
    let disc = lumest::scene::parse(
        &format!("{base}angular_diameter = 0.53\n"),
        std::path::Path::new("sun.toml"),
    )
    .unwrap();
    let rec = Receivers::from_receivers(&disc, &all).unwrap();
    let r =
        lumest::estimator::local::run(&disc, &rec, &common::chains_cfg(1 << 16, 9, 2), &mut |_| {
            true
        });
    let bound = sidak_bound(1e-3, all.len(), Some(r.tallies.batches()));
    // The disc's half-angle: `E_n = L pi sin^2 a`, so the sphere reads
    // `L 2 pi (1 - cos a) / 4 = (E_n / 4) 2 / (1 + cos a)` and the
    // hemisphere `(E_n / 4) (2 / (1 + cos a) + n . w_sun)`, exactly; the
    // cylinders' references above are off by a relative ~a^2 = 2e-5.
    let a = (0.53f64 / 2.0).to_radians();
    let disc_factor = 2.0 / (1.0 + a.cos());
    let sun = DVec3::new(c, 0.0, s);
    for (j, &(kind, n, want)) in cases.iter().enumerate() {
        let want = match kind {
            Some(Solid::Spherical) => want * disc_factor,
            Some(Solid::Hemispherical) => e_n / 4.0 * (disc_factor + n.dot(sun)),
            _ => want,
        };
        let w = &r.tallies.estimated[j];
        let (got, se) = (r.direct[j] + w.mean(), w.std_error());
        if kind.is_none() || want == 0.0 {
            // The plane's disc is exact; the back of the half cylinder only
            // gets the disc's rim at its edges (about E_n alpha^2, 1e-6 E_n).
            assert!((got - want).abs() <= 1e-5 * e_n, "{j}: {got} vs {want}");
            continue;
        }
        assert!(
            0.02 * want > bound * se,
            "{j}: error bar {se} too wide for {want}"
        );
        if se == 0.0 {
            // Light sampling of the cone is exact for a constant response.
            assert!((got / want - 1.0).abs() < 1e-9, "{j}: {got} vs {want}");
            continue;
        }
        let z = (got - want) / se;
        assert!(
            z.abs() < bound,
            "{j} {kind:?}: {got} +- {se} vs {want} (z = {z})"
        );
    }
}

#[test]
fn panel_sampled_direct_matches_quadrature() {
    // A 0.6 m x 1.2 m panel of 1000 cd/m^2 at z = 2.5 m emitting down, over a black floor.
    let src = "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
               material = { type = \"lambertian\", reflectance = 0.0 }\n\n\
               [[light]]\ntype = \"rectangle\"\ncorner = [-0.3, 0.6, 2.5]\nedge1 = [0.6, 0.0, 0.0]\n\
               edge2 = [0.0, -1.2, 0.0]\nluminance = 1000.0\n";
    let scene = lumest::scene::parse(src, std::path::Path::new("panel.toml")).unwrap();
    let l = 1000.0;
    // int L r(w) cos_y / d^2 dA over the panel (cos_y = w_z: it faces down).
    let quad = |p: DVec3, kind: Option<Solid>, n: DVec3| {
        let (na, nb) = (300, 600);
        let mut sum = 0.0;
        for ia in 0..na {
            for ib in 0..nb {
                let y = DVec3::new(
                    -0.3 + 0.6 * (ia as f64 + 0.5) / na as f64,
                    0.6 - 1.2 * (ib as f64 + 0.5) / nb as f64,
                    2.5,
                );
                let v = y - p;
                let d2 = v.length_squared();
                let w = v / d2.sqrt();
                sum += l * response(kind, n, w) * w.z / d2;
            }
        }
        sum * 0.72 / (na * nb) as f64
    };
    let mut all = Vec::new();
    let mut exact = Vec::new();
    for p in [DVec3::new(0.2, 0.1, 1.2), DVec3::new(1.8, -0.9, 1.6)] {
        for kind in KINDS {
            let n = match kind {
                Some(Solid::Semicylindrical) => DVec3::new(-0.8, 0.6, 0.0),
                _ => DVec3::Z,
            };
            all.push(receiver(p, n, kind));
            exact.push(quad(p, kind, n));
        }
    }
    let rec = Receivers::from_receivers(&scene, &all).unwrap();
    let r = lumest::estimator::local::run(
        &scene,
        &rec,
        &common::chains_cfg(1 << 20, 13, 2),
        &mut |_| true,
    );
    let bound = sidak_bound(1e-3, all.len(), Some(r.tallies.batches()));
    for (j, &e) in exact.iter().enumerate() {
        let w = &r.tallies.estimated[j];
        let (got, se) = (r.direct[j] + w.mean(), w.std_error());
        if rec.direct_set(j).is_none() {
            // The planar points: Lambert's exact contour integral.
            assert!((got / e - 1.0).abs() < 1e-5, "point {j}: {got} vs {e}");
            continue;
        }
        assert!(
            0.02 * e > bound * se,
            "point {j}: error bar {se} too wide for {e}"
        );
        let z = (got - e) / se;
        assert!(
            z.abs() < bound,
            "point {j} {:?}: {got} +- {se} vs {e} (z = {z})",
            all[j].response
        );
    }
}

/// Direct light kept by RIS (`--direct-lights ris`, automatic from many
/// sources) at every receiver type, from point sources on all sides (two
/// below the receivers' normals) and a sphere source below them: the
/// solid types read `I r(w) / d^2` summed over the points (the closed
/// forms of `response`, no cosine of the normal) plus the quadrature of the
/// sphere's cone. The old estimate multiplied the plane's `I cos / d^2` by
/// the response (the spherical receiver read 8.8 for 12.5 lx from one
/// light) and never picked a source behind the normal.
#[test]
fn ris_direct_light_reaches_solid_receivers_from_every_side() {
    use lumest::light::array::DirectLights;
    let points = [
        (DVec3::new(1.0, 0.0, 2.0), 100.0),
        (DVec3::new(-0.7, 1.1, 2.6), 60.0),
        (DVec3::new(0.4, -1.3, 0.2), 80.0),
        (DVec3::new(-1.5, -0.4, -0.1), 40.0),
    ];
    let (c, rad, i) = (DVec3::new(0.2, 0.3, -0.8), 0.25, 50.0);
    let mut lights: Vec<Light> = points.iter().map(|&(p, i)| Light::Point { p, i }).collect();
    lights.push(Light::Sphere { c, r: rad, i });
    let scene = Scene::from_parts(
        vec![(
            "floor far below".into(),
            Plane::new(DVec3::new(0.0, 0.0, -20.0), DVec3::Z),
            Material::Lambertian { rho: 0.0 },
        )],
        lights,
    )
    .unwrap()
    .with_direct_lights(DirectLights::Ris, 4);
    assert!(scene.light_array().is_some());
    let l = i / (PI * rad * rad);
    let mut all = Vec::new();
    let mut exact = Vec::new();
    for p in [DVec3::new(0.0, 0.0, 0.8), DVec3::new(0.5, -0.4, 1.1)] {
        for kind in KINDS {
            let n = match kind {
                Some(Solid::Semicylindrical) => DVec3::new(-0.6, 0.8, 0.0),
                _ => DVec3::Z,
            };
            all.push(receiver(p, n, kind));
            let from_points: f64 = points
                .iter()
                .map(|&(s, i)| {
                    let v = s - p;
                    let d2 = v.length_squared();
                    let w = v / d2.sqrt();
                    let r = match kind {
                        None => n.dot(w).max(0.0),
                        _ => response(kind, n, w),
                    };
                    i * r / d2
                })
                .sum();
            let from_sphere = cone_quadrature(c, rad, l, p, |w| match kind {
                None => n.dot(w).max(0.0),
                _ => response(kind, n, w),
            });
            exact.push(from_points + from_sphere);
        }
    }
    let rec = Receivers::from_receivers(&scene, &all).unwrap();
    let r = lumest::estimator::local::run(
        &scene,
        &rec,
        &common::chains_cfg(1 << 18, 5, 2),
        &mut |_| true,
    );
    let bound = sidak_bound(1e-3, all.len(), Some(r.tallies.batches()));
    for (j, &e) in exact.iter().enumerate() {
        let w = &r.tallies.estimated[j];
        let (got, se) = (r.direct[j] + w.mean(), w.std_error());
        assert!(
            0.02 * e > bound * se,
            "point {j}: error bar {se} too wide for {e}"
        );
        let z = (got - e) / se;
        assert!(
            z.abs() < bound,
            "point {j} {:?}: {got} +- {se} vs {e} (z = {z})",
            all[j].response
        );
    }
}
