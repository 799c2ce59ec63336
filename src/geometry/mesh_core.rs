//! The core of a closed mesh: an axis-aligned box strictly inside the
//! solid the mesh bounds, at a known distance (`gap`) from every triangle.
//! A segment that passes through the core and has an end outside the
//! mesh's bounds crosses the surface (the inside is where a ray from a
//! point crosses the closed surface an odd number of times; that parity
//! changes only at the surface, and it is odd in the core and 0 outside
//! the bounds), so a shadow test that meets the core needs no BVH
//! traversal ([`Core::blocks`]). Such a crossing lies at least `gap` from
//! the core and from the outside end, so it falls inside the shadow ray's
//! open range whenever the range's end margins are below `gap`, and it is
//! never on a triangle an end lies on that the ray skips (that end would
//! lie on the same flat triangle as the crossing, with the core, inside,
//! between them).
//!
//! Built when every edge of the mesh joins exactly two triangles, once in
//! each direction (a closed, consistently wound surface): the box grows
//! about the centre of the bounds (or the vertices' centroid, whichever
//! gives more room), kept while no triangle's bounding box meets it, and
//! the centre must be inside by the parity of five rays in unrelated
//! directions, all odd. `None` for an open mesh or when no core is found.

use super::segment_meets_box;
use glam::DVec3;
use std::collections::HashMap;

/// A box inside a closed mesh ([module docs](self)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Core {
    /// The box [m].
    pub lo: DVec3,
    pub hi: DVec3,
    /// A lower bound on the distance [m] from the box to every triangle
    /// (and the margin by which an end must lie outside the mesh's bounds).
    pub gap: f64,
}

/// The fraction of the largest valid growth that the core keeps: the rest
/// is its gap to the triangles.
const KEEP: f64 = 0.95;

impl Core {
    /// The core of the closed mesh of triangles `corners` [m] (indices
    /// `triangles` into a shared vertex list, for the closedness check),
    /// bounds `[lo, hi]`; `None` when open or no core is found.
    pub fn find(
        corners: &[[DVec3; 3]],
        triangles: &[[u32; 3]],
        (lo, hi): (DVec3, DVec3),
    ) -> Option<Self> {
        if !closed(triangles) {
            return None;
        }
        let half = 0.5 * (hi - lo);
        if !half.is_finite() || half.min_element() <= 0.0 {
            return None;
        }
        let boxes: Vec<(DVec3, DVec3)> = corners
            .iter()
            .map(|t| (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2])))
            .collect();
        let n = corners.len() as f64;
        let centroid = corners.iter().flatten().fold(DVec3::ZERO, |s, p| s + *p) / (3.0 * n);
        [0.5 * (lo + hi), centroid]
            .into_iter()
            .filter_map(|c| grow(c, half, &boxes, corners))
            .max_by(|a, b| volume(a).total_cmp(&volume(b)))
    }

    /// Whether the segment from `a` to `b` provably crosses the mesh of
    /// bounds `[lo, hi]` whose core this is, for a shadow ray that leaves
    /// out `margin` [m] at each end: `margin` below the gap, an end outside
    /// the bounds by more than the gap, and the segment through the core.
    /// `false` says nothing (the BVH decides).
    #[inline]
    pub fn blocks(&self, (lo, hi): (DVec3, DVec3), a: DVec3, b: DVec3, margin: f64) -> bool {
        let out = |p: DVec3| (lo - p).max(p - hi).max_element() > self.gap;
        margin < self.gap && (out(a) || out(b)) && segment_meets_box(a, b, self.lo, self.hi)
    }
}

fn volume(c: &Core) -> f64 {
    let e = c.hi - c.lo;
    e.x * e.y * e.z
}

/// Every undirected edge used by exactly two triangles, in opposite
/// directions.
fn closed(triangles: &[[u32; 3]]) -> bool {
    let mut edges: HashMap<(u32, u32), (u32, i32)> = HashMap::with_capacity(3 * triangles.len());
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let (key, dir) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
            let e = edges.entry(key).or_insert((0, 0));
            e.0 += 1;
            e.1 += dir;
        }
    }
    !edges.is_empty() && edges.values().all(|&(n, d)| n == 2 && d == 0)
}

/// The largest box `c +- s half` (s in (0, 1]) that no triangle's box
/// meets, shrunk to [`KEEP`] of it, if `c` is inside.
fn grow(c: DVec3, half: DVec3, boxes: &[(DVec3, DVec3)], corners: &[[DVec3; 3]]) -> Option<Core> {
    let clear = |s: f64| {
        let (blo, bhi) = (c - half * s, c + half * s);
        !boxes
            .iter()
            .any(|(l, h)| l.cmple(bhi).all() && h.cmpge(blo).all())
    };
    let (mut ok, mut bad) = (0.0f64, 1.0f64);
    if clear(1.0) {
        ok = 1.0;
    } else {
        for _ in 0..40 {
            let s = 0.5 * (ok + bad);
            if clear(s) {
                ok = s;
            } else {
                bad = s;
            }
        }
    }
    if ok <= 0.0 || !inside(c, corners) {
        return None;
    }
    let s = KEEP * ok;
    let gap = (ok - s) * half.min_element();
    (gap > 0.0).then(|| Core {
        lo: c - half * s,
        hi: c + half * s,
        gap,
    })
}

