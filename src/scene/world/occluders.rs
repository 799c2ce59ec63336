//! Per-receiver occluder lists: which finite shapes can possibly shadow a
//! segment from a collision on a given set of surfaces to one receiver,
//! and cheap tests that rule a shape out for one segment before its exact
//! test (issue 15, fast rooms).
//!
//! The local estimate tests, at every collision, the segment to every
//! receiver against every finite shape (or the shape BVH). In a furnished
//! room most of those tests cannot succeed: a desk below a work-plane
//! point, a cabinet on the far side, a whiteboard behind. Per receiver `p`
//! and per receiver list (the surfaces whose collisions may score into it,
//! all in a box `R`), a shape `B` stays a candidate only if
//!
//! - it is not wholly behind the receiver's tangent plane (a planar or
//!   luminance receiver scores only collisions strictly in front of it, so
//!   the open segment lies strictly in front), and
//! - its box meets the convex hull of `R` and `p`: every segment from a
//!   point of `R` to `p` lies in that hull, which is the union of the boxes
//!   `p + t (R - p)`, `t` in `[0, 1]`; each axis bounds `t` by two linear
//!   inequalities, so the test is exact for the boxes.
//!
//! Per segment, a candidate is then skipped by a separating plane `m . y =
//! h` with the shape in `m . y <= h` and the receiver in `m . y >= h`
//! (a collision with `m . x > h` gives a segment strictly beyond it): a box
//! face the receiver lies on or beyond (exact coordinates, so a point on a
//! desk top is never tested against the desk), the plane of a flat shape,
//! or a face of a curved shape's box; and by the cone from `p` round the
//! shape's bounding sphere (direction and nearest distance). Only then
//! the shape's own test runs, the one [`Scene::blocked_by_shapes`] runs,
//! so a segment's visibility is the same bit for bit: every skip above
//! rules out a hit by a margin (a relative `1e-9` of the scene's
//! coordinates, the shapes' boxes padded as in the shape tree) far above
//! the rounding of the shapes' own tests.

use super::shape_tree::{padded, prim_bounds};
use super::{Prim, Scene, ShapeRef, segment};
use crate::geometry::mesh_view::{MeshView, Seen};
use crate::geometry::segment_meets_box;
use crate::geometry::shapes::EDGE_REL;
use glam::DVec3;
use std::sync::Arc;

/// Relative margin of every skip (of the largest coordinate magnitude of
/// the receiver, the shape and the region).
const SLACK_REL: f64 = 1e-9;

/// One finite shape that may shadow segments ending at one receiver, with
/// the tests that rule it out for a segment (module docs).
#[derive(Clone, Debug)]
pub struct Occluder {
    prim: Prim,
    /// Separating plane: skip when `m . x > h` (`m = 0`: never).
    m: DVec3,
    h: f64,
    /// Cone round the bounding sphere from the receiver: unit axis, the
    /// squared cosine of the half-angle (negative: no cone, the receiver
    /// is inside the sphere or the cone is a half-space or wider) and the
    /// squared nearest distance [m^2].
    axis: DVec3,
    cos2: f64,
    near2: f64,
    /// A rectangle's pyramid from the receiver: inward normals of the four
    /// planes through the receiver and the (grown) edges; a segment
    /// crosses the rectangle only with `w . m_i >= 0` for all four (`w`
    /// towards the collision). `None` for other shapes. (Boxed: it is
    /// read only past the other tests, and the list stays compact.)
    pyramid: Option<Box<[DVec3; 4]>>,
    /// Shapes other than rectangles (discs included): the receiver
    /// relative to the centre of the grown box, and the box's half extents,
    /// for the separating-axis test of the segment against the box.
    rel: DVec3,
    half: DVec3,
    /// A large mesh's map from the receiver ([`MeshView`]): most segments
    /// it answers without the BVH, with the exact test's answer.
    view: Option<Arc<MeshView>>,
}

impl Occluder {
    /// The mesh this occluder is (its index among the scene's meshes).
    pub fn mesh(&self) -> Option<u32> {
        match self.prim {
            Prim::Mesh(i) => Some(i),
            _ => None,
        }
    }

