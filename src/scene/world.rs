//! The compiled scene: surfaces with their shapes and materials, lights, and
//! the two geometric queries the estimators need (nearest hit, visibility).
//!
//! **What is built is what the scene uses.** Shapes are kept in one list per
//! kind; a kind absent from the scene costs an empty loop and nothing else.
//! A planes-only scene has no BVH, no SH machinery and takes the bit-mask
//! visibility fast path ([`Scene::planes_only`]); the mesh BVH is built only
//! for meshes and the spherical-harmonic root finder only for SH objects.
//! A scene with [`AUTO_MIN_SHAPES`] or more finite shapes puts them in a
//! top-level BVH (`world/shape_tree.rs`; [`Accel`]), so that the nearest-hit
//! and visibility queries cost `log n`; fewer are tested in loops, which is
//! faster then. Both give the same answers bit for bit: every shape is
//! tested by the same code, and the nearest hit is decided from the set of
//! hits by rules that do not depend on the order (`world/nearest.rs`).
//! [`Scene::summary`] reports what was built.
//!
//! **Sides.** Every shape has a *geometric* normal (a plane's, rectangle's or
//! disc's given normal, outward for spheres, boxes and SH objects, the
//! winding normal of mesh triangles). A surface reflects on the side(s) its
//! [`Sides`] names; the other side is black. Every surface is opaque.

mod light_seat;
mod mesh_lit_side;
mod nearest;
mod occluders;
mod panes;
mod shape_tree;

pub use light_seat::LightSeat;
pub use occluders::{CELL_DARK, CELL_REST, Occluder};
pub use panes::{Pane, PaneHit, PaneShape};

pub use shape_tree::{AUTO_MIN_SHAPES, Accel};

use crate::geometry::bvh::{Ends, RayQuery};
use crate::geometry::mesh::Mesh;
use crate::geometry::sh::ShSurface;
use crate::geometry::shapes::{AaBox, Disc, Flat, Inside, Rect, Sphere};
use crate::geometry::{Hit, Plane, Ray, SideMask};
use crate::light::Light;
use crate::material::Material;
use glam::DVec3;
use nearest::{Cand, Nearest};
use shape_tree::ShapeTree;

/// Largest accepted coordinate magnitude \[m\] (also of a vector's
/// components). Where a point lies on a surface is decided to
/// `ON_PLANE_REL` (1e-11, `geometry`) of the coordinates' magnitude,
/// 2 mm here, so the geometry of a room is resolved anywhere within it (a
/// site's UTM coordinates fit); at 1e12 m, the bound before, a floor point
/// 1 m below a ceiling counted as on the ceiling (0 lx, flagged ok), and
/// at 3e10 m the direct light was lost. (Squares of lengths and fourth
/// powers of scores stay finite far beyond.) Re-centre a scene given in
/// larger coordinates.
pub const MAX_COORD: f64 = 1e8;

/// Largest accepted intensity \[cd\] (or luminance [cd/m^2]): results scale
/// exactly with it, and beyond it the fourth powers of scores in the
/// variance of the variance would overflow.
pub const MAX_INTENSITY: f64 = 1e60;

/// Smallest accepted non-zero intensity \[cd\] (or luminance [cd/m^2]):
/// below it scores would underflow.
pub const MIN_INTENSITY: f64 = 1e-60;

/// Relative tolerance within which the hit of a surface set onto another
/// (an emitter in a ceiling, a rectangle in a plane or on a box's face)
/// wins a tie with it ([`Scene::first_hit_from`], [`Scene::intersect`];
/// the rules: `world/nearest.rs`); also a luminaire's luminous opening
/// set into a ceiling against the ceiling
/// ([`crate::estimator::emitted_luminance`]).
pub const COINCIDENT_TIE: f64 = 1e-9;

/// Key of the first finite shape in the fixed order of the nearest-hit
/// ties (`nearest.rs`): planes come first, keyed by their index.
const FIRST_KEY: u32 = MAX_PLANES as u32;

/// A finite shape: its kind and index in that kind's list (a leaf of the
/// top-level BVH).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Prim {
    Rect(u32),
    Disc(u32),
    Sphere(u32),
    Box(u32),
    Mesh(u32),
    Sh(u32),
}

/// Which side(s) of a surface reflect, relative to its geometric normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sides {
    /// The side the geometric normal faces (a sphere's or box's outside).
    Front,
    /// The opposite side (a sphere's or box's inside).
    Back,
    /// Both sides, with the same material.
    Both,
}

impl Sides {
    /// The reflecting normal for light arriving along `d` at a point with
    /// geometric normal `ng`: the normal facing the arriving light when that
    /// side reflects; otherwise a normal with `d . n >= 0` (a black side).
    #[inline]
    pub fn orient(self, ng: DVec3, d: DVec3) -> DVec3 {
        match self {
            Sides::Front => ng,
            Sides::Back => -ng,
            Sides::Both => {
                if d.dot(ng) > 0.0 {
                    -ng
                } else {
                    ng
                }
            }
        }
    }

    /// Whether light arriving along `d` at a point with geometric normal
    /// `ng` meets a reflecting side (not the black one).
    #[inline]
    pub fn lit(self, ng: DVec3, d: DVec3) -> bool {
        match self {
            Sides::Front => d.dot(ng) < 0.0,
            Sides::Back => d.dot(ng) > 0.0,
            Sides::Both => true,
        }
    }

    /// The winding a one-sided mesh reflects on: `Some(true)` the front
    /// (`d . ng < 0`), `Some(false)` the back, `None` both.
    #[inline]
    pub fn front(self) -> Option<bool> {
        match self {
            Sides::Front => Some(true),
            Sides::Back => Some(false),
            Sides::Both => None,
        }
    }
}

/// The shape of a surface: an index into the scene's list of that kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeRef {
    /// Infinite plane `planes[i]` (bit `i` of the side masks).
    Plane(u32),
    /// Parallelogram `rects[i]`.
    Rect(u32),
    /// Disc `discs[i]`.
    Disc(u32),
    /// Sphere `spheres[i]`.
    Sphere(u32),
    /// Face `f` of box `boxes[i]` (face order [`crate::geometry::shapes::BOX_FACES`]).
    BoxFace(u32, u8),
    /// Triangle mesh `meshes[i]` (its BVH built on compile).
    Mesh(u32),
    /// Spherical-harmonic object `shs[i]`.
    Sh(u32),
    /// Glass pane `panes[i]` (not an opaque shape: see `world/panes.rs`).
    Pane(u32),
}

/// A reflecting surface of the compiled scene.
#[derive(Clone, Debug)]
pub struct Surface {
    /// Name from the file, or `surface #k` (box faces: `name.z_min` etc.).
    pub name: String,
    /// Its material.
    pub material: Material,
    /// Its shape.
    pub shape: ShapeRef,
    /// Which side(s) reflect.
    pub sides: Sides,
    /// The area light (index into [`Scene::lights`]) whose emitting
    /// surface this is, if any.
    pub emitter: Option<u32>,
}

/// A surface as handed to [`Scene::build`]: name, shape, sides, material(s).
#[derive(Clone, Debug)]
pub enum SurfaceSpec {
    /// Infinite plane, front side towards its normal.
    Plane(String, Plane, Material),
    /// Parallelogram.
    Rect(String, Rect, Sides, Material),
    /// Disc.
    Disc(String, Disc, Sides, Material),
    /// Sphere (geometric normal outward).
    Sphere(String, Sphere, Sides, Material),
    /// Axis-aligned box, one material per face (geometric normals outward).
    Box(String, AaBox, Sides, [Material; 6]),
    /// Triangle mesh (geometric normals by counter-clockwise winding).
    Mesh(String, Mesh, Sides, Material),
    /// Star-shaped spherical-harmonic object (geometric normal outward).
    Sh(String, ShSurface, Sides, Material),
}

/// Kinds and counts of what a compiled scene holds (only these are built).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SceneSummary {
    /// Number of infinite planes.
    pub planes: usize,
    /// Number of rectangles (parallelograms).
    pub rects: usize,
    /// Number of discs.
    pub discs: usize,
    /// Number of spheres.
    pub spheres: usize,
    /// Number of boxes.
    pub boxes: usize,
    /// Number of triangle meshes.
    pub meshes: usize,
    /// Number of spherical-harmonic objects.
    pub sh_objects: usize,
    /// Number of glass panes.
    pub panes: usize,
    /// Number of point lights.
    pub point_lights: usize,
    /// Number of sphere lights.
    pub sphere_lights: usize,
    /// Number of goniometric luminaires (IES, LDT).
    pub goniometric_lights: usize,
    /// Number of spot lights.
    pub spot_lights: usize,
    /// Number of area sources (their emitting surfaces are counted with
    /// the rectangles and discs).
    pub area_lights: usize,
    /// Whether an acceleration structure (BVH) was built.
    pub bvh: bool,
    /// Whether the spherical-harmonic machinery was built.
    pub sh: bool,
}

impl std::fmt::Display for SceneSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kinds = [
            (self.planes, "plane(s)"),
            (self.rects, "rectangle(s)"),
            (self.discs, "disc(s)"),
            (self.spheres, "sphere(s)"),
            (self.boxes, "box(es)"),
            (self.meshes, "mesh(es)"),
            (self.sh_objects, "SH object(s)"),
            (self.panes, "glass pane(s)"),
        ];
        let shapes: Vec<String> = kinds
            .iter()
            .filter(|k| k.0 > 0)
            .map(|k| format!("{} {}", k.0, k.1))
            .collect();
        let mut gonio = if self.goniometric_lights > 0 {
            format!(", {} goniometric luminaire(s)", self.goniometric_lights)
        } else {
            String::new()
        };
        if self.spot_lights > 0 {
            gonio.push_str(&format!(", {} spot light(s)", self.spot_lights));
        }
        if self.area_lights > 0 {
            gonio.push_str(&format!(", {} area source(s)", self.area_lights));
        }
        write!(
            f,
            "{}, {} point light(s), {} sphere light(s){gonio}, BVH: {}, SH: {}",
            if shapes.is_empty() {
                "no surfaces".to_string()
            } else {
                shapes.join(", ")
            },
            self.point_lights,
            self.sphere_lights,
            if self.bvh {
                "built"
            } else {
                "none (not needed)"
            },
            if self.sh {
                "built"
            } else {
                "none (not needed)"
            }
        )
    }
}

/// Relative length of the ends of a segment (or of the start of an
/// observer's ray) in which a mesh triangle whose plane the end lies on
/// (to rounding, [`Mesh::on_tolerance`]) does not count as a blocker: end
/// points lying on a triangle (a collision, a receiver on a mesh) are not
/// shadowed by it, at any scale ([`Ends`]).
const MESH_REL: f64 = 1e-9;

/// How far \[m\] a point may lie from a mesh's triangle and be on it:
/// `MESH_REL` of the mesh's size (its bounds' diagonal).
fn on_mesh_tol(m: &crate::geometry::mesh::Mesh) -> f64 {
    MESH_REL * (m.bounds().1 - m.bounds().0).length()
}

/// The least step \[m\] off the surfaces at `p` that a point lifted off
/// them ([`Scene::lift_to_its_side`]) or a seated light's shadow origin
/// ([`Scene::light_shadow_origin`]) takes: 1e-8 of the scale of the
/// coordinates (`scale`, [`Scene::coordinate_scale`], or `p`'s own), 100
/// times the tolerances of boxes and 1000 times those of flat shapes.
fn step_off_surface(p: DVec3, scale: f64) -> f64 {
    1e-8 * p.abs().max_element().max(scale).max(1e-6)
}

/// Largest number of infinite planes the bit-mask visibility supports.
pub const MAX_PLANES: usize = 64;

