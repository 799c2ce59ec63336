//! Geometry: shapes, ray intersection and visibility. No radiometry here.
//!
//! Orientation rule: every surface has a front side, the side its normal
//! faces. Light arriving on the front side is reflected by the surface's
//! material; the back side is black (a perfect absorber). Every surface is
//! opaque from both sides.

pub mod bvh;
pub mod mesh;
pub mod mesh_core;
pub mod mesh_parity;
pub mod mesh_view;
pub mod polygon;
pub mod sh;
pub mod shapes;

use glam::DVec3;

/// A ray `o + t d`, `t > 0`, with unit direction `d`.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin \[m\].
    pub o: DVec3,
    /// Unit direction.
    pub d: DVec3,
}

/// Where a ray meets a surface.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the ray \[m\].
    pub t: f64,
    /// Hit point \[m\], on the surface.
    pub p: DVec3,
    /// Unit normal of the surface's front side.
    pub n: DVec3,
    /// Index of the surface in the compiled scene.
    pub surface: u32,
    /// Primitive within the surface (a mesh's triangle; 0 otherwise).
    pub prim: u32,
}

/// An infinite plane `n . x = c`, front side towards `n`.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    /// A point of the plane \[m\].
    pub p: DVec3,
    /// Unit normal (front side).
    pub n: DVec3,
    /// Offset `n . p` \[m\].
    pub c: f64,
}

/// Relative tolerance for deciding that a point lies on a plane.
///
/// Why: a point written by the user on a plane (z = 1.0 exactly, say) or a
/// hit point projected onto it has a signed distance of a few ulps of its
/// coordinates; anything within this band counts as "on" the plane, so a
/// plane never shadows points on itself, at any scene scale.
pub(crate) const ON_PLANE_REL: f64 = 1e-11;

impl Plane {
    /// Plane through `p` with normal direction `n` (normalised here; must be non-zero).
    pub fn new(p: DVec3, n: DVec3) -> Self {
        let n = n.normalize();
        Self { p, n, c: n.dot(p) }
    }

    /// Signed distance of `q` from the plane \[m\], positive on the front side.
    #[inline]
    pub fn signed_distance(&self, q: DVec3) -> f64 {
        self.n.dot(q - self.p)
    }

    /// Which side `q` is on: +1 front, -1 back, 0 on the plane (within tolerance).
    #[inline]
    pub fn side(&self, q: DVec3) -> i8 {
        let s = self.signed_distance(q);
        let tol = ON_PLANE_REL * (q.abs().max_element() + self.p.abs().max_element());
        if s > tol {
            1
        } else if s < -tol {
            -1
        } else {
            0
        }
    }

    /// Ray parameter of the intersection, if it lies in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        let dn = self.n.dot(ray.d);
        if dn == 0.0 {
            return None;
        }
        let t = -self.signed_distance(ray.o) / dn;
        (t > 0.0 && t < t_max).then_some(t)
    }

    /// Project `q` onto the plane.
    #[inline]
    pub fn project(&self, q: DVec3) -> DVec3 {
        q - self.n * self.signed_distance(q)
    }
}

/// Occlusion by a set of planes, as bit masks (at most 64 planes).
///
/// A segment between `a` and `b` is blocked by a plane exactly when `a` and
/// `b` lie strictly on opposite sides of it. Each point gets two masks (planes
/// it is strictly in front of / behind); `a` and `b` see each other when no
/// plane has them on opposite sides: `(front_a & back_b) | (back_a & front_b) == 0`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SideMask {
    /// Bit i set: strictly in front of plane i.
    pub front: u64,
    /// Bit i set: strictly behind plane i.
    pub back: u64,
}

impl SideMask {
    /// Masks of point `q` against `planes` (at most 64).
    pub fn of(q: DVec3, planes: &[Plane]) -> Self {
        debug_assert!(planes.len() <= 64);
        let mut m = SideMask::default();
        for (i, pl) in planes.iter().enumerate() {
            match pl.side(q) {
                1 => m.front |= 1 << i,
                -1 => m.back |= 1 << i,
                _ => {}
            }
        }
        m
    }

