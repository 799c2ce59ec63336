//! Warps from the unit square to directions, each with pdf and inverse.
//!
//! Sampler families in the style of pbrt-v4 (Pharr, Jakob, Humphreys,
//! *Physically Based Rendering*, 4th ed., Sec. A.5): every sampler takes its
//! uniforms explicitly as `u: [f64; 2]` in [0, 1)^2, returns a
//! [`DirectionSample`] carrying its density, and comes with a standalone pdf
//! function and an inverse `invert_*(w) -> u`. All densities are with respect
//! to solid angle, in 1/sr.
use core::f64::consts::{FRAC_1_PI, TAU};
use glam::DVec3;

/// Largest `f64` strictly below 1 (1 - 2^-53); inverses clamp to it so that
/// their results stay in [0, 1).
const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

/// A sampled direction with its pdf [1/sr] (solid-angle measure).
#[derive(Clone, Copy, Debug)]
pub struct DirectionSample {
    /// Unit direction.
    pub w: DVec3,
    /// Density with respect to solid angle [1/sr].
    pub pdf: f64,
}

/// Right-handed orthonormal frame `(s, t, n)` around a unit normal `n`,
/// with `s x t = n`.
///
/// Built branch-free by Duff, Burgess, Christensen, Hery, Kensler, Liani,
/// Villemin, "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017
/// (Listing 3), which fixes the singularity of Frisvad (2012) at
/// `n = (0, 0, -1)` by using `sign(n_z)`.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent (local x axis).
    pub s: DVec3,
    /// Second tangent (local y axis), `t = n x s`.
    pub t: DVec3,
    /// Normal (local z axis).
    pub n: DVec3,
}

impl Frame {
    /// Frame with local z axis `n` (must be unit length).
    ///
    /// With `σ = sign(n_z)` (`±1`, taking the sign bit so `-0.0 -> -1`),
    /// `a = -1 / (σ + n_z)`, `b = n_x n_y a`:
    ///
    /// `s = (1 + σ n_x² a, σ b, -σ n_x)`, `t = (b, σ + n_y² a, -n_y)`.
    ///
    /// Orthonormal to rounding error (~1e-16) for every unit `n`,
    /// including `n = (0, 0, -1)` (Duff et al. 2017).
    #[inline]
    pub fn from_normal(n: DVec3) -> Self {
        let sign = 1.0_f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = DVec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// Local coordinates `(x, y, z)` -> world vector `x s + y t + z n`.
    #[inline]
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    /// World vector -> local coordinates `(v·s, v·t, v·n)`.
    #[inline]
    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

/// `u in [0,1)` -> `2 pi u`, and back with `atan2`, wrapped into [0, 1).
#[inline]
fn phi_to_u(y: f64, x: f64) -> f64 {
    let mut u = y.atan2(x) * (0.5 * FRAC_1_PI);
    if u < 0.0 {
        u += 1.0;
    }
    u.min(ONE_MINUS_EPSILON)
}

/// `(sin 2 pi t, cos 2 pi t)` for `t` in [0, 1], to within 1 ulp.
///
/// Why not `f64::sin_cos`: libm's general argument reduction was a fifth of
/// a chain's cost. Here the quadrant comes from `t` exactly (`t - q/4` is
/// exact), leaving `x` in [-pi/4, pi/4] where Taylor series to `x^15` (sine)
/// and `x^16` (cosine) are accurate to below 1e-16.
#[inline]
pub fn sin_cos_turns(t: f64) -> (f64, f64) {
    let q = (4.0 * t).round();
    let x = (t - 0.25 * q) * TAU;
    let x2 = x * x;
    let s = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0
                    + x2 * (-1.0 / 5040.0
                        + x2 * (1.0 / 362_880.0
                            + x2 * (-1.0 / 39_916_800.0
                                + x2 * (1.0 / 6_227_020_800.0
                                    + x2 * (-1.0 / 1_307_674_368_000.0))))))));
    let c = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0
                    + x2 * (1.0 / 40_320.0
                        + x2 * (-1.0 / 3_628_800.0
                            + x2 * (1.0 / 479_001_600.0
                                + x2 * (-1.0 / 87_178_291_200.0
                                    + x2 * (1.0 / 20_922_789_888_000.0))))))));
    match (q as i64) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Uniform direction on the unit sphere S²; pdf `1/(4 pi)` [1/sr].
