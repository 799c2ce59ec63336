//! A distant (directional) light: the sun, parallel light of illuminance
//! `E_n` \[lx\] on a plane normal to its direction, from a point at infinity
//! (zero angular diameter) or from a disc of angular diameter `2 alpha` and
//! uniform luminance `L = E_n / (pi sin^2 alpha)` [cd/m^2] (the sun: 0.53
//! degrees).
//!
//! **Direction**: `d` is the unit direction in which the light *travels*
//! (from the sun towards the scene; the sun at the zenith has `d = -z`).
//!
//! **Where chains start.** The light crosses every plane normal to `d`
//! with the same flux density, so chains start on the plane `P` normal to
//! `d` through a centre `c`, with a density `p_s` per area over `P`, and
//! carry `E_n / p_s` \[lm\] each (then divided by the light's pick
//! probability); every chain's line is followed from upstream of
//! everything it can meet, so the first surface is met exactly where the
//! light lands. The estimate is unbiased if `p_s > 0` wherever a line can
//! meet a surface ([`StartRegion`]):
//!
//! - a scene of **finite shapes** lies in a ball (centre `c`, radius `r0`):
//!   lines through `P` farther than `r0 / cos alpha` from `c` miss it (a line
//!   in the cone crosses `P` within `r0 / cos alpha` of `c` when it passes
//!   within `r0` of it), so the start points are uniform on that disc and
//!   every chain carries the disc's flux `E_n pi R^2`;
//! - a scene with **infinite planes** is unbounded: every line meets them.
//!   There the start points cover the plane `P` out to `rho_max = 1e6 a`
//!   with the density `p_s(rho) ~ a / (2 pi (rho^2 + a^2)^(3/2))` of the
//!   distance `rho` from `c` (normalised within `rho_max`; drawn as `rho = a
//!   sqrt(v (2 - v)) / (1 - v)`, `v = u F(rho_max)`; 29 % of the chains start
//!   within `a` of `c`, 90 % within `10 a`). Light landing beyond `rho_max`
//!   is left out: into a receiver at distance `h` from a plane it is at
//!   most about `h / (rho_max - |p - c|)` of what that plane reflects there
//!   ([`StartRegion::TRUNCATION`]). A chain starting far out carries a
//!   large weight, `E_n / p_s ~ rho^3`, but its first collision scores into
//!   a receiver at distance `d ~ rho` through the kernel `cos_x cos_p / d^2
//!   <= h / d^3` (`cos_x = h / d`), so first-order scores stay bounded:
//!   on a single plane the error bars are calibrated (`tests/distant_light.rs`).
//!   (The density `a^2 / (pi (rho^2 + a^2)^2)` was tried first: its weights
//!   `~ rho^4` make even first-order scores grow like `d` into a receiver
//!   that faces along the plane.) **Limitation**: light reflected again
//!   (by a second, non-parallel plane or a finite shape standing on the
//!   plane) reaches a receiver from a far start with probability `~
//!   rho^-3` and then scores `~ rho^3`: the variance diverges with
//!   `rho_max` and finite runs read low with error bars too small
//!   (measured on a floor and a wall against their closed form:
//!   0-13 standard errors low over 16 seeds). [`StartRegion::note`] warns;
//!   the backward estimator, which starts at the receivers and reaches the
//!   light by next-event estimation, is calibrated there.
//!   The centre and scale `(c, a)` are fitted to
//!   the finite shapes, the planes' points and, when known, the receivers
//!   ([`crate::scene::Scene::fit_directional`]).
//!
//! The chains' pick weight ([`Distant::power`]) is the disc's flux `E_n pi
//! R^2` in a bounded scene (the light's real power into the scene) and the
//! nominal flux `E_n pi a^2` in an unbounded one (whose real power is
//! infinite).

use crate::sampling::cone::{cone_solid_angle, cosine_cone_pdf, sample_cosine_cone};
use crate::sampling::warp::{Frame, sin_cos_turns};
use glam::DVec3;
use std::f64::consts::PI;