    /// Answer this mesh occluder's segments from `view`, its map from the
    /// receiver whose list holds it.
    pub fn set_view(&mut self, view: Arc<MeshView>) {
        debug_assert!(self.mesh().is_some());
        self.view = Some(view);
    }
}

impl Scene {
    /// Whether the local estimate's scoring uses occluder lists: scenes
    /// with finite shapes on loops (without the shape tree, which already
    /// costs `log n` per segment).
    pub fn uses_occluder_lists(&self) -> bool {
        !self.planes_only() && self.tree.is_none()
    }

    /// The box \[m\] holding surface `s` (a box face: that face alone);
    /// `None` for an infinite plane (unbounded) and a glass pane (never a
    /// collision site).
    pub fn surface_bounds(&self, s: u32) -> Option<(DVec3, DVec3)> {
        let prim = match self.surfaces[s as usize].shape {
            ShapeRef::Plane(_) | ShapeRef::Pane(_) => return None,
            ShapeRef::BoxFace(i, f) => {
                let b = &self.boxes[i as usize].0;
                let (mut lo, mut hi) = (b.lo, b.hi);
                let a = f as usize / 2;
                let c = if f % 2 == 1 { b.hi[a] } else { b.lo[a] };
                (lo[a], hi[a]) = (c, c);
                return Some(padded((lo, hi)));
            }
            ShapeRef::Rect(i) => Prim::Rect(i),
            ShapeRef::Disc(i) => Prim::Disc(i),
            ShapeRef::Sphere(i) => Prim::Sphere(i),
            ShapeRef::Mesh(i) => Prim::Mesh(i),
            ShapeRef::Sh(i) => Prim::Sh(i),
        };
        Some(padded(prim_bounds(self, prim)))
    }

    /// The occluders of a receiver at `p` for collisions within `region`
    /// (`None`: anywhere), in the order of [`Scene::blocked_by_shapes`]'s
    /// loops. `front`: the unit normal of a receiver that scores only
    /// collisions strictly in front of it (`None` for a solid receiver).
    pub fn occluders(
        &self,
        p: DVec3,
        front: Option<DVec3>,
        region: Option<(DVec3, DVec3)>,
    ) -> Vec<Occluder> {
        let mut out = Vec::new();
        for prim in self.finite_prims() {
            if self.holds_both(prim, p, region) {
                continue;
            }
            let (lo, hi) = padded(prim_bounds(self, prim));
            let mut scale = p.abs().max(lo.abs()).max(hi.abs()).max_element();
            if let Some((rlo, rhi)) = region {
                scale = scale.max(rlo.abs().max(rhi.abs()).max_element());
            }
            let slack = SLACK_REL * scale;
            let (lo, hi) = (lo - DVec3::splat(slack), hi + DVec3::splat(slack));
            // Wholly behind the receiver's tangent plane: a solid box whose
            // face the receiver lies on or beyond, facing the same way
            // (exact coordinates: a point on a desk top and the desk), or
            // any shape's grown box by the margin.
            if let (Some(n), Prim::Box(i)) = (front, prim) {
                let b = &self.boxes[i as usize].0;
                let behind = (0..3).any(|a| {
                    let mut e = DVec3::ZERO;
                    e[a] = 1.0;
                    (n == e && p[a] >= b.hi[a]) || (n == -e && p[a] <= b.lo[a])
                });
                if behind {
                    continue;
                }
            }
            if let Some(n) = front {
                // (Box corners are finite, checked at compile: the fold
                // drops no NaN.)
                let far = corners(lo, hi)
                    .iter()
                    .map(|&c| n.dot(c - p))
                    .fold(f64::NEG_INFINITY, f64::max);
                if far < -slack {
                    continue;
                }
            }
            if let Some((rlo, rhi)) = region
                && !hull_meets_box(
                    p,
                    rlo - DVec3::splat(slack),
                    rhi + DVec3::splat(slack),
                    lo,
                    hi,
                )
            {
                continue;
            }
            let (m, h) = self.separating_plane(prim, p, lo, hi, slack);
            // The cone round the bounding sphere of the grown box (a mesh:
            // the ball round its corners, grown by the box's padding and
            // the margin, when that is smaller).
            let c = 0.5 * (lo + hi);
            let mut r = 0.5 * (hi - lo).length() + slack;
            if let Prim::Mesh(i) = prim {
                let (mc, reach) = self.meshes[i as usize].0.bounding_ball();
                let grow = (hi - lo).max_element() * 1e-9 + 2.0 * slack;
                let ball = reach + (mc - c).length() + grow;
                r = r.min(ball);
            }
            let v = c - p;
            let dist = v.length();
            let (axis, cos2, near2) = if dist > r {
                let s = r / dist;
                let cos = (1.0 - s * s).sqrt() - SLACK_REL;
                let near = dist - r;
                (
                    v / dist,
                    if cos > 0.0 { cos * cos } else { -1.0 },
                    near * near,
                )
            } else {
                (DVec3::ZERO, -1.0, 0.0)
            };
            // A flat shape never blocks a receiver in its plane (the exact
            // test needs the end points strictly on opposite sides).
            let flat = self.flat_plane(prim);
            if flat.is_some_and(|pl| pl.side(p) == 0) {
                continue;
            }
            // Nor collisions on its own plane (the region within the
            // plane's tolerance at every point of it: the signed distance
            // is linear, the tolerance at least `ON_PLANE_REL |plane.p|`).
            if let (Some(pl), Some((rlo, rhi))) = (flat, region) {
                let tol = crate::geometry::ON_PLANE_REL * pl.p.abs().max_element();
                let on = corners(rlo, rhi)
                    .iter()
                    .all(|&c| pl.signed_distance(c).abs() <= tol);
                if on {
                    continue;
                }
            }
            let pyramid = match prim {
                Prim::Rect(i) => Some(Box::new(rect_pyramid(&self.rects[i as usize].0, p, slack))),
                _ => None,
            };
            out.push(Occluder {
                prim,
                m,
                h,
                axis,
                cos2,
                near2,
                pyramid,
                rel: p - c,
                half: 0.5 * (hi - lo),
                view: None,
            });
        }
        out
    }

