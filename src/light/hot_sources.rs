//! Hot sources: the few sources of the light array that its power-drawn
//! candidates would under-sample at one receiver, and the receiver's
//! candidate density that mixes them in.
//!
//! The light array ([`super::array`]) draws RIS candidates in proportion to
//! power, `q(k) = Phi_k / Phi`. Its estimate stays unbiased whatever `q`,
//! but one candidate's weight `t_k / q(k)` (`t_k` the RIS target, an
//! unoccluded estimate of source `k`'s direct light at the receiver) can
//! exceed the receiver's total `T = sum_k t_k` many thousand times: a weak
//! source 0.1 m above a point among 199 strong ones 3 m up (0.5 cd against
//! 1000 cd) gives 4 % of the point's light and is drawn once in 400,000
//! candidates. Most runs then never draw it, read 4 % low with a small,
//! steady error bar and no flag (z of -3 to -6), and the rare run that does
//! is flagged. The same happens, milder, to the nearest of 40,000 equal
//! lamps over a hall (each of the nearest few gives 1-2 % of the light and
//! is drawn about once in a run).
//!
//! So each receiver gets, once at set-up, its *hot* sources: those whose
//! weight `t_k / q(k)` exceeds [`HOT_RATIO`] times an estimate `T^` of `T`
//! ([`HOT_PILOT`] power-drawn candidates on a stream of their own, fixed by
//! the receiver's position and normal, so that the list depends on neither
//! the seed, the thread count nor the other receivers), at most
//! [`HOT_MAX`] of them, those of the largest weights. Its candidates are
//! then drawn from the mixture
//!
//! `q'(k) = (1 - beta) q(k) + beta h(k)`,
//!
//! with `h(k) = t_k / sum_H t` over the hot set `H` (0 outside it) and
//! `beta` the hot set's share `sum_H t / (sum_H t + T^)`, clamped to
//! [1/8, 7/8]. RIS is unbiased for any candidate density that is positive
//! wherever the target is ([`super::array`]), and `q' >= (1 - beta) q > 0`
//! there, so this changes the variance only. A receiver without hot
//! sources draws exactly as before (the same uniforms, the same bits).
//!
//! Finding them costs no pass over all sources: a bounding-volume tree over
//! the sources' positions bounds `t_k / q(k) <= kappa_k Phi / d_k^2`
//! (`kappa_k = I_max / Phi_k`, [`kappa`]), and a best-first walk stops
//! where no node's bound reaches the threshold or the [`HOT_MAX`]-th
//! weight found. Sources at infinity (no position) are each evaluated.

use super::Light;
use super::array::{LightArray, target};
use crate::sampling::Philox4x32;
use glam::DVec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::f64::consts::PI;

/// A source is hot where its weight `t / q` exceeds this many times the
/// receiver's estimated total `T^`: a candidate's relative variance is
/// bounded by the largest weight over `T`, and 8 keeps it near that of
/// evenly spread sources while only a handful of near sources qualify.
pub const HOT_RATIO: f64 = 8.0;

/// Most hot sources per receiver (those of the largest weights).
pub const HOT_MAX: usize = 64;

/// Power-drawn candidates of the pilot that estimates `T`.
pub const HOT_PILOT: usize = 64;

/// Most target evaluations per receiver in the tree walk: where even the
/// threshold prunes nothing (a receiver that no sampled source lights),
/// the walk stops there with the best found so far.
const WALK_BUDGET: usize = 8 * HOT_MAX;

/// Sources per leaf of the tree.
const LEAF: usize = 4;

/// One receiver's hot sources ([`HotSources::find`]): scene indices, sorted,
/// with the cumulative probabilities of `h` in that order, and `beta`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HotSources {
    /// Scene indices of the hot sources, ascending.
    pub k: Vec<u32>,
    /// Cumulative `h` in the order of `k` (the last is 1).
    pub cum: Vec<f64>,
    /// The hot set's share of the candidates.
    pub beta: f64,
}

/// A view of [`HotSources`] (flattened per receiver in
/// [`crate::estimator::Receivers`]).
#[derive(Clone, Copy, Debug)]
pub struct Hot<'a> {
    /// Scene indices, ascending.
    pub k: &'a [u32],
    /// Cumulative probabilities of `h`, in the order of `k`.
    pub cum: &'a [f64],
    /// The hot set's share of the candidates.
    pub beta: f64,
}