/// The compiled scene. Units: metres, candela, lumen; lights selected in
/// proportion to their power.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Surfaces (a box contributes six, one per face).
    pub surfaces: Vec<Surface>,
    /// Portals of the lights at infinity ([`Self::set_portals`]).
    portals: Option<std::sync::Arc<crate::light::portal::Portals>>,
    /// Infinite planes (front side towards the normal); `plane_surface[i]` is its surface.
    pub planes: Vec<Plane>,
    plane_surface: Vec<u32>,
    rects: Vec<(Rect, u32)>,
    discs: Vec<(Disc, u32)>,
    spheres: Vec<(Sphere, u32)>,
    /// Boxes with the surface index of their `x_min` face (faces follow in order).
    boxes: Vec<(AaBox, u32)>,
    /// Meshes with their BVH.
    meshes: Vec<(Mesh, u32)>,
    /// Spherical-harmonic objects.
    shs: Vec<(ShSurface, u32)>,
    /// Glass panes (never blockers nor collision sites).
    panes: Vec<Pane>,
    /// The top-level BVH over the finite shapes, when built ([`Accel`]).
    tree: Option<ShapeTree>,
    /// Without the tree: the finite shapes in the order of
    /// [`Self::finite_prims`], each with its padded box (the tree's leaf
    /// boxes, which hold everything the shape's test can report).
    loop_prims: Vec<(Prim, DVec3, DVec3)>,
    /// Light sources.
    pub lights: Vec<Light>,
    /// The lights' names, for messages and summaries (the scene file's
    /// `name`, else `light #k`, 1-based).
    pub light_names: Vec<String>,
    /// What compiling the scene found worth telling the user (for example
    /// a luminaire table's flux against its file's lamp lumens).
    pub notes: Vec<String>,
    /// Why the scene's lights only approximate what it describes (median
    /// cut: an environment map replaced by distant lights), if they do:
    /// every result carries the `approx` flag, whose bias no error bar holds.
    pub approximate: Option<String>,
    /// Alias table of the lights' powers, for picking the emitting light
    /// in O(1); `None` when nothing emits.
    light_pick: Option<crate::sampling::alias::AliasTable>,
    /// Total emitted flux \[lm\].
    total_power: f64,
    /// Per light: the surfaces a point-like light lies on, if any, with
    /// the unit normals of the sides it belongs to (see [`Scene::light_surface`]).
    light_surface: Vec<Option<LightSeat>>,
    /// Per light: [`Self::light_shadow_origin`].
    shadow_origin: Vec<DVec3>,
    /// Per mesh: the winding numbers of the regions that hold the scene's
    /// content, found on first use ([`mesh_lit_side`]).
    mesh_lit_side: mesh_lit_side::MeshLitSide,
    /// How direct light is summed over the sources ([`Self::set_direct_lights`]).
    direct_lights: crate::light::array::DirectLights,
    /// The light array over all sources (RIS candidates per pick set), when
    /// the scene uses it ([`Self::light_array`]).
    light_array: Option<std::sync::Arc<crate::light::array::LightArray>>,
    /// RIS candidates per pick.
    ris_candidates: usize,
}

/// Why [`Scene::build`] refused its input.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BuildError {
    /// More infinite planes than the side masks hold.
    #[error("{0} infinite planes: at most {MAX_PLANES} are supported")]
    TooManyPlanes(usize),
    /// A light's values are out of range.
    #[error("light #{}: {message}", index + 1)]
    Light {
        /// 0-based index of the light.
        index: usize,
        /// What is wrong.
        message: String,
    },
}

/// Where a ray starts, for deciding which surface it must not meet at `t ~ 0`.
#[derive(Clone, Copy, Debug)]
enum Start {
    /// On surface `.0` (primitive `.1`): a collision the ray leaves.
    On(u32, u32),
    /// An observer that may stand on any surfaces: tested per shape.
    Observer,
}

impl Start {
    /// Whether the ray starts on a surface (a collision, or an observer
    /// that may stand on one), not in the air.
    #[inline(always)]
    fn on_surface(self) -> bool {
        !matches!(self, Start::On(u32::MAX, _))
    }

    /// A ray leaving `from` (a collision's surface and primitive), or from
    /// the air (`None`: no surface is skipped).
    fn leaving(from: Option<(u32, u32)>) -> Self {
        match from {
            Some((s, p)) => Start::On(s, p),
            None => Start::On(u32::MAX, 0),
        }
    }
}

impl Scene {
    /// Build a planes-only scene; used by programmatic scenes such as the
    /// Sobolev validation case. Validated as [`Scene::build`].
    pub fn from_parts(
        surfaces: Vec<(String, Plane, Material)>,
        lights: Vec<Light>,
    ) -> Result<Self, BuildError> {
        Self::build(
            surfaces
                .into_iter()
                .map(|(n, p, m)| SurfaceSpec::Plane(n, p, m))
                .collect(),
            lights,
        )
    }

    /// Build a scene from surfaces and lights, checking what the compiled
    /// scene relies on: at most [`MAX_PLANES`] infinite planes; lights with a
    /// finite position, a finite intensity `>= 0` \[cd\] (a power that does not
    /// overflow) and a finite radius `> 0`; sphere lights wholly on one side
    /// of each infinite plane; area sources with a finite luminance `>= 0`.
    /// An area source adds its emitting surface. A scene file passes
    /// these checks at compile time with its line and field
    /// ([`crate::scene::load`]); this is the library's own guard.
    pub fn build(specs: Vec<SurfaceSpec>, lights: Vec<Light>) -> Result<Self, BuildError> {
        let planes = specs
            .iter()
            .filter(|s| matches!(s, SurfaceSpec::Plane(..)))
            .count();
        if planes > MAX_PLANES {
            return Err(BuildError::TooManyPlanes(planes));
        }
        for (k, l) in lights.iter().enumerate() {
            let bad = |message: String| BuildError::Light { index: k, message };
            let (pos, i) = match *l {
                Light::Point { p, i } => (p, i),
                Light::Gonio { p, .. } => (p, l.power() / (4.0 * std::f64::consts::PI)),
                Light::Spot(sp) => (sp.p, sp.i0),
                Light::Sphere { c, r, i } => {
                    if !(r.is_finite() && r > 0.0) {
                        return Err(bad(format!("radius must be finite and > 0 [m], got {r}")));
                    }
                    for spec in &specs {
                        if let SurfaceSpec::Plane(name, pl, _) = spec
                            && pl.signed_distance(c).abs() <= r
                        {
                            return Err(bad(format!("the sphere light cuts plane `{name}`")));
                        }
                    }
                    (c, i)
                }
                Light::Area(ref a) => {
                    let shape_ok = match a.shape {
                        crate::light::AreaShape::Rect { corner, e1, e2 } => {
                            corner.is_finite() && Rect::new(corner, e1, e2).is_some()
                        }
                        crate::light::AreaShape::Disc {
                            center,
                            normal,
                            radius,
                            ..
                        } => {
                            center.is_finite()
                                && (normal.length() - 1.0).abs() < 1e-9
                                && radius.is_finite()
                                && radius > 0.0
                        }
                    };
                    if !shape_ok {
                        return Err(bad(
                            "an area source needs finite, non-parallel edges (a rectangle) or a unit normal and a finite radius > 0 (a disc)".into(),
                        ));
                    }
                    if !(a.l0.is_finite() && a.l0 >= 0.0 && a.power().is_finite()) {
                        return Err(bad(format!(
                            "luminance must be finite and >= 0 [cd/m^2] with a finite flux, got {:e}",
                            a.l0
                        )));
                    }
                    (a.center(), 0.0)
                }
                Light::Distant(ref dl) => {
                    if let Err(message) = dl.check() {
                        return Err(bad(message));
                    }
                    (DVec3::ZERO, 0.0)
                }
                Light::Environment(ref env) => {
                    if !(env.integral().is_finite() && env.integral() > 0.0) {
                        return Err(bad(
                            "an environment map needs a finite luminance, not all zero".into(),
                        ));
                    }
                    (DVec3::ZERO, 0.0)
                }
            };
            if !pos.is_finite() {
                return Err(bad(format!(
                    "position must be finite, got ({}, {}, {})",
                    pos.x, pos.y, pos.z
                )));
            }
            if !(i.is_finite() && (0.0..=MAX_INTENSITY).contains(&i) && l.power().is_finite()) {
                return Err(bad(format!(
                    "intensity must lie in [0, {MAX_INTENSITY:e}] [cd], got {i:e}"
                )));
            }
        }
        Ok(Self::build_checked(specs, lights))
    }

    /// [`Scene::build`] after its checks.
    fn build_checked(specs: Vec<SurfaceSpec>, lights: Vec<Light>) -> Self {
        let mut scene = Scene {
            portals: None,
            surfaces: Vec::new(),
            planes: Vec::new(),
            plane_surface: Vec::new(),
            rects: Vec::new(),
            discs: Vec::new(),
            spheres: Vec::new(),
            boxes: Vec::new(),
            meshes: Vec::new(),
            shs: Vec::new(),
            panes: Vec::new(),
            tree: None,
            loop_prims: Vec::new(),
            lights: Vec::new(),
            light_names: Vec::new(),
            notes: Vec::new(),
            approximate: None,
            light_pick: None,
            total_power: 0.0,
            light_surface: Vec::new(),
            shadow_origin: Vec::new(),
            mesh_lit_side: Default::default(),
            direct_lights: crate::light::array::DirectLights::Auto,
            light_array: None,
            ris_candidates: crate::light::array::RIS_CANDIDATES,
        };
        // An area source's emitting surface joins the scene's shapes.
        let mut lights = lights;
        let mut specs = specs;
        let mut emitter_of = vec![None; specs.len()];
        for (k, l) in lights.iter_mut().enumerate() {
            if let Light::Area(a) = l {
                let sides = if a.two_sided {
                    Sides::Both
                } else {
                    Sides::Front
                };
                let name = format!("emitter of light #{}", k + 1);
                specs.push(match a.shape {
                    crate::light::AreaShape::Rect { corner, e1, e2 } => {
                        // Checked by the light's constructor.
                        let r = Rect::new(corner, e1, e2).expect("a valid parallelogram");
                        SurfaceSpec::Rect(name, r, sides, a.material)
                    }
                    crate::light::AreaShape::Disc {
                        center,
                        normal,
                        radius,
                        ..
                    } => SurfaceSpec::Disc(
                        name,
                        Disc::new(center, normal, radius),
                        sides,
                        a.material,
                    ),
                });
                emitter_of.push(Some(k as u32));
                std::sync::Arc::make_mut(a).surface = u32::MAX;
            }
        }
        for (spec, emitter) in specs.into_iter().zip(emitter_of) {
            let k = scene.surfaces.len() as u32;
            if let Some(e) = emitter
                && let Light::Area(a) = &mut lights[e as usize]
            {
                std::sync::Arc::make_mut(a).surface = k;
            }
            let mut push = |name: String, material, shape, sides| {
                scene.surfaces.push(Surface {
                    name,
                    material,
                    shape,
                    sides,
                    emitter,
                })
            };
            match spec {
                SurfaceSpec::Plane(name, p, m) => {
                    push(
                        name,
                        m,
                        ShapeRef::Plane(scene.planes.len() as u32),
                        Sides::Front,
                    );
                    scene.planes.push(p);
                    scene.plane_surface.push(k);
                }
                SurfaceSpec::Rect(name, r, _, Material::Glass(glass)) => {
                    let i = scene.panes.len() as u32;
                    push(name, Material::Glass(glass), ShapeRef::Pane(i), Sides::Both);
                    scene.panes.push(Pane {
                        shape: PaneShape::Rect(r),
                        glass,
                        surface: k,
                    });
                }
                SurfaceSpec::Disc(name, d, _, Material::Glass(glass)) => {
                    let i = scene.panes.len() as u32;
                    push(name, Material::Glass(glass), ShapeRef::Pane(i), Sides::Both);
                    scene.panes.push(Pane {
                        shape: PaneShape::Disc(d),
                        glass,
                        surface: k,
                    });
                }
                SurfaceSpec::Rect(name, r, sides, m) => {
                    push(name, m, ShapeRef::Rect(scene.rects.len() as u32), sides);
                    scene.rects.push((r, k));
                }
                SurfaceSpec::Disc(name, d, sides, m) => {
                    push(name, m, ShapeRef::Disc(scene.discs.len() as u32), sides);
                    scene.discs.push((d, k));
                }
                SurfaceSpec::Sphere(name, s, sides, m) => {
                    push(name, m, ShapeRef::Sphere(scene.spheres.len() as u32), sides);
                    scene.spheres.push((s, k));
                }
                SurfaceSpec::Box(name, b, sides, ms) => {
                    let i = scene.boxes.len() as u32;
                    for (f, m) in ms.into_iter().enumerate() {
                        let face = crate::geometry::shapes::BOX_FACES[f];
                        push(
                            format!("{name}.{face}"),
                            m,
                            ShapeRef::BoxFace(i, f as u8),
                            sides,
                        );
                    }
                    scene.boxes.push((b, k));
                }
                SurfaceSpec::Mesh(name, m, sides, mat) => {
                    push(name, mat, ShapeRef::Mesh(scene.meshes.len() as u32), sides);
                    scene.meshes.push((m, k));
                }
                SurfaceSpec::Sh(name, o, sides, mat) => {
                    push(name, mat, ShapeRef::Sh(scene.shs.len() as u32), sides);
                    scene.shs.push((o, k));
                }
            }
        }
        scene.light_names = (1..=lights.len()).map(|k| format!("light #{k}")).collect();
        scene.set_lights(lights);
        scene.fit_directional(&[]);
        scene.with_accel(Accel::Auto)
    }

