//! Backward (observer-side) path tracing with next-event estimation: an
//! estimator independent of the light-tracing chains and the local
//! estimates, for cross-checks and honest comparisons.
//!
//! For each receiver a batch traces `bs` paths. A path leaves the receiver
//! in a direction sampled from its response: cosine-weighted about the normal
//! for illuminance (`E = pi E[L_i]`), the sub-point's BRDF for luminance
//! (weight `f' cos / pdf`), a solid receiver's own lobe over the whole
//! sphere (weight `r / pdf`, [`crate::estimator::Solid`]). At each surface vertex `k = 1, 2, ...` it adds
//! next-event estimation from every point light, `beta f_k(wi_l, wo) I cos / d^2 V`,
//! which is light reflected `k` times before it reaches the receiver (the
//! same order buckets as the local estimate), then continues by sampling the
//! BRDF, with Russian roulette on the throughput. The first order is the
//! exact one shared with the local estimator ([`Receivers::direct`]).
//!
//! Path `s` of batch `b` at receiver `j` draws from the Philox stream
//! `(seed ^ BACKWARD_KEY, (b bs + s) n + j)`, so results do not depend on the
//! thread count.

use crate::chain::Collision;
use crate::chain::roulette;
use crate::estimator::first_band::FirstBand;
use crate::estimator::local_kernel;
use crate::estimator::{Receiver, Receivers, Response};
use crate::geometry::{Hit, Ray};
use crate::light::Light;
use crate::material::Material;
use crate::run::{Batch, BatchWork, Checks, Progress, RunConfig, RunResult, cap_batch_size, drive};
use crate::sampling::Philox4x32;
use crate::sampling::grazing::GrazingTable;
use crate::sampling::warp::{Frame, sample_cosine_hemisphere, sample_uniform_sphere};
use crate::scene::Scene;
use crate::tally::bucket;
use glam::DVec3;
use std::f64::consts::PI;

/// Key offset separating backward streams from the chains' streams.
const BACKWARD_KEY: u64 = 0x6261_636b_7761_7264; // "backward"

struct BackwardWork<'a> {
    scene: &'a Scene,
    receivers: &'a Receivers,
    /// Each light's neighbourhood: centre \[m\] and squared radius [m^2] (see [`light_reach`]).
    reach: Vec<(DVec3, f64)>,
}

/// Run the backward estimator on `receivers` (same statistics, stopping
/// rules and output as [`crate::estimator::local::run`]; "chains" count paths).
///
/// Its `sparse` check ([`crate::tally::Diagnostics`]) counts, per receiver,
/// the path vertices that land in some light's neighbourhood
/// ([`light_reach`]), where the light piles up: a receiver whose paths
/// (almost) never get there misses most of its reflected light whatever its
/// error bar says (in the far field of two highly reflecting planes the
/// estimate is 44 % low with otherwise steady statistics).
pub fn run(
    scene: &Scene,
    receivers: &Receivers,
    cfg: &RunConfig,
    observe: &mut dyn FnMut(&Progress) -> bool,
) -> RunResult {
    // A light at infinity lights every vertex alike: every vertex counts.
    let reach = scene
        .lights
        .iter()
        .map(|l| {
            if l.is_directional() {
                (l.position(), f64::INFINITY)
            } else {
                (l.position(), light_reach(scene, l).powi(2))
            }
        })
        .collect();
    drive(
        &BackwardWork {
            scene,
            receivers,
            reach,
        },
        cfg,
        observe,
    )
}

/// Radius \[m\] of a light's neighbourhood: ten times the median distance
/// from its centre to the first surface along 16 directions spread evenly
/// over the sphere (a Fibonacci lattice); infinite when half of them or
/// more escape (an open scene: every vertex then counts). The mirror image
/// of [`crate::estimator::view_radius`]: facing a plane at distance `h`, the
/// ball holds 93 % of the light's first hits, and between two planes the
/// bright halo around the source.
pub fn light_reach(scene: &Scene, light: &Light) -> f64 {
    const PROBES: usize = 16;
    let golden = PI * (3.0 - 5f64.sqrt());
    let o = light.position();
    let mut t: Vec<f64> = (0..PROBES)
        .map(|k| {
            let z = 1.0 - 2.0 * (k as f64 + 0.5) / PROBES as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (sp, cp) = (golden * k as f64).sin_cos();
            let d = DVec3::new(r * cp, r * sp, z);
            scene
                .intersect(&Ray { o, d }, None)
                .map_or(f64::INFINITY, |h| h.t)
        })
        .collect();
    t.sort_by(f64::total_cmp);
    10.0 * 0.5 * (t[PROBES / 2 - 1] + t[PROBES / 2])
}

