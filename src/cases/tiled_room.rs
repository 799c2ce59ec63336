//! A room of six planes holding `n` small horizontal tiles (shelf boards
//! in a store room): the scene of `lumest bench --shapes`, whose cost per
//! chain shows what the number of shapes costs.
//!
//! The room is 10 x 8 x 3 m (floor reflectance 0.3, walls 0.5, ceiling
//! 0.8) with one 1000 cd point light at (5.05, 4.05, 2.95) m. The tiles
//! (reflectance 0.6, both sides) lie in up to 10 layers between z = 0.4 and
//! 2.6 m, on a square-ish grid per layer over x in [0.5, 9.5], y in
//! [0.5, 7.5]; each covers half of its cell in x and in y, so light passes
//! between them. The receivers are 16 points on the floor (a 4 x 4 grid,
//! facing up).

use crate::geometry::Plane;
use crate::geometry::shapes::Rect;
use crate::light::Light;
use crate::material::Material;
use crate::scene::{Scene, Sides, SurfaceSpec};
use glam::DVec3;

/// Room size \[m\].
const ROOM: [f64; 3] = [10.0, 8.0, 3.0];

/// Most tile layers.
const LAYERS: usize = 10;

/// The scene with `n` tiles (`n = 0`: the bare room of six planes) and
/// its receivers `(point [m], unit normal)`.
pub fn tiled_room(n: usize) -> (Scene, Vec<(DVec3, DVec3)>) {
    let lam = |rho| Material::Lambertian { rho };
    let [lx, ly, lz] = ROOM;
    let mut specs: Vec<SurfaceSpec> = [
        (DVec3::ZERO, DVec3::Z, 0.3),
        (DVec3::new(0.0, 0.0, lz), -DVec3::Z, 0.8),
        (DVec3::ZERO, DVec3::X, 0.5),
        (DVec3::new(lx, 0.0, 0.0), -DVec3::X, 0.5),
        (DVec3::ZERO, DVec3::Y, 0.5),
        (DVec3::new(0.0, ly, 0.0), -DVec3::Y, 0.5),
    ]
    .into_iter()
    .enumerate()
    .map(|(k, (p, nrm, rho))| SurfaceSpec::Plane(format!("wall {k}"), Plane::new(p, nrm), lam(rho)))
    .collect();
    if n > 0 {
        let layers = n.min(LAYERS);
        let per_layer = n.div_ceil(layers);
        // nx / ny close to the floor's aspect ratio.
        let nx = ((per_layer as f64 * (lx - 1.0) / (ly - 1.0)).sqrt().ceil() as usize).max(1);
        let ny = per_layer.div_ceil(nx);
        let (dx, dy) = ((lx - 1.0) / nx as f64, (ly - 1.0) / ny as f64);
        let dz = 2.2 / layers as f64;
        for k in 0..n {
            let (layer, cell) = (k / per_layer, k % per_layer);
            let (i, j) = (cell % nx, cell / nx);
            let corner = DVec3::new(
                0.5 + (i as f64 + 0.25) * dx,
                0.5 + (j as f64 + 0.25) * dy,
                0.4 + (layer as f64 + 0.5) * dz,
            );
            let r = Rect::new(corner, DVec3::X * 0.5 * dx, DVec3::Y * 0.5 * dy)
                .expect("a tile has two non-parallel edges");
            specs.push(SurfaceSpec::Rect(
                format!("tile {k}"),
                r,
                Sides::Both,
                lam(0.6),
            ));
        }
    }
    let light = Light::Point {
        p: DVec3::new(5.05, 4.05, 2.95),
        i: 1000.0,
    };
    let scene = Scene::build(specs, vec![light]).expect("the tiled room is a valid scene");
    let points = (0..16)
        .map(|k| {
            let (i, j) = ((k % 4) as f64, (k / 4) as f64);
            (DVec3::new(1.2 + 2.5 * i, 1.1 + 1.9 * j, 0.0), DVec3::Z)
        })
        .collect();
    (scene, points)
}
