//! The top-level BVH of the finite shapes answers exactly as the linear
//! loops: random scenes of hundreds of rectangles, discs, spheres, boxes,
//! two meshes and an SH object, with shared tile edges, duplicated shapes
//! and area sources set into coplanar surfaces; nearest hits (from the air,
//! leaving surfaces, observers on surfaces, aimed at shared edges) and
//! visibility (segments between surface points) compared bit for bit at
//! scales from millimetres to 10 km; then whole runs of both estimators
//! bit-identical with and without the tree.

mod common;
use common::chains_cfg;
use glam::{DMat3, DVec3};
use lumest::estimator::Receivers;
use lumest::geometry::mesh::star_blob;
use lumest::geometry::sh::{ShCoeff, ShSurface};
use lumest::geometry::shapes::{AaBox, Disc, Rect, Sphere};
use lumest::geometry::{Hit, Plane, Ray};
use lumest::light::Light;
use lumest::light::area::{AreaLight, AreaShape};
use lumest::light::radial_profile::RadialProfile;
use lumest::material::Material;
use lumest::sampling::Philox4x32;
use lumest::scene::{Accel, Scene, Sides, SurfaceSpec};
use std::sync::Arc;

/// A room (six planes, 10 x 8 x 4 units) furnished at random, at `s`
/// metres per unit, shifted by `off` units. Returns the scene, the emitters'
/// centres with their downward-facing normals, and the tile-grid edge points.
struct Furnished {
    scene: Scene,
    emitter_targets: Vec<(DVec3, u32)>,
    edge_points: Vec<DVec3>,
}

