//! The part of a luminaire's luminous area that the eye sees: CIE 117
//! counts the solid angle of the luminous parts *seen* from the eye, so a
//! luminaire half hidden behind a screen or a beam glares with half its
//! solid angle (its luminance unchanged).
//!
//! The fraction is taken over a fixed stratified set of points on the
//! luminous parts ([`VISIBILITY_GRID`] x [`VISIBILITY_GRID`] cell centres
//! on each part), each part weighted by its projected area towards the eye:
//! exactly 1 when every point is seen and 0 when none is; where an edge of
//! an obstruction crosses the luminaire it is resolved to a cell (1/64 of
//! the part's area per cell on the edge). The points are deterministic, so
//! the rating stays exact given `E_ind`; no random numbers are drawn.
//!
//! The parts: a goniometric luminaire's bottom opening and luminous sides,
//! placed as a volume centred on the luminaire's position (the photometric
//! centre; the sides `height` tall, the bottom `height / 2` below the
//! centre, so a luminaire without luminous sides has its opening through
//! the centre); the solid LM-63 shapes centred there, each seen as its
//! outline from the eye (an ellipsoid's half facing the eye, uniform in its
//! projected ellipse; a horizontal cylinder's end and the half of its
//! mantle facing the eye; a vertical ellipse), the points of
//! [`crate::light::luminous_parts`]; an area source's surface, its points in proportion to its
//! luminance; a sphere light's cap facing the eye, uniform in its
//! projected disc.

use super::LuminousArea;
use crate::light::{Light, LuminaireFrame};
use crate::scene::Scene;
use glam::DVec3;

/// Points along each side of a part's grid.
pub const VISIBILITY_GRID: usize = 8;

/// A point nudged towards the eye by this fraction of its distance before
/// the shadow test, so that a luminous opening lying in a ceiling (its
/// points on the ceiling's plane, up to rounding) is not hidden by that
/// ceiling: 1e-9 of a few metres, far below any modelled size.
const NUDGE: f64 = 1e-9;

/// The fraction (0 to 1) of luminaire `light`'s luminous parts `area`
/// (centre `c`, local axes `frame`) that the eye at `eye` sees, each part
/// weighted by its projected area towards the eye (unit `w`, from the
/// luminaire to the eye). 0 when nothing luminous faces the eye.
pub fn visible_fraction(
    scene: &Scene,
    light: &Light,
    area: &LuminousArea,
    (c, frame): (DVec3, &LuminaireFrame),
    eye: DVec3,
    w: DVec3,
) -> f64 {
    let seen = |q: DVec3| scene.visible(eye, None, q + (eye - q) * NUDGE);
    // The share of the grid's points of one part that the eye sees.
    let share = |point: &dyn Fn([f64; 2]) -> DVec3| -> f64 {
        let n = VISIBILITY_GRID;
        let mut k = 0usize;
        for i in 0..n {
            for j in 0..n {
                let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                k += seen(point(u)) as usize;
            }
        }
        k as f64 / (n * n) as f64
    };
    // (part's projected area, its seen share), summed.
    let mut parts: Vec<(f64, f64)> = Vec::new();
    match area {
        LuminousArea::Gonio { shape, half } => {
            let d = frame.to_local(w);
            let at = |p: DVec3| c + frame.x * p.x + frame.y * p.y + frame.z * p.z;
            for (a, part) in crate::light::luminous_parts::parts(*shape, *half, d, false) {
                if a > 0.0 {
                    parts.push((a, share(&|u| at(part.point(u)))));
                }
            }
        }
        LuminousArea::Flat { .. } => {
            if let Light::Area(a) = light {
                parts.push((1.0, share(&|u| a.sample_point(u).y)));
            }
        }
        LuminousArea::Sphere { r, .. } => {
            // The cap facing the eye, uniform in its projection (a disc).
            let f = crate::sampling::warp::Frame::from_normal(w);
            parts.push((
                1.0,
                share(&|u| {
                    let rho = u[0].sqrt();
                    let (s, co) = crate::sampling::warp::sin_cos_turns(u[1]);
                    let z = (1.0 - rho * rho).max(0.0).sqrt();
                    c + f.to_world(DVec3::new(rho * co, rho * s, z)) * *r
                }),
            ));
        }
    }
    let total: f64 = parts.iter().map(|p| p.0).sum();
    if total > 0.0 {
        parts.iter().map(|p| p.0 * p.1).sum::<f64>() / total
    } else {
        0.0
    }
}
