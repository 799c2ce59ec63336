//! Light-tracing Markov chains: emission -> collisions -> Russian roulette.
//!
//! A chain starts at a light picked in proportion to its power, with weight
//! `Q_1` equal to the flux of the sampled ray \[lm\] divided by the pick
//! probability, so that `E[sum_n Q_n delta(x - x_n)]` is the collision density
//! (the illuminance arriving at surface points, all orders). At each collision
//! on a front side the chain reports a [`Collision`], then continues by
//! sampling the material (weight times `f_r cos / pdf`, the albedo for
//! Lambertian surfaces). Back sides absorb; rays that leave the scene end.
//!
//! A glass pane on the way ([`crate::scene::Scene::next_pane`]) mirrors the
//! ray or lets it through, picked in proportion to the pane's reflectance
//! and transmittance at that angle, the weight times their sum; it is not a
//! collision.
//!
//! Termination is unbiased: when the weight falls below `rr_weight * Q_1` the
//! chain survives with probability `Q / (rr_weight * Q_1)` and, if it does,
//! its weight is raised to `rr_weight * Q_1`. With `rr_weight = 1` this is the
//! analog game (absorption with probability `1 - albedo`). There is no bounce
//! cap unless `max_order` is set, which truncates (biases) on purpose for
//! order-resolved studies.

use crate::geometry::{Hit, Ray};
use crate::sampling::Philox4x32;
use crate::sampling::warp::Frame;
use crate::scene::Scene;
use glam::DVec3;

/// One collision of a chain with a surface's front side.
#[derive(Clone, Copy, Debug)]
pub struct Collision {
    /// Collision point \[m\].
    pub p: DVec3,
    /// Unit front normal at `p`.
    pub n: DVec3,
    /// Unit direction towards where the light came from (away from the surface).
    pub wi: DVec3,
    /// Flux weight arriving at the collision \[lm\].
    pub q: f64,
    /// Surface index.
    pub surface: u32,
    /// Primitive within the surface (a mesh's triangle; 0 otherwise).
    pub prim: u32,
    /// Collision number: 1 for the first hit after emission. Light reflected
    /// here and scored at a point is of reflection order `order`.
    pub order: u32,
    /// The point-like light whose seat this collision lies at (light it
    /// sent into a surface it stands on, met at its own position,
    /// [`Scene::light_surface`]), if any, where the seat holds more than
    /// one face: what it reflects leaves from just in front of the seat,
    /// so a point behind the seat does not see it
    /// ([`Scene::behind_light_surface`]), as it does not see the light.
    pub seat: Option<u32>,
}

/// Parameters of the random walk.
#[derive(Clone, Copy, Debug)]
pub struct ChainParams {
    /// Roulette threshold and survival weight, relative to the starting weight (0, 1].
    pub rr_weight: f64,
    /// Stop after this many collisions (biased truncation, for studies only).
    pub max_order: Option<u32>,
    /// Backward paths add, at each vertex, a light-guided connection
    /// combined with the BRDF-sampled next vertex by multiple importance
    /// sampling ([`crate::backward`]): the backward estimator's at every
    /// vertex, the near part's of the near/far split where the vertex's
    /// region reaches nearer a light than its radius; `false` leaves plain
    /// next-event estimation. Light-tracing chains do not use it.
    pub guide: bool,
}

impl Default for ChainParams {
    fn default() -> Self {
        Self {
            rr_weight: 0.1,
            max_order: None,
            guide: true,
        }
    }
}

/// How a chain ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChainEnd {
    /// The ray left the scene (in a closed scene: a leak).
    Escaped,
    /// The ray met a black back side and was absorbed there.
    BackSide,
    /// Russian roulette, a zero weight, or a sampled direction below the surface.
    Absorbed,
    /// Stopped by `max_order`.
    Truncated,
}

