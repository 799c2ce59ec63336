//! Validation of the description and compilation into the scene the
//! Markov chains and estimators use.

use super::SceneError;
use super::desc::{LightDesc, MaterialDesc, SceneDesc, SurfaceDesc, Vec3};
use super::world::{
    MAX_COORD, MAX_INTENSITY, MAX_PLANES, MIN_INTENSITY, Scene, Sides, SurfaceSpec,
};
use crate::geometry::Plane;
use crate::geometry::mesh::Mesh;
use crate::geometry::sh::{ShCoeff, ShSurface, read_coefficients};
use crate::geometry::shapes::{AaBox, Disc, Rect, Sphere};
use crate::light::Light;
use crate::material::Material;
use glam::DMat3;
use glam::DVec3;
use std::f64::consts::PI;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// Three numbers as written in messages: `[1e300, 0, 2.5]`.
fn triple(a: [f64; 3]) -> String {
    let f = crate::io::format_number;
    format!("[{}, {}, {}]", f(a[0]), f(a[1]), f(a[2]))
}

/// The text being compiled, for turning byte spans into line and column.
pub struct SourceCtx<'a> {
    pub src: &'a str,
    pub file: &'a Path,
}

impl SourceCtx<'_> {
    /// A path written in the scene file, relative to the file's folder.
    pub fn relative(&self, p: &str) -> std::path::PathBuf {
        let p = Path::new(p);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.file
                .parent()
                .map_or_else(|| p.to_path_buf(), |d| d.join(p))
        }
    }

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

    /// Three finite numbers (a direction: any length).
    fn finite3(&self, v: &Spanned<Vec3>, field: &str) -> Result<DVec3, SceneError> {
        let a = v.get_ref().0;
        if !a.iter().all(|x| x.is_finite()) {
            return Err(self.invalid(
                v.span(),
                field,
                format!("every component must be finite, got {}", triple(a)),
            ));
        }
        Ok(DVec3::from_array(a))
    }

    /// A point or a length vector \[m\]: finite and within [`MAX_COORD`].
    fn finite_vec(&self, v: &Spanned<Vec3>, field: &str) -> Result<DVec3, SceneError> {
        let a = self.finite3(v, field)?.to_array();
        if a.iter().any(|x| x.abs() > MAX_COORD) {
            return Err(self.invalid(
                v.span(),
                field,
                format!(
                    "every component must lie within +-{MAX_COORD:e} (the geometry is resolved to \
                     1e-11 of the coordinates; re-centre the scene), got {}",
                    triple(a)
                ),
            ));
        }
        Ok(DVec3::from_array(a))
    }

    fn unit_vec(&self, v: &Spanned<Vec3>, field: &str) -> Result<DVec3, SceneError> {
        // A direction, of any length (a sun vector in metres).
        let d = self.finite3(v, field)?;
        crate::geometry::unit_direction(d)
            .ok_or_else(|| self.invalid(v.span(), field, "direction must have a non-zero length"))
    }

    fn nonneg(&self, v: &Spanned<f64>, field: &str) -> Result<f64, SceneError> {
        let x = *v.get_ref();
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(
                v.span(),
                field,
                format!(
                    "must be finite and >= 0, got {}",
                    crate::io::format_number(x)
                ),
            ))
        }
    }
}

/// Validate a parsed description and build the scene.
pub fn compile(desc: &SceneDesc, ctx: &SourceCtx) -> Result<Scene, SceneError> {
    let mut surfaces = Vec::with_capacity(desc.surface.len());
    let mut n_planes = 0;
    for (k, s) in desc.surface.iter().enumerate() {
        let spec = surface(s, k, ctx)?;
        if matches!(spec, SurfaceSpec::Plane(..)) {
            n_planes += 1;
            if n_planes > MAX_PLANES {
                return Err(ctx.invalid(
                    s.span(),
                    "surface",
                    format!("at most {MAX_PLANES} infinite planes are supported"),
                ));
            }
        }
        surfaces.push(spec);
    }
    if desc.light.is_empty() {
        return Err(ctx.invalid(0..0, "light", "the scene has no [[light]]"));
    }
    let planes: Vec<Plane> = surfaces
        .iter()
        .filter_map(|s| match s {
            SurfaceSpec::Plane(_, p, _) => Some(*p),
            _ => None,
        })
        .collect();
    let mut lights = Vec::with_capacity(desc.light.len());
    let mut notes = Vec::with_capacity(desc.light.len());
    let mut approximate = None;
    let mut names = Vec::with_capacity(desc.light.len());
    let mut tables = GonioTables::new();
    for (k, l) in desc.light.iter().enumerate() {
        let (light, note) = light(l, ctx, &planes, &mut tables)?;
        let name = l
            .get_ref()
            .name
            .as_ref()
            .map_or_else(|| format!("light #{}", k + 1), |n| n.get_ref().clone());
        // Median cut: the map becomes N distant lights.
        if let (Light::Environment(env), Some(n)) = (&light, median_cut_request(l, ctx)?) {
            let cut = crate::light::median_cut::median_cut(env, n).map_err(|m| {
                let sp = l.get_ref().lights.as_ref().map_or(l.span(), Spanned::span);
                ctx.invalid(sp, "lights", m)
            })?;
            notes.push(note.map(|n0| {
                format!("{n0}; median cut into {n} distant lights (an approximation: see the README for its bias)")
            }));
            approximate = Some(format!(
                "`{name}` is replaced by {n} distant lights (median cut), an approximation of its map"
            ));
            names.push(format!("{name} [median cut 1/{n}]"));
            for m in 1..n {
                notes.push(None);
                names.push(format!("{name} [median cut {}/{n}]", m + 1));
            }
            for c in cut {
                let region = crate::light::StartRegion::fit(None, &[], &[]);
                lights.push(Light::Distant(std::sync::Arc::new(
                    crate::light::Distant::new(-c.wi, c.e_n, 0.0, region),
                )));
            }
            continue;
        }
        lights.push(light);
        notes.push(note);
        names.push(name);
    }
    // Every value was checked above with its line; what `build` checks again
    // cannot fail here.
    let mut scene =
        Scene::build(surfaces, lights).map_err(|e| ctx.invalid(0..0, "light", e.to_string()))?;
    scene.approximate = approximate;
    scene.notes = names
        .iter()
        .zip(notes)
        .filter_map(|(name, note)| note.map(|n| format!("{name}: {n}")))
        .collect();
    if let Some(w) = far_from_origin(&scene) {
        scene.notes.push(w);
    }
    for (k, name) in names.iter().enumerate() {
        if scene.traps_light(k) {
            let span = desc.surface.first().map_or(0..0, |s| {
                s.get_ref()
                    .material
                    .as_ref()
                    .map_or(s.span(), Spanned::span)
            });
            return Err(ctx.invalid(
                span,
                "material",
                format!(
                    "every surface reflects all the light it receives (reflectance 1) and no ray from \
                     {name} leaves the scene: the light is never absorbed, so the illuminance is \
                     infinite and chains would never end; give some surface a reflectance below 1"
                ),
            ));
        }
        if scene.sealed(k) {
            scene.notes.push(format!(
                "WARNING: {name} is sealed inside a solid: most rays from it meet the back of a surface, so its light hardly reaches a point in front of one"
            ));
        }
        // A light in a pane's plane: a ray that starts on a pane never
        // meets it, so the pane dims its light on neither side.
        let p = scene.lights[k].position();
        if scene.lights[k].is_point_like()
            && let Some(pane) = scene
                .panes()
                .iter()
                .find(|g| g.plane().side(p) == 0 && g.contains(p))
        {
            scene.notes.push(format!(
                "WARNING: {name} lies in the plane of glass pane `{}`: its light passes the pane \
                 undimmed on both sides (neither side is behind it); move it off the pane",
                scene.surfaces[pane.surface as usize].name
            ));
        }
        let cut = scene.luminous_shape_cut(k);
        if cut >= 0.01 && matches!(scene.lights[k], Light::Sphere { .. }) {
            scene.notes.push(format!(
                "WARNING: {name}: about {:.0} % of the sphere light's surface lies beyond a surface (it cuts a shape), and that part's light leaves where it is (out of a room through its wall): move it or make it smaller",
                100.0 * cut
            ));
        } else if cut >= 0.01 {
            scene.notes.push(format!(
                "WARNING: {name}: about {:.0} % of its luminous shape lies beyond a surface, whose light meets that surface at once; the shape is centred on `position`, the photometric centre (a luminaire with luminous sides mounted on a ceiling has its centre half the sides' height below it)",
                100.0 * cut
            ));
        }
    }
    let uneven: Vec<String> = scene
        .unevenly_wound_meshes()
        .into_iter()
        .map(String::from)
        .collect();
    for name in uneven {
        let note = format!(
            "WARNING: mesh `{name}` is closed but not wound consistently (some neighbouring triangles run their shared edge the same way): it has no inside, so which side of it light belongs to is taken from each triangle's own winding, and a light or point exactly on it may stand on the wrong side (a light on the ceiling can light the outside only); give every face the same orientation"
        );
        scene.notes.push(note);
    }
    if !desc.portal.is_empty() {
        let mut list = Vec::with_capacity(desc.portal.len());
        for p in &desc.portal {
            let d = p.get_ref();
            let corner = ctx.finite_vec(&d.corner, "corner")?;
            let e1 = ctx.finite_vec(&d.edge1, "edge1")?;
            let e2 = ctx.finite_vec(&d.edge2, "edge2")?;
            let portal = crate::light::portal::Portal::new(corner, e1, e2).ok_or_else(|| {
                ctx.invalid(
                    d.edge2.span(),
                    "edge2",
                    "a portal's edges must span a parallelogram of non-zero area",
                )
            })?;
            list.push(portal);
        }
        if !scene.has_directional() {
            return Err(ctx.invalid(
                desc.portal[0].span(),
                "portal",
                "portals let in the light of `distant`, `environment`, `sky` and `sun` lights, and the scene has none",
            ));
        }
        scene.notes.push(format!(
            "{} portal(s) of {:.4e} m^2 in all: the chains of the lights at infinity start on them (light entering elsewhere is left out)",
            list.len(),
            list.iter().map(|p| p.area).sum::<f64>()
        ));
        scene.set_portals(crate::light::portal::Portals::new(list));
    }
    Ok(scene.with_light_names(names))
}

