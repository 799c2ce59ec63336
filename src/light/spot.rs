//! A spot light: a point source whose intensity falls off smoothly between
//! an inner and an outer cone about its axis.
//!
//! With `c = cos(theta)` the cosine of the angle to the axis, `c_i` and
//! `c_o` the cosines of the inner and outer half-angles (`c_o <= c_i`),
//!
//! `I(theta) = I0 f(c)`, `f = 1` for `c >= c_i`, `f = 0` for `c <= c_o`,
//! and between them `f = t^2 (3 - 2 t)` with `t = (c - c_o) / (c_i - c_o)`
//! (smoothstep in the cosine: continuous with a continuous slope).
//!
//! Its flux is `Phi = 2 pi I0 [(1 - c_i) + (c_i - c_o) / 2]` \[lm\] (the
//! smoothstep averages 1/2 over `t`). Directions are drawn exactly in
//! proportion to the intensity, so every emitted ray carries `Phi`: the
//! inner cap with probability `(1 - c_i) / [(1 - c_i) + (c_i - c_o)/2]`
//! (`c` uniform there), else the falloff ring with `t` of density
//! `2 t^2 (3 - 2 t)`, i.e. CDF `2 t^3 - t^4`, inverted by Newton steps in a
//! bracket; the azimuth uniform.

use crate::sampling::warp::{Frame, sin_cos_turns};
use glam::DVec3;
use std::f64::consts::PI;

/// A spot light (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    /// Position \[m\].
    pub p: DVec3,
    /// Unit direction of the beam's axis.
    pub axis: DVec3,
    /// Cosine of the inner cone's half-angle.
    pub cos_inner: f64,
    /// Cosine of the outer cone's half-angle (`<= cos_inner`).
    pub cos_outer: f64,
    /// Intensity on the axis \[cd\].
    pub i0: f64,
}

impl Spot {
    /// Narrowest outer half-angle a scene may give \[deg\]: `1 - cos` of
    /// 0.01 degrees is 1.5e-8, resolved to 1e-8 of itself; at 1e-6 degrees
    /// it is rounding alone.
    pub const MIN_OUTER_DEG: f64 = 0.01;

    /// A spot at `p` along `axis` (normalised) with half-angles `inner <=
    /// outer` \[rad\] and axial intensity `i0` \[cd\].
    pub fn new(p: DVec3, axis: DVec3, inner: f64, outer: f64, i0: f64) -> Self {
        Self {
            p,
            axis: axis.normalize(),
            cos_inner: inner.cos(),
            cos_outer: outer.cos().min(inner.cos()),
            i0,
        }
    }

    /// Falloff `f(c)` at the cosine `c` to the axis.
    #[inline]
    pub fn falloff(&self, c: f64) -> f64 {
        if c >= self.cos_inner {
            1.0
        } else if c <= self.cos_outer {
            0.0
        } else {
            let t = (c - self.cos_outer) / (self.cos_inner - self.cos_outer);
            t * t * (3.0 - 2.0 * t)
        }
    }

    /// Intensity \[cd\] towards unit direction `w`.
    #[inline]
    pub fn intensity(&self, w: DVec3) -> f64 {
        self.i0 * self.falloff(self.axis.dot(w))
    }

    /// `Phi / I0` \[sr\]: `2 pi [(1 - c_i) + (c_i - c_o)/2]`.
    fn solid_angle(&self) -> f64 {
        2.0 * PI * ((1.0 - self.cos_inner) + 0.5 * (self.cos_inner - self.cos_outer))
    }

    /// Flux \[lm\].
    pub fn power(&self) -> f64 {
        self.i0 * self.solid_angle()
    }

    /// Density [1/sr] of [`Self::sample`] at unit `w`: `I(w) / Phi`.
    #[inline]
    pub fn pdf(&self, w: DVec3) -> f64 {
        self.falloff(self.axis.dot(w)) / self.solid_angle()
    }

    /// A direction drawn in proportion to the intensity, from `u` (the
    /// cosine and the azimuth) and `u2` (the choice of cap or ring).
    pub fn sample(&self, u: [f64; 2], u2: f64) -> DVec3 {
        let cap = 1.0 - self.cos_inner;
        let ring = 0.5 * (self.cos_inner - self.cos_outer);
        let c = if u2 * (cap + ring) < cap || ring <= 0.0 {
            1.0 - u[0] * cap
        } else {
            self.cos_outer + (self.cos_inner - self.cos_outer) * invert_ring(u[0])
        };
        let s = (1.0 - c * c).max(0.0).sqrt();
        let (sp, cp) = sin_cos_turns(u[1]);
        Frame::from_normal(self.axis).to_world(DVec3::new(s * cp, s * sp, c))
    }
}