fn furnished(seed: u64, s: f64, off: DVec3, with_sh: bool, n_random: usize) -> Furnished {
    let mut rng = Philox4x32::new(seed, 0);
    let mut u = move || rng.next_f64();
    let v = |x: f64, y: f64, z: f64| (DVec3::new(x, y, z) + off) * s;
    let lam = |rho| Material::Lambertian { rho };
    let mut specs = vec![];
    for (p, n) in [
        (v(0.0, 0.0, 0.0), DVec3::Z),
        (v(0.0, 0.0, 4.0), -DVec3::Z),
        (v(0.0, 0.0, 0.0), DVec3::X),
        (v(10.0, 0.0, 0.0), -DVec3::X),
        (v(0.0, 0.0, 0.0), DVec3::Y),
        (v(0.0, 8.0, 0.0), -DVec3::Y),
    ] {
        specs.push(SurfaceSpec::Plane(
            "wall".into(),
            Plane::new(p, n),
            lam(0.5),
        ));
    }
    let rect = |o: DVec3, e1: DVec3, e2: DVec3| Rect::new(o, e1, e2).unwrap();
    let e = |x: f64, y: f64, z: f64| DVec3::new(x, y, z) * s;
    // A shelf of 8 x 6 tiles sharing edges at z = 1 (both sides reflect).
    let mut edge_points = vec![];
    for i in 0..8 {
        for j in 0..6 {
            let (x, y) = (1.0 + 0.5 * i as f64, 1.0 + 0.5 * j as f64);
            specs.push(SurfaceSpec::Rect(
                format!("tile {i} {j}"),
                rect(v(x, y, 1.0), e(0.5, 0.0, 0.0), e(0.0, 0.5, 0.0)),
                Sides::Both,
                lam(0.6),
            ));
            edge_points.push(v(x, y + 0.25, 1.0));
            edge_points.push(v(x + 0.25, y, 1.0));
            edge_points.push(v(x, y, 1.0));
        }
    }
    // Ceiling panels in the ceiling's plane, facing down.
    for k in 0..6 {
        let x = 1.0 + 1.4 * k as f64;
        specs.push(SurfaceSpec::Rect(
            format!("panel {k}"),
            rect(v(x, 5.0, 4.0), e(0.0, 1.2, 0.0), e(1.2, 0.0, 0.0)),
            Sides::Front,
            lam(0.7),
        ));
    }
    // Two identical rectangles and two identical spheres (every hit a tie).
    for _ in 0..2 {
        specs.push(SurfaceSpec::Rect(
            "twin".into(),
            rect(v(6.0, 1.0, 2.0), e(1.0, 0.0, 0.3), e(0.0, 1.0, 0.0)),
            Sides::Both,
            lam(0.4),
        ));
        specs.push(SurfaceSpec::Sphere(
            "twin ball".into(),
            Sphere {
                c: v(8.0, 6.0, 1.0),
                r: 0.5 * s,
            },
            Sides::Both,
            lam(0.4),
        ));
    }
    // A disc on the floor and one under the shelf (user discs).
    specs.push(SurfaceSpec::Disc(
        "rug".into(),
        Disc::new(v(7.0, 4.0, 0.0), DVec3::Z, 1.0 * s),
        Sides::Front,
        lam(0.3),
    ));
    specs.push(SurfaceSpec::Disc(
        "lamp shade".into(),
        Disc::new(v(8.5, 2.0, 3.0), -DVec3::Z, 0.5 * s),
        Sides::Both,
        lam(0.3),
    ));
    // Two boxes sharing a face.
    for x in [1.0, 2.0] {
        specs.push(SurfaceSpec::Box(
            "cabinet".into(),
            AaBox {
                lo: v(x, 6.0, 0.0),
                hi: v(x + 1.0, 7.5, 1.5),
            },
            Sides::Front,
            [lam(0.5), lam(0.5), lam(0.6), lam(0.6), lam(0.2), lam(0.7)],
        ));
    }
    let dir = |u: &mut dyn FnMut() -> f64| {
        let z = 2.0 * u() - 1.0;
        let phi = std::f64::consts::TAU * u();
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    let pos = |u: &mut dyn FnMut() -> f64| v(0.3 + 9.4 * u(), 0.3 + 7.4 * u(), 0.3 + 3.4 * u());
    for k in 0..n_random {
        let sides = [Sides::Front, Sides::Back, Sides::Both][k % 3];
        match k % 4 {
            0 | 1 => {
                let o = pos(&mut u);
                let (a, b) = (
                    dir(&mut u) * (0.2 + 0.8 * u()),
                    dir(&mut u) * (0.2 + 0.8 * u()),
                );
                if let Some(r) = Rect::new(o, a * s, b * s) {
                    specs.push(SurfaceSpec::Rect(format!("rect {k}"), r, sides, lam(0.5)));
                }
            }
            2 => {
                let c = pos(&mut u);
                specs.push(SurfaceSpec::Disc(
                    format!("disc {k}"),
                    Disc::new(c, dir(&mut u), (0.1 + 0.5 * u()) * s),
                    sides,
                    lam(0.5),
                ));
            }
            _ => {
                let c = pos(&mut u);
                if k % 8 == 3 {
                    specs.push(SurfaceSpec::Sphere(
                        format!("ball {k}"),
                        Sphere {
                            c,
                            r: (0.1 + 0.4 * u()) * s,
                        },
                        sides,
                        lam(0.5),
                    ));
                } else {
                    let h = DVec3::new(u(), u(), u()) * 0.5 * s + DVec3::splat(0.05 * s);
                    specs.push(SurfaceSpec::Box(
                        format!("box {k}"),
                        AaBox { lo: c, hi: c + h },
                        sides,
                        [lam(0.5); 6],
                    ));
                }
            }
        }
    }
    for (k, c) in [v(3.0, 2.5, 2.5), v(8.0, 3.5, 2.0)].into_iter().enumerate() {
        let blob = star_blob(8, 16, |t: f64, p: f64| 1.0 + 0.2 * t.sin() * p.cos())
            .unwrap()
            .transformed(c, DMat3::IDENTITY, 0.4 * s);
        specs.push(SurfaceSpec::Mesh(
            format!("blob {k}"),
            blob,
            Sides::Both,
            lam(0.5),
        ));
    }
    if with_sh {
        let c = |k, m, a, b| ShCoeff { k, m, a, b };
        let sh = ShSurface::new(
            &[c(0, 0, 0.5, 0.0), c(2, 0, 0.08, 0.0), c(3, 2, 0.03, -0.02)],
            v(5.0, 6.5, 2.5),
            DMat3::from_rotation_x(0.3),
            s,
        )
        .unwrap();
        specs.push(SurfaceSpec::Sh("sh".into(), sh, Sides::Front, lam(0.7)));
    }
    // Area sources set into coplanar surfaces: two panels in the ceiling's
    // plane (one over a ceiling panel), one under the shelf in its plane
    // facing down, a disc in the lamp shade's plane.
    let area = |shape| {
        Light::Area(Arc::new(AreaLight {
            shape,
            l0: 300.0,
            two_sided: false,
            material: lam(0.0),
            surface: u32::MAX,
        }))
    };
    let down = |o: DVec3, a: f64, b: f64| AreaShape::Rect {
        corner: o,
        e1: e(0.0, b, 0.0),
        e2: e(a, 0.0, 0.0),
    };
    let lights = vec![
        Light::Point {
            p: v(5.1, 4.1, 3.0),
            i: 200.0,
        },
        area(down(v(2.0, 2.0, 4.0), 1.0, 0.6)),
        area(down(v(1.3, 5.3, 4.0), 0.6, 0.6)),
        area(down(v(2.1, 1.6, 1.0), 0.8, 0.8)),
        area(AreaShape::Disc {
            center: v(8.5, 2.0, 3.0),
            normal: -DVec3::Z,
            radius: 0.3 * s,
            profile: RadialProfile::uniform(0.3 * s),
        }),
    ];
    let n_specs = specs.len() as u32;
    let scene = Scene::build(specs, lights).unwrap();
    // The emitters' surfaces follow the user's surfaces (box faces count 6).
    let emitter_surfaces: Vec<u32> = (0..scene.surfaces.len() as u32)
        .filter(|&k| scene.surfaces[k as usize].emitter.is_some())
        .collect();
    assert_eq!(emitter_surfaces.len(), 4);
    assert!(emitter_surfaces.iter().all(|&k| k >= n_specs));
    let emitter_targets = vec![
        (v(2.5, 2.3, 4.0), emitter_surfaces[0]),
        (v(1.6, 5.6, 4.0), emitter_surfaces[1]),
        (v(2.5, 2.0, 1.0), emitter_surfaces[2]),
        (v(8.6, 2.1, 3.0), emitter_surfaces[3]),
    ];
    Furnished {
        scene,
        emitter_targets,
        edge_points,
    }
}

fn same(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.t.to_bits() == b.t.to_bits()
                && a.p.to_array().map(f64::to_bits) == b.p.to_array().map(f64::to_bits)
                && a.n.to_array().map(f64::to_bits) == b.n.to_array().map(f64::to_bits)
                && a.surface == b.surface
                && a.prim == b.prim
        }
        _ => false,
    }
}

