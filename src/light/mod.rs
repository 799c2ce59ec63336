//! Light sources: emission sampling, direct illuminance and power [lm].

use crate::sampling::warp::sample_uniform_sphere;
use glam::DVec3;
use std::f64::consts::PI;

/// A light source (closed set).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point source at `p` [m] with intensity `i` [cd].
    Point { p: DVec3, i: f64 },
}

/// A sampled emitted ray; the chain's weight is the flux it carries [lm].
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    /// Origin [m].
    pub o: DVec3,
    /// Unit direction.
    pub d: DVec3,
    /// Flux carried by the sampled ray, `I(d) / pdf(d)` for a point source [lm].
    pub phi: f64,
}

impl Light {
    /// Total emitted luminous flux [lm]: `4 pi I` for an isotropic point.
    pub fn power(&self) -> f64 {
        match *self {
            Light::Point { i, .. } => 4.0 * PI * i,
        }
    }

    /// Sample an emitted ray with uniforms `u`.
    #[inline]
    pub fn sample_emission(&self, u: [f64; 2]) -> EmissionSample {
        match *self {
            Light::Point { p, i } => {
                let s = sample_uniform_sphere(u);
                EmissionSample {
                    o: p,
                    d: s.w,
                    phi: i / s.pdf,
                }
            }
        }
    }

    /// Position of a point light [m] (for visibility tests).
    pub fn position(&self) -> DVec3 {
        match *self {
            Light::Point { p, .. } => p,
        }
    }

    /// Unoccluded direct illuminance [lx] at `x` on a receiver with unit normal `n`
    /// (cosine law `I cos / d^2`; zero when the source is behind the receiver).
    pub fn direct_illuminance(&self, x: DVec3, n: DVec3) -> f64 {
        match *self {
            Light::Point { p, i } => {
                let d = p - x;
                let d2 = d.length_squared();
                let c = n.dot(d);
                if c <= 0.0 || d2 == 0.0 {
                    0.0
                } else {
                    i * c / (d2 * d2.sqrt())
                }
            }
        }
    }
}