    /// Whether `prim` is a sphere or box that holds the receiver `p` and
    /// every point of `region` (inside or on, by the shape's own
    /// classification): a segment between two such points never crosses
    /// its surface (the room a receiver stands in).
    fn holds_both(&self, prim: Prim, p: DVec3, region: Option<(DVec3, DVec3)>) -> bool {
        use crate::geometry::shapes::Inside;
        let Some((lo, hi)) = region else {
            return false;
        };
        let classify = |q: DVec3| match prim {
            Prim::Sphere(i) => self.spheres[i as usize].0.classify(q),
            Prim::Box(i) => self.boxes[i as usize].0.classify(q),
            _ => Inside::Out,
        };
        // The region's corners: the shapes are convex, so they hold the
        // whole box when they hold its corners.
        classify(p) != Inside::Out && corners(lo, hi).iter().all(|&c| classify(c) != Inside::Out)
    }

    /// A plane with `prim` on its `m . y <= h` side and `p` on the other
    /// (or on it); `(0, 0)` when there is none. `lo, hi`: the shape's
    /// grown box.
    fn separating_plane(
        &self,
        prim: Prim,
        p: DVec3,
        lo: DVec3,
        hi: DVec3,
        slack: f64,
    ) -> (DVec3, f64) {
        // A flat shape: its own plane, from the receiver's side (a segment
        // that stays on one side never crosses it), unless the receiver
        // lies within the margin of that plane.
        let flat = self.flat_plane(prim);
        if let Some(pl) = flat {
            let s = pl.signed_distance(p);
            if s.abs() > slack {
                let m = if s > 0.0 { pl.n } else { -pl.n };
                return (m, m.dot(pl.p) + slack);
            }
            return (DVec3::ZERO, 0.0);
        }
        // A box face the receiver lies on or beyond: the exact faces of a
        // solid box (axis-aligned, so `m . x` is a coordinate, exact),
        // else the faces of the grown box.
        let (blo, bhi) = match prim {
            Prim::Box(i) => {
                let b = &self.boxes[i as usize].0;
                (b.lo, b.hi)
            }
            _ => (lo, hi),
        };
        let mut best = (DVec3::ZERO, 0.0, f64::NEG_INFINITY);
        for a in 0..3 {
            let mut e = DVec3::ZERO;
            e[a] = 1.0;
            for (m, h, out) in [(e, bhi[a], p[a] - bhi[a]), (-e, -blo[a], blo[a] - p[a])] {
                if out >= 0.0 && out > best.2 {
                    best = (m, h, out);
                }
            }
        }
        if best.2 >= 0.0 {
            (best.0, best.1)
        } else {
            (DVec3::ZERO, 0.0)
        }
    }

