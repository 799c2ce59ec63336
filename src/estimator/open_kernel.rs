//! The open scoring kernel: one collision into every constant-response
//! receiver of a list with nothing in the way (planes-only scenes, convex
//! rooms), the loop where a run on many points spends its time.
//!
//! The kernel body is written once ([`score_open_body`]) over zipped
//! structure-of-arrays slices, which the compiler vectorises. It is
//! compiled twice: for the build's baseline (SSE2 on x86-64) and, on
//! x86-64, with AVX2 and FMA enabled, chosen at run time
//! ([`active_kernel`]) so that a portable build uses the wider units where
//! the CPU has them. Both give the same bits: every lane computes the same
//! IEEE operations on one receiver in the same order (Rust never fuses a
//! multiply and an add into an FMA on its own), and receivers are
//! independent, so the vector width changes nothing but the speed
//! (`tests::avx2_and_portable_agree_bit_for_bit`). The score needs no
//! square root: `qf w cos_x d cos_p d / d^4` with unnormalised cosines.
// Calling a function compiled for AVX2 is `unsafe` (the CPU must have it):
// one call, after the run-time check.
#![allow(unsafe_code)]

use super::{ReceiverList, kernel_parts};
use glam::DVec3;
use std::sync::atomic::{AtomicU8, Ordering};

/// Which compiled kernel scores.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// The build's baseline instructions (SSE2 on x86-64).
    Portable,
    /// AVX2 and FMA (x86-64 CPUs that have them).
    Avx2,
}

/// 0: choose by the CPU; 1: portable forced (benchmarks and tests).
static FORCE: AtomicU8 = AtomicU8::new(0);

/// Force the portable kernel (`true`) or let the CPU choose (`false`).
/// For benchmarks and tests: the answers are the same either way.
pub fn set_kernel(portable: bool) {
    FORCE.store(portable as u8, Ordering::Relaxed);
}

/// The kernel in use.
#[inline]
pub fn active_kernel() -> Kernel {
    #[cfg(target_arch = "x86_64")]
    {
        if FORCE.load(Ordering::Relaxed) == 0
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
        {
            return Kernel::Avx2;
        }
    }
    Kernel::Portable
}

/// Score a collision at `x` (front normal `n`, weight times BRDF `qf`) into
/// the constant-response entries of `list`, no plane in the way, and count
/// it in `near` where it scores from within the watched radius.
#[inline]
pub(super) fn score_open<const COUNT: bool>(
    list: &ReceiverList,
    x: DVec3,
    n: DVec3,
    qf: f64,
    acc: &mut [f64],
    near: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if active_kernel() == Kernel::Avx2 {
        // SAFETY: the CPU has AVX2 and FMA (checked by `active_kernel`).
        unsafe { score_open_avx2::<COUNT>(list, x, n, qf, acc, near) };
        return;
    }
    score_open_body::<COUNT>(&Entries::of(list, 0, acc.len()), x, n, qf, acc, near);
}

/// [`score_open_body`] compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn score_open_avx2<const COUNT: bool>(
    list: &ReceiverList,
    x: DVec3,
    n: DVec3,
    qf: f64,
    acc: &mut [f64],
    near: &mut [f64],
) {
    score_open_body::<COUNT>(&Entries::of(list, 0, acc.len()), x, n, qf, acc, near);
}

/// Entries `lo..hi` of a list's arrays, as the kernel reads them.
struct Entries<'a> {
    px: &'a [f64],
    py: &'a [f64],
    pz: &'a [f64],
    nx: &'a [f64],
    ny: &'a [f64],
    nz: &'a [f64],
    w: &'a [f64],
    eps2: &'a [f64],
    watch2: &'a [f64],
}

impl<'a> Entries<'a> {
    #[inline(always)]
    fn of(list: &'a ReceiverList, lo: usize, hi: usize) -> Self {
        Self {
            px: &list.px[lo..hi],
            py: &list.py[lo..hi],
            pz: &list.pz[lo..hi],
            nx: &list.nx[lo..hi],
            ny: &list.ny[lo..hi],
            nz: &list.nz[lo..hi],
            w: &list.w[lo..hi],
            eps2: &list.eps2[lo..hi],
            watch2: &list.watch2[lo..hi],
        }
    }
}

