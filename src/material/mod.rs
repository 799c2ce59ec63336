//! Materials: BRDF evaluation, sampling and albedo in the local frame.
//!
//! Directions `wi`, `wo` are unit vectors pointing away from the surface, in
//! the local frame whose z axis is the front normal; the BRDF `f_r` is in
//! [1/sr]. Sampling densities are per solid angle [1/sr].

mod glass;

pub use glass::{FLOAT_GLASS_INDEX, Glass};

use crate::math::quadrature::{CompensatedSum, panel};
use crate::sampling::warp::{
    DirectionSample, Frame, cosine_hemisphere_pdf, sample_cosine_hemisphere, sin_cos_turns,
};
use glam::DVec3;
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4};

/// Largest `f64` strictly below 1 (1 - 2^-53): rescaled uniforms are clamped
/// to it so that they stay in [0, 1).
const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

/// A material (closed set).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Ideal diffuse reflector with reflectance `rho` in [0, 1]: `f_r = rho / pi`.
    Lambertian { rho: f64 },
    /// Energy-conserving normalised ("modified") Phong BRDF of Lafortune and
    /// Willems, "Using the modified Phong reflectance model for physically
    /// based rendering", Tech. Rep. CW 197, KU Leuven, 1994:
    ///
    /// `f_r(wi, wo) = kd / pi + ks (n + 2) / (2 pi) cos^n(alpha)`
    ///
    /// for `wi.z > 0` and `wo.z > 0` (zero otherwise), where `alpha` is the
    /// angle between `wo` and the mirror direction `r = (-wi.x, -wi.y, wi.z)`
    /// of `wi`, so `cos alpha = wo . r = wi.z wo.z - wi.x wo.x - wi.y wo.y`
    /// (symmetric in `wi`, `wo`: the BRDF is reciprocal). The specular term
    /// is zero where `cos alpha <= 0` (its lobe is the hemisphere around `r`;
    /// this only matters for `n = 0`, where `0^0` would otherwise be 1).
    ///
    /// Requirements (checked by the scene compiler): `kd, ks >= 0`,
    /// `kd + ks <= 1`, `n >= 0` finite. Then the directional-hemispherical
    /// reflectance is at most `kd + ks <= 1` (see [`Material::albedo`]).
    Phong {
        /// Diffuse reflectance (dimensionless).
        kd: f64,
        /// Specular reflectance at normal incidence (dimensionless).
        ks: f64,
        /// Phong exponent (dimensionless); larger is sharper.
        n: f64,
    },
    /// A thin clear pane ([`Glass`]): light passes straight through or is
    /// mirrored, both specularly, so it has no BRDF value for any pair of
    /// directions (`eval`, `albedo`, `pdf` are 0 and `sample` returns a zero
    /// pdf). Panes are not collision sites: the scene keeps them apart from
    /// the opaque shapes ([`crate::scene::Scene::pane_transmittance`]) and
    /// chains and paths cross or leave them by [`Glass::reflect_transmit`].
    Glass(Glass),
}

/// `cos alpha = wo . r(wi)` with `r(wi) = (-wi.x, -wi.y, wi.z)`, the cosine
/// between `wo` and the mirror direction of `wi` about the normal.
///
/// Written as `wi.z wo.z - wi.x wo.x - wi.y wo.y`: swapping `wi` and `wo`
/// swaps the factors of each (exactly rounded, commutative) product and keeps
/// the order of the sums, so the result is bit-for-bit symmetric.
#[inline]
fn cos_to_mirror(wi: DVec3, wo: DVec3) -> f64 {
    wi.z * wo.z - wi.x * wo.x - wi.y * wo.y
}

/// Density of the normalised Phong lobe around the mirror direction:
/// `(n + 1) / (2 pi) cos^n(alpha)` for `cos alpha > 0`, else 0 [1/sr].
///
/// It integrates to 1 over the hemisphere around `r`:
/// `int_0^{pi/2} (n + 1) cos^n(a) sin(a) da = 1`.
#[inline]
fn phong_lobe_pdf(cos_alpha: f64, n: f64) -> f64 {
    if cos_alpha > 0.0 {
        (n + 1.0) * (0.5 * FRAC_1_PI) * cos_alpha.powf(n)
    } else {
        0.0
    }
}

