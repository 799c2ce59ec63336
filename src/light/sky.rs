//! Sky luminance distributions: the CIE standard general sky (ISO 15469:2004
//! / CIE S 011/E:2003, 15 types) and the traditional CIE overcast sky.
//!
//! # The general sky
//!
//! The luminance of a sky element at zenith angle `Z` and angular distance
//! `chi` from the sun (at zenith angle `Z_s`), relative to the zenith's, is
//!
//! ```text
//! L / L_z = f(chi) phi(Z) / (f(Z_s) phi(0))
//! phi(Z)   = 1 + a exp(b / cos Z)        (phi(pi/2) = 1, its limit, at the horizon)
//! f(chi)   = 1 + c (exp(d chi) - exp(d pi/2)) + e cos^2 chi
//! cos chi  = cos Z_s cos Z + sin Z_s sin Z cos(alpha - alpha_s)
//! ```
//!
//! with the gradation parameters `(a, b)` and the indicatrix parameters
//! `(c, d, e)` of the type ([`GENERAL_SKY_TYPES`]). At the zenith `chi =
//! Z_s`, so the ratio is 1 there. Type 12 is the CIE standard clear sky and
//! type 5 a uniform sky (`phi = f = 1`).
//!
//! # The traditional CIE overcast sky
//!
//! Moon and Spencer's `L(Z) = L_z (1 + 2 cos Z) / 3`, kept by the standard
//! as a separate formula; its unobstructed horizontal illuminance is
//! `E_h = 7 pi L_z / 9`.
//!
//! # Absolute values and the ground
//!
//! A sky is scaled by its zenith luminance [cd/m^2] or by the horizontal
//! illuminance \[lx\] it gives on an unobstructed plane (the diffuse sky
//! alone, without the sun), found by quadrature ([`Sky::horizontal_illuminance`]).
//! Below the horizon the sky has a uniform ground luminance [cd/m^2] (0 by
//! default; a reflecting ground is better modelled as a plane in the scene).
//! Directions are unit vectors with `+z` up.

use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI};

/// Gradation `(a, b)` and indicatrix `(c, d, e)` parameters of the 15 CIE
/// general sky types (ISO 15469:2004, table 1), index `type - 1`.
pub const GENERAL_SKY_TYPES: [[f64; 5]; 15] = [
    // Gradation group I: overcast, steep gradation towards the zenith.
    [4.0, -0.70, 0.0, -1.0, 0.00],
    [4.0, -0.70, 2.0, -1.5, 0.15],
    // II: overcast, moderate gradation.
    [1.1, -0.80, 0.0, -1.0, 0.00],
    [1.1, -0.80, 2.0, -1.5, 0.15],
    // III: uniform gradation.
    [0.0, -1.00, 0.0, -1.0, 0.00],
    [0.0, -1.00, 2.0, -1.5, 0.15],
    [0.0, -1.00, 5.0, -2.5, 0.30],
    [0.0, -1.00, 10.0, -3.0, 0.45],
    // IV: partly cloudy.
    [-1.0, -0.55, 2.0, -1.5, 0.15],
    [-1.0, -0.55, 5.0, -2.5, 0.30],
    [-1.0, -0.55, 10.0, -3.0, 0.45],
    // V: clear (type 12: the CIE standard clear sky).
    [-1.0, -0.32, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 16.0, -3.0, 0.30],
    // VI: cloudless turbid.
    [-1.0, -0.15, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 24.0, -2.8, 0.15],
];

/// The relative luminance distribution of a sky.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SkyModel {
    /// A CIE general sky: its type (1-15) and the unit direction to the sun.
    General {
        /// Type 1-15.
        kind: u8,
        /// Unit vector towards the sun (`z >= 0`).
        sun: DVec3,
    },
    /// The traditional CIE overcast sky (Moon and Spencer).
    TraditionalOvercast,
}

/// What is wrong with a sky's parameters.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SkyError {
    /// A general sky type outside 1-15.
    #[error("CIE general sky type {0} does not exist (types 1 to 15)")]
    Type(i64),
    /// The sun below the horizon (the general sky is defined for the sun above it).
    #[error(
        "the sun is {0:.3} degrees below the horizon: the CIE general sky needs it at or above the horizon"
    )]
    SunBelowHorizon(f64),
    /// A scale that is not positive and finite.
    #[error("{0} must be positive and finite")]
    Scale(&'static str),
}