/// Where the chains of a distant or environment light start (see the
/// module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct StartRegion {
    /// Centre \[m\] of the start plane's density.
    pub c: DVec3,
    /// Radius \[m\] of a ball holding every finite shape (bounded scenes),
    /// or of the region the density is fitted to (unbounded scenes).
    pub r0: f64,
    /// Scale `a` \[m\] of the unbounded density (`r0`, or 1 m when `r0 = 0`).
    pub a: f64,
    /// Whether the scene has infinite planes.
    pub unbounded: bool,
    /// Whether the scene has finite shapes.
    pub has_finite: bool,
    /// Truncation radius \[m\] of the unbounded density, `TRUNCATION a`
    /// (infinite: none).
    pub rho_max: f64,
    /// The infinite planes, as unit normal `n` and offset `n . p` \[m\].
    pub planes: Vec<(DVec3, f64)>,
    /// The scene's portals: chains start on them instead
    /// ([`super::portal`]); `None`: no portals.
    pub portals: Option<std::sync::Arc<super::portal::Portals>>,
    /// The light's flux \[lm\] through the portals, unobstructed (its pick
    /// weight with portals; set with them by [`super::Light::set_region`]).
    pub portal_flux: f64,
}

impl StartRegion {
    /// The region of a scene whose finite shapes lie in the box `finite`
    /// (`None`: no finite shape), with infinite `planes` (unit normal, a
    /// point), fitted also to `points` \[m\] (the receivers; used only when
    /// there are planes).
    pub fn fit(
        finite: Option<(DVec3, DVec3)>,
        planes: &[(DVec3, DVec3)],
        points: &[DVec3],
    ) -> Self {
        let unbounded = !planes.is_empty();
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut add = |p: DVec3| {
            lo = lo.min(p);
            hi = hi.max(p);
        };
        if let Some((a, b)) = finite {
            add(a);
            add(b);
        }
        if unbounded {
            planes.iter().for_each(|&(_, p)| add(p));
            points.iter().for_each(|&p| add(p));
        }
        let (c, r0) = if lo.x.is_finite() {
            ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
        } else {
            (DVec3::ZERO, 0.0)
        };
        Self {
            c,
            r0,
            a: if r0 > 0.0 { r0 } else { 1.0 },
            unbounded,
            has_finite: finite.is_some(),
            rho_max: Self::truncation() * if r0 > 0.0 { r0 } else { 1.0 },
            planes: planes.iter().map(|&(n, p)| (n, n.dot(p))).collect(),
            portals: None,
            portal_flux: 0.0,
        }
    }

    /// Truncation of the unbounded density in units of `a`: `1e6`. Light
    /// landing farther than `rho_max = 1e6 a` from `c` is left out; into a
    /// receiver at distance `h` from a plane it would bring at most about
    /// `h / (rho_max - |p - c|)` of the light that plane reflects there
    /// (the cosine-weighted share of the view within `h / rho` of the
    /// plane's horizon), below 1e-5 for receivers within `1e3 a` of `c` at
    /// `h <= 10 a`. (At `1e3 a` the open-floor test measured the truncation:
    /// a receiver facing the horizon read 3e-4 low, one standard error.)
    pub const TRUNCATION: f64 = 1e6;

    /// [`Self::TRUNCATION`].
    pub fn truncation() -> f64 {
        Self::TRUNCATION
    }