impl BatchWork for BackwardWork<'_> {
    fn len(&self) -> usize {
        self.receivers.len()
    }
    fn direct(&self) -> &[f64] {
        self.receivers.direct()
    }
    fn emits(&self) -> bool {
        self.scene.total_power() > 0.0
    }
    fn scratch_len(&self, _buckets: usize) -> usize {
        0
    }
    fn checks(&self) -> Checks {
        // Every receiver is watched when some light has a finite neighbourhood.
        let watched = self.reach.iter().any(|&(_, r2)| r2.is_finite());
        Checks {
            watched: vec![watched; self.len()],
            near_plain: vec![false; self.len()],
            near_reach: vec![false; self.len()],
            enclosed: (0..self.len())
                .map(|j| self.receivers.enclosed(j))
                .collect(),
            approximate: self.scene.approximate.is_some(),
        }
    }

    /// Paths per receiver per batch: about 2^18 path vertices per batch in
    /// all, the mean path length measured by a fixed pilot (16 paths per
    /// receiver on their own streams, so the batch size never depends on
    /// timing, seed or thread count); at least `MIN_BATCHES` batches for a
    /// `--chains` run (chains = paths per receiver). Long paths (reflectances
    /// near 1) thus get small batches and `--time` is kept.
    fn default_batch_size(&self, chains: Option<u64>) -> u64 {
        const PILOT: u64 = 16;
        const PILOT_KEY: u64 = 0x0070_696c_6f74; // "pilot"
        let n = self.receivers.len().max(1) as u64;
        let mut vertices = 0u64;
        let cfg = RunConfig::default();
        for (j, rec) in self.receivers.receivers().iter().enumerate() {
            for s in 0..PILOT {
                let mut rng = Philox4x32::new(PILOT_KEY, s * n + j as u64);
                let path = PathSetup {
                    first_max: f64::INFINITY,
                    vertex_r: f64::INFINITY,
                    grazing: None,
                    pool: None,
                    reach: &[],
                    peaked: false,
                    first_band: None,
                };
                let frame = &self.receivers.frames()[j];
                vertices +=
                    trace(self.scene, rec, frame, &cfg, &mut rng, &path, |_, _| {}).vertices;
            }
        }
        let per_path = 1 + vertices / (PILOT * n) * (1 + self.scene.lights.len() as u64);
        let bs = ((1u64 << 18) / (n * per_path)).clamp(1, 1 << 14);
        cap_batch_size(bs, chains)
    }

    fn run_batch(
        &self,
        cfg: &RunConfig,
        b: u64,
        bs: u64,
        buckets: usize,
        _scratch: &mut [f64],
    ) -> Batch {
        let n = self.receivers.len();
        let mut sums = vec![0.0; buckets * n];
        let mut near_hits = vec![0u64; n];
        let mut vertices = 0u64;
        let path = PathSetup {
            first_max: f64::INFINITY,
            vertex_r: f64::INFINITY,
            grazing: None,
            pool: None,
            reach: &self.reach,
            peaked: false,
            first_band: None,
        };
        for (j, rec) in self.receivers.receivers().iter().enumerate() {
            let frame = &self.receivers.frames()[j];
            for s in 0..bs {
                let stream = (b * bs + s) * n as u64 + j as u64;
                let mut rng = Philox4x32::new(cfg.seed ^ BACKWARD_KEY, stream);
                let walk = trace(self.scene, rec, frame, cfg, &mut rng, &path, |order, v| {
                    sums[bucket(order, cfg.orders) * n + j] += v;
                });
                vertices += walk.vertices;
                near_hits[j] += walk.reached;
            }
        }
        // The sampled direct light, as sums over the batch's `bs` paths per
        // receiver (the runner folds every batch by its batch size).
        let mut direct_sums = Vec::new();
        if self.receivers.has_sampled_direct() {
            direct_sums = vec![0.0; n];
            self.receivers
                .sampled_direct(self.scene, cfg.seed, b, bs, &mut direct_sums);
        }
        Batch {
            index: b,
            chains: bs * n as u64,
            sums,
            collisions: vertices,
            scores: vertices,
            near_hits,
            direct_sums,
        }
    }
}

/// The light-tracing collisions of a batch, for the recursive near/far
/// split of the near part (see [`trace`]): a uniform random subset of at
/// most [`Pool::CAP`] of the batch's collisions (reservoir sampling on its
/// own stream), the number it was drawn from, and the batch's chains.
pub(crate) struct Pool {
    items: Vec<Collision>,
    seen: u64,
    chains: u64,
    rng: Philox4x32,
}

impl Pool {
    /// Most collisions kept per batch.
    pub(crate) const CAP: usize = 1 << 16;
    /// Pool collisions joined to a path vertex of full weight (see
    /// [`Pool::picks`]).
    pub(crate) const PICKS: u32 = 16;

    /// Pool collisions joined to a vertex of path weight `beta` on a path
    /// that started with weight `beta0`: `ceil(PICKS beta / beta0)`, at
    /// least 1 and at most [`Self::PICKS`]. A vertex's joins are scaled by
    /// its own count, so any count leaves the estimate unbiased; this one
    /// spends the shadow tests where they weigh, as a vertex's pool light
    /// scales with its weight (a Lambertian path's weight falls by its
    /// reflectance at each bounce; the first vertex keeps full weight).
    /// Measured against 16 at every vertex, same seeds, same minutes: the
    /// office's 506 planar grid points (524,288 chains, 2 threads, seeds 1
    /// and 2) ran 12-15 % faster at the same RMS error, FOM 5.5e3-5.9e3 ->
    /// 6.4e3 (the near parts of the points behind the cabinet bounce in a
    /// 5 cm gap); the far field of two planes (`rho1 rho2 = 0.99`,
    /// `r = 1e4`, 8 s, seeds 1-4) R 1.4e-3-1.7e-3 -> 0.95e-3-1.1e-3 at 1.5
    /// times the chains; points 1 mm to 5 cm above the lit Sobolev floor
    /// unchanged.
    pub(crate) fn picks(beta: f64, beta0: f64) -> u32 {
        let k = (f64::from(Self::PICKS) * (beta / beta0)).ceil();
        // (`as` saturates, NaN to 0.)
        (k as u32).clamp(1, Self::PICKS)
    }

    /// An empty pool for a batch of `chains` chains, drawing its reservoir
    /// choices from `rng`.
    pub(crate) fn new(chains: u64, rng: Philox4x32) -> Self {
        Self {
            items: Vec::new(),
            seen: 0,
            chains,
            rng,
        }
    }

    /// Offer a collision (Vitter's algorithm R: every collision of the batch
    /// ends up in the pool with the same probability).
    pub(crate) fn offer(&mut self, c: &Collision) {
        self.seen += 1;
        if self.items.len() < Self::CAP {
            self.items.push(*c);
        } else {
            let j = (self.rng.next_f64() * self.seen as f64) as u64;
            if (j as usize) < Self::CAP {
                self.items[j as usize] = *c;
            }
        }
    }
}

/// How a backward path is traced (see [`trace`]).
pub(crate) struct PathSetup<'a> {
    /// A path whose first surface lies at or beyond this distance \[m\] from
    /// the receiver contributes nothing (the near part of the local
    /// estimator's near/far split); `f64::INFINITY` for a full path.
    pub(crate) first_max: f64,
    /// With a pool: the receiver's share of the split radius at the path's
    /// vertices (see [`split_radius`]); `first_max` but for a receiver in a
    /// slot ([`crate::estimator::slot_table`]), whose first segment reaches
    /// farther than the radius it needs.
    pub(crate) vertex_r: f64,
    /// An illuminance receiver in a slot draws its first direction from
    /// this table instead of the cosine (and its light-guided connection
    /// weighs by the table's density).
    pub(crate) grazing: Option<&'a GrazingTable>,
    /// The batch's light-tracing collisions, for the recursive split.
    pub(crate) pool: Option<&'a Pool>,
    /// Light neighbourhoods (centre \[m\], squared radius [m^2]) whose
    /// vertices the path counts for the `sparse` check; empty: none.
    pub(crate) reach: &'a [(DVec3, f64)],
    /// With a pool: some light's emission is peaked ([`peaked_lights`]),
    /// so every vertex makes light-guided connections, not only where
    /// [`guides`] says.
    pub(crate) peaked: bool,
    /// A near part's illuminance point draws its first direction in one of
    /// the strata of its cosine lobe ([`FirstBand`]); `None`: the cosine.
    pub(crate) first_band: Option<FirstBand>,
}

