//! The scene exactly as the user writes it (TOML), before any validation.
//!
//! Every value keeps its byte span in the file so that the validation stage
//! (`scene::validate`) can name the line and the field of a bad value.
//! Unknown keys are rejected here by serde.

use serde::{Deserialize, Deserializer};
use toml::Spanned;

/// Exactly `N` numbers, `[x, y, z]`: an array of another length is refused
/// with its length (serde's fixed-size arrays let a longer one through and
/// drop the rest).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Numbers<const N: usize>(pub [f64; N]);

/// Three numbers: a point \[m\] or a direction.
pub type Vec3 = Numbers<3>;

impl<'de, const N: usize> Deserialize<'de> for Numbers<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<f64>::deserialize(d)?;
        let n = v.len();
        v.try_into().map(Numbers).map_err(|_| {
            serde::de::Error::invalid_length(n, &format!("an array of {N} numbers").as_str())
        })
    }
}

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
    /// Calculation surfaces, `[[grid]]` tables (read by [`crate::grid`];
    /// the compiled scene ignores them).
    #[serde(default)]
    pub grid: Vec<Spanned<GridDesc>>,
    /// Portals, `[[portal]]` tables: the openings through which the light of
    /// distant, environment, sky and sun lights enters.
    #[serde(default)]
    pub portal: Vec<Spanned<PortalDesc>>,
    /// Glare observers, `[[observer]]` tables (read by `lumest glare` when
    /// no `--observers` CSV is given; the compiled scene ignores them).
    #[serde(default)]
    pub observer: Vec<Spanned<ObserverDesc>>,
}

/// One `[[observer]]` table: an eye and its line of sight, for `lumest
/// glare` (see [`crate::glare::scene_observers`]).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserverDesc {
    /// A name, written to the `name` column; default `observer N`.
    pub name: Option<Spanned<String>>,
    /// Eye position \[m\].
    pub eye: Spanned<Vec3>,
    /// Line of sight (any length > 0, not vertical).
    pub view: Spanned<Vec3>,
}

/// One `[[portal]]` table: a parallelogram whose normal `edge1 x edge2`
/// points into the scene \[m\].
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PortalDesc {
    /// Optional name.
    pub name: Option<Spanned<String>>,
    /// A corner \[m\].
    pub corner: Spanned<Vec3>,
    /// First edge \[m\].
    pub edge1: Spanned<Vec3>,
    /// Second edge \[m\].
    pub edge2: Spanned<Vec3>,
}

/// One `[[surface]]` table. Which fields are required (and allowed) depends
/// on `type`; see the README for each shape. All lengths in metres.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceDesc {
    /// Shape kind: `"plane"`, `"rectangle"`, `"disc"`, `"sphere"`, `"box"`,
    /// `"mesh"` or `"sh"`.
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    /// Optional name used in messages and summaries.
    pub name: Option<Spanned<String>>,
    /// A point of a plane \[m\].
    pub point: Option<Spanned<Vec3>>,
    /// Normal of a plane or disc (any length > 0; normalised on compile).
    pub normal: Option<Spanned<Vec3>>,
    /// Corner of a rectangle \[m\].
    pub corner: Option<Spanned<Vec3>>,
    /// First edge of a rectangle \[m\]; the front normal is `edge1 x edge2`.
    pub edge1: Option<Spanned<Vec3>>,
    /// Second edge of a rectangle \[m\].
    pub edge2: Option<Spanned<Vec3>>,
    /// Centre of a disc, sphere or SH object \[m\].
    pub center: Option<Spanned<Vec3>>,
    /// Radius of a disc or sphere \[m\].
    pub radius: Option<Spanned<f64>>,
    /// Reflecting side(s): `"front"`, `"back"`, `"both"` (rectangle, disc,
    /// mesh) or `"outside"`, `"inside"`, `"both"` (sphere, SH object).
    pub sides: Option<Spanned<String>>,
    /// Lower corner of a box \[m\].
    pub min: Option<Spanned<Vec3>>,
    /// Upper corner of a box \[m\].
    pub max: Option<Spanned<Vec3>>,
    /// Normals of a box: `"inward"` (a room, default) or `"outward"` (a solid block).
    pub normals: Option<Spanned<String>>,
    /// Per-face materials of a box overriding `material`.
    pub faces: Option<Spanned<BoxFacesDesc>>,
    /// OBJ file of a mesh, or CSV file `k,m,a,b` of SH coefficients;
    /// relative to the scene file's folder.
    pub file: Option<Spanned<String>>,
    /// Inline SH coefficients `[[k, m, a, b], ...]` (instead of `file`).
    pub coefficients: Option<Spanned<Vec<Numbers<4>>>>,
    /// Translation of a mesh \[m\] (applied last).
    pub translate: Option<Spanned<Vec3>>,
    /// Rotation of a mesh or SH object: angles in degrees about x, then y, then z.
    pub rotate: Option<Spanned<Vec3>>,
    /// Uniform scale of a mesh or SH object (dimensionless, > 0).
    pub scale: Option<Spanned<f64>>,
    /// The surface's material (inline table).
    pub material: Option<Spanned<MaterialDesc>>,
}

