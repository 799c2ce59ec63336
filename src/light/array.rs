//! The light array: picking one of many sources for a receiver by
//! resampled importance sampling (RIS; Talbot et al. 2005, "Importance
//! resampling for global illumination"; seed 001).
//!
//! The direct light at a receiver `x` (unit normal `n`) is a sum over the
//! sources, `D = sum_k D_k`. Exact summation costs one closed form and one
//! shadow test per source and receiver. The array instead
//!
//! 1. draws `M` candidates `k_1..k_M` independently from a cheap *source*
//!    distribution `q(k)` (power `Phi_k / sum Phi`, an alias table: O(1);
//!    at a receiver with *hot* sources, which power would under-sample
//!    there, a mixture with them, [`super::hot_sources`]);
//! 2. weighs each by `w_i = p^(k_i) / q(k_i)`, with the *target*
//!    `p^(k)` an unoccluded estimate of `D_k` ([`target`]: solid angle
//!    times brightness times the clamped cosine at the receiver);
//! 3. keeps one, `k = k_j`, with probability `w_j / sum_i w_i`.
//!
//! For the kept source, any estimate `F_k` with `E[F_k | k] = D_k` (the
//! closed form times one shadow test for a point, a sampled point for an
//! area source) gives the estimate `F_k W` with the *unbiased contribution
//! weight*
//!
//! `W = (1 / p^(k)) (1/M) sum_i w_i`.
//!
//! Derivation (discrete form): for any `g` with `g(k) = 0` wherever
//! `p^(k) = 0`, `E[g(k) W] = sum_k g(k)`. By symmetry of the candidates,
//! `E[g(k) W] = M E[ 1{j = 1} g(k_1) W ]`, and given the candidates the
//! probability of keeping the first is `w_1 / sum w`, so
//! `E[g W] = M E[ (w_1 / sum w) g(k_1) (sum w) / (M p^(k_1)) ]
//!         = E[ g(k_1) / q(k_1) ] = sum_{q(k) > 0} g(k)`.
//! With `g = D` this is the direct light, provided `p^(k) > 0` wherever
//! `D_k > 0` (then `q(k) > 0` too: a source that emits has power). Note
//! the factor `1/M`: the estimator is *not* `F / p^ * sum w` (M times too
//! large) and *not* `F / p_eff` with `p_eff = p^ / sum_all p^` (which would
//! need the O(L) sum the array avoids). Every target below is positive
//! wherever its source can light the receiver (an unoccluded upper bound
//! of the visible cone's cosine is used where the emitter is extended), so
//! the estimator is unbiased; where no candidate has a positive target the
//! estimate is 0, which is also unbiased (the identity above holds).
//!
//! MIS with the receiver's own (BRDF, cosine) sampling needs the density
//! of the light sample, and the RIS marginal `P(k)` is intractable (it
//! depends on the other candidates). MIS weights need only sum to 1 for
//! every sample, whichever strategy drew it, so they are computed with the
//! power-pick density `q(k) p(y | k)` as a stand-in (exactly today's
//! weights); the light part is then `w_L(y) f(y) / p(y | k) W`, whose
//! expectation is `sum_k int w_L f`, and the BRDF part adds
//! `int w_B f`: the sum is unbiased.

use super::Light;
use super::hot_sources::Hot;
use crate::sampling::Philox4x32;
use crate::sampling::alias::AliasTable;
use glam::DVec3;
use std::f64::consts::PI;

/// How the direct light of the sources is summed at receivers and at
/// backward-path vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DirectLights {
    /// Exact summation below [`RIS_AUTO_RECEIVERS`] sources at the
    /// receivers and [`RIS_AUTO_VERTICES`] at path vertices, the light
    /// array with RIS from there on.
    #[default]
    Auto,
    /// Every source at every receiver (closed forms where they exist,
    /// computed once at set-up; one shadow test per source and receiver).
    Exact,
    /// The light array with resampled importance sampling.
    Ris,
}