/// The fields each surface type takes (besides `type`, `name`, `material`).
const SURFACE_FIELDS: [(&str, &[&str]); 7] = [
    ("plane", &["point", "normal"]),
    ("rectangle", &["corner", "edge1", "edge2", "sides"]),
    ("disc", &["center", "normal", "radius", "sides"]),
    ("sphere", &["center", "radius", "sides"]),
    ("box", &["min", "max", "normals", "faces"]),
    ("mesh", &["file", "translate", "rotate", "scale", "sides"]),
    (
        "sh",
        &["file", "coefficients", "center", "rotate", "scale", "sides"],
    ),
];

/// Reject a field that the surface's type does not take.
fn surface_fields_allowed(d: &SurfaceDesc, kind: &str, ctx: &SourceCtx) -> Result<(), SceneError> {
    let Some((_, allowed)) = SURFACE_FIELDS.iter().find(|f| f.0 == kind) else {
        return Ok(());
    };
    let span = |v: &Option<Spanned<Vec3>>| v.as_ref().map(Spanned::span);
    let given: [(&str, Option<Range<usize>>); 16] = [
        ("point", span(&d.point)),
        ("normal", span(&d.normal)),
        ("corner", span(&d.corner)),
        ("edge1", span(&d.edge1)),
        ("edge2", span(&d.edge2)),
        ("center", span(&d.center)),
        ("radius", d.radius.as_ref().map(Spanned::span)),
        ("sides", d.sides.as_ref().map(Spanned::span)),
        ("min", span(&d.min)),
        ("max", span(&d.max)),
        ("normals", d.normals.as_ref().map(Spanned::span)),
        ("faces", d.faces.as_ref().map(Spanned::span)),
        ("file", d.file.as_ref().map(Spanned::span)),
        ("coefficients", d.coefficients.as_ref().map(Spanned::span)),
        ("translate", span(&d.translate)),
        ("rotate", span(&d.rotate)),
    ];
    for (field, sp) in given {
        if let Some(sp) = sp
            && !allowed.contains(&field)
        {
            return Err(ctx.invalid(
                sp,
                field,
                format!(
                    "not allowed for surface type `{kind}` (it takes: {})",
                    allowed.join(", ")
                ),
            ));
        }
    }
    if let Some(sc) = &d.scale
        && !allowed.contains(&"scale")
    {
        return Err(ctx.invalid(
            sc.span(),
            "scale",
            format!("not allowed for surface type `{kind}`"),
        ));
    }
    Ok(())
}

/// Parse a `sides` value among `names` (the first is the default), mapped to `values`.
fn sides(
    d: &Option<Spanned<String>>,
    names: [&str; 3],
    values: [Sides; 3],
    ctx: &SourceCtx,
) -> Result<Sides, SceneError> {
    let Some(v) = d else { return Ok(values[0]) };
    names
        .iter()
        .position(|n| n == v.get_ref())
        .map(|k| values[k])
        .ok_or_else(|| {
            ctx.invalid(
                v.span(),
                "sides",
                format!(
                    "must be one of {}, got `{}`",
                    names.map(|n| format!("`{n}`")).join(", "),
                    v.get_ref()
                ),
            )
        })
}

/// The smallest radius \[m\] of a sphere, disc or sphere light: a
/// nanometre, far below any luminaire and far above where `r^2` underflows.
const MIN_RADIUS: f64 = 1e-9;

fn positive(v: &Spanned<f64>, field: &str, ctx: &SourceCtx) -> Result<f64, SceneError> {
    let x = *v.get_ref();
    if field == "radius" && x.is_finite() && x > MAX_COORD {
        // A length like the coordinates: squared in areas and distances.
        Err(ctx.invalid(
            v.span(),
            field,
            format!(
                "must lie within {MAX_COORD:e} m, got {}",
                crate::io::format_number(x)
            ),
        ))
    } else if field == "radius" && x.is_finite() && x > 0.0 && x < MIN_RADIUS {
        // A sphere light's luminance is I / (pi r^2): below about 1e-154 m
        // it overflows (a reviewer's 1e-300 m sphere read NaN, flagged ok).
        Err(ctx.invalid(
            v.span(),
            field,
            format!(
                "must be at least {MIN_RADIUS:e} m, got {} (a smaller sphere light is a point light, `type = \"point\"`)",
                crate::io::format_number(x)
            ),
        ))
    } else if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(ctx.invalid(
            v.span(),
            field,
            format!(
                "must be finite and > 0, got {}",
                crate::io::format_number(x)
            ),
        ))
    }
}

/// `translate` \[m\], `rotate` (degrees about x, then y, then z) and `scale`
/// of a mesh or SH object: `x -> translate + scale R x`.
fn placement(d: &SurfaceDesc, ctx: &SourceCtx) -> Result<(DVec3, DMat3, f64), SceneError> {
    let t = match &d.translate {
        Some(v) => ctx.finite_vec(v, "translate")?,
        None => DVec3::ZERO,
    };
    let r = match &d.rotate {
        Some(v) => {
            let a = ctx.finite_vec(v, "rotate")?;
            DMat3::from_rotation_z(a.z.to_radians())
                * DMat3::from_rotation_y(a.y.to_radians())
                * DMat3::from_rotation_x(a.x.to_radians())
        }
        None => DMat3::IDENTITY,
    };
    let s = match &d.scale {
        Some(v) => positive(v, "scale", ctx)?,
        None => 1.0,
    };
    Ok((t, r, s))
}

const FLAT_SIDES: [&str; 3] = ["front", "back", "both"];
const FLAT_VALUES: [Sides; 3] = [Sides::Front, Sides::Back, Sides::Both];
const ROUND_SIDES: [&str; 3] = ["outside", "inside", "both"];