    /// A note for the run summary: the truncation and its bound, and a
    /// warning where the scores are heavy-tailed (see the module docs).
    pub fn note(&self) -> Option<String> {
        if !self.unbounded {
            return None;
        }
        let mut s = format!(
            "chains start on a plane across the light, density ~ 1/rho^3 around ({:.4e}, {:.4e}, {:.4e}) m with scale {:.4e} m, truncated at rho = {:.4e} m: light landing beyond is left out, at most about h / (rho_max - |p - c|) of what a plane at distance h reflects into a receiver at p",
            self.c.x, self.c.y, self.c.z, self.a, self.rho_max
        );
        let parallel = self
            .planes
            .iter()
            .all(|(n, _)| n.cross(self.planes[0].0).length() < 1e-9);
        if !parallel || self.has_finite {
            s.push_str(
                "; WARNING: with non-parallel infinite planes, or finite shapes on an infinite plane, light from far out reaches the receivers through rare heavy-weight chains: the error bars are not reliable (measured on a floor and a wall: runs 0-13 standard errors low); use --estimator backward (paths from the receivers, next-event estimation from the light: calibrated there), or bound the ground by a finite rectangle",
            );
        }
        Some(s)
    }

    /// Radius \[m\] of the disc whose area holds one chain start at the
    /// start density next to `p`: `1 / sqrt(pi p_s)`, with `p_s` the
    /// density at `p`'s distance from the centre `c` (bounded: the start
    /// disc's radius `r0`; unbounded: `sqrt(2 (rho^2 + a^2)^(3/2) / a)`,
    /// `sqrt(2) a` at the centre). The counterpart for a light at infinity
    /// of a point light's distance, which sets how densely chains collide
    /// around `p` ([`crate::estimator::near_need`]). `None` with portals
    /// (chains start on them: the room sets the scale).
    pub fn start_scale(&self, p: DVec3) -> Option<f64> {
        if self.portals.is_some() {
            return None;
        }
        if !self.unbounded {
            return Some(if self.r0 > 0.0 { self.r0 } else { self.a });
        }
        let q = (p - self.c).length_squared() + self.a * self.a;
        Some((2.0 * q * q.sqrt() / self.a).sqrt())
    }

    /// Probability mass of the untruncated density within `rho_max`.
    #[inline]
    fn mass(&self) -> f64 {
        if self.rho_max.is_finite() {
            1.0 - self.a / (self.rho_max * self.rho_max + self.a * self.a).sqrt()
        } else {
            1.0
        }
    }

    /// Radius \[m\] of the start disc of a bounded scene for a cone of
    /// half-angle `alpha` (`cos_a = cos alpha`).
    #[inline]
    pub fn disc_radius(&self, cos_a: f64) -> f64 {
        // Without finite shapes nothing can be hit: any disc does (the unit
        // one keeps the pick weight, which direct-light sampling uses, > 0).
        if self.r0 > 0.0 {
            self.r0 / cos_a
        } else {
            self.a
        }
    }

    /// Area [m^2] whose flux is the chains' pick weight: the start disc's
    /// (bounded) or `pi a^2` (unbounded).
    pub fn nominal_area(&self, cos_a: f64) -> f64 {
        if self.unbounded {
            PI * self.a * self.a
        } else {
            PI * self.disc_radius(cos_a).powi(2)
        }
    }

    /// A start point on the plane through `c` normal to `frame.n`, drawn
    /// from `u`, with its density per area [1/m^2].
    #[inline]
    pub fn sample_point(&self, frame: &Frame, cos_a: f64, u: [f64; 2]) -> (DVec3, f64) {
        let (sp, cp) = sin_cos_turns(u[1]);
        if self.unbounded {
            let a = self.a;
            let v = u[0] * self.mass();
            let rho = a * (v * (2.0 - v)).sqrt() / (1.0 - v);
            (
                self.c + frame.to_world(DVec3::new(rho * cp, rho * sp, 0.0)),
                self.point_pdf_unbounded(rho * rho),
            )
        } else {
            let r = self.disc_radius(cos_a);
            let rho = r * u[0].sqrt();
            (
                self.c + frame.to_world(DVec3::new(rho * cp, rho * sp, 0.0)),
                1.0 / (PI * r * r),
            )
        }
    }

