//! A mesh seen from one fixed point: which directions from the point
//! provably miss the mesh, which provably pass through it, and which must
//! be left to the exact test (issue 15, fast rooms: shadow tests from
//! collisions to a receiver behind a sculpture of 25,000 triangles).
//!
//! # The map
//!
//! From a point `p` outside the mesh's bounding ball, every direction
//! towards the ball lies in a cone round the axis `a` from `p` to the
//! ball's centre. The gnomonic projection `(u, v) = (w . e1, w . e2) / (w
//! . a)` (`e1`, `e2` completing `a` to an orthonormal frame) maps that cone
//! into a square `[-W, W]^2` and maps straight lines to straight lines, so
//! a triangle projects to the triangle of its projected corners. The
//! square is cut into `N x N` cells.
//!
//! Let `U` be the union of the projected triangles: a ray from `p` meets
//! the mesh exactly when its direction lies in `U`. A point of `U`'s
//! boundary lies on the projection of an edge whose two triangles project
//! to the same side of it (a silhouette edge), of an edge that does not
//! join exactly two triangles (a border), or of a triangle seen edge-on:
//! across any other edge the two triangles continue each other, and round
//! a vertex whose edges are all such the triangles' fan covers a whole
//! neighbourhood. Every such edge is drawn into the map, grown by a margin
//! `pad`: those cells are left to the exact test. Every other cell lies
//! more than `pad` from `U`'s boundary, so it lies wholly inside `U` or
//! wholly outside, and neighbouring cells share their side (their union is
//! connected and does not meet the boundary). Each connected group of
//! such cells is classified by one exact ray through a cell's centre.
//!
//! # Why the answers are the exact test's, bit for bit
//!
//! The exact test is the mesh's watertight ray-triangle test
//! ([`super::bvh`]), whose rounding moves a direction by a few ulp of the
//! coordinates' magnitude over the distance (some `1e-16` of them); `pad`
//! is `1e-9` of them, far above that. The test's ray starts at the
//! segment's other end, so an end far from the mesh or from the origin
//! (beyond `5e4` times the distance to the ball plus the scale of the
//! coordinates, see `LIMIT_REL`) is left to the exact test: a reviewer's
//! 1e-6 m mesh in a room of 1e8 m differed in the third digit without this. A direction in an open cell is more
//! than `pad` from every triangle's projection: no triangle is met. A
//! direction in an inside cell is more than `pad` inside `U`: the
//! watertight test meets some triangle, inside the mesh's ball. When the
//! segment's far end lies past the ball along the segment (outside it by a
//! relative `1e-6` of the segment's length, beyond the ball's centre) and
//! `p` lies outside it (by `1e-6` of the distance, checked when the map is
//! built), that hit lies farther from both ends than the shadow test's end
//! margins (`1e-9` of the length), so it counts: the segment is blocked.
//! Every other case (an edge cell, a far end within the ball or before it)
//! is left to the exact test.

use super::bvh::Ends;
use super::mesh::Mesh;
use glam::DVec3;

/// Cells along each side of a map.
pub const CELLS: usize = 64;

/// Bytes one map holds (its cells).
pub const MAP_BYTES: usize = CELLS * CELLS;

/// Relative margins (see the module docs).
const PAD_REL: f64 = 1e-9;
const END_REL: f64 = 1e-6;

/// The exact test's ray starts at the segment's other end `x`: its
/// rounding moves the ray, near the mesh, by some `8 eps (|x|_inf + |x -
/// p| + S)` (`S` the coordinates' scale of `p` and the mesh), which seen
/// from `p` across the distance `D` to the ball stays below the margin
/// `1e-9 (1 + S / D)` while `|x|_inf + |x - p|` stays below
/// `1e-9 / (8 eps) (D + S)`, 5.6e5 times `D + S`: the map answers ends
/// within a tenth of that.
const LIMIT_REL: f64 = 5e4;

