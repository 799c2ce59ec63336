//! Materials: BRDF evaluation, sampling and albedo in the local frame.
//!
//! Directions `wi`, `wo` are unit vectors pointing away from the surface;
//! the BRDF `f_r` is in [1/sr].

use crate::sampling::warp::{DirectionSample, sample_cosine_hemisphere};
use std::f64::consts::FRAC_1_PI;

/// A material (closed set).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Ideal diffuse reflector with reflectance `rho` in [0, 1]: `f_r = rho / pi`.
    Lambertian { rho: f64 },
}

impl Material {
    /// BRDF value [1/sr] for local directions (z along the front normal).
    #[inline]
    pub fn eval(&self, wi: glam::DVec3, wo: glam::DVec3) -> f64 {
        match *self {
            Material::Lambertian { rho } => {
                if wi.z > 0.0 && wo.z > 0.0 {
                    rho * FRAC_1_PI
                } else {
                    0.0
                }
            }
        }
    }

    /// Directional-hemispherical reflectance for light from `wi` (dimensionless).
    #[inline]
    pub fn albedo(&self, _wi: glam::DVec3) -> f64 {
        match *self {
            Material::Lambertian { rho } => rho,
        }
    }

    /// `f_r` when it does not depend on directions (Lambertian), for hot loops.
    #[inline]
    pub fn constant_brdf(&self) -> Option<f64> {
        match *self {
            Material::Lambertian { rho } => Some(rho * FRAC_1_PI),
        }
    }

    /// Sample an outgoing local direction for light arriving from `wi`;
    /// pdf per solid angle [1/sr].
    #[inline]
    pub fn sample(&self, _wi: glam::DVec3, u: [f64; 2]) -> DirectionSample {
        match *self {
            Material::Lambertian { .. } => sample_cosine_hemisphere(u),
        }
    }
}
