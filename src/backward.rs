//! Backward (observer-side) path tracing with next-event estimation: an
//! estimator independent of the light-tracing chains and the local
//! estimates, for cross-checks and honest comparisons.
//!
//! For each receiver a batch traces `bs` paths. A path leaves the receiver
//! in a direction sampled from its response: cosine-weighted about the normal
//! for illuminance (`E = pi E[L_i]`), the sub-point's BRDF for luminance
//! (weight `f' cos / pdf`). At each surface vertex `k = 1, 2, ...` it adds
//! next-event estimation from every point light, `beta f_k(wi_l, wo) I cos / d^2 V`,
//! which is light reflected `k` times before it reaches the receiver (the
//! same order buckets as the local estimate), then continues by sampling the
//! BRDF, with Russian roulette on the throughput. The first order is the
//! exact one shared with the local estimator ([`Receivers::direct`]).
//!
//! Path `s` of batch `b` at receiver `j` draws from the Philox stream
//! `(seed ^ BACKWARD_KEY, (b bs + s) n + j)`, so results do not depend on the
//! thread count.

use crate::estimator::{Receiver, Receivers, Response};
use crate::geometry::Ray;
use crate::light::Light;
use crate::run::{Batch, BatchWork, Progress, RunConfig, RunResult, drive};
use crate::sampling::Philox4x32;
use crate::sampling::warp::{Frame, sample_cosine_hemisphere};
use crate::scene::Scene;

/// Key offset separating backward streams from the chains' streams.
const BACKWARD_KEY: u64 = 0x6261_636b_7761_7264; // "backward"

struct BackwardWork<'a> {
    scene: &'a Scene,
    receivers: &'a Receivers,
}

/// Run the backward estimator on `receivers` (same statistics, stopping
/// rules and output as [`crate::run::run`]; "chains" count paths).
pub fn run(
    scene: &Scene,
    receivers: &Receivers,
    cfg: &RunConfig,
    observe: &mut dyn FnMut(&Progress) -> bool,
) -> RunResult {
    drive(&BackwardWork { scene, receivers }, cfg, observe)
}

impl BatchWork for BackwardWork<'_> {
    fn scene(&self) -> &Scene {
        self.scene
    }
    fn receivers(&self) -> &Receivers {
        self.receivers
    }

    fn scratch_len(&self, _buckets: usize) -> usize {
        0
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
                vertices += trace(
                    self.scene,
                    rec,
                    &self.receivers.frames()[j],
                    &cfg,
                    &mut rng,
                    f64::INFINITY,
                    |_, _| {},
                );
            }
        }
        let per_path = 1 + vertices / (PILOT * n) * (1 + self.scene.lights.len() as u64);
        let mut bs = ((1u64 << 18) / (n * per_path)).clamp(1, 1 << 14);
        if let Some(c) = chains {
            bs = bs.min(c.div_ceil(crate::run::MIN_BATCHES)).max(1);
        }
        bs
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
        let mut vertices = 0u64;
        let k_max = cfg.orders;
        for (j, rec) in self.receivers.receivers().iter().enumerate() {
            for s in 0..bs {
                let stream = (b * bs + s) * n as u64 + j as u64;
                let mut rng = Philox4x32::new(cfg.seed ^ BACKWARD_KEY, stream);
                vertices += trace(
                    self.scene,
                    rec,
                    &self.receivers.frames()[j],
                    cfg,
                    &mut rng,
                    f64::INFINITY,
                    |order, v| {
                        let k = if k_max == 0 {
                            0
                        } else {
                            (order.min(k_max + 1) - 1) as usize
                        };
                        sums[k * n + j] += v;
                    },
                );
            }
        }
        Batch {
            index: b,
            chains: bs * n as u64,
            sums,
            collisions: vertices,
            scores: vertices,
        }
    }
}