/// Probability of picking the diffuse lobe in [`Material::sample`] for the
/// Phong material: `kd / (kd + ks)`, and 1 for a black material
/// (`kd + ks = 0`; any choice is then exact because `f_r = 0`).
#[inline]
fn diffuse_probability(kd: f64, ks: f64) -> f64 {
    let t = kd + ks;
    if t > 0.0 { kd / t } else { 1.0 }
}

/// Sample the normalised Phong lobe around the unit mirror direction `r`:
/// density `(n + 1) / (2 pi) cos^n(alpha)` [1/sr] on the hemisphere around `r`.
///
/// Inversion of the marginal CDF `F(cos alpha) = cos^(n+1)(alpha)`:
/// `cos alpha = u0^(1/(n+1))`, `phi = 2 pi u1` in the frame
/// [`Frame::from_normal`]`(r)` (Lafortune and Willems 1994, Sec. 4; pbrt-v3
/// Sec. 14.1). `cos alpha = exp(l)` and `sin^2 alpha = -expm1(2 l)` with
/// `l = ln(u0) / (n + 1)` avoid the cancellation in `1 - cos^2 alpha` for
/// sharp lobes. Returns the direction only; the caller computes the pdf.
#[inline]
fn sample_phong_lobe(r: DVec3, n: f64, u: [f64; 2]) -> DVec3 {
    let l = u[0].ln() / (n + 1.0);
    let cos_a = l.exp();
    let sin_a = (-(2.0 * l).exp_m1()).clamp(0.0, 1.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u[1]);
    Frame::from_normal(r).to_world(DVec3::new(sin_a * cos_phi, sin_a * sin_phi, cos_a))
}