impl DirectLights {
    /// Parse `auto`, `exact` or `ris`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "auto" => Some(Self::Auto),
            "exact" => Some(Self::Exact),
            "ris" => Some(Self::Ris),
            _ => None,
        }
    }

    /// Whether a scene of `lights` sources uses the light array for the
    /// direct light at receivers.
    pub fn ris_at_receivers(self, lights: usize) -> bool {
        match self {
            Self::Auto => lights >= RIS_AUTO_RECEIVERS,
            Self::Exact => false,
            Self::Ris => lights > 0,
        }
    }

    /// Whether a scene of `lights` sources uses the light array for
    /// next-event estimation at backward-path vertices.
    pub fn ris_at_vertices(self, lights: usize) -> bool {
        match self {
            Self::Auto => lights >= RIS_AUTO_VERTICES,
            Self::Exact => false,
            Self::Ris => lights > 0,
        }
    }
}

/// From this many sources on, [`DirectLights::Auto`] samples the direct
/// light at receivers with the light array instead of summing it exactly
/// at set-up. Measured (`lumest bench --many-lights`, 1000 luminaires,
/// 10,000 points): the exact sum's set-up cost 1.1 s (about 0.1 us per
/// source and point), while RIS needed 21 % more chains for the same 1 %
/// RMS error (88,064 against 72,704), about 40 s more at the exact run's
/// pace; the set-up grows with `L` and RIS's extra variance does not, so
/// the two meet near 40,000 sources (an extrapolation: RIS never won in
/// the measured range).
pub const RIS_AUTO_RECEIVERS: usize = 40_000;

/// From this many sources on, [`DirectLights::Auto`] keeps one source by
/// RIS at each backward-path vertex instead of summing next-event
/// estimation over all of them. Measured (`lumest bench --many-lights
/// 10,100,1000 --compare`): RIS's FOM was 0.51, 0.13 and 0.11 times the
/// sum's (guided paths still sum strategy B's density over every source,
/// and RIS adds variance to an otherwise exact sum at each vertex), so
/// auto does not pick it in any measured range.
pub const RIS_AUTO_VERTICES: usize = 1_000_000;

/// Direct-light samples per receiver and batch with the light array, as a
/// multiple of the sampled-sources default (4 per 256 chains): the array
/// then carries the whole direct light, and a sample (8 target
/// evaluations and one shadow test, about 0.3 us) costs far less than the
/// chains' scores. In the many-lights hall (`lumest bench --many-lights`)
/// the sampled direct light with 4 per 256 chains made up two thirds of
/// the variance at 1 % of the run time.
pub const RIS_DIRECT_SAMPLES: u64 = 16;

/// Candidates per RIS pick by default.
pub const RIS_CANDIDATES: usize = 8;

/// Most candidates per pick (a stack buffer: the hot loop never allocates).
pub const RIS_MAX_CANDIDATES: usize = 64;

/// The sources of a set, drawn in proportion to power (see the module
/// docs).
#[derive(Clone, Debug, PartialEq)]
pub struct LightArray {
    /// Indices of the set's sources in the scene's lights.
    lights: Vec<u32>,
    /// Alias table of their powers.
    table: AliasTable,
    /// Per scene light, its index in `lights` (`u32::MAX`: not in the set).
    slot: Vec<u32>,
    /// Candidates per pick.
    m: usize,
}

/// A source kept by [`LightArray::pick`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RisPick {
    /// Index of the source in the scene's lights.
    pub k: u32,
    /// Unbiased contribution weight `W = (1/M) sum_i w_i / p^(k)`
    /// [1/lx times the target's unit]: the estimate of the direct light
    /// is `F_k W` with `E[F_k] = D_k`.
    pub w: f64,
    /// The source-pick probability `q(k)` of the power table.
    pub q: f64,
}