fn surface(s: &Spanned<SurfaceDesc>, k: usize, ctx: &SourceCtx) -> Result<SurfaceSpec, SceneError> {
    let d = s.get_ref();
    let name = d
        .name
        .as_ref()
        .map_or_else(|| format!("surface #{}", k + 1), |n| n.get_ref().clone());
    let kind = d.kind.get_ref().as_str();
    surface_fields_allowed(d, kind, ctx)?;
    let vec = |v: &Option<Spanned<Vec3>>, field: &str| {
        ctx.finite_vec(ctx.required(v, s.span(), field)?, field)
    };
    let mat = || material(ctx.required(&d.material, s.span(), "material")?, ctx);
    match kind {
        "plane" => {
            let p = vec(&d.point, "point")?;
            let n = ctx.unit_vec(ctx.required(&d.normal, s.span(), "normal")?, "normal")?;
            Ok(SurfaceSpec::Plane(name, Plane::new(p, n), mat()?))
        }
        "rectangle" => {
            let o = vec(&d.corner, "corner")?;
            let e1 = vec(&d.edge1, "edge1")?;
            let e2 = vec(&d.edge2, "edge2")?;
            let r = Rect::new(o, e1, e2).ok_or_else(|| {
                ctx.invalid(
                    d.edge2.as_ref().map_or(s.span(), Spanned::span),
                    "edge2",
                    "the edges must be non-zero and not parallel",
                )
            })?;
            let sd = sides(&d.sides, FLAT_SIDES, FLAT_VALUES, ctx)?;
            let m = any_material(ctx.required(&d.material, s.span(), "material")?, ctx)?;
            Ok(SurfaceSpec::Rect(name, r, sd, m))
        }
        "disc" => {
            let c = vec(&d.center, "center")?;
            let n = ctx.unit_vec(ctx.required(&d.normal, s.span(), "normal")?, "normal")?;
            let r = positive(ctx.required(&d.radius, s.span(), "radius")?, "radius", ctx)?;
            let sd = sides(&d.sides, FLAT_SIDES, FLAT_VALUES, ctx)?;
            let m = any_material(ctx.required(&d.material, s.span(), "material")?, ctx)?;
            Ok(SurfaceSpec::Disc(name, Disc::new(c, n, r), sd, m))
        }
        "sphere" => {
            let c = vec(&d.center, "center")?;
            let r = positive(ctx.required(&d.radius, s.span(), "radius")?, "radius", ctx)?;
            let sd = sides(&d.sides, ROUND_SIDES, FLAT_VALUES, ctx)?;
            Ok(SurfaceSpec::Sphere(name, Sphere { c, r }, sd, mat()?))
        }
        "box" => {
            let lo = vec(&d.min, "min")?;
            let hi = vec(&d.max, "max")?;
            if !(lo.cmplt(hi).all()) {
                return Err(ctx.invalid(
                    d.max.as_ref().map_or(s.span(), Spanned::span),
                    "max",
                    format!("every component must exceed `min`'s, got min {lo} and max {hi}"),
                ));
            }
            let sd = sides(&d.normals, ["inward", "outward", "inward"], [Sides::Back, Sides::Front, Sides::Back], ctx)
                .map_err(|e| match e {
                    SceneError::Invalid { file, line, column, message, .. } => SceneError::Invalid {
                        file,
                        line,
                        column,
                        field: "normals".into(),
                        message: message.replace("`inward`, `outward`, `inward`", "`inward`, `outward`"),
                    },
                    e => e,
                })?;
            let faces = d.faces.as_ref().map(|f| f.get_ref());
            let mut ms = Vec::with_capacity(6);
            for (f, fname) in crate::geometry::shapes::BOX_FACES.iter().enumerate() {
                let own = faces.and_then(|fs| {
                    [&fs.x_min, &fs.x_max, &fs.y_min, &fs.y_max, &fs.z_min, &fs.z_max][f].as_ref()
                });
                ms.push(match own {
                    Some(m) => material(m, ctx)?,
                    None => material(ctx.required(&d.material, s.span(), "material").map_err(|_| {
                        ctx.invalid(s.span(), "material", format!("missing field (needed for face `{fname}`, which `faces` does not give)"))
                    })?, ctx)?,
                });
            }
            let ms: [Material; 6] = ms.try_into().expect("six faces");
            Ok(SurfaceSpec::Box(name, AaBox { lo, hi }, sd, ms))
        }
        "sh" => {
            let coeffs = match (&d.file, &d.coefficients) {
                (Some(f), None) => read_coefficients(&ctx.relative(f.get_ref()))
                    .map_err(|e| ctx.invalid(f.span(), "file", e.to_string()))?,
                (None, Some(c)) => {
                    let mut v = Vec::with_capacity(c.get_ref().len());
                    for row in c.get_ref() {
                        let row = row.0;
                        let [k, m, a, b] = row;
                        let int = |x: f64| x >= 0.0 && x.fract() == 0.0 && x <= 1e6;
                        if !(int(k) && int(m)) {
                            return Err(ctx.invalid(
                                c.span(),
                                "coefficients",
                                format!("degree k and order m must be whole numbers >= 0, got {row:?}"),
                            ));
                        }
                        v.push(ShCoeff { k: k as usize, m: m as usize, a, b });
                    }
                    v
                }
                (Some(f), Some(_)) => {
                    return Err(ctx.invalid(f.span(), "file", "give either `file` or `coefficients`, not both"));
                }
                (None, None) => {
                    return Err(ctx.invalid(
                        s.span(),
                        "coefficients",
                        "missing field (give `file` = a CSV of k,m,a,b or `coefficients` = [[k, m, a, b], ...])",
                    ));
                }
            };
            let c = vec(&d.center, "center")?;
            let (_, rotation, scale) = placement(d, ctx)?;
            let field_span = d.coefficients.as_ref().map(Spanned::span).or(d.file.as_ref().map(Spanned::span)).unwrap_or(s.span());
            let o = ShSurface::new(&coeffs, c, rotation, scale).map_err(|e| match &d.file {
                // Coefficients from a file: name it.
                Some(f) => ctx.invalid(
                    field_span,
                    "file",
                    format!("{}: {e}", ctx.relative(f.get_ref()).display()),
                ),
                None => ctx.invalid(field_span, "coefficients", e.to_string()),
            })?;
            let sd = sides(&d.sides, ROUND_SIDES, FLAT_VALUES, ctx)?;
            Ok(SurfaceSpec::Sh(name, o, sd, mat()?))
        }
        "mesh" => {
            let fs = ctx.required(&d.file, s.span(), "file")?;
            let path = ctx.relative(fs.get_ref());
            let (translate, rotation, scale) = placement(d, ctx)?;
            let mesh = Mesh::load_obj(&path)
                .and_then(|m| m.try_transformed(translate, rotation, scale))
                .map_err(|e| ctx.invalid(fs.span(), "file", e.to_string()))?;
            let sd = sides(&d.sides, ["both", "front", "back"], [Sides::Both, Sides::Front, Sides::Back], ctx)?;
            Ok(SurfaceSpec::Mesh(name, mesh, sd, mat()?))
        }
        other => Err(ctx.invalid(
            d.kind.span(),
            "type",
            format!(
                "unknown surface type `{other}` (this version knows: plane, rectangle, disc, sphere, box, mesh, sh)"
            ),
        )),
    }
}

/// Fields of a `material` table that only some types accept, with the type
/// that accepts each.
const MATERIAL_ONLY_FIELDS: [(&str, &str); 6] = [
    ("reflectance", "lambertian"),
    ("diffuse", "phong"),
    ("specular", "phong"),
    ("exponent", "phong"),
    ("transmittance", "glass"),
    ("index", "glass"),
];

/// Reject a field given for a material type that does not take it.
fn material_fields_allowed(
    d: &MaterialDesc,
    kind: &str,
    ctx: &SourceCtx,
) -> Result<(), SceneError> {
    let given = [
        &d.reflectance,
        &d.diffuse,
        &d.specular,
        &d.exponent,
        &d.transmittance,
        &d.index,
    ];
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

/// A material of an opaque surface: any type but `glass`, which only the
/// flat shapes a pane can be (rectangles and discs) take.
fn material(m: &Spanned<MaterialDesc>, ctx: &SourceCtx) -> Result<Material, SceneError> {
    let mat = any_material(m, ctx)?;
    if let Material::Glass(_) = mat {
        return Err(ctx.invalid(
            m.get_ref().kind.span(),
            "type",
            "`glass` is a thin flat pane: only `rectangle` and `disc` surfaces take it",
        ));
    }
    Ok(mat)
}

/// A material of any type, `glass` included (see [`crate::material::Glass`]).
fn any_material(m: &Spanned<MaterialDesc>, ctx: &SourceCtx) -> Result<Material, SceneError> {
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
                    format!("must lie in [0, 1], got {}", crate::io::format_number(rho)),
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
        "glass" => {
            material_fields_allowed(d, kind, ctx)?;
            let t = ctx.required(&d.transmittance, m.span(), "transmittance")?;
            let index = d
                .index
                .as_ref()
                .map_or(crate::material::FLOAT_GLASS_INDEX, |v| *v.get_ref());
            let glass = crate::material::Glass::new(*t.get_ref(), index).map_err(|e| {
                let (span, field) = if e.starts_with("`index`") {
                    (d.index.as_ref().map_or(m.span(), Spanned::span), "index")
                } else {
                    (t.span(), "transmittance")
                };
                ctx.invalid(
                    span,
                    field,
                    e.split_once(' ')
                        .map_or(e.clone(), |(_, rest)| rest.to_string()),
                )
            })?;
            Ok(Material::Glass(glass))
        }
        other => Err(ctx.invalid(
            d.kind.span(),
            "type",
            format!(
                "unknown material type `{other}` (this version knows: lambertian, phong, glass)"
            ),
        )),
    }
}