/// Directional-hemispherical reflectance of the normalised Phong specular
/// term alone (`kd = 0`, `ks = 1`) for incidence cosine `c = wi.z`, without
/// the final clamp to 1 of [`Material::albedo`]:
///
/// `A(c) = (n + 2) / (2 pi) int_{wo.z > 0, cos alpha > 0} cos^n(alpha) wo.z dwo`.
///
/// Reduction (derived for this project). In polar coordinates `(alpha, phi)`
/// around the mirror direction, `wo.z = cos(alpha) c + sin(alpha) s cos(phi)`
/// with `s = sin(theta_i)`; the `phi` integral of `max(wo.z, 0)` is
/// elementary (`2 pi cos(alpha) c` while `alpha <= pi/2 - theta_i`, else
/// `2 (a phi0 + sqrt(b^2 - a^2))` with `a = c cos alpha`, `b = s sin alpha`,
/// `phi0 = arccos(-a/b)`). Substituting `cos alpha = s sin psi`, integrating
/// the `arccos` term by parts and writing `x = pi/2 - psi` gives
///
/// `A(c) = c + s^(n+2) / pi * int_0^{pi/2} cos^n(x) sin^2(x) / (c^2 + s^2 sin^2 x) dx`,
///
/// a positive integrand without cancellation. Checks: `A(1) = 1` (normal
/// incidence: the normalisation of Lafortune-Willems); `n = 0` gives
/// `A = (1 + c)/2` in closed form; `A(0+) = W_n / pi` with the Wallis
/// integral `W_n = int_0^{pi/2} cos^n x dx`; for a sharp lobe `A -> c`.
/// `A <= 1` for every `c`: both `cos^n alpha` (on `alpha < pi/2`) and the
/// clamped cosine are non-increasing functions of the angle to their axes, so
/// by the spherical rearrangement inequality (Baernstein and Taylor, Duke
/// Math. J. 43, 1976) their product integrates to its maximum when the axes
/// coincide, i.e. at normal incidence.
///
/// Quadrature: composite 20-point Gauss-Legendre
/// ([`crate::math::quadrature::panel`]). The integrand has features at
/// the scales `x ~ c/s` (the factor `sin^2 x / (c^2 + s^2 sin^2 x)`, whose
/// poles are at `sin x = +-i c/s`) and `x ~ 1/sqrt(n)` (the `cos^n` peak),
/// both at `x = 0`, so `[0, pi/4]` is split into panels `[2^-(k+1), 2^-k] pi/4`
/// graded geometrically down to below `min(c, 1/sqrt(n + 1)) / 8` (at most 64
/// levels), plus the panel `[0, 2^-K pi/4]`; each panel then sees its nearest
/// singularity at least one panel width away (error ~ 5.8^-40 per panel).
/// Near `pi/2`, `cos^n x ~ (pi/2 - x)^n` is not smooth for non-integer `n`:
/// `[pi/4, pi/2]` is split into `[pi/4, 3pi/8]`, `[3pi/8, 7pi/16]` and
/// `[7pi/16, pi/2]`, and on the last the substitution
/// `x = pi/2 - (pi/16) t^8` turns the singularity into `t^(8n+7)` (with the
/// Jacobian), which one 20-point panel integrates with relative error
/// ~ 20^-(16n+16) (< 1e-20 for every `n >= 0`); the short end panel keeps
/// the poles near `x = 0` far from `t = 1` (at `|t| >= 8^(1/8) = 1.3`).
/// Measured accuracy: within 3e-15 of an independently graded 2^12-panel
/// reference for `c` in [1e-3, 1) and `n` in [0, 1e4] (unit test
/// `phong_albedo_quadrature_converged` asserts 1e-13), and exact closed
/// forms (`n = 0`, `c = 1`, grazing `W_n / pi`) to 1e-13. Leaving out
/// `[0, 2^-64 pi/4]` would change `A` by less than 1e-19, so the cap of 64
/// levels keeps this accuracy for every `c > 0` and `n < 1e36`.
pub fn phong_specular_albedo(c: f64, n: f64) -> f64 {
    if c.is_nan() || c <= 0.0 {
        return 0.0;
    }
    let c = c.min(1.0);
    // s^2 = (1 - c)(1 + c) keeps its relative accuracy near c = 1.
    let s2 = (1.0 - c) * (1.0 + c);
    let s_pow = s2.powf(0.5 * (n + 2.0));
    // The correction term is at most s^(n+2) W_n / pi <= s^(n+2) / 2.
    if s_pow < 1e-17 * c {
        return c;
    }
    let c2 = c * c;
    let g = |x: f64| {
        let (sx, cx) = x.sin_cos();
        let sx2 = sx * sx;
        cx.powf(n) * sx2 / (c2 + s2 * sx2)
    };
    let scale = c.min(1.0 / (n + 1.0).sqrt());
    let levels = ((FRAC_PI_4 / scale).log2().ceil() as i64 + 3).clamp(1, 64) as i32;
    let mut sum = CompensatedSum::default();
    let mut hi = FRAC_PI_4;
    for _ in 0..levels {
        let lo = 0.5 * hi;
        sum.add(panel(&g, lo, hi));
        hi = lo;
    }
    sum.add(panel(&g, 0.0, hi));
    // [pi/4, 7 pi/16] plainly, [7 pi/16, pi/2] with x = pi/2 - d t^8,
    // d = pi/16, dx = 8 d t^7 dt.
    let d = FRAC_PI_4 / 4.0;
    sum.add(panel(&g, FRAC_PI_4, FRAC_PI_2 - 2.0 * d));
    sum.add(panel(&g, FRAC_PI_2 - 2.0 * d, FRAC_PI_2 - d));
    let h = |t: f64| {
        let t2 = t * t;
        let t4 = t2 * t2;
        let t7 = t4 * t2 * t;
        g(FRAC_PI_2 - d * t7 * t) * 8.0 * d * t7
    };
    sum.add(panel(&h, 0.0, 1.0));
    c + s_pow * sum.total() * FRAC_1_PI
}

