//! Estimators: scores of collisions at requested points. No accumulation
//! across batches and no I/O here; the caller owns the buffers.
//!
//! **Local estimate** (Marchuk et al. 1980, ch. 5): the illuminance at a point
//! `p` with unit normal `n_p` due to light reflected at least once is
//!
//! `E_ind(p) = E[ sum_n Q_n f_r(wi_n, wo_n) cos(theta_n) cos(theta_p) / d_n^2 V(x_n, p) ]`
//!
//! where `x_n` are the collisions of a light-tracing chain with weights `Q_n`
//! \[lm\], `wo_n` the unit direction from `x_n` to `p`, `theta_n` the angle
//! between `wo_n` and the surface normal at `x_n`, `theta_p` the angle between
//! `-wo_n` and `n_p`, `d_n = |p - x_n|`, and `V` the visibility.
//!
//! **Double local estimate** (ibid.): the luminance seen by an observer along
//! a view ray that first meets a surface at the sub-point `r'` (front normal
//! `n'`, BRDF `f'`, unit direction to the observer `wo'`) is, for light
//! reflected at least twice,
//!
//! `L_ind = E[ sum_n Q_n f_r(wi_n, wo_n) cos(theta_n) cos(theta') / d_n^2 V(x_n, r') f'(wi', wo') ]`
//!
//! with `wi' = -wo_n` the direction from `r'` back to `x_n`: a local estimate
//! at `r'` weighted by the sub-point's BRDF towards the observer. Both kinds
//! are *receivers*: a point, a normal and a response (`1` for illuminance,
//! `f'(wi', wo')` [1/sr] for luminance). A third kind, the solid receivers
//! of [`solid`] (cylindrical, semi-cylindrical, hemispherical and scalar
//! illuminance), replaces `cos(theta_p)` by its response `r(-wo_n)` over the
//! whole sphere: `E_ind = E[ sum_n Q_n f_r cos(theta_n) r / d_n^2 V ]`. Every collision scores into every
//! receiver at once. The first order (light straight from the sources) is
//! computed exactly and separately ([`Receivers::direct`]) where a closed
//! form exists, and sampled per batch elsewhere ([`direct`]); point sources
//! are never seen directly, while a view that meets an emitting surface, a
//! sphere or a luminaire's luminous shape adds its luminance
//! ([`emitted_luminance`]).

pub mod backward;
pub mod direct;
pub mod first_band;
pub mod local;
mod mesh_views;
pub mod near_paths;
mod occluded_kernel;
mod open_kernel;
pub mod pane_images;
pub mod solid;
mod visibility_cells;

use open_kernel::score_open;
pub use open_kernel::{Kernel, active_kernel, arith_touch, set_kernel, stream_touch};
/// Lists longer than this hold their collisions ([`Receivers::score_held`]).
pub const HELD_BLOCK: usize = open_kernel::BLOCK;

use crate::chain::Collision;
use crate::geometry::SideMask;
use crate::light::Light;
use crate::material::Material;
use crate::sampling::grazing::GrazingTable;
use crate::sampling::warp::Frame;
use crate::scene::{Scene, ShapeRef};
use glam::DVec3;
pub use solid::{RECEIVER_TYPES, Solid};

/// The geometric kernel `cos(theta_x) cos(theta_p) / d^2` [1/m^2] between a
/// surface point `x` with front normal `n_x` and a receiver `p` with normal
/// `n_p`; zero when either cosine is not positive.
///
/// This is the one place the kernel is written: the vectorised open-score
/// loop (`open_kernel::open_term`), the per-pair loop and the near part's pool
/// connections ([`crate::backward`]) all evaluate it through
/// [`kernel_parts`].
#[inline]
pub fn local_kernel(x: DVec3, n_x: DVec3, p: DVec3, n_p: DVec3) -> f64 {
    let [cx, cp, d2] = kernel_parts(x, n_x, [p.x, p.y, p.z], [n_p.x, n_p.y, n_p.z]);
    if cx > 0.0 && cp > 0.0 {
        cx * cp / (d2 * d2)
    } else {
        0.0
    }
}

/// The geometric kernel of a score from a surface point `x` (front normal
/// `n_x`) into a receiver at `p` (normal `n_p`): [`local_kernel`] for a
/// receiver with a plane (its cosine in the kernel), or `cos_x / d^2` for a
/// solid receiver, whose response (applied by the caller) stands for the
/// plane's cosine.
#[inline]
fn pair_kernel(x: DVec3, n_x: DVec3, p: DVec3, n_p: DVec3, solid: bool) -> f64 {
    if solid {
        let [cx, _, d2] = kernel_parts(x, n_x, p.to_array(), n_p.to_array());
        if cx > 0.0 { cx / (d2 * d2.sqrt()) } else { 0.0 }
    } else {
        local_kernel(x, n_x, p, n_p)
    }
}

/// The factors of the local kernel between a surface point `x` (front
/// normal `n`) and a receiver at `p` (normal `np`), as
/// `[cos_x d, cos_p d, d^2]` with `d = |p - x|` (unnormalised cosines,
/// clamped at 0): the kernel is `cx cp / d^4`. Scalar components, so the
/// structure-of-arrays loops vectorise.
#[inline(always)]
pub fn kernel_parts(x: DVec3, n: DVec3, p: [f64; 3], np: [f64; 3]) -> [f64; 3] {
    let (dx, dy, dz) = (p[0] - x.x, p[1] - x.y, p[2] - x.z);
    let cx = (n.x * dx + n.y * dy + n.z * dz).max(0.0);
    let cp = (-(np[0] * dx + np[1] * dy + np[2] * dz)).max(0.0);
    let d2 = dx * dx + dy * dy + dz * dz;
    [cx, cp, d2]
}

/// What a receiver measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Response {
    /// Illuminance \[lx\] on the side the normal faces.
    Illuminance,
    /// Luminance [cd/m^2] leaving a surface point towards an observer: the
    /// surface's `material` and the unit direction `wo` to the observer in the
    /// local frame of the receiver's normal.
    Luminance { material: Material, wo: DVec3 },
    /// Illuminance \[lx\] of a small solid ([`Solid`]: cylindrical,
    /// semi-cylindrical, hemispherical, spherical), whose response to light
    /// from `wi` replaces the plane's cosine and covers the whole sphere.
    Solid(Solid),
}

/// A receiver: a point \[m\], its unit normal and its response.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    /// Position \[m\]: the point itself, or the sub-point of a view.
    pub p: DVec3,
    /// Unit normal: the point's, or the front normal at the sub-point.
    pub n: DVec3,
    /// What is measured there.
    pub response: Response,
}

impl Receiver {
    /// An illuminance point.
    pub fn illuminance(p: DVec3, n: DVec3) -> Self {
        Self {
            p,
            n,
            response: Response::Illuminance,
        }
    }

    /// A solid receiver of type `kind` at `p` with unit normal `n` (its
    /// axis, facing direction or pole, see [`Solid`]).
    pub fn solid(p: DVec3, n: DVec3, kind: Solid) -> Self {
        Self {
            p,
            n,
            response: Response::Solid(kind),
        }
    }

    /// Response to light arriving from unit world direction `wi` (towards
    /// the source): 1 for illuminance, `f'(wi, wo)` [1/sr] for luminance,
    /// both multiplied by the plane's `max(0, n . wi)` in the kernel; for a
    /// solid receiver its whole response ([`Solid::response`]), which
    /// replaces that cosine.
    #[inline]
    pub fn weight(&self, frame: &Frame, wi: DVec3) -> f64 {
        match self.response {
            Response::Illuminance => 1.0,
            Response::Luminance { material, wo } => material.eval(frame.to_local(wi), wo),
            Response::Solid(kind) => kind.response(self.n, wi),
        }
    }

    /// The solid type, if the receiver is one.
    pub fn solid_kind(&self) -> Option<Solid> {
        match self.response {
            Response::Solid(kind) => Some(kind),
            _ => None,
        }
    }

    /// A direction of the receiver's own sampling (cosine about the normal,
    /// the sub-point's BRDF, or a solid's, [`Solid::sample`]) in the local
    /// frame of its normal, with its density [1/sr] (0: no direction).
    #[inline]
    pub fn sample_own(&self, u: [f64; 2]) -> crate::sampling::warp::DirectionSample {
        match self.response {
            Response::Illuminance => crate::sampling::warp::sample_cosine_hemisphere(u),
            Response::Luminance { material, wo } => {
                let s = material.sample(wo, u);
                crate::sampling::warp::DirectionSample { w: s.w, pdf: s.pdf }
            }
            Response::Solid(kind) => kind.sample(u),
        }
    }

    /// The receiver's transfer towards unit world direction `wi` (towards
    /// the source; `frame` is that of its normal): `(w(wi) max(0, n . wi),
    /// p_B(wi))`, the response times the cosine (the integrand of
    /// `E = int L cos dw`, or of the luminance) and the density [1/sr] of
    /// the receiver's own sampling (cosine, or the BRDF's) there; for a
    /// solid receiver its response, over the whole sphere.
    #[inline]
    pub fn transfer(&self, frame: &Frame, wi: DVec3) -> (f64, f64) {
        if let Response::Solid(kind) = self.response {
            return (kind.response(self.n, wi), kind.pdf(self.n, wi));
        }
        let wl = frame.to_local(wi);
        if wl.z <= 0.0 {
            return (0.0, 0.0);
        }
        match self.response {
            Response::Illuminance => (wl.z, wl.z / std::f64::consts::PI),
            Response::Luminance { material, wo } => {
                (material.eval(wl, wo) * wl.z, material.pdf(wo, wl))
            }
            Response::Solid(_) => unreachable!("returned above"),
        }
    }

    /// The response when it does not depend on the direction of arrival
    /// (times the plane's cosine); `None` for a solid receiver, whose
    /// response replaces the cosine.
    fn constant_weight(&self) -> Option<f64> {
        match self.response {
            Response::Illuminance => Some(1.0),
            Response::Luminance { material, .. } => material.constant_brdf(),
            Response::Solid(_) => None,
        }
    }
}

/// Where a view ray (observer `o`, unit direction `d`) ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewTarget {
    /// The ray leaves the scene: luminance 0 (there is no environment).
    Miss,
    /// The ray meets the back side of a surface at `p`: black, luminance 0.
    Back { p: DVec3 },
    /// The ray meets a front side: the receiver at the sub-point.
    Front(Receiver),
}

impl ViewTarget {
    /// The sub-point, if the ray meets a surface.
    pub fn sub_point(&self) -> Option<DVec3> {
        match self {
            ViewTarget::Miss => None,
            ViewTarget::Back { p } => Some(*p),
            ViewTarget::Front(r) => Some(r.p),
        }
    }
}