/// What one backward path did.
pub(crate) struct Walk {
    /// Surface vertices.
    pub(crate) vertices: u64,
    /// Vertices inside some light's neighbourhood ([`PathSetup::reach`]).
    pub(crate) reached: u64,
    /// With a pool: vertices whose split radius is the receiver's radius
    /// (not `d / 2`) and whose path region (within it) meets some light's
    /// neighbourhood, whose light the path must then fetch itself (see
    /// [`crate::tally::Diagnostics::near_reach`]).
    pub(crate) exposed: u64,
    /// Rays the path cast: its segments, shadow tests (next-event
    /// estimation counted as one per source, or one with the scene's light
    /// array), light-guided connections (a photon ray, a visibility test and
    /// next-event estimation at the photon's hit) and pool joins' visibility
    /// tests; the near part's cost measure ([`crate::estimator::near_paths`]).
    pub(crate) rays: u64,
}

impl Walk {
    /// A path that ended before its first vertex (its one connection and
    /// first ray counted by the caller, see [`trace`]).
    const NONE: Self = Self {
        vertices: 0,
        reached: 0,
        exposed: 0,
        rays: 0,
    };
}

/// Trace one path from receiver `rec`; `add(order, value)` receives each
/// contribution.
///
/// With `path.pool` (the batch's light-tracing collisions) the split recurses:
/// at each vertex `x` light from surfaces within [`split_radius`] comes by
/// the next segment (a longer one ends the path), and light from farther
/// surfaces by [`Pool::picks`] pool collisions scored into `x` (see
/// [`crate::estimator::Receivers::with_near_field`]).
///
/// # Light-guided connections (`cfg.chain.guide`)
///
/// Next-event estimation (NEE) at a vertex `y` next to a light scores
/// `I cos / d^2` with `d` small: a rare, huge value. So at each vertex `x`
/// (the receiver too) the light reaching `x` through one more vertex `y`,
/// `int T_x(y) N(y) dA(y)`, is estimated with two strategies combined by the
/// balance heuristic (Veach 1997, ch. 9):
///
/// - **A**: `y` is the path's next vertex, sampled from `x`'s BRDF (or the
///   receiver's response): area density `p_A(y) = pdf(w) cos_y / t^2`;
/// - **B**: a photon leaves a light (picked in proportion to power)
///   isotropically from its centre and `y` is its first hit, kept if `x`
///   sees its front side: `p_B(y) = sum_l P_l cos_l(y) / (4 pi d_l(y)^2) V_l(y)`.
///
/// `T_x(y)` is the path weight times `f_x cos_x cos_y / t^2` and `N(y)` is
/// NEE at `y` from every light; both strategies score
/// `T_x(y) N(y) / (p_A(y) + p_B(y))`. Near a light `N / p_B` is bounded
/// (for a point light `N / p_B <= f_y Phi / P_l`), so the spike is gone.
/// B is a defective density (a photon that escapes or lands out of sight
/// scores nothing), which leaves the sum unbiased because `p_A > 0`
/// wherever the integrand is. The path itself continues by BRDF sampling
/// alone, so its weights are those of plain path tracing. One connection
/// costs a photon ray, a visibility test and NEE at `y`; on a source 1 cm
/// above a plane (`rho = 0.9`) it raised the FOM of the backward estimator
/// about 500 times.
///
/// Tried and dropped: continuing a branch from B's `y` (to bring light that
/// has piled up around a distant source, the halo between two highly
/// reflecting planes, to the far field). Photon first hits are spread like
/// the direct illuminance, much tighter than the halo, so the branches'
/// weights were heavy-tailed: no gain at `r = 1e4` and half the speed.
pub(crate) fn trace<F: FnMut(u32, f64)>(
    scene: &Scene,
    rec: &Receiver,
    frame: &Frame,
    cfg: &RunConfig,
    rng: &mut Philox4x32,
    path: &PathSetup,
    mut add: F,
) -> Walk {
    let PathSetup {
        first_max,
        vertex_r,
        grazing,
        pool,
        reach,
        peaked,
        first_band,
    } = *path;
    // Under `--max-order K` no light of a higher order counts: the light a
    // seated source sends into its surface arrives orders above the vertex
    // that adds it ([`Seated`]).
    let max_order = cfg.chain.max_order;
    let mut add = |order: u32, v: f64| {
        if max_order.is_none_or(|k| order <= k) {
            add(order, v);
        }
    };
    let mut reached = 0;
    let mut exposed = 0;
    // Rays of next-event estimation at a vertex and of one connection.
    let nee_rays = if scene.vertex_light_array().is_some() {
        1
    } else {
        scene.lights.len() as u64
    };
    let connect_rays = 2 + nee_rays;
    let mut rays = 0;
    // Light that a point-like source on a surface sends into it, reflected
    // at the source's position ([`seat_intensity`]), reaches the receiver
    // at once: order 1 (2, 3, ... for what bounces on between the faces of
    // a room's edge or corner), where the source lies within the first segment's
    // reach (a near part's radius never holds a source: the chains score
    // that light, and its paths skip the loop).
    let seated = (0..scene.lights.len())
        .filter(|_| pool.is_none())
        .filter_map(|k| scene.light_surface(k).map(|seat| (k, seat)));
    for (k, seat) in seated {
        let y = scene.lights[k].position();
        let v = rec.p - y;
        let d2 = v.length_squared();
        if !(d2 > 0.0 && d2.sqrt() < first_max) || seat.hides(y, rec.p) {
            continue;
        }
        let w = v / d2.sqrt();
        let (value, _) = rec.transfer(frame, -w);
        if value > 0.0 && scene.visible(y, None, rec.p) {
            // Reflected `b` times at the source: order `b`.
            seat_intensity(scene, k, seat, w, rng, |b, i| {
                if i > 0.0 {
                    add(b, value * i / d2);
                }
            });
        }
        rays += 1;
    }
    // Light-guided connections start photons at a light's centre; area
    // sources and luminous openings have no such centre: picked, they give
    // no photon ([`connect`]), as lights at infinity do, and the density
    // of the photons leaves them out ([`VertexLight::guide_density`]), so
    // the combination stays unbiased and the other lights stay guided.
    let guide = cfg.chain.guide && !scene.lights.is_empty() && scene.total_power() > 0.0;
    // A near part's connections only where the vertex's region reaches
    // nearer a light than its own radius ([`guides`]).
    let mut guided =
        guide && (pool.is_none() || peaked || guides(first_max, nearest_light(scene, rec.p)));
    if guided {
        // The receiver's transfer towards world direction `w`: its response
        // times `cos` (the integrand of `E = int L cos dw`, or of the
        // luminance), and the density of its own first direction there.
        let v = connect(
            scene,
            rec.p,
            None,
            first_max,
            pool.is_none(),
            rng,
            |w: DVec3| {
                let (value, pdf) = rec.transfer(frame, w);
                match (grazing, first_band) {
                    (Some(t), _) if matches!(rec.response, Response::Illuminance) => {
                        (value, t.pdf(frame.to_local(w)))
                    }
                    (None, Some(b)) if matches!(rec.response, Response::Illuminance) => {
                        (value, b.pdf(frame.to_local(w)))
                    }
                    _ => (value, pdf),
                }
            },
        );
        if v.0 > 0.0 {
            add(1, v.0);
        }
        for (b, x) in v.1 {
            add(1 + b, x);
        }
        rays += connect_rays;
    }
    // First direction, from the receiver's response.
    let (d_local, mut beta, mut pdf) = match rec.response {
        Response::Illuminance => match grazing {
            // A point in a slot: weight cos / pdf.
            Some(table) => {
                let [u0, u1] = rng.next_2d();
                let s = table.sample([u0, u1, rng.next_f64()]);
                if s.pdf <= 0.0 {
                    return Walk::NONE;
                }
                (s.w, s.w.z / s.pdf, s.pdf)
            }
            None => match first_band {
                // A stratum of the cosine lobe: weight cos / pdf.
                Some(b) => b.sample(rng.next_2d()),
                None => {
                    let s = sample_cosine_hemisphere(rng.next_2d());
                    (s.w, PI, s.pdf)
                }
            },
        },
        Response::Luminance { material, wo } => {
            let s = material.sample(wo, rng.next_2d());
            if s.pdf <= 0.0 || s.w.z <= 0.0 {
                return Walk::NONE;
            }
            (s.w, material.eval(s.w, wo) * s.w.z / s.pdf, s.pdf)
        }
        // A solid receiver: its own lobe over the whole sphere, weight r / pdf.
        Response::Solid(kind) => {
            let s = kind.sample(rng.next_2d());
            (
                s.w,
                kind.response(rec.n, frame.to_world(s.w)) / s.pdf,
                s.pdf,
            )
        }
    };
    let beta0 = beta;
    let rr = cfg.chain.rr_weight * beta0;
    let mut d = frame.to_world(d_local);
    let mut hit = scene.first_hit_within(rec.p, d, first_max);
    rays += 1;
    let mut order = 0u32;
    let mut vertices = 0;
    while let Some(h) = hit {
        if d.dot(h.n) >= 0.0 || beta <= 0.0 {
            break; // back side: black
        }
        order += 1;
        vertices += 1;
        if reach.iter().any(|&(c, r2)| (h.p - c).length_squared() < r2) {
            reached += 1;
        }
        let m = &scene.surfaces[h.surface as usize].material;
        let f_frame = Frame::from_normal(h.n);
        let wo = f_frame.to_local(-d);
        // Strategy B's density at `h` where the previous vertex connected.
        let (nee, seat, p_b) = next_event(scene, &h, m, &f_frame, wo, guided, pool.is_none(), rng);
        rays += nee_rays;
        if nee > 0.0 || !seat.is_empty() {
            // Strategy A's share of the balance heuristic (1 without guiding).
            // p_A / (p_A + p_B) with p_A = pdf cos / t^2, written without the
            // division by t^2 (no overflow for tiny t).
            let pc = pdf * (-d.dot(h.n));
            let w_a = if p_b > 0.0 {
                pc / (pc + p_b * h.t * h.t)
            } else {
                1.0
            };
            if nee > 0.0 {
                add(order, beta * nee * w_a);
            }
            // Reflected `b` more times at a source on a surface.
            for (b, v) in seat {
                add(order + b, beta * v * w_a);
            }
        }
        // With a pool, the split radius at this vertex: light from closer
        // surfaces comes by the path, from farther ones by the pool.
        let seg_max = match pool {
            Some(pool) => {
                let (radius, d) = split_radius(scene, h.p, vertex_r);
                guided = guide && (peaked || guides(radius, d));
                let at = Vertex {
                    h: &h,
                    m,
                    frame: &f_frame,
                    wo,
                    beta,
                    k: order,
                    picks: Pool::picks(beta, beta0),
                };
                // (Lit from infinity alone, the radius is infinite and the
                // path carries all: no collision lies beyond it.)
                if radius.is_finite() {
                    rays += join_pool(scene, pool, &at, radius, cfg.chain.max_order, rng, &mut add);
                }
                // Exposed: the receiver's radius, not `d / 2`, sets the split
                // here and a light's core lies within it.
                if radius == vertex_r
                    && reach
                        .iter()
                        .any(|&(c, r2)| (h.p - c).length() < radius + r2.sqrt())
                {
                    exposed += 1;
                }
                radius
            }
            None => f64::INFINITY,
        };
        if cfg.chain.max_order.is_some_and(|k| order >= k) {
            break;
        }
        let from = Some((h.surface, h.prim));
        if guided {
            let b = beta;
            let v = connect(
                scene,
                h.p,
                from,
                seg_max,
                pool.is_none(),
                rng,
                |w: DVec3| {
                    let wl = f_frame.to_local(w);
                    if wl.z <= 0.0 {
                        (0.0, 0.0)
                    } else {
                        (b * m.eval(wl, wo) * wl.z, m.pdf(wo, wl))
                    }
                },
            );
            if v.0 > 0.0 {
                add(order + 1, v.0);
            }
            for (b, x) in v.1 {
                add(order + 1 + b, x);
            }
            rays += connect_rays;
        }
        let s = m.sample(wo, rng.next_2d());
        if s.pdf <= 0.0 || s.w.z <= 0.0 {
            break;
        }
        beta *= m.eval(s.w, wo) * s.w.z / s.pdf;
        pdf = s.pdf;
        let Some(survivor) = roulette(beta, rr, rng) else {
            break;
        };
        beta = survivor;
        d = f_frame.to_world(s.w);
        hit = scene.intersect_within(&Ray { o: h.p, d }, from, seg_max);
        rays += 1;
    }
    Walk {
        vertices,
        reached,
        exposed,
        rays,
    }
}

