//! Scoring through occluder lists: one collision on a constant-BRDF surface
//! into the constant-response receivers of a list, each pair's segment
//! tested only against the receiver's occluders
//! ([`crate::scene::world::Occluder`]), in a scene whose finite shapes may
//! be in the way (furnished rooms). The same terms, in the same order, as
//! the general per-pair loop gives these pairs (`c.q f g w`), so the
//! answers do not depend on which loop scored; it skips what the general
//! loop spends on a direction-dependent BRDF (a normalised direction, the
//! local frame, the BRDF call) and on panes (none here).

// Calling a function compiled for AVX2 is `unsafe` (the CPU must have it):
// one call, after the run-time check.
#![allow(unsafe_code)]

use super::visibility_cells::{CellSplit, VisibilityCells};
use super::{ReceiverList, kernel_parts};
use crate::scene::Scene;
use glam::DVec3;

/// Score a collision at `x` (front normal `n`, on `from`, inside the
/// spheres and boxes `x_inside`; weight `q`, BRDF `f`) into the
/// constant-response entries of `list` (`acc`, `near` their stretches),
/// with no plane in the way and occluder lists built (and `cells`, the
/// list's visibility cells, where it has them);
/// count it in `near` where it scores from within the watched radius.
#[allow(clippy::too_many_arguments)]
pub(super) fn score_occluded<const COUNT: bool>(
    scene: &Scene,
    list: &ReceiverList,
    cells: Option<&VisibilityCells>,
    x: DVec3,
    n: DVec3,
    from: Option<(u32, u32)>,
    x_inside: u64,
    qf: (f64, f64),
    acc: &mut [f64],
    near: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if super::open_kernel::active_kernel() == super::open_kernel::Kernel::Avx2 {
        // SAFETY: the CPU has AVX2 and FMA (checked by `active_kernel`).
        unsafe {
            score_occluded_avx2::<COUNT>(scene, list, cells, x, n, from, x_inside, qf, acc, near)
        };
        return;
    }
    score_occluded_body::<COUNT>(scene, list, cells, x, n, from, x_inside, qf, acc, near);
}

