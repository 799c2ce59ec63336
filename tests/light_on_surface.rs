//! A point light exactly on a surface (a luminaire at ceiling height, a lamp
//! standing on a desk) belongs to the surface's reflecting side: the answer
//! is continuous as the light approaches the surface from that side, and
//! agrees with the exact Sobolev solution in the limit.

mod common;

use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::geometry::Plane;
use lumest::light::Light;
use lumest::material::Material;
use lumest::reference::Sobolev;
use lumest::scene::{Scene, parse};
use statrs::distribution::{ContinuousCDF, Normal};
use std::path::Path;

fn sidak(m: usize) -> f64 {
    let a = 1.0 - (1.0 - 1e-4f64).powf(1.0 / m as f64);
    Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - a / 2.0)
}

fn planes_with_light_at(z: f64) -> Scene {
    Scene::from_parts(
        vec![
            (
                "floor".into(),
                Plane::new(DVec3::ZERO, DVec3::Z),
                Material::Lambertian { rho: 0.5 },
            ),
            (
                "ceiling".into(),
                Plane::new(DVec3::new(0.0, 0.0, 1.0), -DVec3::Z),
                Material::Lambertian { rho: 0.5 },
            ),
        ],
        vec![Light::Point {
            p: DVec3::new(0.0, 0.0, z),
            i: 1.0,
        }],
    )
    .unwrap()
}

#[test]
fn a_light_on_the_ceiling_plane_is_the_limit_of_one_just_below_it() {
    // Exact: the source 1e-7 m below the ceiling (h1 = 1 - 1e-7, h2 = 1e-7).
    let s = Sobolev::new(1.0 - 1e-7, 1e-7, 0.5, 0.5, 1.0).unwrap();
    let mut points = Vec::new();
    let mut exact = Vec::new();
    for k in 0..6 {
        let r = 0.3 * k as f64;
        points.push((DVec3::new(r, 0.0, 0.0), DVec3::Z));
        exact.push(s.illuminance(1, r).e);
    }
    for r in [0.5, 1.0, 2.0] {
        points.push((DVec3::new(0.0, r, 1.0), -DVec3::Z));
        exact.push(s.illuminance(2, r).e);
    }
    let bound = sidak(2 * points.len());
    let cfg = common::chains_cfg(400_000, 3, 2);
    for z in [1.0, 1.0 - 1e-7] {
        let scene = planes_with_light_at(z);
        assert_eq!(scene.light_surface(0).is_some(), z == 1.0);
        let rec = Receivers::new(&scene, &points).unwrap();
        let r = run(&scene, &rec, &cfg, &mut |_| true);
        for (j, &e) in exact.iter().enumerate() {
            let zs = common::z(&r, j, e);
            assert!(
                zs.abs() < bound,
                "light at z = {z}, point {j}: {} vs exact {e} (z = {zs:.2})",
                r.direct[j] + r.tallies.estimated[j].mean()
            );
            // Missing the light sent into the ceiling (the old answer, about
            // 40 % less reflected light) would fail.
            let reflected = e - r.direct[j];
            let se = r.tallies.estimated[j].std_error();
            assert!(
                0.2 * reflected > bound * se,
                "point {j}: too imprecise to see a lost half"
            );
        }
    }
    // Behind the ceiling the light on it is not seen.
    let scene = planes_with_light_at(1.0);
    let rec = Receivers::new(&scene, &[(DVec3::new(0.3, 0.0, 1.5), -DVec3::Z)]).unwrap();
    assert_eq!(rec.direct()[0], 0.0);
}