/// A sky with absolute luminances [cd/m^2].
#[derive(Clone, Debug, PartialEq)]
pub struct Sky {
    model: SkyModel,
    /// Zenith luminance [cd/m^2].
    l_zenith: f64,
    /// Luminance below the horizon [cd/m^2].
    l_ground: f64,
    /// `f(Z_s) phi(0)` of a general sky (the zenith's relative value).
    norm: f64,
}

impl Sky {
    /// A sky of the given model with zenith luminance 1 cd/m^2 and a black
    /// ground.
    pub fn new(model: SkyModel) -> Result<Self, SkyError> {
        let norm = match model {
            SkyModel::General { kind, sun } => {
                if !(1..=15).contains(&kind) {
                    return Err(SkyError::Type(kind as i64));
                }
                if sun.z < 0.0 {
                    return Err(SkyError::SunBelowHorizon(-sun.z.asin().to_degrees()));
                }
                let p = GENERAL_SKY_TYPES[kind as usize - 1];
                indicatrix(&p, sun.z.clamp(-1.0, 1.0).acos()) * gradation(&p, 1.0)
            }
            SkyModel::TraditionalOvercast => 1.0,
        };
        Ok(Self {
            model,
            l_zenith: 1.0,
            l_ground: 0.0,
            norm,
        })
    }

    /// The model.
    pub fn model(&self) -> SkyModel {
        self.model
    }

    /// Scale to zenith luminance `l` [cd/m^2].
    pub fn with_zenith_luminance(mut self, l: f64) -> Result<Self, SkyError> {
        if !(l > 0.0 && l.is_finite()) {
            return Err(SkyError::Scale("the zenith luminance"));
        }
        self.l_zenith = l;
        Ok(self)
    }

    /// Scale so that the sky gives horizontal illuminance `e` \[lx\] on an
    /// unobstructed plane.
    pub fn with_horizontal_illuminance(mut self, e: f64) -> Result<Self, SkyError> {
        if !(e > 0.0 && e.is_finite()) {
            return Err(SkyError::Scale("the horizontal illuminance"));
        }
        self.l_zenith = 1.0;
        self.l_zenith = e / self.horizontal_illuminance();
        Ok(self)
    }

    /// Uniform luminance below the horizon [cd/m^2].
    pub fn with_ground_luminance(mut self, l: f64) -> Result<Self, SkyError> {
        if !(l >= 0.0 && l.is_finite()) {
            return Err(SkyError::Scale("the ground luminance"));
        }
        self.l_ground = l;
        Ok(self)
    }

    /// Zenith luminance [cd/m^2].
    pub fn zenith_luminance(&self) -> f64 {
        self.l_zenith
    }

    /// Luminance below the horizon [cd/m^2].
    pub fn ground_luminance(&self) -> f64 {
        self.l_ground
    }

    /// Luminance relative to the zenith's of the sky element in unit
    /// direction `w` at or above the horizon (`w.z >= 0`).
    pub fn relative(&self, w: DVec3) -> f64 {
        let cz = w.z.clamp(0.0, 1.0);
        match self.model {
            SkyModel::TraditionalOvercast => (1.0 + 2.0 * cz) / 3.0,
            SkyModel::General { kind, sun } => {
                let p = GENERAL_SKY_TYPES[kind as usize - 1];
                let chi = w.dot(sun).clamp(-1.0, 1.0).acos();
                indicatrix(&p, chi) * gradation(&p, cz) / self.norm
            }
        }
    }

    /// Luminance [cd/m^2] seen looking along unit direction `w`: the sky's
    /// above the horizon, the ground's below.
    pub fn luminance(&self, w: DVec3) -> f64 {
        if w.z < 0.0 {
            self.l_ground
        } else {
            self.l_zenith * self.relative(w)
        }
    }