impl Material {
    /// BRDF value [1/sr] for local directions (z along the front normal).
    ///
    /// Lambertian: `rho / pi`; Phong: `kd / pi + ks (n + 2)/(2 pi) cos^n(alpha)`
    /// (see [`Material::Phong`]). Zero unless `wi.z > 0` and `wo.z > 0`.
    #[inline]
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> f64 {
        let front = wi.z > 0.0 && wo.z > 0.0;
        if !front {
            return 0.0;
        }
        match *self {
            Material::Lambertian { rho } => rho * FRAC_1_PI,
            Material::Phong { kd, ks, n } => {
                let cos_a = cos_to_mirror(wi, wo);
                let spec = if cos_a > 0.0 && ks > 0.0 {
                    ks * (n + 2.0) * (0.5 * FRAC_1_PI) * cos_a.powf(n)
                } else {
                    0.0
                };
                kd * FRAC_1_PI + spec
            }
            Material::Glass(_) => 0.0,
        }
    }

    /// Directional-hemispherical reflectance for light from `wi`
    /// (dimensionless): `int_{wo.z > 0} f_r(wi, wo) wo.z dwo`.
    ///
    /// Lambertian: `rho` (for every `wi`, as before). Phong:
    /// `kd + ks A(wi.z)` with the specular albedo `A` of
    /// [`phong_specular_albedo`] (a 1-D reduction evaluated by graded
    /// Gauss-Legendre quadrature, absolute error < 1e-13), clamped to 1 to
    /// absorb rounding (exactly, `A <= 1` with equality only at normal
    /// incidence, so the albedo is at most `kd + ks <= 1`); 0 for
    /// `wi.z <= 0`. Costs a few hundred transcendental evaluations: not for
    /// per-collision hot loops.
    pub fn albedo(&self, wi: DVec3) -> f64 {
        match *self {
            Material::Lambertian { rho } => rho,
            Material::Phong { kd, ks, n } => {
                if wi.z.is_nan() || wi.z <= 0.0 {
                    return 0.0;
                }
                let spec = if ks > 0.0 {
                    ks * phong_specular_albedo(wi.z, n)
                } else {
                    0.0
                };
                (kd + spec).min(1.0)
            }
            Material::Glass(_) => 0.0,
        }
    }

    /// `f_r` when it does not depend on directions (Lambertian), for hot
    /// loops; `None` for Phong (evaluate [`Material::eval`] per direction).
    #[inline]
    pub fn constant_brdf(&self) -> Option<f64> {
        match *self {
            Material::Lambertian { rho } => Some(rho * FRAC_1_PI),
            Material::Phong { .. } => None,
            Material::Glass(_) => Some(0.0),
        }
    }

    /// Whether this is the Lambertian material (direction-independent BRDF).
    #[inline]
    pub fn is_lambertian(&self) -> bool {
        matches!(self, Material::Lambertian { .. })
    }