/// Distance of `p` from a triangle's plane, relative to the distance from
/// `p` to the ball's far side (at least its distance from the triangle)
/// plus the coordinates' scale, within which the triangle counts as seen
/// edge-on (its edges drawn). It must exceed the rounding
/// of the side's sign, and the exact test's end tolerance: a hit within
/// its end margin of `p` is skipped when `p` lies within `Mesh::on_tolerance`
/// of the triangle's plane, which for an end at the [`LIMIT_REL`] bound
/// reaches about `3.6e-10 (D + S)` (64 ulp of its coordinates); such a
/// triangle is then drawn, never behind an inside cell. `1e-8` keeps that
/// 28 times clear (a reviewer's reading: 2.8 times with `1e-9`).
const EDGE_ON_REL: f64 = 1e-8;

/// A cell's class.
const OPEN: u8 = 0;
const INSIDE: u8 = 1;
const EDGE: u8 = 2;
/// Not yet classified (during the build).
const UNKNOWN: u8 = 3;

/// What a map says of a segment from its point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Seen {
    /// The segment misses every triangle.
    Open,
    /// The segment passes through the mesh (a hit the exact test counts).
    Blocked,
    /// Left to the exact test.
    Test,
}

/// The edges of a mesh and its triangles' planes, shared by all the maps of
/// that mesh.
#[derive(Clone, Debug)]
pub struct MeshEdges {
    /// Per triangle: `n = (b - a) x (c - a)` in its stored order, `n . a`
    /// and `|n|`.
    normals: Vec<DVec3>,
    offsets: Vec<f64>,
    norms: Vec<f64>,
    /// Per edge `(a, b)` (vertex indices): the two triangles joined there
    /// (`t1 = u32::MAX` where the edge does not join exactly two) and
    /// whether both run it the same way.
    edges: Vec<Edge>,
}

#[derive(Clone, Copy, Debug)]
struct Edge {
    a: u32,
    b: u32,
    t0: u32,
    t1: u32,
    same_way: bool,
}

impl MeshEdges {
    /// The edges and planes of `mesh`'s triangles.
    pub fn new(mesh: &Mesh) -> Self {
        let v = mesh.vertices();
        let tris = mesh.triangles();
        let mut normals = Vec::with_capacity(tris.len());
        let mut norms = Vec::with_capacity(tris.len());
        let mut offsets = Vec::with_capacity(tris.len());
        // (min, max, triangle, runs min -> max)
        let mut keys: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(3 * tris.len());
        for (t, tri) in tris.iter().enumerate() {
            let [a, b, c] = tri.map(|i| v[i as usize]);
            let n = (b - a).cross(c - a);
            normals.push(n);
            norms.push(n.length());
            offsets.push(n.dot(a));
            for k in 0..3 {
                let (i, j) = (tri[k], tri[(k + 1) % 3]);
                keys.push((i.min(j), i.max(j), t as u32, i < j));
            }
        }
        keys.sort_unstable();
        let mut edges = Vec::with_capacity(keys.len() / 2 + 1);
        let mut s = 0;
        while s < keys.len() {
            let mut e = s + 1;
            while e < keys.len() && keys[e].0 == keys[s].0 && keys[e].1 == keys[s].1 {
                e += 1;
            }
            let (a, b) = (keys[s].0, keys[s].1);
            edges.push(if e - s == 2 {
                Edge {
                    a,
                    b,
                    t0: keys[s].2,
                    t1: keys[s + 1].2,
                    same_way: keys[s].3 == keys[s + 1].3,
                }
            } else {
                Edge {
                    a,
                    b,
                    t0: keys[s].2,
                    t1: u32::MAX,
                    same_way: false,
                }
            });
            s = e;
        }
        Self {
            normals,
            offsets,
            norms,
            edges,
        }
    }
}

/// The map of a mesh seen from one point ([module docs](self)).
#[derive(Clone, Debug)]
pub struct MeshView {
    p: DVec3,
    axis: DVec3,
    e1: DVec3,
    e2: DVec3,
    /// Half width of the square \[tan\] and cells per unit of tan.
    w: f64,
    inv_cell: f64,
    /// Squared distance \[m^2\] within which a segment from `p` ends
    /// before the ball.
    near2: f64,
    /// Half the largest `|x|_inf + |x - p|` \[m\] of a segment end `x` the
    /// map answers for (see [`Self::classify`]).
    half_limit: f64,
    /// The ball holding the mesh (grown by the margin): centre \[m\] and
    /// radius \[m\].
    c: DVec3,
    r: f64,
    cells: Box<[u8]>,
}