/// Sampled direct-light estimates per receiver in a batch of `bs` chains:
/// 4 for every 256 chains (at least 4), so that the sampled part's error
/// shrinks with the chains'.
pub fn direct_samples(bs: u64) -> u64 {
    4 * bs.div_ceil(256).max(1)
}

/// Whether light `k`'s direct light is exact at every receiver (a closed
/// form, occluded only by planes, which side masks decide): point sources
/// always (a luminaire emitting from its opening never); a sphere in a scene of infinite planes alone; a uniform area
/// source where the only other finite shapes are emitters in its own plane
/// and it lies wholly on one side of (or in) every plane.
pub fn exact_direct(scene: &Scene, k: usize) -> bool {
    let l = &scene.lights[k];
    match l {
        Light::Gonio {
            opening: Some(_), ..
        } => false,
        Light::Point { .. } | Light::Gonio { .. } | Light::Spot(_) => true,
        Light::Sphere { .. } => scene.planes_only(),
        // The sun as a point: one direction, one shadow ray. As a disc: in
        // a scene of planes none of which the disc straddles (seen from any
        // point, each plane then hides all of it or none), the axis decides.
        Light::Distant(dl) => {
            dl.collimated()
                || (scene.planes_only()
                    && scene
                        .planes()
                        .iter()
                        .all(|pl| pl.n.dot(dl.d).abs() >= dl.sin_a))
        }
        Light::Environment(_) => false,
        Light::Area(a) => {
            if !a.is_uniform() {
                return false;
            }
            let (p, m) = (a.center(), a.normal());
            let alone = scene.surfaces.iter().all(|s| match s.emitter {
                Some(e) => match &scene.lights[e as usize] {
                    Light::Area(b) => {
                        let (lo, hi) = b.extent_along(p, m);
                        let tol = 1e-9 * (1.0 + p.abs().max_element() + b.bounding_radius());
                        lo.abs() <= tol && hi.abs() <= tol
                    }
                    _ => false,
                },
                None => matches!(s.shape, ShapeRef::Plane(_)),
            });
            alone
                && scene.planes().iter().all(|pl| {
                    let (lo, hi) = a.extent_along(pl.p, pl.n);
                    let tol = 1e-9 * (1.0 + pl.p.abs().max_element() + a.bounding_radius());
                    lo >= -tol || hi <= tol
                })
        }
    }
}

/// The hot sources of every receiver whose direct set is picked by RIS
/// (`direct_set[j]` into `direct_sets`), flattened: start offsets (empty
/// when no set uses RIS), scene indices, cumulative probabilities and
/// shares ([`crate::light::hot_sources`]). Each receiver's list depends on
/// it alone, so it is the same whatever the threads or the other receivers.
type HotLists = (Vec<u32>, Vec<u32>, Vec<f64>, Vec<f64>);
fn hot_lists(
    scene: &Scene,
    receivers: &[Receiver],
    direct_sets: &[direct::LightSet],
    direct_set: &[Option<u8>],
) -> HotLists {
    use crate::light::hot_sources::{HotSources, SourceTree};
    use rayon::prelude::*;
    let trees: Vec<Option<SourceTree>> = direct_sets
        .iter()
        .map(|set| set.array().map(|a| SourceTree::new(a, &scene.lights)))
        .collect();
    if trees.iter().all(Option::is_none) {
        return Default::default();
    }
    let lists: Vec<HotSources> = receivers
        .par_iter()
        .zip(direct_set)
        .map(|(rec, s)| {
            let Some(s) = s.map(usize::from) else {
                return HotSources::default();
            };
            match (direct_sets[s].array(), &trees[s]) {
                (Some(a), Some(t)) => HotSources::find(
                    a,
                    t,
                    &scene.lights,
                    rec.p,
                    rec.solid_kind().is_none().then_some(rec.n),
                ),
                _ => HotSources::default(),
            }
        })
        .collect();
    let mut out: HotLists = (vec![0], Vec::new(), Vec::new(), Vec::new());
    for h in lists {
        out.1.extend_from_slice(&h.k);
        out.2.extend_from_slice(&h.cum);
        out.3.push(h.beta);
        out.0.push(out.1.len() as u32);
    }
    out
}

/// Emitted luminance [cd/m^2] seen along the ray `o + t d` (unit `d`) from
/// an observer at `o`: that of the sphere lights and the luminous shapes
/// of luminaires ([`Light::shape_luminance`]) it enters before `t_max`
/// \[m\] (they do not block what lies behind them; a shape entered at
/// `t_max`, within the relative `COINCIDENT_TIE`, counts where the ray
/// meets a surface's reflecting side there), plus that of an area
/// source whose emitting side is the first surface it meets (within
/// `t_max`).
pub fn emitted_luminance(scene: &Scene, o: DVec3, d: DVec3, t_max: f64) -> f64 {
    // A fold from +0 (an empty f64 sum is -0, which would print as "-0").
    let spheres = scene
        .lights
        .iter()
        .filter(|l| l.hit(o, d, t_max).is_some())
        .fold(0.0, |a, l| a + l.luminance());
    let hit = scene.observer_hit(o, d);
    // A luminous opening flush with the ceiling it is set into is entered
    // where the ceiling is met: seen from the ceiling's reflecting side it
    // wins that tie, as emitters in a surface do (from behind, the ceiling
    // hides it).
    let t_shape = match &hit {
        Some(h) if h.n.dot(d) < 0.0 => t_max * (1.0 + crate::scene::world::COINCIDENT_TIE),
        _ => t_max,
    };
    let shapes = scene
        .lights
        .iter()
        .fold(0.0, |a, l| a + l.shape_luminance(o, d, t_shape));
    // A ray that leaves the scene sees the lights at infinity.
    let sky = if hit.is_none() {
        scene
            .lights
            .iter()
            .fold(0.0, |a, l| a + l.escaped_luminance(d))
    } else {
        0.0
    };
    let area = hit
        .filter(|h| h.t <= t_max)
        .and_then(|h| {
            let k = scene.surfaces[h.surface as usize].emitter?;
            match &scene.lights[k as usize] {
                Light::Area(a) => Some(a.emitted(h.p, -d)),
                _ => None,
            }
        })
        .unwrap_or(0.0);
    spheres + shapes + area + sky
}

/// How far \[m, per metre of the largest coordinate, at least 1 m\] a
/// view's sub-point that falls on a point-like light moves along the
/// surface ([`view_target`]): well beyond the light's own tolerance
/// ([`Light::contains`], 1e-12), far below any scene detail.
const SUB_POINT_SHIFT: f64 = 1e-9;

/// Trace the view ray from observer `o` \[m\] looking along unit `d` to its
/// sub-point ([`Scene::observer_hit`]: an observer standing on a surface
/// and looking into it sees the surface at its feet).
pub fn view_target(scene: &Scene, o: DVec3, d: DVec3) -> ViewTarget {
    match scene.observer_hit(o, d) {
        None => ViewTarget::Miss,
        Some(h) if d.dot(h.n) >= 0.0 => ViewTarget::Back { p: h.p },
        Some(h) => {
            let material = scene.surfaces[h.surface as usize].material;
            let frame = Frame::from_normal(h.n);
            let wo = frame.to_local(-d);
            // A sub-point on a point-like light (a downlight set into the
            // ceiling, seen straight on): the light's flux into the surface
            // meets it there, a delta with no luminance of its own, and the
            // direct term is 0/0; the luminance there is its neighbours'
            // limit, so the sub-point moves a hair along the surface.
            let mut p = h.p;
            if scene
                .lights
                .iter()
                .any(|l| l.is_point_like() && l.contains(p))
            {
                p += frame.to_world(DVec3::X) * (SUB_POINT_SHIFT * p.abs().max_element().max(1.0));
            }
            ViewTarget::Front(Receiver {
                p,
                n: h.n,
                response: Response::Luminance { material, wo },
            })
        }
    }
}

/// Error building receivers from a point list.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("point {index}: {message}")]
pub struct ReceiverError {
    /// 0-based index of the receiver in the list.
    pub index: usize,
    /// What is wrong.
    pub message: String,
}

/// Receivers that can be reached from one surface, as structure of arrays so
/// the scoring loop vectorises. Entries `..n_const` have a constant response
/// `w`; the rest (luminance at glossy sub-points) are evaluated per pair.
#[derive(Clone, Debug, Default)]
struct ReceiverList {
    /// Index of each entry in the user's receiver list.
    idx: Vec<u32>,
    px: Vec<f64>,
    py: Vec<f64>,
    pz: Vec<f64>,
    nx: Vec<f64>,
    ny: Vec<f64>,
    nz: Vec<f64>,
    /// Constant response (1 or `rho/pi`); unused for general entries.
    w: Vec<f64>,
    /// Squared near-field radius [m^2]: collisions closer than this score
    /// nothing here (the near part is estimated separately; 0 when off).
    eps2: Vec<f64>,
    /// Squared radius [m^2] of the entry's watched neighbourhood (see
    /// [`Receivers::view_radius`]): collisions that score from closer than
    /// this are counted; 0 when not watched.
    watch2: Vec<f64>,
    masks: Vec<SideMask>,
    /// Spheres and boxes each entry lies inside or on ([`Scene::inside_mask`]).
    inside: Vec<u64>,
    /// AND of `inside` over the entries.
    inside_all: u64,
    /// Entries with a constant response come first.
    n_const: usize,
    /// Planes (bits) that could separate a collision on this surface from some entry.
    blockers: u64,
    /// Offset of this list in a flat accumulator.
    offset: usize,
    /// Per entry, the finite shapes that may shadow it from a collision on
    /// this list's surfaces (`occ[occ_start[k]..occ_start[k + 1]]`, see
    /// [`crate::scene::world::Occluder`]); empty `occ_start` when the scene
    /// has none on loops or the lists would be too large (every shape is
    /// then tested).
    occ_start: Vec<u32>,
    occ: Vec<crate::scene::world::Occluder>,
    /// The list's region cut into cells, with per (cell, entry) the
    /// occluders that can shadow the entry from there
    /// ([`visibility_cells`]); `None` without occluder lists or past
    /// [`MAX_CELL_MASKS`].
    cells: Option<visibility_cells::VisibilityCells>,
    /// The list's surfaces are flat (an infinite plane or a flat shape's
    /// support plane): every entry lies strictly in front of it, so a
    /// positive unnormalised cosine at the collision is the BRDF's front.
    flat: bool,
}

/// Most occluders kept over all receiver lists (144 bytes each, 96 more
/// for a rectangle's); past it a list tests every shape.
const MAX_OCCLUDERS: usize = 2_000_000;