    /// `int L dOmega` over the whole sphere [cd/m^2 sr]: the sky by the
    /// quadrature of [`Self::horizontal_illuminance`] without the cosine,
    /// and the ground's `2 pi L_ground`.
    pub fn integral(&self) -> f64 {
        self.hemisphere(false) + 2.0 * PI * self.l_ground
    }

    /// Illuminance \[lx\] the sky alone gives on an unobstructed horizontal
    /// plane, `int L cos Z dOmega` over the upper hemisphere: Gauss-Legendre
    /// panels in `cos Z` (16 x 20 nodes) and in the azimuth from the sun
    /// (32 x 20 nodes, the distribution being smooth and periodic).
    pub fn horizontal_illuminance(&self) -> f64 {
        self.hemisphere(true)
    }

    /// `int L (cos Z if cosine) dOmega` over the upper hemisphere.
    fn hemisphere(&self, cosine: bool) -> f64 {
        use crate::math::quadrature::{CompensatedSum, panel};
        let sun_az = match self.model {
            SkyModel::General { sun, .. } => sun.y.atan2(sun.x),
            SkyModel::TraditionalOvercast => 0.0,
        };
        let mut total = CompensatedSum::default();
        let (nz, na) = (16, 32);
        for i in 0..nz {
            let (c0, c1) = (i as f64 / nz as f64, (i + 1) as f64 / nz as f64);
            total.add(panel(
                &|cz: f64| {
                    let sz = (1.0 - cz * cz).max(0.0).sqrt();
                    let mut ring = 0.0;
                    for j in 0..na {
                        let (a0, a1) = (
                            sun_az + 2.0 * PI * j as f64 / na as f64,
                            sun_az + 2.0 * PI * (j + 1) as f64 / na as f64,
                        );
                        ring += panel(
                            &|az: f64| {
                                let (s, c) = az.sin_cos();
                                self.luminance(DVec3::new(sz * c, sz * s, cz))
                            },
                            a0,
                            a1,
                        );
                    }
                    if cosine { ring * cz } else { ring }
                },
                c0,
                c1,
            ));
        }
        total.total()
    }
}

/// The gradation `phi(Z) = 1 + a exp(b / cos Z)` at `cos Z = cz`, 1 at
/// the horizon (its limit for `b < 0`).
fn gradation(p: &[f64; 5], cz: f64) -> f64 {
    if cz <= 0.0 {
        1.0
    } else {
        1.0 + p[0] * (p[1] / cz).exp()
    }
}

