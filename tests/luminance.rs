//! Luminance by the double local estimate and the backward estimator against
//! the exact Sobolev luminance `rho_j E_j(r') / pi`; views that see nothing.

mod common;
use common::{chains_cfg, max_abs_z, z, zcheck};
use glam::DVec3;
use lumest::cases::sobolev::{sobolev_case, sobolev_receivers};
use lumest::estimator::local::run;
use lumest::estimator::{Receivers, ViewTarget, view_target};
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, Stop};
use lumest::tally::sidak_bound;

#[test]
fn double_local_estimate_matches_exact_luminance_with_points_in_the_same_run() {
    let mut worst: f64 = 0.0;
    let mut m = 0;
    let mut batches = u64::MAX;
    for (k, p) in [(0.5, 0.5, 0.5, 0.5), (0.3, 0.7, 0.9, 0.6)]
        .into_iter()
        .enumerate()
    {
        let s = Sobolev::new(p.0, p.1, p.2, p.3, 1.0).unwrap();
        let (case, all, exact) = sobolev_receivers(&s, 10, 16, 2.0);
        let rec = Receivers::from_receivers(&case.scene, &all).unwrap();
        let r = run(
            &case.scene,
            &rec,
            &chains_cfg(200_000, 70 + k as u64, 0),
            &mut |_| true,
        );
        batches = batches.min(r.tallies.batches());
        for (j, &e) in exact.iter().enumerate() {
            worst = zcheck::max_abs(worst, z(&r, j, e));
        }
        m += exact.len();
    }
    let bound = sidak_bound(1e-3, m, Some(batches));
    assert!(worst < bound, "max |z| {worst} >= {bound}");
}