impl HotSources {
    /// This set as a view.
    pub fn view(&self) -> Hot<'_> {
        Hot {
            k: &self.k,
            cum: &self.cum,
            beta: self.beta,
        }
    }
}

impl Hot<'_> {
    /// The probability `h(k)` of scene source `k` (0 outside the set).
    #[inline]
    pub fn prob(&self, k: u32) -> f64 {
        match self.k.binary_search(&k) {
            Ok(0) => self.cum[0],
            Ok(i) => self.cum[i] - self.cum[i - 1],
            Err(_) => 0.0,
        }
    }

    /// The scene index drawn from `h` with one uniform `u` in `[0, 1)`.
    #[inline]
    pub fn draw(&self, u: f64) -> u32 {
        let i = self.cum.partition_point(|&c| c <= u).min(self.k.len() - 1);
        self.k[i]
    }
}

/// `kappa_k` \[1/sr\]: a bound on `t_k d^2 / Phi_k` (`t_k` the RIS target,
/// [`target`], `d` the distance from the receiver to
/// [`Light::position`]), for a source with a position; `None` for one at
/// infinity or without power.
///
/// - point, sphere: `I / Phi = 1 / (4 pi)` (a sphere's illuminance is at
///   most `I / d^2` outside it);
/// - spot, goniometric point: `I_max / Phi`; a luminaire emitting from
///   its opening too (its target's floor, `1e-3 Phi / (4 pi) / d^2`, lies
///   below `I_max / d^2`);
/// - area source: `L_0 A / Phi` (its target is at most `L_0 A / d^2`).
pub fn kappa(light: &Light) -> Option<f64> {
    let phi = light.power();
    if !(phi > 0.0 && phi.is_finite()) {
        return None;
    }
    let k = match light {
        Light::Point { .. } | Light::Sphere { .. } => 1.0 / (4.0 * PI),
        Light::Spot(sp) => sp.i0 / phi,
        Light::Gonio { dist, .. } => dist.max_intensity() / dist.power(),
        Light::Area(a) => a.l0 * a.area() / phi,
        Light::Distant(_) | Light::Environment(_) => return None,
    };
    k.is_finite().then_some(k)
}

/// A node of [`SourceTree`]: the box of its sources' positions, their
/// largest `kappa`, and either two children (`count == 0`, the left at
/// `first`, the right after it) or a leaf of `count` sources from `first`.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    kappa: f64,
    first: u32,
    count: u32,
}

/// A bounding-volume tree over the positions of a light array's sources,
/// for [`HotSources::find`].
#[derive(Clone, Debug)]
pub struct SourceTree {
    nodes: Vec<Node>,
    /// Scene indices of the sources with a position, in leaf order.
    order: Vec<u32>,
    /// Their `kappa`, in the same order.
    kappa: Vec<f64>,
    /// Scene indices of the array's sources at infinity.
    far: Vec<u32>,
    /// The array's total power \[lm\].
    phi: f64,
}

impl SourceTree {
    /// The tree over the sources of `array` (scene lights `all`).
    pub fn new(array: &LightArray, all: &[Light]) -> Self {
        let mut items: Vec<(u32, DVec3, f64)> = Vec::new();
        let mut far = Vec::new();
        let mut phi = 0.0;
        for &k in array.lights() {
            let l = &all[k as usize];
            phi += l.power();
            match kappa(l) {
                Some(c) => items.push((k, l.position(), c)),
                None if l.is_directional() => far.push(k),
                None => {} // no power: never drawn, never hot
            }
        }
        let mut tree = Self {
            nodes: Vec::new(),
            order: Vec::with_capacity(items.len()),
            kappa: Vec::with_capacity(items.len()),
            far,
            phi,
        };
        if !items.is_empty() {
            tree.nodes.push(Node {
                lo: DVec3::ZERO,
                hi: DVec3::ZERO,
                kappa: 0.0,
                first: 0,
                count: 0,
            });
            tree.build(0, &mut items);
        }
        tree
    }