/// The indicatrix `f(chi) = 1 + c (exp(d chi) - exp(d pi/2)) + e cos^2 chi`.
fn indicatrix(p: &[f64; 5], chi: f64) -> f64 {
    1.0 + p[2] * ((p[3] * chi).exp() - (p[3] * FRAC_PI_2).exp()) + p[4] * chi.cos().powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::sun_position::sun_direction;

    /// `int L cos dOmega` by the midpoint rule on an n x 4n grid in
    /// (Z, azimuth): shares no code with the Gauss-Legendre sum above.
    fn midpoint(sky: &Sky, n: usize) -> f64 {
        let mut s = 0.0;
        for i in 0..n {
            let z = FRAC_PI_2 * (i as f64 + 0.5) / n as f64;
            for j in 0..4 * n {
                let az = 2.0 * PI * (j as f64 + 0.5) / (4 * n) as f64;
                let w = DVec3::new(z.sin() * az.cos(), z.sin() * az.sin(), z.cos());
                s += sky.luminance(w) * z.cos() * z.sin();
            }
        }
        s * (FRAC_PI_2 / n as f64) * (2.0 * PI / (4 * n) as f64)
    }

    #[test]
    fn traditional_overcast_gives_seven_ninths_pi_lz() {
        let sky = Sky::new(SkyModel::TraditionalOvercast)
            .unwrap()
            .with_zenith_luminance(3000.0)
            .unwrap();
        let e = sky.horizontal_illuminance();
        assert!((e / (7.0 * PI * 3000.0 / 9.0) - 1.0).abs() < 1e-13, "{e}");
        assert!((sky.luminance(DVec3::X) - 1000.0).abs() < 1e-12);
    }

    #[test]
    fn type_5_is_uniform_and_gives_pi_l() {
        let sky = Sky::new(SkyModel::General {
            kind: 5,
            sun: sun_direction(35.0, 120.0),
        })
        .unwrap();
        for w in [DVec3::Z, DVec3::X, DVec3::new(0.3, -0.4, 0.5).normalize()] {
            assert!((sky.relative(w) - 1.0).abs() < 1e-15);
        }
        assert!((sky.horizontal_illuminance() / PI - 1.0).abs() < 1e-13);
    }

    /// The CIE standard clear sky (type 12) is Kittler's formula
    /// `(0.91 + 10 exp(-3 chi) + 0.45 cos^2 chi)(1 - exp(-0.32 / cos Z))`
    /// over its zenith value.
    #[test]
    fn type_12_is_the_standard_clear_sky() {
        let sun = sun_direction(40.0, 200.0);
        let sky = Sky::new(SkyModel::General { kind: 12, sun }).unwrap();
        let kittler = |w: DVec3| {
            let chi = w.dot(sun).acos();
            let f = |x: f64| 0.91 + 10.0 * (-3.0 * x).exp() + 0.45 * x.cos().powi(2);
            let g = |cz: f64| 1.0 - (-0.32 / cz).exp();
            f(chi) * g(w.z) / (f(sun.z.acos()) * g(1.0))
        };
        for w in [
            DVec3::Z,
            DVec3::new(0.3, -0.4, 0.5).normalize(),
            DVec3::new(-0.9, 0.1, 0.05).normalize(),
            sun,
        ] {
            // 1 - 10 exp(-3 pi / 2) = 0.91017 against Kittler's rounded 0.91:
            // each f differs by at most 1.7e-4 / 0.91, the ratio by twice that.
            assert!((sky.relative(w) / kittler(w) - 1.0).abs() < 3.8e-4, "{w}");
        }
    }

    #[test]
    fn horizontal_illuminance_of_every_type_against_a_midpoint_rule() {
        for kind in 1..=15u8 {
            for (alt, az) in [(10.0, 90.0), (45.0, 180.0), (75.0, 300.0)] {
                let sky = Sky::new(SkyModel::General {
                    kind,
                    sun: sun_direction(alt, az),
                })
                .unwrap();
                let (gl, mid) = (sky.horizontal_illuminance(), midpoint(&sky, 400));
                assert!(
                    (gl / mid - 1.0).abs() < 2e-5,
                    "type {kind} sun {alt}: {gl} vs {mid}"
                );
                // Scaling by illuminance gives it back exactly.
                let scaled = sky.clone().with_horizontal_illuminance(10_000.0).unwrap();
                assert!((scaled.horizontal_illuminance() / 10_000.0 - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn zenith_is_one_and_the_circumsolar_region_is_brightest_on_clear_skies() {
        for kind in 1..=15u8 {
            let sun = sun_direction(30.0, 45.0);
            let sky = Sky::new(SkyModel::General { kind, sun }).unwrap();
            assert!((sky.relative(DVec3::Z) - 1.0).abs() < 1e-14, "type {kind}");
            if kind >= 11 {
                let opposite = DVec3::new(-sun.x, -sun.y, sun.z);
                assert!(
                    sky.relative(sun) > 5.0 * sky.relative(opposite),
                    "type {kind}"
                );
            }
        }
    }

    #[test]
    fn bad_skies_are_refused() {
        let sun = sun_direction(-1.0, 0.0);
        assert!(matches!(
            Sky::new(SkyModel::General { kind: 3, sun }),
            Err(SkyError::SunBelowHorizon(_))
        ));
        assert!(matches!(
            Sky::new(SkyModel::General {
                kind: 16,
                sun: DVec3::Z
            }),
            Err(SkyError::Type(16))
        ));
        let sky = Sky::new(SkyModel::TraditionalOvercast).unwrap();
        assert!(sky.clone().with_zenith_luminance(0.0).is_err());
        assert!(sky.clone().with_horizontal_illuminance(f64::NAN).is_err());
        assert!(sky.with_ground_luminance(-1.0).is_err());
    }
}