/// Most 8-byte words of visibility cells kept over all receiver lists
/// (masks, split responses and, at worst, full test lists: 64 MB;
/// [`visibility_cells::VisibilityCells::size`]); a list whose cells would
/// pass it takes coarser cells, or none.
const MAX_CELL_MASKS: usize = 8_000_000;

/// Receivers compiled against a scene.
#[derive(Clone, Debug)]
pub struct Receivers {
    /// Near-field radius \[m\] and backward paths per receiver and batch
    /// (radius 0: off).
    /// Backward paths per receiver and batch for the near part (0: off) and
    /// each receiver's near-field radius \[m\] (0: plain local estimate).
    near_paths: u32,
    near_r: Vec<f64>,
    /// Per receiver: its own paths for every 256 chains
    /// ([`Self::with_allocated_near_paths`]); empty: `near_paths` each.
    near_per: Vec<u32>,
    /// Per receiver: the variance of one near path's value relative to
    /// `E^2`, from the pilot of [`Self::set_allocated_near_paths`] (empty
    /// without it): where it is not small the near paths' first directions
    /// are not stratified ([`Self::near_bands`]).
    near_var: Vec<f64>,
    /// Set by [`local::prepare`].
    near_prepared: bool,
    /// Radius \[m\] of each receiver's neighbourhood that holds almost all of
    /// its view (0: none, or not an illuminance point).
    view_r: Vec<f64>,
    /// Per receiver: whether it is enclosed ([`view_probe`]).
    enclosed: Vec<bool>,
    /// Per receiver: the near/far radius \[m\] it needs, a quarter of its
    /// distance to the nearest light where a surface lies closer than a tenth
    /// (0: none needed); see [`near_need`].
    need_r: Vec<f64>,
    /// The receivers in a slot ([`slot_table`]), by index, with the table
    /// their near paths draw their first directions from; empty until the
    /// auto split sets them.
    slots: Vec<(u32, GrazingTable)>,
    all: Vec<Receiver>,
    frames: Vec<Frame>,
    /// The distinct receiver lists ([`Self::from_receivers`]).
    lists: Vec<ReceiverList>,
    /// The receivers read as the limit beside the surfaces they lie on
    /// ([`Self::lifted`]).
    lifted: Vec<u32>,
    /// Per surface: its list.
    list_of: Vec<u32>,
    total_len: usize,
    /// The list of every receiver that takes the scores reflected by glass
    /// panes (`None` without panes).
    image_list: Option<u32>,
    direct: Vec<f64>,
    /// The sets of sources whose direct light is sampled ([`direct`]).
    direct_sets: Vec<direct::LightSet>,
    /// Per receiver: its set in `direct_sets`, if any source is sampled there.
    direct_set: Vec<Option<u8>>,
    /// Per receiver whose set is picked by RIS, its hot sources
    /// ([`crate::light::hot_sources`]): `hot_k[hot_start[j]..hot_start[j +
    /// 1]]` with their cumulative probabilities in `hot_cum` and the share
    /// `hot_beta[j]` (all empty without RIS).
    hot_start: Vec<u32>,
    hot_k: Vec<u32>,
    hot_cum: Vec<f64>,
    hot_beta: Vec<f64>,
    /// How the sampled direct light is drawn.
    direct_strategy: direct::Strategy,
}

impl Receivers {
    /// Compile illuminance points `p` \[m\] with unit normals `n` against `scene`.
    pub fn new(scene: &Scene, points: &[(DVec3, DVec3)]) -> Result<Self, ReceiverError> {
        let r: Vec<Receiver> = points
            .iter()
            .map(|&(p, n)| Receiver::illuminance(p, n))
            .collect();
        Self::from_receivers(scene, &r)
    }

