//! Validation of the description and compilation into the scene the
//! Markov chains and estimators use.

use super::SceneError;
use super::desc::{LightDesc, MaterialDesc, SceneDesc, SurfaceDesc};
use crate::geometry::{Hit, Plane, Ray, SideMask};
use crate::light::Light;
use crate::material::Material;
use glam::DVec3;
use std::f64::consts::PI;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// The text being compiled, for turning byte spans into line and column.
pub struct SourceCtx<'a> {
    pub src: &'a str,
    pub file: &'a Path,
}

impl SourceCtx<'_> {
    /// 1-based line and column of byte offset `at`.
    pub fn line_col(&self, at: usize) -> (usize, usize) {
        let at = at.min(self.src.len());
        let before = &self.src[..at];
        let line = before.matches('\n').count() + 1;
        let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
        (line, column)
    }

    fn invalid(&self, span: Range<usize>, field: &str, message: impl Into<String>) -> SceneError {
        let (line, column) = self.line_col(span.start);
        SceneError::Invalid {
            file: self.file.to_path_buf(),
            line,
            column,
            field: field.to_string(),
            message: message.into(),
        }
    }

    fn required<'t, T>(
        &self,
        v: &'t Option<Spanned<T>>,
        table: Range<usize>,
        field: &str,
    ) -> Result<&'t Spanned<T>, SceneError> {
        v.as_ref()
            .ok_or_else(|| self.invalid(table, field, "missing field"))
    }

    fn finite_vec(&self, v: &Spanned<[f64; 3]>, field: &str) -> Result<DVec3, SceneError> {
        let a = *v.get_ref();
        if a.iter().all(|x| x.is_finite()) {
            Ok(DVec3::from_array(a))
        } else {
            Err(self.invalid(
                v.span(),
                field,
                format!("every component must be finite, got {a:?}"),
            ))
        }
    }

    fn unit_vec(&self, v: &Spanned<[f64; 3]>, field: &str) -> Result<DVec3, SceneError> {
        let d = self.finite_vec(v, field)?;
        let n = d.normalize_or_zero();
        if n == DVec3::ZERO || !n.is_finite() {
            return Err(self.invalid(v.span(), field, "direction must have a non-zero length"));
        }
        Ok(n)
    }

    fn nonneg(&self, v: &Spanned<f64>, field: &str) -> Result<f64, SceneError> {
        let x = *v.get_ref();
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(v.span(), field, format!("must be finite and >= 0, got {x}")))
        }
    }
}

/// Kinds of shape present in a compiled scene (only these are built).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SceneSummary {
    /// Number of infinite planes.
    pub planes: usize,
    /// Number of point lights.
    pub point_lights: usize,
    /// Number of sphere lights.
    pub sphere_lights: usize,
    /// Whether an acceleration structure (BVH) was built.
    pub bvh: bool,
}

impl std::fmt::Display for SceneSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} plane(s), {} point light(s), {} sphere light(s), BVH: {}",
            self.planes,
            self.point_lights,
            self.sphere_lights,
            if self.bvh {
                "built"
            } else {
                "none (not needed)"
            }
        )
    }
}

/// A reflecting surface of the compiled scene.
#[derive(Clone, Debug)]
pub struct Surface {
    /// Name from the file, or `surface #k`.
    pub name: String,
    /// Its material.
    pub material: Material,
}

/// The compiled scene. Units: metres, candela, lumen; lights selected in
/// proportion to their power.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Surfaces; surface `k` has geometry `planes[k]` (planes are the only shape yet).
    pub surfaces: Vec<Surface>,
    /// Plane geometry, indexed like `surfaces`.
    pub planes: Vec<Plane>,
    /// Light sources.
    pub lights: Vec<Light>,
    /// Cumulative power fractions for picking a light (last entry 1).
    light_cdf: Vec<f64>,
    /// Total emitted flux [lm].
    total_power: f64,
}

/// Largest number of planes the bit-mask visibility supports.
pub const MAX_PLANES: usize = 64;

impl Scene {
    /// Build a scene from parts (validated by the caller); used by `compile`
    /// and by programmatic scenes such as the Sobolev validation case.
    pub fn from_parts(surfaces: Vec<(String, Plane, Material)>, lights: Vec<Light>) -> Self {
        let mut s = Vec::with_capacity(surfaces.len());
        let mut planes = Vec::with_capacity(surfaces.len());
        for (name, pl, m) in surfaces {
            s.push(Surface { name, material: m });
            planes.push(pl);
        }
        let total_power: f64 = lights.iter().map(Light::power).sum();
        let mut acc = 0.0;
        let mut light_cdf: Vec<f64> = lights
            .iter()
            .map(|l| {
                acc += l.power();
                if total_power > 0.0 {
                    acc / total_power
                } else {
                    0.0
                }
            })
            .collect();
        if let Some(last) = light_cdf.last_mut() {
            *last = 1.0;
        }
        Scene {
            surfaces: s,
            planes,
            lights,
            light_cdf,
            total_power,
        }
    }