impl MeshView {
    /// The map of `mesh` (its `edges`) from `p`; `None` where `p` is not
    /// outside the mesh's bounding ball by the margin, or where the map's
    /// edge cells would be at least as many as its inside cells (it would
    /// leave most tests to the BVH and only add its lookup).
    pub fn build(mesh: &Mesh, edges: &MeshEdges, p: DVec3) -> Option<Self> {
        let (c, reach) = mesh.bounding_ball();
        let (lo, hi) = mesh.bounds();
        let scale = p.abs().max(lo.abs()).max(hi.abs()).max_element();
        let r = reach * (1.0 + PAD_REL) + PAD_REL * scale;
        let dist = (c - p).length();
        // (NaN fails the comparison: no map.)
        let clear = dist - r > END_REL * dist;
        if !clear || !r.is_finite() {
            return None;
        }
        let axis = (c - p) / dist;
        let (e1, e2) = axis.any_orthonormal_pair();
        let sin = r / dist;
        let w = sin / (1.0 - sin * sin).sqrt() * (1.0 + PAD_REL);
        // The rounding of a projected direction, in units of tan: a few
        // ulp of the coordinates over the distance, times the projection's
        // stretch (at most 1 + W^2).
        let pad = PAD_REL * (1.0 + scale / (dist - r)) * (1.0 + w * w);
        let cell = 2.0 * w / CELLS as f64;
        let mut cells = vec![UNKNOWN; CELLS * CELLS].into_boxed_slice();
        let vtx = mesh.vertices();
        // Each triangle's side as seen from p (the orientation of its
        // projection): positive, negative or 0 within the tolerance
        // (`EDGE_ON_REL` of the distance plus the scale: every corner lies
        // within `dist + r` of p), far above the rounding of `n . a - n . p`.
        let k = EDGE_ON_REL * (dist + r + scale);
        let side: Vec<i8> = edges
            .normals
            .iter()
            .zip(&edges.offsets)
            .zip(&edges.norms)
            .map(|((n, d), m)| {
                let s = d - n.dot(p);
                let tol = k * m;
                if s > tol {
                    1
                } else if s < -tol {
                    -1
                } else {
                    0
                }
            })
            .collect();
        let project = |q: DVec3| {
            let d = q - p;
            let t = d.dot(axis);
            (d.dot(e1) / t, d.dot(e2) / t)
        };
        for e in &edges.edges {
            let outline = e.t1 == u32::MAX || {
                let (s0, s1) = (side[e.t0 as usize], side[e.t1 as usize]);
                // Opposite sides of the edge: the same orientation for
                // triangles that run it opposite ways (consistent
                // winding), opposite orientations for the same way.
                s0 == 0 || s1 == 0 || (s0 == s1) == e.same_way
            };
            if outline {
                let a = project(vtx[e.a as usize]);
                let b = project(vtx[e.b as usize]);
                draw_segment(&mut cells, a, b, w, cell, pad);
            }
        }
        // The groups of unmarked cells, each classified by one exact ray.
        let t_max = 2.0 * (dist + r);
        let mut stack = Vec::new();
        for start in 0..cells.len() {
            if cells[start] != UNKNOWN {
                continue;
            }
            let (i, j) = (start % CELLS, start / CELLS);
            let u = -w + (i as f64 + 0.5) * cell;
            let v = -w + (j as f64 + 0.5) * cell;
            let d = axis + u * e1 + v * e2;
            let class = if mesh.segment_blocked(p, d, 0.0, t_max, Ends::default()) {
                INSIDE
            } else {
                OPEN
            };
            cells[start] = class;
            stack.push(start);
            while let Some(k) = stack.pop() {
                let (i, j) = (k % CELLS, k / CELLS);
                let mut visit = |k: usize| {
                    if cells[k] == UNKNOWN {
                        cells[k] = class;
                        stack.push(k);
                    }
                };
                if i > 0 {
                    visit(k - 1);
                }
                if i + 1 < CELLS {
                    visit(k + 1);
                }
                if j > 0 {
                    visit(k - CELLS);
                }
                if j + 1 < CELLS {
                    visit(k + CELLS);
                }
            }
        }
        // A map mostly left to the exact test would only add its lookup
        // to every test: kept where its inside cells outnumber its edge
        // cells (a double-sided sheet, every edge a silhouette, or a mesh
        // of T-junctions, every edge a border, is not).
        let [_, inside, edge] = class_counts(&cells);
        if edge >= inside {
            return None;
        }
        let near = dist - r;
        Some(Self {
            p,
            axis,
            e1,
            e2,
            w,
            inv_cell: 1.0 / cell,
            near2: near * near,
            half_limit: 0.5 * LIMIT_REL * (near + scale),
            c,
            r,
            cells,
        })
    }