/// Goniometric tables already built in this scene, by file and scale:
/// luminaires of one file share its tables (and their angle grids) rather
/// than each holding a copy.
type GonioTables =
    std::collections::HashMap<(std::path::PathBuf, u64), std::sync::Arc<crate::light::Goniometric>>;

fn light(
    l: &Spanned<LightDesc>,
    ctx: &SourceCtx,
    planes: &[Plane],
    tables: &mut GonioTables,
) -> Result<(Light, Option<String>), SceneError> {
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
    let kind = d.kind.get_ref().as_str();
    if kind == "sky" || kind == "sun" {
        return daylight(l, ctx);
    }
    // The keys of the sky and the sun belong to them alone.
    let sky_keys = [
        ("sky", d.sky.as_ref().map(Spanned::span)),
        (
            "zenith_luminance",
            d.zenith_luminance.as_ref().map(Spanned::span),
        ),
        (
            "ground_luminance",
            d.ground_luminance.as_ref().map(Spanned::span),
        ),
        ("sun_altitude", d.sun_altitude.as_ref().map(Spanned::span)),
        ("sun_azimuth", d.sun_azimuth.as_ref().map(Spanned::span)),
        ("date", d.date.as_ref().map(Spanned::span)),
        ("time", d.time.as_ref().map(Spanned::span)),
        ("utc_offset", d.utc_offset.as_ref().map(Spanned::span)),
        ("latitude", d.latitude.as_ref().map(Spanned::span)),
        ("longitude", d.longitude.as_ref().map(Spanned::span)),
    ];
    not_for(kind, &sky_keys)?;
    if kind == "environment" {
        return environment(l, ctx);
    }
    not_for(
        kind,
        &[
            ("scale", d.scale.as_ref().map(Spanned::span)),
            (
                "horizontal_illuminance",
                d.horizontal_illuminance.as_ref().map(Spanned::span),
            ),
            ("mapping", d.mapping.as_ref().map(Spanned::span)),
            ("sampling", d.sampling.as_ref().map(Spanned::span)),
            ("lights", d.lights.as_ref().map(Spanned::span)),
        ],
    )?;
    if kind == "distant" {
        return distant(l, ctx);
    }
    not_for(
        kind,
        &[
            ("illuminance", d.illuminance.as_ref().map(Spanned::span)),
            (
                "angular_diameter",
                d.angular_diameter.as_ref().map(Spanned::span),
            ),
        ],
    )?;
    if kind == "rectangle" || kind == "disc" {
        return area(l, ctx);
    }
    if kind != "spot" {
        not_for(
            kind,
            &[
                ("direction", d.direction.as_ref().map(Spanned::span)),
                ("inner", d.inner.as_ref().map(Spanned::span)),
                ("outer", d.outer.as_ref().map(Spanned::span)),
            ],
        )?;
    }
    let area_only = [
        ("corner", d.corner.as_ref().map(Spanned::span)),
        ("edge1", d.edge1.as_ref().map(Spanned::span)),
        ("edge2", d.edge2.as_ref().map(Spanned::span)),
        ("normal", d.normal.as_ref().map(Spanned::span)),
        ("luminance", d.luminance.as_ref().map(Spanned::span)),
        ("sides", d.sides.as_ref().map(Spanned::span)),
        ("profile", d.profile.as_ref().map(Spanned::span)),
        ("material", d.material.as_ref().map(Spanned::span)),
    ];
    not_for(kind, &area_only)?;
    if kind == "ies" || kind == "ldt" {
        return goniometric(l, ctx, tables);
    }
    let gonio_only = [
        ("file", d.file.as_ref().map(Spanned::span)),
        ("aim", d.aim.as_ref().map(Spanned::span)),
        ("rotate", d.rotate.as_ref().map(Spanned::span)),
        ("multiplier", d.multiplier.as_ref().map(Spanned::span)),
        ("opening", d.opening.as_ref().map(Spanned::span)),
    ];
    not_for(kind, &gonio_only)?;
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
    if i > MAX_INTENSITY || (i > 0.0 && i < MIN_INTENSITY) {
        let sp = d.intensity.as_ref().map_or_else(
            || d.flux.as_ref().map_or(l.span(), Spanned::span),
            Spanned::span,
        );
        return Err(ctx.invalid(
            sp,
            if d.intensity.is_some() {
                "intensity"
            } else {
                "flux"
            },
            format!(
                "out of range: 0 or between {MIN_INTENSITY:e} and {MAX_INTENSITY:e} cd (4 pi times that in lm); \
                 results scale exactly with intensity, so rescale the input"
            ),
        ));
    }
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
            Ok((Light::Point { p, i }, None))
        }
        "sphere" => {
            not_for(
                "sphere",
                &[("position", d.position.as_ref().map(Spanned::span))],
            )?;
            let cs = ctx.required(&d.center, l.span(), "center")?;
            let c = ctx.finite_vec(cs, "center")?;
            let rs = ctx.required(&d.radius, l.span(), "radius")?;
            let r = positive(rs, "radius", ctx)?;
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
            Ok((Light::Sphere { c, r, i }, None))
        }
        "spot" => {
            not_for(
                "spot",
                &[
                    ("center", d.center.as_ref().map(Spanned::span)),
                    ("radius", d.radius.as_ref().map(Spanned::span)),
                ],
            )?;
            let p = ctx.finite_vec(ctx.required(&d.position, l.span(), "position")?, "position")?;
            let axis = ctx.unit_vec(ctx.required(&d.direction, l.span(), "direction")?, "direction")?;
            let angle = |v: &Option<Spanned<f64>>, field: &str| -> Result<f64, SceneError> {
                let a = ctx.required(v, l.span(), field)?;
                let x = *a.get_ref();
                if !(x.is_finite() && (0.0..=180.0).contains(&x)) {
                    return Err(ctx.invalid(a.span(), field, format!("must lie in [0, 180] degrees, got {}", crate::io::format_number(x))));
                }
                Ok(x)
            };
            let (inner, outer) = (angle(&d.inner, "inner")?, angle(&d.outer, "outer")?);
            if outer < inner || outer <= 0.0 {
                let sp = d.outer.as_ref().map_or(l.span(), Spanned::span);
                return Err(ctx.invalid(
                    sp,
                    "outer",
                    format!("must be > 0 and >= `inner` ({inner} degrees), got {}", crate::io::format_number(outer)),
                ));
            }
            // The cones are held by their cosines, whose distance from 1
            // (`theta^2 / 2`) is resolved to 1.1e-16: at 1e-6 degrees a flux
            // gave 37 % too much on the axis. From 0.01 degrees on it is
            // resolved to 1e-8 of itself.
            if outer < crate::light::Spot::MIN_OUTER_DEG {
                let sp = d.outer.as_ref().map_or(l.span(), Spanned::span);
                return Err(ctx.invalid(
                    sp,
                    "outer",
                    format!(
                        "must be at least {} degrees (a narrower cone is below what its cosine resolves in double precision), got {}",
                        crate::light::Spot::MIN_OUTER_DEG,
                        crate::io::format_number(outer)
                    ),
                ));
            }
            // `i` above took a flux as isotropic: a spot's flux fills its cones.
            let unit = crate::light::Spot::new(p, axis, inner.to_radians(), outer.to_radians(), 1.0);
            let i0 = if d.flux.is_some() { i * 4.0 * PI / unit.power() } else { i };
            Ok((
                Light::Spot(crate::light::Spot { i0, ..unit }),
                None,
            ))
        }
        other => Err(ctx.invalid(
            d.kind.span(),
            "type",
            format!(
                "unknown light type `{other}` (this version knows: point, sphere, spot, ies, ldt, rectangle, disc, distant, environment, sky, sun)"
            ),
        )),
    }
}