    /// Bounding box \[m\] of the finite shapes (`None`: there are none).
    pub fn finite_bounds(&self) -> Option<(DVec3, DVec3)> {
        self.shape_bounds_except_mesh(usize::MAX)
            .into_iter()
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// The bounds \[m\] of each finite shape (the disc and sphere's boxes
    /// of their radius) but the `skip`-th mesh.
    fn shape_bounds_except_mesh(&self, skip: usize) -> Vec<(DVec3, DVec3)> {
        let mut all = Vec::new();
        for (r, _) in &self.rects {
            let cs = [r.o, r.o + r.e1, r.o + r.e2, r.o + r.e1 + r.e2];
            all.push((
                cs.iter().fold(DVec3::INFINITY, |m, &c| m.min(c)),
                cs.iter().fold(DVec3::NEG_INFINITY, |m, &c| m.max(c)),
            ));
        }
        for (d, _) in &self.discs {
            all.push((d.plane.p - DVec3::splat(d.r), d.plane.p + DVec3::splat(d.r)));
        }
        for (s, _) in &self.spheres {
            all.push((s.c - DVec3::splat(s.r), s.c + DVec3::splat(s.r)));
        }
        for (b, _) in &self.boxes {
            all.push((b.lo, b.hi));
        }
        for (i, (m, _)) in self.meshes.iter().enumerate() {
            if i != skip {
                all.push(m.bounds());
            }
        }
        for (o, _) in &self.shs {
            let r = DVec3::splat(o.bounds().1);
            all.push((o.center() - r, o.center() + r));
        }
        for pane in &self.panes {
            all.push(pane.bounds());
        }
        all
    }

    /// The largest coordinate magnitude of the finite shapes \[m\] (0
    /// without any): the scale of [`step_off_surface`].
    fn coordinate_scale(&self) -> f64 {
        self.finite_bounds()
            .map_or(0.0, |(lo, hi)| lo.abs().max(hi.abs()).max_element())
    }

    /// Fit the start regions of the lights at infinity
    /// ([`crate::light::StartRegion`]) to the finite shapes, the planes and
    /// `points` \[m\] (the receivers, when known: with infinite planes the
    /// answer is exact whatever the fit, which only steers efficiency), and
    /// renew the lights' pick table. Nothing changes without such lights.
    pub fn fit_directional(&mut self, points: &[DVec3]) {
        if !self.lights.iter().any(Light::is_directional) {
            return;
        }
        let planes: Vec<(DVec3, DVec3)> = self.planes.iter().map(|p| (p.n, p.p)).collect();
        let mut region = crate::light::StartRegion::fit(self.finite_bounds(), &planes, points);
        region.portals = self.portals.clone();
        let mut lights = std::mem::take(&mut self.lights);
        for l in &mut lights {
            l.set_region(&region);
        }
        self.set_lights(lights);
    }

    /// Whether some light lies at infinity (distant or environment).
    pub fn has_directional(&self) -> bool {
        self.lights.iter().any(Light::is_directional)
    }

    /// Let the light of the lights at infinity in through `portals` only:
    /// their chains start there ([`crate::light::portal`]).
    pub fn set_portals(&mut self, portals: crate::light::portal::Portals) {
        self.portals = Some(std::sync::Arc::new(portals));
        self.fit_directional(&[]);
    }

    /// Whether the chains of the lights at infinity start on portals.
    pub fn has_portals(&self) -> bool {
        self.portals.is_some()
    }

    /// The portals, if any.
    pub fn portals(&self) -> Option<&crate::light::portal::Portals> {
        self.portals.as_deref()
    }

    /// Name the lights (in their order) for messages and summaries.
    ///
    /// # Panics
    /// If the number of names differs from the number of lights.
    pub fn with_light_names(mut self, names: Vec<String>) -> Self {
        assert_eq!(names.len(), self.lights.len(), "one name per light");
        self.light_names = names;
        self
    }

    fn set_lights(&mut self, lights: Vec<Light>) {
        let total_power: f64 = lights.iter().map(Light::power).sum();
        let powers: Vec<f64> = lights.iter().map(Light::power).collect();
        let light_pick = crate::sampling::alias::AliasTable::new(&powers);
        self.lights = lights;
        self.mesh_lit_side = Default::default();
        // (The seats read the lights: a seat on a closed two-sided mesh
        // takes the side of the region the other content is in.)
        self.light_surface = self
            .lights
            .iter()
            .map(|l| {
                if l.is_point_like() {
                    self.seat_at(l.position())
                } else {
                    None
                }
            })
            .collect();
        let scale = self.coordinate_scale();
        self.shadow_origin = self
            .lights
            .iter()
            .zip(&self.light_surface)
            .map(|(l, seat)| {
                let c = l.position();
                seat.as_ref()
                    .map_or(c, |seat| c + step_off_surface(c, scale) * seat.bisector())
            })
            .collect();
        self.light_pick = light_pick;
        self.total_power = total_power;
        self.refresh_light_array();
    }

    /// Sum direct light by `mode` with `candidates` RIS candidates per pick
    /// (see [`crate::light::array`]); the default is
    /// [`DirectLights::Auto`](crate::light::array::DirectLights::Auto) with
    /// [`RIS_CANDIDATES`](crate::light::array::RIS_CANDIDATES). Set it before
    /// compiling receivers.
    pub fn set_direct_lights(
        &mut self,
        mode: crate::light::array::DirectLights,
        candidates: usize,
    ) {
        self.direct_lights = mode;
        self.ris_candidates = candidates;
        self.refresh_light_array();
    }

    /// The scene with [`Self::set_direct_lights`] applied.
    pub fn with_direct_lights(
        mut self,
        mode: crate::light::array::DirectLights,
        candidates: usize,
    ) -> Self {
        self.set_direct_lights(mode, candidates);
        self
    }

    /// The light array over all sources when the direct light at receivers
    /// is sampled by RIS (the mode asks for it, or `Auto` with many
    /// sources); `None` for exact summation.
    /// Glass panes keep the exact sum: the sampled point-like sources would
    /// miss their pane transmittance and mirror images.
    pub fn light_array(&self) -> Option<&crate::light::array::LightArray> {
        self.light_array.as_deref().filter(|_| {
            self.direct_lights.ris_at_receivers(self.lights.len()) && self.panes.is_empty()
        })
    }

    /// The light array when next-event estimation at backward-path
    /// vertices keeps one source by RIS; `None`: summed over all sources.
    pub fn vertex_light_array(&self) -> Option<&crate::light::array::LightArray> {
        self.light_array
            .as_deref()
            .filter(|_| self.direct_lights.ris_at_vertices(self.lights.len()))
    }

    /// One line on how direct light is summed, for the run summary.
    pub fn direct_lights_note(&self) -> String {
        use crate::light::array::{DirectLights, RIS_AUTO_RECEIVERS, RIS_AUTO_VERTICES};
        let n = self.lights.len();
        let why = match self.direct_lights {
            DirectLights::Auto => format!(
                "auto: RIS at the points from {RIS_AUTO_RECEIVERS} sources on, at path vertices from {RIS_AUTO_VERTICES} on"
            ),
            DirectLights::Exact => "forced by --direct-lights exact".into(),
            DirectLights::Ris => "forced by --direct-lights ris".into(),
        };
        let m = self.light_array.as_ref().map_or(0, |a| a.candidates());
        // (Under the light array a collimated sun stays exact, as in
        // `Receivers::new`.)
        let collimated = self
            .lights
            .iter()
            .filter(|l| matches!(l, Light::Distant(dl) if dl.collimated()))
            .count();
        let at_receivers = match self.light_array() {
            Some(_) if collimated == n => format!(
                "exact sum: all {n} are collimated lights at infinity, which stay exact under RIS \
                 (one shadow test per source and receiver)"
            ),
            Some(_) if collimated > 0 => format!(
                "sampled by RIS ({m} candidates drawn by power, mixed with each point's hot sources, one \
                 shadow test per sample), but for {collimated} collimated light(s) at infinity, exact"
            ),
            Some(_) => format!(
                "sampled by RIS ({m} candidates drawn by power, mixed with each point's hot sources, one \
                 shadow test per sample)"
            ),
            None => {
                let sampled = (0..n)
                    .filter(|&k| !crate::estimator::exact_direct(self, k))
                    .count();
                match sampled {
                    0 => "exact sum (closed forms at set-up, one shadow test per source and receiver)"
                        .into(),
                    s if s == n => "sum over every source, each sampled (an estimate with its error bar)".into(),
                    s => format!(
                        "sum over every source: {} by closed forms at set-up (one shadow test per source and receiver), {s} sampled (an estimate with its error bar)",
                        n - s
                    ),
                }
            }
        };
        let at_vertices = match self.vertex_light_array() {
            Some(_) => "one source by RIS",
            None => "summed over all sources",
        };
        format!(
            "direct light from {n} source(s): at the points {at_receivers}; next-event estimation at backward-path vertices {at_vertices} ({why})"
        )
    }

    fn refresh_light_array(&mut self) {
        let n = self.lights.len();
        let any = self.direct_lights.ris_at_receivers(n) || self.direct_lights.ris_at_vertices(n);
        self.light_array = if any {
            crate::light::array::LightArray::new(
                &self.lights,
                (0..self.lights.len() as u32).collect(),
                self.ris_candidates,
            )
            .map(std::sync::Arc::new)
        } else {
            None
        };
    }

    /// The infinite planes (in side-mask bit order).
    pub fn planes(&self) -> &[Plane] {
        &self.planes
    }

    /// The planes, rectangles, discs, spheres and box faces that point `p`
    /// lies on (within their on-surface tolerance), in that order, each with
    /// its geometric normal (a box's faces in face order; meshes are not
    /// searched).
    fn surfaces_through(&self, p: DVec3) -> Vec<(u32, DVec3)> {
        let mut through = Vec::new();
        for (i, pl) in self.planes.iter().enumerate() {
            if pl.side(p) == 0 {
                through.push((self.plane_surface[i], pl.n));
            }
        }
        for (r, s) in &self.rects {
            if r.plane.side(p) == 0 && r.contains_planar(p) {
                through.push((*s, r.plane.n));
            }
        }
        for (d, s) in &self.discs {
            if d.plane.side(p) == 0 && d.contains_planar(p) {
                through.push((*s, d.plane.n));
            }
        }
        for (sp, s) in &self.spheres {
            if sp.classify(p) == Inside::On {
                through.push((*s, (p - sp.c).normalize()));
            }
        }
        for (b, s0) in &self.boxes {
            if b.classify(p) == Inside::On {
                for f in (0..6).filter(|&f| b.face_plane(f).side(p) == 0) {
                    through.push((s0 + f as u32, AaBox::outward_normal(f)));
                }
            }
        }
        through
    }

    /// Whether the scene has meshes or spherical-harmonic objects (see
    /// [`Self::snap_to_surface`]).
    pub fn has_curved_shapes(&self) -> bool {
        !(self.meshes.is_empty() && self.shs.is_empty())
    }

    /// Point `p` of a receiver with unit normal `n` moved onto a mesh
    /// triangle it lies behind (on a one-sided mesh's black side; for a
    /// two-sided mesh, on the side `n` faces away from), within `MESH_REL`
    /// of the mesh's size (along the triangle's normal), or onto a
    /// spherical-harmonic surface it lies within `MESH_REL` of the radius
    /// of (radially), where it is farther than rounding from it; `p`
    /// itself otherwise. [`Self::on_surface`] counts such a point
    /// as on the mesh, but rays and shadow tests pass a triangle only where
    /// their end lies on its plane to rounding ([`Ends`]), so a point 1e-9 m
    /// below a mesh room's floor would lie under it (before the rule of
    /// [`Ends`] it kept its direct light and lost part of its reflected
    /// light, 68.1 lx flagged `ok` against 74.0 on the floor); a
    /// point 4e-12 m outside an SH integrating sphere (coordinates written
    /// to 12 digits) read 0. Moved, both read the surface's value.
    ///
    /// A mesh's triangles near `p` are found by short rays through `p`
    /// along `n` and the three axes (one of which crosses any plane at
    /// least at `1 / sqrt(3)`), so the receiver's normal need not be the
    /// surface's; of the planes met within the tolerance that `p` lies
    /// behind, over all meshes, the nearest. A point on one of them to
    /// rounding is left alone.
    pub fn snap_to_surface(&self, p: DVec3, n: DVec3) -> DVec3 {
        if !self.surfaces_through(p).is_empty() {
            return p;
        }
        // Closer than this, `p` is on an SH surface to the rounding of its
        // coordinates: left as it is (a mesh's: `Mesh::on_tolerance`).
        let rounding = 64.0 * f64::EPSILON * p.abs().max_element();
        // The nearest plane over every mesh; a point already on one (to
        // rounding) stays, also where another mesh's face passes within the
        // tolerance (a floor point at a cabinet mesh's foot).
        let mut nearest: Option<(f64, DVec3)> = None;
        for (m, s) in &self.meshes {
            let sides = self.surfaces[*s as usize].sides;
            let size = (m.bounds().1 - m.bounds().0).length();
            let tol = MESH_REL * size;
            let reach = tol * 3f64.sqrt();
            for d in [n, DVec3::X, DVec3::Y, DVec3::Z] {
                let o = p - reach * d;
                if let Some((t, ng, _)) = m.first_hit(o, d, 0.0, 2.0 * reach, None, None) {
                    // Signed distance of `p` from the triangle's plane.
                    let dist = (p - (o + t * d)).dot(ng);
                    if dist.abs() <= m.on_tolerance(p) {
                        return p;
                    }
                    // Only from behind: from a one-sided mesh's black
                    // side, or a two-sided mesh's side the receiver's
                    // normal faces away from (a point written 2e-9 m under
                    // a floor, facing up). From the front a point's rays
                    // and shadow tests meet the triangle ([`Ends`]) and its
                    // value is what is there; one whose normal lies along
                    // the triangle would, moved onto it, see it edge-on
                    // (0 lx from it, against pi L / 2 beside it).
                    let behind = match sides {
                        Sides::Front => dist < 0.0,
                        Sides::Back => dist > 0.0,
                        Sides::Both => n.dot(ng) * dist < 0.0,
                    };
                    if behind
                        && dist.abs() <= tol
                        && nearest.is_none_or(|(b, _)| dist.abs() < b.abs())
                    {
                        nearest = Some((dist, ng));
                    }
                }
            }
        }
        if let Some((dist, ng)) = nearest {
            return p - dist * ng;
        }
        for (sh, _) in &self.shs {
            let (r_min, r_max) = sh.bounds();
            let v = p - sh.center();
            let rho = v.length();
            if rho < r_min * (1.0 - MESH_REL) || rho > r_max * (1.0 + MESH_REL) {
                continue;
            }
            let f = sh.level(p);
            // (Well within the march's band, 1e-12 of the radius, a point
            // counts as on the surface already.)
            if f.abs() > (1e-13 * r_max).max(rounding) && f.abs() <= MESH_REL * r_max {
                return sh.center() + v * ((rho - f) / rho);
            }
        }
        p
    }

    /// Point `p` of a receiver with unit normal `n` that lies on surfaces
    /// (flat shapes, box faces, spheres, mesh triangles) and faces along
    /// the normal of not every one of them, moved off them into the region
    /// it belongs to: its value is the limit from there. On a surface, a
    /// receiver belongs to the side its normal faces (the reflecting side
    /// where its normal lies along a one-sided surface; along a two-sided
    /// face of a closed mesh, the side of the region with light,
    /// [`mesh_lit_side`]; along another two-sided one, no side: it sees
    /// past the sheet on both, as before); a
    /// surface through the point itself it would see edge-on, and so
    /// count no light from it, where a point beside it sees it over a part
    /// of its hemisphere, `pi L (1 - cos a) / 2` for a normal at `a` to the
    /// surface's. A floor point at a wall's foot facing up read 35.26 lx
    /// against 41.88 a micrometre into the room, a room's corner point
    /// facing its diagonal 31.14 against 39.31, a floor point facing along
    /// the floor 4.35 against 11.13, all flagged `ok` (a reviewer's find).
    ///
    /// The point moves along the sum of those sides' normals by the least
    /// of `1e-8 s 2^k`, `k <= 6` (`s` the scale of the coordinates: 100
    /// times the tolerances of boxes, 1000 times those of flat shapes, so
    /// that the collisions its rays find next to the edge are resolved
    /// too) that leaves every one of those surfaces. Where that sum does not
    /// point off every one of them (a cabinet's bottom face lying on the
    /// floor, facing down: sliding along a surface took a point out of the
    /// room, a reviewer's find), the faces of one side, else of two, are
    /// left out where that gives a move off the others into a region that
    /// is not dark ([`Self::in_dark_solid`]; the first such where all lead
    /// into the same region, [`Self::region_key`]), else the point stays;
    /// `p` itself also
    /// where it faces along every normal (a floor point facing up: exact as
    /// it is), lies on nothing, or faces a black side
    /// ([`Self::faces_black_side`]: flagged as it is) and is edge-on to
    /// none of the faces (edge-on, it belongs to the face's reflecting
    /// side).
    pub fn lift_to_its_side(&self, p: DVec3, n: DVec3) -> DVec3 {
        // The side of surface `s` (geometric normal `ng`; the `i`-th mesh's
        // triangle of corners `v`, if on one) the point belongs to, if any.
        let side = |s: u32, ng: DVec3, tri: Option<(usize, &[DVec3; 3])>| -> Option<DVec3> {
            let c = n.dot(ng);
            if c.abs() > 1e-12 {
                return Some(ng * c.signum());
            }
            match self.surfaces[s as usize].sides {
                Sides::Back => Some(-ng),
                Sides::Front => Some(ng),
                // Edge-on to a face of a closed mesh that reflects on both
                // sides: the side of the region with light
                // ([`mesh_lit_side`]). Edge-on to a sheet (a partition
                // screen through a work-plane grid): neither side is the
                // point's, which sees both halves of the room past the
                // sheet, as before.
                Sides::Both => tri.and_then(|(i, v)| self.lit_side_of_face(i, v, ng)),
            }
        };
        // The faces to leave: (surface, mesh triangle or `u32::MAX`, side).
        let mut faces: Vec<(u32, u32, DVec3)> = Vec::new();
        for (s, ng) in self.surfaces_through(p) {
            faces.extend(side(s, ng, None).map(|m| (s, u32::MAX, m)));
        }
        for (i, (m, s)) in self.meshes.iter().enumerate() {
            for (tri, v) in m.triangles_through(p, m.on_tolerance(p)) {
                let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                faces.extend(side(*s, ng, Some((i, &v))).map(|m| (*s, tri, m)));
            }
        }
        if faces.iter().all(|f| n.dot(f.2) >= 1.0 - 1e-12) {
            return p;
        }
        // The move must leave every one of them: along one it would slide
        // on it, out of the room.
        let delta0 = step_off_surface(p, self.coordinate_scale());
        let along = |faces: &[(u32, u32, DVec3)]| {
            let u = faces.iter().map(|f| f.2).sum::<DVec3>().normalize_or_zero();
            faces.iter().all(|f| u.dot(f.2) >= 1e-3).then_some(u)
        };
        let u = match along(&faces) {
            Some(u) => u,
            None => {
                // Faces lying against others, facing the other way (a
                // cabinet's bottom face on the floor, for a point at the
                // cabinet's foot facing along the floor; and its side
                // against a wall, at the corner there): the faces of one
                // side, else of two, are left out where that gives a move
                // off the others into a region that is not dark (inside a
                // solid box or sphere, outside a room box, a closed mesh's
                // region that holds no light); where several do with as few
                // sides left out, the first, in the order of the sides, if
                // all of them move into the same region (two cabinets side
                // by side: in front of either; [`Self::region_key`]); else
                // the point stays where it is (a sunlit outside below a room
                // mesh's floor and the room above it). It read 3.22 against
                // 9.29 lx, flagged `enclosed` (a reviewer's find).
                let without = |drop: &[DVec3]| -> Vec<(u32, u32, DVec3)> {
                    faces
                        .iter()
                        .copied()
                        .filter(|f| drop.iter().all(|d| f.2.dot(*d) < 1.0 - 1e-12))
                        .collect()
                };
                // Each side once: several triangles of a mesh's bottom face
                // through the point (a corner on its diagonal, a tessellated
                // face) are one side.
                let mut sides: Vec<DVec3> = Vec::new();
                for f in &faces {
                    if !sides.iter().any(|s| s.dot(f.2) >= 1.0 - 1e-12) {
                        sides.push(f.2);
                    }
                }
                let k = sides.len();
                let fit = |drop: Vec<DVec3>| {
                    let rest = without(&drop);
                    along(&rest)
                        .filter(|&u| !rest.is_empty() && !self.in_dark_solid(p + delta0 * u))
                        .map(|u| (rest, u))
                };
                let ones: Vec<_> = (0..k).filter_map(|i| fit(vec![sides[i]])).collect();
                let fits = if ones.is_empty() {
                    (0..k)
                        .flat_map(|i| (i + 1..k).map(move |j| (i, j)))
                        .filter_map(|(i, j)| fit(vec![sides[i], sides[j]]))
                        .collect()
                } else {
                    ones
                };
                let Some((rest, u)) = fits.first().cloned() else {
                    return p;
                };
                let key = self.region_key(p + delta0 * u);
                if fits
                    .iter()
                    .any(|(_, v)| self.region_key(p + delta0 * *v) != key)
                {
                    return p;
                }
                faces = rest;
                u
            }
        };
        // A point facing a black side stays, to be flagged; but one
        // edge-on to a face belongs to its reflecting side, which a solid's
        // black inside is not (a point on a cabinet's side facing up, on a
        // sphere facing along it: flagged `enclosed` and read 25-65 % low
        // on the surface; a reviewer's find).
        if !faces.iter().any(|f| n.dot(f.2).abs() <= 1e-12) && self.faces_black_side(p, n) {
            return p;
        }
        let still_on = |q: DVec3| {
            let through = self.surfaces_through(q);
            faces.iter().any(|&(s, tri, _)| {
                if tri == u32::MAX {
                    through.iter().any(|t| t.0 == s)
                } else {
                    self.meshes.iter().any(|(m, ms)| {
                        *ms == s
                            && m.triangles_through(q, m.on_tolerance(q))
                                .iter()
                                .any(|t| t.0 == tri)
                    })
                }
            })
        };
        let mut delta = delta0;
        // At most 1e-6 of the scale.
        for _ in 0..7 {
            let q = p + delta * u;
            if !still_on(q) {
                return q;
            }
            delta *= 2.0;
        }
        p
    }

    /// The names of the meshes that are closed surfaces but not
    /// consistently wound ([`Mesh::is_closed_but_unevenly_wound`]).
    pub fn unevenly_wound_meshes(&self) -> Vec<&str> {
        self.meshes
            .iter()
            .filter(|(m, _)| m.is_closed_but_unevenly_wound())
            .map(|(_, s)| self.surfaces[*s as usize].name.as_str())
            .collect()
    }

    /// Which region `q` lies in, as far as the scene's infinite planes and
    /// solids tell: its side of each plane, its place against each box and
    /// sphere and its winding number in each closed mesh (`i64::MIN` where
    /// not found). Two points with the same key may still lie apart
    /// (behind a rectangle), but two with different keys lie in different
    /// regions.
    fn region_key(&self, q: DVec3) -> Vec<i64> {
        let place = |at: Inside| match at {
            Inside::In => 1,
            Inside::On => 0,
            Inside::Out => -1,
        };
        self.planes
            .iter()
            .map(|pl| i64::from(pl.side(q)))
            .chain(self.boxes.iter().map(|(b, _)| place(b.classify(q))))
            .chain(self.spheres.iter().map(|(sp, _)| place(sp.classify(q))))
            .chain(
                self.meshes
                    .iter()
                    .filter(|(m, _)| m.is_closed())
                    .map(|(m, _)| crate::geometry::mesh_parity::winding(m, q).unwrap_or(i64::MIN)),
            )
            .collect()
    }

    /// Whether `q` lies inside a box or sphere that reflects only outward
    /// (a solid), or outside one that reflects only inward (a room), on a
    /// side of an infinite plane without light ([`Self::behind_dark_plane`]),
    /// or in a region of a closed mesh that holds no light
    /// ([`Self::in_dark_mesh_region`]: a cabinet mesh's inside): a region
    /// of the scene no light there can reach.
    fn in_dark_solid(&self, q: DVec3) -> bool {
        let dark = |s: u32, at: Inside| match self.surfaces[s as usize].sides {
            Sides::Front => at == Inside::In,
            Sides::Back => at == Inside::Out,
            Sides::Both => false,
        };
        self.boxes.iter().any(|(b, s)| dark(*s, b.classify(q)))
            || self.spheres.iter().any(|(sp, s)| dark(*s, sp.classify(q)))
            || self.behind_dark_plane(q)
            || self.in_dark_mesh_region(q)
    }

    /// Whether `q` lies on a side of an infinite plane where no light is
    /// (below a ground plane lit from above): no light crosses a plane. A
    /// light standing on surfaces counts from just off its seat, a sphere
    /// light on each side its ball reaches, the sun on each side its disc
    /// shines from, an environment map, an area light or a luminous shape
    /// on both.
    fn behind_dark_plane(&self, q: DVec3) -> bool {
        self.planes.iter().any(|pl| {
            let sq = f64::from(pl.side(q));
            sq != 0.0
                && !self.lights.iter().enumerate().any(|(k, l)| match l {
                    Light::Distant(dl) => sq * pl.n.dot(-dl.d) >= -dl.sin_a,
                    Light::Sphere { c, r, .. } => sq * pl.signed_distance(*c) > -r,
                    _ if l.is_point_like() => {
                        let at = match self.light_surface(k) {
                            Some(_) => self.light_shadow_origin(k),
                            None => l.position(),
                        };
                        f64::from(pl.side(at)) != -sq
                    }
                    _ => true,
                })
        })
    }

    /// Whether a receiver at `p` with unit normal `n` lies on the boundary
    /// of a region no light can reach and faces into it: on an infinite
    /// plane, a box's face or a sphere, with `n` on that surface's black
    /// side, where the region on that side holds no light (a room box's
    /// floor point facing down, out of a room whose lights are all inside
    /// and with no sky; a point on a solid facing into it). Such a receiver
    /// is *enclosed*, like one just beyond the surface, whose probes meet
    /// the black side; its own probes leave the surface and may meet
    /// nothing. A point facing into a solid box from inside one of its
    /// faces is flagged whatever else passes through it (the floor under a
    /// cabinet). Not flagged: a point where another surface through it
    /// reflects on `n`'s side (a wall two rooms share, the floor along a
    /// cabinet's foot), a facade point under a sky or near a light outside,
    /// and points on rectangles and discs (open sheets: under a shelf) or
    /// meshes (left to the probes). Lights whose extent the test cannot
    /// place (area sources, sphere lights crossing the surface) count as
    /// reaching the region.
    pub fn faces_black_side(&self, p: DVec3, n: DVec3) -> bool {
        let through = self.surfaces_through(p);
        // Whether light can be in the region beyond a black side. A light
        // standing on a surface is in the region its seat faces (a
        // downlight on a room box's ceiling is inside the room).
        let reaches = |inside: &dyn Fn(DVec3) -> bool, infinite: bool| {
            self.lights.iter().enumerate().any(|(k, l)| match l {
                _ if l.is_directional() => infinite,
                _ if l.is_point_like() => inside(self.light_shadow_origin(k)),
                _ => true,
            })
        };
        let lit = |&(s, ng): &(u32, DVec3)| self.surfaces[s as usize].sides.lit(ng, -n);
        // Facing into a solid box from inside one of its faces (not on an
        // edge): inside it, whatever else passes through `p` (a point on
        // the floor under a cabinet standing on it).
        for (b, s0) in &self.boxes {
            if b.classify(p) == Inside::On {
                let mut faces = (0..6).filter(|&f| b.face_plane(f).side(p) == 0);
                if let (Some(f), None) = (faces.next(), faces.next()) {
                    let ng = AaBox::outward_normal(f);
                    if n.dot(ng) < 0.0
                        && !lit(&(s0 + f as u32, ng))
                        && !reaches(&|q| b.classify(q) == Inside::In, false)
                    {
                        return true;
                    }
                }
            }
        }
        // ... else a point where any surface through it reflects on `n`'s
        // side is a legitimate one.
        if through.is_empty() || through.iter().any(lit) {
            return false;
        }
        // A closed solid's black side faces out of it where `n` leaves it
        // (the region outside, where lights at infinity are too), else into
        // it.
        let solid = |classify: &dyn Fn(DVec3) -> Inside, out: bool| {
            if out {
                !reaches(&|q| classify(q) == Inside::Out, true)
            } else {
                !reaches(&|q| classify(q) == Inside::In, false)
            }
        };
        through
            .iter()
            .any(|&(s, ng)| match self.surfaces[s as usize].shape {
                ShapeRef::Plane(i) => {
                    let pl = &self.planes[i as usize];
                    let side = if n.dot(ng) > 0.0 { 1 } else { -1 };
                    !reaches(&|q| pl.side(q) == side, true)
                }
                ShapeRef::BoxFace(i, _) => {
                    let b = &self.boxes[i as usize].0;
                    solid(&|q| b.classify(q), n.dot(ng) > 0.0)
                }
                ShapeRef::Sphere(i) => {
                    let sp = &self.spheres[i as usize].0;
                    solid(&|q| sp.classify(q), n.dot(ng) > 0.0)
                }
                _ => false,
            })
    }

    /// The seat of a light at `p` ([`LightSeat`]): every face through `p`
    /// (within the shapes' on-surface tolerances; a mesh's triangles within
    /// `MESH_REL` of its size), each with the unit normal of its reflecting
    /// side (the geometric normal's where both reflect, but on a closed
    /// mesh: the side of the region with light, [`mesh_lit_side`]) and its
    /// edges through `p`: a box's other faces
    /// there, a rectangle's or disc's rim, a triangle's sides.
    fn seat_at(&self, p: DVec3) -> Option<LightSeat> {
        let reflecting = |s: u32, ng: DVec3| match self.surfaces[s as usize].sides {
            Sides::Back => -ng,
            Sides::Front | Sides::Both => ng,
        };
        let both = |s: u32| self.surfaces[s as usize].sides == Sides::Both;
        let mut faces: Vec<(u32, u32, DVec3, Vec<DVec3>)> = Vec::new();
        for (s, ng) in self.surfaces_through(p) {
            let edges = match self.surfaces[s as usize].shape {
                ShapeRef::Rect(i) => self.rects[i as usize].0.rims(p),
                ShapeRef::Disc(i) => self.discs[i as usize].0.rim(p).into_iter().collect(),
                // Into the box across the other faces through `p`.
                ShapeRef::BoxFace(i, f) => {
                    let b = &self.boxes[i as usize].0;
                    (0..6)
                        .filter(|&g| g != f as usize && b.face_plane(g).side(p) == 0)
                        .map(|g| -AaBox::outward_normal(g))
                        .collect()
                }
                _ => Vec::new(),
            };
            faces.push((s, 0, reflecting(s, ng), edges));
        }
        for (i, (m, s)) in self.meshes.iter().enumerate() {
            let tol = on_mesh_tol(m);
            for (tri, v) in m.triangles_through(p, tol) {
                let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                // A closed two-sided mesh: the side of the region with
                // light ([`mesh_lit_side`]).
                let n = match both(*s) {
                    true => self.lit_side_of_face(i, &v, ng).unwrap_or(ng),
                    false => ng,
                };
                // Into the triangle across each side whose line passes
                // within `tol` of `p`.
                let edges = (0..3)
                    .filter_map(|k| {
                        let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
                        let along = (b - a).normalize();
                        let off = (p - a) - along * along.dot(p - a);
                        (off.length() <= tol).then(|| {
                            let e = n.cross(along);
                            if e.dot(c - a) < 0.0 { -e } else { e }
                        })
                    })
                    .collect();
                faces.push((*s, tri, reflecting(*s, n), edges));
            }
        }
        let faces: Vec<light_seat::SeatFace<'_>> = faces
            .iter()
            .map(|(s, prim, n, e)| (*s, *prim, *n, e.as_slice(), both(*s)))
            .collect();
        LightSeat::new(&faces)
    }

    /// Whether point `p` lies on a surface (within the shapes' on-surface
    /// tolerances, a mesh's triangles within `MESH_REL` of its size; see
    /// [`Self::light_surface`] for the tolerance's use).
    pub fn on_surface(&self, p: DVec3) -> bool {
        !self.surfaces_through(p).is_empty()
            || self.meshes.iter().any(|(m, _)| {
                let tol = on_mesh_tol(m);
                m.triangle_at(p, tol).is_some()
            })
    }

    /// The surfaces point-like light `k` stands on, if any ([`LightSeat`]).
    /// **Rule**: a light exactly on a surface belongs to its reflecting
    /// side (the geometric normal's side when both reflect; on a closed
    /// two-sided mesh the side [`mesh_lit_side`] finds), as if it stood
    /// just in front of it: light it emits into the surface meets the
    /// surface at once, at the light's position, and points behind the
    /// surface do not see it. The answer is thus continuous as the light
    /// approaches the surface from that side; on an edge or a corner (of a
    /// box, a rectangle or a disc) the seat holds every face through it.
    pub fn light_surface(&self, k: usize) -> Option<&LightSeat> {
        self.light_surface.get(k).and_then(Option::as_ref)
    }

    /// Where point-like light `k` is seen from by a shadow test: its
    /// position, or, standing on surfaces, `1e-8` of the scene's scale off
    /// them along its seat's bisector (the limit it is defined by): a
    /// segment from the light that runs in the plane of a face through it
    /// (a lamp on a cabinet's top corner, a floor point in line with the
    /// cabinet's side) would otherwise graze that face and meet its far
    /// edge exactly (E_direct 0 against 8.94 lx with the light 1e-7 m off).
    #[inline]
    pub fn light_shadow_origin(&self, k: usize) -> DVec3 {
        self.shadow_origin[k]
    }

    /// Whether `x` lies behind the surfaces that point-like light `k`
    /// stands on (see [`Self::light_surface`]): the light cannot reach it.
    #[inline]
    pub fn behind_light_surface(&self, k: usize, x: DVec3) -> bool {
        self.light_surface(k)
            .is_some_and(|seat| seat.hides(self.lights[k].position(), x))
    }

    /// Whether light `k` is sealed: strictly inside a box or sphere that
    /// reflects outward, or at least 28 of 32 probe rays from its
    /// position (a Fibonacci sphere) meet the back side of a surface, as
    /// inside a closed solid (not all: a solid standing on a floor shares
    /// its bottom face's plane with the floor's front); its light then
    /// hardly reaches a point in front of any surface. Area sources are
    /// never probed (they emit from their own surface).
    pub fn sealed(&self, k: usize) -> bool {
        const PROBES: usize = 32;
        let l = &self.lights[k];
        if matches!(l, Light::Area(_)) || l.is_directional() {
            return false;
        }
        let p = l.position();
        // Strictly inside a closed box or sphere that reflects outward.
        let outward = |s: u32| self.surfaces[s as usize].sides == Sides::Front;
        if self
            .spheres
            .iter()
            .any(|(sp, s)| outward(*s) && sp.classify(p) == Inside::In)
            || self
                .boxes
                .iter()
                .any(|(b, s)| outward(*s) && b.classify(p) == Inside::In)
        {
            return true;
        }
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let back = (0..PROBES)
            .filter(|&i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / PROBES as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let (sp, cp) = (golden * i as f64).sin_cos();
                let d = DVec3::new(r * cp, r * sp, z);
                self.first_hit_from(p, d).is_some_and(|h| d.dot(h.n) >= 0.0)
            })
            .count();
        back >= PROBES * 7 / 8
    }

