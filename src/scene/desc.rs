//! The scene exactly as the user writes it (TOML), before any validation.
//!
//! Every value keeps its byte span in the file so that the validation stage
//! (`scene::validate`) can name the line and the field of a bad value.
//! Unknown keys are rejected here by serde.

use serde::Deserialize;
use toml::Spanned;

/// A whole scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// Reflecting surfaces, `[[surface]]` tables.
    #[serde(default)]
    pub surface: Vec<Spanned<SurfaceDesc>>,
    /// Light sources, `[[light]]` tables.
    #[serde(default)]
    pub light: Vec<Spanned<LightDesc>>,
}

/// One `[[surface]]` table. Which fields are required depends on `type`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceDesc {
    /// Shape kind: `"plane"`.
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    /// Optional name used in messages and summaries.
    pub name: Option<Spanned<String>>,
    /// A point of the plane [m].
    pub point: Option<Spanned<[f64; 3]>>,
    /// Normal of the plane (any length > 0; normalised on compile).
    pub normal: Option<Spanned<[f64; 3]>>,
    /// The surface's material (inline table).
    pub material: Option<Spanned<MaterialDesc>>,
}

/// A `material = { ... }` inline table. Which fields are required (and
/// allowed) depends on `type`:
///
/// - `"lambertian"`: `reflectance`;
/// - `"phong"`: `diffuse`, `specular`, `exponent` (the normalised modified
///   Phong BRDF of Lafortune and Willems 1994, see
///   [`crate::material::Material::Phong`]), e.g.
///   `{ type = "phong", diffuse = 0.3, specular = 0.2, exponent = 20 }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// Material kind: `"lambertian"` or `"phong"`.
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    /// Lambertian reflectance in [0, 1] (dimensionless).
    pub reflectance: Option<Spanned<f64>>,
    /// Phong diffuse reflectance `kd >= 0` (dimensionless); `kd + ks <= 1`.
    pub diffuse: Option<Spanned<f64>>,
    /// Phong specular reflectance `ks >= 0` at normal incidence
    /// (dimensionless); `kd + ks <= 1`.
    pub specular: Option<Spanned<f64>>,
    /// Phong exponent `n >= 0`, finite (dimensionless).
    pub exponent: Option<Spanned<f64>>,
}

/// One `[[light]]` table.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// Light kind: `"point"` or `"sphere"`.
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    /// Optional name used in messages and summaries.
    pub name: Option<Spanned<String>>,
    /// Position of a point light [m].
    pub position: Option<Spanned<[f64; 3]>>,
    /// Centre of a sphere light [m].
    pub center: Option<Spanned<[f64; 3]>>,
    /// Radius of a sphere light [m].
    pub radius: Option<Spanned<f64>>,
    /// Luminous intensity [cd] (isotropic point source). Exclusive with `flux`.
    pub intensity: Option<Spanned<f64>>,
    /// Luminous flux [lm]. Exclusive with `intensity`.
    pub flux: Option<Spanned<f64>>,
}