impl LightArray {
    /// The array of `lights` (indices into `all`), `m` candidates per pick
    /// (clamped to `1..=RIS_MAX_CANDIDATES`); `None` when none emits.
    pub fn new(all: &[Light], lights: Vec<u32>, m: usize) -> Option<Self> {
        let powers: Vec<f64> = lights.iter().map(|&k| all[k as usize].power()).collect();
        let table = AliasTable::new(&powers)?;
        let mut slot = vec![u32::MAX; all.len()];
        for (i, &k) in lights.iter().enumerate() {
            slot[k as usize] = i as u32;
        }
        Some(Self {
            lights,
            table,
            slot,
            m: m.clamp(1, RIS_MAX_CANDIDATES),
        })
    }

    /// Scene indices of the array's sources.
    pub fn lights(&self) -> &[u32] {
        &self.lights
    }

    /// A source drawn in proportion to power with one uniform `u`: its
    /// scene index and probability `q(k)`.
    pub fn draw_power(&self, u: f64) -> (u32, f64) {
        let i = self.table.sample(u);
        (self.lights[i], self.table.pmf(i))
    }

    /// Candidates per pick.
    pub fn candidates(&self) -> usize {
        self.m
    }

    /// Number of sources in the array.
    pub fn len(&self) -> usize {
        self.lights.len()
    }

    /// Whether the array is empty (never: [`Self::new`] refuses that).
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// Keep one source for the receiver at `x` \[m\] with unit normal `n`
    /// (`None`: a solid receiver, lit from every side) by RIS over `M`
    /// candidates drawn by power, or from the mixture with the receiver's
    /// `hot` sources ([`super::hot_sources`]), drawing `M + 1` uniforms from
    /// `rng` (always, so streams stay aligned); `None` when no candidate has
    /// a positive target (the estimate is then 0).
    pub fn pick(
        &self,
        all: &[Light],
        x: DVec3,
        n: Option<DVec3>,
        hot: Option<Hot<'_>>,
        rng: &mut Philox4x32,
    ) -> Option<RisPick> {
        self.pick_with(all, x, n, hot, rng, 1.0)
    }

    /// [`Self::pick`] with the weight `W` scaled by `bias` (1: unbiased);
    /// for the test that a mis-normalised weight is caught.
    #[doc(hidden)]
    pub fn pick_with(
        &self,
        all: &[Light],
        x: DVec3,
        n: Option<DVec3>,
        hot: Option<Hot<'_>>,
        rng: &mut Philox4x32,
        bias: f64,
    ) -> Option<RisPick> {
        let hot = hot.filter(|h| !h.k.is_empty());
        let mut cand = [(0u32, 0.0f64, 0.0f64); RIS_MAX_CANDIDATES];
        let mut sum = 0.0;
        for c in cand.iter_mut().take(self.m) {
            let u = rng.next_f64();
            // The candidate and its density: by power, or from the mixture
            // `(1 - beta) q + beta h` (one uniform either way).
            let (i, q) = match hot {
                None => {
                    let i = self.table.sample(u);
                    (i, self.table.pmf(i))
                }
                Some(h) => {
                    let i = if u < h.beta {
                        self.slot[h.draw(u / h.beta) as usize] as usize
                    } else {
                        self.table
                            .sample(((u - h.beta) / (1.0 - h.beta)).min(1.0 - f64::EPSILON))
                    };
                    let k = self.lights[i];
                    (i, (1.0 - h.beta) * self.table.pmf(i) + h.beta * h.prob(k))
                }
            };
            let k = self.lights[i];
            let t = target(&all[k as usize], x, n);
            let w = if q > 0.0 { t / q } else { 0.0 };
            sum += w;
            *c = (i as u32, w, t);
        }
        let u = rng.next_f64();
        if !(sum > 0.0 && sum.is_finite()) {
            return None;
        }
        // The kept candidate: the first whose running sum passes u * sum.
        let goal = u * sum;
        let mut run = 0.0;
        let mut kept = self.m - 1;
        for (j, c) in cand.iter().enumerate().take(self.m) {
            run += c.1;
            if goal < run && c.1 > 0.0 {
                kept = j;
                break;
            }
        }
        // Rounding can leave the last candidate with zero weight: take the
        // last with a positive one.
        while cand[kept].1 <= 0.0 {
            kept -= 1;
        }
        let (i, _, t) = cand[kept];
        Some(RisPick {
            k: self.lights[i as usize],
            w: bias * sum / (self.m as f64 * t),
            q: self.table.pmf(i as usize),
        })
    }
}

