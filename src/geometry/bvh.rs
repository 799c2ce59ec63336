//! A bounding volume hierarchy over axis-aligned boxes, all in `f64`, and
//! the ray query it is traversed with, including a watertight
//! ray–triangle test. Two uses: [`TriangleBvh`], the triangles of a mesh,
//! and the scene's top-level tree over its finite shapes
//! (`scene/world/shape_tree.rs`), whose leaves are tested by the shapes'
//! own code ([`Bvh::nearest`], [`Bvh::any`] hand over leaf positions).
//!
//! # Why our own BVH, in `f64`
//!
//! `obvhs` (f32, compressed wide BVH) traced about 3.5 times faster than the
//! `bvh` crate in a measurement on this kind of machine, but its boxes and
//! its ray–box test are in `f32`: a box rounded from `f64` coordinates may
//! not contain the `f64` triangle, and its slab test may reject a ray that
//! grazes a box by less than an `f32` ulp (a millimetre at 10 km). Making
//! that conservative would mean patching its build and traversal. A compact
//! `f64` BVH whose box test is conservative by construction is short, and
//! its speed is in the same range (about 1 M nearest-hit rays/s per thread
//! on 100k triangles): see [`crate::geometry::mesh`] for the measurement
//! (`bench_100k_triangles`, run with `--ignored`).
//!
//! # Construction
//!
//! Top-down binned surface-area heuristic (16 bins on each axis, a box test
//! costed like a leaf test), leaves of at most [`MAX_LEAF`] boxes,
//! nodes flattened depth first (left child right after its parent). Where the centroids of a node coincide (no
//! binned split exists) the node is halved by index, so the depth stays
//! below the traversal stack size whatever the input.
//!
//! # Traversal
//!
//! Stack based, nearest child first; a child whose entry distance is beyond
//! the best hit so far is skipped.
//!
//! # Robustness: why no ray slips between triangles or past a box
//!
//! - Triangle test: Woop, Benthin and Wald (2013), "Watertight ray/triangle
//!   intersection", JCGT 2(1). The ray is sheared so that it becomes the
//!   `+z` axis; the vertices are transformed once per triangle, and the 2D
//!   edge functions decide the hit. Two triangles sharing an edge compute
//!   that edge's function from the same transformed vertices with the roles
//!   of the factors swapped, and the sign of each edge function is exact
//!   (a cheap error bound decides; near zero an FMA-based difference of
//!   products, Kahan's algorithm, whose relative error is below 2 ulp,
//!   decides; exact as long as products do not underflow, i.e. for
//!   coordinate differences above about 1e-150 m). Edges and vertices are inclusive (a zero edge function counts
//!   as inside), so a ray through a shared edge or vertex of a conforming
//!   mesh hits at least one of the triangles around it. Both sides count.
//! - Box test: every node box is padded by `BOX_PAD` times the largest
//!   coordinate magnitude of the node, and every ray pads the slabs by the
//!   same factor times its largest origin coordinate (folded into shifted
//!   origins, at no cost per box). This is far more than the rounding of
//!   the slab distances and of the sheared triangle test (both a few ulp of
//!   `|vertex| + |origin|`), so a triangle the exact test hits is never
//!   culled by its boxes. Slab distances that come out NaN (origin on a slab
//!   plane of an axis the ray is parallel to) are ignored, which only makes
//!   the test more conservative. All of this is relative, so it works the
//!   same at millimetre and at kilometre scale.

use glam::DVec3;

/// Most triangles in a leaf (exceeded only at the depth limit, which more
/// than 2^56 triangles would need).
pub const MAX_LEAF: usize = 8;

/// Traversal stack size; the build keeps the depth below it.
const STACK: usize = 64;

/// Deepest node the build creates (the root has depth 0).
const MAX_DEPTH: usize = STACK - 4;

/// Number of SAH bins per axis.
const BINS: usize = 16;

/// Relative padding of boxes (node coordinates and ray origins).
const BOX_PAD: f64 = 64.0 * f64::EPSILON;

/// Cost of one box test relative to one triangle test (SAH).
const TRAVERSAL_COST: f64 = 1.0;