    /// Total emitted flux [lm].
    pub fn total_power(&self) -> f64 {
        self.total_power
    }

    /// What the compiled scene holds.
    pub fn summary(&self) -> SceneSummary {
        SceneSummary {
            planes: self.planes.len(),
            point_lights: self
                .lights
                .iter()
                .filter(|l| matches!(l, Light::Point { .. }))
                .count(),
            sphere_lights: self
                .lights
                .iter()
                .filter(|l| matches!(l, Light::Sphere { .. }))
                .count(),
            bvh: false,
        }
    }

    /// Pick a light with probability proportional to its power.
    #[inline]
    pub fn pick_light(&self, u: f64) -> &Light {
        let k = self
            .light_cdf
            .partition_point(|&c| c <= u)
            .min(self.lights.len() - 1);
        &self.lights[k]
    }

    /// Nearest surface hit along `ray`, ignoring surface `skip` (the flat
    /// surface the ray leaves, which it cannot hit again).
    #[inline]
    pub fn intersect(&self, ray: &Ray, skip: Option<u32>) -> Option<Hit> {
        let mut best: Option<(f64, u32)> = None;
        for (k, pl) in self.planes.iter().enumerate() {
            if Some(k as u32) == skip {
                continue;
            }
            let t_max = best.map_or(f64::INFINITY, |b| b.0);
            if let Some(t) = pl.intersect(ray, t_max) {
                best = Some((t, k as u32));
            }
        }
        best.map(|(t, k)| {
            let pl = &self.planes[k as usize];
            Hit {
                t,
                p: pl.project(ray.o + ray.d * t),
                n: pl.n,
                surface: k,
            }
        })
    }

    /// First surface hit by a ray leaving `o` (an observer, possibly standing
    /// on a surface: planes through `o` are ignored) in unit direction `d`.
    pub fn first_hit_from(&self, o: DVec3, d: DVec3) -> Option<Hit> {
        let mut best: Option<(f64, u32)> = None;
        for (k, pl) in self.planes.iter().enumerate() {
            if pl.side(o) == 0 {
                continue;
            }
            let t_max = best.map_or(f64::INFINITY, |b| b.0);
            if let Some(t) = pl.intersect(&Ray { o, d }, t_max) {
                best = Some((t, k as u32));
            }
        }
        best.map(|(t, k)| {
            let pl = &self.planes[k as usize];
            Hit {
                t,
                p: pl.project(o + d * t),
                n: pl.n,
                surface: k,
            }
        })
    }

    /// Visibility masks of a point against every plane.
    pub fn side_mask(&self, q: DVec3) -> SideMask {
        SideMask::of(q, &self.planes)
    }
}

/// Validate a parsed description and build the scene.
pub fn compile(desc: &SceneDesc, ctx: &SourceCtx) -> Result<Scene, SceneError> {
    let mut surfaces = Vec::with_capacity(desc.surface.len());
    for (k, s) in desc.surface.iter().enumerate() {
        surfaces.push(surface(s, k, ctx)?);
    }
    if surfaces.len() > MAX_PLANES {
        let s = &desc.surface[MAX_PLANES];
        return Err(ctx.invalid(
            s.span(),
            "surface",
            format!("at most {MAX_PLANES} planes are supported"),
        ));
    }
    if desc.light.is_empty() {
        return Err(ctx.invalid(0..0, "light", "the scene has no [[light]]"));
    }
    let planes: Vec<Plane> = surfaces.iter().map(|s| s.1).collect();
    let lights = desc
        .light
        .iter()
        .map(|l| light(l, ctx, &planes))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Scene::from_parts(surfaces, lights))
}

fn surface(
    s: &Spanned<SurfaceDesc>,
    k: usize,
    ctx: &SourceCtx,
) -> Result<(String, Plane, Material), SceneError> {
    let d = s.get_ref();
    let name = d
        .name
        .as_ref()
        .map_or_else(|| format!("surface #{}", k + 1), |n| n.get_ref().clone());
    match d.kind.get_ref().as_str() {
        "plane" => {
            let p = ctx.finite_vec(ctx.required(&d.point, s.span(), "point")?, "point")?;
            let n = ctx.unit_vec(ctx.required(&d.normal, s.span(), "normal")?, "normal")?;
            let m = material(ctx.required(&d.material, s.span(), "material")?, ctx)?;
            Ok((name, Plane::new(p, n), m))
        }
        other => Err(ctx.invalid(
            d.kind.span(),
            "type",
            format!("unknown surface type `{other}` (this version knows: plane)"),
        )),
    }
}

/// Fields of a `material` table that only some types accept, with the type
/// that accepts each.
const MATERIAL_ONLY_FIELDS: [(&str, &str); 4] = [
    ("reflectance", "lambertian"),
    ("diffuse", "phong"),
    ("specular", "phong"),
    ("exponent", "phong"),
];