/// [`score_occluded_body`] compiled for AVX2 and FMA (the same bits: Rust
/// never fuses a multiply and an add on its own, see `open_kernel`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
unsafe fn score_occluded_avx2<const COUNT: bool>(
    scene: &Scene,
    list: &ReceiverList,
    cells: Option<&VisibilityCells>,
    x: DVec3,
    n: DVec3,
    from: Option<(u32, u32)>,
    x_inside: u64,
    qf: (f64, f64),
    acc: &mut [f64],
    near: &mut [f64],
) {
    score_occluded_body::<COUNT>(scene, list, cells, x, n, from, x_inside, qf, acc, near);
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn score_occluded_body<const COUNT: bool>(
    scene: &Scene,
    list: &ReceiverList,
    cells: Option<&VisibilityCells>,
    x: DVec3,
    n: DVec3,
    from: Option<(u32, u32)>,
    x_inside: u64,
    (q, f): (f64, f64),
    acc: &mut [f64],
    near: &mut [f64],
) {
    if let Some((open_w, tests, row)) = cells.and_then(|c| c.split(x)) {
        return score_split::<COUNT>(
            scene,
            list,
            (open_w, tests, row),
            x,
            n,
            from,
            x_inside,
            (q, f),
            acc,
            near,
        );
    }
    let cell = cells.map(|c| c.row(x));
    // Two passes per block of entries: the kernels (straight-line code over
    // the structure of arrays, which the compiler vectorises), then the
    // shadow tests of the pairs that score.
    const BLOCK: usize = 64;
    let mut g = [0.0f64; BLOCK];
    let mut d2 = [0.0f64; BLOCK];
    let len = acc.len();
    let mut start = 0;
    while start < len {
        let end = (start + BLOCK).min(len);
        let m = end - start;
        let it = g[..m]
            .iter_mut()
            .zip(d2[..m].iter_mut())
            .zip(
                list.px[start..end]
                    .iter()
                    .zip(&list.py[start..end])
                    .zip(&list.pz[start..end]),
            )
            .zip(
                list.nx[start..end]
                    .iter()
                    .zip(&list.ny[start..end])
                    .zip(&list.nz[start..end]),
            );
        for (((g, d2), ((px, py), pz)), ((nx, ny), nz)) in it {
            let [cx, cp, dd] = kernel_parts(x, n, [*px, *py, *pz], [*nx, *ny, *nz]);
            // `local_kernel`'s value, as a select.
            *g = if cx > 0.0 && cp > 0.0 {
                cx * cp / (dd * dd)
            } else {
                0.0
            };
            *d2 = dd;
        }
        for i in 0..m {
            let k = start + i;
            if g[i] == 0.0 || d2[i] < list.eps2[k] {
                continue;
            }
            let p = DVec3::new(list.px[k], list.py[k], list.pz[k]);
            let occ = &list.occ[list.occ_start[k] as usize..list.occ_start[k + 1] as usize];
            let inside = x_inside & list.inside[k];
            let blocked = match cell {
                Some(row) => {
                    row[k] != 0 && scene.blocked_in_cell(x, from, p, inside, occ, row[k], d2[i])
                }
                None => {
                    !occ.is_empty() && scene.blocked_by_occluders(x, from, p, inside, occ, d2[i])
                }
            };
            if blocked {
                continue;
            }
            // On a curved surface the general loop's BRDF is 0 where the
            // normalised direction to the receiver is not in front (a
            // receiver grazing the tangent plane): the same test here.
            let f = if list.flat || (p - x).normalize().dot(n) > 0.0 {
                f
            } else {
                0.0
            };
            acc[k] += q * f * g[i] * list.w[k];
            if COUNT && d2[i] < list.watch2[k] {
                near[k] += 1.0;
            }
        }
        start = end;
    }
}

/// [`score_occluded_body`] on a flat list whose cells were split
/// ([`VisibilityCells::split`]): the pairs no occluder can shadow from the
/// collision's cell score in one straight-line pass over the structure of
/// arrays (`open_w`: their responses, 0 for the rest), and only the pairs
/// in `tests` take a shadow test. Each entry gets the same term as the
/// per-pair loop, `q f g w`, or nothing (a dark pair, or a test that finds
/// a shadow), so the sums are the same bits. A counted chain (`COUNT`)
/// takes the open pairs from the cell's masks (`row`, 0 where open), so
/// that an open entry of response 0 is counted as the per-pair loop does.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn score_split<const COUNT: bool>(
    scene: &Scene,
    list: &ReceiverList,
    (open_w, tests, row): CellSplit<'_>,
    x: DVec3,
    n: DVec3,
    from: Option<(u32, u32)>,
    x_inside: u64,
    (q, f): (f64, f64),
    acc: &mut [f64],
    near: &mut [f64],
) {
    let qf = q * f;
    let len = acc.len();
    let it = acc
        .iter_mut()
        .zip(open_w)
        .zip(
            list.px[..len]
                .iter()
                .zip(&list.py[..len])
                .zip(&list.pz[..len]),
        )
        .zip(
            list.nx[..len]
                .iter()
                .zip(&list.ny[..len])
                .zip(&list.nz[..len]),
        );
    if COUNT {
        let it = it
            .zip(list.eps2[..len].iter().zip(&list.watch2[..len]))
            .zip(near.iter_mut().zip(row));
        for (((((a, w), ((px, py), pz)), ((nx, ny), nz)), (e2, w2)), (c, m)) in it {
            let [cx, cp, dd] = kernel_parts(x, n, [*px, *py, *pz], [*nx, *ny, *nz]);
            let g = if cx > 0.0 && cp > 0.0 {
                cx * cp / (dd * dd)
            } else {
                0.0
            };
            // (Selects, not branches, so that the loop vectorises.)
            let open = *m == 0 && g != 0.0 && dd >= *e2;
            *a += if open { qf * g * w } else { 0.0 };
            *c += if open && dd < *w2 { 1.0 } else { 0.0 };
        }
    } else {
        for ((((a, w), ((px, py), pz)), ((nx, ny), nz)), e2) in it.zip(&list.eps2[..len]) {
            let [cx, cp, dd] = kernel_parts(x, n, [*px, *py, *pz], [*nx, *ny, *nz]);
            let g = if cx > 0.0 && cp > 0.0 {
                cx * cp / (dd * dd)
            } else {
                0.0
            };
            // (`w == 0` where the pair is not open: it adds `qf g 0 = 0`,
            // NaN only if `qf g` overflowed, for a collision within about
            // 1e-150 m of the point. Testing `w != 0` here as well cost 6 %
            // of the office's run time, so it is not.)
            *a += if g != 0.0 && dd >= *e2 {
                qf * g * w
            } else {
                0.0
            };
        }
    }
    for &k in tests {
        let k = k as usize;
        let mask = row[k];
        let p = [list.px[k], list.py[k], list.pz[k]];
        let [cx, cp, dd] = kernel_parts(x, n, p, [list.nx[k], list.ny[k], list.nz[k]]);
        if !(cx > 0.0 && cp > 0.0) || dd < list.eps2[k] {
            continue;
        }
        let g = cx * cp / (dd * dd);
        if g == 0.0 {
            continue;
        }
        let occ = &list.occ[list.occ_start[k] as usize..list.occ_start[k + 1] as usize];
        let inside = x_inside & list.inside[k];
        if scene.blocked_in_cell(x, from, DVec3::from_array(p), inside, occ, mask, dd) {
            continue;
        }
        acc[k] += qf * g * list.w[k];
        if COUNT && dd < list.watch2[k] {
            near[k] += 1.0;
        }
    }
}