/// A node of the flattened tree: a box and either two children or a run of
/// triangles.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Lower corner of the (padded) box \[m\].
    lo: [f64; 3],
    /// Upper corner of the (padded) box \[m\].
    hi: [f64; 3],
    /// Leaf: first triangle in leaf order. Interior: index of the right
    /// child (the left child is the next node).
    first: u32,
    /// Leaf: number of triangles (> 0). Interior: 0.
    count: u32,
}

/// Relative tolerance within which two triangles' hits tie in
/// [`TriangleBvh::first_hit`] (the scene's own, `COINCIDENT_TIE`).
pub const FACING_TIE: f64 = 1e-9;

/// A ray prepared for the watertight triangle test and the box test.
#[derive(Clone, Copy, Debug)]
pub struct RayQuery {
    /// Origin \[m\].
    o: DVec3,
    /// Direction.
    d: DVec3,
    /// Axis of the largest direction component (becomes `z` after shearing).
    kz: usize,
    /// The two other axes, ordered to keep the winding.
    kx: usize,
    ky: usize,
    /// Shear constants `d[kx]/d[kz]`, `d[ky]/d[kz]`, `1/d[kz]`.
    sx: f64,
    sy: f64,
    sz: f64,
    /// Componentwise inverse direction (infinite on axes the ray is parallel to).
    inv: [f64; 3],
    /// Origins used for the near and far slab planes (shifted by the pad).
    o_near: [f64; 3],
    o_far: [f64; 3],
    /// Per axis: the direction component is negative (the near plane is the upper one).
    neg: [bool; 3],
}

impl RayQuery {
    /// Prepare the ray `o + t d` (`d` non-zero; its length sets the unit of `t`).
    pub fn new(o: DVec3, d: DVec3) -> Self {
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let pad = BOX_PAD * o.abs().max_element();
        let mut inv = [0.0; 3];
        let mut o_near = [0.0; 3];
        let mut o_far = [0.0; 3];
        let mut neg = [false; 3];
        for k in 0..3 {
            inv[k] = 1.0 / d[k];
            neg[k] = d[k].is_sign_negative();
            let s = if neg[k] { -pad } else { pad };
            o_near[k] = o[k] + s;
            o_far[k] = o[k] - s;
        }
        Self {
            o,
            d,
            kz,
            kx,
            ky,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
            inv,
            o_near,
            o_far,
            neg,
        }
    }

    /// Watertight ray–triangle test (both sides). Returns the ray parameter
    /// `t` of the hit (any sign; the caller checks the range), or `None`.
    #[inline(always)]
    pub fn triangle(&self, v: &[DVec3; 3]) -> Option<f64> {
        let a = (v[0] - self.o).to_array();
        let b = (v[1] - self.o).to_array();
        let c = (v[2] - self.o).to_array();
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];
        let u = diff_of_products(cx, by, cy, bx);
        let v_ = diff_of_products(ax, cy, ay, cx);
        let w = diff_of_products(bx, ay, by, ax);
        if (u < 0.0 || v_ < 0.0 || w < 0.0) && (u > 0.0 || v_ > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v_ + w;
        if det == 0.0 {
            return None;
        }
        let t = (u * a[kz] + v_ * b[kz] + w * c[kz]) * self.sz / det;
        Some(t)
    }

    /// Entry distance of the ray into a node's box if it meets it within
    /// `[t_min, t_max]` (conservatively), else `None`.
    #[inline(always)]
    fn enter(&self, n: &Node, t_min: f64, t_max: f64) -> Option<f64> {
        let mut tn = t_min;
        let mut tf = t_max;
        for k in 0..3 {
            let (near, far) = if self.neg[k] {
                (n.hi[k], n.lo[k])
            } else {
                (n.lo[k], n.hi[k])
            };
            // f64::max/min return the other operand when one is NaN.
            tn = tn.max((near - self.o_near[k]) * self.inv[k]);
            tf = tf.min((far - self.o_far[k]) * self.inv[k]);
        }
        (tn <= tf).then_some(tn)
    }
}