/// A distant light (`type = "distant"`): `direction` (the direction the
/// light travels, from the sun towards the scene), `illuminance` \[lx\] on a
/// plane normal to it and `angular_diameter` \[deg\] (default 0). Its start
/// region is fitted when the scene is built.
fn distant(l: &Spanned<LightDesc>, ctx: &SourceCtx) -> Result<(Light, Option<String>), SceneError> {
    let d = l.get_ref();
    let others = [
        ("position", d.position.as_ref().map(Spanned::span)),
        ("center", d.center.as_ref().map(Spanned::span)),
        ("radius", d.radius.as_ref().map(Spanned::span)),
        ("intensity", d.intensity.as_ref().map(Spanned::span)),
        ("flux", d.flux.as_ref().map(Spanned::span)),
        ("file", d.file.as_ref().map(Spanned::span)),
        ("aim", d.aim.as_ref().map(Spanned::span)),
        ("rotate", d.rotate.as_ref().map(Spanned::span)),
        ("multiplier", d.multiplier.as_ref().map(Spanned::span)),
        ("opening", d.opening.as_ref().map(Spanned::span)),
        ("inner", d.inner.as_ref().map(Spanned::span)),
        ("outer", d.outer.as_ref().map(Spanned::span)),
        ("corner", d.corner.as_ref().map(Spanned::span)),
        ("edge1", d.edge1.as_ref().map(Spanned::span)),
        ("edge2", d.edge2.as_ref().map(Spanned::span)),
        ("normal", d.normal.as_ref().map(Spanned::span)),
        ("luminance", d.luminance.as_ref().map(Spanned::span)),
        ("sides", d.sides.as_ref().map(Spanned::span)),
        ("profile", d.profile.as_ref().map(Spanned::span)),
        ("material", d.material.as_ref().map(Spanned::span)),
    ];
    if let Some((name, Some(span))) = others.iter().find(|f| f.1.is_some()) {
        return Err(ctx.invalid(
            span.clone(),
            name,
            "not allowed for a `distant` light (it takes `direction`, `illuminance`, `angular_diameter`)",
        ));
    }
    let dir = ctx.unit_vec(
        ctx.required(&d.direction, l.span(), "direction")?,
        "direction",
    )?;
    distant_along(l, ctx, dir, 0.0)
}

/// A distant light travelling along unit `dir` with the `illuminance` and
/// `angular_diameter` \[deg\] (default `diam`) of `l`.
fn distant_along(
    l: &Spanned<LightDesc>,
    ctx: &SourceCtx,
    dir: DVec3,
    default_diam: f64,
) -> Result<(Light, Option<String>), SceneError> {
    let d = l.get_ref();
    let es = ctx.required(&d.illuminance, l.span(), "illuminance")?;
    let e_n = ctx.nonneg(es, "illuminance")?;
    if e_n > MAX_INTENSITY {
        return Err(ctx.invalid(
            es.span(),
            "illuminance",
            format!("out of range: at most {MAX_INTENSITY:e} lx; results scale exactly with it, so rescale the input"),
        ));
    }
    let diam = match &d.angular_diameter {
        None => default_diam,
        Some(a) => {
            let x = *a.get_ref();
            let max = crate::light::Distant::MAX_DIAMETER_DEG;
            if !(x.is_finite() && (0.0..=max).contains(&x)) {
                return Err(ctx.invalid(
                    a.span(),
                    "angular_diameter",
                    format!(
                        "must lie in [0, {max}] degrees, got {}",
                        crate::io::format_number(x)
                    ),
                ));
            }
            x
        }
    };
    let region = crate::light::StartRegion::fit(None, &[], &[]);
    let light = crate::light::Distant::new(dir, e_n, diam.to_radians(), region);
    Ok((Light::Distant(std::sync::Arc::new(light)), None))
}

/// Every optional key of a `[[light]]` table with its span, if given.
fn light_keys(d: &LightDesc) -> Vec<(&'static str, Option<Range<usize>>)> {
    macro_rules! keys {
        ($($f:ident),*) => { vec![$((stringify!($f), d.$f.as_ref().map(Spanned::span))),*] };
    }
    keys!(
        position,
        center,
        radius,
        intensity,
        flux,
        file,
        aim,
        rotate,
        multiplier,
        opening,
        direction,
        inner,
        outer,
        corner,
        edge1,
        edge2,
        normal,
        luminance,
        sides,
        profile,
        material,
        illuminance,
        angular_diameter,
        scale,
        horizontal_illuminance,
        mapping,
        sampling,
        lights,
        sky,
        zenith_luminance,
        ground_luminance,
        sun_altitude,
        sun_azimuth,
        date,
        time,
        utc_offset,
        latitude,
        longitude
    )
}

/// A warning for a scene far from the origin for its size: its finite
/// shapes lie more than [`FAR_FROM_ORIGIN`] times their extent from it.
/// Positions there are resolved to a share of the coordinates, not of the
/// scene, and the steps that take a light standing on a surface or a point
/// on a wall's foot off it are 1e-8 of the coordinates: 6.4 cm at 6.4e6 m
/// (georeferenced coordinates), where a reviewer measured a plate 5 cm
/// below a ceiling light missed by its shadow test and points at a wall's
/// foot reading +3.7 %, flagged ok. Translating the scene and the points
/// near the origin gives the answer at the origin.
fn far_from_origin(scene: &Scene) -> Option<String> {
    let (lo, hi) = scene.finite_bounds()?;
    let extent = (hi - lo).length();
    let far = lo.abs().max(hi.abs()).max_element();
    (extent > 0.0 && far > FAR_FROM_ORIGIN * extent).then(|| {
        format!(
            "WARNING: the scene lies up to {far:.3e} m from the origin, {:.0} times its own size \
             ({extent:.3e} m): positions are resolved to a share of the coordinates there, and \
             lights standing on surfaces and points at the foot of walls are stepped {:.1e} m off \
             them (1e-8 of the coordinates), enough to change the answer next to them; translate \
             the scene and the points near the origin",
            far / extent,
            1e-8 * far
        )
    })
}

/// Ratio of a scene's distance from the origin to its extent above which
/// it is warned of ([`far_from_origin`]).
const FAR_FROM_ORIGIN: f64 = 1000.0;

/// The days in month `m` (1-12) of Gregorian year `y`: February has 29 in
/// years divisible by 4, except centuries not divisible by 400.
fn days_in_month(y: i32, m: u32) -> u32 {
    match m {
        4 | 6 | 9 | 11 => 30,
        2 if (y % 4 == 0 && y % 100 != 0) || y % 400 == 0 => 29,
        2 => 28,
        _ => 31,
    }
}

/// The sun's unit direction (towards it) from `sun_altitude` and
/// `sun_azimuth` \[deg\], or from `date`, `time`, `utc_offset`, `latitude`
/// and `longitude` ([`crate::light::sun_position`]), with a note.
fn sun_position(l: &Spanned<LightDesc>, ctx: &SourceCtx) -> Result<(DVec3, String), SceneError> {
    use crate::light::sun_position::{UtcTime, solar_position, sun_direction};
    let d = l.get_ref();
    let finite = |v: &Spanned<f64>, field: &str, lo: f64, hi: f64| {
        let x = *v.get_ref();
        if x.is_finite() && (lo..=hi).contains(&x) {
            Ok(x)
        } else {
            Err(ctx.invalid(
                v.span(),
                field,
                format!(
                    "must lie in [{lo}, {hi}], got {}",
                    crate::io::format_number(x)
                ),
            ))
        }
    };
    if let (Some(alt), Some(az)) = (&d.sun_altitude, &d.sun_azimuth) {
        for (k, v) in [
            ("date", d.date.as_ref().map(Spanned::span)),
            ("time", d.time.as_ref().map(Spanned::span)),
            ("latitude", d.latitude.as_ref().map(Spanned::span)),
            ("longitude", d.longitude.as_ref().map(Spanned::span)),
            ("utc_offset", d.utc_offset.as_ref().map(Spanned::span)),
        ] {
            if let Some(span) = v {
                return Err(ctx.invalid(
                    span,
                    k,
                    "give the sun's position either by `sun_altitude` and `sun_azimuth` or by date, time and place, not both",
                ));
            }
        }
        let a = finite(alt, "sun_altitude", -90.0, 90.0)?;
        let z = finite(az, "sun_azimuth", -360.0, 360.0)?;
        return Ok((
            sun_direction(a, z),
            format!("sun at altitude {a} deg, azimuth {z} deg"),
        ));
    }
    if let Some(x) = d.sun_altitude.as_ref().or(d.sun_azimuth.as_ref()) {
        let field = if d.sun_altitude.is_some() {
            "sun_altitude"
        } else {
            "sun_azimuth"
        };
        return Err(ctx.invalid(
            x.span(),
            field,
            "give both `sun_altitude` and `sun_azimuth` [deg]",
        ));
    }
    let ds = ctx.required(&d.date, l.span(), "date (or sun_altitude and sun_azimuth)")?;
    let ts = ctx.required(&d.time, l.span(), "time")?;
    let lat = finite(
        ctx.required(&d.latitude, l.span(), "latitude")?,
        "latitude",
        -90.0,
        90.0,
    )?;
    let lon = finite(
        ctx.required(&d.longitude, l.span(), "longitude")?,
        "longitude",
        -180.0,
        180.0,
    )?;
    let off = match &d.utc_offset {
        Some(o) => finite(o, "utc_offset", -14.0, 14.0)?,
        None => 0.0,
    };
    let date: Vec<&str> = ds.get_ref().split('-').collect();
    let ymd = match date.as_slice() {
        [y, m, dd] => (
            y.parse::<i32>().ok(),
            m.parse::<u32>().ok(),
            dd.parse::<u32>().ok(),
        ),
        _ => (None, None, None),
    };
    let (year, month, day) = match ymd {
        (Some(y), Some(m), Some(dd))
            if (1800..=2100).contains(&y) && (1..=12).contains(&m) && dd >= 1 =>
        {
            let last = days_in_month(y, m);
            if dd > last {
                return Err(ctx.invalid(
                    ds.span(),
                    "date",
                    format!(
                        "`{}` is not a date: month {m} of {y} has {last} days (Gregorian calendar)",
                        ds.get_ref()
                    ),
                ));
            }
            (y, m, dd)
        }
        _ => {
            return Err(ctx.invalid(
                ds.span(),
                "date",
                format!(
                    "`{}` is not a date YYYY-MM-DD (years 1800-2100, where the sun position's algorithm holds to 0.01 degree)",
                    ds.get_ref()
                ),
            ));
        }
    };
    let hms: Vec<Option<f64>> = ts
        .get_ref()
        .split(':')
        .map(|x| x.parse::<f64>().ok())
        .collect();
    let hour = match hms.as_slice() {
        [Some(h), Some(m)] if (0.0..24.0).contains(h) && (0.0..60.0).contains(m) => h + m / 60.0,
        [Some(h), Some(m), Some(sec)]
            if (0.0..24.0).contains(h) && (0.0..60.0).contains(m) && (0.0..61.0).contains(sec) =>
        {
            h + m / 60.0 + sec / 3600.0
        }
        _ => {
            return Err(ctx.invalid(
                ts.span(),
                "time",
                format!("`{}` is not a clock time HH:MM or HH:MM:SS", ts.get_ref()),
            ));
        }
    };
    // Local clock time to UTC (the day may change; the Julian day handles
    // hours outside 0-24).
    let t = UtcTime {
        year,
        month,
        day,
        hour: hour - off,
    };
    let p = solar_position(&t, lat, lon);
    Ok((
        sun_direction(p.altitude, p.azimuth),
        format!(
            "sun on {} at {} (UTC{off:+}) at latitude {lat}, longitude {lon}: altitude {:.3} deg, azimuth {:.3} deg (NOAA/Meeus, no refraction)",
            ds.get_ref(),
            ts.get_ref(),
            p.altitude,
            p.azimuth
        ),
    ))
}