/// Split radius \[m\] at a path vertex `x` of the near part:
/// `max(r, d / 2)` with `r` the receiver's radius and `d` the distance from
/// `x` to the nearest light. Light from surfaces within it comes by the
/// path, from farther ones by the pool: every surface nearer the light than
/// `d / 2` lies beyond it, so the light piled up around the sources (which
/// the path would have to wander to) always comes from the pool, and the
/// path carries what lies around itself. Measured in the far field of two
/// planes (`rho1 rho2 = 0.999`, `r = 1e4`, `--near-radius auto`, 5 s):
/// `d / 2` gives `E` within 0.4 % (z = 0.4); `d / 10` within 2 %; `d`
/// leaves half of that halo to the path and reads 23 % low, `2 d` 44 %
/// (4 pool picks a vertex then; now up to 16, [`Pool::picks`]).
/// Returns the radius and `d` \[m\].
fn split_radius(scene: &Scene, x: DVec3, r: f64) -> (f64, f64) {
    // (Lights at infinity pile up nowhere: without others, the path
    // carries all.)
    let d = nearest_light(scene, x);
    (r.max(0.5 * d), d)
}

/// Distance \[m\] from `x` to the nearest light's position (lights at
/// infinity left out; infinite without others).
fn nearest_light(scene: &Scene, x: DVec3) -> f64 {
    scene
        .lights
        .iter()
        .filter(|l| !l.is_directional())
        .map(|l| (l.position() - x).length())
        .fold(f64::INFINITY, f64::min)
}