/// Whether `q` is inside the closed mesh: the crossings of five rays in
/// unrelated directions all odd (a ray through an edge or vertex may
/// miscount, and all five would have to).
fn inside(q: DVec3, corners: &[[DVec3; 3]]) -> bool {
    // (No two components alike in size, so that no ray runs along a
    // diagonal of an axis-aligned face from a centre.)
    const DIRS: [[f64; 3]; 5] = [
        [0.2342, 0.5719, 0.7862],
        [-0.6213, 0.1377, 0.7714],
        [0.8128, -0.4551, 0.3637],
        [-0.2873, -0.8911, 0.3511],
        [0.0931, 0.3797, -0.9204],
    ];
    DIRS.iter().all(|d| {
        let d = DVec3::from_array(*d);
        corners.iter().filter(|t| ray_hits(q, d, t)).count() % 2 == 1
    })
}

/// Moller-Trumbore: whether the ray `q + t d`, `t > 0`, meets triangle `t`.
fn ray_hits(q: DVec3, d: DVec3, t: &[DVec3; 3]) -> bool {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return false;
    }
    let inv = 1.0 / det;
    let s = q - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = s.cross(e1);
    let v = d.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    e2.dot(qv) * inv > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mesh::{Mesh, star_blob};
    use crate::sampling::rng::Philox4x32;

    fn uniform(rng: &mut Philox4x32, lo: DVec3, hi: DVec3) -> DVec3 {
        DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * (hi - lo) + lo
    }

    /// Whenever the core says a segment is blocked, the BVH's shadow ray
    /// over the same range finds a triangle: random segments through and
    /// around the mesh, from outside points, from points on the surface
    /// (skipping their triangle, as a collision's shadow ray does) and
    /// from inside points; and the core catches a good part of the blocked
    /// ones (it is not empty).
    #[test]
    fn core_blocks_only_what_the_bvh_blocks() {
        // Not convex: the radius swings by a quarter.
        let blob = star_blob(48, 96, |t, p| {
            0.3 * (1.0 + 0.25 * (3.0 * t).sin() * (2.0 * p).cos())
        })
        .unwrap();
        let m = blob.transformed(DVec3::new(1.0, 2.0, 0.5), glam::DMat3::IDENTITY, 1.0);
        let core = m.core().expect("a closed blob has a core");
        let (lo, hi) = m.bounds();
        assert!(core.lo.cmpgt(lo).all() && core.hi.cmplt(hi).all());
        let mut rng = Philox4x32::new(7, 1);
        let (mut by_core, mut blocked) = (0, 0);
        let margin_rel = 1e-9;
        for i in 0..20_000 {
            let span = hi - lo;
            let a = uniform(&mut rng, lo - span, hi + span);
            let (b, skip) = match i % 3 {
                0 => (uniform(&mut rng, lo - span, hi + span), None),
                // A point on a triangle.
                1 => {
                    let k = (rng.next_f64() * m.triangle_count() as f64) as u32;
                    let c = m.corners(k);
                    let (u, v) = (rng.next_f64(), rng.next_f64());
                    let (u, v) = if u + v > 1.0 {
                        (1.0 - u, 1.0 - v)
                    } else {
                        (u, v)
                    };
                    (c[0] + (c[1] - c[0]) * u + (c[2] - c[0]) * v, Some(k))
                }
                _ => (uniform(&mut rng, core.lo, core.hi), None),
            };
            // The shadow ray leaves `b` (the end that may lie on the mesh).
            let len = (a - b).length();
            let d = (a - b) / len;
            let margin = margin_rel * len;
            let bvh = m.occluded(b, d, margin, len - margin, skip);
            blocked += bvh as usize;
            if core.blocks((lo, hi), b, a, margin) {
                by_core += 1;
                assert!(
                    bvh,
                    "segment {b} -> {a}: the core says blocked, the BVH not"
                );
            }
        }
        assert!(blocked > 2000, "{blocked}");
        assert!(by_core * 4 > blocked, "core {by_core} of {blocked} blocked");
    }

    /// A mesh with a hole (one triangle removed) has no core; a cube has
    /// one, centred, with a positive gap.
    #[test]
    fn open_meshes_have_no_core() {
        let v: Vec<DVec3> = (0..8)
            .map(|k| DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64))
            .collect();
        // Outward, counter-clockwise faces of the unit cube.
        let t: Vec<[u32; 3]> = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        let cube = Mesh::from_triangles(v.clone(), t.clone()).unwrap();
        let c = cube.core().expect("a closed cube has a core");
        assert!(c.gap > 0.0);
        assert!((0.5 * (c.lo + c.hi) - DVec3::splat(0.5)).length() < 1e-12);
        let open = Mesh::from_triangles(v, t[1..].to_vec()).unwrap();
        assert!(open.core().is_none());
    }
}