#[test]
fn a_lamp_standing_on_a_desk_top_equals_one_just_above_it() {
    let src = |z: f64| {
        format!(
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

[[surface]]
name = "desk"
type = "box"
min = [-0.5, -0.4, 0.0]
max = [0.5, 0.4, 0.75]
normals = "outward"
material = {{ type = "lambertian", reflectance = 0.7 }}

[[light]]
type = "point"
position = [0.1, 0.0, {z}]
intensity = 100.0
"#
        )
    };
    let points = [
        (DVec3::new(1.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(0.0, 1.0, 0.8), DVec3::Z),
        (DVec3::new(1.5, 0.5, 1.0), DVec3::new(-1.0, 0.0, 0.0)),
        (DVec3::new(0.45, 0.0, 0.75), DVec3::Z), // on the desk top
    ];
    let cfg = common::chains_cfg(400_000, 8, 2);
    let mut res = Vec::new();
    for z in [0.75, 0.75 + 1e-7] {
        let scene = parse(&src(z), Path::new("desk.toml")).unwrap();
        assert_eq!(scene.light_surface(0).is_some(), z == 0.75);
        let rec = Receivers::new(&scene, &points).unwrap();
        res.push(run(&scene, &rec, &cfg, &mut |_| true));
    }
    let bound = sidak(points.len());
    for j in 0..points.len() {
        let e = |k: usize| res[k].direct[j] + res[k].tallies.estimated[j].mean();
        let se = (res[0].tallies.estimated[j].std_error().powi(2)
            + res[1].tallies.estimated[j].std_error().powi(2))
        .sqrt();
        assert!(e(0) > 0.0 && se > 0.0, "point {j}: nothing to compare");
        assert!(
            ((e(0) - e(1)) / se).abs() < bound,
            "point {j}: on the desk {} vs just above {} +- {se}",
            e(0),
            e(1)
        );
    }
}

/// A light on the ceiling of a room given as a closed triangle mesh with
/// inward normals is the same light on the ceiling of the same room given as
/// a box (whose seat has its own tests): the mesh's triangle under the
/// light is its seat. The old build gave a light on a mesh no seat: half
/// its flux left through the ceiling (the room's mean illuminance 12.6 for
/// 18.8 lx) and a point above the ceiling read I cos / d^2.
#[test]
fn a_light_on_a_mesh_ceiling_is_seated_like_one_on_a_box() {
    let dir = std::env::temp_dir().join(format!("lumest-mesh-seat-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A 4 x 4 x 3 m room, every face wound to face inward.
    std::fs::write(
        dir.join("room.obj"),
        "v 0 0 0\nv 4 0 0\nv 0 4 0\nv 4 4 0\nv 0 0 3\nv 4 0 3\nv 0 4 3\nv 4 4 3\n\
         f 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\nf 1 5 6\nf 1 6 2\nf 3 4 8\nf 3 8 7\n\
         f 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\n",
    )
    .unwrap();
    let material = "material = { type = \"lambertian\", reflectance = 0.5 }";
    let light = "[[light]]\ntype = \"point\"\nposition = [1.3, 1.7, 3.0]\nflux = 1000\n";
    let mesh = format!(
        "[[surface]]\ntype = \"mesh\"\nname = \"room\"\nfile = \"room.obj\"\n{material}\n{light}"
    );
    let boxed = format!(
        "[[surface]]\ntype = \"box\"\nname = \"room\"\nmin = [0, 0, 0]\nmax = [4, 4, 3]\n\
         normals = \"inward\"\n{material}\n{light}"
    );
    let points = [
        (DVec3::new(2.0, 2.0, 0.0), DVec3::Z),
        (DVec3::new(0.5, 3.5, 0.8), DVec3::Z),
        (DVec3::new(3.0, 1.0, 3.0), -DVec3::Z),
        (DVec3::new(0.0, 2.0, 1.5), DVec3::X),
    ];
    let cfg = |seed| common::chains_cfg(200_000, seed, 2);
    let mut res = Vec::new();
    for (src, seed) in [(&mesh, 21), (&boxed, 22)] {
        let scene = parse(src, &dir.join("room.toml")).unwrap();
        assert!(
            scene.light_surface(0).is_some(),
            "the light stands on the ceiling"
        );
        // Above the ceiling: not lit.
        let above = Receivers::new(&scene, &[(DVec3::new(1.5, 1.5, 3.5), -DVec3::Z)]).unwrap();
        assert_eq!(above.direct()[0], 0.0);
        let rec = Receivers::new(&scene, &points).unwrap();
        res.push(run(&scene, &rec, &cfg(seed), &mut |_| true));
    }
    let bound = sidak(points.len());
    for j in 0..points.len() {
        let e = |k: usize| res[k].direct[j] + res[k].tallies.estimated[j].mean();
        let se = (res[0].tallies.estimated[j].std_error().powi(2)
            + res[1].tallies.estimated[j].std_error().powi(2))
        .sqrt();
        let reflected = res[1].tallies.estimated[j].mean();
        assert!(0.02 * reflected > bound * se, "point {j}: too imprecise");
        assert!(
            ((e(0) - e(1)) / se).abs() < bound,
            "point {j}: mesh room {} vs box room {} +- {se}",
            e(0),
            e(1)
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The backward estimator (and the local estimator's near part, whose
/// backward paths draw on the chains' collisions instead) with point-like
/// lights on surfaces: what a light sends into the surface it stands on is
/// reflected at its position, which no backward path can hit, so
/// next-event estimation adds it. Against the exact Sobolev solution (the
/// source on the ceiling plane), and in a room with an isotropic source on
/// a wall-ceiling edge and the LM-63 pendant on the ceiling, the two
/// estimators against each other at points near the walls and in a corner
/// (where the near part decides). The old build's backward estimate lost
/// that light (0.78 for 1.47 lx at r = 0.5; the pendant's room 34 for 59 lx).
#[test]
fn backward_paths_see_the_light_sent_into_the_surface_a_source_stands_on() {
    let s = Sobolev::new(1.0 - 1e-7, 1e-7, 0.5, 0.5, 1.0).unwrap();
    let mut points = Vec::new();
    let mut exact = Vec::new();
    for r in [0.0, 0.5, 1.5] {
        points.push((DVec3::new(r, 0.0, 0.0), DVec3::Z));
        exact.push(s.illuminance(1, r).e);
    }
    points.push((DVec3::new(0.0, 0.7, 1.0), -DVec3::Z));
    exact.push(s.illuminance(2, 0.7).e);
    let scene = planes_with_light_at(1.0);
    let rec = Receivers::new(&scene, &points).unwrap();
    let cfg = common::chains_cfg(1 << 17, 31, 2);
    let r = lumest::backward::run(&scene, &rec, &cfg, &mut |_| true);
    let bound = sidak(points.len() + 5);
    for (j, &e) in exact.iter().enumerate() {
        let w = &r.tallies.estimated[j];
        let reflected = e - r.direct[j];
        assert!(
            0.02 * reflected > bound * w.std_error(),
            "point {j}: imprecise"
        );
        let z = common::z(&r, j, e);
        assert!(
            z.abs() < bound,
            "point {j}: backward {} vs exact {e} (z = {z:.2})",
            r.direct[j] + w.mean()
        );
    }
    // The room: local (with its near/far split) against backward.
    let pendant = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/pendant.ies");
    let src = format!(
        "[[surface]]\ntype = \"box\"\nname = \"room\"\nmin = [0, 0, 0]\nmax = [6, 4, 2.8]\n\
         normals = \"inward\"\nmaterial = {{ type = \"lambertian\", reflectance = 0.5 }}\n\n\
         [[light]]\ntype = \"point\"\nposition = [0, 2, 2.8]\nintensity = 100\n\n\
         [[light]]\ntype = \"ies\"\nfile = \"{}\"\nposition = [4, 1.5, 2.8]\n",
        pendant.display()
    );
    let room = parse(&src, Path::new("room.toml")).unwrap();
    assert!(room.light_surface(0).is_some() && room.light_surface(1).is_some());
    let pts = [
        (DVec3::new(3.0, 2.0, 0.0), DVec3::Z),
        (DVec3::new(0.01, 1.0, 1.5), DVec3::X),
        (DVec3::new(5.99, 3.99, 0.01), DVec3::Z),
        (DVec3::new(4.5, 1.5, 2.79), -DVec3::Z),
        (DVec3::new(2.0, 3.99, 1.0), -DVec3::Y),
    ];
    let rec = Receivers::new(&room, &pts).unwrap();
    let local = run(
        &room,
        &rec,
        &common::chains_cfg(1 << 19, 32, 2),
        &mut |_| true,
    );
    let back = lumest::backward::run(
        &room,
        &rec,
        &common::chains_cfg(1 << 16, 33, 2),
        &mut |_| true,
    );
    for j in 0..pts.len() {
        let (a, b) = (&local.tallies.estimated[j], &back.tallies.estimated[j]);
        let se = a.std_error().hypot(b.std_error());
        assert!(0.02 * b.mean() > bound * se, "room point {j}: imprecise");
        let z = (a.mean() - b.mean()) / se;
        assert!(
            z.abs() < bound,
            "room point {j}: local {} vs backward {} +- {se} (z = {z:.2})",
            a.mean(),
            b.mean()
        );
    }
}

/// The reflection orders of the light a source on a surface sends into it
/// (reflected at the source: one order of its own). At a receiver that
/// sees the source it is order 1; added by next-event estimation at a
/// path vertex (or at a guided connection's photon vertex) it is one order
/// above that vertex. It was counted at the vertex's own order: backward
/// order 1 read exact orders 1 + 2 (0.322 for 0.178 lx) and order 2 of a
/// floor point read 0, all flagged `ok`, and `--max-order 1` was wrong in
/// total (a reviewer's find). Backward estimator, with and without the
/// guided connection, and truncated at order 1, against the exact Sobolev
/// orders (the source on the ceiling plane).
#[test]
fn backward_orders_of_a_seated_light_are_the_exact_orders() {
    let s = Sobolev::new(1.0 - 1e-7, 1e-7, 0.5, 0.5, 1.0).unwrap();
    let mut points = Vec::new();
    let mut at = Vec::new();
    for r in [0.0, 0.5, 1.5] {
        points.push((DVec3::new(r, 0.0, 0.0), DVec3::Z));
        at.push((1u8, r));
    }
    points.push((DVec3::new(0.0, 0.7, 1.0), -DVec3::Z));
    at.push((2, 0.7));
    let scene = planes_with_light_at(1.0);
    let rec = Receivers::new(&scene, &points).unwrap();
    let bound = sidak(2 * 3 * points.len());
    for guide in [true, false] {
        let mut cfg = common::chains_cfg(1 << 18, 33, 2);
        cfg.orders = 3;
        cfg.chain.guide = guide;
        let r = lumest::backward::run(&scene, &rec, &cfg, &mut |_| true);
        for (j, &(plane, rr)) in at.iter().enumerate() {
            for k in 0..3 {
                let w = &r.tallies.orders[k][j];
                let exact = s.order(plane, rr, k as u32 + 1);
                // Orders 1 and 2 (between which the light was misplaced)
                // precise enough that a 2 % error shows.
                assert!(
                    k == 2 || 0.02 * exact > bound * w.std_error(),
                    "guide {guide}, point {j}, order {}: imprecise",
                    k + 1
                );
                let z = (w.mean() - exact) / w.std_error();
                assert!(
                    z.abs() < bound,
                    "guide {guide}, point {j}, order {}: {} +- {} vs exact {exact} (z = {z:.2})",
                    k + 1,
                    w.mean(),
                    w.std_error()
                );
            }
        }
    }
    // `--max-order 1`: the once-reflected light alone, in total.
    let mut cfg = common::chains_cfg(1 << 16, 34, 2);
    cfg.chain.max_order = Some(1);
    let r = lumest::backward::run(&scene, &rec, &cfg, &mut |_| true);
    let bound = sidak(points.len());
    for (j, &(plane, rr)) in at.iter().enumerate() {
        let w = &r.tallies.estimated[j];
        let exact = s.order(plane, rr, 1);
        assert!(0.02 * exact > bound * w.std_error(), "point {j}: imprecise");
        let z = (w.mean() - exact) / w.std_error();
        assert!(
            z.abs() < bound,
            "--max-order 1, point {j}: {} vs exact order 1 {exact} (z = {z:.2})",
            w.mean()
        );
    }
}
