//! Directions in a cone of half-angle `alpha` about the local `+z` axis:
//! uniform per solid angle, or cosine-weighted (density proportional to
//! `cos theta` about the axis). Each family takes explicit uniforms and has
//! a pdf [1/sr] and an inverse (pbrt-v4 `SampleUniformCone`,
//! `UniformConePDF`, `InvertUniformConeSample`, Sec. A.5.4). The cone is
//! given by `sin alpha` and `cos alpha`, so that a tiny cone (the sun's
//! 0.27 degrees) keeps its digits: `1 - cos alpha` is never formed.

use super::warp::{DirectionSample, sin_cos_turns};
use core::f64::consts::PI;
use glam::DVec3;

/// Largest `f64` strictly below 1.
const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

/// Solid angle \[sr\] of the cone, `2 pi (1 - cos alpha) = 2 pi sin^2 / (1 + cos)`.
#[inline]
pub fn cone_solid_angle(sin_a: f64, cos_a: f64) -> f64 {
    2.0 * PI * sin_a * sin_a / (1.0 + cos_a)
}

/// Uniform direction in the cone: `1 - cos theta = u0 (1 - cos alpha)`,
/// `phi = 2 pi u1`; pdf `1 / Omega` [1/sr].
#[inline]
pub fn sample_uniform_cone(u: [f64; 2], sin_a: f64, cos_a: f64) -> DirectionSample {
    // 1 - cos theta without cancellation.
    let one_minus = u[0] * sin_a * sin_a / (1.0 + cos_a);
    let ct = 1.0 - one_minus;
    let st = (one_minus * (2.0 - one_minus)).max(0.0).sqrt();
    let (sp, cp) = sin_cos_turns(u[1]);
    DirectionSample {
        w: DVec3::new(st * cp, st * sp, ct),
        pdf: 1.0 / cone_solid_angle(sin_a, cos_a),
    }
}

/// Density of [`sample_uniform_cone`] at local `w` [1/sr]: `1 / Omega`
/// inside the cone (`w.z >= cos alpha`), 0 outside.
#[inline]
pub fn uniform_cone_pdf(w: DVec3, sin_a: f64, cos_a: f64) -> f64 {
    if w.z >= cos_a {
        1.0 / cone_solid_angle(sin_a, cos_a)
    } else {
        0.0
    }
}

/// Inverse of [`sample_uniform_cone`] for a unit local `w` in the cone.
#[inline]
pub fn invert_uniform_cone(w: DVec3, sin_a: f64, cos_a: f64) -> [f64; 2] {
    let s2 = w.x * w.x + w.y * w.y;
    // 1 - cos theta = s2 / (1 + cos theta).
    let one_minus = s2 / (1.0 + w.z);
    let u0 = (one_minus * (1.0 + cos_a) / (sin_a * sin_a)).clamp(0.0, ONE_MINUS_EPSILON);
    [u0, phi_u(w)]
}

/// Cosine-weighted direction in the cone: `sin^2 theta = u0 sin^2 alpha`,
/// `phi = 2 pi u1`; pdf `cos theta / (pi sin^2 alpha)` [1/sr] (the flux
/// through a plane normal to the axis of a cone of uniform luminance is
/// distributed so).
#[inline]
pub fn sample_cosine_cone(u: [f64; 2], sin_a: f64) -> DirectionSample {
    let st = sin_a * u[0].sqrt();
    let ct = (1.0 - st * st).max(0.0).sqrt();
    let (sp, cp) = sin_cos_turns(u[1]);
    DirectionSample {
        w: DVec3::new(st * cp, st * sp, ct),
        pdf: ct / (PI * sin_a * sin_a),
    }
}

/// Density of [`sample_cosine_cone`] at local `w` [1/sr] (0 outside).
#[inline]
pub fn cosine_cone_pdf(w: DVec3, sin_a: f64, cos_a: f64) -> f64 {
    if w.z >= cos_a {
        w.z / (PI * sin_a * sin_a)
    } else {
        0.0
    }
}

/// Inverse of [`sample_cosine_cone`] for a unit local `w` in the cone.
#[inline]
pub fn invert_cosine_cone(w: DVec3, sin_a: f64) -> [f64; 2] {
    let s2 = w.x * w.x + w.y * w.y;
    [
        (s2 / (sin_a * sin_a)).clamp(0.0, ONE_MINUS_EPSILON),
        phi_u(w),
    ]
}

fn phi_u(w: DVec3) -> f64 {
    let mut u = w.y.atan2(w.x) / (2.0 * PI);
    if u < 0.0 {
        u += 1.0;
    }
    u.clamp(0.0, ONE_MINUS_EPSILON)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_samplers_invert_and_stay_inside() {
        for deg in [0.265_f64, 5.0, 30.0, 60.0] {
            let a = deg.to_radians();
            let (sa, ca) = a.sin_cos();
            for i in 0..50 {
                let u = [(i as f64 + 0.3) / 50.0, (i * 17 % 50) as f64 / 50.0 + 0.01];
                for (s, inv) in [
                    (sample_uniform_cone(u, sa, ca), 0),
                    (sample_cosine_cone(u, sa), 1),
                ] {
                    assert!((s.w.length() - 1.0).abs() < 1e-14);
                    assert!(s.w.z >= ca - 1e-15, "{deg}: {}", s.w.z);
                    let back = if inv == 0 {
                        invert_uniform_cone(s.w, sa, ca)
                    } else {
                        invert_cosine_cone(s.w, sa)
                    };
                    assert!((back[0] - u[0]).abs() < 1e-9, "{deg} {inv}: {back:?} {u:?}");
                    assert!((back[1] - u[1]).abs() < 1e-9);
                    let pdf = if inv == 0 {
                        uniform_cone_pdf(s.w, sa, ca)
                    } else {
                        cosine_cone_pdf(s.w, sa, ca.min(s.w.z))
                    };
                    assert!((pdf / s.pdf - 1.0).abs() < 1e-12);
                }
            }
        }
    }

    /// Both densities integrate to 1 over the cone (midpoint rule in cos theta).
    #[test]
    fn cone_densities_are_normalised() {
        for deg in [0.265_f64, 10.0, 45.0] {
            let a = deg.to_radians();
            let (sa, ca) = a.sin_cos();
            let m = 20_000;
            let (mut iu, mut ic) = (0.0, 0.0);
            for i in 0..m {
                let ct = ca + (1.0 - ca) * (i as f64 + 0.5) / m as f64;
                let w = DVec3::new((1.0 - ct * ct).sqrt(), 0.0, ct);
                let dw = 2.0 * PI * (1.0 - ca) / m as f64;
                iu += uniform_cone_pdf(w, sa, ca) * dw;
                ic += cosine_cone_pdf(w, sa, ca) * dw;
            }
            assert!((iu - 1.0).abs() < 1e-6, "{deg}: {iu}");
            assert!((ic - 1.0).abs() < 1e-6, "{deg}: {ic}");
        }
    }
}