/// Whether a near part's vertex whose next segment reaches at most
/// `radius` \[m\] makes light-guided connections: where that reach
/// exceeds half the distance `d` \[m\] to the nearest light (and everywhere when a
/// light's emission is peaked, [`PathSetup::peaked`]). The connections are
/// there for next-event estimates at vertices next to a light; a vertex
/// within `radius <= d / 2` of `x` lies at least `d / 2` from every
/// light, where next-event estimation from a light of broad emission
/// varies by a factor of 4 with the distance over the region, and the
/// connection (a photon ray, a visibility test and next-event estimation
/// at its hit) only costs. The split radius
/// ([`split_radius`]) is `d / 2` at most vertices, so they skip it. Which
/// strategies a vertex uses depends on the vertex alone (the next
/// vertex's next-event estimate is weighted by the balance heuristic only
/// where this one connected), so the estimate stays unbiased. Measured on
/// the office's 506 grid points (50,000 chains, seed 3, one thread, least
/// of 3 interleaved runs): 4.55 against 5.72 s of user time with every
/// vertex connecting; RMS relative error at 100,000 chains, seeds 1-3,
/// 3.9e-3-4.0e-3 against 3.8e-3-4.3e-3.
fn guides(radius: f64, d: f64) -> bool {
    radius > 0.5 * d
}

/// Largest [`Light::peakedness`] of the lights for which a near part's
/// vertices connect only where [`guides`] says: above it, next-event
/// estimation varies over a region by the beam's footprint as well as by
/// the distance (under a narrow spot, from 0 to `I / h^2`), and a path
/// seldom finds the footprint by itself. A reviewer measured, next to a
/// wall under spots (seeds 1-10, 100,000 chains), efficiency 65-1300
/// times lower under a 1-2 degree spot, 3-12 times under a 5 degree one,
/// the same under a 15 degree one (peakedness about 80), and 20 % better
/// under an isotropic light, without the connections.
pub(crate) const PEAKED: f64 = 16.0;

/// Whether some light that sends photons has a peaked emission (above
/// [`PEAKED`]): a near part's vertices then all connect.
pub(crate) fn peaked_lights(scene: &Scene) -> bool {
    scene
        .lights
        .iter()
        .any(|l| l.peakedness().is_some_and(|k| k > PEAKED))
}

/// A path vertex: the hit, its material and normal frame, the direction to
/// the previous vertex (local), the path weight, its order `k` and the
/// pool collisions it joins ([`Pool::picks`]).
struct Vertex<'a> {
    h: &'a Hit,
    m: &'a Material,
    frame: &'a Frame,
    wo: DVec3,
    beta: f64,
    k: u32,
    picks: u32,
}

/// The far part at path vertex `v`: light-tracing collisions `y` at
/// `|y - x| >= radius` score into it as into a receiver,
/// `beta Q_y f_y cos_y cos_x / d^2 f_x`, through `v.picks` collisions
/// drawn uniformly from the pool, each weighted by `seen / (picks chains)`;
/// light reflected `o_y + k` times (dropped beyond `max_order`, if set).
/// Returns the visibility tests it made.
fn join_pool<F: FnMut(u32, f64)>(
    scene: &Scene,
    pool: &Pool,
    v: &Vertex,
    radius: f64,
    max_order: Option<u32>,
    rng: &mut Philox4x32,
    add: &mut F,
) -> u64 {
    let Vertex {
        h,
        m,
        frame: f_frame,
        wo,
        beta,
        k,
        picks,
    } = *v;
    let n = pool.items.len();
    if n == 0 || beta <= 0.0 {
        return 0;
    }
    let mut tests = 0;
    let scale = pool.seen as f64 / (f64::from(picks) * pool.chains as f64);
    let from = Some((h.surface, h.prim));
    // Every pick is drawn first (the same draws in the same order: the loop
    // below draws nothing) and the picked collisions are read together, so
    // that their cache misses in a pool of megabytes overlap instead of
    // coming one per pick after a shadow test each.
    let mut picked = [0usize; Pool::PICKS as usize];
    let picked = &mut picked[..(picks.min(Pool::PICKS) as usize)];
    let mut touch = 0.0;
    for i in picked.iter_mut() {
        *i = ((rng.next_f64() * n as f64) as usize).min(n - 1);
        let y = &pool.items[*i];
        touch += y.p.x + y.q;
    }
    std::hint::black_box(touch);
    for &i in picked.iter() {
        let y = &pool.items[i];
        if max_order.is_some_and(|m| y.order + k > m) {
            continue;
        }
        let v = h.p - y.p;
        let d2 = v.length_squared();
        if d2 < radius * radius {
            continue;
        }
        let g = local_kernel(y.p, y.n, h.p, h.n);
        if g <= 0.0 {
            continue;
        }
        tests += 1;
        // A collision at a light's seat hides from points behind the seat,
        // and is seen from just off it (`Scene::light_shadow_origin`).
        let seen = match y.seat {
            Some(l) => {
                let l = l as usize;
                !scene.behind_light_surface(l, h.p)
                    && scene.visible(h.p, from, scene.light_shadow_origin(l))
            }
            None => scene.visible(h.p, from, y.p),
        };
        if !seen {
            continue;
        }
        let w = v / d2.sqrt(); // from y towards x
        let fy_frame = Frame::from_normal(y.n);
        let my = &scene.surfaces[y.surface as usize].material;
        let f_y = my.eval(fy_frame.to_local(y.wi), fy_frame.to_local(w));
        let f_x = m.eval(f_frame.to_local(-w), wo);
        let value = beta * scale * y.q * f_y * g * f_x;
        if value > 0.0 {
            add(y.order + k, value);
        }
    }
    tests
}