    /// The share of light `k`'s luminous solid (`opening = true` on a
    /// solid shape, [`crate::light::LuminousShape`]) that lies beyond a
    /// surface: of points drawn over the shape (8 x 8 per direction, over
    /// 64 directions of a Fibonacci sphere, each uniform in the area the
    /// shape projects along it), those a surface hides from a point just
    /// inside the shape's bottom (its lowest luminous point seen from the
    /// nadir, which a luminaire's room holds). Such a part's light meets
    /// the surface at once: a luminaire with luminous sides placed with its
    /// photometric centre (`position`) in a ceiling sends half its sides'
    /// light into the ceiling. For a sphere light, the share of its surface
    /// (1024 points of a Fibonacci sphere) that a finite shape hides from
    /// its centre (stepped off a surface it lies on): a sphere cutting a box's wall sends that part of its
    /// flux out of the room (one cutting an infinite plane is refused when
    /// the scene is read). 0 for every other light.
    pub fn luminous_shape_cut(&self, k: usize) -> f64 {
        const DIRS: usize = 64;
        const GRID: usize = 8;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        if let Light::Sphere { c, r, .. } = &self.lights[k] {
            // Centred on a surface, its centre is taken off it to the side
            // its seat faces (as a point light's shadow origin): from the
            // centre itself every segment starts on that surface and none
            // is hidden, so a sphere half sunk in a box's top read 0.
            let scale = self.coordinate_scale();
            let from = self.seat_at(*c).map_or(*c, |seat| {
                *c + step_off_surface(*c, scale) * seat.bisector()
            });
            let n = 16 * DIRS;
            let hidden = (0..n)
                .filter(|&i| {
                    let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                    let s = (1.0 - z * z).max(0.0).sqrt();
                    let (sp, cp) = (golden * i as f64).sin_cos();
                    let y = *c + *r * (1.0 - 1e-9) * DVec3::new(s * cp, s * sp, z);
                    !self.visible(from, None, y)
                })
                .count();
            return hidden as f64 / n as f64;
        }
        let Light::Gonio {
            p,
            frame,
            opening: Some(o),
            ..
        } = &self.lights[k]
        else {
            return 0.0;
        };
        if o.is_flat() {
            return 0.0;
        }
        let inside = *p + frame.to_world(DVec3::new(0.0, 0.0, -0.999 * o.half.z));
        let (mut hidden, mut total) = (0usize, 0usize);
        for i in 0..DIRS {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / DIRS as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (sp, cp) = (golden * i as f64).sin_cos();
            let d = DVec3::new(r * cp, r * sp, z);
            for a in 0..GRID {
                for b in 0..GRID {
                    let u = [
                        (a as f64 + 0.5) / GRID as f64,
                        (b as f64 + 0.5) / GRID as f64,
                    ];
                    if let Some((y, _, _)) = o.sample(d, u) {
                        // A hair inside the shape: a face lying in a
                        // surface's plane (a top against the ceiling) is
                        // not beyond it.
                        let y = *p + frame.to_world(y);
                        let y = inside + (y - inside) * (1.0 - 1e-9);
                        total += 1;
                        hidden += !self.visible(inside, None, y) as usize;
                    }
                }
            }
        }
        if total == 0 {
            0.0
        } else {
            hidden as f64 / total as f64
        }
    }

