//! Triangulating a mesh file's polygon faces by ear clipping.
//!
//! A face of an OBJ file may have any number of vertices and need not be
//! convex (an L-shaped panel, a floor plan): a fan from its first vertex
//! covers the outside of a concave polygon and leaves part of it open.
//! Ear clipping in the polygon's own plane (its Newell normal) covers
//! exactly the polygon for any simple polygon, convex or not, and keeps
//! its winding, so the triangles face the same side as the face.

use glam::{DVec2, DVec3};

/// Triangles of the polygon `pts` (its vertices in order, roughly in one
/// plane), as index triples into `pts` in the polygon's winding: `n - 2` of
/// them for `n >= 3` vertices. A simple polygon (no edge crossing another)
/// is covered exactly; a polygon with no area (collinear vertices) or one
/// that is not simple, where clipping finds no ear, is finished as a fan
/// from a remaining vertex (its zero-area triangles are dropped by the
/// mesh).
pub fn triangulate(pts: &[DVec3]) -> Vec<[usize; 3]> {
    let n = pts.len();
    if n < 3 {
        return Vec::new();
    }
    if n == 3 {
        return vec![[0, 1, 2]];
    }
    // Newell's normal: the polygon's vector area, sense given by the winding.
    let mut normal = DVec3::ZERO;
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        normal += a.cross(b);
    }
    let Some(w) = normal.try_normalize() else {
        return fan(&(0..n).collect::<Vec<_>>());
    };
    // A frame (u, v, w) with u x v = w: the winding is counter-clockwise in
    // (u, v), whatever the polygon's orientation in space.
    let u = w.any_orthonormal_vector();
    let v = w.cross(u);
    // Coordinates about the first vertex, so that the tolerance below
    // scales with the polygon, not with its distance from the origin (a
    // georeferenced model lies 1e5-1e6 m out).
    let o = pts[0];
    let q: Vec<DVec2> = pts
        .iter()
        .map(|p| DVec2::new((*p - o).dot(u), (*p - o).dot(v)))
        .collect();
    // Lengths in the plane for the tolerance of the tests below.
    let scale = q
        .iter()
        .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()))
        .max(f64::MIN_POSITIVE);
    let eps = 1e-12 * scale * scale;
    let mut left: Vec<usize> = (0..n).collect();
    let mut out = Vec::with_capacity(n - 2);
    while left.len() > 3 {
        let m = left.len();
        let ear = (0..m).find(|&k| {
            let (a, b, c) = (left[(k + m - 1) % m], left[k], left[(k + 1) % m]);
            let (pa, pb, pc) = (q[a], q[b], q[c]);
            // Convex corner (strictly), and no other vertex in the ear.
            cross(pb - pa, pc - pb) > eps
                && left
                    .iter()
                    .all(|&j| j == a || j == b || j == c || !in_triangle(q[j], pa, pb, pc, eps))
        });
        match ear {
            Some(k) => {
                let (a, b, c) = (left[(k + m - 1) % m], left[k], left[(k + 1) % m]);
                out.push([a, b, c]);
                left.remove(k);
            }
            None => {
                out.extend(fan(&left));
                return out;
            }
        }
    }
    out.push([left[0], left[1], left[2]]);
    out
}

/// The fan from the first of `idx`.
fn fan(idx: &[usize]) -> Vec<[usize; 3]> {
    (1..idx.len().saturating_sub(1))
        .map(|k| [idx[0], idx[k], idx[k + 1]])
        .collect()
}