/// Next-event estimation at the surface vertex `h` (material `m`, frame
/// `f_frame` of its front normal, unit direction `wo` towards the previous
/// vertex in that frame): `N = sum_l f(wi_l, wo) E_l V_l` (per unit path
/// weight), exact for a point light, one direction drawn uniformly in the
/// cone of a sphere light. With `deposit`, apart from `N`, the light that
/// sources standing on a surface sent into it ([`Seated`], orders above
/// `N`'s). With `guide`, also the density `p_B(h)` [1/m^2] of the
/// light-guided strategy at `h` (see [`trace`]; 0 without). Returns
/// `(N, seated, p_B)`.
///
/// With the scene's light array ([`Scene::vertex_light_array`], many sources) the
/// sum is replaced by one source kept by RIS and weighted by its unbiased
/// contribution weight ([`crate::light::array`]): one shadow test instead
/// of one per source. Strategy B's density `p_B` is still summed over all
/// sources (one centre-visibility test each: side masks in a scene of
/// planes); it is only needed with light-guided connections.
#[allow(clippy::too_many_arguments)]
fn next_event(
    scene: &Scene,
    h: &Hit,
    m: &Material,
    f_frame: &Frame,
    wo: DVec3,
    guide: bool,
    deposit: bool,
    rng: &mut Philox4x32,
) -> (f64, Seated, f64) {
    let v = VertexLight {
        scene,
        h,
        m,
        f_frame,
        wo,
        deposit,
        hm: scene.side_mask(h.p),
        from: Some((h.surface, h.prim)),
        seen: std::cell::Cell::new(None),
        seat: std::cell::RefCell::new(Vec::new()),
    };
    let (mut nee, mut p_b) = (0.0, 0.0);
    match scene.vertex_light_array() {
        None => {
            for k in 0..scene.lights.len() {
                nee += v.nee(k, rng);
                if guide {
                    p_b += v.guide_density(k);
                }
            }
        }
        Some(array) => {
            // One source kept by RIS (target: its unoccluded illuminance
            // at the vertex), `N = W N_k` (see `crate::light::array`).
            // Strategy B's density stays the exact sum over the sources.
            if let Some(pick) = array.pick(&scene.lights, h.p, Some(h.n), None, rng) {
                nee = pick.w * v.nee(pick.k as usize, rng);
                for x in v.seat.borrow_mut().iter_mut() {
                    x.1 *= pick.w;
                }
            }
            if guide {
                for k in 0..scene.lights.len() {
                    p_b += v.guide_density(k);
                }
            }
        }
    }
    (nee, v.seat.into_inner(), p_b)
}

/// Light that point-like sources on a surface sent into it, reflected there
/// `b` times (1, 2, ...: more on a room's edge or corner) before it reaches
/// a vertex ([`seat_intensity`]), as `(b, value)` pairs in the units of the
/// next-event estimate: `b` orders above it. Empty without such sources.
type Seated = Vec<(u32, f64)>;

/// Estimates of the intensity \[cd\] towards unit `w` of the light that
/// point-like light `k`, standing on the surfaces of `seat`, sends into
/// them: it meets them at the light's own position
/// ([`crate::scene::world::LightSeat`]) and is reflected there, a point
/// source of `I_r(w) = int I(w_i) f(w_i, w) cos(w) dw_i` over the
/// directions that meet a face (on a room's edge, reflected light can meet
/// the next face at once: those bounces are walked too, with Russian
/// roulette). One emission direction drawn from the light's photon
/// density, so the estimate is unbiased. Nothing where `w` meets the seat.
/// The chains find this light as collisions at the light's position; a
/// backward path cannot hit that point, so next-event estimation adds it.
/// `out(b, I_b)` takes the share reflected `b` times at the seat (1, and 2,
/// 3, ... on a room's edge or corner): `b` reflection orders of its own.
fn seat_intensity(
    scene: &Scene,
    k: usize,
    seat: &crate::scene::world::LightSeat,
    w: DVec3,
    rng: &mut Philox4x32,
    mut out: impl FnMut(u32, f64),
) {
    const MAX_BOUNCES: u32 = 64;
    let l = &scene.lights[k];
    if seat.meets(w).is_some() {
        return;
    }
    let d = l.photon(rng.next_2d(), rng.next_f64());
    let pdf = l.photon_pdf(d);
    if pdf <= 0.0 {
        return;
    }
    let mut weight = l.intensity(d) / pdf;
    let threshold = 0.25 * weight;
    let mut d = d;
    for b in 1..=MAX_BOUNCES {
        let Some((s, n)) = seat.meets(d) else {
            break;
        };
        let m = &scene.surfaces[s as usize].material;
        let frame = Frame::from_normal(n);
        let wi = frame.to_local(-d);
        let wo = frame.to_local(w);
        if wo.z > 0.0 {
            out(b, weight * m.eval(wi, wo) * wo.z);
        }
        let smp = m.sample(wi, rng.next_2d());
        if smp.pdf <= 0.0 || smp.w.z <= 0.0 {
            break;
        }
        weight *= m.eval(wi, smp.w) * smp.w.z / smp.pdf;
        let Some(survivor) = roulette(weight, threshold, rng) else {
            break;
        };
        weight = survivor;
        d = frame.to_world(smp.w);
    }
}

/// A surface vertex lit by next-event estimation (see [`next_event`]).
struct VertexLight<'a> {
    scene: &'a Scene,
    h: &'a Hit,
    m: &'a Material,
    f_frame: &'a Frame,
    wo: DVec3,
    /// Whether a light on a surface adds what it sends into the surface,
    /// reflected at its position ([`seat_intensity`]): not where the
    /// chains' pool brings that light (a near part's paths).
    deposit: bool,
    /// The vertex's side mask.
    hm: crate::geometry::SideMask,
    from: Option<(u32, u32)>,
    /// The last light whose centre was tested, and the answer.
    seen: std::cell::Cell<Option<(usize, bool)>>,
    /// What [`Self::nee`] found of the light sources on a surface sent
    /// into it ([`Seated`]), apart from its return value.
    seat: std::cell::RefCell<Seated>,
}