    /// Fill node `at` with `items`, splitting at the median of the box's
    /// longest axis.
    fn build(&mut self, at: usize, items: &mut [(u32, DVec3, f64)]) {
        let (mut lo, mut hi, mut kap) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0.0f64);
        for it in items.iter() {
            lo = lo.min(it.1);
            hi = hi.max(it.1);
            kap = kap.max(it.2);
        }
        if items.len() <= LEAF {
            self.nodes[at] = Node {
                lo,
                hi,
                kappa: kap,
                first: self.order.len() as u32,
                count: items.len() as u32,
            };
            for it in items.iter() {
                self.order.push(it.0);
                self.kappa.push(it.2);
            }
            return;
        }
        let e = hi - lo;
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        let mid = items.len() / 2;
        // Ties broken by the scene index: the tree does not depend on the
        // sort's algorithm.
        items.select_nth_unstable_by(mid, |a, b| {
            a.1[axis].total_cmp(&b.1[axis]).then(a.0.cmp(&b.0))
        });
        let first = self.nodes.len() as u32;
        self.nodes[at] = Node {
            lo,
            hi,
            kappa: kap,
            first,
            count: 0,
        };
        let blank = self.nodes[at];
        self.nodes.push(blank);
        self.nodes.push(blank);
        let (l, r) = items.split_at_mut(mid);
        self.build(first as usize, l);
        self.build(first as usize + 1, r);
    }

    /// Upper bound of `t / q` over node `i`'s sources at `x`.
    fn bound(&self, i: usize, x: DVec3) -> f64 {
        let nd = &self.nodes[i];
        let d = (nd.lo - x).max(x - nd.hi).max(DVec3::ZERO);
        let d2 = d.length_squared();
        if d2 > 0.0 {
            nd.kappa * self.phi / d2
        } else {
            f64::INFINITY
        }
    }
}

impl HotSources {
    /// The hot sources of `array` (tree `tree`, scene lights `all`) at a
    /// receiver at `x` \[m\] with unit normal `n` (`None`: a solid
    /// receiver), as the module doc describes; empty where none is hot.
    pub fn find(
        array: &LightArray,
        tree: &SourceTree,
        all: &[Light],
        x: DVec3,
        n: Option<DVec3>,
    ) -> Self {
        // The pilot's stream: fixed by the receiver alone.
        let key = [x.x, x.y, x.z]
            .into_iter()
            .chain(n.map_or([0.0; 3], |v| [v.x, v.y, v.z]))
            .fold(0x686f_7473_u64, |h, v| {
                (h ^ v.to_bits())
                    .wrapping_mul(0x9e37_79b9_7f4a_7c15)
                    .rotate_left(29)
            });
        let mut rng = Philox4x32::new(0x686f_7420_736f_7572, key);
        let mut total = 0.0;
        for _ in 0..HOT_PILOT {
            let (k, q) = array.draw_power(rng.next_f64());
            if q > 0.0 {
                total += target(&all[k as usize], x, n) / q;
            }
        }
        Self::with_total(tree, all, x, n, total / HOT_PILOT as f64)
    }