/// A search bounded at `t_max` (`Scene::intersect_within`,
/// `first_hit_within`) answers as the full search filtered to `t < t_max`:
/// checked at the hit's own `t`, a hair either side of it, and at `t_max`
/// well before and beyond, on both scenes. At an edge or emitter tie the
/// competing hits lie within 1e-9 (relative) of the answer, so a bound
/// that cut them off would change it.
fn check_within(
    scenes: [&Scene; 2],
    ray: Ray,
    from: Option<(u32, u32)>,
    observer: bool,
    full: &Option<Hit>,
    rng: &mut Philox4x32,
) {
    let t = full.as_ref().map_or(1.0, |h| h.t);
    for t_max in [
        t,
        t * (1.0 + 1e-12),
        t * (1.0 - 1e-12),
        t * (1.0 + 1e-10),
        t * 0.5 * rng.next_f64(),
        t * (1.0 + 4.0 * rng.next_f64()),
    ] {
        let want = full.filter(|h| h.t < t_max);
        for s in scenes {
            let got = if observer {
                s.first_hit_within(ray.o, ray.d, t_max)
            } else {
                s.intersect_within(&ray, from, t_max)
            };
            assert!(
                same(&want, &got),
                "within {t_max}: o {} d {} from {from:?}: full {full:?}, bounded {got:?}",
                ray.o,
                ray.d
            );
        }
    }
}