impl VertexLight<'_> {
    /// Whether light `k`'s centre sees the vertex: the photons of strategy
    /// B leave from there, and a point source is lit through it.
    /// (Kept for the last light asked: next-event estimation and strategy
    /// B's density ask for the same light in turn.)
    fn center_seen(&self, k: usize) -> bool {
        if let Some((last, seen)) = self.seen.get()
            && last == k
        {
            return seen;
        }
        let (scene, l) = (self.scene, &self.scene.lights[k]);
        let seen = scene.side_mask(l.position()).sees(self.hm)
            && !scene.behind_light_surface(k, self.h.p)
            && (scene.planes_only()
                || !scene.blocked_by_shapes(self.h.p, self.from, l.position(), 0));
        self.seen.set(Some((k, seen)));
        seen
    }

    /// Strategy B's density [1/m^2] at the vertex due to light `k` (see
    /// [`trace`]): 0 for sources it draws no photons from.
    fn guide_density(&self, k: usize) -> f64 {
        let (scene, h, l) = (self.scene, self.h, &self.scene.lights[k]);
        if l.emits_from_opening() || matches!(l, Light::Area(_)) || l.is_directional() {
            return 0.0;
        }
        let to_c = l.position() - h.p;
        let dist2 = to_c.length_squared();
        let dist = dist2.sqrt();
        let cos_l = h.n.dot(to_c) / dist;
        if cos_l.is_nan() || cos_l <= 0.0 {
            return 0.0;
        }
        let total = scene.total_power();
        let density = match l {
            // The photon's direction density towards `h`, per solid angle.
            Light::Gonio { .. } | Light::Spot(_) => {
                l.power() / total * l.photon_pdf(-to_c / dist) * cos_l / dist2
            }
            _ => l.power() / total * cos_l / (4.0 * PI * dist2),
        };
        // (The shadow test only where it matters: a zero density is zero
        // either way.)
        if density == 0.0 || !self.center_seen(k) {
            return 0.0;
        }
        density
    }

    /// Next-event estimate from light `k` alone (per unit path weight).
    fn nee(&self, k: usize, rng: &mut Philox4x32) -> f64 {
        let VertexLight {
            scene,
            h,
            m,
            f_frame,
            wo,
            from,
            deposit,
            ..
        } = *self;
        let l = &scene.lights[k];
        if let Light::Gonio {
            frame,
            dist,
            opening: Some(_),
            ..
        } = l
        {
            // One point of the luminous shape ([`Light::shape_point`]):
            // the estimate is I(w) emit / pdf cos_x / t^2.
            let Some(sp) = l.shape_point(h.p, rng.next_2d()) else {
                return 0.0;
            };
            let v = sp.y - h.p;
            let t2 = v.length_squared();
            if t2 <= 0.0 || sp.emit <= 0.0 {
                return 0.0;
            }
            let wi = v / t2.sqrt();
            let cos_x = h.n.dot(wi);
            if cos_x > 0.0 && scene.visible(h.p, from, sp.y) {
                let i = dist.intensity_world(frame, -wi) * (sp.emit / sp.pdf);
                return m.eval(f_frame.to_local(wi), wo) * i * cos_x / t2;
            }
            return 0.0;
        }
        if let Light::Area(a) = l {
            // One point drawn on the emitter (area sampling).
            let pt = a.sample_point(rng.next_2d());
            let v = pt.y - h.p;
            let t2 = v.length_squared();
            if t2 <= 0.0 || pt.pdf_a <= 0.0 {
                return 0.0;
            }
            let wi = v / t2.sqrt();
            let (cos_x, cos_y) = (h.n.dot(wi), a.normal().dot(wi).abs());
            let le = a.emitted(pt.y, -wi);
            if cos_x > 0.0 && le > 0.0 && scene.visible(h.p, from, pt.y) {
                return m.eval(f_frame.to_local(wi), wo) * le * cos_x * cos_y / (t2 * pt.pdf_a);
            }
            return 0.0;
        }
        if let Light::Environment(env) = l {
            // Next-event estimation from the map (see the sun's below).
            let (wi, pdf, le) = env.sample(rng.next_2d());
            let cos_n = wi.dot(h.n);
            if cos_n > 0.0
                && pdf > 0.0
                && scene
                    .intersect(&crate::geometry::Ray { o: h.p, d: wi }, from)
                    .is_none()
            {
                return m.eval(f_frame.to_local(wi), wo) * le * cos_n / pdf;
            }
            return 0.0;
        }
        if let Light::Distant(dl) = l {
            // Next-event estimation from the sun, alone: a path ray that
            // leaves the scene adds nothing (the sun's light comes by this
            // estimate only), and strategy B draws no photons from it.
            let u = rng.next_2d();
            let (wi, scale) = if dl.collimated() {
                (-dl.d, dl.e_n)
            } else {
                let s = crate::sampling::cone::sample_uniform_cone(u, dl.sin_a, dl.cos_a);
                (
                    Frame::from_normal(-dl.d).to_world(s.w),
                    dl.luminance() / s.pdf,
                )
            };
            let cos_n = wi.dot(h.n);
            if cos_n > 0.0
                && scene
                    .intersect(&crate::geometry::Ray { o: h.p, d: wi }, from)
                    .is_none()
            {
                return m.eval(f_frame.to_local(wi), wo) * scale * cos_n;
            }
            return 0.0;
        }
        let to_c = l.position() - h.p;
        let dist = to_c.length();
        match *l {
            Light::Point { .. } | Light::Gonio { .. } | Light::Spot(_) => {
                // (The shadow test only for light that arrives: a source
                // that sends nothing this way, the back of the vertex.)
                let e = l.direct_illuminance(h.p, h.n);
                // A light on a surface: and what it sends into the surface,
                // reflected there ([`seat_intensity`]), orders of its own.
                let mut seated = Seated::new();
                if deposit && let Some(seat) = scene.light_surface(k) {
                    let cos_x = h.n.dot(to_c) / dist;
                    if cos_x > 0.0 && dist > 0.0 {
                        seat_intensity(scene, k, seat, -to_c / dist, rng, |b, i| {
                            if i > 0.0 {
                                seated.push((b, i * cos_x / (dist * dist)));
                            }
                        });
                    }
                }
                if (e > 0.0 || !seated.is_empty()) && self.center_seen(k) {
                    let f = m.eval(f_frame.to_local(to_c / dist), wo);
                    self.seat
                        .borrow_mut()
                        .extend(seated.into_iter().map(|(b, x)| (b, f * x)));
                    return f * e;
                }
                0.0
            }
            Light::Sphere { r, .. } => {
                if dist <= r {
                    return 0.0;
                }
                let cos_a = (1.0 - (r / dist).powi(2)).max(0.0).sqrt();
                let u = rng.next_2d();
                let ct = 1.0 - u[0] * (1.0 - cos_a);
                let st = (1.0 - ct * ct).max(0.0).sqrt();
                let (sp, cp) = crate::sampling::warp::sin_cos_turns(u[1]);
                let wi = Frame::from_normal(to_c / dist).to_world(DVec3::new(st * cp, st * sp, ct));
                let cos_n = wi.dot(h.n);
                // In a scene of planes the sphere lies on one side of each,
                // so its centre decides; elsewhere the sampled direction's
                // own segment to the sphere (partial occlusion).
                let seen = if scene.planes_only() {
                    self.center_seen(k)
                } else {
                    l.hit(h.p, wi, f64::INFINITY)
                        .is_some_and(|t| scene.visible(h.p, from, h.p + wi * t))
                };
                if cos_n > 0.0 && seen {
                    let solid_angle = 2.0 * PI * (1.0 - cos_a);
                    return m.eval(f_frame.to_local(wi), wo) * l.luminance() * cos_n * solid_angle;
                }
                0.0
            }
            Light::Area(_) | Light::Distant(_) | Light::Environment(_) => {
                unreachable!("handled above")
            }
        }
    }
}

