//! Flux bookkeeping of a closed scene: absorbed against emitted flux \[lm\].

use crate::chain::{ChainEnd, ChainParams, trace_ex};
use crate::sampling::Philox4x32;
use crate::scene::Scene;
use crate::tally::Welford;
use rayon::prelude::*;

/// Flux bookkeeping of a closed room, per face and in total \[lm\].
#[derive(Clone, Debug)]
pub struct FluxBalance {
    /// Flux absorbed by each surface \[lm\], mean and error over batches.
    pub absorbed: Vec<Welford>,
    /// Total absorbed \[lm\] per chain-batch mean.
    pub total: Welford,
    /// Chains that left the scene (a leak) or met a black back side.
    pub escaped: u64,
    /// Chains that met a black back side.
    pub back_side: u64,
    /// Emitted flux \[lm\].
    pub emitted: f64,
}

/// Trace `chains` chains in `batches` batches and account for every lumen:
/// at a collision of weight `Q` on a surface of albedo `a(wi)` the expected
/// absorbed flux is `Q (1 - a)`; a ray that leaves the scene or meets a
/// black back side takes its weight with it.
pub fn flux_balance(scene: &Scene, chains: u64, batches: u64, seed: u64) -> FluxBalance {
    let ns = scene.surfaces.len();
    let per = chains.div_ceil(batches);
    let params = ChainParams::default();
    let results: Vec<(Vec<f64>, u64, u64)> = (0..batches)
        .into_par_iter()
        .map(|b| {
            let mut abs = vec![0.0; ns];
            let (mut esc, mut back) = (0u64, 0u64);
            for c in 0..per {
                let mut rng = Philox4x32::new(seed, b * per + c);
                let u = [rng.next_2d(), rng.next_2d()];
                let (_, end) = trace_ex(scene, &mut rng, &params, u, |col| {
                    let m = &scene.surfaces[col.surface as usize].material;
                    let wi = crate::sampling::warp::Frame::from_normal(col.n).to_local(col.wi);
                    abs[col.surface as usize] += col.q * (1.0 - m.albedo(wi));
                });
                match end {
                    ChainEnd::Escaped => esc += 1,
                    ChainEnd::BackSide => back += 1,
                    _ => {}
                }
            }
            for v in &mut abs {
                *v /= per as f64;
            }
            (abs, esc, back)
        })
        .collect();
    let mut absorbed = vec![Welford::default(); ns];
    let mut total = Welford::default();
    let (mut escaped, mut back_side) = (0, 0);
    for (abs, e, bk) in results {
        for (w, v) in absorbed.iter_mut().zip(&abs) {
            w.push(*v);
        }
        total.push(abs.iter().sum());
        escaped += e;
        back_side += bk;
    }
    FluxBalance {
        absorbed,
        total,
        escaped,
        back_side,
        emitted: scene.total_power(),
    }
}