/// Entries of a list scored a block at a time by [`score_open_held`]: 2048
/// entries of 10 arrays (160 KiB, a sixth of this machine's 1 MiB L2 per
/// core) stay in cache while every held collision scores into them.
pub(super) const BLOCK: usize = 2048;

/// One collision held for the open kernel ([`score_open_held`]): at `x`
/// (front normal `n`, weight times BRDF `qf`), scoring into the
/// accumulator from index `acc` on (its order's bucket, at the list's
/// offset), counted where `count`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Held {
    pub x: DVec3,
    pub n: DVec3,
    pub qf: f64,
    pub acc: usize,
    pub count: bool,
}

/// Score `held` collisions, in order, into the constant-response entries
/// of `list` ([`score_open`] for each), a [`BLOCK`] of entries at a time:
/// every entry receives the same terms in the same order (the same bits),
/// while its arrays are read from memory once per block rather than once
/// per collision (cache blocking: 1,000,000 Sobolev points ran at 4.5e8
/// scores/s, the arrays far larger than the caches, and now at 1.5e9).
/// `acc` holds every bucket (`Held::acc` indexes it); `near` the counts,
/// at the list's offset.
pub(super) fn score_open_held(
    list: &ReceiverList,
    held: &[Held],
    acc: &mut [f64],
    near: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if active_kernel() == Kernel::Avx2 {
        // SAFETY: the CPU has AVX2 and FMA (checked by `active_kernel`).
        unsafe { score_open_held_avx2(list, held, acc, near) };
        return;
    }
    score_open_held_body(list, held, acc, near);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn score_open_held_avx2(
    list: &ReceiverList,
    held: &[Held],
    acc: &mut [f64],
    near: &mut [f64],
) {
    score_open_held_body(list, held, acc, near);
}

#[inline(always)]
fn score_open_held_body(list: &ReceiverList, held: &[Held], acc: &mut [f64], near: &mut [f64]) {
    let nc = list.n_const;
    let mut lo = 0;
    while lo < nc {
        let hi = (lo + BLOCK).min(nc);
        let e = Entries::of(list, lo, hi);
        for h in held {
            let a = &mut acc[h.acc + lo..h.acc + hi];
            if h.count {
                let c = &mut near[list.offset + lo..list.offset + hi];
                score_open_body::<true>(&e, h.x, h.n, h.qf, a, c);
            } else {
                score_open_body::<false>(&e, h.x, h.n, h.qf, a, &mut []);
            }
        }
        lo = hi;
    }
}

/// The kernel body, over zipped slices so the compiler drops bounds checks
/// and vectorises.
#[inline(always)]
fn score_open_body<const COUNT: bool>(
    list: &Entries,
    x: DVec3,
    n: DVec3,
    qf: f64,
    acc: &mut [f64],
    near: &mut [f64],
) {
    // Both loops evaluate the same term, so counted chains round alike; the
    // uncounted one stays free of the extra stream for vectorisation.
    if !COUNT {
        let it = acc
            .iter_mut()
            .zip(list.px.iter().zip(list.py).zip(list.pz))
            .zip(list.nx.iter().zip(list.ny).zip(list.nz))
            .zip(list.w.iter().zip(list.eps2));
        for (((a, p), nr), (w, e2)) in it {
            let [far, cx, cp, d2] = open_term(x, n, p, nr, *e2);
            *a += qf * w * far * cx * cp / (d2 * d2);
        }
        return;
    }
    let it = acc
        .iter_mut()
        .zip(near.iter_mut())
        .zip(list.px.iter().zip(list.py).zip(list.pz))
        .zip(list.nx.iter().zip(list.ny).zip(list.nz))
        .zip(list.w.iter().zip(list.eps2.iter().zip(list.watch2)));
    for ((((a, c), p), nr), (w, (e2, w2))) in it {
        let [far, cx, cp, d2] = open_term(x, n, p, nr, *e2);
        *a += qf * w * far * cx * cp / (d2 * d2);
        *c += if d2 < *w2 && far * cx * cp > 0.0 {
            1.0
        } else {
            0.0
        };
    }
}

/// The open kernel's memory traffic without its arithmetic: adds the sum of
/// eight arrays into `acc` (nine streams read, one written, as a score),
/// with the kernel's dispatch. For the memory bound of `lumest bench
/// --bound`.
pub fn stream_touch(arrays: [&[f64]; 8], acc: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if active_kernel() == Kernel::Avx2 {
        // SAFETY: the CPU has AVX2 and FMA (checked by `active_kernel`).
        unsafe { stream_touch_avx2(arrays, acc) };
        return;
    }
    stream_touch_body(arrays, acc);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn stream_touch_avx2(arrays: [&[f64]; 8], acc: &mut [f64]) {
    stream_touch_body(arrays, acc);
}

#[inline(always)]
fn stream_touch_body([a, b, c, d, e, f, g, h]: [&[f64]; 8], acc: &mut [f64]) {
    let it = acc
        .iter_mut()
        .zip(a.iter().zip(b).zip(c.iter().zip(d)))
        .zip(e.iter().zip(f).zip(g.iter().zip(h)));
    for ((s, ((a, b), (c, d))), ((e, f), (g, h))) in it {
        *s += ((a + b) + (c + d)) + ((e + f) + (g + h));
    }
}

/// Peak arithmetic of the kernel's instruction set: `x <- x a + b`, 16
/// times per element of `x` (a separate multiply and add: the kernel uses
/// no fused ones), 32 floating-point operations per element, elements
/// independent so the units stay full. For the compute bound of `lumest
/// bench --bound`.
pub fn arith_touch(x: &mut [f64], a: f64, b: f64) {
    #[cfg(target_arch = "x86_64")]
    if active_kernel() == Kernel::Avx2 {
        // SAFETY: the CPU has AVX2 and FMA (checked by `active_kernel`).
        unsafe { arith_touch_avx2(x, a, b) };
        return;
    }
    arith_touch_body(x, a, b);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn arith_touch_avx2(x: &mut [f64], a: f64, b: f64) {
    arith_touch_body(x, a, b);
}

#[inline(always)]
fn arith_touch_body(x: &mut [f64], a: f64, b: f64) {
    // Twelve independent 4-lane vectors per step (with the two constants,
    // 14 of the 16 registers: no spills), enough to hide the multiply and
    // add latencies (3 + 3 cycles) behind four units.
    for c in x.chunks_exact_mut(48) {
        let mut v: [f64; 48] = c.try_into().expect("48 values");
        for _ in 0..16 {
            for y in v.iter_mut() {
                *y = *y * a + b;
            }
        }
        c.copy_from_slice(&v);
    }
}

/// The geometric factors of an open score, `[far, cos_x d, cos_p d, d^2]`
/// (unnormalised cosines, clamped at 0; `far` is 0 inside the near-field
/// ball of squared radius `e2`, where the score is left to the near part):
/// the score is `qf w far cx cp / d^4`.
#[inline(always)]
fn open_term(
    x: DVec3,
    n: DVec3,
    ((px, py), pz): ((&f64, &f64), &f64),
    ((nx, ny), nz): ((&f64, &f64), &f64),
    e2: f64,
) -> [f64; 4] {
    let [cx, cp, d2] = kernel_parts(x, n, [*px, *py, *pz], [*nx, *ny, *nz]);
    let far = if d2 >= e2 { 1.0 } else { 0.0 };
    [far, cx, cp, d2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;

    fn list(len: usize, rng: &mut Philox4x32) -> ReceiverList {
        let mut l = ReceiverList::default();
        for _ in 0..len {
            let u = rng.next_2d();
            let v = rng.next_2d();
            l.px.push(6.0 * u[0] - 3.0);
            l.py.push(6.0 * u[1] - 3.0);
            l.pz.push(0.0);
            let nz = 1.0 - v[0];
            let s = (1.0 - nz * nz).sqrt();
            l.nx.push(s * (6.3 * v[1]).cos());
            l.ny.push(s * (6.3 * v[1]).sin());
            l.nz.push(nz);
            l.w.push(0.5 + v[0]);
            l.eps2.push(if v[1] < 0.2 { 0.3 } else { 0.0 });
            l.watch2.push(if v[1] > 0.7 { 4.0 } else { 0.0 });
        }
        l
    }

    /// Held collisions scored a block of entries at a time give every
    /// entry the bits of one `score_open` per collision in order: over
    /// buckets, counted and uncounted collisions, a list longer than two
    /// blocks (not a whole number of them) at an offset in the accumulator.
    #[test]
    fn held_collisions_score_the_same_bits_as_one_by_one() {
        let mut rng = Philox4x32::new(11, 3);
        let len = 2 * BLOCK + 517;
        let mut l = list(len, &mut rng);
        l.n_const = len;
        l.offset = 5;
        let total = l.offset + len + 9;
        let buckets = 3;
        let held: Vec<Held> = (0..300)
            .map(|i| {
                let u = rng.next_2d();
                let x = DVec3::new(6.0 * u[0] - 3.0, 6.0 * u[1] - 3.0, 0.3 + 0.01 * i as f64);
                Held {
                    x,
                    n: DVec3::new(0.2 * u[1], 0.1, -1.0).normalize(),
                    qf: 0.5 + u[0],
                    acc: (i % buckets) * total + l.offset,
                    count: i % 7 == 0,
                }
            })
            .collect();
        let mut acc1: Vec<f64> = (0..buckets * total)
            .map(|i| 0.1 * (i % 13) as f64)
            .collect();
        let mut near1 = vec![0.0; total];
        let (mut acc2, mut near2) = (acc1.clone(), near1.clone());
        score_open_held(&l, &held, &mut acc1, &mut near1);
        for h in &held {
            let a = &mut acc2[h.acc..h.acc + len];
            if h.count {
                score_open::<true>(&l, h.x, h.n, h.qf, a, &mut near2[l.offset..l.offset + len]);
            } else {
                score_open::<false>(&l, h.x, h.n, h.qf, a, &mut []);
            }
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&acc1), bits(&acc2));
        assert_eq!(near1, near2);
        assert!(
            near1.iter().sum::<f64>() > 0.0,
            "some collisions were counted"
        );
    }

    #[test]
    fn avx2_and_portable_agree_bit_for_bit() {
        let mut rng = Philox4x32::new(7, 1);
        // Odd lengths exercise the loops' remainders.
        for len in [0, 1, 3, 7, 64, 1001] {
            let l = list(len, &mut rng);
            for k in 0..20 {
                let u = rng.next_2d();
                let x = DVec3::new(6.0 * u[0] - 3.0, 6.0 * u[1] - 3.0, 0.5 + k as f64 * 0.1);
                let n = DVec3::new(0.1 * u[0], -0.2 * u[1], -1.0).normalize();
                let qf = 1.0 + u[0];
                let (mut a1, mut c1) = (vec![0.25; len], vec![0.0; len]);
                let (mut a2, mut c2) = (a1.clone(), c1.clone());
                let e = Entries::of(&l, 0, len);
                score_open_body::<true>(&e, x, n, qf, &mut a1, &mut c1);
                score_open::<true>(&l, x, n, qf, &mut a2, &mut c2);
                assert_eq!(a1, a2);
                assert_eq!(c1, c2);
                score_open_body::<false>(&e, x, n, qf, &mut a1, &mut []);
                score_open::<false>(&l, x, n, qf, &mut a2, &mut []);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&a1), bits(&a2));
                // And the score is the plain formula.
                if len > 0 {
                    let p = DVec3::new(l.px[0], l.py[0], l.pz[0]);
                    let np = DVec3::new(l.nx[0], l.ny[0], l.nz[0]);
                    let d = p - x;
                    let want = if d.length_squared() >= l.eps2[0] {
                        qf * l.w[0] * n.dot(d).max(0.0) * (-np.dot(d)).max(0.0)
                            / d.length_squared().powi(2)
                    } else {
                        0.0
                    };
                    let mut a = vec![0.0; len];
                    score_open::<false>(&l, x, n, qf, &mut a, &mut []);
                    assert!(
                        (a[0] - want).abs() <= 1e-14 * want.abs(),
                        "{} vs {want}",
                        a[0]
                    );
                }
            }
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            assert_eq!(active_kernel(), Kernel::Avx2);
        }
    }
}
