//! The core of a closed mesh: an axis-aligned box strictly inside the
//! solid the mesh bounds, at a known distance (`gap`) from every triangle.
//! A segment that passes through the core and has an end outside the
//! mesh's bounds crosses the surface (the inside is where a ray from a
//! point crosses the closed surface an odd number of times; that parity
//! changes only at the surface, and it is odd in the core and 0 outside
//! the bounds), so a shadow test that meets the core needs no BVH
//! traversal ([`Core::blocks`]). Such a crossing lies at least `gap` from
//! the core and from the outside end, so it falls inside the shadow ray's
//! open range whenever the range's end margins are below `gap` by more
//! than the rounding of the ray's distances (half the gap, see
//! [`Core::margin_fits`]), and it is
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
    /// The box \[m\].
    pub lo: DVec3,
    pub hi: DVec3,
    /// A lower bound on the distance \[m\] from the box to every triangle
    /// (and the margin by which an end must lie outside the mesh's bounds).
    pub gap: f64,
}

/// The fraction of the largest valid growth that the core keeps: the rest
/// is its gap to the triangles.
const KEEP: f64 = 0.95;

/// The largest share of the gap a shadow ray's end margin may take for the
/// core to answer ([`Core::margin_fits`]): the rest, half the gap, is far
/// above the rounding of the ray's distances (a few ulp of a length at most
/// `gap / MESH_REL`, some 1e-7 of the gap).
pub const MARGIN_SHARE: f64 = 0.5;

impl Core {
    /// The core of the closed mesh of triangles `corners` \[m\] (indices
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
    /// out `margin` \[m\] at each end: `margin` within [`Self::margin_fits`],
    /// an end outside the bounds by more than the gap, and the segment
    /// through the core. `false` says nothing (the BVH decides).
    #[inline]
    pub fn blocks(&self, (lo, hi): (DVec3, DVec3), a: DVec3, b: DVec3, margin: f64) -> bool {
        let out = |p: DVec3| (lo - p).max(p - hi).max_element() > self.gap;
        self.margin_fits(margin) && (out(a) || out(b)) && segment_meets_box(a, b, self.lo, self.hi)
    }

    /// Whether a shadow ray's end margin \[m\] leaves the crossing (at least
    /// `gap` from either end) inside its range with room for the rounding
    /// of the ray's distances: at most [`MARGIN_SHARE`] of the gap. (With
    /// `margin` just below `gap`, a crossing `gap` from an end of a long
    /// segment falls on either side of the range's end by a few ulp of the
    /// length, and the BVH may miss what the core claims.)
    #[inline]
    pub fn margin_fits(&self, margin: f64) -> bool {
        margin <= MARGIN_SHARE * self.gap
    }
}

fn volume(c: &Core) -> f64 {
    let e = c.hi - c.lo;
    e.x * e.y * e.z
}

/// Every undirected edge used by exactly two triangles, in opposite
/// directions.
pub(crate) fn closed(triangles: &[[u32; 3]]) -> bool {
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

/// Whether every edge joins exactly two triangles, whichever way each
/// runs: a closed surface, wound consistently or not.
pub(crate) fn closed_unoriented(triangles: &[[u32; 3]]) -> bool {
    let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(3 * triangles.len());
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    !edges.is_empty() && edges.values().all(|&n| n == 2)
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

/// The cube `at + s [0, 1]^3` as a closed mesh: outward, counter-clockwise
/// faces (the tests' simplest closed solid).
#[cfg(test)]
pub(crate) fn test_cube(s: f64, at: DVec3) -> crate::geometry::mesh::Mesh {
    let v: Vec<DVec3> = (0..8)
        .map(|k| at + s * DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64))
        .collect();
    crate::geometry::mesh::Mesh::from_triangles(v, TEST_CUBE_FACES.to_vec()).unwrap()
}

/// The faces of [`test_cube`].
#[cfg(test)]
pub(crate) const TEST_CUBE_FACES: [[u32; 3]; 12] = [
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
        let cube = test_cube(1.0, DVec3::ZERO);
        let c = cube.core().expect("a closed cube has a core");
        assert!(c.gap > 0.0);
        assert!((0.5 * (c.lo + c.hi) - DVec3::splat(0.5)).length() < 1e-12);
        let v = cube.vertices().to_vec();
        let open = Mesh::from_triangles(v, TEST_CUBE_FACES[1..].to_vec()).unwrap();
        assert!(open.core().is_none());
    }
}

/// Adversarial segments: the core never claims what the BVH's shadow ray
/// (as `Scene::blocks` casts it) does not find.
#[cfg(test)]
mod adversarial_tests {
    use super::*;
    use crate::geometry::mesh::Mesh;
    use crate::sampling::rng::Philox4x32;

    const MESH_REL: f64 = 1e-9;

    /// As `Scene::blocks` asks: the core first, else the BVH; and the BVH
    /// alone.
    fn both(m: &Mesh, a: DVec3, b: DVec3, skip: Option<u32>) -> (bool, bool) {
        let len = (b - a).length();
        let d = (b - a) / len;
        let core = m
            .core()
            .is_some_and(|c| c.blocks(m.bounds(), a, b, MESH_REL * len));
        let bvh = m.occluded(a, d, MESH_REL * len, (1.0 - MESH_REL) * len, skip);
        (core, bvh)
    }