#[test]
fn backward_estimator_matches_exact_values() {
    let s = Sobolev::new(0.5, 0.5, 0.6, 0.7, 1.0).unwrap();
    let (case, all, exact) = sobolev_receivers(&s, 6, 6, 2.0);
    let rec = Receivers::from_receivers(&case.scene, &all).unwrap();
    let cfg = RunConfig {
        seed: 9,
        stop: Stop {
            chains: Some(20_000),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let r = lumest::backward::run(&case.scene, &rec, &cfg, &mut |_| true);
    let worst = max_abs_z((0..exact.len()).map(|j| z(&r, j, exact[j])));
    let bound = sidak_bound(1e-3, exact.len(), Some(r.tallies.batches()));
    assert!(worst < bound, "max |z| {worst} >= {bound}");
    // Thread count does not matter for the backward estimator either.
    let r1 = lumest::backward::run(
        &case.scene,
        &rec,
        &RunConfig {
            threads: 1,
            ..cfg.clone()
        },
        &mut |_| true,
    );
    let r2 = lumest::backward::run(
        &case.scene,
        &rec,
        &RunConfig { threads: 2, ..cfg },
        &mut |_| true,
    );
    for j in 0..exact.len() {
        assert_eq!(
            r1.tallies.estimated[j].mean().to_bits(),
            r2.tallies.estimated[j].mean().to_bits()
        );
    }
}

#[test]
fn views_that_miss_or_meet_a_back_side_see_nothing() {
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    // Parallel to the planes: leaves the scene.
    assert_eq!(
        view_target(&case.scene, DVec3::new(0.0, 0.0, 0.5), DVec3::X),
        ViewTarget::Miss
    );
    // From below the floor looking up: meets the floor's back side.
    match view_target(&case.scene, DVec3::new(0.0, 0.0, -1.0), DVec3::Z) {
        ViewTarget::Back { p } => assert_eq!(p, DVec3::ZERO),
        t => panic!("expected a back side, got {t:?}"),
    }
    // An observer standing on the floor looking up sees the ceiling, not the floor.
    match view_target(&case.scene, DVec3::new(0.3, 0.0, 0.0), DVec3::Z) {
        ViewTarget::Front(r) => assert!((r.p - DVec3::new(0.3, 0.0, 1.0)).length() < 1e-15),
        t => panic!("expected the ceiling, got {t:?}"),
    }
}

/// An observer standing exactly on a surface belongs to its reflecting
/// side (as a light does): looking into the surface it sees the surface at
/// its feet, as an observer a hair in front of it would; the old build
/// looked through planes, rectangles and a room's walls (a view from the
/// inside of a wall looking out read the sky), and into a solid's back.
#[test]
fn an_observer_on_a_surface_looking_into_it_sees_it() {
    let src = r#"
[[surface]]
name = "floor"
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
name = "room"
type = "box"
min = [-5, -5, -1]
max = [5, 5, 3]
normals = "inward"
material = { type = "lambertian", reflectance = 0.6 }

[[surface]]
name = "block"
type = "box"
min = [1, 1, 0]
max = [2, 2, 1]
normals = "outward"
material = { type = "lambertian", reflectance = 0.4 }

[[surface]]
name = "shelf"
type = "rectangle"
corner = [-2, -2, 1.5]
edge1 = [1, 0, 0]
edge2 = [0, 1, 0]
material = { type = "lambertian", reflectance = 0.7 }

[[light]]
type = "point"
position = [0, 0, 2]
intensity = 100
"#;
    let scene = lumest::scene::parse(src, std::path::Path::new("eyes.toml")).unwrap();
    let lift = 1e-7;
    for (o, d, n, what) in [
        (
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.3, 0.0, -1.0),
            DVec3::Z,
            "the floor",
        ),
        (
            DVec3::new(1.5, 1.5, 1.0),
            -DVec3::Z,
            DVec3::Z,
            "the block's top",
        ),
        (
            DVec3::new(1.0, 1.5, 0.5),
            DVec3::X,
            -DVec3::X,
            "the block's side",
        ),
        (
            DVec3::new(-5.0, 0.0, 1.0),
            -DVec3::X,
            DVec3::X,
            "the room's wall",
        ),
        (
            DVec3::new(-1.5, -1.5, 1.5),
            -DVec3::Z,
            DVec3::Z,
            "the shelf",
        ),
    ] {
        let d = d.normalize();
        let on = view_target(&scene, o, d);
        let ViewTarget::Front(r) = on else {
            panic!("{what}: an observer on it looking in sees {on:?}")
        };
        assert!(
            (r.p - o).length() < 1e-12 && (r.n - n).length() < 1e-12,
            "{what}: sub-point {} normal {}",
            r.p,
            r.n
        );
        // The same as from a hair in front of it.
        let ViewTarget::Front(f) = view_target(&scene, o + n * lift, d) else {
            panic!("{what}: from in front")
        };
        assert!((f.p - r.p).length() < 1e-6, "{what}: {} vs {}", f.p, r.p);
    }
    // Looking out of the surface: what lies beyond, as before.
    match view_target(&scene, DVec3::ZERO, DVec3::Z) {
        ViewTarget::Front(r) => assert!((r.p - DVec3::new(0.0, 0.0, 3.0)).length() < 1e-12),
        t => panic!("expected the ceiling, got {t:?}"),
    }
}

/// A view straight at a point light set into the ceiling meets the ceiling
/// at the light's own position, where the light's flux into the ceiling is
/// a delta and its direct term 0/0: the luminance there is its neighbours'
/// limit (the old build refused the whole run: "point lies on or inside
/// light ...: its illuminance is not finite", which a render with the
/// light on its axis met).
#[test]
fn a_view_of_a_light_in_the_ceiling_reads_its_neighbours_limit() {
    let src = r#"
[[surface]]
name = "floor"
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
name = "ceiling"
type = "plane"
point = [0, 0, 3]
normal = [0, 0, -1]
material = { type = "lambertian", reflectance = 0.7 }

[[light]]
type = "point"
position = [0, 0, 3]
intensity = 100
"#;
    let scene = lumest::scene::parse(src, std::path::Path::new("axis.toml")).unwrap();
    let mut rec = Vec::new();
    for o in [DVec3::new(0.0, 0.0, 1.0), DVec3::new(1e-6, 0.0, 1.0)] {
        let ViewTarget::Front(r) = view_target(&scene, o, DVec3::Z) else {
            panic!("the ceiling")
        };
        rec.push(r);
    }
    let receivers = Receivers::from_receivers(&scene, &rec).expect("a finite answer");
    assert_eq!(receivers.direct(), [0.0, 0.0], "in the light's own plane");
    let r = run(&scene, &receivers, &chains_cfg(1 << 16, 4, 2), &mut |_| {
        true
    });
    let (a, b) = (&r.tallies.estimated[0], &r.tallies.estimated[1]);
    // Against the exact Sobolev limit (the source 1e-7 m below the
    // ceiling): L = rho_2 / pi times the reflected illuminance there (the
    // ceiling's direct light is 0 in the limit), a 2 % error detectable.
    let sob = Sobolev::new(3.0 - 1e-7, 1e-7, 0.5, 0.7, 100.0).unwrap();
    let want = 0.7 / std::f64::consts::PI * sob.illuminance(2, 0.0).e_reflected;
    let bound = sidak_bound(1e-3, 1, Some(r.tallies.batches()));
    assert!(
        a.mean().is_finite() && 0.02 * want > bound * a.std_error(),
        "{a:?}"
    );
    assert!(
        (a.mean() - want).abs() < bound * a.std_error(),
        "{} +- {} vs exact {want}",
        a.mean(),
        a.std_error()
    );
    // The same chains score both: their difference is far inside the error.
    assert!(
        (a.mean() - b.mean()).abs() < 0.1 * a.std_error(),
        "{} +- {} vs {} +- {}",
        a.mean(),
        a.std_error(),
        b.mean(),
        b.std_error()
    );
}
