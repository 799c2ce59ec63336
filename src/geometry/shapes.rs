//! Finite analytic shapes: rectangles (parallelograms), discs, spheres and
//! axis-aligned boxes, with ray intersection and robust segment crossing.
//!
//! **Robustness.** Two kinds of query, each built to be stable at any scene
//! scale (every tolerance is relative to the shape's own size):
//!
//! - *Nearest hit* of a ray that may leave the shape itself. A ray leaving a
//!   flat shape never meets it again; a ray leaving a sphere or a box is
//!   handled by convexity (outward: never again; inward: the chord or the
//!   exit face, computed directly, never a root near `t = 0`). No
//!   epsilon-offset of the origin is needed, so there is no acne.
//! - *Does the open segment `a b` cross the surface?* (shadow rays). Decided
//!   by classifying the end points as inside / on / outside with a relative
//!   tolerance, and, only where needed, whether the segment enters the shrunk
//!   interior. End points lying on the surface (a collision on a wall, a
//!   receiver on the floor) therefore never shadow themselves, and two
//!   points on the inside of a sphere or box always see each other.
//!
//! Edges of rectangles and discs are extended by [`EDGE_REL`] of their size,
//! so shapes that share an edge (walls of a room) leave no crack for light.

use super::{Plane, Ray};
use glam::DVec3;

/// Relative extension of rectangle and disc edges (see the module docs).
pub const EDGE_REL: f64 = 1e-9;

/// Relative tolerance for "on the surface" of spheres and boxes.
const ON_REL: f64 = 1e-10;

/// A parallelogram `o + u e1 + v e2`, `u, v` in `[0, 1]`; front normal
/// `e1 x e2` (right-hand rule).
#[derive(Clone, Copy, Debug)]
pub struct Rect {
    /// Corner \[m\].
    pub o: DVec3,
    /// First edge \[m\].
    pub e1: DVec3,
    /// Second edge \[m\].
    pub e2: DVec3,
    /// Supporting plane, normal `e1 x e2` normalised.
    pub plane: Plane,
    /// Dual vectors: `u = b1 . (p - o)`, `v = b2 . (p - o)`.
    b1: DVec3,
    b2: DVec3,
}

impl Rect {
    /// Parallelogram with corner `o` and edges `e1`, `e2` (not parallel, non-zero).
    pub fn new(o: DVec3, e1: DVec3, e2: DVec3) -> Option<Self> {
        let c = e1.cross(e2);
        let n = c.normalize_or_zero();
        if n == DVec3::ZERO || !n.is_finite() || c.length() <= 1e-12 * e1.length() * e2.length() {
            return None;
        }
        let t1 = e2.cross(n);
        let t2 = n.cross(e1);
        Some(Self {
            o,
            e1,
            e2,
            plane: Plane::new(o, n),
            b1: t1 / e1.dot(t1),
            b2: t2 / e2.dot(t2),
        })
    }

    /// Area [m^2].
    pub fn area(&self) -> f64 {
        self.e1.cross(self.e2).length()
    }

    /// The coordinates `(u, v)` of a point of the plane (`p = o + u e1 +
    /// v e2`; the shape is `u, v` in `[0, 1]`).
    pub fn uv(&self, p: DVec3) -> (f64, f64) {
        let q = p - self.o;
        (self.b1.dot(q), self.b2.dot(q))
    }

    /// For a point of the plane on the rectangle's rim (within
    /// [`EDGE_REL`] of an edge), the in-plane unit vectors into the shape
    /// across each edge it lies on (two at a corner); none inside.
    pub fn rims(&self, p: DVec3) -> Vec<DVec3> {
        let (u, v) = self.uv(p);
        let mut out = Vec::new();
        for (w, b) in [(u, self.b1), (v, self.b2)] {
            if w.abs() <= EDGE_REL {
                out.push(b.normalize());
            } else if (w - 1.0).abs() <= EDGE_REL {
                out.push(-b.normalize());
            }
        }
        out
    }
}

impl Flat for Rect {
    fn plane(&self) -> &Plane {
        &self.plane
    }