    /// Compile any receivers against `scene`.
    ///
    /// A receiver enters the list of a surface only if it lies strictly in
    /// front of it (a collision there can score into it); the exact first
    /// order is computed here once.
    pub fn from_receivers(scene: &Scene, receivers: &[Receiver]) -> Result<Self, ReceiverError> {
        // Points a hair off a mesh or an SH surface, on it
        // ([`Scene::snap_to_surface`]); points on surfaces they do not face
        // along, off them ([`Scene::lift_to_its_side`]); positions that are
        // not finite and normals that are not unit are refused below as
        // they are.
        // The direct part is taken where a point is seated (snapped, not
        // lifted): it is continuous there, and exact; but what hides a
        // light is seen from where it was lifted to (a floor point at a
        // room mesh's wall foot does not see the sun through the wall).
        let mut lifted = Vec::new();
        let mut seated = Vec::with_capacity(receivers.len());
        let placed: Vec<Receiver> = receivers
            .iter()
            .enumerate()
            .map(|(j, r)| match r.response {
                Response::Illuminance if r.p.is_finite() && (r.n.length() - 1.0).abs() < 1e-9 => {
                    let p = if scene.has_curved_shapes() {
                        scene.snap_to_surface(r.p, r.n)
                    } else {
                        r.p
                    };
                    seated.push(p);
                    let q = scene.lift_to_its_side(p, r.n);
                    if q != p {
                        lifted.push(j as u32);
                    }
                    Receiver { p: q, ..*r }
                }
                _ => {
                    seated.push(r.p);
                    *r
                }
            })
            .collect();
        let receivers = &placed[..];
        let masks: Vec<SideMask> = receivers.iter().map(|r| scene.side_mask(r.p)).collect();
        let inside: Vec<u64> = receivers.iter().map(|r| scene.inside_mask(r.p)).collect();
        let frames: Vec<Frame> = receivers.iter().map(|r| Frame::from_normal(r.n)).collect();
        let mut direct = vec![0.0; receivers.len()];
        // With the light array (many sources) only a collimated sun stays
        // exact: every other source is sampled, one RIS pick per sample.
        let ris = scene.light_array().map(|a| a.candidates());
        let exact: Vec<bool> = (0..scene.lights.len())
            .map(|k| match ris {
                Some(_) => matches!(&scene.lights[k], Light::Distant(dl) if dl.collimated()),
                None => exact_direct(scene, k),
            })
            .collect();
        // Sources other than points and a collimated sun (which are exact
        // for any response).
        let non_point = |k: &usize| {
            let l = &scene.lights[*k];
            !l.is_point_like() && !matches!(l, Light::Distant(dl) if dl.collimated())
        };
        let shadow_origin: Vec<DVec3> = (0..scene.lights.len())
            .map(|k| scene.light_shadow_origin(k))
            .collect();
        for (j, rec) in receivers.iter().enumerate() {
            let (p, n, lifted_to) = (seated[j], rec.n, rec.p);
            if !(p.is_finite() && n.is_finite() && (n.length() - 1.0).abs() < 1e-9) {
                return Err(ReceiverError {
                    index: j,
                    message: "position and unit normal must be finite".into(),
                });
            }
            if rec.solid_kind() == Some(Solid::Semicylindrical) && n.z.abs() > 1e-9 {
                return Err(ReceiverError {
                    index: j,
                    message: format!(
                        "a semicylindrical receiver has a vertical axis: its normal columns give the horizontal direction it faces (nz = 0), not ({}, {}, {})",
                        n.x, n.y, n.z
                    ),
                });
            }
            if let Some(kind) = rec.solid_kind()
                && scene.on_surface(p)
            {
                // Half of a small solid centred on a surface would lie
                // inside it; the plane's rule (a point on a surface faces
                // its normal's side) has no counterpart for a solid.
                let hint = match kind {
                    Solid::Cylindrical | Solid::Semicylindrical => {
                        "EN 12464-1 asks cylindrical illuminance 1.2 m above the floor for seated and 1.6 m for standing people; EN 13201-3 semi-cylindrical illuminance 1.5 m above a road"
                    }
                    Solid::Hemispherical => {
                        "a small `offset` in its [[grid]], such as 0.001 m, lifts it; EN 13201-3's hemispherical illuminance at a road's surface counts the luminaires' light alone, which the `E_direct` column holds"
                    }
                    Solid::Spherical => "give it a small offset along the normal",
                };
                return Err(ReceiverError {
                    index: j,
                    message: format!(
                        "a {} receiver lies on a surface, so part of it would be inside: place it off the surface ({hint})",
                        kind.name()
                    ),
                });
            }
            if p.abs().max_element() > crate::scene::MAX_COORD {
                return Err(ReceiverError {
                    index: j,
                    message: format!(
                        "every coordinate must lie within +-{:e} m (the geometry is resolved to 1e-11 of the coordinates; re-centre the scene)",
                        crate::scene::MAX_COORD
                    ),
                });
            }
            for (k, l) in scene.lights.iter().enumerate() {
                if l.contains(p) {
                    let c = l.position();
                    let name = scene.light_names.get(k).map_or("a light", String::as_str);
                    let message = if let crate::light::Light::Gonio {
                        p: lp,
                        frame,
                        opening: Some(shape),
                        ..
                    } = *l
                        && shape.holds(frame.to_local(p - lp))
                    {
                        let h = shape.half * 2.0;
                        format!(
                            "point lies inside or on the luminous {} ({} x {} x {} m) of {name} at ({}, {}, {}) m, or within {:e} of its size of it: place it outside, where its light can be resolved",
                            shape.shape.name(h.y, h.x, h.z),
                            h.x,
                            h.y,
                            h.z,
                            c.x,
                            c.y,
                            c.z,
                            crate::light::LuminousShape::NEAR
                        )
                    } else if let crate::light::Light::Sphere { r, .. } = *l {
                        // On its surface the limit from outside is finite,
                        // but the sphere's own emission and shadow are not
                        // resolved there: a clear refusal, not a guess.
                        format!(
                            "point lies on or inside {name}, a sphere light of radius {r} m centred at ({}, {}, {}) m: place it outside the sphere",
                            c.x, c.y, c.z
                        )
                    } else {
                        format!(
                            "point lies on or inside {name} at ({}, {}, {}) m: its illuminance is not finite",
                            c.x, c.y, c.z
                        )
                    };
                    return Err(ReceiverError { index: j, message });
                }
                // A receiver whose response varies with the direction (a
                // glossy view, a solid receiver) has closed forms for points
                // and the collimated sun only: every other source is in its
                // sampled set (`sets_of[1]`, below), never summed here too.
                if !exact[k] || (rec.constant_weight().is_none() && non_point(&k)) {
                    continue; // sampled, see below
                }
                // Mirror images of the light in glass panes (point-like
                // lights and a collimated sun; `pane_images`).
                if scene.has_panes() {
                    let frame = &frames[j];
                    direct[j] += pane_images::image_direct(
                        scene,
                        k,
                        p,
                        n,
                        &|xi, ni, unm| match rec.response {
                            Response::Illuminance => l.direct_illuminance(xi, ni),
                            // Mirroring both the receiver and the direction
                            // keeps the response: r(n', w') = r(n, w).
                            Response::Solid(kind) => match l {
                                Light::Distant(dl) => {
                                    dl.direct_illuminance(-dl.d) * kind.response(ni, -dl.d)
                                }
                                _ => {
                                    let v = l.position() - xi;
                                    let d2 = v.length_squared();
                                    let wi = v / d2.sqrt();
                                    l.intensity(-wi) * kind.response(ni, wi) / d2
                                }
                            },
                            _ => l.direct_weighted(xi, ni, &|wi| rec.weight(frame, unm(wi))),
                        },
                    );
                }
                if let Light::Distant(dl) = l {
                    // Lit where the ray towards the sun leaves the scene.
                    if scene.first_hit_from(lifted_to, -dl.d).is_none() {
                        let glass = scene.pane_transmittance_ray(lifted_to, -dl.d, false);
                        direct[j] += glass
                            * match rec.response {
                                Response::Illuminance => dl.direct_illuminance(n),
                                // E_n times the response to the sun's direction.
                                Response::Solid(kind) => {
                                    dl.direct_illuminance(-dl.d) * kind.response(n, -dl.d)
                                }
                                _ if dl.collimated() => {
                                    l.direct_weighted(p, n, &|wi| rec.weight(&frames[j], wi))
                                }
                                _ => {
                                    dl.direct_illuminance(n)
                                        * rec.constant_weight().unwrap_or(f64::NAN)
                                }
                            };
                    }
                    continue;
                }
                // What `exact` admits lies wholly on one side of every plane
                // (or in it) and nothing else can hide it, so its centre
                // decides its visibility.
                let seen = scene.side_mask(l.position()).sees(masks[j])
                    && !scene.behind_light_surface(k, lifted_to)
                    && (scene.planes_only()
                        || !scene.blocked_by_shapes(shadow_origin[k], None, lifted_to, 0));
                if seen {
                    let glass = scene.pane_transmittance(l.position(), lifted_to);
                    direct[j] += glass
                        * match (rec.response, l) {
                            (Response::Illuminance, _) => l.direct_illuminance(p, n),
                            // A point-like source: I(-wi) r(wi) / d^2.
                            (Response::Solid(kind), _) => {
                                let v = l.position() - p;
                                let d2 = v.length_squared();
                                let wi = v / d2.sqrt();
                                l.intensity(-wi) * kind.response(n, wi) / d2
                            }
                            (_, Light::Area(_)) => {
                                l.direct_illuminance(p, n)
                                    * rec.constant_weight().unwrap_or(f64::NAN)
                            }
                            (Response::Luminance { .. }, _) => {
                                l.direct_weighted(p, n, &|wi| rec.weight(&frames[j], wi))
                            }
                        };
                }
            }
        }
        // Sources sampled per batch: those without an exact form anywhere,
        // and every non-point source at a receiver whose response varies
        // (`non_point`, above).
        let sampled: Vec<usize> = (0..scene.lights.len()).filter(|&k| !exact[k]).collect();
        let sets_of = [
            sampled.clone(),
            match ris {
                Some(_) => sampled,
                None => (0..scene.lights.len()).filter(non_point).collect(),
            },
        ];
        let direct_sets: Vec<direct::LightSet> = sets_of
            .iter()
            .map(|ks| {
                let ks = ks.iter().map(|&k| k as u32).collect();
                match ris {
                    Some(m) => direct::LightSet::with_ris(scene, ks, m),
                    None => direct::LightSet::new(scene, ks),
                }
            })
            .collect();
        let direct_set: Vec<Option<u8>> = receivers
            .iter()
            .map(|rec| {
                let s = if rec.constant_weight().is_some() {
                    0
                } else {
                    1
                };
                (!direct_sets[s].is_empty()).then_some(s as u8)
            })
            .collect();
        // Surfaces whose collisions reach the same receivers share one list
        // (and one stretch of the accumulators): the tiles of one floor,
        // every curved shape. A list is keyed by what decides its entries:
        // an infinite plane's own bit, or the support plane (normal,
        // offset, sides) of a flat shape, or nothing for a curved one.
        let mut list_of = Vec::with_capacity(scene.surfaces.len());
        let mut keys: std::collections::HashMap<(u64, [u64; 4], u8), u32> =
            std::collections::HashMap::new();
        let mut lists = Vec::new();
        let mut offset = 0;
        for s in 0..scene.surfaces.len() {
            let key = match (scene.surfaces[s].shape, scene.support_plane(s as u32)) {
                (ShapeRef::Plane(i), _) => (1u64 << i, [0; 4], 0),
                (_, Some((pl, both))) => (
                    0,
                    [pl.n.x, pl.n.y, pl.n.z, pl.c].map(f64::to_bits),
                    1 + both as u8,
                ),
                (ShapeRef::Pane(_), _) => (0, [0; 4], 4),
                (_, None) => (0, [0; 4], 3),
            };
            if let Some(&k) = keys.get(&key) {
                list_of.push(k);
                continue;
            }
            keys.insert(key, lists.len() as u32);
            list_of.push(lists.len() as u32);
            let mut list = ReceiverList {
                offset,
                inside_all: u64::MAX,
                flat: key.2 <= 2,
                ..Default::default()
            };
            // Which receivers a collision on surface `s` can score into: those
            // strictly on the reflecting side of a flat surface's plane; all
            // for a curved one (the kernel's cosine sorts them out).
            let own_bit = match scene.surfaces[s].shape {
                ShapeRef::Plane(i) => 1u64 << i,
                _ => 0,
            };
            let support = scene.support_plane(s as u32);
            // A glass pane is never a collision site (chains cross or leave it).
            let pane = matches!(scene.surfaces[s].shape, ShapeRef::Pane(_));
            let reach = |j: &usize| {
                if pane {
                    return false;
                }
                if own_bit != 0 {
                    return masks[*j].front & own_bit != 0;
                }
                match support {
                    Some((pl, false)) => pl.side(receivers[*j].p) == 1,
                    Some((pl, true)) => pl.side(receivers[*j].p) != 0,
                    None => true,
                }
            };
            let constant = (0..receivers.len())
                .filter(reach)
                .filter(|&j| receivers[j].constant_weight().is_some());
            let general = (0..receivers.len())
                .filter(reach)
                .filter(|&j| receivers[j].constant_weight().is_none());
            let order: Vec<usize> = constant.chain(general).collect();
            for j in order {
                let rec = &receivers[j];
                list.idx.push(j as u32);
                list.px.push(rec.p.x);
                list.py.push(rec.p.y);
                list.pz.push(rec.p.z);
                list.nx.push(rec.n.x);
                list.ny.push(rec.n.y);
                list.nz.push(rec.n.z);
                list.masks.push(masks[j]);
                list.eps2.push(0.0);
                list.watch2.push(0.0);
                list.inside.push(inside[j]);
                list.inside_all &= inside[j];
                match rec.constant_weight() {
                    Some(w) => {
                        list.w.push(w);
                        list.n_const += 1;
                    }
                    None => list.w.push(0.0),
                }
                list.blockers |= (masks[j].front | masks[j].back) & !own_bit;
            }
            offset += list.idx.len();
            lists.push(list);
        }
        // Occluder lists: per list, the region its surfaces span.
        if scene.uses_occluder_lists() {
            let mut region: Vec<Option<Option<(DVec3, DVec3)>>> = vec![None; lists.len()];
            for (s, &k) in list_of.iter().enumerate() {
                let b = scene.surface_bounds(s as u32);
                let r = &mut region[k as usize];
                *r = Some(match (*r, b) {
                    (None, b) => b,
                    (Some(Some((lo, hi))), Some((l, h))) => Some((lo.min(l), hi.max(h))),
                    _ => None,
                });
            }
            // Per list, the support plane of its surfaces (flat lists).
            let mut support = vec![None; lists.len()];
            for (s, &k) in list_of.iter().enumerate().rev() {
                support[k as usize] = scene.support_plane(s as u32).map(|(pl, _)| pl);
            }
            let mut total = 0;
            for ((list, region), support) in lists.iter_mut().zip(&region).zip(support) {
                let region = region.flatten();
                let mut start = vec![0u32];
                let mut occ = Vec::new();
                for &j in &list.idx {
                    let rec = &receivers[j as usize];
                    let front = rec.solid_kind().is_none().then_some(rec.n);
                    // (A flat shape in the list's own plane never blocks.)
                    occ.extend(
                        scene
                            .occluders(rec.p, front, region)
                            .into_iter()
                            .filter(|o| !support.is_some_and(|pl| scene.flat_in_plane(o, pl))),
                    );
                    start.push(occ.len() as u32);
                    if total + occ.len() > MAX_OCCLUDERS {
                        break;
                    }
                }
                if start.len() == list.idx.len() + 1 {
                    total += occ.len();
                    list.occ_start = start;
                    list.occ = occ;
                }
            }
            mesh_views::attach(scene, receivers, &mut lists);
            // Visibility cells over each bounded region whose list tests
            // occluders, as fine as the budget allows (in list order).
            let mut masks = 0;
            let plans: Vec<Option<((DVec3, DVec3), usize)>> = lists
                .iter()
                .zip(&region)
                .map(|(list, region)| {
                    let region = (*region).flatten()?;
                    if list.occ.is_empty() {
                        return None;
                    }
                    let mut side = visibility_cells::VisibilityCells::per_side(region);
                    let split = if list.flat { list.n_const } else { 0 };
                    loop {
                        let size = visibility_cells::VisibilityCells::size(
                            region,
                            list.idx.len(),
                            split,
                            side,
                        );
                        if masks + size <= MAX_CELL_MASKS {
                            masks += size;
                            return Some((region, side));
                        }
                        if side == 1 {
                            return None;
                        }
                        side /= 2;
                    }
                })
                .collect();
            use rayon::prelude::*;
            lists.par_iter_mut().zip(plans).for_each(|(list, plan)| {
                if let Some((region, side)) = plan {
                    let points: Vec<DVec3> = (0..list.idx.len())
                        .map(|k| DVec3::new(list.px[k], list.py[k], list.pz[k]))
                        .collect();
                    list.cells = Some(visibility_cells::VisibilityCells::build(
                        scene,
                        region,
                        &points,
                        &list.occ_start,
                        &list.occ,
                        side,
                        list.flat.then_some(&list.w[..list.n_const]),
                    ));
                }
            });
        }
        // With glass panes, one more stretch of the accumulators holds
        // every receiver once: the scores reflected to it by a pane
        // ([`Self::score_images`]).
        let image_list = scene.has_panes().then(|| {
            let list = ReceiverList {
                offset,
                idx: (0..receivers.len() as u32).collect(),
                px: receivers.iter().map(|r| r.p.x).collect(),
                py: receivers.iter().map(|r| r.p.y).collect(),
                pz: receivers.iter().map(|r| r.p.z).collect(),
                nx: receivers.iter().map(|r| r.n.x).collect(),
                ny: receivers.iter().map(|r| r.n.y).collect(),
                nz: receivers.iter().map(|r| r.n.z).collect(),
                w: vec![0.0; receivers.len()],
                eps2: vec![0.0; receivers.len()],
                watch2: vec![0.0; receivers.len()],
                masks: masks.clone(),
                inside: inside.clone(),
                ..Default::default()
            };
            offset += receivers.len();
            lists.push(list);
            lists.len() as u32 - 1
        });
        // A point inside a closed mesh that holds no light is enclosed too,
        // even where both of the mesh's sides reflect (its probes then meet
        // no black side): it can get no light at all.
        let lightless = scene.lightless_closed_meshes();
        // Per receiver, in parallel (collected in order: the same whatever
        // the thread count).
        use rayon::prelude::*;
        let (view_r, enclosed): (Vec<f64>, Vec<bool>) = receivers
            .par_iter()
            .zip(&frames)
            .map(|(rec, frame)| {
                let (r, enclosed) = match rec.response {
                    Response::Illuminance => view_probe(scene, rec.p, frame, false),
                    Response::Solid(_) => view_probe(scene, rec.p, frame, true),
                    Response::Luminance { .. } => return (0.0, false),
                };
                let walled_in = || lightless.iter().any(|&k| scene.inside_mesh(k, rec.p));
                // On a room's floor facing down (out of the room): the
                // probes leave the floor and meet nothing, yet the point
                // is outside the room.
                let facing_out = || {
                    matches!(rec.response, Response::Illuminance)
                        && scene.faces_black_side(rec.p, frame.n)
                };
                (r, enclosed || walled_in() || facing_out())
            })
            .unzip();
        let need_r = receivers
            .par_iter()
            .zip(&frames)
            .map(|(rec, frame)| near_need(scene, rec.p, frame, rec.solid_kind().is_some()))
            .collect();
        let (hot_start, hot_k, hot_cum, hot_beta) =
            hot_lists(scene, receivers, &direct_sets, &direct_set);
        let mut r = Self {
            near_paths: 0,
            near_per: Vec::new(),
            near_var: Vec::new(),
            near_prepared: false,
            near_r: vec![0.0; receivers.len()],
            slots: Vec::new(),
            view_r,
            enclosed,
            need_r,
            all: receivers.to_vec(),
            frames,
            lists,
            list_of,
            total_len: offset,
            image_list,
            direct,
            direct_sets,
            direct_set,
            hot_start,
            hot_k,
            hot_cum,
            hot_beta,
            direct_strategy: direct::Strategy::Power,
            lifted,
        };
        r.refresh_watch();
        Ok(r)
    }