///
/// Archimedes' map: `z = 1 - 2 u0`, `φ = 2 π u1`,
/// `w = (r cos φ, r sin φ, z)` with `r = sqrt(1 - z²) = 2 sqrt(u0 (1 - u0))`
/// (the latter form avoids cancellation near the poles). Area-preserving up
/// to the factor 4π, so the density is constant (pbrt-v4 `SampleUniformSphere`).
#[inline]
pub fn sample_uniform_sphere(u: [f64; 2]) -> DirectionSample {
    let z = 1.0 - 2.0 * u[0];
    let r = 2.0 * (u[0] * (1.0 - u[0])).max(0.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u[1]);
    DirectionSample {
        w: DVec3::new(r * cos_phi, r * sin_phi, z),
        pdf: uniform_sphere_pdf(),
    }
}

/// Density of [`sample_uniform_sphere`]: `1/(4 pi)` [1/sr].
#[inline]
pub fn uniform_sphere_pdf() -> f64 {
    0.25 * FRAC_1_PI
}

/// Inverse of [`sample_uniform_sphere`]: `u0 = (1 - z)/2`,
/// `u1 = atan2(y, x) / (2 π)` wrapped into [0, 1).
///
/// `w` must be unit length. At the poles (`x = y = 0`) `φ` is undefined and
/// `u1 = 0` is returned. Results are clamped to [0, 1).
#[inline]
pub fn invert_uniform_sphere(w: DVec3) -> [f64; 2] {
    let u0 = (0.5 * (1.0 - w.z)).clamp(0.0, ONE_MINUS_EPSILON);
    [u0, phi_to_u(w.y, w.x)]
}

/// Cosine-weighted direction on the hemisphere z > 0 of the local frame
/// (z up; map to world with [`Frame::to_world`]); pdf `cos θ / π` [1/sr].
///
/// Malley's method with the direct polar map of the unit disk:
/// `r = sqrt(u0)`, `φ = 2 π u1`, `w = (r cos φ, r sin φ, sqrt(1 - u0))`.
/// The disk point is uniform (density 1/π per unit area); projecting it up
/// onto the hemisphere multiplies the density by `cos θ` (Pharr et al.,
/// pbrt-v4 Sec. A.5.3, which uses the concentric map instead; the polar map
/// is chosen here because its inverse is elementary and exact).
#[inline]
pub fn sample_cosine_hemisphere(u: [f64; 2]) -> DirectionSample {
    let r = u[0].sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u[1]);
    let z = (1.0 - u[0]).max(0.0).sqrt();
    DirectionSample {
        w: DVec3::new(r * cos_phi, r * sin_phi, z),
        pdf: cosine_hemisphere_pdf(z),
    }
}

/// Density of [`sample_cosine_hemisphere`]: `max(cos θ, 0) / π` [1/sr],
/// where `cos_theta` is the local z coordinate of the direction.
/// Zero for directions below the hemisphere, which are never sampled.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f64) -> f64 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Inverse of [`sample_cosine_hemisphere`] (local frame, z up):
/// `u0 = r² = (x² + y²) / |w|²`, `u1 = atan2(y, x) / (2 π)` in [0, 1).
///
/// Dividing by `|w|²` makes the result insensitive to small
/// normalisation errors in `w`. A direction with `z < 0` is inverted as its
/// mirror image `(x, y, -z)`. At the pole `u1 = 0`. Results are clamped to
/// [0, 1).
#[inline]
pub fn invert_cosine_hemisphere(w: DVec3) -> [f64; 2] {
    let rho2 = w.x * w.x + w.y * w.y;
    let u0 = (rho2 / (rho2 + w.z * w.z)).clamp(0.0, ONE_MINUS_EPSILON);
    [u0, phi_to_u(w.y, w.x)]
}

