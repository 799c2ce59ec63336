//! The Sobolev problem: two infinite parallel Lambertian planes and an
//! isotropic point source between them (exact solution by Hankel transform).

/// Error for invalid Sobolev parameters.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SobolevError {
    #[error("{0}")]
    Invalid(String),
}

/// The Sobolev configuration. Plane 1 lies at distance `h1` [m] from the
/// source, plane 2 at `h2` [m] on the other side; reflectances `rho1`, `rho2`;
/// source intensity `intensity` [cd].
#[derive(Clone, Debug)]
pub struct Sobolev {
    pub h1: f64,
    pub h2: f64,
    pub rho1: f64,
    pub rho2: f64,
    pub intensity: f64,
}

/// Illuminance at a point of one plane [lx].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SobolevValue {
    /// Total illuminance [lx].
    pub e: f64,
    /// Direct illuminance from the source [lx].
    pub e_direct: f64,
    /// Illuminance by reflected light, all orders [lx].
    pub e_reflected: f64,
}

impl Sobolev {
    pub fn new(h1: f64, h2: f64, rho1: f64, rho2: f64, intensity: f64) -> Result<Self, SobolevError> {
        let _ = (h1, h2, rho1, rho2, intensity);
        todo!()
    }
    /// Illuminance on plane `plane` (1 or 2) at horizontal distance `r` [m].
    pub fn illuminance(&self, plane: u8, r: f64) -> SobolevValue {
        let _ = (plane, r);
        todo!()
    }
    /// Illuminance [lx] of reflection order `n >= 1` on plane `plane` at `r`.
    pub fn order(&self, plane: u8, r: f64, n: u32) -> f64 {
        let _ = (plane, r, n);
        todo!()
    }
}
