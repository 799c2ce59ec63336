//! Scoring through occluder lists: one collision on a constant-BRDF surface
//! into the constant-response receivers of a list, each pair's segment
//! tested only against the receiver's occluders
//! ([`crate::scene::world::Occluder`]), in a scene whose finite shapes may
//! be in the way (furnished rooms). The same terms, in the same order, as
//! the general per-pair loop gives these pairs (`c.q f g w`), so the
//! answers do not depend on which loop scored; it skips what the general
//! loop spends on a direction-dependent BRDF (a normalised direction, the
//! local frame, the BRDF call) and on panes (none here).

use super::{ReceiverList, local_kernel};
use crate::scene::Scene;
use glam::DVec3;

/// Score a collision at `x` (front normal `n`, on `from`, inside the
/// spheres and boxes `x_inside`; weight `q`, BRDF `f`) into the
/// constant-response entries of `list` (`acc`, `near` their stretches),
/// with no plane in the way and occluder lists built; count it in `near`
/// where it scores from within the watched radius.
#[allow(clippy::too_many_arguments)]
pub(super) fn score_occluded<const COUNT: bool>(
    scene: &Scene,
    list: &ReceiverList,
    x: DVec3,
    n: DVec3,
    from: Option<(u32, u32)>,
    x_inside: u64,
    (q, f): (f64, f64),
    acc: &mut [f64],
    near: &mut [f64],
) {
    for (k, a) in acc.iter_mut().enumerate() {
        let p = DVec3::new(list.px[k], list.py[k], list.pz[k]);
        let np = DVec3::new(list.nx[k], list.ny[k], list.nz[k]);
        let g = local_kernel(x, n, p, np);
        let d2 = (p - x).length_squared();
        if g == 0.0 || d2 < list.eps2[k] {
            continue;
        }
        let occ = &list.occ[list.occ_start[k] as usize..list.occ_start[k + 1] as usize];
        if scene.blocked_by_occluders(x, from, p, x_inside & list.inside[k], occ, d2) {
            continue;
        }
        *a += q * f * g * list.w[k];
        if COUNT && d2 < list.watch2[k] {
            near[k] += 1.0;
        }
    }
}