    /// The unbounded density at squared distance `rho2` [m^2] from `c`.
    #[inline]
    fn point_pdf_unbounded(&self, rho2: f64) -> f64 {
        if rho2 > self.rho_max * self.rho_max {
            return 0.0;
        }
        let q = rho2 + self.a * self.a;
        self.a / (2.0 * PI * q * q.sqrt() * self.mass())
    }

    /// Density per area [1/m^2] of [`Self::sample_point`] at `s` on the plane.
    pub fn point_pdf(&self, s: DVec3, cos_a: f64) -> f64 {
        let rho2 = (s - self.c).length_squared();
        if self.unbounded {
            self.point_pdf_unbounded(rho2)
        } else {
            let r = self.disc_radius(cos_a);
            if rho2 <= r * r {
                1.0 / (PI * r * r)
            } else {
                0.0
            }
        }
    }

    /// Where the line through `s` along unit `w` must start so that it
    /// meets every surface on it ahead: upstream of the ball of finite
    /// shapes and of every crossing with an infinite plane (one more `a`
    /// upstream, in empty space).
    #[inline]
    pub fn upstream(&self, s: DVec3, w: DVec3) -> DVec3 {
        let mut t0 = -((s - self.c).length() + self.r0);
        for &(n, off) in &self.planes {
            let nw = n.dot(w);
            if nw.abs() > 1e-300 {
                t0 = t0.min((off - n.dot(s)) / nw);
            }
        }
        s + w * (t0 - self.a)
    }
}

/// A distant light (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Distant {
    /// Unit direction the light travels [-].
    pub d: DVec3,
    /// Illuminance on a plane normal to `d` \[lx\].
    pub e_n: f64,
    /// `sin alpha`, `alpha` the half of the angular diameter (0: a point at infinity).
    pub sin_a: f64,
    /// `cos alpha`.
    pub cos_a: f64,
    /// Where chains start.
    pub region: StartRegion,
}

impl Distant {
    /// A distant light travelling along unit `d` with normal illuminance
    /// `e_n` \[lx\] and angular diameter `diameter` \[rad\] (0: a point).
    pub fn new(d: DVec3, e_n: f64, diameter: f64, region: StartRegion) -> Self {
        let (sin_a, cos_a) = (0.5 * diameter).sin_cos();
        Self {
            d,
            e_n,
            sin_a,
            cos_a,
            region,
        }
    }

    /// Largest angular diameter \[deg\] accepted (a half-angle of 45 degrees).
    pub const MAX_DIAMETER_DEG: f64 = 90.0;

    /// Check what the light relies on: a unit, finite direction, a finite
    /// illuminance `>= 0` and a half-angle in [0, 45] degrees.
    pub fn check(&self) -> Result<(), String> {
        if !(self.d.is_finite() && (self.d.length() - 1.0).abs() < 1e-9) {
            return Err("direction must be a finite unit vector".into());
        }
        if !(self.e_n.is_finite() && self.e_n >= 0.0) {
            return Err(format!(
                "illuminance must be finite and >= 0 [lx], got {:e}",
                self.e_n
            ));
        }
        let max_sin = (0.5 * Self::MAX_DIAMETER_DEG).to_radians().sin() * (1.0 + 1e-12);
        if !(self.sin_a >= 0.0 && self.sin_a <= max_sin && self.cos_a > 0.0) {
            return Err(format!(
                "angular diameter must lie in [0, {}] degrees",
                Self::MAX_DIAMETER_DEG
            ));
        }
        Ok(())
    }

    /// Whether the light comes from a single direction (zero diameter).
    #[inline]
    pub fn collimated(&self) -> bool {
        self.sin_a == 0.0
    }

    /// Luminance of the solar disc [cd/m^2], `E_n / (pi sin^2 alpha)`
    /// (0 for a point at infinity, which is never seen).
    pub fn luminance(&self) -> f64 {
        if self.collimated() {
            0.0
        } else {
            self.e_n / (PI * self.sin_a * self.sin_a)
        }
    }