/// Strategy B of the light-guided connection from vertex `x` (on surface and
/// primitive `from`, if any): a photon from a light picked by power, leaving
/// its centre isotropically (a goniometric light: by its emission sampler), lands at its first hit `y`; if `x` sees `y`'s
/// front side within `max_t` \[m\], the score `T N(y) / (p_A + p_B)` (see
/// [`trace`]). `transfer(w)` gives `x`'s transfer towards unit world
/// direction `w` (path weight times BRDF or response, times `cos_x`) and the
/// solid-angle density of its own sampling there.
/// Returns the score and, apart, the seated shares of `y`'s next-event
/// estimate ([`Seated`], one order above the score's and more).
fn connect(
    scene: &Scene,
    x: DVec3,
    from: Option<(u32, u32)>,
    max_t: f64,
    deposit: bool,
    rng: &mut Philox4x32,
    transfer: impl Fn(DVec3) -> (f64, f64),
) -> (f64, Seated) {
    let k = scene.pick_light_index(rng.next_f64());
    let light = &scene.lights[k];
    // A light at infinity, an area source or a luminous opening has no
    // centre to send photons from: picked, it gives no sample (its share
    // is left out of `p_B` too, see [`next_event`], so the combination
    // stays unbiased; its light comes by next-event estimation).
    if light.is_directional() || matches!(light, Light::Area(_)) || light.emits_from_opening() {
        return (0.0, Seated::new());
    }
    // Isotropic from points and spheres; a goniometric light's photons
    // follow its emission (so that p_B stays positive where it emits).
    let dir = match light {
        Light::Gonio { .. } | Light::Spot(_) => light.photon(rng.next_2d(), rng.next_f64()),
        _ => sample_uniform_sphere(rng.next_2d()).w,
    };
    let ray = Ray {
        o: light.position(),
        d: dir,
    };
    // A light on a surface: photons into it meet it at the light (no
    // vertex of a path lies there), the others leave it.
    let leave = match scene.light_surface(k) {
        Some(seat) if seat.meets(dir).is_some() => return (0.0, Seated::new()),
        Some(seat) => Some(seat.leaves(dir)),
        None => None,
    };
    let Some(y) = scene.intersect(&ray, leave) else {
        return (0.0, Seated::new());
    };
    if dir.dot(y.n) >= 0.0 {
        return (0.0, Seated::new()); // the photon met a black back side
    }
    let v = y.p - x;
    let t2 = v.length_squared();
    let t = t2.sqrt();
    if !(t > 0.0 && t < max_t) {
        return (0.0, Seated::new());
    }
    let w = v / t;
    let cos_y = -w.dot(y.n);
    if cos_y <= 0.0 {
        return (0.0, Seated::new());
    }
    let (tr, pdf_a) = transfer(w);
    if tr <= 0.0 || !scene.visible(x, from, y.p) {
        return (0.0, Seated::new());
    }
    let f_frame = Frame::from_normal(y.n);
    let m = &scene.surfaces[y.surface as usize].material;
    let (nee, mut seat, p_b) = next_event(
        scene,
        &y,
        m,
        &f_frame,
        f_frame.to_local(-w),
        true,
        deposit,
        rng,
    );
    if (nee <= 0.0 && seat.is_empty()) || p_b <= 0.0 {
        return (0.0, Seated::new());
    }
    // T (cos_y / t^2) N / (pdf_a cos_y / t^2 + p_B), multiplied through by t^2.
    let denom = pdf_a * cos_y + p_b * t2;
    for x in &mut seat {
        x.1 = tr * cos_y * x.1 / denom;
    }
    (tr * cos_y * nee / denom, seat)
}

#[cfg(test)]
mod tests {
    use super::Pool;

    /// Full weight joins every pick, a lighter vertex fewer in proportion
    /// (rounded up), never none, never more, and a NaN weight one.
    #[test]
    fn pool_picks_follow_the_path_weight() {
        let b0 = std::f64::consts::PI;
        assert_eq!(Pool::picks(b0, b0), Pool::PICKS);
        assert_eq!(Pool::picks(2.0 * b0, b0), Pool::PICKS);
        assert_eq!(Pool::picks(0.5 * b0, b0), Pool::PICKS / 2);
        assert_eq!(Pool::picks(0.3 * b0, b0), 5); // ceil(4.8)
        assert_eq!(Pool::picks(1e-9 * b0, b0), 1);
        assert_eq!(Pool::picks(0.0, b0), 1);
        assert_eq!(Pool::picks(0.0, 0.0), 1);
        assert_eq!(Pool::picks(f64::INFINITY, b0), Pool::PICKS);
    }
}