    /// What the map says of the segment from its point to `x` \[m\].
    #[inline]
    pub fn classify(&self, x: DVec3) -> Seen {
        let d = x - self.p;
        let l2 = d.length_squared();
        if l2 < self.near2 {
            return Seen::Open;
        }
        // An end so far away (or so far from the origin) that the exact
        // test's rounding, a few ulp of its coordinates and of the length,
        // could pass the map's margin as seen from p: left to that test.
        let h = self.half_limit;
        if x.abs().max_element() > h || l2 > h * h {
            return Seen::Test;
        }
        let t = d.dot(self.axis);
        if t.is_nan() || t <= 0.0 {
            return Seen::Test;
        }
        let u = d.dot(self.e1) / t + self.w;
        let v = d.dot(self.e2) / t + self.w;
        let side = 2.0 * self.w;
        if !(u >= 0.0 && v >= 0.0) || u >= side || v >= side {
            // Outside the square: outside the cone round the ball (NaN
            // cannot come here: d is finite and t > 0).
            return Seen::Open;
        }
        let i = ((u * self.inv_cell) as usize).min(CELLS - 1);
        let j = ((v * self.inv_cell) as usize).min(CELLS - 1);
        match self.cells[j * CELLS + i] {
            OPEN => Seen::Open,
            INSIDE => {
                // Past the ball along the ray (out of it, and on the far
                // side of its centre's foot), by the margin.
                let e = x - self.c;
                let beyond = self.r + END_REL * l2.sqrt();
                if d.dot(e) > 0.0 && e.length_squared() > beyond * beyond {
                    Seen::Blocked
                } else {
                    Seen::Test
                }
            }
            _ => Seen::Test,
        }
    }

    /// Shares of the map's cells that are open, inside and left to the
    /// exact test.
    #[cfg(test)]
    fn shares(&self) -> [f64; 3] {
        class_counts(&self.cells).map(|k| k as f64 / self.cells.len() as f64)
    }
}

/// How many of `cells` are open, inside and edge cells.
fn class_counts(cells: &[u8]) -> [usize; 3] {
    let mut n = [0usize; 3];
    for &c in cells {
        n[usize::from(c.min(EDGE))] += 1;
    }
    n
}

