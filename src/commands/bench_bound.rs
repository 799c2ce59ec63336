//! `lumest bench --bound`: how far the scoring kernel runs from this
//! machine's bound.
//!
//! Three single-thread measurements, each the best of five rounds:
//!
//! - the **kernel** as runs use it: collisions on the upper Sobolev plane
//!   scoring into `n` points of the lower plane ([`Receivers::score`], the
//!   open kernel), in scores/s, with the portable (SSE2) and the AVX2
//!   build of the kernel;
//! - the **compute bound**: the peak rate of separate multiplies and adds
//!   (the kernel uses no fused ones, for bit-reproducibility across
//!   machines) on L1-resident data, divided by the kernel's 28 operations a
//!   score (14 multiplies, 10 adds, 2 maxima, a compare and a select; no
//!   square root); and the kernel itself on 256 points, whose arrays (20 KB)
//!   stay in L1, to show what its division and dependencies cost;
//! - the **memory bound**: streaming the nine arrays a score touches (three
//!   coordinates, three normal components, weight, near radius, the
//!   accumulator: 72 bytes read, 8 written) at the size of `n` points, in
//!   bytes/s, divided by 80 bytes a score.
//!
//! The bound is the smaller of the two; the report gives the kernel's share
//! of it per core and for all cores (cores times the single-thread rates:
//! the points' arrays are per thread). Runs hold the collisions of lists
//! longer than a block and score them a block of points at a time
//! ([`Receivers::score_held`]): their memory traffic is then a fraction of
//! a byte a score, and that kernel is reported against the compute bound.

use crate::cases::sobolev::{plane_point, sobolev_scene};
use crate::chain::Collision;
use crate::estimator::{Receivers, set_kernel};
use crate::reference::Sobolev;
use glam::DVec3;
use std::hint::black_box;
use std::time::Instant;

/// Floating-point operations of one open score: 14 multiplies, 10 adds or
/// subtractions, 2 maxima, a compare and a select (the division, one more,
/// runs in its own unit and is not counted).
const FLOPS_PER_SCORE: f64 = 28.0;

/// Bytes one open score moves: nine 8-byte loads and one store (80; it
/// read 88 before, which put the printed GB/s 10 % high; the memory bound
/// in scores/s divides it out).
const BYTES_PER_SCORE: f64 = 80.0;

/// Scores/s of one thread scoring collisions into `n` lower-plane points,
/// each at once ([`Receivers::score`]) or, with `held`, held and scored a
/// block of points at a time ([`Receivers::score_held`], as runs do).
fn kernel_rate(n: usize, portable: bool, held: bool) -> anyhow::Result<f64> {
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).map_err(|e| anyhow::anyhow!("{e}"))?;
    let scene = sobolev_scene(&s);
    // A square grid on [-3, 3]^2 of the lower plane.
    let side = (n as f64).sqrt().ceil() as usize;
    let pts: Vec<(DVec3, DVec3)> = (0..n)
        .map(|j| {
            let (a, b) = ((j % side) as f64, (j / side) as f64);
            let x = -3.0 + 6.0 * (a + 0.5) / side as f64;
            let y = -3.0 + 6.0 * (b + 0.5) / side as f64;
            let (p, nn) = plane_point(&s, 1, x.hypot(y), y.atan2(x));
            (p, nn)
        })
        .collect();
    let rec = Receivers::new(&scene, &pts).map_err(|e| anyhow::anyhow!("{e}"))?;
    set_kernel(portable);
    let mut acc = vec![0.0; rec.accumulator_len()];
    // One bucket and the counts, for the held path.
    let mut acc_all = vec![0.0; 2 * rec.accumulator_len()];
    let mut hold = rec.new_hold();
    let top = s.h1 + s.h2;
    let mut best: f64 = 0.0;
    // Enough collisions for about 2e7 scores a round.
    let m = (2e7 / n as f64).ceil() as usize;
    for _ in 0..5 {
        let t0 = Instant::now();
        let mut scores = 0usize;
        for k in 0..m {
            let f = k as f64 / m as f64;
            let c = Collision {
                p: DVec3::new(4.0 * f - 2.0, 1.5 - 3.0 * f, top),
                n: -DVec3::Z,
                wi: -DVec3::Z,
                q: 1.0,
                surface: 1,
                prim: 0,
                order: 1,
                seat: None,
            };
            scores += if held {
                rec.score_held(&scene, &c, 0, &mut acc_all, false, &mut hold)
            } else {
                rec.score(&scene, &c, &mut acc, None)
            };
        }
        rec.flush_held(&mut hold, &mut acc_all);
        black_box((&acc, &acc_all));
        best = best.max(scores as f64 / t0.elapsed().as_secs_f64());
    }
    set_kernel(false);
    Ok(best)
}