/// Direction on the whole unit sphere with density proportional to
/// `1 + cos θ` about the local z axis (a cardioid lobe, the response of a
/// hemispherical receiver); pdf `(1 + cos θ) / (4 pi)` [1/sr].
///
/// `cos θ` has the density `(1 + c) / 2` on [-1, 1], whose distribution
/// function `((1 + c) / 2)^2` inverts to `c = 2 sqrt(u0) - 1`; `φ = 2 π u1`.
#[inline]
pub fn sample_cardioid_sphere(u: [f64; 2]) -> DirectionSample {
    let h = u[0].sqrt();
    let z = 2.0 * h - 1.0;
    // sin θ = sqrt((1 - z)(1 + z)) = 2 sqrt(h (1 - h)), free of cancellation.
    let r = 2.0 * (h * (1.0 - h)).max(0.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u[1]);
    DirectionSample {
        w: DVec3::new(r * cos_phi, r * sin_phi, z),
        pdf: cardioid_sphere_pdf(z),
    }
}

/// Density of [`sample_cardioid_sphere`]: `(1 + cos θ) / (4 pi)` [1/sr],
/// `cos_theta` the local z coordinate of the direction.
#[inline]
pub fn cardioid_sphere_pdf(cos_theta: f64) -> f64 {
    (1.0 + cos_theta.clamp(-1.0, 1.0)) * 0.25 * FRAC_1_PI
}