    /// Whether a shape among `occ` (from [`Self::occluders`] for the
    /// receiver `b`) blocks the open segment from the collision `a` (on
    /// `from`) to `b`: the same answer as [`Self::blocked_by_shapes`] for
    /// collisions in the region and in front of the receiver the list was
    /// made for. `l2 = |a - b|^2`. No square root unless a shape's own
    /// test runs: the cone test squared (`w . axis >= cos |w|` for a cone
    /// narrower than a half-space).
    #[inline(always)]
    pub fn blocked_by_occluders(
        &self,
        a: DVec3,
        from: Option<(u32, u32)>,
        b: DVec3,
        inside_both: u64,
        occ: &[Occluder],
        l2: f64,
    ) -> bool {
        let w = a - b;
        for o in occ {
            if o.m.dot(a) > o.h || l2 < o.near2 {
                continue;
            }
            if o.cos2 >= 0.0 {
                let t = w.dot(o.axis);
                if t < 0.0 || t * t < o.cos2 * l2 {
                    continue;
                }
            }
            match &o.pyramid {
                Some(pm) => {
                    if pm.iter().any(|m| w.dot(*m) < 0.0) {
                        continue;
                    }
                }
                None => {
                    if segment_misses_box(o.rel, w, o.half) {
                        continue;
                    }
                }
            }
            if let Some(v) = &o.view {
                match v.classify(a) {
                    Seen::Open => continue,
                    Seen::Blocked => return true,
                    Seen::Test => {}
                }
            }
            if self.exact_blocks(o.prim, a, from, b, inside_both) {
                return true;
            }
        }
        false
    }

    /// Mesh `i` of the scene.
    pub fn mesh(&self, i: u32) -> &crate::geometry::mesh::Mesh {
        &self.meshes[i as usize].0
    }

    /// The supporting plane of a rectangle or disc; `None` for other shapes.
    fn flat_plane(&self, prim: Prim) -> Option<crate::geometry::Plane> {
        match prim {
            Prim::Rect(i) => Some(self.rects[i as usize].0.plane),
            Prim::Disc(i) => Some(self.discs[i as usize].0.plane),
            _ => None,
        }
    }

    /// Whether `o` is a rectangle or disc whose plane is `support` (the
    /// same normal and offset, either way round; a receiver list's support
    /// plane): it never blocks a segment from a collision on that list's
    /// surfaces, which lie on its plane (its test needs the ends strictly
    /// on opposite sides).
    pub fn flat_in_plane(&self, o: &Occluder, support: crate::geometry::Plane) -> bool {
        let Some(pl) = self.flat_plane(o.prim) else {
            return false;
        };
        (pl.n == support.n && pl.c == support.c) || (pl.n == -support.n && pl.c == -support.c)
    }