/// Per-face materials of a box: `faces = { z_min = { type = "lambertian", reflectance = 0.2 } }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxFacesDesc {
    pub x_min: Option<Spanned<MaterialDesc>>,
    pub x_max: Option<Spanned<MaterialDesc>>,
    pub y_min: Option<Spanned<MaterialDesc>>,
    pub y_max: Option<Spanned<MaterialDesc>>,
    pub z_min: Option<Spanned<MaterialDesc>>,
    pub z_max: Option<Spanned<MaterialDesc>>,
}

/// A `material = { ... }` inline table. Which fields are required (and
/// allowed) depends on `type`:
///
/// - `"lambertian"`: `reflectance`;
/// - `"phong"`: `diffuse`, `specular`, `exponent` (the normalised modified
///   Phong BRDF of Lafortune and Willems 1994, see
///   [`crate::material::Material::Phong`]), e.g.
///   `{ type = "phong", diffuse = 0.3, specular = 0.2, exponent = 20 }`;
/// - `"glass"`: `transmittance` (at normal incidence) and optionally
///   `index` (default 1.52): a thin clear pane, rectangles and discs only
///   ([`crate::material::Glass`]), e.g. `{ type = "glass", transmittance = 0.88 }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// Material kind: `"lambertian"`, `"phong"` or `"glass"`.
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
    /// Glass: direct transmittance at normal incidence (dimensionless).
    pub transmittance: Option<Spanned<f64>>,
    /// Glass: refractive index (dimensionless), default 1.52.
    pub index: Option<Spanned<f64>>,
}

/// One `[[light]]` table.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// Light kind: `"point"`, `"sphere"`, `"spot"`, `"ies"`, `"ldt"`,
    /// `"rectangle"`, `"disc"`, `"distant"`, `"environment"`, `"sky"` or
    /// `"sun"`.
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    /// Optional name used in messages and summaries.
    pub name: Option<Spanned<String>>,
    /// Position of a point light \[m\].
    pub position: Option<Spanned<Vec3>>,
    /// Centre of a sphere light \[m\].
    pub center: Option<Spanned<Vec3>>,
    /// Radius of a sphere light \[m\].
    pub radius: Option<Spanned<f64>>,
    /// Luminous intensity \[cd\] (isotropic point source). Exclusive with `flux`.
    pub intensity: Option<Spanned<f64>>,
    /// Luminous flux \[lm\]. Exclusive with `intensity`; for a goniometric
    /// luminaire, the flux its table is scaled to (exclusive with `multiplier`).
    pub flux: Option<Spanned<f64>>,
    /// Photometric file of a goniometric luminaire (`type = "ies"` or
    /// `"ldt"`) or the HDR map of an environment light, relative to the
    /// scene file.
    pub file: Option<Spanned<String>>,
    /// Direction of a goniometric luminaire's photometric nadir (gamma = 0);
    /// default `[0, 0, -1]`.
    pub aim: Option<Spanned<Vec3>>,
    /// Turn of a goniometric luminaire about its nadir \[deg\], from C0 along
    /// the world `+x` axis (projected), or of an environment map about the
    /// vertical `+z` (counter-clockwise seen from above); default 0.
    pub rotate: Option<Spanned<f64>>,
    /// Factor on a goniometric luminaire's candela values; default 1.
    pub multiplier: Option<Spanned<f64>>,
    /// Emit a goniometric luminaire's light from the luminous opening or
    /// shape its file gives ([`crate::light::LuminousShape`], near-field
    /// accuracy) instead of from its position alone; default false.
    pub opening: Option<Spanned<bool>>,
    /// Beam direction of a spot light, or the direction a distant light
    /// travels (from the sun towards the scene); normalised, non-zero.
    pub direction: Option<Spanned<Vec3>>,
    /// Inner cone half-angle of a spot light \[deg\]: full intensity inside.
    pub inner: Option<Spanned<f64>>,
    /// Outer cone half-angle of a spot light \[deg\]: nothing outside.
    pub outer: Option<Spanned<f64>>,
    /// Corner of a rectangle source \[m\].
    pub corner: Option<Spanned<Vec3>>,
    /// First edge of a rectangle source \[m\].
    pub edge1: Option<Spanned<Vec3>>,
    /// Second edge of a rectangle source \[m\]; it emits towards `edge1 x edge2`.
    pub edge2: Option<Spanned<Vec3>>,
    /// Emitting side's normal of a disc source.
    pub normal: Option<Spanned<Vec3>>,
    /// Luminance of an area source [cd/m^2] (at its profile's peak).
    /// Exclusive with `flux`.
    pub luminance: Option<Spanned<f64>>,
    /// Emitting sides of an area source: `"front"` (default) or `"both"`.
    pub sides: Option<Spanned<String>>,
    /// Radial luminance profile of a disc source (a name or a table; see
    /// [`crate::light::radial_profile`]); default uniform.
    pub profile: Option<Spanned<toml::Value>>,
    /// How an area source's surface reflects; default black.
    pub material: Option<Spanned<MaterialDesc>>,
    /// Illuminance of a distant light on a plane normal to its direction \[lx\].
    pub illuminance: Option<Spanned<f64>>,
    /// Angular diameter of a distant light's disc \[deg\]; default 0 (a point
    /// at infinity); the sun: 0.53.
    pub angular_diameter: Option<Spanned<f64>>,
    /// Factor from an environment map's pixel value to luminance [cd/m^2
    /// per unit of pixel value]. Exclusive with `horizontal_illuminance`.
    pub scale: Option<Spanned<f64>>,
    /// Scale an environment map so that it gives this illuminance \[lx\] on
    /// an unobstructed horizontal plane facing up. Exclusive with `scale`.
    pub horizontal_illuminance: Option<Spanned<f64>>,
    /// An environment map's layout: `"equirect"` (default) or `"angular"`.
    pub mapping: Option<Spanned<String>>,
    /// How an environment light is sampled: `"importance"` (default: the
    /// map itself, importance-sampled) or `"median-cut"` (replaced by
    /// `lights` distant lights of equal energy, an approximation).
    pub sampling: Option<Spanned<String>>,
    /// Number of median-cut lights (a power of two; default 64).
    pub lights: Option<Spanned<i64>>,
    /// A sky's luminance distribution: `"overcast"` (the traditional CIE
    /// overcast sky), `"clear"` (the CIE standard clear sky, general type
    /// 12) or `"cie-1"` ... `"cie-15"` (ISO 15469 general sky types).
    pub sky: Option<Spanned<String>>,
    /// A sky's zenith luminance [cd/m^2]. Exclusive with `horizontal_illuminance`.
    pub zenith_luminance: Option<Spanned<f64>>,
    /// A sky's uniform luminance below the horizon [cd/m^2]; default 0.
    pub ground_luminance: Option<Spanned<f64>>,
    /// The sun's altitude above the horizon \[deg\] (with `sun_azimuth`).
    pub sun_altitude: Option<Spanned<f64>>,
    /// The sun's azimuth from north (`+y`) towards east (`+x`) \[deg\].
    pub sun_azimuth: Option<Spanned<f64>>,
    /// Local date `YYYY-MM-DD` for the sun's position (with `time`,
    /// `latitude`, `longitude`, optional `utc_offset`).
    pub date: Option<Spanned<String>>,
    /// Local clock time `HH:MM` or `HH:MM:SS`.
    pub time: Option<Spanned<String>>,
    /// Local time minus UTC \[h\]; default 0.
    pub utc_offset: Option<Spanned<f64>>,
    /// Latitude \[deg\], north positive.
    pub latitude: Option<Spanned<f64>>,
    /// Longitude \[deg\], east positive.
    pub longitude: Option<Spanned<f64>>,
}