/// `a b - c d` with the exact sign (zero exactly when `a b = c d`).
#[inline]
fn diff_of_products(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let ab = a * b;
    let cd = c * d;
    let e = ab - cd;
    // |e - (ab - cd)_exact| <= u (|ab| + |cd|) + u |e|, u = EPSILON / 2.
    if e.abs() > 2.0 * f64::EPSILON * (ab.abs() + cd.abs()) {
        e
    } else {
        diff_of_products_fma(a, b, c, d)
    }
}

/// Kahan's difference of products with fused multiply-adds: relative error
/// below 2 ulp (Jeannerod, Louvet, Muller 2013), hence the exact sign.
#[cold]
#[inline(never)]
fn diff_of_products_fma(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let w = c * d;
    let err = (-c).mul_add(d, w); // w - c d, exactly
    let f = a.mul_add(b, -w);
    f + err
}

/// A bounding volume hierarchy over a fixed set of axis-aligned boxes (the
/// bounds of triangles, of shapes): the tree and the traversals. What a
/// leaf holds and how it is tested is the caller's: the traversals hand
/// over leaf positions (see [`Bvh::ids`]).
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Input index of each box in leaf order.
    ids: Vec<u32>,
}

/// Which triangles a ray or segment does not meet at its ends: `skip`, the
/// one it leaves (a collision's), and any met within `near` \[m\] of an
/// end lying on the triangle's plane, within `tol` \[m\] (a receiver on a
/// mesh floor, a collision on a rug laid on it, a panel written front and
/// back: rounding would put such a hit at `t ~ 1e-17`, on either side). A
/// triangle the end lies off, however near (a floor point `1e-10` m from a
/// cabinet's side), is met: skipping every triangle within `near`, the
/// rule before, let the rays of such a point pass through the cabinet's
/// side, and the point lost the light of that side (E_indirect 0.21
/// against 3.58 lx at 1e-3 m).
#[derive(Clone, Copy, Debug, Default)]
pub struct Ends {
    /// The triangle the ray leaves, never met.
    pub skip: Option<u32>,
    /// Distance from an end within which a triangle through that end is
    /// not met \[m\] (0: every hit counts).
    pub near: f64,
    /// How far an end may lie from a triangle's plane and be on it \[m\].
    pub tol: f64,
}

impl Ends {
    /// Skip triangle `skip` alone.
    pub fn skip(skip: Option<u32>) -> Self {
        Self {
            skip,
            ..Self::default()
        }
    }

    /// Whether a hit at distance `t` from the end `p` counts: beyond
    /// `near`, or with `p` farther than `tol` from the plane of `v`.
    #[inline(always)]
    fn counts(&self, p: DVec3, t: f64, v: &[DVec3; 3]) -> bool {
        t > self.near || {
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            (p - v[0]).dot(n).abs() > self.tol * n.length()
        }
    }
}

/// A BVH over a fixed set of triangles, answering nearest-hit and any-hit
/// queries with the watertight triangle test. Triangles are named by their
/// index in the input slice.
#[derive(Clone, Debug)]
pub struct TriangleBvh {
    tree: Bvh,
    /// Triangle vertices \[m\] in leaf order.
    tris: Vec<[DVec3; 3]>,
}

/// A box reference during the build.
#[derive(Clone, Copy)]
struct Item {
    lo: DVec3,
    hi: DVec3,
    c: DVec3,
    id: u32,
}

#[derive(Clone, Copy)]
struct Bin {
    lo: DVec3,
    hi: DVec3,
    n: usize,
}

impl Bin {
    const EMPTY: Bin = Bin {
        lo: DVec3::splat(f64::INFINITY),
        hi: DVec3::splat(f64::NEG_INFINITY),
        n: 0,
    };
    fn add(&mut self, lo: DVec3, hi: DVec3, n: usize) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
        self.n += n;
    }
}