    /// [`Self::blocked_by_occluders`] for a collision in a visibility cell
    /// ([`Self::cell_visibility`]): only the occluders whose bits `mask`
    /// sets (bit [`CELL_REST`] for every occluder from that index on), and
    /// blocked outright for [`CELL_DARK`]. The same answer as the whole
    /// list for collisions in the cell.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn blocked_in_cell(
        &self,
        a: DVec3,
        from: Option<(u32, u32)>,
        b: DVec3,
        inside_both: u64,
        occ: &[Occluder],
        mask: u64,
        l2: f64,
    ) -> bool {
        if mask == CELL_DARK {
            return true;
        }
        let mut m = mask;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            let some = if i == CELL_REST as usize {
                &occ[i.min(occ.len())..]
            } else {
                &occ[i..i + 1]
            };
            if self.blocked_by_occluders(a, from, b, inside_both, some, l2) {
                return true;
            }
        }
        false
    }

    /// Which of `occ` (the occluders of a receiver at `p`, from
    /// [`Self::occluders`]) can shadow a segment from a point of the box
    /// `cell` to `p`: bit `i` for occluder `i` (`i <` [`CELL_REST`]), bit
    /// `CELL_REST` for any from that index on, set when the occluder's
    /// grown box meets the hull of the grown cell and `p` and it is not a
    /// box or sphere holding both (the region tests of [`Self::occluders`]
    /// on a smaller region) nor a box the cell lies on the face plane of
    /// ([`Self::box_face_holds_cell`]); [`CELL_DARK`] when a
    /// solid box provably blocks every such segment
    /// ([`Self::box_shadows_cell`]).
    pub fn cell_visibility(&self, p: DVec3, occ: &[Occluder], (clo, chi): (DVec3, DVec3)) -> u64 {
        let mut mask = 0u64;
        for (i, o) in occ.iter().enumerate() {
            let (lo, hi) = padded(prim_bounds(self, o.prim));
            let scale = p
                .abs()
                .max(lo.abs())
                .max(hi.abs())
                .max(clo.abs())
                .max(chi.abs())
                .max_element();
            let g = DVec3::splat(SLACK_REL * scale);
            if !hull_meets_box(p, clo - g, chi + g, lo - g, hi + g)
                || self.holds_both(o.prim, p, Some((clo - g, chi + g)))
            {
                continue;
            }
            if let Prim::Box(b) = o.prim
                && self.box_face_holds_cell(b, p, (clo, chi))
            {
                continue;
            }
            let grown = (clo - g, chi + g);
            let dark = match o.prim {
                Prim::Box(b) => self.box_shadows_cell(b, p, grown, scale),
                Prim::Rect(_) | Prim::Disc(_) => self.flat_shadows_cell(o.prim, p, grown, scale),
                Prim::Mesh(i) => self.core_shadows_cell(i, p, grown, scale),
                _ => false,
            };
            if dark {
                return CELL_DARK;
            }
            mask |= 1 << (i as u32).min(CELL_REST);
        }
        mask
    }

    /// Whether the rectangle or disc `prim` crosses every segment from a
    /// point of the box `cell` to `p`, with the margin `m = 1e-7 scale` of
    /// [`Self::box_shadows_cell`]: `p` lies more than `m` from its plane,
    /// the cell's eight corners more than `m` on the other side, and the
    /// segment from `p` to each corner crosses the plane inside the shape
    /// shrunk by a relative `1e-7` (`u, v` of a rectangle in `[1e-7,
    /// 1 - 1e-7]`, a disc's radius times `1 - 1e-7`). The same convexity
    /// argument gives every segment from the cell a point of the shrunk
    /// shape, its one crossing of the plane; the shape's test (ends
    /// strictly on opposite sides, the crossing point inside, both far
    /// beyond its tolerances) then finds it.
    fn flat_shadows_cell(
        &self,
        prim: Prim,
        p: DVec3,
        (clo, chi): (DVec3, DVec3),
        scale: f64,
    ) -> bool {
        const SHRINK: f64 = 1e-7;
        let m = 1e-7 * scale;
        let Some(pl) = self.flat_plane(prim) else {
            return false;
        };
        let sp = pl.signed_distance(p);
        if sp.abs() <= m {
            return false;
        }
        corners(clo, chi).iter().all(|&c| {
            let sc = pl.signed_distance(c);
            if sc * sp.signum() >= -m {
                return false;
            }
            let y = p + (c - p) * (sp / (sp - sc));
            match prim {
                Prim::Rect(i) => {
                    let (u, v) = self.rects[i as usize].0.uv(y);
                    (SHRINK..=1.0 - SHRINK).contains(&u) && (SHRINK..=1.0 - SHRINK).contains(&v)
                }
                Prim::Disc(i) => {
                    let d = &self.discs[i as usize].0;
                    let r = d.r * (1.0 - SHRINK);
                    (y - d.plane.p).length_squared() <= r * r
                }
                _ => false,
            }
        })
    }

    /// Whether the box `b` never crosses a segment from a point of the
    /// (ungrown) `cell` to `p` because the cell lies on the plane of one of
    /// its faces, or beyond it, to within a quarter of the box's own
    /// tolerance, and `p` on or beyond that plane (collisions on the box's
    /// own face, or on a face in the same plane, such as the other desk
    /// top): every point of such a segment lies outside the box shrunk by
    /// its tolerance along that axis, so its test (an `On` or `Out` end,
    /// then the slab test of the shrunk box) finds no crossing.
    fn box_face_holds_cell(&self, b: u32, p: DVec3, (clo, chi): (DVec3, DVec3)) -> bool {
        let bx = &self.boxes[b as usize].0;
        let q = 0.25 * bx.tolerance();
        (0..3).any(|a| {
            (clo[a] >= bx.hi[a] - q && p[a] >= bx.hi[a])
                || (chi[a] <= bx.lo[a] + q && p[a] <= bx.lo[a])
        })
    }

    /// Whether the solid box `b` crosses every segment from a point of the
    /// box `cell` to `p`, with a margin `m = 1e-7 scale` far above the
    /// rounding of [`crate::geometry::shapes::AaBox::crosses`]: `p` and the
    /// cell lie outside the box grown by `m` (both ends classify `Out`, so
    /// the box test is its slab test), and the segment from `p` to each of
    /// the cell's eight corners meets the box shrunk by `m`, `S`. The set
    /// of points `q` whose segment from `p` meets a convex `S` is convex
    /// (with `b_i = p + s_i (q_i - p)` in `S`, `s_i` in `[0, 1]`, the
    /// segment to a convex combination `sum l_i q_i` passes through
    /// `sum l_i t / s_i b_i`, `t = 1 / sum (l_i / s_i)` in `(0, 1]`), so it
    /// holds the cell, the corners' hull: every segment from the cell
    /// passes through a point at least `m` inside the box.
    fn box_shadows_cell(&self, b: u32, p: DVec3, (clo, chi): (DVec3, DVec3), scale: f64) -> bool {
        let bx = &self.boxes[b as usize].0;
        let m = 1e-7 * scale;
        let (slo, shi) = (bx.lo + DVec3::splat(m), bx.hi - DVec3::splat(m));
        if (shi - slo).min_element() <= 0.0 {
            return false;
        }
        let p_out = (bx.lo - p).max(p - bx.hi).max_element() > m;
        let cell_out = (bx.lo - chi).max(clo - bx.hi).max_element() > m;
        p_out
            && cell_out
            && corners(clo, chi)
                .iter()
                .all(|&c| segment_meets_box(p, c, slo, shi))
    }

    /// Whether mesh `i`'s core ([`crate::geometry::mesh_core`]) proves
    /// every segment from a point of the box `cell` to `p` blocked by the
    /// mesh, as its shape test ([`Self::blocks`]) finds pair by pair: `p`
    /// outside the mesh's bounds by more than the core's gap, the shadow
    /// ray's end margin (`MESH_REL` of the longest such segment, which ends
    /// at a corner) within the core's rule for it (`Core::margin_fits`,
    /// the one [`Self::blocks`] applies), and every such segment through the core
    /// shrunk by `m = 1e-7 scale` (the corners decide, as in
    /// [`Self::box_shadows_cell`]).
    fn core_shadows_cell(&self, i: u32, p: DVec3, (clo, chi): (DVec3, DVec3), scale: f64) -> bool {
        let mesh = &self.meshes[i as usize].0;
        let Some(core) = mesh.core() else {
            return false;
        };
        let (lo, hi) = mesh.bounds();
        let m = 1e-7 * scale;
        let (slo, shi) = (core.lo + DVec3::splat(m), core.hi - DVec3::splat(m));
        if (shi - slo).min_element() <= 0.0 {
            return false;
        }
        let cs = corners(clo, chi);
        // (NaN-propagating, so that a NaN corner never passes.)
        let far = cs
            .iter()
            .map(|c| (*c - p).length())
            .fold(0.0, |m: f64, d| if d.is_nan() || d > m { d } else { m });
        (lo - p).max(p - hi).max_element() > core.gap
            && core.margin_fits(super::MESH_REL * far)
            && cs.iter().all(|&c| segment_meets_box(p, c, slo, shi))
    }

    /// The shape's own test of the open segment `a b` (out of line; the
    /// segment's direction and length computed only for the shapes whose
    /// tests take them, meshes and SH objects).
    #[inline(never)]
    fn exact_blocks(
        &self,
        prim: Prim,
        a: DVec3,
        from: Option<(u32, u32)>,
        b: DVec3,
        inside_both: u64,
    ) -> bool {
        match prim {
            Prim::Mesh(_) | Prim::Sh(_) => {
                segment(a, b).is_some_and(|s| self.blocks(prim, a, from, b, s, inside_both))
            }
            // (Their tests take the end points alone.)
            _ => {
                (b - a).length_squared() > 0.0
                    && self.blocks(prim, a, from, b, (DVec3::ZERO, 0.0), inside_both)
            }
        }
    }
}