/// The RIS target `p^` \[lx\] of `light` at a receiver at `x` \[m\] with unit
/// normal `n`: an unoccluded estimate of its direct illuminance, positive
/// wherever the source can light the receiver. For a solid receiver (`n`
/// `None`, lit from every side) every `max(0, cos)` below is 1: the
/// illuminance on a plane facing the source.
///
/// - point, spot, goniometric point: `I(w) max(0, cos) / d^2`, exact;
/// - sphere, distant disc: the exact unoccluded illuminance
///   (`L int_cone max(0, n . w) dw`);
/// - area source: `L0 Omega c_b` with `Omega = min(2 pi, A |cos_y| / d^2)`
///   (`cos_y` at the centre; zero only with the receiver in the emitter's
///   plane, where no light reaches it) and `c_b` the largest
///   `max(0, n . w)` over the cone of the emitter's bounding ball; zero
///   behind a one-sided emitter;
/// - goniometric light emitting from its opening: the point form, but no
///   less than `1e-3 Phi / (4 pi) c_b / max(d^2, rho^2)` (`rho` the
///   opening's radius; the opening may light a receiver that its centre
///   does not);
/// - environment: `int L dw / 4` (the illuminance of a uniform map).
pub fn target(light: &Light, x: DVec3, n: Option<DVec3>) -> f64 {
    // A solid receiver: facing the source (the point, or a ball's centre).
    let facing = |c: DVec3| n.unwrap_or_else(|| (c - x).normalize_or_zero());
    match light {
        Light::Point { .. } | Light::Spot(_) | Light::Gonio { opening: None, .. } => {
            light.direct_illuminance(x, facing(light.position()))
        }
        Light::Sphere { c, .. } => light.direct_illuminance(x, facing(*c)),
        Light::Distant(dl) => dl.direct_illuminance(n.unwrap_or(-dl.d)),
        Light::Environment(env) => 0.25 * env.integral(),
        Light::Gonio {
            p,
            opening: Some(o),
            ..
        } => {
            let rho = o.bounding_radius();
            let d2 = (*p - x).length_squared();
            let n = facing(*p);
            let floor =
                1e-3 * light.power() / (4.0 * PI) * cos_bound(x, n, *p, rho) / d2.max(rho * rho);
            let c = n.dot(*p - x);
            let point = if c > 0.0 && d2 > 0.0 {
                light.intensity((x - *p) / d2.sqrt()) * c / (d2 * d2.sqrt())
            } else {
                0.0
            };
            point.max(floor)
        }
        Light::Area(a) => {
            let c = a.center();
            let v = x - c;
            let d2 = v.length_squared();
            let cos_y = a.normal().dot(v);
            if cos_y == 0.0 || (!a.two_sided && cos_y < 0.0) || d2 == 0.0 {
                return 0.0;
            }
            let omega = (a.area() * cos_y.abs() / (d2 * d2.sqrt())).min(2.0 * PI);
            a.l0 * omega * n.map_or(1.0, |n| cos_bound(x, n, c, a.bounding_radius()))
        }
    }
}

/// The largest `max(0, n . w)` over unit directions `w` from `x` towards
/// the ball of radius `r` about `c`: 1 inside the ball, else
/// `cos(max(0, theta - alpha))` clamped at 0, with `theta` the angle
/// between `n` and the ball's centre and `sin alpha = r / d`.
pub fn cos_bound(x: DVec3, n: DVec3, c: DVec3, r: f64) -> f64 {
    let v = c - x;
    let d = v.length();
    if d <= r {
        return 1.0;
    }
    let ct = (n.dot(v) / d).clamp(-1.0, 1.0);
    let st = (1.0 - ct * ct).sqrt();
    let sa = r / d;
    let ca = (1.0 - sa * sa).max(0.0).sqrt();
    // theta <= alpha: the normal points into the cone.
    if ct >= ca {
        return 1.0;
    }
    (ct * ca + st * sa).max(0.0)
}