    /// The receivers (by index) that lay on surfaces they do not face
    /// along, read as the limit from the side they face
    /// ([`Scene::lift_to_its_side`]).
    pub fn lifted(&self) -> &[u32] {
        &self.lifted
    }

    /// Set each entry's watched radius: the view radius where it exceeds
    /// the near-field radius (collisions inside the near ball do not score
    /// here, so the check covers the shell between the two), else none.
    fn refresh_watch(&mut self) {
        for list in &mut self.lists {
            for (w, &j) in list.watch2.iter_mut().zip(&list.idx) {
                let (v, r) = (self.view_r[j as usize], self.near_r[j as usize]);
                *w = if v > r { v * v } else { 0.0 };
            }
        }
    }

    /// Whether receiver `j` has a watched neighbourhood (the `sparse` check
    /// of [`crate::tally::Diagnostics`] applies to it).
    pub fn watched(&self, j: usize) -> bool {
        self.view_r[j] > self.near_r[j]
    }

    /// Whether illuminance point `j` is enclosed: it sees the back of a
    /// surface in most directions (inside a solid, behind a wall, outside a
    /// closed room; see [`view_probe`]), or it lies inside a closed mesh
    /// that holds no light ([`Scene::lightless_closed_meshes`]), whose
    /// sides may both reflect. Its `E` is almost surely not what
    /// was meant, and it is flagged `enclosed`.
    pub fn enclosed(&self, j: usize) -> bool {
        self.enclosed[j]
    }

    /// Radius \[m\] of receiver `j`'s watched neighbourhood (0: none); see
    /// [`view_radius`].
    pub fn view_radius(&self, j: usize) -> f64 {
        self.view_r[j]
    }

    /// Number of receivers.
    pub fn len(&self) -> usize {
        self.all.len()
    }

    /// True when there are no receivers.
    pub fn is_empty(&self) -> bool {
        self.all.is_empty()
    }

    /// Local frames of the receivers' normals, in input order.
    pub fn frames(&self) -> &[Frame] {
        &self.frames
    }

    /// The receivers, in input order.
    pub fn receivers(&self) -> &[Receiver] {
        &self.all
    }

    /// Exact first order at each receiver: illuminance \[lx\] straight from the
    /// sources, or the luminance [cd/m^2] of light reflected once at the
    /// sub-point; without the sources that are sampled there
    /// ([`Self::sampled_direct`]).
    pub fn direct(&self) -> &[f64] {
        &self.direct
    }

    /// The sources whose direct light is sampled at receiver `j`, if any.
    pub fn direct_set(&self, j: usize) -> Option<&direct::LightSet> {
        self.direct_set[j].map(|s| &self.direct_sets[s as usize])
    }