    /// True when light from light `k` is never absorbed: every surface
    /// reflects all the light it receives (Lambertian reflectance 1, or Phong
    /// `kd + ks = 1`) and each of 32 probe rays from the light meets a
    /// reflecting side (none leaves the scene or meets a black back side), as
    /// in a closed room whose surfaces all have reflectance 1. The
    /// illuminance is then infinite and a chain (or a backward path) would
    /// never end. Area sources are not probed.
    pub fn traps_light(&self, k: usize) -> bool {
        const PROBES: usize = 32;
        let l = &self.lights[k];
        let lossless = |m: &Material| match *m {
            Material::Lambertian { rho } => rho >= 1.0,
            Material::Phong { kd, ks, .. } => kd + ks >= 1.0,
            // A pane that absorbs nothing passes or mirrors all it gets.
            Material::Glass(g) => g.internal_transmittance() >= 1.0,
        };
        if matches!(l, Light::Area(_)) || !self.surfaces.iter().all(|s| lossless(&s.material)) {
            return false;
        }
        let p = l.position();
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..PROBES).all(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / PROBES as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (sp, cp) = (golden * i as f64).sin_cos();
            let d = DVec3::new(r * cp, r * sp, z);
            self.first_hit_from(p, d).is_some_and(|h| d.dot(h.n) < 0.0)
        })
    }

    /// Index of a light picked with probability proportional to its power
    /// (an alias table: O(1)); light 0 when nothing emits (no chain is
    /// traced then).
    #[inline]
    pub fn pick_light_index(&self, u: f64) -> usize {
        self.light_pick.as_ref().map_or(0, |t| t.sample(u))
    }

    /// Total emitted flux \[lm\].
    pub fn total_power(&self) -> f64 {
        self.total_power
    }

    /// True when every surface is an infinite plane: visibility is then
    /// decided by side masks alone and scoring takes the vectorised path.
    #[inline]
    pub fn planes_only(&self) -> bool {
        self.planes.len() == self.surfaces.len()
    }

    /// Cost weight of one receiver score for choosing batch sizes only: 1,
    /// except 8 with SH objects (their shadow marches cost microseconds).
    /// Deliberately mild: smaller batches would keep a batch's time short
    /// but make batch means skewed, which the normal-based `tail` check
    /// mistakes for rare huge scores (tried: weights 10-1000 gave batches of
    /// 32 chains on the office and flagged a third of its points). A fixed
    /// model, so batch sizes (and results) never depend on timing.
    pub fn score_cost(&self) -> u64 {
        if self.shs.is_empty() { 1 } else { 8 }
    }

    /// What the compiled scene holds.
    pub fn summary(&self) -> SceneSummary {
        let count = |f: fn(&Light) -> bool| self.lights.iter().filter(|l| f(l)).count();
        SceneSummary {
            planes: self.planes.len(),
            rects: self.rects.len(),
            discs: self.discs.len(),
            spheres: self.spheres.len(),
            boxes: self.boxes.len(),
            meshes: self.meshes.len(),
            sh_objects: self.shs.len(),
            panes: self.panes.len(),
            point_lights: count(|l| matches!(l, Light::Point { .. })),
            goniometric_lights: count(|l| matches!(l, Light::Gonio { .. })),
            spot_lights: count(|l| matches!(l, Light::Spot(_))),
            sphere_lights: count(|l| matches!(l, Light::Sphere { .. })),
            area_lights: count(|l| matches!(l, Light::Area(_))),
            bvh: self.tree.is_some() || !self.meshes.is_empty(),
            sh: !self.shs.is_empty(),
        }
    }

    /// Pick a light with probability proportional to its power.
    #[inline]
    pub fn pick_light(&self, u: f64) -> &Light {
        &self.lights[self.pick_light_index(u)]
    }

    /// The plane a flat surface lies in, with its normal turned to the
    /// reflecting side, and whether both sides reflect; `None` for curved
    /// surfaces. Used to decide which points a collision can score into.
    pub fn support_plane(&self, s: u32) -> Option<(Plane, bool)> {
        let surf = &self.surfaces[s as usize];
        let pl = match surf.shape {
            ShapeRef::Plane(i) => self.planes[i as usize],
            ShapeRef::Rect(i) => self.rects[i as usize].0.plane,
            ShapeRef::Disc(i) => self.discs[i as usize].0.plane,
            ShapeRef::BoxFace(i, f) => self.boxes[i as usize].0.face_plane(f as usize),
            ShapeRef::Sphere(_) | ShapeRef::Mesh(_) | ShapeRef::Sh(_) | ShapeRef::Pane(_) => {
                return None;
            }
        };
        match surf.sides {
            Sides::Front => Some((pl, false)),
            Sides::Back => Some((Plane::new(pl.p, -pl.n), false)),
            Sides::Both => Some((pl, true)),
        }
    }

    /// Nearest surface hit along `ray`; `from` is the `(surface, primitive)`
    /// the ray leaves (a collision), which it does not meet again at its origin.
    #[inline]
    pub fn intersect(&self, ray: &Ray, from: Option<(u32, u32)>) -> Option<Hit> {
        self.nearest(ray, Start::leaving(from), f64::INFINITY)
    }

    /// First surface hit by a ray leaving `o` (an observer, possibly standing
    /// on surfaces: a surface through `o` is not hit at `t ~ 0`) in unit direction `d`.
    pub fn first_hit_from(&self, o: DVec3, d: DVec3) -> Option<Hit> {
        self.nearest(&Ray { o, d }, Start::Observer, f64::INFINITY)
    }

    /// The first surface an eye at `o` (a view's observer, a camera) sees
    /// along unit `d`. An eye standing exactly on a surface belongs to its
    /// reflecting side, as a light does ([`LightSeat`]): looking into that
    /// surface it sees it at its feet (`t = 0`, the reflecting side);
    /// otherwise [`Self::first_hit_from`].
    pub fn observer_hit(&self, o: DVec3, d: DVec3) -> Option<Hit> {
        if let Some(seat) = self.seat_at(o)
            && let Some((surface, n, prim)) = seat.meets_prim(d)
        {
            return Some(Hit {
                t: 0.0,
                p: o,
                n,
                surface,
                prim,
            });
        }
        self.first_hit_from(o, d)
    }

    /// [`Self::intersect`] for a ray that matters only before `t_max` \[m\]:
    /// the same hit where it lies nearer than `t_max`, else `None`. Shapes
    /// beyond `t_max` are not tested (a backward path's segment within a
    /// split radius).
    #[inline]
    pub fn intersect_within(&self, ray: &Ray, from: Option<(u32, u32)>, t_max: f64) -> Option<Hit> {
        self.nearest(ray, Start::leaving(from), t_max)
            .filter(|h| h.t < t_max)
    }

    /// [`Self::first_hit_from`] for a ray that matters only before `t_max`
    /// \[m\] (see [`Self::intersect_within`]).
    pub fn first_hit_within(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<Hit> {
        self.nearest(&Ray { o, d }, Start::Observer, t_max)
            .filter(|h| h.t < t_max)
    }

    /// The nearest hit, of those that can be nearer than `t_max` \[m\]
    /// (`INFINITY`: all): the search starts bounded just beyond `t_max`.
    /// The answer is one of the hits, and every hit that can compete with
    /// it lies within a relative `PRUNE` (1e-8) of the nearest hit
    /// (`nearest.rs`): where the answer lies nearer than `t_max`, all of
    /// them lie nearer than `t_max (1 + 1e-6)` and are still collected, so
    /// the answer is the unbounded search's.
    fn nearest(&self, ray: &Ray, start: Start, t_max: f64) -> Option<Hit> {
        let on = |s: u32| matches!(start, Start::On(x, _) if x == s);
        let on_surface = start.on_surface();
        // Every hit is collected; which one wins follows the rules of
        // `nearest.rs`, whatever the order of the tests.
        let mut acc = Nearest::new();
        acc.bound = t_max * (1.0 + 1e-6);
        for (i, pl) in self.planes.iter().enumerate() {
            let s = self.plane_surface[i];
            if on(s) || (on_surface && pl.side(ray.o) == 0) {
                continue;
            }
            if let Some(t) = pl.intersect(ray, acc.bound) {
                let c = Cand {
                    t,
                    key: i as u32,
                    surface: s,
                    prim: 0,
                    lit: self.surfaces[s as usize].sides.lit(pl.n, ray.d),
                };
                acc.plane(c);
            }
        }
        match &self.tree {
            Some(tree) => {
                let q = RayQuery::new(ray.o, ray.d);
                let ids = tree.bvh.ids();
                let bound = acc.bound;
                tree.bvh.nearest(&q, 0.0, bound, |pos, _| {
                    self.offer(tree.prims[pos], FIRST_KEY + ids[pos], ray, start, &mut acc);
                    acc.bound
                });
            }
            None => {
                let mut key = FIRST_KEY;
                let mut each = |p: Prim| {
                    self.offer(p, key, ray, start, &mut acc);
                    key += 1;
                };
                (0..self.rects.len()).for_each(|i| each(Prim::Rect(i as u32)));
                (0..self.discs.len()).for_each(|i| each(Prim::Disc(i as u32)));
                (0..self.spheres.len()).for_each(|i| each(Prim::Sphere(i as u32)));
                (0..self.boxes.len()).for_each(|i| each(Prim::Box(i as u32)));
                (0..self.meshes.len()).for_each(|i| each(Prim::Mesh(i as u32)));
            }
        }
        let (mut best_t, mut best, emitter) = match acc.resolve() {
            Some((c, e)) => (c.t, Some((c.surface, c.prim)), e),
            None => (f64::INFINITY, None, false),
        };
        // SH objects last, in index order: a march's result depends on its
        // interval, so each gets the same one in every path. They must
        // beat an emitter's hit clearly, like the solids. A ray starting on
        // an SH surface (a collision, an observer on it) leaves it on the
        // side its direction points to: no self-hit at t = 0.
        if !self.shs.is_empty() {
            let mut t_max = if emitter {
                best_t * (1.0 - COINCIDENT_TIE)
            } else {
                best_t
            };
            for (o, s) in &self.shs {
                if let Some((t, _)) = o.first_hit(ray.o, ray.d, 0.0, t_max) {
                    (t_max, best_t, best) = (t, t, Some((*s, 0)));
                }
            }
        }
        let (s, prim) = best?;
        let surf = &self.surfaces[s as usize];
        let q = ray.o + ray.d * best_t;
        let (p, ng) = match surf.shape {
            ShapeRef::Plane(i) => {
                let pl = &self.planes[i as usize];
                (pl.project(q), pl.n)
            }
            ShapeRef::Rect(i) => {
                let pl = &self.rects[i as usize].0.plane;
                (pl.project(q), pl.n)
            }
            ShapeRef::Disc(i) => {
                let pl = &self.discs[i as usize].0.plane;
                (pl.project(q), pl.n)
            }
            ShapeRef::Sphere(i) => self.spheres[i as usize].0.surface_point(q),
            ShapeRef::BoxFace(i, f) => {
                let b = &self.boxes[i as usize].0;
                (
                    b.face_point(q, f as usize),
                    AaBox::outward_normal(f as usize),
                )
            }
            ShapeRef::Sh(i) => (q, self.shs[i as usize].0.normal(q)),
            // Panes are met by `next_pane`, never by this search.
            ShapeRef::Pane(i) => {
                let pl = self.panes[i as usize].plane();
                (pl.project(q), pl.n)
            }
            ShapeRef::Mesh(i) => {
                let m = &self.meshes[i as usize].0;
                let ng = m.normal(prim);
                let c0 = m.corners(prim)[0];
                (q - ng * ng.dot(q - c0), ng)
            }
        };
        Some(Hit {
            t: best_t,
            p,
            n: surf.sides.orient(ng, ray.d),
            surface: s,
            prim,
        })
    }

    /// Test finite shape `p` (key `key` in the fixed order) against `ray`
    /// up to `acc.bound` and add its hit: the one per-shape test of both the
    /// linear loops and the tree.
    #[inline(always)]
    fn offer(&self, p: Prim, key: u32, ray: &Ray, start: Start, acc: &mut Nearest) {
        let on = |s: u32| matches!(start, Start::On(x, _) if x == s);
        // A ray starting on a surface does not meet the flat shapes, planes,
        // spheres and box faces that pass through its start (a rectangle
        // set onto another, two back to back): only rounding would put
        // such a hit at t ~ 1e-17, on either side.
        let on_surface = start.on_surface();
        let emits = |s: u32| self.surfaces[s as usize].emitter.is_some();
        let cand = |t, surface: u32, prim, ng: DVec3| Cand {
            t,
            key,
            surface,
            prim,
            lit: self.surfaces[surface as usize].sides.lit(ng, ray.d),
        };
        match p {
            Prim::Rect(i) => {
                let (r, s) = &self.rects[i as usize];
                if !on(*s)
                    && let Some(t) = r.intersect(ray, acc.bound)
                    && !(on_surface && r.plane.side(ray.o) == 0)
                {
                    acc.flat(cand(t, *s, 0, r.plane.n), emits(*s));
                }
            }
            Prim::Disc(i) => {
                let (dc, s) = &self.discs[i as usize];
                if !on(*s)
                    && let Some(t) = dc.intersect(ray, acc.bound)
                    && !(on_surface && dc.plane.side(ray.o) == 0)
                {
                    acc.flat(cand(t, *s, 0, dc.plane.n), emits(*s));
                }
            }
            Prim::Sphere(i) => {
                let (sp, s) = &self.spheres[i as usize];
                let leaving = on(*s) || (on_surface && sp.classify(ray.o) == Inside::On);
                if let Some(t) = sp.intersect(ray, acc.bound, leaving) {
                    acc.solid(cand(t, *s, 0, ray.o + t * ray.d - sp.c));
                }
            }
            Prim::Box(i) => {
                let (b, s0) = &self.boxes[i as usize];
                let leaving = match start {
                    Start::On(x, _) if (*s0..*s0 + 6).contains(&x) => Some((x - s0) as usize),
                    // Of the faces through the start (two at an edge, a
                    // floor point at a cabinet's foot), the nearest: the
                    // start lies on it and may lie just outside the others,
                    // which `intersect` then meets from outside.
                    _ if on_surface && b.classify(ray.o) == Inside::On => (0..6)
                        .filter_map(|f| {
                            let pl = b.face_plane(f);
                            (pl.side(ray.o) == 0).then(|| (f, pl.signed_distance(ray.o).abs()))
                        })
                        .min_by(|x, y| x.1.total_cmp(&y.1))
                        .map(|(f, _)| f),
                    _ => None,
                };
                if let Some((t, f)) = b.intersect(ray, acc.bound, leaving) {
                    acc.solid(cand(t, s0 + f as u32, 0, AaBox::outward_normal(f)));
                }
            }
            Prim::Mesh(i) => {
                let (m, s) = &self.meshes[i as usize];
                // A ray leaving a surface does not meet, within `MESH_REL`
                // of the mesh's size, a triangle whose plane its start lies
                // on ([`Ends`]: a rug on the floor, a panel written front
                // and back, which rounding would meet again at t ~ 1e-17,
                // on either side); a triangle its start lies off, however
                // near, it meets.
                let near = on_mesh_tol(m);
                let ends = |skip| Ends {
                    skip,
                    near,
                    tol: m.on_tolerance(ray.o),
                };
                let ends = match start {
                    Start::On(x, p) if x == *s => ends(Some(p)),
                    Start::On(u32::MAX, _) => Ends::default(),
                    Start::On(..) | Start::Observer => ends(None),
                };
                let front = self.surfaces[*s as usize].sides.front();
                if let Some((t, ng, tri)) =
                    m.first_hit_leaving(ray.o, ray.d, 0.0, acc.bound, ends, front)
                {
                    acc.solid(cand(t, *s, tri, ng));
                }
            }
            // Tested after the others, in index order (see `nearest`).
            Prim::Sh(_) => {}
        }
    }

    /// Whether finite shape `p` blocks the open segment `a b` (`seg`: its
    /// unit direction and length); `from`, `inside_both` as in
    /// [`Self::blocked_by_shapes`]. The one per-shape test of both the
    /// linear loops and the tree.
    #[inline(always)]
    fn blocks(
        &self,
        p: Prim,
        a: DVec3,
        from: Option<(u32, u32)>,
        b: DVec3,
        (d, len): (DVec3, f64),
        inside_both: u64,
    ) -> bool {
        let skip = |k: usize| k < 64 && inside_both & (1 << k) != 0;
        match p {
            Prim::Rect(i) => self.rects[i as usize].0.crosses(a, b),
            Prim::Disc(i) => self.discs[i as usize].0.crosses(a, b),
            Prim::Sphere(i) => !skip(i as usize) && self.spheres[i as usize].0.crosses(a, b),
            Prim::Box(i) => {
                !skip(self.spheres.len() + i as usize) && self.boxes[i as usize].0.crosses(a, b)
            }
            // A shadow ray over the segment, skipping the triangle `a` is
            // on and, within `MESH_REL` of the segment's length of an end,
            // the triangles whose planes that end lies on ([`Ends`]).
            Prim::Mesh(i) => {
                let (m, s) = &self.meshes[i as usize];
                // Through the core of a closed mesh from outside its
                // bounds: a crossing the BVH would find (`mesh_core`).
                if m.core()
                    .is_some_and(|c| c.blocks(m.bounds(), a, b, MESH_REL * len))
                {
                    return true;
                }
                let ends = Ends {
                    skip: from.filter(|f| f.0 == *s).map(|f| f.1),
                    near: MESH_REL * len,
                    tol: m.on_tolerance(a).max(m.on_tolerance(b)),
                };
                m.segment_blocked(a, d, 0.0, len, ends)
            }
            Prim::Sh(i) => {
                let o = &self.shs[i as usize].0;
                // A segment within the inner bounding ball (end points on or
                // inside it; the ball is convex) meets the surface, which lies
                // outside that ball, at most at its end points: no crossing.
                // Exact for a degree-0 object (a sphere seen from inside).
                let r_in = o.bounds().0 * (1.0 + 1e-12);
                let c = o.center();
                if (a - c).length() <= r_in && (b - c).length() <= r_in {
                    return false;
                }
                o.crosses(a, d, 0.0, len)
            }
        }
    }

    /// The finite shapes in the fixed order (rectangles, discs, spheres,
    /// boxes, meshes, SH objects); a shape's key is [`FIRST_KEY`] plus its
    /// place here.
    fn finite_prims(&self) -> Vec<Prim> {
        let n = |k: usize| 0..k as u32;
        n(self.rects.len())
            .map(Prim::Rect)
            .chain(n(self.discs.len()).map(Prim::Disc))
            .chain(n(self.spheres.len()).map(Prim::Sphere))
            .chain(n(self.boxes.len()).map(Prim::Box))
            .chain(n(self.meshes.len()).map(Prim::Mesh))
            .chain(n(self.shs.len()).map(Prim::Sh))
            .collect()
    }

    /// The same scene with its finite shapes in a BVH or not (see
    /// [`Accel`]); the answers of every query are the same bit for bit,
    /// only their cost differs. Scenes are built with [`Accel::Auto`].
    pub fn with_accel(mut self, accel: Accel) -> Self {
        let n = self.rects.len()
            + self.discs.len()
            + self.spheres.len()
            + self.boxes.len()
            + self.meshes.len()
            + self.shs.len();
        let build = match accel {
            Accel::Never => false,
            Accel::Always => true,
            Accel::Auto => n >= AUTO_MIN_SHAPES,
        };
        self.tree = if build { ShapeTree::build(&self) } else { None };
        self.loop_prims = if build {
            Vec::new()
        } else {
            self.finite_prims()
                .into_iter()
                .map(|p| {
                    let (lo, hi) = shape_tree::padded(shape_tree::prim_bounds(&self, p));
                    (p, lo, hi)
                })
                .collect()
        };
        self
    }

    /// Bytes held by the top-level BVH of the finite shapes (0 without one).
    pub fn shape_tree_bytes(&self) -> usize {
        self.tree.as_ref().map_or(0, ShapeTree::storage_bytes)
    }

    /// Visibility masks of a point against every infinite plane.
    pub fn side_mask(&self, q: DVec3) -> SideMask {
        SideMask::of(q, &self.planes)
    }

    /// Bit mask of the spheres and boxes (bits `0..` spheres, then boxes; the
    /// first 64 in all) that `p` lies inside or on. A segment between two
    /// points inside or on the same convex shape never crosses it.
    pub fn inside_mask(&self, p: DVec3) -> u64 {
        let mut m = 0u64;
        let convex = self
            .spheres
            .iter()
            .map(|(s, _)| s.classify(p))
            .chain(self.boxes.iter().map(|(b, _)| b.classify(p)));
        for (k, c) in convex.take(64).enumerate() {
            if c != Inside::Out {
                m |= 1 << k;
            }
        }
        m
    }

    /// The meshes that are closed and hold no light: every light with a
    /// position lies clearly outside ([`crate::geometry::mesh_parity`]).
    /// A point-like light counts by its position; a sphere light by its
    /// centre, and only when the ball keeps clear of the mesh's bounds; a
    /// light with any other extent (an area source, a luminaire emitting
    /// from its luminous shape) counts as held, as may be part of it (a
    /// light on the surface, or where the parity is unclear, counts as held
    /// too). Lights at infinity lie outside every mesh. No light reaches a
    /// point inside such a mesh, whichever sides reflect (it is opaque).
    pub fn lightless_closed_meshes(&self) -> Vec<u32> {
        use crate::geometry::mesh_parity::{Side, side};
        let outside = |m: &crate::geometry::mesh::Mesh, k: usize| match &self.lights[k] {
            l if l.is_directional() => true,
            Light::Sphere { c, r, .. } => {
                let (lo, hi) = m.bounds();
                (lo - *c).max(*c - hi).max_element() > *r && side(m, *c) == Side::Outside
            }
            l if l.is_point_like() => match self.light_surface(k) {
                // A light standing on surfaces belongs to the side it
                // stands on: its shadow origin, stepped off them to that
                // side, is where it is (a lamp on a closed cabinet mesh's
                // side is outside the cabinet, whose inside then holds no
                // light; a lamp on a room mesh's ceiling is inside the
                // room).
                Some(_) => {
                    let q = self.light_shadow_origin(k);
                    m.triangles_through(q, on_mesh_tol(m)).is_empty() && side(m, q) == Side::Outside
                }
                // A light on the surface (`seat_at`'s tolerance) that no
                // seat holds is held: a box-shaped room mesh's corner reads
                // outside by the parity's rays, all of which leave along
                // its edges and faces.
                None => {
                    m.triangles_through(l.position(), on_mesh_tol(m)).is_empty()
                        && side(m, l.position()) == Side::Outside
                }
            },
            _ => false,
        };
        (0..self.meshes.len() as u32)
            .filter(|&i| {
                let m = &self.meshes[i as usize].0;
                m.is_closed() && (0..self.lights.len()).all(|k| outside(m, k))
            })
            .collect()
    }

    /// Whether `p` \[m\] lies clearly inside the closed mesh `meshes[k]`
    /// ([`crate::geometry::mesh_parity`]; not on its surface).
    pub fn inside_mesh(&self, k: u32, p: DVec3) -> bool {
        use crate::geometry::mesh_parity::{Side, side};
        side(&self.meshes[k as usize].0, p) == Side::Inside
    }

    /// Whether every shape that could block a segment is a sphere or box
    /// whose bit is set in `inside_both` (see [`Self::inside_mask`]).
    #[inline]
    pub fn nothing_blocks(&self, inside_both: u64) -> bool {
        let n = self.spheres.len() + self.boxes.len();
        self.rects.is_empty()
            && self.discs.is_empty()
            && self.meshes.is_empty()
            && self.shs.is_empty()
            && n <= 64
            && inside_both.count_ones() as usize == n
    }

    /// Whether a shape other than an infinite plane blocks the open segment
    /// from `a` to `b`; `from` is the `(surface, primitive)` `a` lies on, if
    /// any. Planes are handled by [`Self::side_mask`]; end points lying on a
    /// surface are never shadowed by it. `inside_both`: spheres and boxes
    /// known to contain both points (see [`Self::inside_mask`]), skipped.
    pub fn blocked_by_shapes(
        &self,
        a: DVec3,
        from: Option<(u32, u32)>,
        b: DVec3,
        inside_both: u64,
    ) -> bool {
        // Coinciding end points: nothing lies between them.
        let Some(seg) = segment(a, b) else {
            return false;
        };
        let blocks = |p: Prim| self.blocks(p, a, from, b, seg, inside_both);
        match &self.tree {
            Some(tree) => {
                let q = RayQuery::new(a, b - a);
                tree.bvh.any(&q, 0.0, 1.0, |pos| blocks(tree.prims[pos]))
            }
            // Each shape whose padded box the segment's box meets (exact
            // comparisons: a shape it does not meet cannot report a
            // crossing), in the fixed order.
            None => {
                let (lo, hi) = (a.min(b), a.max(b));
                self.loop_prims
                    .iter()
                    .any(|&(p, plo, phi)| lo.cmple(phi).all() && hi.cmpge(plo).all() && blocks(p))
            }
        }
    }

    /// Whether `a` (on surface/primitive `from`, if any) and `b` see each other.
    #[inline]
    pub fn visible(&self, a: DVec3, from: Option<(u32, u32)>, b: DVec3) -> bool {
        self.side_mask(a).sees(self.side_mask(b)) && !self.blocked_by_shapes(a, from, b, 0)
    }
}