/// For tests: `count` picks at the receiver (`x`, `n`) from a stream of
/// `seed`, each kept source `k` estimated as `value(k) W` with the weight
/// scaled by `bias`: the z of their mean against `exact`, and the relative
/// standard error.
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn pick_z(
    arr: &LightArray,
    lights: &[Light],
    (x, n): (DVec3, DVec3),
    hot: Option<Hot<'_>>,
    (seed, count): (u64, u64),
    bias: f64,
    value: &dyn Fn(u32) -> f64,
    exact: f64,
) -> (f64, f64) {
    let mut rng = Philox4x32::new(seed, 0);
    let (mut s, mut s2) = (0.0, 0.0);
    for _ in 0..count {
        let v = arr
            .pick_with(lights, x, Some(n), hot, &mut rng, bias)
            .map_or(0.0, |p| value(p.k) * p.w);
        s += v;
        s2 += v * v;
    }
    let m = count as f64;
    let mean = s / m;
    let se = ((s2 / m - mean * mean) / (m - 1.0)).sqrt();
    ((mean - exact) / se, se / exact)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(n: usize) -> Vec<Light> {
        (0..n)
            .map(|k| {
                let a = k as f64 * 2.399_963;
                Light::Point {
                    p: DVec3::new(5.0 * a.cos(), 5.0 * a.sin(), 1.0 + (k % 7) as f64 * 0.5),
                    i: 10.0 + (k % 13) as f64 * 7.0,
                }
            })
            .collect()
    }

    /// Mean of `F W` with the exact unoccluded `F` over many picks equals
    /// the exact sum; a weight 2 % off or without `1/M` is caught.
    #[test]
    fn ris_sum_is_unbiased_and_normalised() {
        let lights = points(200);
        let arr = LightArray::new(&lights, (0..200).collect(), 8).unwrap();
        let (x, n) = (DVec3::new(0.3, -0.2, 0.0), DVec3::Z);
        let exact: f64 = lights.iter().map(|l| l.direct_illuminance(x, n)).sum();
        let value = |k: u32| lights[k as usize].direct_illuminance(x, n);
        let est = |bias: f64| {
            pick_z(
                &arr,
                &lights,
                (x, n),
                None,
                (7, 200_000),
                bias,
                &value,
                exact,
            )
        };
        let (z, r) = est(1.0);
        assert!(z.abs() < 4.0, "z = {z}");
        // The error bar resolves a 2 % bias many times over.
        assert!(r < 0.002, "relative standard error {r}");
        let (z, _) = est(1.02);
        assert!(z.abs() > 4.0, "2 % bias not caught: z = {z}");
        let (z, _) = est(8.0);
        assert!(z.abs() > 4.0, "dropped 1/M not caught: z = {z}");
    }

    #[test]
    fn cos_bound_is_an_upper_bound() {
        let mut rng = Philox4x32::new(3, 1);
        for _ in 0..2000 {
            let u = rng.next_2d();
            let v = rng.next_2d();
            let c = DVec3::new(u[0] * 4.0 - 2.0, u[1] * 4.0 - 2.0, v[0] * 4.0 - 2.0);
            let r = v[1];
            let b = cos_bound(DVec3::ZERO, DVec3::Z, c, r);
            for _ in 0..50 {
                let s = crate::sampling::warp::sample_uniform_sphere(rng.next_2d()).w;
                let y = c + s * r;
                let w = y.normalize();
                assert!(w.z.max(0.0) <= b + 1e-12, "bound {b} < {}", w.z);
            }
        }
    }
}
