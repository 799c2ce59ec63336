//! A receiver a hair beside a mesh face it does not lie on reads that
//! face's light. Rays and shadow tests used to skip every triangle within
//! 1e-9 of the mesh's size of their start, so a floor point 1e-10 m from a
//! cabinet mesh's side saw through it: E_indirect 0.21 lx, flagged `ok`,
//! against 3.58 lx 1 mm away; and a point 1e-10 m from the side at half
//! its height, facing up, was moved onto the side, saw it edge-on and read
//! no reflected light at all, against 5.3 lx beside it.
//!
//! Reference: the same cabinet as a box on a rectangle floor (shapes whose
//! tests share no code with the meshes'), at points 1e-6 m from its side,
//! with another seed. Both estimators are checked.

mod common;

use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::scene::{Scene, parse};
use lumest::tally::sidak_bound;

const LIGHT: &str = r#"
[[light]]
type = "point"
position = [0.0, 1.5, 2.0]
intensity = 100
"#;

fn shapes() -> Scene {
    let text = format!(
        r#"
[[surface]]
type = "box"
min = [1, 1, 0]
max = [2, 2, 1]
normals = "outward"
material = {{ type = "lambertian", reflectance = 0.5 }}

[[surface]]
type = "rectangle"
corner = [-5, -5, 0]
edge1 = [10, 0, 0]
edge2 = [0, 10, 0]
material = {{ type = "lambertian", reflectance = 0.5 }}
{LIGHT}"#
    );
    parse(&text, std::path::Path::new("shapes.toml")).unwrap()
}

/// `(mean, standard error)` of the reflected illuminance \[lx\] at each
/// point (facing up), and the direct part.
fn reflected(
    scene: &Scene,
    points: &[DVec3],
    seed: u64,
    backward: bool,
) -> (Vec<(f64, f64)>, Vec<f64>) {
    let pts: Vec<(DVec3, DVec3)> = points.iter().map(|&p| (p, DVec3::Z)).collect();
    let rec = Receivers::new(scene, &pts).unwrap();
    let cfg = common::chains_cfg(if backward { 100_000 } else { 200_000 }, seed, 2);
    let r = if backward {
        lumest::backward::run(scene, &rec, &cfg, &mut |_| true)
    } else {
        lumest::estimator::local::run(scene, &rec, &cfg, &mut |_| true)
    };
    let e = (0..points.len())
        .map(|j| {
            assert_eq!(
                r.tallies.diagnostics(j, r.direct[j]).flag(),
                "ok",
                "point {j}"
            );
            let t = &r.tallies.estimated[j];
            (t.mean(), t.std_error())
        })
        .collect();
    (e, r.direct)
}

#[test]
fn a_point_beside_a_mesh_face_reads_its_light() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = common::cabinet_on_floor_meshes(dir.path());
    let shapes = shapes();
    // Floor points 1e-8, 1e-9 and 1e-10 m from the cabinet's side, and a
    // point 1e-10 m from it at half its height.
    let near = |d: f64, z: f64| DVec3::new(1.0 - d, 1.5, z);
    let at = [
        near(1e-8, 0.0),
        near(1e-9, 0.0),
        near(1e-10, 0.0),
        near(1e-10, 0.5),
    ];
    // The reference 1e-6 m from the side: the reflected light varies by
    // some 1e-6 of itself over that distance.
    let reference = [near(1e-6, 0.0), near(1e-6, 0.5)];
    let (want, want_direct) = reflected(&shapes, &reference, 11, false);
    let want = |j: usize| want[if j < 3 { 0 } else { 1 }];
    for backward in [false, true] {
        let (got, direct) = reflected(&mesh, &at, 12, backward);
        let bound = sidak_bound(1e-3, 2 * at.len(), None);
        for (j, p) in at.iter().enumerate() {
            let (w, wse) = want(j);
            let (g, gse) = got[j];
            let se = wse.hypot(gse);
            // Precise enough that a 2 % error of the reflected part shows.
            assert!(0.02 * w > bound * se, "{p}: se {se} on {w}");
            let z = (g - w) / se;
            assert!(
                z.abs() < bound,
                "{p} (backward {backward}): {g} +- {gse} against {w} +- {wse}, z = {z}"
            );
            let d_ref = want_direct[if j < 3 { 0 } else { 1 }];
            assert!((direct[j] / d_ref - 1.0).abs() < 1e-5, "{p}: {}", direct[j]);
        }
    }
}