    /// Sample an outgoing local direction for light arriving from `wi`;
    /// `pdf` is per solid angle [1/sr] and equals [`Material::pdf`]`(wi, w)`,
    /// so the caller's weight `f_r(wi, w) w.z / pdf` is unbiased.
    ///
    /// Lambertian: cosine-weighted hemisphere
    /// ([`sample_cosine_hemisphere`]`(u)`, unchanged).
    ///
    /// Phong: one-sample lobe mixture (pbrt-v3 Sec. 14.1.2 style). With
    /// `P_d = kd / (kd + ks)` (1 if `kd + ks = 0`): if `u0 < P_d` the diffuse
    /// lobe is sampled with `u = (u0 / P_d, u1)`, else the specular lobe
    /// ([`Material::Phong`], density `(n + 1)/(2 pi) cos^n alpha` around the
    /// mirror direction, `cos alpha = u'^(1/(n+1))`) with
    /// `u = ((u0 - P_d) / (1 - P_d), u1)`; the rescaled `u0` is uniform on
    /// [0, 1) given the branch (clamped to `1 - 2^-53`). The returned pdf is
    /// the full mixture density `P_d cos(theta)/pi + (1 - P_d) (n + 1)/(2 pi)
    /// cos^n alpha`, not the density of the branch taken.
    ///
    /// Below the horizon: the specular lobe around `r` reaches below the
    /// surface when `wi` is oblique, so a returned `w` may have `w.z <= 0`
    /// (with its mixture pdf, > 0). `f_r = 0` there, so the caller's weight
    /// is 0; terminating the walk on `w.z <= 0` is therefore exactly the
    /// unbiased estimator (a light-tracing walk loses that probability mass
    /// as absorption, which is what the BRDF's energy loss at grazing angles
    /// means). The pdf can be 0 only on the rim of the specular lobe
    /// (rescaled `u0 = 0` gives `cos alpha = 0`; with `kd = 0` or below the
    /// horizon nothing else contributes), an event of probability <= 2^-53
    /// where `cos^n alpha` underflows; callers stop on `pdf <= 0` (as
    /// `chain` does).
    #[inline]
    pub fn sample(&self, wi: DVec3, u: [f64; 2]) -> DirectionSample {
        match *self {
            Material::Lambertian { .. } => sample_cosine_hemisphere(u),
            Material::Phong { kd, ks, n } => {
                let pd = diffuse_probability(kd, ks);
                let w = if u[0] < pd {
                    let u0 = (u[0] / pd).min(ONE_MINUS_EPSILON);
                    sample_cosine_hemisphere([u0, u[1]]).w
                } else {
                    let u0 = ((u[0] - pd) / (1.0 - pd)).clamp(0.0, ONE_MINUS_EPSILON);
                    let r = DVec3::new(-wi.x, -wi.y, wi.z);
                    sample_phong_lobe(r, n, [u0, u[1]])
                };
                DirectionSample {
                    w,
                    pdf: self.pdf(wi, w),
                }
            }
            Material::Glass(_) => DirectionSample {
                w: DVec3::Z,
                pdf: 0.0,
            },
        }
    }