    /// Long segments whose end margin `MESH_REL len` lies just below the
    /// gap, from far off to a point in the core about `gap` from a face.
    #[test]
    fn margins_just_below_the_gap() {
        let mut rng = Philox4x32::new(3, 3);
        let mut bad = Vec::new();
        let mut n_core = 0;
        for &s in &[1e-3, 1.0, 0.37] {
            let m = test_cube(s, DVec3::new(0.3, -0.2, 0.1));
            let c = *m.core().unwrap();
            for i in 0..4000 {
                // In the core, on its face nearest the bottom of the cube.
                let mut b = c.lo + (c.hi - c.lo) * DVec3::new(rng.next_f64(), rng.next_f64(), 0.0);
                b.z = c.lo.z + (rng.next_f64() - 0.5) * 1e-12 * s;
                // From far below: MESH_REL len just under the gap.
                // (Every other one well below the gap, so that the core
                // has something to answer whatever its rule.)
                let f = if i % 2 == 0 {
                    1.0 - 1e-6 * rng.next_f64()
                } else {
                    0.1 + 0.3 * rng.next_f64()
                };
                let len = c.gap / MESH_REL * f;
                let dir = DVec3::new(
                    1e-3 * (rng.next_f64() - 0.5),
                    1e-3 * (rng.next_f64() - 0.5),
                    -1.0,
                )
                .normalize();
                let a = b + dir * len;
                for (p, q) in [(a, b), (b, a)] {
                    let (core, bvh) = both(&m, p, q, None);
                    n_core += core as usize;
                    if core && !bvh {
                        bad.push((s, i, p, q));
                    }
                }
            }
        }
        assert!(n_core > 1000, "{n_core}");
        assert!(
            bad.is_empty(),
            "{} misses, first {:?}",
            bad.len(),
            bad.first()
        );
    }

    /// Adversarial segments on a non-convex blob and a cube: from a
    /// vertex or an edge's midpoint of the mesh (skipping a triangle
    /// there), from a corner or edge of the core (grazing it), to points
    /// just beyond the bounds by the gap, and the same with the ends
    /// swapped.
    #[test]
    fn adversarial_segments_agree_with_the_bvh() {
        let blob = crate::geometry::mesh::star_blob(12, 24, |t, p| {
            0.3 * (1.0 + 0.3 * (3.0 * t).sin() * (2.0 * p).cos())
        })
        .unwrap()
        .transformed(DVec3::new(1.0, 2.0, 0.5), glam::DMat3::IDENTITY, 1.0);
        let mut rng = Philox4x32::new(9, 1);
        let mut bad = Vec::new();
        let mut n_core = 0;
        for m in [
            test_cube(1.0, DVec3::ZERO),
            test_cube(0.01, DVec3::splat(5.0)),
            blob,
        ] {
            let c = *m.core().unwrap();
            let (lo, hi) = m.bounds();
            let cc: Vec<DVec3> = (0..8)
                .map(|k| {
                    DVec3::new(
                        if k & 1 == 0 { c.lo.x } else { c.hi.x },
                        if k & 2 == 0 { c.lo.y } else { c.hi.y },
                        if k & 4 == 0 { c.lo.z } else { c.hi.z },
                    )
                })
                .collect();
            for i in 0..20_000 {
                // The first end: on the mesh (a vertex or an edge's
                // midpoint, skipping one triangle there), or a corner of
                // the core, or a point in the core.
                let k = (rng.next_f64() * m.triangle_count() as f64) as u32;
                let t = m.corners(k);
                let (a, skip) = match i % 4 {
                    0 => (t[i % 3], Some(k)),
                    1 => (0.5 * (t[0] + t[1]), Some(k)),
                    2 => (cc[i % 8], None),
                    _ => (
                        c.lo + (c.hi - c.lo)
                            * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()),
                        None,
                    ),
                };
                // The other: just beyond the bounds by the gap on one
                // axis, aimed through the core (or a corner of it).
                let axis = i % 3;
                let target = if i % 2 == 0 {
                    cc[(i / 3) % 8]
                } else {
                    c.lo + (c.hi - c.lo)
                        * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64())
                };
                let dir = (target - a).normalize_or_zero();
                if dir == DVec3::ZERO {
                    continue;
                }
                let mut b = if dir[axis] > 0.0 { hi } else { lo };
                let sign = if dir[axis] > 0.0 { 1.0 } else { -1.0 };
                b[axis] += sign * c.gap * (1.0 + 1e-12 * rng.next_f64());
                // On the line from `a` through `target`, at that plane.
                if dir[axis].abs() < 1e-6 {
                    continue;
                }
                let tt = (b[axis] - a[axis]) / dir[axis];
                let mut q = a + dir * tt;
                q[axis] = b[axis];
                for (p, r, sk) in [(a, q, skip), (q, a, None)] {
                    let (core, bvh) = both(&m, p, r, sk);
                    n_core += core as usize;
                    if core && !bvh {
                        bad.push((i, p, r, sk));
                    }
                }
            }
        }
        assert!(n_core > 10_000, "{n_core}");
        assert!(
            bad.is_empty(),
            "{} misses, first {:?}",
            bad.len(),
            bad.first()
        );
    }
}