/// Reject a field given for a material type that does not take it.
fn material_fields_allowed(
    d: &MaterialDesc,
    kind: &str,
    ctx: &SourceCtx,
) -> Result<(), SceneError> {
    let given = [&d.reflectance, &d.diffuse, &d.specular, &d.exponent];
    for (v, (field, owner)) in given.into_iter().zip(MATERIAL_ONLY_FIELDS) {
        let Some(v) = v else { continue };
        if owner != kind {
            return Err(ctx.invalid(
                v.span(),
                field,
                format!("not allowed for material type `{kind}` (it belongs to type `{owner}`)"),
            ));
        }
    }
    Ok(())
}

fn material(m: &Spanned<MaterialDesc>, ctx: &SourceCtx) -> Result<Material, SceneError> {
    let d = m.get_ref();
    let kind = d.kind.get_ref().as_str();
    match kind {
        "lambertian" => {
            material_fields_allowed(d, kind, ctx)?;
            let r = ctx.required(&d.reflectance, m.span(), "reflectance")?;
            let rho = *r.get_ref();
            if !(rho.is_finite() && (0.0..=1.0).contains(&rho)) {
                return Err(ctx.invalid(
                    r.span(),
                    "reflectance",
                    format!("must lie in [0, 1], got {rho}"),
                ));
            }
            Ok(Material::Lambertian { rho })
        }
        "phong" => {
            material_fields_allowed(d, kind, ctx)?;
            let kd = ctx.nonneg(ctx.required(&d.diffuse, m.span(), "diffuse")?, "diffuse")?;
            let s = ctx.required(&d.specular, m.span(), "specular")?;
            let ks = ctx.nonneg(s, "specular")?;
            let n = ctx.nonneg(ctx.required(&d.exponent, m.span(), "exponent")?, "exponent")?;
            if kd + ks > 1.0 {
                return Err(ctx.invalid(
                    s.span(),
                    "specular",
                    format!(
                        "`diffuse` + `specular` must be <= 1 (energy conservation), \
                         got {kd} + {ks} = {}",
                        kd + ks
                    ),
                ));
            }
            Ok(Material::Phong { kd, ks, n })
        }
        other => Err(ctx.invalid(
            d.kind.span(),
            "type",
            format!("unknown material type `{other}` (this version knows: lambertian, phong)"),
        )),
    }
}

fn light(l: &Spanned<LightDesc>, ctx: &SourceCtx, planes: &[Plane]) -> Result<Light, SceneError> {
    let d = l.get_ref();
    // Fields that belong to the other kind of light are rejected.
    let not_for = |kind: &str, fields: &[(&str, Option<Range<usize>>)]| -> Result<(), SceneError> {
        match fields.iter().find(|f| f.1.is_some()) {
            Some((name, Some(span))) => Err(ctx.invalid(
                span.clone(),
                name,
                format!("not allowed for a `{kind}` light"),
            )),
            _ => Ok(()),
        }
    };
    let i = match (&d.intensity, &d.flux) {
        (Some(i), None) => ctx.nonneg(i, "intensity")?,
        (None, Some(f)) => ctx.nonneg(f, "flux")? / (4.0 * PI),
        (Some(_), Some(f)) => {
            return Err(ctx.invalid(
                f.span(),
                "flux",
                "give either `intensity` [cd] or `flux` [lm], not both",
            ));
        }
        (None, None) => {
            return Err(ctx.invalid(
                l.span(),
                "intensity",
                "missing field (give `intensity` [cd] or `flux` [lm])",
            ));
        }
    };
    match d.kind.get_ref().as_str() {
        "point" => {
            not_for(
                "point",
                &[
                    ("center", d.center.as_ref().map(Spanned::span)),
                    ("radius", d.radius.as_ref().map(Spanned::span)),
                ],
            )?;
            let p = ctx.finite_vec(ctx.required(&d.position, l.span(), "position")?, "position")?;
            Ok(Light::Point { p, i })
        }
        "sphere" => {
            not_for(
                "sphere",
                &[("position", d.position.as_ref().map(Spanned::span))],
            )?;
            let cs = ctx.required(&d.center, l.span(), "center")?;
            let c = ctx.finite_vec(cs, "center")?;
            let rs = ctx.required(&d.radius, l.span(), "radius")?;
            let r = *rs.get_ref();
            if !(r.is_finite() && r > 0.0) {
                return Err(ctx.invalid(
                    rs.span(),
                    "radius",
                    format!("must be finite and > 0, got {r}"),
                ));
            }
            if let Some(k) = planes
                .iter()
                .position(|pl| pl.signed_distance(c).abs() <= r)
            {
                return Err(ctx.invalid(
                    rs.span(),
                    "radius",
                    format!("the sphere light cuts plane surface #{} (it must lie wholly on one side of every plane)", k + 1),
                ));
            }
            Ok(Light::Sphere { c, r, i })
        }
        other => Err(ctx.invalid(
            d.kind.span(),
            "type",
            format!("unknown light type `{other}` (this version knows: point, sphere)"),
        )),
    }
}