/// The z component of `a x b`.
fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Whether `p` lies in the counter-clockwise triangle `a b c` or on its
/// boundary (within `eps`, in squared length).
fn in_triangle(p: DVec2, a: DVec2, b: DVec2, c: DVec2, eps: f64) -> bool {
    cross(b - a, p - a) >= -eps && cross(c - b, p - b) >= -eps && cross(a - c, p - c) >= -eps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed area of triangle `t` of `pts` along `w`.
    fn area(pts: &[DVec3], t: [usize; 3], w: DVec3) -> f64 {
        0.5 * (pts[t[1]] - pts[t[0]]).cross(pts[t[2]] - pts[t[0]]).dot(w)
    }

    /// Whether `p` (in the plane z = const) lies in a polygon, by the
    /// crossing rule: a test that shares nothing with the clipping.
    fn inside(poly: &[DVec3], p: DVec3) -> bool {
        let mut c = false;
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                c = !c;
            }
        }
        c
    }

    /// Concave polygons in both windings and a tilted plane: the
    /// triangles keep the winding, sum to the polygon's area, and cover
    /// exactly its points (a 200 x 200 grid of test points, each inside
    /// the polygon exactly when inside one triangle); a fan fails the L.
    #[test]
    fn concave_polygons_are_covered_exactly() {
        let l = [
            (0.0, 0.0),
            (2.0, 0.0),
            (2.0, 2.0),
            (1.0, 2.0),
            (1.0, 1.0),
            (0.0, 1.0),
        ];
        let comb = [
            (0.0, 0.0),
            (5.0, 0.0),
            (5.0, 3.0),
            (4.0, 3.0),
            (4.0, 1.0),
            (3.0, 1.0),
            (3.0, 3.0),
            (2.0, 3.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 3.0),
            (0.0, 3.0),
        ];
        for (shape, want) in [(&l[..], 3.0), (&comb[..], 11.0)] {
            for reversed in [false, true] {
                let mut pts: Vec<DVec3> =
                    shape.iter().map(|&(x, y)| DVec3::new(x, y, 1.0)).collect();
                if reversed {
                    pts.reverse();
                }
                let w = if reversed { -DVec3::Z } else { DVec3::Z };
                let tris = triangulate(&pts);
                assert_eq!(tris.len(), pts.len() - 2);
                let total: f64 = tris.iter().map(|&t| area(&pts, t, w)).sum();
                assert!((total - want).abs() < 1e-12, "area {total}");
                assert!(tris.iter().all(|&t| area(&pts, t, w) > 0.0), "winding kept");
                for i in 0..200 {
                    for j in 0..200 {
                        let p = DVec3::new(
                            0.01234 + 0.02507 * i as f64,
                            0.01117 + 0.01503 * j as f64,
                            1.0,
                        );
                        let hits = tris
                            .iter()
                            .filter(|t| inside(&[pts[t[0]], pts[t[1]], pts[t[2]]], p))
                            .count();
                        assert_eq!(
                            hits,
                            inside(&pts, p) as usize,
                            "{p} {tris:?} reversed {reversed}"
                        );
                    }
                }
            }
        }
        // The fan from the first vertex covers (0.8, 1.2), outside the L.
        let pts: Vec<DVec3> = l.iter().map(|&(x, y)| DVec3::new(x, y, 1.0)).collect();
        let p = DVec3::new(0.8, 1.2, 1.0);
        assert!(!inside(&pts, p));
        assert!(
            fan(&[0, 1, 2, 3, 4, 5])
                .iter()
                .any(|t| inside(&[pts[t[0]], pts[t[1]], pts[t[2]]], p))
        );
        // The L 0.1 m across and 1e6 m from the origin: still ear-clipped
        // (a tolerance from absolute coordinates found no ear there).
        let far: Vec<DVec3> = l
            .iter()
            .map(|&(x, y)| DVec3::new(1e6 + 0.05 * x, -2e5 + 0.05 * y, 30.0))
            .collect();
        let tris = triangulate(&far);
        let c = DVec3::new(1e6 + 0.05 * 0.8, -2e5 + 0.05 * 1.2, 30.0);
        assert!(inside(
            &far,
            DVec3::new(1e6 + 0.05 * 0.5, -2e5 + 0.05 * 0.5, 30.0)
        ));
        assert!(
            !tris
                .iter()
                .any(|t| inside(&[far[t[0]], far[t[1]], far[t[2]]], c)),
            "{tris:?}"
        );
        // The L tilted out of its plane: the same area.
        let r = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let tilted: Vec<DVec3> = pts.iter().map(|&p| r * p).collect();
        let w = r * DVec3::Z;
        let total: f64 = triangulate(&tilted)
            .iter()
            .map(|&t| area(&tilted, t, w))
            .sum();
        assert!((total - 3.0).abs() < 1e-12);
    }

    /// Degenerate input: fewer than 3 vertices give nothing, collinear
    /// ones a fan of zero-area triangles.
    #[test]
    fn degenerate_polygons() {
        assert!(triangulate(&[DVec3::ZERO, DVec3::X]).is_empty());
        let line = [DVec3::ZERO, DVec3::X, 2.0 * DVec3::X, 3.0 * DVec3::X];
        assert_eq!(triangulate(&line).len(), 2);
    }
}