/// A CIE sky (`type = "sky"`: `sky`, `zenith_luminance` [cd/m^2] or
/// `horizontal_illuminance` \[lx\], `ground_luminance`, and the sun's
/// position for the general skies) as an environment light with an exact
/// luminance ([`crate::light::Environment::from_sky`]); or the sun (`type =
/// "sun"`: a distant light from the sun's position with `illuminance` \[lx\]
/// normal to it and `angular_diameter`, default 0.53 degrees).
fn daylight(
    l: &Spanned<LightDesc>,
    ctx: &SourceCtx,
) -> Result<(Light, Option<String>), SceneError> {
    use crate::light::sky::{Sky, SkyModel};
    let d = l.get_ref();
    let kind = d.kind.get_ref().as_str();
    let sun_keys = [
        "sun_altitude",
        "sun_azimuth",
        "date",
        "time",
        "utc_offset",
        "latitude",
        "longitude",
    ];
    let allowed: Vec<&str> = if kind == "sun" {
        let mut v = vec!["illuminance", "angular_diameter"];
        v.extend(sun_keys);
        v
    } else {
        let mut v = vec![
            "sky",
            "zenith_luminance",
            "horizontal_illuminance",
            "ground_luminance",
        ];
        v.extend(sun_keys);
        v
    };
    for (name, span) in light_keys(d) {
        if let Some(span) = span
            && !allowed.contains(&name)
        {
            return Err(ctx.invalid(
                span,
                name,
                format!(
                    "not allowed for a `{kind}` light (it takes {})",
                    allowed.join(", ")
                ),
            ));
        }
    }
    if kind == "sun" {
        let (to_sun, note) = sun_position(l, ctx)?;
        if to_sun.z < 0.0 {
            return Err(ctx.invalid(
                l.span(),
                "sun",
                format!("{note}: the sun is below the horizon"),
            ));
        }
        let (light, _) = distant_along(l, ctx, -to_sun, 0.53)?;
        return Ok((light, Some(note)));
    }
    let ms = ctx.required(&d.sky, l.span(), "sky")?;
    let name = ms.get_ref().as_str();
    let general = match name {
        "overcast" => None,
        "clear" => Some(12u8),
        other => match other
            .strip_prefix("cie-")
            .and_then(|k| k.parse::<u8>().ok())
        {
            Some(k) if (1..=15).contains(&k) => Some(k),
            _ => {
                return Err(ctx.invalid(
                    ms.span(),
                    "sky",
                    format!("unknown sky `{other}` (use \"overcast\", \"clear\" or \"cie-1\" to \"cie-15\")"),
                ));
            }
        },
    };
    let (model, mut note) = match general {
        None => {
            if let Some((k, Some(span))) = light_keys(d)
                .into_iter()
                .find(|(k, s)| sun_keys.contains(k) && s.is_some())
            {
                return Err(ctx.invalid(
                    span,
                    k,
                    "the traditional CIE overcast sky does not depend on the sun: leave out its position",
                ));
            }
            (
                SkyModel::TraditionalOvercast,
                "traditional CIE overcast sky".to_string(),
            )
        }
        Some(k) => {
            let (sun, note) = sun_position(l, ctx)?;
            (
                SkyModel::General { kind: k, sun },
                format!("CIE general sky type {k}, {note}"),
            )
        }
    };
    let sky = Sky::new(model).map_err(|e| ctx.invalid(l.span(), "sky", e.to_string()))?;
    let sky = match (&d.zenith_luminance, &d.horizontal_illuminance) {
        (Some(z), None) => sky
            .with_zenith_luminance(ctx.nonneg(z, "zenith_luminance")?)
            .map_err(|e| ctx.invalid(z.span(), "zenith_luminance", e.to_string()))?,
        (None, Some(h)) => sky
            .with_horizontal_illuminance(ctx.nonneg(h, "horizontal_illuminance")?)
            .map_err(|e| ctx.invalid(h.span(), "horizontal_illuminance", e.to_string()))?,
        (Some(_), Some(h)) => {
            return Err(ctx.invalid(
                h.span(),
                "horizontal_illuminance",
                "give either `zenith_luminance` [cd/m^2] or `horizontal_illuminance` [lx], not both",
            ));
        }
        (None, None) => {
            return Err(ctx.invalid(
                l.span(),
                "zenith_luminance",
                "a sky needs `zenith_luminance` [cd/m^2] or `horizontal_illuminance` [lx]",
            ));
        }
    };
    let sky = match &d.ground_luminance {
        Some(g) => sky
            .with_ground_luminance(ctx.nonneg(g, "ground_luminance")?)
            .map_err(|e| ctx.invalid(g.span(), "ground_luminance", e.to_string()))?,
        None => sky,
    };
    if sky.zenith_luminance() > MAX_INTENSITY || sky.ground_luminance() > MAX_INTENSITY {
        return Err(ctx.invalid(
            l.span(),
            "zenith_luminance",
            format!("out of range: luminances at most {MAX_INTENSITY:e} cd/m^2"),
        ));
    }
    note = format!(
        "{note}: zenith luminance {:.6e} cd/m^2, {:.6e} lx on an unobstructed horizontal plane",
        sky.zenith_luminance(),
        sky.horizontal_illuminance()
    );
    let env = crate::light::Environment::from_sky(sky, 256)
        .map_err(|m| ctx.invalid(l.span(), "sky", m))?;
    Ok((Light::Environment(std::sync::Arc::new(env)), Some(note)))
}