    /// `u, v` in `[0, 1]`, extended by [`EDGE_REL`].
    #[inline]
    fn contains_planar(&self, p: DVec3) -> bool {
        let q = p - self.o;
        let (u, v) = (self.b1.dot(q), self.b2.dot(q));
        (-EDGE_REL..=1.0 + EDGE_REL).contains(&u) && (-EDGE_REL..=1.0 + EDGE_REL).contains(&v)
    }
}

/// A disc: centre `c`, front normal `plane.n`, radius `r`.
#[derive(Clone, Copy, Debug)]
pub struct Disc {
    /// Supporting plane through the centre.
    pub plane: Plane,
    /// Radius \[m\].
    pub r: f64,
}

impl Disc {
    /// Disc of centre `c`, normal direction `n` (non-zero) and radius `r > 0`.
    pub fn new(c: DVec3, n: DVec3, r: f64) -> Self {
        Self {
            plane: Plane::new(c, n),
            r,
        }
    }

    /// For a point of the plane on the disc's rim (within [`EDGE_REL`] of
    /// the radius), the in-plane unit vector into the disc; `None` inside.
    pub fn rim(&self, p: DVec3) -> Option<DVec3> {
        let q = self.plane.p - p;
        let q = q - self.plane.n * self.plane.n.dot(q);
        (q.length_squared() >= self.r * self.r * (1.0 - 2.0 * EDGE_REL)).then(|| q.normalize())
    }
}

impl Flat for Disc {
    fn plane(&self) -> &Plane {
        &self.plane
    }

    /// Within the radius, extended by [`EDGE_REL`].
    #[inline]
    fn contains_planar(&self, p: DVec3) -> bool {
        (p - self.plane.p).length_squared() <= self.r * self.r * (1.0 + 2.0 * EDGE_REL)
    }
}

/// A flat shape: a region of its supporting plane. Intersection and segment
/// crossing follow from the plane and the region test.
pub trait Flat {
    /// The supporting plane (normal: the shape's front).
    fn plane(&self) -> &Plane;

    /// Whether a point of the supporting plane lies in the shape.
    fn contains_planar(&self, p: DVec3) -> bool;

    /// Ray parameter of the hit in `(0, t_max)`.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        let t = self.plane().intersect(ray, t_max)?;
        self.contains_planar(ray.o + ray.d * t).then_some(t)
    }

    /// Whether the open segment `a b` crosses the shape: the end points lie
    /// strictly on opposite sides of its plane and the crossing point is
    /// inside the shape.
    #[inline]
    fn crosses(&self, a: DVec3, b: DVec3) -> bool {
        let plane = self.plane();
        if plane.side(a) * plane.side(b) >= 0 {
            return false;
        }
        let (da, db) = (plane.signed_distance(a), plane.signed_distance(b));
        self.contains_planar(a + (b - a) * (da / (da - db)))
    }
}

/// Where a point lies relative to a closed convex surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inside {
    /// Strictly inside.
    In,
    /// On the surface, within the relative tolerance.
    On,
    /// Strictly outside.
    Out,
}

/// A sphere: centre `c` \[m\], radius `r` \[m\]; geometric normal outward.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre \[m\].
    pub c: DVec3,
    /// Radius \[m\].
    pub r: f64,
}

impl Sphere {
    /// The distance \[m\] within which a point counts as on the sphere:
    /// [`ON_REL`] of the radius, and at least 64 ulps of the largest
    /// coordinate (as a box's, [`AaBox::tolerance`]): a 2 m sphere 6.4e6 m
    /// from the origin had a tolerance (2e-10 m) below the rounding of its
    /// own points (1e-9 m), and its collisions, counted outside, lost 9 %
    /// of an integrating sphere's light.
    #[inline]
    fn tol(&self) -> f64 {
        let ulps = 64.0 * f64::EPSILON * (self.c.abs().max_element() + self.r);
        (ON_REL * self.r).max(ulps)
    }

    /// Where `p` lies.
    #[inline]
    pub fn classify(&self, p: DVec3) -> Inside {
        let s = (p - self.c).length() - self.r;
        let tol = self.tol();
        if s < -tol {
            Inside::In
        } else if s > tol {
            Inside::Out
        } else {
            Inside::On
        }
    }