    /// Solid angle of the disc \[sr\] (0 for a point).
    pub fn solid_angle(&self) -> f64 {
        cone_solid_angle(self.sin_a, self.cos_a)
    }

    /// Whether unit `wi` (towards the light) lies in the disc.
    #[inline]
    pub fn in_cone(&self, wi: DVec3) -> bool {
        !self.collimated() && -wi.dot(self.d) >= self.cos_a
    }

    /// The chains' pick weight \[lm\] (see the module docs).
    pub fn power(&self) -> f64 {
        if self.region.portals.is_some() {
            return self.region.portal_flux;
        }
        self.e_n * self.region.nominal_area(self.cos_a)
    }

    /// The flux \[lm\] the light sends through `portals`, unobstructed (the
    /// disc counted as collimated along its axis).
    pub fn flux_through(&self, portals: &super::portal::Portals) -> f64 {
        portals.flux(std::iter::once((-self.d, self.e_n, 1.0)))
    }

    /// Unoccluded illuminance \[lx\] on a receiver with unit normal `n`:
    /// `E_n max(0, n . -d)` for a point; for a disc `L int_cone max(0, n .
    /// w) dw`, which is `E_n n . -d` above the horizon and integrated
    /// exactly where the horizon cuts the disc.
    pub fn direct_illuminance(&self, n: DVec3) -> f64 {
        let c = -n.dot(self.d);
        if self.collimated() {
            self.e_n * c.max(0.0)
        } else {
            self.luminance() * super::sphere_cone_integral(self.sin_a, c)
        }
    }

    /// An emitted ray: a start point from `u_pos` (see [`StartRegion`]), a
    /// direction cosine-weighted in the cone from `u_dir` (ignored for a
    /// point at infinity), started upstream of everything.
    pub fn sample_emission(&self, u_pos: [f64; 2], u_dir: [f64; 2]) -> super::EmissionSample {
        let frame = Frame::from_normal(self.d);
        let (w, le, cos, pdf_dir) = if self.collimated() {
            (self.d, self.e_n, 1.0, 1.0)
        } else {
            let ds = sample_cosine_cone(u_dir, self.sin_a);
            (frame.to_world(ds.w), self.luminance(), ds.w.z, ds.pdf)
        };
        // With portals the ray starts on one, carrying the illuminance
        // (collimated) or luminance (a disc) across it; else upstream of
        // everything on the plane across the beam.
        let (o, pdf_pos, phi) = match &self.region.portals {
            Some(portals) => portals.emission(w, le, pdf_dir, u_pos),
            None => {
                let (s, pdf_pos) = self.region.sample_point(&frame, self.cos_a, u_pos);
                (self.region.upstream(s, w), pdf_pos, self.e_n / pdf_pos)
            }
        };
        super::EmissionSample {
            o,
            d: w,
            le,
            cos,
            pdf_pos,
            pdf_dir,
            delta_pos: false,
            delta_dir: self.collimated(),
            phi,
        }
    }

    /// Density [1/sr] of the emitted directions at world `w`.
    pub fn direction_pdf(&self, w: DVec3) -> f64 {
        cosine_cone_pdf(
            Frame::from_normal(self.d).to_local(w),
            self.sin_a,
            self.cos_a,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z).normalize()
    }