/// The `t` in `[0, 1]` with `2 t^3 - t^4 = u`: Newton steps inside a
/// shrinking bracket (bisection when a step leaves it).
fn invert_ring(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    crate::math::roots::bracketed_newton(
        |t| {
            (
                2.0 * t * t * t - t * t * t * t - u,
                6.0 * t * t - 4.0 * t * t * t,
            )
        },
        0.0,
        1.0,
        u.powf(1.0 / 3.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;

    fn spot() -> Spot {
        Spot::new(
            DVec3::new(0.0, 0.0, 3.0),
            DVec3::new(0.3, 0.0, -1.0),
            20f64.to_radians(),
            35f64.to_radians(),
            500.0,
        )
    }

    #[test]
    fn power_is_the_integral_of_the_intensity() {
        for s in [
            spot(),
            Spot::new(DVec3::ZERO, DVec3::Z, 0.0, 60f64.to_radians(), 2.0),
            Spot::new(
                DVec3::ZERO,
                DVec3::Z,
                30f64.to_radians(),
                30f64.to_radians(),
                2.0,
            ),
            Spot::new(DVec3::ZERO, DVec3::Z, PI, PI, 2.0),
        ] {
            // Midpoint rule in cos(theta) about the axis (the intensity
            // depends on it alone).
            let m = 200_000;
            let sum: f64 = (0..m)
                .map(|k| s.i0 * s.falloff(-1.0 + 2.0 * (k as f64 + 0.5) / m as f64))
                .sum::<f64>()
                * 2.0
                / m as f64
                * 2.0
                * PI;
            // A hard edge (inner = outer) costs the midpoint rule up to one
            // cell of the step; the smooth falloff is integrated to 1e-9.
            let tol = if s.cos_inner == s.cos_outer && s.cos_inner > -1.0 {
                2.0 / m as f64 / (1.0 - s.cos_inner)
            } else {
                1e-9
            };
            assert!(
                (s.power() / sum - 1.0).abs() < tol,
                "{} vs {sum}",
                s.power()
            );
        }
        // Inner = outer = 180 degrees: an isotropic point, 4 pi I0.
        let iso = Spot::new(DVec3::ZERO, DVec3::Z, PI, PI, 2.0);
        assert!((iso.power() - 8.0 * PI).abs() < 1e-12);
        assert_eq!(iso.intensity(-DVec3::Z), 2.0);
    }

    #[test]
    fn sampled_cosines_follow_the_intensity_chi_square() {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        let s = spot();
        let mut rng = Philox4x32::new(8, 0);
        let n = 200_000;
        let bins = 40;
        let (lo, hi) = (s.cos_outer, 1.0);
        let mut counts = vec![0.0; bins];
        for _ in 0..n {
            let w = s.sample(rng.next_2d(), rng.next_f64());
            let c = s.axis.dot(w);
            assert!(c >= s.cos_outer - 1e-12, "outside the outer cone: {c}");
            let k = (((c - lo) / (hi - lo)) * bins as f64)
                .floor()
                .clamp(0.0, (bins - 1) as f64);
            counts[k as usize] += 1.0;
        }
        let expected = |f: &dyn Fn(f64) -> f64| -> Vec<f64> {
            (0..bins)
                .map(|k| {
                    let (a, b) = (
                        lo + (hi - lo) * k as f64 / bins as f64,
                        lo + (hi - lo) * (k + 1) as f64 / bins as f64,
                    );
                    let m = 200;
                    (0..m)
                        .map(|i| f(a + (b - a) * (i as f64 + 0.5) / m as f64))
                        .sum::<f64>()
                        * (b - a)
                        / m as f64
                })
                .collect()
        };
        let chi2 = |e: &[f64]| {
            let tot: f64 = e.iter().sum();
            counts
                .iter()
                .zip(e)
                .map(|(o, e)| {
                    let e = e / tot * n as f64;
                    (o - e) * (o - e) / e
                })
                .sum::<f64>()
        };
        let p = |x: f64| 1.0 - ChiSquared::new((bins - 1) as f64).unwrap().cdf(x);
        let right = chi2(&expected(&|c| s.falloff(c)));
        assert!(p(right) > 1e-4, "chi2 {right}");
        // A linear falloff instead of smoothstep is rejected.
        let wrong = chi2(&expected(&|c| {
            ((c - s.cos_outer) / (s.cos_inner - s.cos_outer)).clamp(0.0, 1.0)
        }));
        assert!(p(wrong) < 1e-10, "chi2 {wrong}");
    }

    #[test]
    fn ring_inversion_is_exact() {
        for k in 0..=100 {
            let u = k as f64 / 100.0;
            let t = invert_ring(u);
            assert!(
                (2.0 * t.powi(3) - t.powi(4) - u).abs() < 1e-14,
                "{u} -> {t}"
            );
        }
    }
}