/// An environment light (`type = "environment"`): `file` (an HDR map,
/// relative to the scene file), `mapping` (`"equirect"`, default, or
/// `"angular"`), `rotate` \[deg\] about the vertical, and `scale` (pixel value
/// times scale is luminance [cd/m^2]; default 1) or `horizontal_illuminance`
/// \[lx\] (the map scaled to give it on an unobstructed horizontal plane).
fn environment(
    l: &Spanned<LightDesc>,
    ctx: &SourceCtx,
) -> Result<(Light, Option<String>), SceneError> {
    use crate::light::{Environment, Mapping};
    let d = l.get_ref();
    let others = [
        ("position", d.position.as_ref().map(Spanned::span)),
        ("center", d.center.as_ref().map(Spanned::span)),
        ("radius", d.radius.as_ref().map(Spanned::span)),
        ("intensity", d.intensity.as_ref().map(Spanned::span)),
        ("flux", d.flux.as_ref().map(Spanned::span)),
        ("aim", d.aim.as_ref().map(Spanned::span)),
        ("multiplier", d.multiplier.as_ref().map(Spanned::span)),
        ("opening", d.opening.as_ref().map(Spanned::span)),
        ("direction", d.direction.as_ref().map(Spanned::span)),
        ("inner", d.inner.as_ref().map(Spanned::span)),
        ("outer", d.outer.as_ref().map(Spanned::span)),
        ("corner", d.corner.as_ref().map(Spanned::span)),
        ("edge1", d.edge1.as_ref().map(Spanned::span)),
        ("edge2", d.edge2.as_ref().map(Spanned::span)),
        ("normal", d.normal.as_ref().map(Spanned::span)),
        ("luminance", d.luminance.as_ref().map(Spanned::span)),
        ("sides", d.sides.as_ref().map(Spanned::span)),
        ("profile", d.profile.as_ref().map(Spanned::span)),
        ("material", d.material.as_ref().map(Spanned::span)),
        ("illuminance", d.illuminance.as_ref().map(Spanned::span)),
        (
            "angular_diameter",
            d.angular_diameter.as_ref().map(Spanned::span),
        ),
    ];
    if let Some((name, Some(span))) = others.iter().find(|f| f.1.is_some()) {
        return Err(ctx.invalid(
            span.clone(),
            name,
            "not allowed for an `environment` light (it takes `file`, `mapping`, `rotate`, `scale` or `horizontal_illuminance`)",
        ));
    }
    median_cut_request(l, ctx)?;
    let fs = ctx.required(&d.file, l.span(), "file")?;
    let path = ctx.relative(fs.get_ref());
    let map = crate::io::envmap::read_luminance_map(&path)
        .map_err(|m| ctx.invalid(fs.span(), "file", m))?;
    let mapping = match &d.mapping {
        None => Mapping::Equirect,
        Some(m) => match m.get_ref().as_str() {
            "equirect" => Mapping::Equirect,
            "angular" => Mapping::Angular,
            other => {
                return Err(ctx.invalid(
                    m.span(),
                    "mapping",
                    format!("unknown mapping `{other}` (use \"equirect\" or \"angular\")"),
                ));
            }
        },
    };
    let rotate = match &d.rotate {
        None => 0.0,
        Some(r) => {
            let x = *r.get_ref();
            if !x.is_finite() {
                return Err(ctx.invalid(r.span(), "rotate", "must be finite [deg]"));
            }
            x.to_radians()
        }
    };
    let build = |scale: f64, span: Range<usize>, field: &str| {
        Environment::new(&map.y, map.width, map.height, mapping, scale, rotate)
            .map_err(|m| ctx.invalid(span, field, m))
    };
    let env = match (&d.scale, &d.horizontal_illuminance) {
        (Some(_), Some(h)) => {
            return Err(ctx.invalid(
                h.span(),
                "horizontal_illuminance",
                "give either `scale` or `horizontal_illuminance` [lx], not both",
            ));
        }
        (Some(s), None) => {
            let k = ctx.nonneg(s, "scale")?;
            build(k, s.span(), "scale")?
        }
        (None, Some(h)) => {
            let e = ctx.nonneg(h, "horizontal_illuminance")?;
            let unit = build(1.0, fs.span(), "file")?;
            let e1 = unit.horizontal_illuminance();
            if e1 <= 0.0 {
                return Err(ctx.invalid(
                    h.span(),
                    "horizontal_illuminance",
                    "the map's upper hemisphere is black: no scale gives a horizontal illuminance",
                ));
            }
            build(e / e1, h.span(), "horizontal_illuminance")?
        }
        (None, None) => build(1.0, fs.span(), "file")?,
    };
    if !(env.integral().is_finite() && env.integral() <= MAX_INTENSITY) {
        return Err(ctx.invalid(
            fs.span(),
            "file",
            format!("the map's luminance integrated over the sphere must be finite and at most {MAX_INTENSITY:e} cd/m^2 sr: rescale it"),
        ));
    }
    let header = map.header_note();
    let note = format!(
        "environment map `{}`: {} x {} pixels ({}{}{}), {:.6e} lx on an unobstructed horizontal plane, int L dw = {:.6e} cd/m^2 sr",
        fs.get_ref(),
        map.width,
        map.height,
        if mapping == Mapping::Angular {
            "angular, resampled"
        } else {
            "equirectangular"
        },
        if header.is_empty() { "" } else { "; " },
        header,
        env.horizontal_illuminance(),
        env.integral()
    );
    Ok((Light::Environment(std::sync::Arc::new(env)), Some(note)))
}

/// The number of median-cut lights an environment light asks for
/// (`sampling = "median-cut"`, `lights = N`, default 64, a power of two up
/// to 4096), or `None` for importance sampling (`sampling = "importance"`,
/// the default).
fn median_cut_request(
    l: &Spanned<LightDesc>,
    ctx: &SourceCtx,
) -> Result<Option<usize>, SceneError> {
    let d = l.get_ref();
    let cut = match &d.sampling {
        None => false,
        Some(s) => match s.get_ref().as_str() {
            "importance" => false,
            "median-cut" => true,
            other => {
                return Err(ctx.invalid(
                    s.span(),
                    "sampling",
                    format!("unknown sampling `{other}` (use \"importance\" or \"median-cut\")"),
                ));
            }
        },
    };
    match (&d.lights, cut) {
        (Some(n), false) => {
            Err(ctx.invalid(n.span(), "lights", "only with `sampling = \"median-cut\"`"))
        }
        (None, false) => Ok(None),
        (None, true) => Ok(Some(64)),
        (Some(n), true) => {
            let v = *n.get_ref();
            if !(1..=4096).contains(&v) || !(v as u64).is_power_of_two() {
                return Err(ctx.invalid(
                    n.span(),
                    "lights",
                    format!("must be a power of two from 1 to 4096, got {v}"),
                ));
            }
            Ok(Some(v as usize))
        }
    }
}