/// Mark `EDGE` every cell whose box, grown by `pad`, meets the segment from
/// `a` to `b` (projected coordinates; the square `[-w, w]^2` of `cell`-wide
/// cells): the overlap of the boxes, then the segment's own axis.
fn draw_segment(cells: &mut [u8], a: (f64, f64), b: (f64, f64), w: f64, cell: f64, pad: f64) {
    let index = |x: f64| ((x + w) / cell).floor();
    let range = |lo: f64, hi: f64| {
        let i0 = index(lo - pad).max(0.0);
        let i1 = index(hi + pad).min((CELLS - 1) as f64);
        (i0 as usize, i1 as usize, i0 <= i1)
    };
    let (i0, i1, ok_i) = range(a.0.min(b.0), a.0.max(b.0));
    let (j0, j1, ok_j) = range(a.1.min(b.1), a.1.max(b.1));
    if !ok_i || !ok_j {
        return;
    }
    // The segment's normal; a cell's grown box meets the line where
    // |n . (centre - a)| <= h (|n.x| + |n.y|), h its half width.
    let (nx, ny) = (a.1 - b.1, b.0 - a.0);
    let h = 0.5 * cell + pad;
    let reach = h * (nx.abs() + ny.abs());
    for j in j0..=j1 {
        let cy = -w + (j as f64 + 0.5) * cell;
        for i in i0..=i1 {
            let cx = -w + (i as f64 + 0.5) * cell;
            // (A degenerate segment, a point: n = 0, every cell of its
            // grown box is marked.)
            if (nx * (cx - a.0) + ny * (cy - a.1)).abs() <= reach * (1.0 + 1e-12) {
                cells[j * CELLS + i] = EDGE;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mesh::star_blob;

    /// A closed blob: every edge joins two triangles that run it opposite
    /// ways (3 T / 2 edges); no map from inside its ball; from outside, a
    /// map whose inside share is about the blob's disc in the square, and
    /// whose answers are the exact test's along rays through cell centres.
    #[test]
    fn a_blob_seen_from_outside() {
        let m = star_blob(24, 48, |_, _| 1.0).unwrap();
        let e = MeshEdges::new(&m);
        assert_eq!(2 * e.edges.len(), 3 * m.triangle_count());
        assert!(e.edges.iter().all(|e| e.t1 != u32::MAX && !e.same_way));
        assert!(MeshView::build(&m, &e, DVec3::new(0.5, 0.0, 0.0)).is_none());
        assert!(MeshView::build(&m, &e, DVec3::new(1.0 + 1e-9, 0.0, 0.0)).is_none());
        let p = DVec3::new(3.0, 1.0, -0.5);
        let v = MeshView::build(&m, &e, p).unwrap();
        let [open, inside, edge] = v.shares();
        // The unit sphere from distance sqrt(10.25) fills a disc of
        // tan^2 = 1 / 9.25 in a square of side 2 W, W^2 about the same.
        let disc = std::f64::consts::PI / 4.0;
        assert!(
            inside > 0.6 * disc && inside + edge > disc,
            "{inside} {edge}"
        );
        assert!(edge < 0.12 && open > 0.1, "{open} {inside} {edge}");
        let mut seen = [0; 3];
        for j in 0..CELLS {
            for i in 0..CELLS {
                let u = -v.w + (i as f64 + 0.5) / v.inv_cell;
                let w = -v.w + (j as f64 + 0.5) / v.inv_cell;
                let d = v.axis + u * v.e1 + w * v.e2;
                let x = p + 10.0 * d;
                let hit = m.segment_blocked(p, d, 0.0, 10.0, Ends::default());
                match v.classify(x) {
                    Seen::Open => {
                        assert!(!hit, "{i} {j}");
                        seen[0] += 1;
                    }
                    Seen::Blocked => {
                        assert!(hit, "{i} {j}");
                        seen[1] += 1;
                    }
                    Seen::Test => seen[2] += 1,
                }
            }
        }
        assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");
    }

    /// A wavy sheet gets a map; the same sheet written twice, front and
    /// back (every edge then a silhouette), gets none: it would leave
    /// every test to the BVH.
    #[test]
    fn a_map_that_would_answer_little_is_not_kept() {
        let n = 30u32;
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
                v.push(DVec3::new(x, y, 0.1 * (6.0 * x).sin()));
            }
        }
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let k = j * (n + 1) + i;
                t.push([k, k + 1, k + n + 2]);
                t.push([k, k + n + 2, k + n + 1]);
            }
        }
        let p = DVec3::new(0.4, 0.6, 3.0);
        let one = Mesh::from_triangles(v.clone(), t.clone()).unwrap();
        assert!(MeshView::build(&one, &MeshEdges::new(&one), p).is_some());
        let back: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let both = Mesh::from_triangles(v, [t, back].concat()).unwrap();
        assert!(MeshView::build(&both, &MeshEdges::new(&both), p).is_none());
    }
}