/// The mask of [`Scene::cell_visibility`] for a cell that one solid box
/// shadows wholly from the receiver.
pub const CELL_DARK: u64 = u64::MAX;

/// The bit of [`Scene::cell_visibility`]'s mask that stands for every
/// occluder from this index on.
pub const CELL_REST: u32 = 62;

/// The eight corners of the box `[lo, hi]`.
fn corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|k| {
        DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// Whether the segment from `r` to `r + w` (relative to a box's centre)
/// misses the box of half extents `e`: the separating-axis test on the
/// box's three axes and their cross products with the segment (no
/// division). The box is the grown one, so a miss rules out a hit.
#[inline(always)]
fn segment_misses_box(r: DVec3, w: DVec3, e: DVec3) -> bool {
    let d = 0.5 * w;
    let m = r + d;
    let ad = d.abs();
    if m.x.abs() > e.x + ad.x || m.y.abs() > e.y + ad.y || m.z.abs() > e.z + ad.z {
        return true;
    }
    (m.y * d.z - m.z * d.y).abs() > e.y * ad.z + e.z * ad.y
        || (m.z * d.x - m.x * d.z).abs() > e.x * ad.z + e.z * ad.x
        || (m.x * d.y - m.y * d.x).abs() > e.x * ad.y + e.y * ad.x
}

/// The inward normals of the four planes through `p` and the edges of the
/// rectangle `r` grown by its edge extension ([`EDGE_REL`]) and `slack`
/// (module docs); zeros where `p` lies within the margin of its plane.
fn rect_pyramid(r: &crate::geometry::shapes::Rect, p: DVec3, slack: f64) -> [DVec3; 4] {
    let (l1, l2) = (r.e1.length(), r.e2.length());
    // Grow each edge by twice the extension and by the margin.
    let (g1, g2) = (2.0 * EDGE_REL + slack / l1, 2.0 * EDGE_REL + slack / l2);
    let o = r.o - r.e1 * g1 - r.e2 * g2;
    let (a, b) = (r.e1 * (1.0 + 2.0 * g1), r.e2 * (1.0 + 2.0 * g2));
    let c = [o, o + a, o + a + b, o + b];
    // A receiver (almost) in the rectangle's plane: no pyramid (zero
    // normals skip nothing; the box test takes over). The planes' normals
    // are cross products of nearly parallel vectors of length up to `L`
    // there, rounded by about `eps L^2 / edge` against a margin of `slack
    // s / L` (`s` the receiver's distance from the plane), so the pyramid
    // is kept only with a thousandfold safety, `s slack edge >= 1e3 eps
    // L^3`.
    let s = r.plane.signed_distance(p).abs();
    // (Finite corners and receiver, checked at load: the fold drops no NaN.)
    let l = c.iter().map(|&q| (q - p).length()).fold(0.0, f64::max);
    if s <= slack || s * slack * l1.min(l2) < 1e3 * f64::EPSILON * l * l * l {
        return [DVec3::ZERO; 4];
    }
    let centre = o + 0.5 * (a + b);
    let mut out = [DVec3::ZERO; 4];
    for k in 0..4 {
        let m = (c[k] - p).cross(c[(k + 1) % 4] - p);
        out[k] = if m.dot(centre - p) >= 0.0 { m } else { -m };
    }
    out
}

/// Whether the convex hull of the box `[rlo, rhi]` and the point `p` meets
/// the box `[lo, hi]`: some `t` in `[0, 1]` with `p + t (r - p)` in it for
/// every axis, i.e. the box `p + t ([rlo, rhi] - p)` overlapping `[lo, hi]`.
fn hull_meets_box(p: DVec3, rlo: DVec3, rhi: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for a in 0..3 {
        // The hull's interval along axis a at t: [p + t (rlo - p), p + t (rhi - p)];
        // it overlaps [lo, hi] when its low end <= hi and its high end >= lo.
        for (slope, bound, upper) in [
            (rlo[a] - p[a], hi[a] - p[a], true),
            (rhi[a] - p[a], lo[a] - p[a], false),
        ] {
            // upper: slope t <= bound; else slope t >= bound.
            let (s, b) = if upper {
                (slope, bound)
            } else {
                (-slope, -bound)
            };
            // s t <= b
            if s > 0.0 {
                t1 = t1.min(b / s);
            } else if s < 0.0 {
                t0 = t0.max(b / s);
            } else if b < 0.0 {
                return false;
            }
        }
    }
    t0 <= t1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The separating-axis test never misses a segment that enters the
    /// box (sampled points of the segment), and rejects most that do not.
    #[test]
    fn segment_box_test_is_conservative() {
        let mut rng = crate::sampling::Philox4x32::new(6, 0);
        let mut u = || rng.next_2d()[0] * 4.0 - 2.0;
        let (mut entered, mut missed, mut rejected) = (0, 0, 0);
        for _ in 0..20_000 {
            let r = DVec3::new(u(), u(), u());
            let w = DVec3::new(u(), u(), u()) * 1.5;
            let e = DVec3::new(u().abs(), u().abs(), u().abs()) * 0.4;
            let inside = (0..=200).any(|k| {
                let q = r + w * (k as f64 / 200.0);
                q.abs().cmple(e).all()
            });
            let miss = segment_misses_box(r, w, e);
            assert!(!(inside && miss), "{r} {w} {e}");
            entered += inside as usize;
            if !inside {
                missed += 1;
                rejected += miss as usize;
            }
        }
        assert!(entered > 500, "{entered}");
        // Exact for a box: all but the sampling's near misses rejected.
        assert!(
            rejected as f64 > 0.98 * missed as f64,
            "{rejected} of {missed}"
        );
    }

    #[test]
    fn hull_test_matches_sampling() {
        let mut rng = crate::sampling::Philox4x32::new(5, 0);
        let mut u = || rng.next_2d()[0] * 4.0 - 2.0;
        let mut met = [0usize; 2];
        for _ in 0..4000 {
            let p = DVec3::new(u(), u(), u());
            let (a, b) = (DVec3::new(u(), u(), u()), DVec3::new(u(), u(), u()));
            let (rlo, rhi) = (a.min(b), a.max(b));
            let (c, d) = (DVec3::new(u(), u(), u()), DVec3::new(u(), u(), u()));
            let (lo, hi) = (c.min(d) * 0.3, c.max(d) * 0.3);
            let got = hull_meets_box(p, rlo, rhi, lo, hi);
            // Sampled: points of the hull (t, corner mixes) inside the box.
            let inside = |q: DVec3| q.cmpge(lo).all() && q.cmple(hi).all();
            let mut seen = false;
            for i in 0..=40 {
                let t = i as f64 / 40.0;
                let (qlo, qhi) = (p + (rlo - p) * t, p + (rhi - p) * t);
                // The box at t overlaps [lo, hi]: its clamp of the centre.
                let q = (0.5 * (lo + hi)).clamp(qlo, qhi);
                if inside(q) {
                    seen = true;
                    break;
                }
            }
            // Sampling finds a subset of what the exact test finds.
            assert!(!seen || got, "{p} {rlo} {rhi} {lo} {hi}");
            met[got as usize] += 1;
        }
        assert!(met[0] > 200 && met[1] > 200, "{met:?}");
    }
}