    /// True when no plane separates the two points.
    #[inline]
    pub fn sees(self, other: SideMask) -> bool {
        (self.front & other.back) | (self.back & other.front) == 0
    }
}

/// The unit vector along `v` \[any unit\], or `None` where `v` is zero or
/// not finite. Lengths whose square leaves the `f64` range (1e-170, 1e200)
/// are scaled by the largest component first, so they give their direction
/// rather than a zero or NaN vector; others are normalised as they are
/// (`v.normalize()`, the same bits).
pub fn unit_direction(v: DVec3) -> Option<DVec3> {
    if !v.is_finite() {
        return None;
    }
    let len = v.length();
    let u = if (1e-150..1e150).contains(&len) {
        v.normalize()
    } else {
        let m = v.abs().max_element();
        if m == 0.0 {
            return None;
        }
        (v / m).normalize()
    };
    u.is_finite().then_some(u)
}

/// Whether the closed segment from `a` to `b` meets the box `[lo, hi]`
/// (the slab test over `t` in `[0, 1]`).
pub fn segment_meets_box(a: DVec3, b: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k] == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (ta, tb) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    t0 <= t1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Any non-zero finite length gives its direction, with the bits of
    /// `normalize` in the ordinary range; zero and non-finite give `None`.
    #[test]
    fn unit_direction_of_any_length() {
        let d = DVec3::new(0.3, -1.2, 0.7);
        assert_eq!(unit_direction(d), Some(d.normalize()));
        for s in [1e-300, 1e-170, 1e160, 1e300] {
            let u = unit_direction(d * s).unwrap();
            assert!((u - d.normalize()).length() < 1e-15, "{s}: {u}");
        }
        assert_eq!(unit_direction(DVec3::new(0.0, 0.0, 1e-320)), Some(DVec3::Z));
        assert_eq!(unit_direction(DVec3::ZERO), None);
        assert_eq!(unit_direction(DVec3::new(f64::INFINITY, 0.0, 0.0)), None);
        assert_eq!(unit_direction(DVec3::new(f64::NAN, 0.0, 1.0)), None);
    }

    #[test]
    fn plane_intersection_and_sides() {
        let pl = Plane::new(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.0, -2.0));
        assert_eq!(pl.n, DVec3::new(0.0, 0.0, -1.0));
        let ray = Ray {
            o: DVec3::ZERO,
            d: DVec3::new(0.0, 0.6, 0.8),
        };
        let t = pl.intersect(&ray, f64::INFINITY).unwrap();
        assert!((t - 1.25).abs() < 1e-15);
        assert!(
            pl.intersect(
                &Ray {
                    o: DVec3::ZERO,
                    d: -ray.d
                },
                f64::INFINITY
            )
            .is_none()
        );
        assert_eq!(pl.side(DVec3::ZERO), 1);
        assert_eq!(pl.side(DVec3::new(5.0, 3.0, 1.0)), 0);
        assert_eq!(pl.side(DVec3::new(0.0, 0.0, 2.0)), -1);
    }

    #[test]
    fn masks_block_only_across_a_plane() {
        let planes = [
            Plane::new(DVec3::ZERO, DVec3::Z),
            Plane::new(DVec3::new(0.0, 0.0, 1.0), -DVec3::Z),
        ];
        let on_floor = SideMask::of(DVec3::new(3.0, 0.0, 0.0), &planes);
        let on_ceiling = SideMask::of(DVec3::new(-1.0, 2.0, 1.0), &planes);
        let middle = SideMask::of(DVec3::new(0.0, 0.0, 0.5), &planes);
        let below = SideMask::of(DVec3::new(0.0, 0.0, -0.5), &planes);
        assert!(on_floor.sees(on_ceiling));
        assert!(middle.sees(on_ceiling));
        assert!(!below.sees(middle));
        assert!(!below.sees(on_ceiling));
        assert!(below.sees(on_floor));
    }
}