/// The uniforms of a chain's leading decisions, given by the caller (from a
/// stratified net over the batch, or from the chain's stream); a `None`
/// draws from the chain's stream where it is used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeadingUniforms {
    /// The light pick.
    pub pick: Option<f64>,
    /// The emission position on the light (area lights, openings).
    pub pos: Option<[f64; 2]>,
    /// The emitted direction.
    pub dir: [f64; 2],
    /// The reflections at collisions 1, 2, 3.
    pub reflect: [Option<[f64; 2]>; 3],
}

/// Coordinates of one point of a net that [`LeadingUniforms::from_point`] reads.
pub const LEADING_DIMS: usize = 11;

impl LeadingUniforms {
    /// All leading uniforms from the coordinates `u(d)`, `d < LEADING_DIMS`,
    /// of one point of a net, the decisions that shape the first collisions
    /// most on the best-stratified coordinates: the emitted direction on
    /// 0-1 (a (0,2)-pair of Sobol' points), the first reflection on 2-3,
    /// the emission position on 4-5, the light pick on 6, the second and
    /// third reflections on 7-8 and 9-10.
    #[inline]
    pub fn from_point(mut u: impl FnMut(usize) -> f64) -> Self {
        Self {
            dir: [u(0), u(1)],
            reflect: [Some([u(2), u(3)]), Some([u(7), u(8)]), Some([u(9), u(10)])],
            pos: Some([u(4), u(5)]),
            pick: Some(u(6)),
        }
    }
}

/// The emitted direction and the first reflection; the rest from the stream.
impl From<[[f64; 2]; 2]> for LeadingUniforms {
    fn from(u: [[f64; 2]; 2]) -> Self {
        Self {
            pick: None,
            pos: None,
            dir: u[0],
            reflect: [Some(u[1]), None, None],
        }
    }
}

/// Trace one chain, calling `on_collision` at every front-side collision.
/// `u_first` are the uniforms of its leading decisions ([`LeadingUniforms`];
/// `[[f64; 2]; 2]`: the emitted direction and the first reflection);
/// everything else draws from `rng`.
/// Returns the number of collisions.
#[inline]
pub fn trace<F: FnMut(&Collision)>(
    scene: &Scene,
    rng: &mut Philox4x32,
    params: &ChainParams,
    u_first: impl Into<LeadingUniforms>,
    on_collision: F,
) -> u32 {
    trace_ex(scene, rng, params, u_first, on_collision).0
}