    /// Receiver `j`'s hot sources, where its direct light is kept by RIS
    /// ([`crate::light::hot_sources`]).
    pub fn hot(&self, j: usize) -> Option<crate::light::hot_sources::Hot<'_>> {
        let r = *self.hot_start.get(j)? as usize..*self.hot_start.get(j + 1)? as usize;
        Some(crate::light::hot_sources::Hot {
            k: &self.hot_k[r.clone()],
            cum: &self.hot_cum[r],
            beta: self.hot_beta[j],
        })
    }

    /// Whether some receiver has sampled direct light.
    pub fn has_sampled_direct(&self) -> bool {
        self.direct_set.iter().any(Option::is_some)
    }

    /// Draw the sampled direct light with `strategy` (default: the power
    /// heuristic), e.g. to compare the strategies' variances.
    pub fn with_direct_strategy(mut self, strategy: direct::Strategy) -> Self {
        self.direct_strategy = strategy;
        self
    }

    /// Sampled direct light of batch `b` with `bs` chains: for each receiver
    /// with sampled sources, the mean of `samples` estimates
    /// ([`direct::sample`]) times `bs` is added to `out[j]` (so that the
    /// per-chain mean of the batch holds it); each estimate draws from its
    /// own stream of `seed`, so the result does not depend on threads.
    pub fn sampled_direct(&self, scene: &Scene, seed: u64, b: u64, bs: u64, out: &mut [f64]) {
        const DIRECT_KEY: u64 = 0x6469_7265_6374; // "direct"
        let n = self.all.len() as u64;
        for (j, rec) in self.all.iter().enumerate() {
            let Some(set) = self.direct_set(j) else {
                continue;
            };
            // A RIS set carries the direct light of every source: more
            // samples (see `RIS_DIRECT_SAMPLES`).
            let samples = match set.uses_ris() {
                true => crate::light::array::RIS_DIRECT_SAMPLES * direct_samples(bs),
                false => direct_samples(bs),
            };
            let mut sum = 0.0;
            for s in 0..samples {
                let stream = (b * samples + s) * n + j as u64;
                let mut rng = crate::sampling::Philox4x32::new(seed ^ DIRECT_KEY, stream);
                sum += direct::sample(
                    scene,
                    set,
                    rec,
                    &self.frames[j],
                    self.direct_strategy,
                    self.hot(j),
                    &mut rng,
                );
            }
            out[j] += sum / samples as f64 * bs as f64;
        }
    }

    /// The near/far split: collisions closer than `radius` \[m\] to a
    /// receiver no longer score into it, and each batch adds, per receiver,
    /// `paths` backward paths whose first surface lies within `radius`. Both
    /// parts are unbiased; the far kernel is bounded by `1 / radius^2`, so
    /// the variance stays finite next to walls and in corners.
    ///
    /// The split is recursive: at each vertex `x` of such a path the light
    /// from surfaces within `max(radius, d_x / 2)` (`d_x`: distance from `x`
    /// to the nearest light) comes by the path's next segment, and the light
    /// from farther surfaces by the batch's light-tracing collisions, a few
    /// drawn at random from the batch, scored into `x` as into a receiver
    /// ([`crate::backward`]). A far point between highly reflecting
    /// surfaces thus receives the light piled up around the sources, which
    /// neither the chains (they never come near the point) nor the paths
    /// (they never come near the sources) reach alone.
    pub fn with_near_field(mut self, radius: f64, paths: u32) -> Self {
        self.set_near_field(radius, paths);
        self
    }

    /// [`Self::with_near_field`] in place.
    pub fn set_near_field(&mut self, radius: f64, paths: u32) {
        self.slots.clear();
        let r = vec![radius; self.all.len()];
        self.set_near_radii(r, paths);
    }

    /// The split with radius `radii[j]` \[m\] at receiver `j` (0: plain).
    fn set_near_radii(&mut self, radii: Vec<f64>, paths: u32) {
        let on = paths > 0 && radii.iter().any(|&r| r > 0.0);
        self.near_paths = if on { paths } else { 0 };
        self.near_per.clear();
        self.near_var.clear();
        self.near_r = if on { radii } else { vec![0.0; self.all.len()] };
        for list in &mut self.lists {
            for (e, &j) in list.eps2.iter_mut().zip(&list.idx) {
                *e = self.near_r[j as usize].powi(2);
            }
        }
        self.refresh_watch();
    }

    /// The split where it is needed, with a radius per receiver
    /// ([`near_need`]); elsewhere the plain local estimate. Either way every
    /// estimate is unbiased (a probe that misses a small nearby object only
    /// leaves that receiver on the plain estimate); a receiver with no
    /// surface within a tenth of its distance to the nearest light gets
    /// exactly the plain estimate.
    ///
    /// An enclosed illuminance point in a slot ([`slot_table`]: a wall point
    /// behind a board hung 1 cm off it, the board's back black), where
    /// light gets in through a narrow share of its hemisphere (the table's
    /// mean reach below 0.01), gets the slot's radius, so that its near part
    /// covers what it sees through the slit, and its near paths draw their
    /// first direction from the slot's [`GrazingTable`]; at their vertices
    /// the split radius stays the one it needs. Measured on the office's 12 wall points behind the
    /// whiteboard (E 0.015-0.17 lx): the local estimate scored them only from
    /// collisions in a strip about 2 cm wide along the wall (R 3-6 % at
    /// 131,072 chains, 70 % of the 506 planar grid points' summed R^2);
    /// their near paths now give R 0.3-0.5 % at 1,048,576 chains in 3 s,
    /// where the local estimate needed 16,777,216 chains and 20 s.
    pub fn with_auto_near_field(mut self, scene: &Scene, paths: u32) -> Self {
        self.set_auto_near_field(scene, paths);
        self
    }

    /// [`Self::with_auto_near_field`] in place.
    pub fn set_auto_near_field(&mut self, scene: &Scene, paths: u32) {
        use rayon::prelude::*;
        let mut radii = self.need_r.clone();
        // The candidates' probes in parallel (each up to 32 x 26 rays); the
        // slots in index order, so the same whatever the thread count.
        let candidates: Vec<usize> = (0..radii.len())
            .filter(|&j| {
                radii[j] > 0.0
                    && self.enclosed[j]
                    && matches!(self.all[j].response, Response::Illuminance)
            })
            .collect();
        self.slots = candidates
            .par_iter()
            .filter_map(|&j| {
                let (table, radius) = slot_table(scene, self.all[j].p, &self.frames[j])?;
                (radius > radii[j] && table.mean_reach() < SLOT_REACH)
                    .then_some((j as u32, table, radius))
            })
            .collect::<Vec<_>>()
            .into_iter()
            .map(|(j, table, radius)| {
                radii[j as usize] = radius;
                (j, table)
            })
            .collect();
        self.set_near_radii(radii, paths);
    }

    /// How receiver `j`'s near paths are traced: the table of grazing
    /// directions their first direction is drawn from, if it is in a slot,
    /// and the split radius \[m\] at their vertices (see
    /// [`Self::with_auto_near_field`]).
    pub fn near_path_setup(&self, j: usize) -> (Option<&GrazingTable>, f64) {
        match self.slots.binary_search_by_key(&(j as u32), |s| s.0) {
            Ok(k) => (Some(&self.slots[k].1), self.need_r[j]),
            Err(_) => (None, self.near_r[j]),
        }
    }

    /// Per receiver: the width of the grazing band that stratifies its near
    /// paths' first directions ([`first_band::band_width`]): illuminance
    /// points with a near part and no slot table whose near paths' values
    /// vary little, by the pilot ([`first_band::STEADY`]; all such points
    /// without a pilot); 0 elsewhere.
    pub fn near_bands(&self, scene: &Scene) -> Vec<f64> {
        use rayon::prelude::*;
        (0..self.all.len())
            .into_par_iter()
            .map(|j| {
                let r = self.near_r[j];
                let plain = matches!(self.all[j].response, Response::Illuminance)
                    && self.near_path_setup(j).0.is_none();
                let steady = self
                    .near_var
                    .get(j)
                    .is_none_or(|&v| v <= first_band::STEADY);
                if r > 0.0 && plain && steady {
                    first_band::band_width(scene, self.all[j].p, &self.frames[j], r)
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Whether receiver `j` needs the near/far split ([`near_need`]) but is
    /// on the plain local estimate: the `near` check of
    /// [`crate::tally::Diagnostics`] flags it.
    pub fn near_plain(&self, j: usize) -> bool {
        self.need_r[j] > 0.0 && self.near_r[j] == 0.0
    }

    /// Paths per receiver and batch of the near part (0: off) and each
    /// receiver's near-field radius \[m\] (0: plain local estimate there).
    pub fn near_field(&self) -> (u32, &[f64]) {
        (self.near_paths, &self.near_r)
    }

    /// Receiver `j`'s near-part paths for every 256 chains: its own count
    /// where they were allocated ([`Self::with_allocated_near_paths`]),
    /// else the split's common count (0: off).
    pub fn near_paths_at(&self, j: usize) -> u32 {
        self.near_per.get(j).copied().unwrap_or(self.near_paths)
    }

    /// Receiver `j`'s near-part paths in a batch of `bs` chains (0 where it
    /// has no near part): [`Self::near_paths_at`] for every 256 chains.
    pub fn near_paths_in_batch(&self, j: usize, bs: u64) -> u64 {
        if self.near_r[j] <= 0.0 {
            return 0;
        }
        u64::from(self.near_paths_at(j)) * bs.div_ceil(256)
    }

    /// Each receiver with a near part gets its own number of paths, chosen
    /// by a fixed pilot for the least RMS relative error per unit of work
    /// ([`near_paths`]); without a near part, or where the pilot would
    /// cost too much ([`near_paths::affordable`]), unchanged. Returns the
    /// pilot's measures too (empty when none ran).
    pub fn with_allocated_near_paths(
        mut self,
        scene: &Scene,
        cfg: &crate::run::RunConfig,
    ) -> (Self, near_paths::Allocation) {
        let alloc = self.set_allocated_near_paths(scene, cfg);
        (self, alloc)
    }

    /// [`Self::with_allocated_near_paths`] in place.
    pub fn set_allocated_near_paths(
        &mut self,
        scene: &Scene,
        cfg: &crate::run::RunConfig,
    ) -> near_paths::Allocation {
        if self.near_paths == 0 || !near_paths::affordable(self.total_len) {
            return near_paths::Allocation::default();
        }
        let alloc = near_paths::allocate(scene, self, cfg);
        self.near_per = alloc.paths.clone();
        self.near_var = alloc.near_var.clone();
        alloc
    }

    /// Whether the run's near/far split was set on these receivers by
    /// [`local::prepare`] (so that [`local::run`] takes them as they are).
    pub fn near_prepared(&self) -> bool {
        self.near_prepared
    }

    /// Number of receivers a collision on surface `s` scores into.
    pub fn list_len(&self, s: u32) -> usize {
        self.lists[self.list_of[s as usize] as usize].idx.len()
    }

    /// Length of the flat per-bucket accumulator used by [`Self::score`].
    pub fn accumulator_len(&self) -> usize {
        self.total_len
    }

    /// Add the scores of collision `c` (local estimate \[lx\] or double local
    /// estimate [cd/m^2]) into `acc` (one bucket of length
    /// [`Self::accumulator_len`]), and, when `near` (same layout) is given,
    /// one into it for each receiver it scores into from within that
    /// receiver's watched neighbourhood; returns the number of receiver
    /// scores evaluated.
    #[inline]
    pub fn score(
        &self,
        scene: &Scene,
        c: &Collision,
        acc_all: &mut [f64],
        mut near_all: Option<&mut [f64]>,
    ) -> usize {
        let list = &self.lists[self.list_of[c.surface as usize] as usize];
        let len = list.idx.len();
        let material = &scene.surfaces[c.surface as usize].material;
        if len == 0 {
            return match self.image_list {
                Some(img) => self.score_images(scene, img, material, c, acc_all),
                None => 0,
            };
        }
        let acc = &mut acc_all[list.offset..list.offset + len];
        let mut none = [];
        let (near, counting) = match near_all.as_deref_mut() {
            Some(v) => (&mut v[list.offset..list.offset + len], true),
            None => (&mut none[..], false),
        };
        let (x, n) = (c.p, c.n);
        let (xm, x_inside, open, shapes_open) = collision_context(scene, list, x);
        let nc = list.n_const;
        // A collision at a light's seat scores per pair: points behind the
        // seat do not see it (`score_general`).
        let open = open && c.seat.is_none();
        match material.constant_brdf() {
            Some(f) if open && shapes_open && counting => {
                score_open::<true>(list, x, n, c.q * f, &mut acc[..nc], &mut near[..nc])
            }
            Some(f) if open && shapes_open => {
                score_open::<false>(list, x, n, c.q * f, &mut acc[..nc], &mut [])
            }
            // Shapes may be in the way: through the occluder lists, where
            // the general loop would give the same terms (no panes, light
            // arriving on the front, where its BRDF is `f`; on a curved
            // surface the kernel repeats the general loop's test of the
            // normalised direction, see `occluded_kernel`).
            Some(f)
                if open
                    && !list.occ_start.is_empty()
                    && !scene.has_panes()
                    && c.n.dot(c.wi) > 0.0 =>
            {
                let from = Some((c.surface, c.prim));
                let cell = list.cells.as_ref();
                if counting {
                    occluded_kernel::score_occluded::<true>(
                        scene,
                        list,
                        cell,
                        x,
                        n,
                        from,
                        x_inside,
                        (c.q, f),
                        &mut acc[..nc],
                        &mut near[..nc],
                    )
                } else {
                    occluded_kernel::score_occluded::<false>(
                        scene,
                        list,
                        cell,
                        x,
                        n,
                        from,
                        x_inside,
                        (c.q, f),
                        &mut acc[..nc],
                        &mut [],
                    )
                }
            }
            _ => self.score_general(scene, list, x_inside, 0..nc, material, c, xm, acc, near),
        }
        len + self.score_rest(scene, list, (x_inside, xm), material, c, acc_all, near_all)
    }

    /// The scores of collision `c` beyond the constant-response entries of
    /// its list `list`: into the entries evaluated per pair (`n_const..`),
    /// and by reflection in glass panes ([`Self::score_images`]). `acc_all`
    /// is one bucket of [`Self::accumulator_len`], `near_all` (if
    /// counting) the counts; `(x_inside, xm)` from [`collision_context`].
    /// Returns the pane pairs evaluated.
    #[allow(clippy::too_many_arguments)]
    fn score_rest(
        &self,
        scene: &Scene,
        list: &ReceiverList,
        (x_inside, xm): (u64, SideMask),
        material: &Material,
        c: &Collision,
        acc_all: &mut [f64],
        near_all: Option<&mut [f64]>,
    ) -> usize {
        let (nc, len) = (list.n_const, list.idx.len());
        if nc < len {
            let range = list.offset..list.offset + len;
            let near = match near_all {
                Some(v) => &mut v[range.clone()],
                None => &mut [],
            };
            let acc = &mut acc_all[range];
            self.score_general(scene, list, x_inside, nc..len, material, c, xm, acc, near);
        }
        match self.image_list {
            Some(img) => self.score_images(scene, img, material, c, acc_all),
            None => 0,
        }
    }

    /// [`Self::score`] for a batch's chains, with collisions bound for
    /// the open kernel of a list of more than [`open_kernel::BLOCK`]
    /// entries held in `held` and scored a block of entries at a time
    /// ([`open_kernel::score_open_held`]); the others are scored at once,
    /// after what the list holds. Every entry receives the same terms in
    /// the same order as from [`Self::score`] (the same bits), once
    /// [`Self::flush_held`] has run. `acc_all` holds every bucket of
    /// [`Self::accumulator_len`] and then the counts (the batch's scratch);
    /// the collision goes to bucket `bucket` and is counted where
    /// `counting`.
    #[inline]
    pub fn score_held(
        &self,
        scene: &Scene,
        c: &Collision,
        bucket: usize,
        acc_all: &mut [f64],
        counting: bool,
        held: &mut HeldScores,
    ) -> usize {
        let total = self.total_len;
        let li = self.list_of[c.surface as usize] as usize;
        let list = &self.lists[li];
        let material = &scene.surfaces[c.surface as usize].material;
        if list.n_const > open_kernel::BLOCK
            && c.seat.is_none()
            && let Some(f) = material.constant_brdf()
        {
            let (xm, x_inside, open, shapes_open) = collision_context(scene, list, c.p);
            if open && shapes_open {
                held.lists[li].push(open_kernel::Held {
                    x: c.p,
                    n: c.n,
                    qf: c.q * f,
                    acc: bucket * total + list.offset,
                    count: counting,
                });
                if held.lists[li].len() >= HeldScores::HOLD {
                    self.flush_list(li, held, acc_all);
                }
                // The rest touches other entries than the held ones (and
                // the panes' own stretch, which holds nothing).
                let (acc, near) = acc_all.split_at_mut(acc_all.len() - total);
                let acc = &mut acc[bucket * total..(bucket + 1) * total];
                let near = counting.then_some(near);
                let at = (x_inside, xm);
                return list.idx.len() + self.score_rest(scene, list, at, material, c, acc, near);
            }
        }
        self.flush_list(li, held, acc_all);
        let (acc, near) = acc_all.split_at_mut(acc_all.len() - total);
        let acc = &mut acc[bucket * total..(bucket + 1) * total];
        self.score(scene, c, acc, counting.then_some(near))
    }

    /// Score what list `li` holds ([`Self::score_held`]) and let it go.
    fn flush_list(&self, li: usize, held: &mut HeldScores, acc_all: &mut [f64]) {
        let h = &mut held.lists[li];
        if h.is_empty() {
            return;
        }
        let (acc, near) = acc_all.split_at_mut(acc_all.len() - self.total_len);
        open_kernel::score_open_held(&self.lists[li], h, acc, near);
        h.clear();
    }

    /// Score everything held ([`Self::score_held`]): at the end of a batch,
    /// before its accumulator is read.
    pub fn flush_held(&self, held: &mut HeldScores, acc_all: &mut [f64]) {
        for li in 0..held.lists.len() {
            self.flush_list(li, held, acc_all);
        }
    }

    /// An empty hold for [`Self::score_held`].
    pub fn new_hold(&self) -> HeldScores {
        HeldScores {
            lists: vec![Vec::new(); self.lists.len()],
        }
    }

    /// Scores of collision `c` that reach a receiver by one mirror
    /// reflection in a glass pane (`pane_images` explains the geometry:
    /// the receiver `p` is mirrored to `p'`, the segment from the collision
    /// to `p'` must cross the pane, both legs must be clear). Each is the
    /// plain score towards `p'` times the pane's reflectance at the angle
    /// and the transmittance of other panes on the way; it is added to the
    /// receiver's entry in the image list. Returns the number of pairs
    /// evaluated. Reflections in two panes (`R^2`) are left out.
    fn score_images(
        &self,
        scene: &Scene,
        img: u32,
        material: &Material,
        c: &Collision,
        acc: &mut [f64],
    ) -> usize {
        let list = &self.lists[img as usize];
        let acc = &mut acc[list.offset..list.offset + list.idx.len()];
        let frame = Frame::from_normal(c.n);
        let wi = frame.to_local(c.wi);
        let (origin, from) = match c.seat {
            Some(k) => (scene.light_shadow_origin(k as usize), None),
            None => (c.p, Some((c.surface, c.prim))),
        };
        let mut count = 0;
        for pane in scene.panes() {
            let pl = pane.plane();
            let side = pl.side(c.p);
            if side == 0 {
                continue;
            }
            let mirror = |v: DVec3| v - pl.n * (2.0 * pl.n.dot(v));
            for (k, a) in acc.iter_mut().enumerate() {
                let p = DVec3::new(list.px[k], list.py[k], list.pz[k]);
                if pl.side(p) != side {
                    continue;
                }
                count += 1;
                let np = DVec3::new(list.nx[k], list.ny[k], list.nz[k]);
                let p_img = p - pl.n * (2.0 * pl.signed_distance(p));
                let j = list.idx[k] as usize;
                // A solid receiver: `cos_x / d^2`, its response in `w`.
                let solid = self.all[j].solid_kind().is_some();
                let g = pair_kernel(c.p, c.n, p_img, mirror(np), solid);
                if g == 0.0 {
                    continue;
                }
                let (dx, dp) = (pl.signed_distance(c.p), pl.signed_distance(p_img));
                let m = pl.project(c.p + (p_img - c.p) * (dx / (dx - dp)));
                if !pane.contains(m)
                    || c.seat
                        .is_some_and(|l| scene.behind_light_surface(l as usize, m))
                    || !scene.visible(origin, from, m)
                    || !scene.visible(m, None, p)
                {
                    continue;
                }
                let wo = (p_img - c.p).normalize();
                let f = material.eval(wi, frame.to_local(wo));
                let (r, _) = pane.glass.reflect_transmit(wo.dot(pl.n));
                let glass = scene.pane_transmittance(c.p, m) * scene.pane_transmittance(m, p);
                // Arriving at p from the mirror image of the outgoing direction.
                let w = self.all[j].weight(&self.frames[j], -mirror(wo));
                *a += c.q * f * g * w * r * glass;
            }
        }
        count
    }

    /// Per-pair scoring: any BRDF at the collision and at the receiver, with
    /// visibility masks.
    #[allow(clippy::too_many_arguments)]
    fn score_general(
        &self,
        scene: &Scene,
        list: &ReceiverList,
        x_inside: u64,
        range: std::ops::Range<usize>,
        material: &Material,
        c: &Collision,
        xm: SideMask,
        acc: &mut [f64],
        near: &mut [f64],
    ) {
        let frame = Frame::from_normal(c.n);
        let wi = frame.to_local(c.wi);
        let planes_only = scene.planes_only();
        // Shadow tests from the collision, or from just off a light's seat
        // for a collision there (`Scene::light_shadow_origin`).
        let (origin, from) = match c.seat {
            Some(k) => (scene.light_shadow_origin(k as usize), None),
            None => (c.p, Some((c.surface, c.prim))),
        };
        let cell = list.cells.as_ref().map(|g| g.row(c.p));
        for k in range {
            if !xm.sees(list.masks[k]) {
                continue;
            }
            let p = DVec3::new(list.px[k], list.py[k], list.pz[k]);
            let np = DVec3::new(list.nx[k], list.ny[k], list.nz[k]);
            let j = list.idx[k] as usize;
            // A solid receiver: `cos_x / d^2`, its response (in `w` below)
            // standing for the plane's cosine.
            let solid = k >= list.n_const && self.all[j].solid_kind().is_some();
            let g = pair_kernel(c.p, c.n, p, np, solid);
            let d2 = (p - c.p).length_squared();
            if g == 0.0
                || d2 < list.eps2[k]
                || c.seat
                    .is_some_and(|l| scene.behind_light_surface(l as usize, p))
                || (!planes_only && {
                    let inside = x_inside & list.inside[k];
                    if list.occ_start.is_empty() {
                        scene.blocked_by_shapes(origin, from, p, inside)
                    } else {
                        let occ =
                            &list.occ[list.occ_start[k] as usize..list.occ_start[k + 1] as usize];
                        match cell {
                            Some(row) => {
                                scene.blocked_in_cell(origin, from, p, inside, occ, row[k], d2)
                            }
                            None => scene.blocked_by_occluders(origin, from, p, inside, occ, d2),
                        }
                    }
                })
            {
                continue;
            }
            let wo = (p - c.p).normalize();
            let f = material.eval(wi, frame.to_local(wo));
            let w = if k < list.n_const {
                list.w[k]
            } else {
                self.all[j].weight(&self.frames[j], -wo)
            };
            let glass = scene.pane_transmittance(c.p, p);
            acc[k] += c.q * f * g * w * glass;
            if !near.is_empty() && d2 < list.watch2[k] {
                near[k] += 1.0;
            }
        }
    }

    /// Add a flat accumulator bucket (see [`Self::score`]) into per-receiver sums.
    pub fn reduce(&self, acc: &[f64], per_point: &mut [f64]) {
        for list in &self.lists {
            for (k, &j) in list.idx.iter().enumerate() {
                per_point[j as usize] += acc[list.offset + k];
            }
        }
    }
}

/// Collisions held for the open kernel, per receiver list
/// ([`Receivers::score_held`]).
#[derive(Debug)]
pub struct HeldScores {
    lists: Vec<Vec<open_kernel::Held>>,
}

impl HeldScores {
    /// Collisions a list holds before they are scored: enough that reading
    /// a block of entries from memory is spread over many of them.
    const HOLD: usize = 256;
}

/// How a collision at `x` on a surface of `list` reaches the list's
/// entries: its side mask (planes that may be in the way), the spheres and
/// boxes it lies inside, whether no plane separates it from any entry
/// (`open`), and whether no shape can be in the way either.
#[inline]
fn collision_context(scene: &Scene, list: &ReceiverList, x: DVec3) -> (SideMask, u64, bool, bool) {
    let xm = if list.blockers != 0 {
        scene.side_mask(x)
    } else {
        SideMask::default()
    };
    let open = (xm.front | xm.back) & list.blockers == 0;
    // Spheres and boxes holding both the collision and every entry never block.
    let x_inside = if scene.planes_only() {
        0
    } else {
        scene.inside_mask(x)
    };
    // Panes on the way scale scores by their transmittance: per pair.
    let shapes_open = scene.planes_only()
        || (!scene.has_panes() && scene.nothing_blocks(x_inside & list.inside_all));
    (xm, x_inside, open, shapes_open)
}

/// Share of a receiver's distance to the nearest light within which a
/// surface makes it need the near/far split ([`near_need`]).
pub const NEAR_TRIGGER: f64 = 0.1;

/// The split's radius where a receiver needs it ([`near_need`]), as a share
/// of its distance to the nearest light: a quarter, not the tenth it was
/// (the share that triggers the split, [`NEAR_TRIGGER`]). Between the
/// Sobolev planes (h = 0.5, rho = 0.5, 20,000 chains, 100 seeds each) a
/// tenth left the points at r = 12-30 with their first-order light from
/// 3-10 m away to rare light-tracing collisions, whose batch means were so
/// skewed that the 95 % intervals covered 82-90 % of runs (mean z^2
/// 1.7-2.3, the misses all low; z = -7.4 at r = 30 with seed 94, every
/// check `ok`). A quarter: R 5-10 times smaller there at 1.6 times the
/// run time, coverage 91-97 % (mean z^2 0.9-1.3); the office's FOM at its
/// 506 planar grid points unchanged within the machine's noise (1.35e4 and
/// 1.74e4 against 1.35e4-1.64e4, `lumest bench --scene data/office.toml`).
/// A half helped the far points as much but cost the office about 10 %;
/// a quarter as the trigger too split the points at r = 5-10 as well (R
/// 2-8 % -> about 1 %) but split many points near walls that had none, and
/// is left for another turn.
pub const NEAR_SHARE: f64 = 0.25;

/// The near/far radius \[m\] a receiver at `p` (normal frame `frame`) needs:
/// [`NEAR_SHARE`] of the distance `d` to the nearest light, `R = 0.25 d`,
/// where one of 64 probe rays over the receiver's hemisphere (a Fibonacci
/// spiral, cosine-distributed; over the whole sphere for a solid receiver,
/// `sphere`) meets a surface closer than [`NEAR_TRIGGER`] `d = 0.1 d`; 0
/// elsewhere (and in a scene without lights). In a scene lit from infinity
/// alone (sun, sky, environment) `d` is the scale of the chains' start
/// density next to the point ([`Light::start_scale`]), or in a room (three
/// in four probes meet a surface, in front of the point and behind it) of
/// finite shapes or lit through portals the median distance of the
/// probes' hits. Closer than that, the local estimate's `1/d^2`
/// kernel dominates its variance (infinite in a corner), and far from the
/// lights the light reaching the point from around it comes from rare
/// collisions.
pub fn near_need(scene: &Scene, p: DVec3, frame: &Frame, sphere: bool) -> f64 {
    const PROBES: usize = 64;
    let mut hits: Vec<f64> = (0..PROBES)
        .map(|k| {
            let w = probe_direction(k, PROBES, frame, sphere);
            scene.first_hit_from(p, w).map_or(f64::INFINITY, |h| h.t)
        })
        .collect();
    let mut d = scene
        .lights
        .iter()
        .filter(|l| !l.is_directional())
        .map(|l| (l.position() - p).length())
        .fold(f64::INFINITY, f64::min);
    if d == f64::INFINITY && !scene.lights.is_empty() {
        // Lit from infinity alone (the sun, the sky). In a room (three in
        // four probes meet a surface, in front of the point and behind it)
        // of finite shapes, or lit through portals, the scale is the
        // point's surroundings, the median distance of the probes' hits (a
        // point 1 mm from two walls of a daylit room read 29 % low,
        // unflagged). Under the open sky, and over infinite planes, it is
        // the chains' start density next to the point, the counterpart of
        // a point light's distance ([`Light::start_scale`]). (The probes
        // in front alone took a point facing a surface 2 mm off for one in
        // a room, and its median, 3 mm, as the scale: under the open sky,
        // a point 2 mm off a lit block's side read 1788 +- 708 lx against
        // the backward 18835 +- 6, points 1-2 cm above an infinite ground
        // facing down 5-50 % of `rho E_h`, flagged `sparse`.)
        hits.sort_by(f64::total_cmp);
        let mostly_met = |met: usize| met >= 3 * PROBES / 4;
        let room = mostly_met(hits.iter().filter(|t| t.is_finite()).count())
            && (sphere || {
                let back = Frame::from_normal(-frame.n);
                mostly_met(
                    (0..PROBES)
                        .filter(|&k| {
                            let w = probe_direction(k, PROBES, &back, false);
                            scene.first_hit_from(p, w).is_some()
                        })
                        .count(),
                )
            });
        let unbounded = !scene.planes().is_empty();
        d = scene
            .lights
            .iter()
            .filter(|_| unbounded || !room)
            .filter_map(|l| l.start_scale(p))
            .fold(f64::INFINITY, f64::min);
        if d == f64::INFINITY && room {
            d = hits[PROBES / 2];
        }
    }
    let r = NEAR_TRIGGER * d;
    if !r.is_finite() || r <= 0.0 {
        return 0.0;
    }
    if hits.iter().any(|&t| t < r) {
        NEAR_SHARE * d
    } else {
        0.0
    }
}

/// Largest mean reach of a slot's table ([`GrazingTable::mean_reach`]):
/// where light gets in through more than about 1 % of the cosine-weighted
/// hemisphere, cosine-sampled paths find it often enough and the local
/// estimate's collisions land there, so the split stays as it was. (A
/// point at the very edge of a board, mean reach 0.5, ran 4-13 times less
/// efficiently as a slot; points 5 cm inside the edge, mean reach 0.024,
/// about as well; the office's 12 points behind the whiteboard have
/// 2.4e-4 to 3.1e-3.)
const SLOT_REACH: f64 = 0.01;

/// Where an enclosed illuminance point at `p` (normal frame `frame`) can
/// receive light from: per azimuth bin of a [`GrazingTable`], the largest
/// `cos^2 theta` at which a ray from `p` still meets the front of a surface
/// (bisection in `log cos^2 theta` over `[1e-8, 1]` at the 32 bin edges;
/// a bin takes 1.25 times the larger of its edges'), and the farthest
/// such first hit \[m\] (times 1.01). `None` where no direction gets
/// through. On a wall behind a board hung 1 cm off it (the board's back
/// black) the light comes in only through the slit round the board, almost
/// parallel to the wall: cosine sampling finds it once in 10^3-10^4 paths,
/// and the local estimate scores into the point only from collisions in a
/// strip about 2 cm wide along the wall.
pub fn slot_table(scene: &Scene, p: DVec3, frame: &Frame) -> Option<(GrazingTable, f64)> {
    const BINS: usize = 32;
    const STEPS: usize = 24;
    let lowest = 1e-8f64.ln();
    let mut farthest: f64 = 0.0;
    let mut through = |turns: f64, v: f64| -> bool {
        let (sp, cp) = (turns * std::f64::consts::TAU).sin_cos();
        let st = (1.0 - v).max(0.0).sqrt();
        let d = frame.to_world(DVec3::new(st * cp, st * sp, v.sqrt()));
        match scene.first_hit_from(p, d) {
            Some(h) if d.dot(h.n) < 0.0 => {
                farthest = farthest.max(h.t);
                true
            }
            _ => false,
        }
    };
    let edges: Vec<f64> = (0..BINS)
        .map(|a| {
            let turns = a as f64 / BINS as f64;
            if !through(turns, lowest.exp()) {
                return 0.0;
            }
            // through at `lo`, blocked (or untested) at `hi`.
            let (mut lo, mut hi) = (lowest, 0.0);
            if through(turns, 1.0) {
                return 1.0;
            }
            for _ in 0..STEPS {
                let mid = 0.5 * (lo + hi);
                if through(turns, mid.exp()) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo.exp()
        })
        .collect();
    let reach = (0..BINS)
        .map(|a| 1.25 * edges[a].max(edges[(a + 1) % BINS]))
        .collect();
    let table = GrazingTable::new(reach)?;
    Some((table, 1.01 * farthest))
}

/// Radius \[m\] of the neighbourhood holding almost all of what an
/// illuminance point at `p` (normal frame `frame`) sees: ten times the
/// median distance along 16 cosine-distributed probe rays (a Fibonacci
/// spiral over its hemisphere), 0 when half of them or more escape. Facing
/// a plane at distance `h` the median is `sqrt(2) h` and the disc of
/// radius `14 h` holds 99.5 % of the cosine-weighted view
/// (`a^2 / (a^2 + h^2)`). The local estimate of the light from there rests
/// on the collisions that land there, which [`Receivers::score`] counts.
pub fn view_radius(scene: &Scene, p: DVec3, frame: &Frame) -> f64 {
    view_probe(scene, p, frame, false).0
}

/// The probe of [`view_radius`], which also tells whether the point is
/// *enclosed*: more than half of its 16 probe rays meet the back (black)
/// side of a surface, as from inside a solid, behind a wall or outside a
/// closed room. Returns `(radius, enclosed)`. With `sphere` (a solid
/// receiver, which sees every direction) the probes cover the whole sphere.
pub fn view_probe(scene: &Scene, p: DVec3, frame: &Frame, sphere: bool) -> (f64, bool) {
    const PROBES: usize = 16;
    let mut back = 0;
    let mut t: Vec<f64> = (0..PROBES)
        .map(|k| {
            let d = probe_direction(k, PROBES, frame, sphere);
            let h = scene.first_hit_from(p, d);
            if h.as_ref().is_some_and(|h| d.dot(h.n) >= 0.0) {
                back += 1;
            }
            h.map_or(f64::INFINITY, |h| h.t)
        })
        .collect();
    t.sort_by(f64::total_cmp);
    let median = 0.5 * (t[PROBES / 2 - 1] + t[PROBES / 2]);
    let radius = if median.is_finite() {
        10.0 * median
    } else {
        0.0
    };
    (radius, back > PROBES / 2)
}

/// Probe direction `k` of `count` over the hemisphere of `frame`'s normal:
/// a Fibonacci spiral, cosine-distributed (`sin^2 theta` uniform in (0, 1));
/// with `sphere`, uniform over the whole sphere (`cos theta` uniform in
/// (-1, 1)).
fn probe_direction(k: usize, count: usize, frame: &Frame, sphere: bool) -> DVec3 {
    // The local directions of the two probe counts used, computed once
    // (their sines and cosines were a tenth of the set-up of 1,000,000
    // points); the same bits as computing them here.
    static TABLES: std::sync::OnceLock<[Vec<DVec3>; 4]> = std::sync::OnceLock::new();
    let tables = TABLES.get_or_init(|| {
        let t = |count: usize, sphere: bool| {
            (0..count).map(|k| probe_local(k, count, sphere)).collect()
        };
        [t(16, false), t(16, true), t(64, false), t(64, true)]
    });
    let local = match (count, sphere) {
        (16, false) => tables[0][k],
        (16, true) => tables[1][k],
        (64, false) => tables[2][k],
        (64, true) => tables[3][k],
        _ => probe_local(k, count, sphere),
    };
    frame.to_world(local)
}

/// Probe direction `k` of `count` in the local frame ([`probe_direction`]).
fn probe_local(k: usize, count: usize, sphere: bool) -> DVec3 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let (st, ct) = if sphere {
        let ct = 1.0 - 2.0 * (k as f64 + 0.5) / count as f64;
        ((1.0 - ct * ct).max(0.0).sqrt(), ct)
    } else {
        let s2 = (k as f64 + 0.5) / count as f64;
        (s2.sqrt(), (1.0 - s2).sqrt())
    };
    let (sp, cp) = (golden * k as f64).sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}