fn unit(u: &mut Philox4x32) -> DVec3 {
    let z = 2.0 * u.next_f64() - 1.0;
    let phi = std::f64::consts::TAU * u.next_f64();
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Counts of what the comparisons exercised.
#[derive(Default, Debug)]
struct Seen {
    rays: usize,
    hits: usize,
    leaving: usize,
    observers: usize,
    edge_ties: usize,
    emitter_ties: usize,
    segments: usize,
    blocked: usize,
}

fn compare(f: &Furnished, seed: u64, s: f64, off: DVec3, n_rays: usize) -> Seen {
    let lin = f.scene.clone().with_accel(Accel::Never);
    let tree = f.scene.clone().with_accel(Accel::Always);
    assert_eq!(lin.shape_tree_bytes(), 0);
    assert!(tree.shape_tree_bytes() > 0);
    let mut rng = Philox4x32::new(seed, 1);
    let mut seen = Seen::default();
    let air = |rng: &mut Philox4x32| {
        (DVec3::new(
            0.2 + 9.6 * rng.next_f64(),
            0.2 + 7.6 * rng.next_f64(),
            0.2 + 3.6 * rng.next_f64(),
        ) + off)
            * s
    };
    let mut surface_points: Vec<(DVec3, (u32, u32))> = vec![];
    // (Their own streams: the rays drawn from `rng` stay those of before.)
    let mut within_rng = Philox4x32::new(seed, 2);
    let mut observer_rng = Philox4x32::new(seed, 3);
    let mut check_ray = |ray: Ray, from: Option<(u32, u32)>, what: &str| -> Option<Hit> {
        let a = lin.intersect(&ray, from);
        let b = tree.intersect(&ray, from);
        assert!(
            same(&a, &b),
            "{what}: o {} d {} from {from:?}: linear {a:?}, tree {b:?}",
            ray.o,
            ray.d
        );
        check_within([&lin, &tree], ray, from, false, &a, &mut within_rng);
        a
    };
    // Rays from the air, then chains of rays leaving the surfaces they hit.
    for _ in 0..n_rays {
        let mut ray = Ray {
            o: air(&mut rng),
            d: unit(&mut rng),
        };
        let mut from = None;
        for bounce in 0..5 {
            seen.rays += 1;
            let Some(h) = check_ray(ray, from, "ray") else {
                break;
            };
            seen.hits += 1;
            if bounce > 0 {
                seen.leaving += 1;
            }
            surface_points.push((h.p, (h.surface, h.prim)));
            from = Some((h.surface, h.prim));
            ray = Ray {
                o: h.p,
                d: unit(&mut rng),
            };
        }
    }
    // Observers standing on surfaces (and in the air), any direction.
    for &(o, _) in surface_points.iter().take(n_rays) {
        let d = unit(&mut rng);
        let (a, b) = (lin.first_hit_from(o, d), tree.first_hit_from(o, d));
        assert!(
            same(&a, &b),
            "observer at {o} d {d}: linear {a:?}, tree {b:?}"
        );
        check_within(
            [&lin, &tree],
            Ray { o, d },
            None,
            true,
            &a,
            &mut observer_rng,
        );
        seen.observers += 1;
    }
    // Rays aimed exactly at shared tile edges and corners: two or four
    // tiles meet the ray at the same t; the fixed order decides.
    for p in &f.edge_points {
        for _ in 0..3 {
            let o = air(&mut rng);
            let ray = Ray {
                o,
                d: (*p - o).normalize(),
            };
            if let Some(h) = check_ray(ray, None, "edge")
                && (h.p - *p).length() < 1e-9 * s
            {
                seen.edge_ties += 1;
            }
        }
    }
    // Area sources set into coplanar surfaces: the emitter wins the tie.
    for &(target, surface) in &f.emitter_targets {
        for k in 0..60 {
            let o = (DVec3::new(
                0.5 + 9.0 * rng.next_f64(),
                0.5 + 7.0 * rng.next_f64(),
                0.3 + 0.5 * rng.next_f64(),
            ) + off)
                * s;
            let o = if k % 2 == 0 {
                o
            } else {
                target - DVec3::Z * 0.5 * s
            };
            let ray = Ray {
                o,
                d: (target - o).normalize(),
            };
            let h = check_ray(ray, None, "emitter").unwrap();
            if (h.p - target).length() < 1e-9 * s {
                assert_eq!(h.surface, surface, "the emitter at {target} wins the tie");
                seen.emitter_ties += 1;
            }
        }
    }
    // Visibility between surface points, and from the air to surface points.
    for k in 0..surface_points.len() {
        let (a, from) = surface_points[k];
        let (b, _) = surface_points[(k * 7 + 3) % surface_points.len()];
        let c = air(&mut rng);
        for (x, fx, y) in [(a, Some(from), b), (c, None, b), (a, Some(from), c)] {
            let (p, q) = (lin.visible(x, fx, y), tree.visible(x, fx, y));
            assert_eq!(p, q, "visible {x} {fx:?} -> {y}");
            let inside = lin.inside_mask(x) & lin.inside_mask(y);
            let (p2, q2) = (
                lin.blocked_by_shapes(x, fx, y, inside),
                tree.blocked_by_shapes(x, fx, y, inside),
            );
            assert_eq!(p2, q2, "blocked {x} {fx:?} -> {y}");
            seen.segments += 1;
            seen.blocked += p2 as usize;
        }
    }
    seen
}

#[test]
fn tree_and_loops_agree_bit_for_bit_at_every_scale() {
    for (k, (s, off)) in [
        (1.0, DVec3::ZERO),
        (1e-3, DVec3::ZERO),
        (1e4, DVec3::ZERO),
        (1.0, DVec3::new(1e5, -3e4, 2e4)),
    ]
    .into_iter()
    .enumerate()
    {
        let f = furnished(10 + k as u64, s, off, true, 320);
        let seen = compare(&f, 20 + k as u64, s, off, 800);
        let summary = f.scene.summary();
        assert!(
            summary.rects > 150 && summary.discs > 50 && summary.spheres > 20 && summary.boxes > 30
        );
        // The comparisons exercised what they claim to.
        assert!(seen.hits > 3000 && seen.leaving > 2000, "{seen:?}");
        assert!(seen.edge_ties > 150, "{seen:?}");
        assert!(seen.emitter_ties > 100, "{seen:?}");
        let frac = seen.blocked as f64 / seen.segments as f64;
        assert!(frac > 0.1 && frac < 0.9, "{seen:?}");
    }
}

#[test]
fn auto_builds_the_tree_only_for_scenes_with_many_shapes() {
    use lumest::scene::AUTO_MIN_SHAPES;
    let big = furnished(3, 1.0, DVec3::ZERO, false, 100);
    assert!(big.scene.shape_tree_bytes() > 0);
    assert!(big.scene.summary().to_string().contains("BVH: built"));
    // The room with a few rectangles and no mesh: no tree, no BVH.
    let lam = Material::Lambertian { rho: 0.5 };
    let few: Vec<SurfaceSpec> = (0..AUTO_MIN_SHAPES - 1)
        .map(|k| {
            SurfaceSpec::Rect(
                format!("r{k}"),
                Rect::new(DVec3::new(k as f64, 0.0, 1.0), DVec3::X * 0.5, DVec3::Y).unwrap(),
                Sides::Front,
                lam,
            )
        })
        .chain([SurfaceSpec::Plane(
            "floor".into(),
            Plane::new(DVec3::ZERO, DVec3::Z),
            lam,
        )])
        .collect();
    let light = Light::Point {
        p: DVec3::new(0.0, 0.0, 3.0),
        i: 1.0,
    };
    let scene = Scene::build(few.clone(), vec![light.clone()]).unwrap();
    assert_eq!(scene.shape_tree_bytes(), 0);
    assert!(
        scene
            .summary()
            .to_string()
            .contains("BVH: none (not needed)")
    );
    let mut more = few;
    more.push(SurfaceSpec::Disc(
        "d".into(),
        Disc::new(DVec3::new(0.0, 5.0, 1.0), DVec3::Z, 0.5),
        Sides::Front,
        lam,
    ));
    let scene = Scene::build(more, vec![light]).unwrap();
    assert!(scene.shape_tree_bytes() > 0);
    assert!(scene.summary().to_string().contains("BVH: built"));
}

/// Whole runs (forward local estimate and backward estimator) give the
/// same numbers bit for bit with and without the tree.
#[test]
fn runs_are_bit_identical_with_and_without_the_tree() {
    let f = furnished(5, 1.0, DVec3::ZERO, false, 240);
    let lin = f.scene.clone().with_accel(Accel::Never);
    let tree = f.scene.clone().with_accel(Accel::Always);
    // Points in the air, on the floor, on the shelf (a tile's top), under
    // the ceiling panels.
    let points: Vec<(DVec3, DVec3)> = vec![
        (DVec3::new(5.0, 4.0, 0.0), DVec3::Z),
        (DVec3::new(1.25, 1.25, 1.0), DVec3::Z),
        (DVec3::new(3.0, 2.0, 0.0), DVec3::Z),
        (DVec3::new(7.0, 6.0, 2.0), DVec3::new(0.0, 0.6, 0.8)),
        (DVec3::new(2.0, 5.5, 3.9), -DVec3::Z),
        (DVec3::new(9.0, 1.0, 0.8), DVec3::Z),
    ];
    let cfg = chains_cfg(6000, 7, 2);
    let rl = Receivers::new(&lin, &points).unwrap();
    let rt = Receivers::new(&tree, &points).unwrap();
    let a = lumest::estimator::local::run(&lin, &rl, &cfg, &mut |_| true);
    let b = lumest::estimator::local::run(&tree, &rt, &cfg, &mut |_| true);
    let bits = |r: &lumest::run::RunResult| -> Vec<[u64; 3]> {
        (0..points.len())
            .map(|j| {
                let w = &r.tallies.estimated[j];
                [
                    r.direct[j].to_bits(),
                    w.mean().to_bits(),
                    w.std_error().to_bits(),
                ]
            })
            .collect()
    };
    assert_eq!(
        (a.chains, a.collisions, a.scores),
        (b.chains, b.collisions, b.scores)
    );
    assert_eq!(bits(&a), bits(&b));
    // Light reached every point (the comparison is not of zeros).
    assert!((0..points.len()).all(|j| a.direct[j] + a.tallies.estimated[j].mean() > 0.0));
    let cfg = chains_cfg(1500, 8, 2);
    let a = lumest::backward::run(&lin, &rl, &cfg, &mut |_| true);
    let b = lumest::backward::run(&tree, &rt, &cfg, &mut |_| true);
    assert_eq!(bits(&a), bits(&b));
}

/// The bounded search's margin: an area source set a hair (1e-11 m,
/// within the emitter tie) behind a ceiling panel wins the tie, so a search
/// bounded between the panel's `t` and the source's must answer `None`, as
/// the full search filtered does; a bound with no margin would collect the
/// panel alone and answer it.
#[test]
fn a_bounded_search_keeps_the_tie_beyond_its_bound() {
    let lam = |rho| Material::Lambertian { rho };
    let panel = Rect::new(
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    )
    .unwrap();
    let specs = vec![SurfaceSpec::Rect(
        "panel".into(),
        panel,
        Sides::Both,
        lam(0.5),
    )];
    let light = Light::Area(Arc::new(AreaLight {
        shape: AreaShape::Rect {
            corner: DVec3::new(0.0, 0.0, 2.0 + 1e-11),
            e1: DVec3::new(0.0, 1.0, 0.0),
            e2: DVec3::new(1.0, 0.0, 0.0),
        },
        l0: 100.0,
        two_sided: false,
        material: lam(0.0),
        surface: u32::MAX,
    }));
    let scene = Scene::build(specs, vec![light]).unwrap();
    let emitter = (0..scene.surfaces.len() as u32)
        .find(|&k| scene.surfaces[k as usize].emitter.is_some())
        .unwrap();
    let ray = Ray {
        o: DVec3::new(0.4, 0.3, 0.0),
        d: DVec3::Z,
    };
    let full = scene.intersect(&ray, None).unwrap();
    assert_eq!(full.surface, emitter, "the source wins the tie");
    let panel_t = 2.0;
    assert!(
        full.t > panel_t,
        "the source lies beyond the panel: {}",
        full.t
    );
    for t_max in [panel_t + 2e-12, 0.5 * (panel_t + full.t), full.t] {
        assert!(t_max > panel_t && t_max <= full.t);
        assert!(
            scene.intersect_within(&ray, None, t_max).is_none(),
            "{t_max}"
        );
        assert!(
            scene.first_hit_within(ray.o, ray.d, t_max).is_none(),
            "{t_max}"
        );
    }
    let beyond = scene.intersect_within(&ray, None, full.t * (1.0 + 1e-12));
    assert_eq!(beyond.map(|h| h.surface), Some(emitter));
}
