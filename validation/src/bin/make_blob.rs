//! Writes `data/blob.obj`: the bundled star-shaped test object (a "potato"
//! with three smooth bumps and a dent, 25,280 triangles), used for the
//! mesh-against-spherical-harmonic comparison and in the office example.
//!
//! `cargo run --release -p lumest-validation --bin make_blob -- data/blob.obj`

use glam::DVec3;
use lumest::geometry::mesh::star_blob;

/// Radius \[m\] of the object in the unit direction `u`: smooth everywhere on
/// the sphere (Gaussian bumps of the chord distance), not a finite
/// spherical-harmonic sum, so a fit of degree L leaves an honest residual.
pub fn blob_radius(u: DVec3) -> f64 {
    let bump = |c: DVec3, w: f64| (-(u - c.normalize()).length_squared() / (w * w)).exp();
    1.0 + 0.05 * u.x * u.y
        + 0.30 * bump(DVec3::new(1.0, 0.3, 0.4), 0.45)
        + 0.22 * bump(DVec3::new(-0.6, 0.8, -0.2), 0.35)
        + 0.15 * bump(DVec3::new(0.1, -0.5, -1.0), 0.6)
        - 0.18 * bump(DVec3::new(-0.4, -0.9, 0.5), 0.4)
}

fn main() {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "data/blob.obj".into());
    let mesh = star_blob(80, 160, |theta: f64, phi: f64| {
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        blob_radius(DVec3::new(st * cp, st * sp, ct))
    })
    .expect("valid blob");
    mesh.write_obj(std::path::Path::new(&out)).expect("write");
    eprintln!("wrote {out}: {} triangles", mesh.triangle_count());
}