    /// [`Self::find`] with the estimated total `t_hat` \[lx\] given (the
    /// tree's sources are the array's).
    pub(crate) fn with_total(
        tree: &SourceTree,
        all: &[Light],
        x: DVec3,
        n: Option<DVec3>,
        t_hat: f64,
    ) -> Self {
        let threshold = HOT_RATIO * t_hat;
        let q_of = |k: u32| all[k as usize].power() / tree.phi;
        // The best weights found: a min-heap of (weight bits, index, target).
        let mut best: BinaryHeap<Reverse<(u64, u32, u64)>> = BinaryHeap::new();
        let floor = |best: &BinaryHeap<Reverse<(u64, u32, u64)>>| {
            if best.len() < HOT_MAX {
                threshold
            } else {
                best.peek()
                    .map_or(threshold, |r| f64::from_bits(r.0.0).max(threshold))
            }
        };
        let offer = |best: &mut BinaryHeap<Reverse<(u64, u32, u64)>>, k: u32| {
            let t = target(&all[k as usize], x, n);
            let q = q_of(k);
            if !(t > 0.0 && q > 0.0) {
                return;
            }
            let w = t / q;
            if w.is_finite() && w > floor(best) {
                best.push(Reverse((w.to_bits(), k, t.to_bits())));
                if best.len() > HOT_MAX {
                    best.pop();
                }
            }
        };
        for &k in &tree.far {
            offer(&mut best, k);
        }
        if !tree.nodes.is_empty() {
            // Best-first by bound (non-negative, so its bits order it).
            let mut open: BinaryHeap<(u64, u32)> = BinaryHeap::new();
            open.push((tree.bound(0, x).to_bits(), 0));
            let mut evals = 0;
            while let Some((b, i)) = open.pop() {
                if f64::from_bits(b) <= floor(&best) || evals >= WALK_BUDGET {
                    break;
                }
                let nd = tree.nodes[i as usize];
                if nd.count > 0 {
                    for s in nd.first..nd.first + nd.count {
                        let k = tree.order[s as usize];
                        // The source's own bound, before its target.
                        let d2 = (all[k as usize].position() - x).length_squared();
                        if d2 > 0.0 && tree.kappa[s as usize] * tree.phi / d2 <= floor(&best) {
                            continue;
                        }
                        evals += 1;
                        offer(&mut best, k);
                    }
                } else {
                    for c in [nd.first, nd.first + 1] {
                        open.push((tree.bound(c as usize, x).to_bits(), c));
                    }
                }
            }
        }
        if best.is_empty() {
            return Self::default();
        }
        let mut hot: Vec<(u32, f64)> = best
            .into_iter()
            .map(|Reverse((_, k, t))| (k, f64::from_bits(t)))
            .collect();
        hot.sort_by_key(|h| h.0);
        let sum: f64 = hot.iter().map(|h| h.1).sum();
        let mut acc = 0.0;
        let mut cum: Vec<f64> = hot
            .iter()
            .map(|h| {
                acc += h.1;
                acc / sum
            })
            .collect();
        *cum.last_mut().expect("not empty") = 1.0;
        Self {
            k: hot.iter().map(|h| h.0).collect(),
            cum,
            beta: (sum / (sum + t_hat)).clamp(0.125, 0.875),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 199 lamps of 1000 cd 3 m up, scattered over 30 x 30 m, and one of
    /// 0.5 cd 0.1 m above the origin (scene index 0).
    fn weak_and_strong() -> Vec<Light> {
        let mut v = vec![Light::Point {
            p: DVec3::new(0.0, 0.0, 0.1),
            i: 0.5,
        }];
        v.extend((1..200).map(|k| {
            let a = k as f64 * 2.399_963;
            let r = 15.0 * (k as f64 / 200.0).sqrt();
            Light::Point {
                p: DVec3::new(r * a.cos() + 0.7, r * a.sin() - 0.4, 3.0),
                i: 1000.0,
            }
        }));
        v
    }

    /// The walk finds exactly the sources a pass over all of them finds:
    /// weights above the threshold, the largest [`HOT_MAX`] of them.
    #[test]
    fn walk_matches_a_pass_over_every_source() {
        let mut lights = weak_and_strong();
        // Some spots and area sources too, at other heights.
        for k in 0..40 {
            let a = k as f64 * 1.3;
            let p = DVec3::new(4.0 * a.cos(), 4.0 * a.sin(), 0.5 + 0.1 * k as f64);
            lights.push(if k % 2 == 0 {
                Light::Spot(crate::light::Spot::new(p, -DVec3::Z, 0.2, 0.4, 300.0))
            } else {
                // Facing down (e1 x e2 = -z).
                Light::Area(std::sync::Arc::new(crate::light::AreaLight {
                    shape: crate::light::AreaShape::Rect {
                        corner: p,
                        e1: DVec3::new(0.0, 0.3, 0.0),
                        e2: DVec3::new(0.3, 0.0, 0.0),
                    },
                    l0: 2000.0,
                    two_sided: false,
                    material: crate::material::Material::Lambertian { rho: 0.0 },
                    surface: 0,
                }))
            });
        }
        let array = LightArray::new(&lights, (0..lights.len() as u32).collect(), 8).unwrap();
        let tree = SourceTree::new(&array, &lights);
        let phi: f64 = lights.iter().map(Light::power).sum();
        for (x, t_hat) in [
            (DVec3::ZERO, 1000.0),
            (DVec3::new(0.1, 0.0, 0.0), 10.0),
            (DVec3::new(3.0, -2.0, 0.0), 1.0),
            (DVec3::new(20.0, 20.0, 0.0), 100.0),
            (DVec3::new(1.0, 1.0, 0.0), 0.0),
        ] {
            let got = HotSources::with_total(&tree, &lights, x, Some(DVec3::Z), t_hat);
            let mut all: Vec<(f64, u32)> = (0..lights.len() as u32)
                .filter_map(|k| {
                    let l = &lights[k as usize];
                    let w = target(l, x, Some(DVec3::Z)) / (l.power() / phi);
                    (w > HOT_RATIO * t_hat).then_some((w, k))
                })
                .collect();
            all.sort_by(|a, b| b.0.total_cmp(&a.0));
            all.truncate(HOT_MAX);
            let mut want: Vec<u32> = all.iter().map(|a| a.1).collect();
            want.sort_unstable();
            assert_eq!(got.k, want, "at {x} with T^ = {t_hat}");
            if !want.is_empty() {
                assert_eq!(*got.cum.last().unwrap(), 1.0);
                assert!(got.cum.windows(2).all(|w| w[0] <= w[1]));
                assert!((0.125..=0.875).contains(&got.beta));
            }
        }
    }

    /// Per-candidate relative variance of `t / q`, `sum t^2 / q / T^2 - 1`,
    /// computed exactly over every source for the power density and for the
    /// receiver's mixture: the weak lamp 0.1 m above the point makes the
    /// first about 480 and the hot sources bring it below 2. And the
    /// mixture's picks, with the exact unoccluded light of the kept source,
    /// average to the sum over the sources (a 2 % error would not).
    #[test]
    fn hot_sources_tame_a_weak_lamp_next_to_the_point() {
        let lights = weak_and_strong();
        let array = LightArray::new(&lights, (0..200).collect(), 8).unwrap();
        let tree = SourceTree::new(&array, &lights);
        let (x, n) = (DVec3::ZERO, DVec3::Z);
        let hot = HotSources::find(&array, &tree, &lights, x, Some(n));
        assert!(hot.k.contains(&0), "the weak lamp is not hot: {hot:?}");
        let h = hot.view();
        let phi: f64 = lights.iter().map(Light::power).sum();
        let t: Vec<f64> = lights.iter().map(|l| target(l, x, Some(n))).collect();
        let total: f64 = t.iter().sum();
        let rel_var = |q: &dyn Fn(usize) -> f64| {
            t.iter()
                .enumerate()
                .map(|(k, &tk)| tk * tk / q(k))
                .sum::<f64>()
                / (total * total)
                - 1.0
        };
        let power = rel_var(&|k| lights[k].power() / phi);
        let mixed =
            rel_var(&|k| (1.0 - h.beta) * lights[k].power() / phi + h.beta * h.prob(k as u32));
        assert!(power > 300.0, "power density: {power}");
        assert!(mixed < 2.0, "mixture: {mixed}");
        // The picks themselves: unbiased, and a 2 % error is resolved.
        let value = |k: u32| t[k as usize];
        let est = |bias: f64| {
            let at = (x, n);
            super::super::array::pick_z(
                &array,
                &lights,
                at,
                Some(h),
                (5, 100_000),
                bias,
                &value,
                total,
            )
            .0
        };
        let z = est(1.0);
        assert!(z.abs() < 4.0, "z = {z}");
        assert!(est(1.02).abs() > 4.0 && est(0.98).abs() > 4.0);
    }

    /// Where the sources are spread evenly over the receiver's view no
    /// source is hot, and the candidates are drawn by power as before.
    #[test]
    fn evenly_lit_receivers_have_no_hot_sources() {
        let lights: Vec<Light> = (0..64)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 64.0;
                Light::Point {
                    p: DVec3::new(5.0 * a.cos(), 5.0 * a.sin(), 5.0),
                    i: 100.0,
                }
            })
            .collect();
        let array = LightArray::new(&lights, (0..64).collect(), 8).unwrap();
        let tree = SourceTree::new(&array, &lights);
        let hot = HotSources::find(&array, &tree, &lights, DVec3::ZERO, Some(DVec3::Z));
        assert!(hot.k.is_empty(), "{hot:?}");
    }
}