    /// The emission record's flux equals `le cos / (pdf_pos pdf_dir)` and
    /// the mean flux per unit of the start plane's area is `E_n`: over a
    /// disc of the plane, `E[phi 1(s in disc)] = E_n pi r^2`.
    #[test]
    fn emission_records_and_flux_density() {
        for (unbounded, diam) in [
            (false, 0.0),
            (false, 0.53_f64.to_radians()),
            (true, 0.0),
            (true, 0.2),
        ] {
            let planes = if unbounded {
                vec![(DVec3::Z, DVec3::ZERO)]
            } else {
                vec![]
            };
            let region = StartRegion::fit(
                Some((DVec3::new(-1.0, -2.0, 0.0), DVec3::new(3.0, 1.0, 2.0))),
                &planes,
                &[],
            );
            let l = Distant::new(unit(0.3, -0.2, -1.0), 1.0e5, diam, region);
            let n = 200_000;
            let (mut sum, mut sum2) = (0.0, 0.0);
            let r_test = 1.5;
            for k in 0..n {
                let u = [(k as f64 + 0.5) / n as f64, (k as f64 * 0.618_034).fract()];
                let e = l.sample_emission(u, [u[1], u[0]]);
                let w = e.le * e.cos / (e.pdf_pos * e.pdf_dir);
                assert!((w / e.phi - 1.0).abs() < 1e-9, "{w} vs {}", e.phi);
                // The line's crossing of the start plane.
                let t = (l.region.c - e.o).dot(l.d) / e.d.dot(l.d);
                let s = e.o + e.d * t;
                assert!((s - l.region.c).dot(l.d).abs() < 1e-6 * (1.0 + (s - l.region.c).length()));
                let inside = if (s - l.region.c).length() < r_test {
                    1.0
                } else {
                    0.0
                };
                sum += e.phi * inside;
                sum2 += (e.phi * inside).powi(2);
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
            let want = 1.0e5 * PI * r_test * r_test;
            // Stratified in u0: far tighter than 5 se in practice.
            assert!(
                (mean - want).abs() < 5.0 * se + 1e-9 * want,
                "{unbounded} {diam}: {mean} vs {want} (se {se})"
            );
        }
    }

    #[test]
    fn start_points_lie_upstream_of_planes_and_finite_shapes() {
        let planes = vec![
            (DVec3::Z, DVec3::ZERO),
            (-DVec3::Z, DVec3::new(0.0, 0.0, 3.0)),
        ];
        let region = StartRegion::fit(Some((DVec3::splat(-1.0), DVec3::splat(1.0))), &planes, &[]);
        let l = Distant::new(unit(1.0, 0.0, -0.05), 1.0, 0.0, region);
        for k in 0..1000 {
            let u = [(k as f64 + 0.5) / 1000.0, (k as f64 * 0.754_877).fract()];
            let e = l.sample_emission(u, u);
            // Every plane crossing lies ahead of the origin.
            for &(n, off) in &l.region.planes {
                let t = (off - n.dot(e.o)) / n.dot(e.d);
                assert!(t > 0.0, "plane crossing behind the start: {t}");
            }
            assert!((e.o - l.region.c).dot(e.d) < -l.region.r0);
        }
    }

    #[test]
    fn direct_illuminance_closed_forms() {
        let region = StartRegion::fit(None, &[], &[]);
        let p = Distant::new(-DVec3::Z, 1.0e5, 0.0, region.clone());
        for deg in [0.0_f64, 30.0, 60.0, 89.0, 95.0] {
            let n = DVec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
            let want = 1.0e5 * deg.to_radians().cos().max(0.0);
            assert!((p.direct_illuminance(n) - want).abs() <= 1e-10 * 1.0e5);
        }
        // A disc above the horizon gives E_n cos exactly; on the horizon half.
        let s = Distant::new(-DVec3::Z, 1.0e5, 0.53_f64.to_radians(), region);
        let n = unit(0.5, 0.0, 1.0);
        assert!((s.direct_illuminance(n) / (1.0e5 * n.z) - 1.0).abs() < 1e-12);
        let e_h = s.direct_illuminance(DVec3::X);
        // On the horizon: int over the half disc of L cos, = L * (2/3) sin^3 alpha (small alpha).
        let want = s.luminance() * 2.0 / 3.0 * s.sin_a.powi(3);
        assert!((e_h / want - 1.0).abs() < 1e-4, "{e_h} vs {want}");
    }
}