/// Trace one path from receiver `rec`; `add(order, value)` receives each
/// next-event contribution. Returns the number of surface vertices.
///
/// `first_max` [m]: a path whose first surface lies at or beyond this
/// distance from the receiver contributes nothing (the near-field part of
/// the local estimator's near/far split); `f64::INFINITY` for a full path.
pub(crate) fn trace<F: FnMut(u32, f64)>(
    scene: &Scene,
    rec: &Receiver,
    frame: &Frame,
    cfg: &RunConfig,
    rng: &mut Philox4x32,
    first_max: f64,
    mut add: F,
) -> u64 {
    // First direction, from the receiver's response.
    let (d_local, mut beta) = match rec.response {
        Response::Illuminance => {
            let s = sample_cosine_hemisphere(rng.next_2d());
            (s.w, std::f64::consts::PI)
        }
        Response::Luminance { material, wo } => {
            let s = material.sample(wo, rng.next_2d());
            if s.pdf <= 0.0 || s.w.z <= 0.0 {
                return 0;
            }
            (s.w, material.eval(s.w, wo) * s.w.z / s.pdf)
        }
    };
    let beta0 = beta;
    let rr = cfg.chain.rr_weight * beta0;
    let mut d = frame.to_world(d_local);
    let mut hit = scene.first_hit_from(rec.p, d).filter(|h| h.t < first_max);
    let mut order = 0u32;
    let mut vertices = 0;
    while let Some(h) = hit {
        if d.dot(h.n) >= 0.0 || beta <= 0.0 {
            break; // back side: black
        }
        order += 1;
        vertices += 1;
        let m = &scene.surfaces[h.surface as usize].material;
        let f_frame = Frame::from_normal(h.n);
        let wo = f_frame.to_local(-d);
        // Next-event estimation from every light: exact for a point, one
        // direction drawn uniformly in the cone of a sphere.
        let hm = scene.side_mask(h.p);
        let from = Some((h.surface, h.prim));
        for l in &scene.lights {
            if !scene.side_mask(l.position()).sees(hm)
                || (!scene.planes_only() && scene.blocked_by_shapes(h.p, from, l.position(), 0))
            {
                continue;
            }
            match *l {
                Light::Point { p: lp, .. } => {
                    let e = l.direct_illuminance(h.p, h.n);
                    if e > 0.0 {
                        let wi = f_frame.to_local((lp - h.p).normalize());
                        add(order, beta * m.eval(wi, wo) * e);
                    }
                }
                Light::Sphere { c, r, .. } => {
                    let to_c = c - h.p;
                    let dist = to_c.length();
                    let cos_a = (1.0 - (r / dist).powi(2)).max(0.0).sqrt();
                    let u = rng.next_2d();
                    let ct = 1.0 - u[0] * (1.0 - cos_a);
                    let st = (1.0 - ct * ct).max(0.0).sqrt();
                    let (sp, cp) = crate::sampling::warp::sin_cos_turns(u[1]);
                    let wi = Frame::from_normal(to_c / dist).to_world(glam::DVec3::new(
                        st * cp,
                        st * sp,
                        ct,
                    ));
                    let cos_n = wi.dot(h.n);
                    if cos_n > 0.0 {
                        let solid_angle = 2.0 * std::f64::consts::PI * (1.0 - cos_a);
                        let wl = f_frame.to_local(wi);
                        add(
                            order,
                            beta * m.eval(wl, wo) * l.luminance() * cos_n * solid_angle,
                        );
                    }
                }
            }
        }
        if cfg.chain.max_order.is_some_and(|k| order >= k) {
            break;
        }
        let s = m.sample(wo, rng.next_2d());
        if s.pdf <= 0.0 || s.w.z <= 0.0 {
            break;
        }
        beta *= m.eval(s.w, wo) * s.w.z / s.pdf;
        if beta < rr {
            if rng.next_f64() >= beta / rr {
                break;
            }
            beta = rr;
        }
        d = f_frame.to_world(s.w);
        hit = scene.intersect(&Ray { o: h.p, d }, from);
    }
    vertices
}