/// Half the surface area of a box (0 for an empty one).
fn half_area(lo: DVec3, hi: DVec3) -> f64 {
    let e = (hi - lo).max(DVec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

impl Bvh {
    /// Build over boxes `(lower, upper)` \[m\] (finite; at most `u32::MAX`).
    /// Node boxes are padded by `BOX_PAD` of their largest coordinate; the
    /// caller's boxes must hold everything its leaf test can report.
    pub fn build(bounds: &[(DVec3, DVec3)]) -> Self {
        assert!(bounds.len() < u32::MAX as usize, "too many boxes");
        let mut items: Vec<Item> = bounds
            .iter()
            .enumerate()
            .map(|(i, &(lo, hi))| Item {
                lo,
                hi,
                c: 0.5 * (lo + hi),
                id: i as u32,
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * bounds.len() / MAX_LEAF + 1);
        if !items.is_empty() {
            build_node(&mut items, 0, 0, &mut nodes);
        }
        let ids = items.iter().map(|it| it.id).collect();
        Self { nodes, ids }
    }

    /// Input index of the box at each leaf position.
    pub fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// Bytes held by the tree (nodes and ids).
    pub fn storage_bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>() + self.ids.len() * size_of::<u32>()
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Nearest-first traversal for a nearest-hit query over `(t_min, t_max)`:
    /// calls `leaf(position, bound)` for every leaf position whose boxes the
    /// ray meets before the current bound, which `leaf` returns (lowered
    /// when it found a nearer hit). Nodes entered beyond the bound are
    /// skipped. Returns the final bound.
    #[inline(always)]
    pub fn nearest(
        &self,
        q: &RayQuery,
        t_min: f64,
        t_max: f64,
        mut leaf: impl FnMut(usize, f64) -> f64,
    ) -> f64 {
        let mut best_t = t_max;
        let Some(root) = self.nodes.first() else {
            return best_t;
        };
        if q.enter(root, t_min, best_t).is_none() {
            return best_t;
        }
        let mut stack = [(0u32, 0.0f64); STACK];
        let mut sp = 0usize;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if n.count > 0 {
                let start = n.first as usize;
                let end = start + n.count as usize;
                for pos in start..end {
                    best_t = leaf(pos, best_t);
                }
            } else {
                let l = node + 1;
                let r = n.first as usize;
                let hl = q.enter(&self.nodes[l], t_min, best_t);
                let hr = q.enter(&self.nodes[r], t_min, best_t);
                match (hl, hr) {
                    (Some(tl), Some(tr)) => {
                        let (near, far, tfar) = if tl <= tr { (l, r, tr) } else { (r, l, tl) };
                        stack[sp] = (far as u32, tfar);
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = l;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = r;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node that may still hold a nearer hit.
            loop {
                if sp == 0 {
                    return best_t;
                }
                sp -= 1;
                let (i, t) = stack[sp];
                if t <= best_t {
                    node = i as usize;
                    break;
                }
            }
        }
    }

    /// Any-hit traversal over `(t_min, t_max)`: whether `leaf(position)` is
    /// true for a leaf position whose boxes the ray meets (stops at the
    /// first).
    #[inline(always)]
    pub fn any(
        &self,
        q: &RayQuery,
        t_min: f64,
        t_max: f64,
        mut leaf: impl FnMut(usize) -> bool,
    ) -> bool {
        let Some(root) = self.nodes.first() else {
            return false;
        };
        if q.enter(root, t_min, t_max).is_none() {
            return false;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 0usize;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if n.count > 0 {
                let start = n.first as usize;
                let end = start + n.count as usize;
                if (start..end).any(&mut leaf) {
                    return true;
                }
            } else {
                let l = node + 1;
                let r = n.first as usize;
                let hl = q.enter(&self.nodes[l], t_min, t_max).is_some();
                let hr = q.enter(&self.nodes[r], t_min, t_max).is_some();
                match (hl, hr) {
                    (true, true) => {
                        stack[sp] = r as u32;
                        sp += 1;
                        node = l;
                        continue;
                    }
                    (true, false) => {
                        node = l;
                        continue;
                    }
                    (false, true) => {
                        node = r;
                        continue;
                    }
                    (false, false) => {}
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node = stack[sp] as usize;
        }
    }
}

impl TriangleBvh {
    /// Build over `tris` (vertices \[m\], finite; at most `u32::MAX` triangles).
    pub fn build(tris: &[[DVec3; 3]]) -> Self {
        let bounds: Vec<(DVec3, DVec3)> = tris
            .iter()
            .map(|t| (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2])))
            .collect();
        let tree = Bvh::build(&bounds);
        let tris = tree.ids().iter().map(|&i| tris[i as usize]).collect();
        Self { tree, tris }
    }

    /// Bytes held by the tree (nodes, leaf-ordered triangle copies, ids).
    pub fn storage_bytes(&self) -> usize {
        self.tree.storage_bytes() + self.tris.len() * size_of::<[DVec3; 3]>()
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.tree.node_count()
    }

    /// Nearest hit with `t` in `(t_min, t_max)`, skipping triangle `skip`:
    /// `(t, input index, corners [m])`. With `facing = Some((d, front))`
    /// (`d` the ray's direction), of triangles met within a relative
    /// [`FACING_TIE`] of each other the one whose winding side `front`
    /// (`d . ng < 0`; `false`: the back) faces the ray is returned: two
    /// coincident triangles of opposite winding (a "double-sided" face as
    /// exporters write it) have hit distances a few ulps apart, and the
    /// ray must meet the one that reflects towards it.
    pub fn first_hit(
        &self,
        q: &RayQuery,
        t_min: f64,
        t_max: f64,
        ends: Ends,
        facing: Option<(DVec3, bool)>,
    ) -> Option<(f64, u32, [DVec3; 3])> {
        let skip = ends.skip.unwrap_or(u32::MAX);
        let ids = self.tree.ids();
        let faces = |p: &[DVec3; 3]| {
            facing.is_none_or(|(d, front)| {
                let dn = d.dot((p[1] - p[0]).cross(p[2] - p[0]));
                if front { dn < 0.0 } else { dn > 0.0 }
            })
        };
        // (position, t, faces the ray)
        let mut best: Option<(usize, f64, bool)> = None;
        self.tree.nearest(q, t_min, t_max, |pos, bound| {
            if ids[pos] != skip
                && let Some(t) = q.triangle(&self.tris[pos])
                && t > t_min
                && t < bound
                && t < t_max
                && ends.counts(q.o, t, &self.tris[pos])
            {
                let take = match best {
                    None => true,
                    Some((_, bt, bf)) => {
                        if t < bt * (1.0 - FACING_TIE) {
                            true
                        } else {
                            // A tie (`t` within the tolerance beyond is all
                            // the bound lets through): the facing one, then
                            // the nearer.
                            let f = faces(&self.tris[pos]);
                            (f && !bf) || (f == bf && t < bt)
                        }
                    }
                };
                if take {
                    best = Some((pos, t, faces(&self.tris[pos])));
                }
            }
            match best {
                // Keep looking just beyond a hit that shows its back.
                Some((_, bt, false)) => bound.min(bt * (1.0 + FACING_TIE)),
                Some((_, bt, true)) => bt,
                None => bound,
            }
        });
        best.map(|(pos, t, _)| (t, ids[pos], self.tris[pos]))
    }

    /// Call `f(t, input index, corners)` for every triangle the ray meets with `t` in
    /// `(t_min, t_max)`, each once (including triangles met at the same
    /// distance), in no particular order.
    pub fn for_each_hit(
        &self,
        q: &RayQuery,
        t_min: f64,
        t_max: f64,
        mut f: impl FnMut(f64, u32, &[DVec3; 3]),
    ) {
        let ids = self.tree.ids();
        self.tree.any(q, t_min, t_max, |pos| {
            if let Some(t) = q.triangle(&self.tris[pos])
                && t > t_min
                && t < t_max
            {
                f(t, ids[pos], &self.tris[pos]);
            }
            false
        });
    }

    /// Call `f(input index, corners)` for every triangle of the leaves
    /// whose boxes the ray meets with `t` in `(t_min, t_max)`, each once,
    /// in no particular order, with no triangle test (the caller's own).
    pub fn for_each_candidate(
        &self,
        q: &RayQuery,
        t_min: f64,
        t_max: f64,
        mut f: impl FnMut(u32, &[DVec3; 3]),
    ) {
        let ids = self.tree.ids();
        self.tree.any(q, t_min, t_max, |pos| {
            f(ids[pos], &self.tris[pos]);
            false
        });
    }

    /// Whether any triangle is hit with `t` in `(t_min, t_max)` that
    /// `ends` lets count, both ends of the segment `(0, t_max)` checked.
    pub fn any_hit(&self, q: &RayQuery, t_min: f64, t_max: f64, ends: Ends) -> bool {
        let skip = ends.skip.unwrap_or(u32::MAX);
        let ids = self.tree.ids();
        self.tree.any(q, t_min, t_max, |pos| {
            ids[pos] != skip
                && q.triangle(&self.tris[pos]).is_some_and(|t| {
                    t > t_min
                        && t < t_max
                        && ends.counts(q.o, t, &self.tris[pos])
                        && ends.counts(q.o + t_max * q.d, t_max - t, &self.tris[pos])
                })
        })
    }
}

/// Build the subtree over `items` (non-empty), whose first triangle has leaf
/// position `offset`; returns nothing, appends nodes depth first.
fn build_node(items: &mut [Item], offset: usize, depth: usize, nodes: &mut Vec<Node>) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut clo = lo;
    let mut chi = hi;
    for it in items.iter() {
        lo = lo.min(it.lo);
        hi = hi.max(it.hi);
        clo = clo.min(it.c);
        chi = chi.max(it.c);
    }
    let pad = BOX_PAD * lo.abs().max(hi.abs()).max_element();
    let index = nodes.len();
    nodes.push(Node {
        lo: (lo - pad).to_array(),
        hi: (hi + pad).to_array(),
        first: offset as u32,
        count: items.len() as u32,
    });
    let n = items.len();
    if n <= 1 || depth >= MAX_DEPTH {
        return;
    }
    let split = match best_split(items, lo, hi, clo, chi) {
        Some((axis, bin, cost)) => {
            if n <= MAX_LEAF && cost >= n as f64 {
                return; // a leaf is cheaper
            }
            let scale = BINS as f64 / (chi[axis] - clo[axis]);
            let mid = partition(items, |it| bin_of(it.c[axis], clo[axis], scale) < bin);
            if mid == 0 || mid == n { n / 2 } else { mid }
        }
        None => {
            if n <= MAX_LEAF {
                return;
            }
            n / 2 // coincident centroids: halve by index
        }
    };
    let (left, right) = items.split_at_mut(split);
    build_node(left, offset, depth + 1, nodes);
    nodes[index].first = nodes.len() as u32;
    nodes[index].count = 0;
    build_node(right, offset + split, depth + 1, nodes);
}

#[inline]
fn bin_of(c: f64, clo: f64, scale: f64) -> usize {
    (((c - clo) * scale) as usize).min(BINS - 1)
}

/// Best binned SAH split: `(axis, first bin of the right side, cost)` with
/// the cost in units of one triangle test, or `None` when the centroids
/// coincide.
fn best_split(
    items: &[Item],
    lo: DVec3,
    hi: DVec3,
    clo: DVec3,
    chi: DVec3,
) -> Option<(usize, usize, f64)> {
    let parent = half_area(lo, hi);
    let mut best: Option<(usize, usize, f64)> = None;
    for axis in 0..3 {
        let extent = chi[axis] - clo[axis];
        if extent.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let scale = BINS as f64 / extent;
        let mut bins = [Bin::EMPTY; BINS];
        for it in items {
            bins[bin_of(it.c[axis], clo[axis], scale)].add(it.lo, it.hi, 1);
        }
        // Right-to-left sweep: area * count of bins[k..].
        let mut right_cost = [0.0; BINS];
        let mut acc = Bin::EMPTY;
        for k in (1..BINS).rev() {
            acc.add(bins[k].lo, bins[k].hi, bins[k].n);
            right_cost[k] = half_area(acc.lo, acc.hi) * acc.n as f64;
        }
        let mut acc = Bin::EMPTY;
        for k in 1..BINS {
            acc.add(bins[k - 1].lo, bins[k - 1].hi, bins[k - 1].n);
            if acc.n == 0 || acc.n == items.len() {
                continue;
            }
            let c = half_area(acc.lo, acc.hi) * acc.n as f64 + right_cost[k];
            let cost = if parent > 0.0 {
                TRAVERSAL_COST + c / parent
            } else {
                TRAVERSAL_COST + items.len() as f64
            };
            if best.is_none_or(|b| cost < b.2) {
                best = Some((axis, k, cost));
            }
        }
    }
    best
}

/// Reorder `items` so that those satisfying `left` come first; returns
/// their number.
fn partition(items: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if left(&items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;

    #[test]
    fn difference_of_products_has_the_exact_sign() {
        let e = 2f64.powi(-27);
        // (1 + e)(1 - e) = 1 - 2^-54 rounds to 1: the plain difference says 0.
        let (a, b) = (1.0 + e, 1.0 - e);
        assert_eq!(a * b - 1.0, 0.0);
        assert!(diff_of_products(a, b, 1.0, 1.0) < 0.0);
        assert!(diff_of_products(1.0, 1.0, a, b) > 0.0);
        assert_eq!(diff_of_products(3.0, 0.1, 0.1, 3.0), 0.0);
        // Integers below 2^53 (exact in f64; products exact in i128) with
        // a b ~ 2^61 and c d within a few ulp of it.
        let mut rng = Philox4x32::new(3, 0);
        let mut naive_wrong = 0;
        for _ in 0..200_000 {
            let a = (1i128 << 30) + (rng.next_u32() >> 2) as i128;
            let b = (1i128 << 30) + (rng.next_u32() >> 2) as i128;
            let c = (1i128 << 9) + (rng.next_u32() % 3584) as i128;
            let d = a * b / c + (rng.next_u32() % 3) as i128 - 1;
            let exact = (a * b - c * d).signum();
            let (fa, fb, fc, fd) = (a as f64, b as f64, c as f64, d as f64);
            let got = diff_of_products(fa, fb, fc, fd);
            assert_eq!(
                got.partial_cmp(&0.0).map(|o| o as i128),
                Some(exact),
                "{a} {b} {c} {d}"
            );
            let naive = fa * fb - fc * fd;
            if naive.partial_cmp(&0.0).map(|o| o as i128) != Some(exact) {
                naive_wrong += 1;
            }
        }
        assert!(naive_wrong > 10_000, "only {naive_wrong} hard cases");
    }

    #[test]
    fn triangle_test_is_two_sided_and_inclusive() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        for (o, d, want) in [
            (DVec3::new(0.25, 0.25, 1.0), -DVec3::Z, Some(1.0)),
            (DVec3::new(0.25, 0.25, -2.0), DVec3::Z, Some(2.0)),
            (DVec3::new(0.25, 0.25, 1.0), DVec3::Z, Some(-1.0)),
            (DVec3::new(0.0, 0.0, 1.0), -DVec3::Z, Some(1.0)), // vertex
            (DVec3::new(0.5, 0.5, 1.0), -DVec3::Z, Some(1.0)), // hypotenuse
            (DVec3::new(0.5, 0.0, 1.0), -DVec3::Z, Some(1.0)), // edge on an axis
            (DVec3::new(0.5, 0.5 + 1e-16, 1.0), -DVec3::Z, None),
            (DVec3::new(-1.0, 0.25, 0.0), DVec3::X, None), // in the plane
        ] {
            assert_eq!(RayQuery::new(o, d).triangle(&tri), want, "{o} {d}");
        }
    }

    #[test]
    fn depth_stays_bounded_for_coincident_boxes() {
        // 5000 copies of one triangle: no split by SAH, halved by index.
        let tris = vec![[DVec3::ZERO, DVec3::X, DVec3::Y]; 5000];
        let bvh = TriangleBvh::build(&tris);
        let q = RayQuery::new(DVec3::new(0.2, 0.2, 1.0), -DVec3::Z);
        let (t, id, _) = bvh
            .first_hit(&q, 0.0, f64::INFINITY, Ends::default(), None)
            .unwrap();
        assert_eq!(t, 1.0);
        assert!(id < 5000);
        assert!(bvh.any_hit(&q, 0.0, 1.5, Ends::skip(Some(id))));
        assert!(!bvh.any_hit(&q, 0.0, 1.0, Ends::default()));
    }
}
