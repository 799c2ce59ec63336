//! The scene's top-level BVH: one leaf per finite shape (rectangle, disc,
//! sphere, box, mesh, SH object), so that the nearest-hit and visibility
//! queries cost `log n` in the number of shapes instead of `n`. A mesh is
//! one leaf with its own triangle BVH below it; an SH object one leaf with
//! its own march. Infinite planes stay outside (side masks, and a plane's
//! box would be the whole space).
//!
//! **Same answers as the loops.** The tree only decides which shapes a ray
//! or segment is tested against; every test is the shape's own, the one
//! the linear loops call. The leaf boxes hold everything a shape's test can
//! report: the shape's exact bounds, its edges extended by
//! [`crate::geometry::shapes::EDGE_REL`] (rectangles, discs) or its
//! on-surface band (spheres, boxes, SH clipping ball), padded by [`PAD_REL`]
//! of the largest coordinate. A point a shape's test reports lies within
//! rounding of the ray (a few ulp of the origin's and the point's
//! coordinates) and of the shape (a few ulp of its coordinates); both are
//! far inside the pads of the tree's boxes and of the ray query
//! ([`crate::geometry::bvh`]), so no shape whose test answers is culled.
//! The nearest hit then depends only on the set of candidates, not on the
//! order of the tests ([`super::nearest`]); visibility is an "any".

use super::{Prim, Scene};
use crate::geometry::bvh::Bvh;
use crate::geometry::shapes::EDGE_REL;
use glam::DVec3;

/// Relative padding of a leaf box by its largest coordinate magnitude (and
/// its size), far above the rounding of the shapes' tests (about 1e-15).
const PAD_REL: f64 = 1e-12;

/// Extra relative growth of curved shapes' boxes beyond their radius or
/// extent (the on-surface bands are 1e-10 of the size, the SH clipping
/// ball 1e-8).
const BAND_REL: f64 = 1e-7;

/// Which scenes get the tree with [`Accel::Auto`]: those with at least this
/// many finite shapes. Measured with `lumest bench --shapes
/// 1,2,4,6,8,10,12,16,24,32,64 --threads 1` (a room of six planes with `N`
/// small rectangles, on a shared 2-core machine, so within about 30 %):
/// loops were faster for 1 and 2 shapes (by 25 %), the two were level
/// from 4 to 12, the tree faster from 16 on (1.2x at 16, 1.9x at 32, 2.9x
/// at 64). 12 keeps small scenes such as the office (8 finite shapes) on
/// loops.
pub const AUTO_MIN_SHAPES: usize = 12;

/// Whether the compiled scene puts its finite shapes in a BVH.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Accel {
    /// Build the tree for scenes with at least [`AUTO_MIN_SHAPES`] finite
    /// shapes (rectangles, discs, spheres, boxes, meshes, SH objects).
    #[default]
    Auto,
    /// Never: every query loops over every shape (the reference path).
    Never,
    /// Always, whenever the scene has a finite shape.
    Always,
}

/// The top-level BVH over a scene's finite shapes.
#[derive(Clone, Debug)]
pub(super) struct ShapeTree {
    pub(super) bvh: Bvh,
    /// The shape at each leaf position.
    pub(super) prims: Vec<Prim>,
}

impl ShapeTree {
    /// The tree over every finite shape of `scene` (`None` when it has none).
    pub(super) fn build(scene: &Scene) -> Option<Self> {
        let all = scene.finite_prims();
        if all.is_empty() {
            return None;
        }
        let bounds: Vec<(DVec3, DVec3)> =
            all.iter().map(|&p| padded(prim_bounds(scene, p))).collect();
        let bvh = Bvh::build(&bounds);
        let prims = bvh.ids().iter().map(|&i| all[i as usize]).collect();
        Some(Self { bvh, prims })
    }

    /// Bytes held (nodes, ids, leaf shapes).
    pub(super) fn storage_bytes(&self) -> usize {
        self.bvh.storage_bytes() + self.prims.len() * size_of::<Prim>()
    }
}

/// A box grown by [`PAD_REL`] of its largest coordinate and of its size.
pub(super) fn padded((lo, hi): (DVec3, DVec3)) -> (DVec3, DVec3) {
    let mag = lo.abs().max(hi.abs()).max_element() + (hi - lo).max_element();
    let pad = DVec3::splat(PAD_REL * mag);
    (lo - pad, hi + pad)
}

/// Bounds of everything the shape's tests can report \[m\].
pub(super) fn prim_bounds(scene: &Scene, p: Prim) -> (DVec3, DVec3) {
    match p {
        Prim::Rect(i) => {
            let r = &scene.rects[i as usize].0;
            // Corners of the parallelogram with its edges extended (twice
            // the extension, for the rounding of the dual coordinates).
            let (e1, e2) = (r.e1 * 2.0 * EDGE_REL, r.e2 * 2.0 * EDGE_REL);
            let o = r.o - e1 - e2;
            let (a, b) = (r.e1 + 2.0 * e1, r.e2 + 2.0 * e2);
            let cs = [o, o + a, o + b, o + a + b];
            let lo = cs.iter().fold(DVec3::INFINITY, |m, &c| m.min(c));
            let hi = cs.iter().fold(DVec3::NEG_INFINITY, |m, &c| m.max(c));
            (lo, hi)
        }
        Prim::Disc(i) => {
            let d = &scene.discs[i as usize].0;
            // Half-extent of a disc of radius r with unit normal n along
            // axis k: r sqrt(1 - n_k^2); r grown by the edge extension.
            let r = d.r * (1.0 + 4.0 * EDGE_REL);
            let n = d.plane.n;
            let ext = DVec3::new(
                (1.0 - n.x * n.x).max(0.0).sqrt(),
                (1.0 - n.y * n.y).max(0.0).sqrt(),
                (1.0 - n.z * n.z).max(0.0).sqrt(),
            ) * r
                + DVec3::splat(BAND_REL * d.r);
            (d.plane.p - ext, d.plane.p + ext)
        }
        Prim::Sphere(i) => {
            let s = &scene.spheres[i as usize].0;
            let r = DVec3::splat(s.r * (1.0 + BAND_REL));
            (s.c - r, s.c + r)
        }
        Prim::Box(i) => {
            let b = &scene.boxes[i as usize].0;
            let g = DVec3::splat(BAND_REL * (b.hi - b.lo).max_element());
            (b.lo - g, b.hi + g)
        }
        Prim::Mesh(i) => scene.meshes[i as usize].0.bounds(),
        Prim::Sh(i) => {
            let o = &scene.shs[i as usize].0;
            let r = DVec3::splat(o.bounds().1 * (1.0 + BAND_REL));
            (o.center() - r, o.center() + r)
        }
    }
}
