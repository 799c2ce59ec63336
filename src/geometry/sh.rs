//! Star-shaped surfaces given by real spherical-harmonic (SH) expansions.
//!
//! ## The surface
//!
//! In the object's local frame the surface is the set of points at distance
//! `U(theta, phi)` from the origin in the direction `(theta, phi)`:
//!
//! ```text
//! U(theta, phi) = sum_{k=0..L} sum_{m=0..k} P_k^m(cos theta) (a_km cos m phi + b_km sin m phi)
//! ```
//!
//! `theta` is the polar angle from local `+z`, `phi` the azimuth from local
//! `+x` towards `+y`. `P_k^m` are the Schmidt semi-normalised associated
//! Legendre functions without the Condon-Shortley phase:
//! `P_k^m = sqrt((2 - delta_m0) (k - m)! / (k + m)!) (1 - x^2)^(m/2) d^m P_k / dx^m`,
//! so `P_k^0 = P_k`, `sum_m P_k^m(x)^2 = 1` and `|P_k^m| <= 1`. The world
//! placement is `x_world = center + scale R x_local` (`R` a proper rotation,
//! `scale > 0`); coefficients are in local units, world radii are `scale U`.
//! `U > 0` everywhere is required (checked by [`ShSurface::new`]): the
//! surface is then star-shaped about `center` (every ray from the centre
//! crosses it exactly once) and it bounds a solid.
//!
//! The pieces, one module each (their docs hold the maths):
//!
//! - the surface, its evaluation (value, surface gradient, normal) and its
//!   construction: [`surface`] ([`ShSurface`]); the Legendre recurrences
//!   behind it are in [`crate::math::sph_harm`];
//! - the radius and derivative bounds that make the ray march safe, and the
//!   grid that proves `U > 0`: [`bounds`];
//! - the ray intersection by a Lipschitz-certified march: [`march`]
//!   ([`ShSurface::first_hit`], [`ShSurface::crosses`]);
//! - the least-squares fit of a point set: [`fit()`];
//! - coefficient CSV files: [`crate::io::sh_coeffs`] ([`read_coefficients`]
//!   adds this module's degree limit and error type).

pub mod bounds;
pub mod fit;
pub mod march;
pub mod surface;
#[cfg(test)]
mod tests;

pub use crate::io::sh_coeffs::write_coefficients;
pub use crate::math::sph_harm::{ShCoeff, schmidt_legendre};
pub use bounds::MAX_GRID;
pub use fit::{ShFit, fit};
pub use surface::ShSurface;

use crate::io::csvio::InputError;
use glam::DVec3;
use std::path::Path;

/// Highest supported degree `L`.
///
/// Why: the recurrences are stable far beyond this, but the construction
/// check (a grid over the sphere fine enough for the gradient bound) and
/// the per-evaluation cost `O(L^2)` grow quickly.
pub const MAX_DEGREE: usize = 100;

/// Invalid SH surfaces, coefficient files and fits.
#[derive(Debug, thiserror::Error)]
pub enum ShError {
    /// The coefficient list is empty.
    #[error("no spherical-harmonic coefficients given")]
    Empty,
    /// `m > k`.
    #[error("coefficient {index}: order m = {m} exceeds degree k = {k} (need m <= k)")]
    OrderAboveDegree { index: usize, k: usize, m: usize },
    /// `k > MAX_DEGREE`.
    #[error("coefficient {index}: degree k = {k} exceeds the supported maximum {max}")]
    DegreeTooHigh { index: usize, k: usize, max: usize },
    /// A coefficient is NaN or infinite.
    #[error("coefficient {index} (k = {k}, m = {m}): {which} = {value} is not finite")]
    NotFinite {
        index: usize,
        k: usize,
        m: usize,
        which: &'static str,
        value: f64,
    },
    /// `b != 0` at `m = 0`, where it has no effect.
    #[error(
        "coefficient {index} (k = {k}, m = 0): b = {} must be 0 (sin(0 phi) = 0, so b has no effect at m = 0)",
        crate::io::format_number(*.b)
    )]
    SineAtZeroOrder { index: usize, k: usize, b: f64 },
    /// The same `(k, m)` twice.
    #[error("coefficient {index} (k = {k}, m = {m}) repeats coefficient {first}")]
    Duplicate {
        index: usize,
        first: usize,
        k: usize,
        m: usize,
    },
    /// The centre is NaN or infinite.
    #[error("centre {center} is not finite")]
    Center { center: DVec3 },
    /// The scale is not a positive finite number.
    #[error("scale {} must be finite and > 0", crate::io::format_number(*.scale))]
    Scale { scale: f64 },
    /// The rotation is not a proper rotation matrix.
    #[error("rotation is not a proper rotation matrix: {reason}")]
    Rotation { reason: String },
    /// `U <= 0` somewhere: not star-shaped about the centre.
    #[error(
        "not star-shaped about the centre: radius U = {radius:e} <= 0 at theta = {theta} rad, phi = {phi} rad (local frame)"
    )]
    NotStarShaped { radius: f64, theta: f64, phi: f64 },
    /// `U > 0` on a fine grid but the rigorous bound could not prove it.
    #[error(
        "could not verify that the radius is positive everywhere: smallest grid value {grid_min:e} \
         (at theta = {theta} rad, phi = {phi} rad), rigorous lower bound {lower:e} on a {n_theta} x {n_phi} grid; \
         the surface (nearly) touches its centre"
    )]
    Unverified {
        grid_min: f64,
        theta: f64,
        phi: f64,
        lower: f64,
        n_theta: usize,
        n_phi: usize,
    },
    /// A bad coefficient file (names the file, line and field).
    #[error(transparent)]
    Input(#[from] InputError),
    /// Fewer fit points than unknowns.
    #[error(
        "fit: {count} points cannot determine the {needed} coefficients of degree {degree}; need at least {needed}"
    )]
    TooFewPoints {
        count: usize,
        degree: usize,
        needed: usize,
    },
    /// A fit point is NaN or infinite.
    #[error("fit: point {index} ({point}) is not finite")]
    PointNotFinite { index: usize, point: DVec3 },
    /// A fit point coincides with the centre (no direction).
    #[error("fit: point {index} coincides with the centre (its direction is undefined)")]
    PointAtCenter { index: usize },
    /// The fit directions do not determine the coefficients.
    #[error(
        "fit: the point directions do not determine the degree-{degree} coefficients \
         (condition number {condition:e}); spread the points over the sphere or lower the degree"
    )]
    IllConditioned { degree: usize, condition: f64 },
}

/// Read SH coefficients from a CSV file with the header columns `k,m,a,b`
/// ([`crate::io::sh_coeffs::read_coefficients`] with the degree limit
/// [`MAX_DEGREE`]); errors name the file, the line and the field.
pub fn read_coefficients(path: &Path) -> Result<Vec<ShCoeff>, ShError> {
    Ok(crate::io::sh_coeffs::read_coefficients(path, MAX_DEGREE)?)
}