/// A Lambertian area source (`type = "rectangle"` or `"disc"`): its shape
/// (`corner`, `edge1`, `edge2`, emitting towards `edge1 x edge2`; or
/// `center`, `normal` = the emitting side, `radius`), `luminance` [cd/m^2]
/// at the profile's peak or `flux` \[lm\], `sides` (`"front"` or `"both"`),
/// a disc's radial `profile` and the surface's `material` (default black).
fn area(l: &Spanned<LightDesc>, ctx: &SourceCtx) -> Result<(Light, Option<String>), SceneError> {
    use crate::light::radial_profile::RadialProfile;
    use crate::light::{AreaLight, AreaShape};
    let d = l.get_ref();
    let kind = d.kind.get_ref().as_str();
    let rect = kind == "rectangle";
    let foreign = [
        ("position", d.position.as_ref().map(Spanned::span)),
        ("intensity", d.intensity.as_ref().map(Spanned::span)),
        ("file", d.file.as_ref().map(Spanned::span)),
        ("aim", d.aim.as_ref().map(Spanned::span)),
        ("rotate", d.rotate.as_ref().map(Spanned::span)),
        ("multiplier", d.multiplier.as_ref().map(Spanned::span)),
        ("opening", d.opening.as_ref().map(Spanned::span)),
        ("direction", d.direction.as_ref().map(Spanned::span)),
        ("inner", d.inner.as_ref().map(Spanned::span)),
        ("outer", d.outer.as_ref().map(Spanned::span)),
    ];
    let by_shape = if rect {
        [
            ("center", d.center.as_ref().map(Spanned::span)),
            ("normal", d.normal.as_ref().map(Spanned::span)),
            ("radius", d.radius.as_ref().map(Spanned::span)),
            ("profile", d.profile.as_ref().map(Spanned::span)),
        ]
    } else {
        [
            ("corner", d.corner.as_ref().map(Spanned::span)),
            ("edge1", d.edge1.as_ref().map(Spanned::span)),
            ("edge2", d.edge2.as_ref().map(Spanned::span)),
            ("position", None),
        ]
    };
    for (name, span) in foreign.into_iter().chain(by_shape) {
        if let Some(span) = span {
            return Err(ctx.invalid(span, name, format!("not allowed for a `{kind}` light")));
        }
    }
    let vec = |v: &Option<Spanned<Vec3>>, field: &str| {
        ctx.finite_vec(ctx.required(v, l.span(), field)?, field)
    };
    let shape = if rect {
        let corner = vec(&d.corner, "corner")?;
        let e1 = vec(&d.edge1, "edge1")?;
        let e2 = vec(&d.edge2, "edge2")?;
        if Rect::new(corner, e1, e2).is_none() {
            return Err(ctx.invalid(
                d.edge2.as_ref().map_or(l.span(), Spanned::span),
                "edge2",
                "the edges must be non-zero and not parallel",
            ));
        }
        AreaShape::Rect { corner, e1, e2 }
    } else {
        let center = vec(&d.center, "center")?;
        let normal = ctx.unit_vec(ctx.required(&d.normal, l.span(), "normal")?, "normal")?;
        let radius = positive(ctx.required(&d.radius, l.span(), "radius")?, "radius", ctx)?;
        let profile = match &d.profile {
            Some(p) => RadialProfile::parse(p.get_ref(), radius)
                .map_err(|m| ctx.invalid(p.span(), "profile", m))?,
            None => RadialProfile::uniform(radius),
        };
        AreaShape::Disc {
            center,
            normal,
            radius,
            profile,
        }
    };
    let two_sided = match &d.sides {
        None => false,
        Some(s) if s.get_ref() == "front" => false,
        Some(s) if s.get_ref() == "both" => true,
        Some(s) => {
            return Err(ctx.invalid(
                s.span(),
                "sides",
                format!("must be `front` or `both`, got `{}`", s.get_ref()),
            ));
        }
    };
    let material = match &d.material {
        Some(m) => material(m, ctx)?,
        None => Material::Lambertian { rho: 0.0 },
    };
    let mut light = AreaLight {
        shape,
        l0: 1.0,
        two_sided,
        material,
        surface: u32::MAX,
    };
    // The flux of a unit peak luminance.
    let unit = light.power();
    light.l0 = match (&d.luminance, &d.flux) {
        (Some(v), None) => ctx.nonneg(v, "luminance")?,
        (None, Some(f)) => {
            let f = ctx.nonneg(f, "flux")?;
            if !(unit > 0.0 && unit.is_finite()) {
                return Err(ctx.invalid(
                    f_span(d, l),
                    "flux",
                    format!("the source's emitting area weighted by its profile is {unit:e} m^2: it cannot carry a flux"),
                ));
            }
            f / unit
        }
        (Some(_), Some(f)) => {
            return Err(ctx.invalid(
                f.span(),
                "flux",
                "give either `luminance` [cd/m^2] or `flux` [lm], not both",
            ));
        }
        (None, None) => {
            return Err(ctx.invalid(
                l.span(),
                "luminance",
                "missing field (give `luminance` [cd/m^2] or `flux` [lm])",
            ));
        }
    };
    if !(light.power().is_finite()
        && light.l0 <= MAX_INTENSITY
        && (light.l0 == 0.0 || light.l0 >= MIN_INTENSITY))
    {
        return Err(ctx.invalid(
            d.luminance
                .as_ref()
                .map_or_else(|| f_span(d, l), Spanned::span),
            if d.luminance.is_some() {
                "luminance"
            } else {
                "flux"
            },
            format!(
                "out of range: the luminance must be 0 or between {MIN_INTENSITY:e} and {MAX_INTENSITY:e} cd/m^2"
            ),
        ));
    }
    Ok((Light::Area(std::sync::Arc::new(light)), None))
}

fn f_span(d: &LightDesc, l: &Spanned<LightDesc>) -> Range<usize> {
    d.flux.as_ref().map_or(l.span(), Spanned::span)
}

/// A goniometric luminaire (`type = "ies"` or `"ldt"`): the photometric
/// file, its placement and orientation, and an optional `flux` \[lm\] or
/// `multiplier` on its candela values, times an IES tilt table's factor
/// at the installed tilt ([`crate::io::photometry::Tilt`]); with a note
/// for the run summary (the table's flux against the file's lamp lumens).
fn goniometric(
    l: &Spanned<LightDesc>,
    ctx: &SourceCtx,
    tables: &mut GonioTables,
) -> Result<(Light, Option<String>), SceneError> {
    use crate::light::{Goniometric, LuminaireFrame};
    let d = l.get_ref();
    let kind = d.kind.get_ref().as_str();
    for (name, span) in [
        ("intensity", d.intensity.as_ref().map(Spanned::span)),
        ("center", d.center.as_ref().map(Spanned::span)),
        ("radius", d.radius.as_ref().map(Spanned::span)),
    ] {
        if let Some(span) = span {
            return Err(ctx.invalid(
                span,
                name,
                format!("not allowed for a `{kind}` luminaire (its file gives the intensities; scale them with `flux` or `multiplier`)"),
            ));
        }
    }
    let fs = ctx.required(&d.file, l.span(), "file")?;
    let path = ctx.relative(fs.get_ref());
    let ext_ok = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(kind));
    if !ext_ok {
        return Err(ctx.invalid(
            fs.span(),
            "file",
            format!(
                "a `{kind}` luminaire needs a .{kind} file, got `{}`",
                fs.get_ref()
            ),
        ));
    }
    let photometry = crate::io::photometry::read(&path)
        .map_err(|e| ctx.invalid(fs.span(), "file", e.to_string()))?;
    let p = ctx.finite_vec(ctx.required(&d.position, l.span(), "position")?, "position")?;
    let aim = match &d.aim {
        Some(a) => ctx.unit_vec(a, "aim")?,
        None => -DVec3::Z,
    };
    let rotate = match &d.rotate {
        Some(r) if r.get_ref().is_finite() => r.get_ref().to_radians(),
        Some(r) => return Err(ctx.invalid(r.span(), "rotate", "must be a finite angle [deg]")),
        None => 0.0,
    };
    let frame = LuminaireFrame::aimed(aim, rotate);
    // An IES tilt table: its factor at the installed tilt (the aim, and
    // for a horizontal lamp the rotation) multiplies every intensity, on
    // top of `flux` or `multiplier`, which scale the file's table.
    let (tilt_factor, tilt_angle) = photometry.tilt_factor(frame.x, frame.y, frame.z);
    let mut table = |scale: f64| {
        tables
            .entry((path.clone(), scale.to_bits()))
            .or_insert_with(|| std::sync::Arc::new(Goniometric::new(&photometry, scale)))
            .clone()
    };
    let unscaled = table(1.0);
    let scale = match (&d.flux, &d.multiplier) {
        (Some(_), Some(m)) => {
            return Err(ctx.invalid(
                m.span(),
                "multiplier",
                "give either `flux` [lm] or `multiplier`, not both",
            ));
        }
        (Some(f), None) => {
            let f = ctx.nonneg(f, "flux")?;
            if unscaled.power() <= 0.0 {
                return Err(ctx.invalid(
                    fs.span(),
                    "file",
                    "the table emits nothing: it cannot be scaled to a flux",
                ));
            }
            f / unscaled.power()
        }
        (None, Some(m)) => ctx.nonneg(m, "multiplier")?,
        (None, None) => 1.0,
    };
    let dist = table(scale * tilt_factor);
    if let Some(e) = dist.range_error() {
        return Err(ctx.invalid(fs.span(), "file", e));
    }
    let lamps = photometry.lamp_lumens.map_or_else(
        || "absolute photometry".to_string(),
        |lm| format!("{:.4} x the file's {lm} lamp lumens", unscaled.power() / lm),
    );
    let tilted = match (&photometry.tilt, tilt_angle) {
        (Some(t), Some(a)) => format!(
            "; TILT lamp {:?} at {a:.4} deg: factor {tilt_factor:.6}",
            t.geometry
        ),
        _ => String::new(),
    };
    let note = format!(
        "{} `{}`: table flux {:.6e} lm ({lamps}){tilted}; emitting {:.6e} lm, max {:.6e} cd",
        photometry.format,
        fs.get_ref(),
        unscaled.power(),
        dist.power(),
        dist.max_intensity()
    );
    let opening = match &d.opening {
        Some(o) if *o.get_ref() => Some(
            crate::light::LuminousShape::of(&photometry.opening).ok_or_else(|| {
                ctx.invalid(
                    o.span(),
                    "opening",
                    format!(
                        "`{}` gives no luminous shape with an area (its luminous shape: {}, width {} m, length {} m, height {} m): it can only be a point",
                        fs.get_ref(),
                        photometry.opening.shape.name(
                            photometry.opening.width,
                            photometry.opening.length,
                            photometry.opening.height
                        ),
                        photometry.opening.width,
                        photometry.opening.length,
                        photometry.opening.height
                    ),
                )
            })?,
        ),
        _ => None,
    };
    let note = match &opening {
        Some(o) => format!("{note}; emitting from its luminous shape: {}", o.describe()),
        None => note,
    };
    Ok((
        Light::Gonio {
            p,
            frame,
            dist,
            opening,
        },
        Some(note),
    ))
}
