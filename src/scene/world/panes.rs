//! Glass panes: thin clear rectangles or discs that let light through with
//! a transmittance and mirror the rest of what they do not absorb
//! ([`crate::material::Glass`]).
//!
//! Panes are kept apart from the opaque shapes: they never block a
//! visibility test ([`Scene::visible`], the side masks, the BVH) and are
//! never collision sites. Instead
//!
//! - a segment or ray that crosses panes carries the product of their
//!   transmittances at its incidence angles ([`Scene::pane_transmittance`],
//!   [`Scene::pane_transmittance_ray`]): the local and double local
//!   estimates and the direct term multiply their scores by it;
//! - a light-tracing chain meets the nearest pane before the nearest
//!   opaque surface ([`Scene::next_pane`]) and is mirrored or passed
//!   straight through there ([`crate::chain`]).
//!
//! A ray that starts on a pane's plane (it leaves the pane, or a collision
//! on a coplanar wall, or a portal set in the same opening) does not meet
//! that pane again. A scene without panes pays nothing: every query returns
//! at once.

use super::Scene;
use crate::geometry::shapes::{Disc, Flat, Rect};
use crate::geometry::{Plane, Ray};
use crate::material::Glass;
use glam::DVec3;

/// The flat shape of a pane.
#[derive(Clone, Copy, Debug)]
pub enum PaneShape {
    /// A parallelogram.
    Rect(Rect),
    /// A disc.
    Disc(Disc),
}

/// A glass pane of the compiled scene.
#[derive(Clone, Copy, Debug)]
pub struct Pane {
    /// Its shape.
    pub shape: PaneShape,
    /// Its glass.
    pub glass: Glass,
    /// Its surface index (for names in messages).
    pub surface: u32,
}

impl Pane {
    /// The supporting plane.
    #[inline]
    pub fn plane(&self) -> &Plane {
        match &self.shape {
            PaneShape::Rect(r) => r.plane(),
            PaneShape::Disc(d) => d.plane(),
        }
    }

    /// Whether a point of the pane's plane lies on the pane.
    #[inline]
    pub fn contains(&self, p: DVec3) -> bool {
        self.contains_planar(p)
    }

    #[inline]
    fn contains_planar(&self, p: DVec3) -> bool {
        match &self.shape {
            PaneShape::Rect(r) => r.contains_planar(p),
            PaneShape::Disc(d) => d.contains_planar(p),
        }
    }

    /// Ray parameter of the hit in `(0, t_max)`; a ray starting on the
    /// pane's plane never meets it.
    #[inline]
    fn hit(&self, ray: &Ray, t_max: f64) -> Option<f64> {
        if self.plane().side(ray.o) == 0 {
            return None;
        }
        match &self.shape {
            PaneShape::Rect(r) => r.intersect(ray, t_max),
            PaneShape::Disc(d) => d.intersect(ray, t_max),
        }
    }

    /// Transmittance for a ray of unit direction `d` crossing the pane.
    #[inline]
    pub fn transmittance(&self, d: DVec3) -> f64 {
        self.glass.reflect_transmit(d.dot(self.plane().n)).1
    }

    /// Bounding box \[m\].
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match &self.shape {
            PaneShape::Rect(r) => {
                let c = [r.o, r.o + r.e1, r.o + r.e2, r.o + r.e1 + r.e2];
                let lo = c.iter().fold(DVec3::splat(f64::INFINITY), |a, p| a.min(*p));
                let hi = c
                    .iter()
                    .fold(DVec3::splat(f64::NEG_INFINITY), |a, p| a.max(*p));
                (lo, hi)
            }
            PaneShape::Disc(d) => (d.plane.p - DVec3::splat(d.r), d.plane.p + DVec3::splat(d.r)),
        }
    }
}

/// A pane met by a ray: where, and what it does there.
#[derive(Clone, Copy, Debug)]
pub struct PaneHit {
    /// Ray parameter \[m\].
    pub t: f64,
    /// The point \[m\] (on the pane's plane).
    pub p: DVec3,
    /// Index into the scene's panes.
    pub pane: u32,
}

impl Scene {
    /// Whether the scene has glass panes.
    #[inline]
    pub fn has_panes(&self) -> bool {
        !self.panes.is_empty()
    }

    /// The glass panes.
    pub fn panes(&self) -> &[Pane] {
        &self.panes
    }

    /// Product of the transmittances of the panes the open segment from
    /// `a` to `b` crosses (1 with none). End points on a pane's plane do
    /// not count as crossing it.
    #[inline]
    pub fn pane_transmittance(&self, a: DVec3, b: DVec3) -> f64 {
        if self.panes.is_empty() {
            return 1.0;
        }
        let d = (b - a).normalize_or_zero();
        let mut t = 1.0;
        for pane in &self.panes {
            let crosses = match &pane.shape {
                PaneShape::Rect(r) => r.crosses(a, b),
                PaneShape::Disc(dc) => dc.crosses(a, b),
            };
            if crosses {
                t *= pane.transmittance(d);
            }
        }
        t
    }

    /// Product of the transmittances of the panes the ray from `o` in unit
    /// direction `d` crosses on its way out of the scene (to a light at
    /// infinity). With `through_origin`, a pane whose plane holds `o` and
    /// that holds `o` counts too: a ray started on a portal set in a glazed
    /// opening, traced backwards, has crossed the glass there.
    pub fn pane_transmittance_ray(&self, o: DVec3, d: DVec3, through_origin: bool) -> f64 {
        if self.panes.is_empty() {
            return 1.0;
        }
        let ray = Ray { o, d };
        let mut t = 1.0;
        for pane in &self.panes {
            let on = pane.plane().side(o) == 0;
            let crossed = if on {
                through_origin && pane.contains_planar(o) && d.dot(pane.plane().n) != 0.0
            } else {
                pane.hit(&ray, f64::INFINITY).is_some()
            };
            if crossed {
                t *= pane.transmittance(d);
            }
        }
        t
    }

    /// The nearest pane along `ray` in `(0, t_max)`, if any (a ray starting
    /// on a pane's plane does not meet that pane). Ties go to the lower index.
    #[inline]
    pub fn next_pane(&self, ray: &Ray, t_max: f64) -> Option<PaneHit> {
        let mut best: Option<PaneHit> = None;
        let mut bound = t_max;
        for (k, pane) in self.panes.iter().enumerate() {
            if let Some(t) = pane.hit(ray, bound) {
                bound = t;
                best = Some(PaneHit {
                    t,
                    p: pane.plane().project(ray.o + ray.d * t),
                    pane: k as u32,
                });
            }
        }
        best
    }

    /// The direction a ray of unit direction `d` leaves pane `k` with: the
    /// mirror image if `u < R / (R + T)`, else `d` itself (straight
    /// through), and the weight factor `R + T` that keeps the estimate
    /// unbiased (`None`: the pane absorbs everything at this angle).
    #[inline]
    pub fn pane_scatter(&self, k: u32, d: DVec3, u: f64) -> Option<(DVec3, f64)> {
        let pane = &self.panes[k as usize];
        let n = pane.plane().n;
        let c = d.dot(n);
        let (r, t) = pane.glass.reflect_transmit(c);
        let s = r + t;
        if s <= 0.0 {
            return None;
        }
        let d_out = if u * s < r { d - n * (2.0 * c) } else { d };
        Some((d_out.normalize(), s))
    }
}