/// Unit direction and length of the segment from `a` to `b`; `None` when
/// the two points coincide (nothing lies between them).
#[inline]
fn segment(a: DVec3, b: DVec3) -> Option<(DVec3, f64)> {
    let ab = b - a;
    let len = ab.length();
    (len > 0.0).then(|| (ab / len, len))
}

#[cfg(test)]
mod build_tests {
    use super::*;
    use crate::geometry::Plane;

    fn plane(k: usize) -> SurfaceSpec {
        SurfaceSpec::Plane(
            format!("p{k}"),
            Plane::new(DVec3::new(0.0, 0.0, k as f64), DVec3::Z),
            Material::Lambertian { rho: 0.5 },
        )
    }

    #[test]
    fn build_refuses_what_the_compiled_scene_cannot_hold() {
        let light = Light::Point {
            p: DVec3::new(0.0, 0.0, -0.5),
            i: 1.0,
        };
        let ok: Vec<SurfaceSpec> = (0..MAX_PLANES).map(plane).collect();
        assert!(Scene::build(ok, vec![light.clone()]).is_ok());
        let many: Vec<SurfaceSpec> = (0..=MAX_PLANES).map(plane).collect();
        assert_eq!(
            Scene::build(many, vec![light.clone()]).unwrap_err(),
            BuildError::TooManyPlanes(MAX_PLANES + 1)
        );
        for bad in [
            Light::Point {
                p: DVec3::new(f64::NAN, 0.0, 0.0),
                i: 1.0,
            },
            Light::Point {
                p: DVec3::ZERO,
                i: -1.0,
            },
            Light::Point {
                p: DVec3::ZERO,
                i: 1e308,
            },
            Light::Sphere {
                c: DVec3::new(0.0, 0.0, 0.5),
                r: 0.0,
                i: 1.0,
            },
            // Cuts the plane z = 0.
            Light::Sphere {
                c: DVec3::new(0.0, 0.0, 0.5),
                r: 0.6,
                i: 1.0,
            },
        ] {
            let what = format!("{bad:?}");
            let e = Scene::build(vec![plane(0)], vec![light.clone(), bad]).unwrap_err();
            assert!(
                matches!(e, BuildError::Light { index: 1, .. }),
                "{what}: {e}"
            );
            assert!(e.to_string().starts_with("light #2: "), "{e}");
        }
    }

    #[test]
    fn lights_keep_their_names() {
        let scene = crate::scene::parse(
            "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
             material = { type = \"lambertian\", reflectance = 0.5 }\n\
             [[light]]\ntype = \"point\"\nname = \"pendant\"\nposition = [0, 0, 1]\nintensity = 1\n\
             [[light]]\ntype = \"point\"\nposition = [1, 0, 1]\nintensity = 1\n",
            std::path::Path::new("t.toml"),
        )
        .unwrap();
        assert_eq!(scene.light_names, ["pendant", "light #2"]);
        let e = crate::estimator::Receivers::new(&scene, &[(DVec3::new(0.0, 0.0, 1.0), DVec3::Z)])
            .unwrap_err();
        assert!(
            e.message.contains("pendant at (0, 0, 1) m"),
            "{}",
            e.message
        );
    }
}