/// [`trace`], also reporting how the chain ended.
#[inline]
pub fn trace_ex<F: FnMut(&Collision)>(
    scene: &Scene,
    rng: &mut Philox4x32,
    params: &ChainParams,
    u_first: impl Into<LeadingUniforms>,
    mut on_collision: F,
) -> (u32, ChainEnd) {
    let lead: LeadingUniforms = u_first.into();
    let k_light = scene.pick_light_index(lead.pick.unwrap_or_else(|| rng.next_f64()));
    let light = &scene.lights[k_light];
    let u_pos = lead.pos.unwrap_or_else(|| rng.next_2d());
    let u_extra = if light.emits_from_opening() {
        rng.next_f64()
    } else {
        u_pos[0]
    };
    let e = light.sample_emission(lead.dir, u_pos, u_extra);
    let q0 = scene.total_power();
    // A light picked with probability power/total carries the total power per chain.
    let mut q = e.phi / light.power() * q0;
    let mut ray = Ray { o: e.o, d: e.d };
    let mut skip = None;
    let rr = params.rr_weight * q0;
    let mut order = 0;
    let mut end = ChainEnd::Absorbed;
    // A ray leaving an area source starts on its emitting surface, which may
    // lie in another surface's plane (a panel set into the ceiling): like
    // an observer's, it meets no flat surface through its origin.
    let through_portal = light.is_directional() && scene.has_portals();
    let mut from_emitter = matches!(light, crate::light::Light::Area(_))
        || light.emits_from_opening()
        || through_portal;
    // A ray started on a portal carries light only if nothing blocks it
    // between the light and the portal ([`crate::light::portal`]).
    if through_portal && q > 0.0 {
        if scene.first_hit_from(ray.o, -ray.d).is_some() {
            q = 0.0;
        } else {
            // Glass on the way in (a pane set in the portal's opening
            // included) passes its transmittance ([`Scene::pane_transmittance_ray`]).
            q *= scene.pane_transmittance_ray(ray.o, -ray.d, true);
        }
    }
    // A point light on a surface stands on its reflecting side
    // ([`Scene::light_surface`]): a ray into the surface meets it at once.
    // On an edge or a corner a ray reflected there is tested again: a
    // room's corner can send it into another face at once.
    let seat = scene.light_surface(k_light);
    let mut on_surface = seat.is_some();
    while q > 0.0 {
        let mut at_seat = false;
        let next = if from_emitter {
            from_emitter = false;
            scene.first_hit_from(ray.o, ray.d)
        } else if let Some(seat) = seat.filter(|_| on_surface) {
            match seat.meets_prim(ray.d) {
                Some((s, n, prim)) => {
                    at_seat = true;
                    Some(Hit {
                        t: 0.0,
                        p: ray.o,
                        n,
                        surface: s,
                        prim,
                    })
                }
                None => {
                    on_surface = false;
                    scene.intersect(&ray, Some(seat.leaves(ray.d)))
                }
            }
        } else {
            scene.intersect(&ray, skip)
        };
        // A glass pane before the surface: mirrored or passed straight
        // through with probabilities R : T, the weight times R + T; no
        // collision (a specular event scores nowhere).
        if scene.has_panes() {
            let t_max = next.as_ref().map_or(f64::INFINITY, |h| h.t);
            if let Some(ph) = scene.next_pane(&ray, t_max) {
                let Some((d, w)) = scene.pane_scatter(ph.pane, ray.d, rng.next_f64()) else {
                    break;
                };
                let Some(survivor) = roulette(q * w, rr, rng) else {
                    break;
                };
                q = survivor;
                ray = Ray { o: ph.p, d };
                // Leaving the pane's plane, the ray meets no flat surface
                // through its origin (an observer's rule).
                from_emitter = true;
                on_surface = false;
                continue;
            }
        }
        let Some(hit) = next else {
            end = ChainEnd::Escaped;
            break;
        };
        if ray.d.dot(hit.n) >= 0.0 {
            end = ChainEnd::BackSide;
            break; // back side: absorbed
        }
        order += 1;
        let wi = -ray.d;
        on_collision(&Collision {
            p: hit.p,
            n: hit.n,
            wi,
            q,
            surface: hit.surface,
            prim: hit.prim,
            order,
            // (On one face, the collision's own cosine hides what the seat
            // does: the scores take the fast kernels.)
            seat: (at_seat && seat.is_some_and(|s| !s.single_face())).then_some(k_light as u32),
        });
        if params.max_order.is_some_and(|m| order >= m) {
            end = ChainEnd::Truncated;
            break;
        }
        let m = &scene.surfaces[hit.surface as usize].material;
        let frame = Frame::from_normal(hit.n);
        let wi_local = frame.to_local(wi);
        let u = lead
            .reflect
            .get(order as usize - 1)
            .copied()
            .flatten()
            .unwrap_or_else(|| rng.next_2d());
        let s = m.sample(wi_local, u);
        if s.pdf <= 0.0 || s.w.z <= 0.0 {
            break;
        }
        q *= m.eval(wi_local, s.w) * s.w.z / s.pdf;
        let Some(survivor) = roulette(q, rr, rng) else {
            break;
        };
        q = survivor;
        ray = Ray {
            o: hit.p,
            d: frame.to_world(s.w),
        };
        skip = Some((hit.surface, hit.prim));
    }
    (order, end)
}

/// Russian roulette on a weight `w` against the threshold `t`: a weight at
/// or above `t` is kept; one below survives with probability `w / t`
/// (drawing one uniform from `rng`) and is raised to `t`, so the expected
/// weight is unchanged. `None`: the walk ends. Light-tracing chains and
/// backward paths both play it.
#[inline]
pub fn roulette(w: f64, t: f64, rng: &mut Philox4x32) -> Option<f64> {
    if w >= t {
        Some(w)
    } else if rng.next_f64() >= w / t {
        None
    } else {
        Some(t)
    }
}