/// Bytes/s of one thread streaming nine arrays of `n` values (reading all,
/// writing one), as the kernel does, with the kernel's instruction set.
fn stream_rate(n: usize) -> f64 {
    let arrays: Vec<Vec<f64>> = (0..8).map(|k| vec![k as f64 * 0.5; n]).collect();
    let mut acc = vec![0.0; n];
    let passes = (2e8 / (n as f64 * BYTES_PER_SCORE)).ceil().max(1.0) as usize * 8;
    let mut best: f64 = 0.0;
    for _ in 0..5 {
        let t0 = Instant::now();
        let a: [&[f64]; 8] = std::array::from_fn(|k| arrays[k].as_slice());
        for _ in 0..passes {
            crate::estimator::stream_touch(a, &mut acc);
            black_box(&acc);
        }
        let bytes = passes as f64 * n as f64 * BYTES_PER_SCORE;
        best = best.max(bytes / t0.elapsed().as_secs_f64());
    }
    best
}

/// Print the kernel's rates against the compute and memory bounds at `n`
/// points, for `cores` cores.
pub fn bound(n: usize, cores: usize) -> anyhow::Result<()> {
    let avx2 = crate::estimator::active_kernel() == crate::estimator::Kernel::Avx2;
    let portable = kernel_rate(n, true, false)?;
    let fast = if avx2 {
        kernel_rate(n, false, false)?
    } else {
        portable
    };
    let l1 = kernel_rate(256, !avx2, false)?;
    // Lists longer than a block hold their collisions in runs.
    let held = (n > crate::estimator::HELD_BLOCK).then(|| kernel_rate(n, !avx2, true));
    let flops = arith_rate();
    let compute = flops / FLOPS_PER_SCORE;
    let bw = stream_rate(n);
    let memory = bw / BYTES_PER_SCORE;
    let limit = compute.min(memory);
    println!("kernel bound at {n} points, one thread (best of 5 rounds each):");
    println!("  kernel, portable (SSE2):   {portable:.3e} scores/s");
    if avx2 {
        println!(
            "  kernel, AVX2 + FMA build:  {fast:.3e} scores/s ({:.2}x the portable)",
            fast / portable
        );
    } else {
        println!("  kernel, AVX2: not available on this CPU");
    }
    println!(
        "  compute bound: {:.1} GFLOP/s peak (separate mul and add, vectorised, L1) / {FLOPS_PER_SCORE} operations a score = {compute:.3e} scores/s",
        flops / 1e9
    );
    println!(
        "  the kernel on 256 points (arrays in L1): {l1:.3e} scores/s ({:.0} % of the compute bound)",
        100.0 * l1 / compute
    );
    println!(
        "  memory bound: {:.2} GB/s streaming the {n} points' arrays / {BYTES_PER_SCORE} B a score = {memory:.3e} scores/s",
        bw / 1e9
    );
    println!(
        "  achieved {:.0} % of the bound ({}); on {cores} core(s): {:.3e} scores/s bound, {:.3e} achievable by the kernel",
        100.0 * fast / limit,
        if compute <= memory {
            "compute-bound"
        } else {
            "memory-bound"
        },
        limit * cores as f64,
        fast * cores as f64
    );
    if let Some(held) = held.transpose()? {
        // Held collisions read the arrays once per block of points and 256
        // collisions: the memory traffic a score is 88 / 256 bytes, so the
        // compute bound is the bound.
        println!(
            "  runs hold the collisions of lists longer than {} points and score them a block at a time (cache blocking): {held:.3e} scores/s, {:.0} % of the compute bound; on {cores} core(s): {:.3e} scores/s",
            crate::estimator::HELD_BLOCK,
            100.0 * held / compute,
            held * cores as f64
        );
    }
    Ok(())
}

/// Floating-point operations/s of one thread at the kernel's instruction
/// set (separate multiplies and adds on L1-resident data).
fn arith_rate() -> f64 {
    let mut x: Vec<f64> = (0..960).map(|k| 1.0 + k as f64 * 1e-3).collect();
    let passes = 20_000;
    let mut best: f64 = 0.0;
    for _ in 0..5 {
        let t0 = Instant::now();
        for _ in 0..passes {
            crate::estimator::arith_touch(&mut x, 0.999_999, 1e-7);
            black_box(&x);
        }
        let flops = passes as f64 * x.len() as f64 * 32.0;
        best = best.max(flops / t0.elapsed().as_secs_f64());
    }
    best
}