/// One `[[grid]]` table: a calculation surface (see [`crate::grid`]).
/// A rectangle (`corner`, `edge1`, `edge2`) or a named surface of the
/// scene (`surface = "desk 1.z_max"`), or a road field (`type = "road"`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridDesc {
    /// The grid's name (unique in the file), written to the `grid` column.
    pub name: Spanned<String>,
    /// `"area"` (default: EN 12464-1 cells) or `"road"` (EN 13201-3 field).
    #[serde(rename = "type")]
    pub kind: Option<Spanned<String>>,
    /// Name of a rectangle or disc of the scene, or `"BOX.FACE"` for a box
    /// face (`x_min` .. `z_max`); exclusive with `corner`.
    pub surface: Option<Spanned<String>>,
    /// Corner of the grid's rectangle \[m\].
    pub corner: Option<Spanned<Vec3>>,
    /// First edge \[m\] (a road field: along the road, between two luminaires).
    pub edge1: Option<Spanned<Vec3>>,
    /// Second edge \[m\], perpendicular to `edge1`; the points face `edge1 x edge2`.
    pub edge2: Option<Spanned<Vec3>>,
    /// Shift of the points along the grid's normal \[m\]; default 0.
    pub offset: Option<Spanned<f64>>,
    /// Largest cell side \[m\]; default: the EN 12464-1 rule.
    pub spacing: Option<Spanned<f64>>,
    /// Band left out along every edge \[m\]; default 0.
    pub border: Option<Spanned<f64>>,
    /// Lanes of a road field (3 points across each); default 1.
    pub lanes: Option<Spanned<i64>>,
    /// Receiver type of the points; default `"planar"`.
    pub receiver: Option<Spanned<String>>,
    /// Horizontal facing direction of `semicylindrical` points (required
    /// for them, refused otherwise); written to the normal columns.
    pub facing: Option<Spanned<Vec3>>,
    /// Required maintained average illuminance \[lx\].
    pub em: Option<Spanned<f64>>,
    /// Required uniformity `U0 = E_min / E_avg` (dimensionless).
    pub u0: Option<Spanned<f64>>,
    /// Maintenance factor on the computed illuminance, in (0, 1]; default 1.
    pub maintenance_factor: Option<Spanned<f64>>,
}