    /// Density [1/sr] with which [`Material::sample`] returns `wo` given
    /// `wi`, over the whole sphere of directions.
    ///
    /// Lambertian: `max(wo.z, 0) / pi`. Phong:
    /// `P_d max(wo.z, 0) / pi + (1 - P_d) (n + 1)/(2 pi) cos^n(alpha)` for
    /// `cos alpha > 0` (second term 0 otherwise), `P_d = kd / (kd + ks)`;
    /// it integrates to 1 over the sphere and to the probability of landing
    /// above the horizon (`<= 1`) over `wo.z > 0`.
    #[inline]
    pub fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match *self {
            Material::Lambertian { .. } => cosine_hemisphere_pdf(wo.z),
            Material::Phong { kd, ks, n } => {
                let pd = diffuse_probability(kd, ks);
                let spec = if pd < 1.0 {
                    (1.0 - pd) * phong_lobe_pdf(cos_to_mirror(wi, wo), n)
                } else {
                    0.0
                };
                pd * cosine_hemisphere_pdf(wo.z) + spec
            }
            Material::Glass(_) => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;
    use crate::sampling::warp::sample_uniform_sphere;
    use std::f64::consts::PI;

    fn dir(theta: f64, phi: f64) -> DVec3 {
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        DVec3::new(st * cp, st * sp, ct)
    }

    /// Reference for [`phong_specular_albedo`]: the same 1-D integral by
    /// 2^12 uniform 20-point panels on [0, pi/2] (the features at x ~ c and
    /// x ~ 1/sqrt(n) are resolved for c >= 1e-3, n <= 1e4), the last one
    /// graded geometrically (60 levels) towards the endpoint singularity
    /// `(pi/2 - x)^n` instead of the substitution used in the code.
    fn albedo_reference(c: f64, n: f64) -> f64 {
        let s2 = 1.0 - c * c;
        let g = |x: f64| {
            let (sx, cx) = x.sin_cos();
            cx.powf(n) * sx * sx / (c * c + s2 * sx * sx)
        };
        let m = 1 << 12;
        let h = FRAC_PI_2 / m as f64;
        let mut sum = CompensatedSum::default();
        for k in 0..m - 1 {
            sum.add(panel(&g, k as f64 * h, (k + 1) as f64 * h));
        }
        let mut d = h;
        for _ in 0..60 {
            sum.add(panel(&g, FRAC_PI_2 - d, FRAC_PI_2 - 0.5 * d));
            d *= 0.5;
        }
        c + s2.powf(0.5 * (n + 2.0)) * sum.total() / PI
    }

    #[test]
    fn phong_albedo_quadrature_converged() {
        let mut worst: f64 = 0.0;
        for n in [0.0, 0.1, 0.5, 1.0, 1.5, 2.0, 7.3, 20.0, 200.0, 1000.0, 1e4] {
            for c in [1e-3, 0.01, 0.05, 0.2, 0.5, 0.8, 0.99, 0.999_999] {
                let a = phong_specular_albedo(c, n);
                let r = albedo_reference(c, n);
                worst = worst.max((a - r).abs());
                assert!((a - r).abs() < 1e-13, "n {n} c {c}: {a} vs {r}");
                assert!(a <= 1.0 + 1e-15, "n {n} c {c}: {a}");
            }
        }
        eprintln!("worst albedo quadrature error {worst:e}");
    }

    #[test]
    fn phong_albedo_closed_forms() {
        // n = 0: A = (1 + c)/2 exactly.
        for c in [1e-12, 1e-6, 0.01, 0.3, 0.7, 1.0 - 1e-12, 1.0] {
            let a = phong_specular_albedo(c, 0.0);
            assert!((a - 0.5 * (1.0 + c)).abs() < 1e-14, "c {c}: {a}");
        }
        // Normal incidence: exactly 1 for every n.
        for n in [0.0, 1.0, 20.0, 1e3, 1e8] {
            assert_eq!(phong_specular_albedo(1.0, n), 1.0);
        }
        // Grazing limit: W_n / pi, with W_1 = 1, W_2 = pi/4, W_3 = 2/3.
        for (n, w) in [(1.0, 1.0), (2.0, PI / 4.0), (3.0, 2.0 / 3.0)] {
            let a = phong_specular_albedo(1e-15, n);
            assert!((a - w / PI).abs() < 1e-13, "n {n}: {a} vs {}", w / PI);
        }
        // Tiny but positive c and huge n stay finite and in [0, 1].
        for c in [f64::MIN_POSITIVE, 1e-300, 1e-20] {
            for n in [0.0, 0.5, 1e3, 1e30] {
                let a = phong_specular_albedo(c, n);
                assert!(a.is_finite() && (0.0..=1.0).contains(&a), "{c} {n} {a}");
            }
        }
        assert_eq!(phong_specular_albedo(0.0, 3.0), 0.0);
        assert_eq!(phong_specular_albedo(-0.5, 3.0), 0.0);
    }

    #[test]
    fn phong_albedo_is_bounded_and_monotone_in_incidence() {
        // Energy conservation on a fine grid; A(c) also increases with c.
        for n in [0.0, 0.3, 1.0, 4.0, 20.0, 100.0, 1000.0] {
            let mut prev = 0.0;
            for k in 1..=400 {
                let c = k as f64 / 400.0;
                let a = phong_specular_albedo(c, n);
                assert!(a <= 1.0 + 1e-15, "n {n} c {c}: {a}");
                assert!(a >= prev - 1e-14, "n {n} c {c}: {a} < {prev}");
                prev = a;
            }
        }
    }

    #[test]
    fn lambertian_is_unchanged() {
        let m = Material::Lambertian { rho: 0.6 };
        let mut rng = Philox4x32::new(0x1A4B, 0);
        for _ in 0..1000 {
            let wi = sample_cosine_hemisphere(rng.next_2d()).w;
            let u = rng.next_2d();
            let s = m.sample(wi, u);
            let c = sample_cosine_hemisphere(u);
            assert_eq!((s.w, s.pdf), (c.w, c.pdf));
            assert_eq!(m.pdf(wi, s.w), s.pdf);
            assert_eq!(m.eval(wi, s.w), 0.6 * FRAC_1_PI);
            assert_eq!(m.albedo(wi), 0.6);
        }
        assert_eq!(m.constant_brdf(), Some(0.6 * FRAC_1_PI));
        assert_eq!(m.eval(DVec3::Z, -DVec3::Z), 0.0);
        assert_eq!(m.pdf(DVec3::Z, -DVec3::Z), 0.0);
        assert!(m.is_lambertian());
    }

    #[test]
    fn phong_without_specular_is_lambertian() {
        let p = Material::Phong {
            kd: 0.6,
            ks: 0.0,
            n: 10.0,
        };
        let l = Material::Lambertian { rho: 0.6 };
        let mut rng = Philox4x32::new(0x1A4B, 1);
        for _ in 0..1000 {
            let wi = sample_uniform_sphere(rng.next_2d()).w;
            let wo = sample_uniform_sphere(rng.next_2d()).w;
            assert_eq!(p.eval(wi, wo), l.eval(wi, wo));
            assert_eq!(p.pdf(wi, wo), l.pdf(wi, wo));
            let u = rng.next_2d();
            assert_eq!(p.sample(wi, u).w, l.sample(wi, u).w);
            if wi.z > 0.0 {
                assert_eq!(p.albedo(wi), 0.6);
            }
        }
        assert_eq!(p.constant_brdf(), None);
        assert!(!p.is_lambertian());
    }

    #[test]
    fn phong_sample_branches_and_uniform_reuse() {
        let m = Material::Phong {
            kd: 0.25,
            ks: 0.5,
            n: 30.0,
        };
        let wi = dir(0.6, 0.4);
        // Diffuse branch (u0 < 1/3): the cosine warp at u0 / P_d.
        let s = m.sample(wi, [0.1, 0.7]);
        assert_eq!(s.w, sample_cosine_hemisphere([0.1 / (0.25 / 0.75), 0.7]).w);
        // Specular branch: u0 = 2/3 -> u' = 1/2 -> cos alpha = 2^(-1/31).
        let s = m.sample(wi, [2.0 / 3.0, 0.2]);
        let r = DVec3::new(-wi.x, -wi.y, wi.z);
        assert!((s.w.dot(r) - 0.5_f64.powf(1.0 / 31.0)).abs() < 1e-14);
        assert_eq!(s.pdf, m.pdf(wi, s.w));
        // Extreme uniforms give unit directions and finite positive pdfs.
        for u in [
            [0.0, 0.0],
            [1.0 / 3.0, 0.5],
            [ONE_MINUS_EPSILON; 2],
            [1e-300, 0.1],
        ] {
            let s = m.sample(wi, u);
            assert!((s.w.length() - 1.0).abs() < 1e-14, "{u:?} {:?}", s.w);
            assert!(s.pdf.is_finite() && s.pdf >= 0.0, "{u:?} {}", s.pdf);
            assert_eq!(s.pdf, m.pdf(wi, s.w));
        }
        // Black material: samples the cosine lobe, f = 0.
        let b = Material::Phong {
            kd: 0.0,
            ks: 0.0,
            n: 5.0,
        };
        let s = b.sample(wi, [0.4, 0.4]);
        assert_eq!(s.w, sample_cosine_hemisphere([0.4, 0.4]).w);
        assert_eq!(b.eval(wi, s.w), 0.0);
        assert_eq!(b.albedo(wi), 0.0);
    }

    #[test]
    fn phong_pure_specular_sharp_lobe_sampling_is_accurate() {
        // For n = 1e4 the lobe half-width is ~0.01 rad; the expm1 form keeps
        // sin(alpha) accurate, so the sampled cos alpha matches u^(1/(n+1)).
        let n = 1e4;
        let m = Material::Phong {
            kd: 0.0,
            ks: 1.0,
            n,
        };
        let wi = dir(0.3, 1.0);
        let r = DVec3::new(-wi.x, -wi.y, wi.z);
        let mut rng = Philox4x32::new(0x1A4B, 2);
        for _ in 0..1000 {
            let u = rng.next_2d();
            let s = m.sample(wi, u);
            let alpha = s.w.cross(r).length().atan2(s.w.dot(r));
            let expect = (u[0].ln() / (n + 1.0)).exp().acos();
            assert!((alpha - expect).abs() < 1e-9, "{alpha} vs {expect}");
        }
    }
}