/// Inverse of [`sample_cardioid_sphere`]: `u0 = ((1 + z) / 2)^2`,
/// `u1 = atan2(y, x) / (2 π)` in [0, 1); clamped to [0, 1).
#[inline]
pub fn invert_cardioid_sphere(w: DVec3) -> [f64; 2] {
    let h = 0.5 * (1.0 + w.z.clamp(-1.0, 1.0));
    [(h * h).clamp(0.0, ONE_MINUS_EPSILON), phi_to_u(w.y, w.x)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_turns_matches_libm() {
        let mut worst: f64 = 0.0;
        for i in 0..=200_000 {
            let t = i as f64 / 200_000.0;
            let (s, c) = sin_cos_turns(t);
            let (s0, c0) = (TAU * t).sin_cos();
            worst = worst.max((s - s0).abs()).max((c - c0).abs());
        }
        // Within a few ulps of 1, including libm's own rounding of 2 pi t.
        assert!(worst < 4.0 * f64::EPSILON, "{worst:e}");
        assert_eq!(sin_cos_turns(0.0), (0.0, 1.0));
        assert!(sin_cos_turns(0.25).1.abs() < 1e-16);
    }
    use crate::sampling::Philox4x32;
    use core::f64::consts::PI;

    /// Cell-centred grid of `n x n` points of the open unit square, plus
    /// points close to its edges.
    fn grid(n: usize) -> Vec<[f64; 2]> {
        let mut v: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
        v.extend([1e-9, 1e-6, 0.25, 0.5, 0.75, 1.0 - 1e-6, 1.0 - 1e-9]);
        let mut g = Vec::new();
        for &a in &v {
            for &b in &v {
                g.push([a, b]);
            }
        }
        g
    }

    #[test]
    fn uniform_sphere_roundtrip_and_record() {
        for u in grid(64) {
            let ds = sample_uniform_sphere(u);
            assert!((ds.w.length() - 1.0).abs() < 1e-14, "{u:?}");
            assert_eq!(ds.pdf, uniform_sphere_pdf());
            let v = invert_uniform_sphere(ds.w);
            assert!(
                (v[0] - u[0]).abs() < 1e-12 && (v[1] - u[1]).abs() < 1e-12,
                "{u:?} -> {v:?}"
            );
        }
        assert!((uniform_sphere_pdf() * 4.0 * PI - 1.0).abs() < 1e-15);
    }

    #[test]
    fn cardioid_sphere_roundtrip_and_record() {
        for u in grid(64) {
            let ds = sample_cardioid_sphere(u);
            assert!((ds.w.length() - 1.0).abs() < 1e-14, "{u:?}");
            assert!((ds.pdf - (1.0 + ds.w.z) / (4.0 * PI)).abs() < 1e-15);
            let v = invert_cardioid_sphere(ds.w);
            assert!(
                (v[0] - u[0]).abs() < 1e-9 && (v[1] - u[1]).abs() < 1e-12,
                "{u:?} -> {v:?}"
            );
        }
    }

    #[test]
    fn cosine_hemisphere_roundtrip_and_record() {
        for u in grid(64) {
            let ds = sample_cosine_hemisphere(u);
            assert!((ds.w.length() - 1.0).abs() < 1e-14, "{u:?}");
            assert!(ds.w.z > 0.0);
            assert!((ds.pdf - ds.w.z / PI).abs() < 1e-15);
            let v = invert_cosine_hemisphere(ds.w);
            assert!(
                (v[0] - u[0]).abs() < 1e-12 && (v[1] - u[1]).abs() < 1e-12,
                "{u:?} -> {v:?}"
            );
        }
    }

    #[test]
    fn corners_give_valid_directions_and_inverses_stay_in_range() {
        for u in [
            [0.0, 0.0],
            [0.0, 0.999],
            [ONE_MINUS_EPSILON, ONE_MINUS_EPSILON],
        ] {
            for ds in [sample_uniform_sphere(u), sample_cosine_hemisphere(u)] {
                assert!(ds.w.is_finite() && (ds.w.length() - 1.0).abs() < 1e-14);
                assert!(ds.pdf.is_finite() && ds.pdf >= 0.0);
            }
        }
        let dirs = [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(1.0, -1e-300, 0.0),
            DVec3::new(1.0, -0.0, 0.0),
        ];
        for w in dirs {
            for v in [invert_uniform_sphere(w), invert_cosine_hemisphere(w)] {
                assert!(v.iter().all(|x| (0.0..1.0).contains(x)), "{w:?} -> {v:?}");
            }
        }
        assert_eq!(cosine_hemisphere_pdf(-0.5), 0.0);
    }

    fn check_frame(n: DVec3) {
        let f = Frame::from_normal(n);
        let tol = 1e-14;
        assert!((f.s.length() - 1.0).abs() < tol, "{n:?}");
        assert!((f.t.length() - 1.0).abs() < tol, "{n:?}");
        assert!(f.s.dot(f.t).abs() < tol, "{n:?}");
        assert!(f.s.dot(f.n).abs() < tol, "{n:?}");
        assert!(f.t.dot(f.n).abs() < tol, "{n:?}");
        // Right-handed: s x t = n.
        assert!((f.s.cross(f.t) - f.n).length() < tol, "{n:?}");
        // Round trip through the frame.
        let v = DVec3::new(0.3, -0.7, 0.2);
        assert!((f.to_local(f.to_world(v)) - v).length() < tol);
        assert!((f.to_world(DVec3::Z) - n).length() < tol);
    }

    #[test]
    fn frame_orthonormal_right_handed() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(1e-9, -2e-9, -1.0).normalize(),
            DVec3::new(-1e-5, 1e-5, -1.0).normalize(),
            DVec3::new(1e-3, 0.0, -1.0).normalize(),
            DVec3::new(0.0, 1e-8, 1.0).normalize(),
            DVec3::X,
            -DVec3::Y,
            DVec3::new(1.0, 1.0, 1e-300).normalize(),
            DVec3::new(1.0, 1.0, -1e-300).normalize(),
        ] {
            check_frame(n);
        }
        // Equator normal with a negative-zero z: copysign picks sign = -1.
        check_frame(DVec3::new(1.0, 0.0, -0.0));
        let mut rng = Philox4x32::new(0xF4A3E, 0);
        for _ in 0..10_000 {
            check_frame(sample_uniform_sphere(rng.next_2d()).w);
        }
    }
}