    /// Nearest hit in `(0, t_max)` of a ray; `leaving`: the ray starts on
    /// this sphere (a collision), so the root at its origin is not a hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64, leaving: bool) -> Option<f64> {
        let oc = ray.o - self.c;
        let b = oc.dot(ray.d);
        if leaving {
            // Outward: a convex surface is never met again. Inward: the chord.
            let t = -2.0 * b;
            return (t > 0.0 && t < t_max).then_some(t);
        }
        let c = oc.length_squared() - self.r * self.r;
        // Numerically stable roots of t^2 + 2 b t + c = 0.
        let h = b * b - c;
        if h < 0.0 {
            return None;
        }
        let q = -(b + b.signum() * h.sqrt());
        let (t0, t1) = if q == 0.0 {
            (0.0, 0.0)
        } else {
            let (x, y) = (q, c / q);
            if x < y { (x, y) } else { (y, x) }
        };
        if t0 > 0.0 && t0 < t_max {
            Some(t0)
        } else if t1 > 0.0 && t1 < t_max {
            Some(t1)
        } else {
            None
        }
    }

    /// Project a point onto the sphere and give the outward unit normal there.
    #[inline]
    pub fn surface_point(&self, p: DVec3) -> (DVec3, DVec3) {
        let n = (p - self.c).normalize();
        (self.c + n * self.r, n)
    }

    /// Whether the open segment `a b` crosses the sphere.
    pub fn crosses(&self, a: DVec3, b: DVec3) -> bool {
        use Inside::*;
        match (self.classify(a), self.classify(b)) {
            (In, Out) | (Out, In) => true,
            (In | On, In | On) => false,
            // One end outside, the other outside or on: crosses when the
            // segment passes strictly inside the (shrunk) sphere.
            _ => {
                let ab = b - a;
                let t = ((self.c - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                let q = a + ab * t;
                (q - self.c).length() < self.r - self.tol()
            }
        }
    }
}

/// Faces of an axis-aligned box, in the order `x_min, x_max, y_min, y_max,
/// z_min, z_max`; face `f` lies on axis `f / 2`, at the maximum when `f` is odd.
pub const BOX_FACES: [&str; 6] = ["x_min", "x_max", "y_min", "y_max", "z_min", "z_max"];

/// An axis-aligned box `[lo, hi]`.
#[derive(Clone, Copy, Debug)]
pub struct AaBox {
    /// Lower corner \[m\].
    pub lo: DVec3,
    /// Upper corner \[m\].
    pub hi: DVec3,
}

impl AaBox {
    /// Outward unit normal of face `f`.
    pub fn outward_normal(f: usize) -> DVec3 {
        let mut n = DVec3::ZERO;
        n[f / 2] = if f % 2 == 1 { 1.0 } else { -1.0 };
        n
    }

    /// Plane of face `f` with its outward normal.
    pub fn face_plane(&self, f: usize) -> Plane {
        let p = if f % 2 == 1 { self.hi } else { self.lo };
        Plane::new(p, Self::outward_normal(f))
    }

    /// [`ON_REL`] of the largest extent, and at least 64 ulps of the
    /// largest coordinate: a small box far from the origin would otherwise
    /// have a tolerance below the rounding of its own coordinates (its
    /// shrunk box in [`Self::crosses`] rounding back to the box, so that a
    /// segment along a face plane would count as crossing it).
    fn tol(&self) -> f64 {
        let ulps = 64.0 * f64::EPSILON * self.lo.abs().max(self.hi.abs()).max_element();
        (ON_REL * (self.hi - self.lo).max_element()).max(ulps)
    }

    /// The distance \[m\] within which a point counts as on the surface
    /// ([`Self::classify`]); [`Self::crosses`] tests the box shrunk by it.
    pub fn tolerance(&self) -> f64 {
        self.tol()
    }

    /// Where `p` lies.
    pub fn classify(&self, p: DVec3) -> Inside {
        let tol = self.tol();
        let outside = (self.lo - p).max(p - self.hi).max_element();
        if outside > tol {
            Inside::Out
        } else if outside < -tol {
            Inside::In
        } else {
            Inside::On
        }
    }

    /// Slab interval `[t0, t1]` of the ray inside the box shrunk by `shrink`.
    #[inline]
    fn slab(&self, o: DVec3, d: DVec3, shrink: f64) -> (f64, f64, usize, usize) {
        let inv = d.recip();
        let lo = self.lo + DVec3::splat(shrink);
        let hi = self.hi - DVec3::splat(shrink);
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        let (mut f0, mut f1) = (0, 0);
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < lo[a] || o[a] > hi[a] {
                    return (f64::INFINITY, f64::NEG_INFINITY, 0, 0);
                }
                continue;
            }
            let (ta, tb) = ((lo[a] - o[a]) * inv[a], (hi[a] - o[a]) * inv[a]);
            // Entering through the min face when d > 0, the max face when d < 0.
            let (near, far, fnear, ffar) = if d[a] > 0.0 {
                (ta, tb, 2 * a, 2 * a + 1)
            } else {
                (tb, ta, 2 * a + 1, 2 * a)
            };
            if near > t0 {
                t0 = near;
                f0 = fnear;
            }
            if far < t1 {
                t1 = far;
                f1 = ffar;
            }
        }
        (t0, t1, f0, f1)
    }

    /// Nearest hit `(t, face)` in `(0, t_max)` of a ray. `leaving`: the face
    /// the ray starts on (a collision): leaving outward it never meets the box
    /// again (convex); leaving inward it meets the exit face. A start on
    /// the face's plane but just beyond its edge (within the tolerance of
    /// [`Self::classify`]: a floor point beside a cabinet's foot) may miss
    /// the box, or enter it through the next face, which it then meets from
    /// outside: the exit face, met from inside, lost that face's light.
    pub fn intersect(&self, ray: &Ray, t_max: f64, leaving: Option<usize>) -> Option<(f64, usize)> {
        let (t0, t1, f0, f1) = self.slab(ray.o, ray.d, 0.0);
        if let Some(f) = leaving {
            let inward = ray.d.dot(Self::outward_normal(f)) < 0.0;
            if !inward || t0 > t1 {
                return None;
            }
            if t0 > 0.0 && f0 != f {
                return (t0 < t_max).then_some((t0, f0));
            }
            return (t1 > 0.0 && t1 < t_max && f1 != f).then_some((t1, f1));
        }
        if t0 > t1 {
            return None;
        }
        if t0 > 0.0 {
            (t0 < t_max).then_some((t0, f0))
        } else if t1 > 0.0 {
            (t1 < t_max).then_some((t1, f1))
        } else {
            None
        }
    }

    /// Project a point onto face `f`.
    pub fn face_point(&self, p: DVec3, f: usize) -> DVec3 {
        let mut q = p.clamp(self.lo, self.hi);
        q[f / 2] = if f % 2 == 1 {
            self.hi[f / 2]
        } else {
            self.lo[f / 2]
        };
        q
    }

    /// Whether the open segment `a b` crosses the box's surface.
    pub fn crosses(&self, a: DVec3, b: DVec3) -> bool {
        use Inside::*;
        match (self.classify(a), self.classify(b)) {
            (In, Out) | (Out, In) => true,
            (In | On, In | On) => false,
            _ => {
                let ab = b - a;
                let len = ab.length();
                let (t0, t1, _, _) = self.slab(a, ab / len, self.tol());
                t0.max(0.0) < t1.min(len)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f64; 3], d: [f64; 3]) -> Ray {
        Ray {
            o: DVec3::from_array(o),
            d: DVec3::from_array(d).normalize(),
        }
    }

    #[test]
    fn leaving_a_face_beside_its_edge() {
        // A unit box; a start on the plane of its floor face (z_min), 1e-11
        // m outside its x_min face (a floor point at a cabinet's foot,
        // within the box's tolerance).
        let b = AaBox {
            lo: DVec3::new(1.0, 1.0, 0.0),
            hi: DVec3::new(2.0, 2.0, 1.0),
        };
        let o = DVec3::new(1.0 - 1e-11, 1.5, 0.0);
        assert_eq!(b.classify(o), Inside::On);
        let z_min = 4;
        // Towards the box: it meets the x_min face from outside, at once,
        // not the far faces from inside.
        let d = DVec3::new(1.0, 0.0, 1.0).normalize();
        let (t, f) = b
            .intersect(&Ray { o, d }, f64::INFINITY, Some(z_min))
            .unwrap();
        assert!(f == 0 && t < 1e-10, "face {f} at {t}");
        // Up and along the face, past the box: nothing.
        let d = DVec3::new(1e-12, 1.0, 1.0).normalize();
        assert_eq!(b.intersect(&Ray { o, d }, f64::INFINITY, Some(z_min)), None);
        // From inside the face, as before: the exit face.
        let o = DVec3::new(1.5, 1.5, 0.0);
        let d = DVec3::new(0.0, 0.0, 1.0);
        assert_eq!(
            b.intersect(&Ray { o, d }, f64::INFINITY, Some(z_min)),
            Some((1.0, 5))
        );
    }

    #[test]
    fn rectangle_hits_inside_and_shares_edges_without_cracks() {
        let r = Rect::new(DVec3::ZERO, DVec3::X * 2.0, DVec3::Y).unwrap();
        assert_eq!(r.plane.n, DVec3::Z);
        assert!((r.area() - 2.0).abs() < 1e-15);
        let t = r.intersect(&ray([1.0, 0.5, 3.0], [0.0, 0.0, -1.0]), f64::INFINITY);
        assert_eq!(t, Some(3.0));
        assert!(
            r.intersect(&ray([2.5, 0.5, 3.0], [0.0, 0.0, -1.0]), f64::INFINITY)
                .is_none()
        );
        // A neighbour sharing the edge x = 2: every ray through the edge hits one.
        let s = Rect::new(DVec3::new(2.0, 0.0, 0.0), DVec3::X, DVec3::Y).unwrap();
        for k in 0..1000 {
            let y = k as f64 / 999.0;
            let rr = ray([2.0 - 0.3, y, 1.0], [0.3, 0.0, -1.0]);
            assert!(r.intersect(&rr, 10.0).is_some() || s.intersect(&rr, 10.0).is_some());
        }
        // Skewed parallelogram: dual coordinates.
        let p = Rect::new(DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0)).unwrap();
        assert!(p.contains_planar(DVec3::new(1.9, 0.95, 0.0)));
        assert!(!p.contains_planar(DVec3::new(0.5, 0.95, 0.0)));
        assert!(Rect::new(DVec3::ZERO, DVec3::X, DVec3::X * 2.0).is_none());
    }

    #[test]
    fn rectangle_and_disc_block_only_segments_through_them() {
        let r = Rect::new(DVec3::ZERO, DVec3::X, DVec3::Y).unwrap();
        let above = DVec3::new(0.5, 0.5, 1.0);
        assert!(r.crosses(above, DVec3::new(0.5, 0.5, -1.0)));
        assert!(!r.crosses(above, DVec3::new(3.0, 0.5, -1.0)));
        // An end point on the rectangle is never shadowed by it.
        assert!(!r.crosses(above, DVec3::new(0.2, 0.3, 0.0)));
        let d = Disc::new(DVec3::ZERO, DVec3::Z, 1.0);
        assert!(d.crosses(above, DVec3::new(0.5, 0.5, -1.0)));
        assert!(!d.crosses(DVec3::new(0.9, 0.9, 1.0), DVec3::new(0.9, 0.9, -1.0)));
        assert!(!d.crosses(above, DVec3::new(0.1, 0.0, 0.0)));
    }

    #[test]
    fn sphere_roots_chords_and_crossings() {
        let s = Sphere {
            c: DVec3::new(1.0, 2.0, 3.0),
            r: 2.0,
        };
        let t = s.intersect(
            &ray([1.0, 2.0, -2.0], [0.0, 0.0, 1.0]),
            f64::INFINITY,
            false,
        );
        assert!((t.unwrap() - 3.0).abs() < 1e-15);
        let t = s.intersect(&ray([1.0, 2.0, 3.0], [0.0, 1.0, 0.0]), f64::INFINITY, false);
        assert!((t.unwrap() - 2.0).abs() < 1e-15);
        // Leaving inward from the bottom: the chord through the centre.
        let t = s.intersect(&ray([1.0, 2.0, 1.0], [0.0, 0.0, 1.0]), f64::INFINITY, true);
        assert!((t.unwrap() - 4.0).abs() < 1e-15);
        assert!(
            s.intersect(&ray([1.0, 2.0, 1.0], [0.0, 0.0, -1.0]), 1e9, true)
                .is_none()
        );
        // Two points on the inside wall always see each other, at any scale.
        for scale in [1e-3, 1.0, 1e4] {
            let s = Sphere {
                c: DVec3::splat(0.3) * scale,
                r: scale,
            };
            let a = s.surface_point(s.c + DVec3::new(0.3, -0.2, 0.9)).0;
            let b = s.surface_point(s.c + DVec3::new(0.3, -0.2, 0.9000001)).0;
            let c = s.surface_point(s.c + DVec3::new(-0.3, 0.5, 0.1)).0;
            assert!(!s.crosses(a, b) && !s.crosses(a, c) && !s.crosses(s.c, c));
            assert!(s.crosses(s.c, s.c + DVec3::X * 2.0 * scale));
            assert!(s.crosses(s.c - DVec3::X * 2.0 * scale, s.c + DVec3::X * 2.0 * scale));
            assert!(!s.crosses(
                s.c + DVec3::new(-2.0, 1.01, 0.0) * scale,
                s.c + DVec3::new(2.0, 1.01, 0.0) * scale
            ));
            // From a point of the outer surface, through the sphere, to outside.
            assert!(s.crosses(s.c + DVec3::X * scale, s.c - DVec3::X * 3.0 * scale));
            assert!(!s.crosses(s.c + DVec3::X * scale, s.c + DVec3::X * 3.0 * scale));
        }
    }

    #[test]
    fn box_exit_faces_entries_and_crossings() {
        let b = AaBox {
            lo: DVec3::ZERO,
            hi: DVec3::new(4.0, 3.0, 2.5),
        };
        // Inside: every ray leaves through some face, also through edges and corners.
        let (t, f) = b
            .intersect(&ray([1.0, 1.0, 1.0], [0.0, 0.0, 1.0]), 1e9, None)
            .unwrap();
        assert_eq!((t, f), (1.5, 5));
        let hit = b.intersect(&ray([1.0, 1.0, 1.0], [3.0, 2.0, 1.5]), 1e9, None);
        assert!(hit.is_some());
        // Leaving the floor upwards: the ceiling; leaving it downwards: nothing.
        let up = b.intersect(&ray([2.0, 2.0, 0.0], [0.1, 0.0, 1.0]), 1e9, Some(4));
        assert_eq!(up.unwrap().1, 5);
        assert!(
            b.intersect(&ray([2.0, 2.0, 0.0], [0.0, 0.0, -1.0]), 1e9, Some(4))
                .is_none()
        );
        // From outside: entry face.
        let (t, f) = b
            .intersect(&ray([-1.0, 1.0, 1.0], [1.0, 0.0, 0.0]), 1e9, None)
            .unwrap();
        assert_eq!((t, f), (1.0, 0));
        assert!(!b.crosses(DVec3::new(0.0, 1.0, 1.0), DVec3::new(4.0, 2.0, 2.5)));
        assert!(b.crosses(DVec3::new(1.0, 1.0, 1.0), DVec3::new(5.0, 1.0, 1.0)));
        assert!(b.crosses(DVec3::new(-1.0, 1.0, 1.0), DVec3::new(5.0, 1.0, 1.0)));
        assert!(!b.crosses(DVec3::new(-1.0, 1.0, 3.0), DVec3::new(5.0, 1.0, 3.0)));
        assert_eq!(b.face_plane(5).n, DVec3::Z);
        assert_eq!(b.face_point(DVec3::new(1.0, 1.0, 2.4999), 5).z, 2.5);
    }
}
