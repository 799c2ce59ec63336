//! Which side of a closed mesh a point lies on, by the parity of a ray's
//! crossings: a ray from a point inside the solid crosses its closed
//! surface an odd number of times, from outside an even number.
//!
//! Three pairs of opposite rays in unrelated directions are counted, each
//! crossing once (the next query starts strictly beyond the last hit, so
//! two triangles met at the same distance, at a shared edge, count once),
//! and the rays start a hair beyond the point (a billionth of the mesh's
//! size), so that a point on the surface does not count its own triangle.
//! The answer is *inside* only when all six counts are odd, *outside* only
//! when all are even; anything else (a point on the surface: its rays into
//! the solid odd, out of it even; a ray grazing an edge) is *unknown*, and
//! the callers then assume nothing. An open mesh has no sides: unknown.

use super::mesh::Mesh;
use glam::DVec3;

/// Where a point lies against a closed mesh ([module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Inside the solid the mesh bounds.
    Inside,
    /// Outside it.
    Outside,
    /// On the surface, an open mesh, or the rays disagree.
    Unknown,
}

/// Unrelated directions (no two components alike in size, none along an
/// axis or a face diagonal); each is also used reversed.
const DIRS: [[f64; 3]; 3] = [
    [0.2342, 0.5719, 0.7862],
    [-0.6213, 0.1377, 0.7714],
    [0.8128, -0.4551, 0.3637],
];

/// The side of `mesh` that `q` \[m\] lies on.
pub fn side(mesh: &Mesh, q: DVec3) -> Side {
    if !mesh.is_closed() {
        return Side::Unknown;
    }
    let (lo, hi) = mesh.bounds();
    let eps = 1e-9 * (hi - lo).length();
    // Beyond the bounds (by more than the start's hair): outside.
    if (lo - q).max(q - hi).max_element() > eps {
        return Side::Outside;
    }
    let mut odd = 0;
    for d in DIRS {
        let d = DVec3::from_array(d).normalize();
        for d in [d, -d] {
            odd += crossings(mesh, q, d, eps) % 2;
        }
    }
    match odd {
        6 => Side::Inside,
        0 => Side::Outside,
        _ => Side::Unknown,
    }
}

/// Crossings of the ray `q + t d`, `t > t0`, with `mesh`.
fn crossings(mesh: &Mesh, q: DVec3, d: DVec3, t0: f64) -> usize {
    let (mut t_min, mut skip, mut n) = (t0, None, 0);
    // At most one crossing per triangle.
    for _ in 0..mesh.triangle_count() {
        let Some((t, _, tri)) = mesh.first_hit(q, d, t_min, f64::INFINITY, skip) else {
            break;
        };
        n += 1;
        t_min = t;
        skip = Some(tri);
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit cube `[0, 1]^3` (outward, counter-clockwise faces), and an
    /// open box (its top left out).
    fn cube(open: bool) -> Mesh {
        let v: Vec<DVec3> = (0..8)
            .map(|k| DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64))
            .collect();
        let mut f = vec![
            [0, 2, 1],
            [1, 2, 3],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        if !open {
            f.extend([[4, 5, 6], [5, 7, 6]]);
        }
        Mesh::from_triangles(v, f).unwrap()
    }

    #[test]
    fn points_inside_outside_and_on_a_closed_cube() {
        let m = cube(false);
        assert!(m.is_closed());
        for q in [[0.5, 0.5, 0.5], [0.01, 0.99, 0.5], [0.999, 0.001, 0.999]] {
            assert_eq!(side(&m, DVec3::from_array(q)), Side::Inside, "{q:?}");
        }
        // Outside, also within the bounds' slab on two axes, and beyond
        // them; and a point off a face by a millimetre.
        for q in [
            [1.5, 0.5, 0.5],
            [0.5, 0.5, -0.2],
            [3.0, 3.0, 3.0],
            [0.5, 0.5, 1.001],
        ] {
            assert_eq!(side(&m, DVec3::from_array(q)), Side::Outside, "{q:?}");
        }
        // On a face, an edge or a corner: not inside.
        for q in [
            [0.5, 0.5, 1.0],
            [0.5, 0.0, 0.3],
            [1.0, 1.0, 0.5],
            [0.0, 0.0, 0.0],
        ] {
            assert_ne!(side(&m, DVec3::from_array(q)), Side::Inside, "{q:?}");
        }
    }

    #[test]
    fn an_open_mesh_has_no_inside() {
        let m = cube(true);
        assert!(!m.is_closed());
        assert_eq!(side(&m, DVec3::splat(0.5)), Side::Unknown);
    }

    /// Against a second rule that shares no code: a point inside the
    /// star-shaped blob iff it is closer to the centre than the surface
    /// along its own direction (the blob's radius function), away from a
    /// thin shell around the surface where the triangulation departs from it.
    #[test]
    fn the_star_blob_by_its_radius() {
        let radius = |t: f64, p: f64| 1.0 + 0.3 * (3.0 * t).sin() * (2.0 * p).cos();
        let m = crate::geometry::mesh::star_blob(48, 96, radius).unwrap();
        let mut rng = crate::sampling::rng::Philox4x32::new(7, 0);
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..2000 {
            let q = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 3.2
                - DVec3::splat(1.6);
            let r = q.length();
            let surface = radius((q.z / r).acos(), q.y.atan2(q.x));
            if (r - surface).abs() < 0.05 {
                continue;
            }
            let want = if r < surface {
                Side::Inside
            } else {
                Side::Outside
            };
            assert_eq!(side(&m, q), want, "{q:?} r {r} surface {surface}");
            if want == Side::Inside {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        assert!(inside > 200 && outside > 200, "{inside} {outside}");
    }
}
