//! Directions for a point in a slot (a wall point behind a board hung 1 cm
//! off it): its light arrives almost parallel to its own plane, through
//! directions that cosine sampling draws with probability about
//! `cos^2 theta_max` (1e-4 for 1 cm over 1 m).
//!
//! With `v = cos^2 theta`, cosine sampling draws `v` uniform in `(0, 1)`
//! and the azimuth uniformly; its illuminance weight `cos theta / pdf` is
//! `pi`. [`sample_grazing_cosine`] draws `v` from the mixture
//! `p(v) = a0 + sum_k a_k 1[v <= s_k] / s_k` (the cosine share `a0 = 0.4`
//! and bands `s_k = 10^-k`, `k = 1..6`, each `a_k = 0.1`), density
//! `p(v) cos theta / pi` per solid angle and weight `pi / p(v)`: at most
//! `pi / a0`, so every direction stays possible at a bounded weight.
//! [`GrazingTable`] adds what a point's probes found: per azimuth, the
//! largest `v` through which light gets in, drawn uniformly below it, so
//! that the weight is nearly constant over those directions.

use crate::sampling::DirectionSample;
use crate::sampling::warp::sin_cos_turns;
use glam::DVec3;
use std::f64::consts::FRAC_1_PI;

/// The grazing bands' upper bounds on `cos^2 theta`.
const BANDS: [f64; 6] = [1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6];
/// The cosine share `a0` of the mixture.
const COSINE_SHARE: f64 = 0.4;
/// Each band's share `a_k`: `(1 - a0) / 6`.
const BAND_SHARE: f64 = (1.0 - COSINE_SHARE) / BANDS.len() as f64;

/// Density of `v = cos^2 theta` under the mixture (cosine sampling: 1).
fn v_density(v: f64) -> f64 {
    COSINE_SHARE
        + BANDS
            .iter()
            .filter(|&&s| v <= s)
            .map(|&s| BAND_SHARE / s)
            .sum::<f64>()
}

/// A direction in the local frame (z the normal) drawn from the mixture,
/// with its density [1/sr]; `u[2]` picks the component.
pub fn sample_grazing_cosine(u: [f64; 3]) -> DirectionSample {
    let scale = if u[2] < COSINE_SHARE {
        1.0
    } else {
        let k = ((u[2] - COSINE_SHARE) / BAND_SHARE) as usize;
        BANDS[k.min(BANDS.len() - 1)]
    };
    let v = scale * u[0];
    let z = v.sqrt();
    let r = (1.0 - v).max(0.0).sqrt();
    let (sin_phi, cos_phi) = sin_cos_turns(u[1]);
    DirectionSample {
        w: DVec3::new(r * cos_phi, r * sin_phi, z),
        pdf: grazing_cosine_pdf(z),
    }
}

/// Density [1/sr] of [`sample_grazing_cosine`] at a direction whose local z
/// coordinate is `cos_theta` (0 below the hemisphere).
pub fn grazing_cosine_pdf(cos_theta: f64) -> f64 {
    if cos_theta <= 0.0 {
        return 0.0;
    }
    v_density(cos_theta * cos_theta) * cos_theta * FRAC_1_PI
}

/// Share of [`GrazingTable::sample`] drawn from the table; the rest from
/// [`sample_grazing_cosine`], which keeps every direction of the
/// hemisphere possible.
const TABLE_SHARE: f64 = 0.8;

/// Where light can reach a slot point, per azimuth: bin `a` of `A` (the
/// azimuth in turns in `[a / A, (a + 1) / A)`) holds the directions with
/// `cos^2 theta <= reach[a]`. [`GrazingTable::sample`] draws from it with
/// share 0.8 (a bin in proportion to its `reach`, the azimuth uniform in
/// it, `cos^2 theta` uniform in `[0, reach[a]]`: density `1 / mean(reach)`
/// in `(cos^2 theta, azimuth in turns)`, where cosine sampling has 1) and
/// from [`sample_grazing_cosine`] with share 0.2, so that the illuminance
/// weight `pi / p(v)` is nearly constant over the table's directions and
/// any direction the table misses is still drawn.
#[derive(Clone, Debug)]
pub struct GrazingTable {
    reach: Vec<f64>,
    /// Cumulative sums of `reach`.
    cdf: Vec<f64>,
    mean: f64,
}

impl GrazingTable {
    /// The table of per-bin reaches (each clamped to `[0, 1]`); `None` when
    /// none is positive.
    pub fn new(reach: Vec<f64>) -> Option<Self> {
        let reach: Vec<f64> = reach.into_iter().map(|r| r.clamp(0.0, 1.0)).collect();
        let mut sum = 0.0;
        let cdf: Vec<f64> = reach
            .iter()
            .map(|r| {
                sum += r;
                sum
            })
            .collect();
        (sum > 0.0).then(|| Self {
            mean: sum / reach.len() as f64,
            reach,
            cdf,
        })
    }

    /// The mean of the bins' reaches: about the cosine-weighted share of
    /// the hemisphere the table holds (cosine sampling draws a direction
    /// in it with that probability).
    pub fn mean_reach(&self) -> f64 {
        self.mean
    }

    /// A direction in the local frame (z the normal) and its density
    /// [1/sr] ([`Self::pdf`]).
    pub fn sample(&self, u: [f64; 3]) -> DirectionSample {
        let w = if u[2] < TABLE_SHARE {
            let total = self.cdf[self.cdf.len() - 1];
            let pick = u[2] / TABLE_SHARE * total;
            let a = self
                .cdf
                .partition_point(|&c| c <= pick)
                .min(self.reach.len() - 1);
            let v = self.reach[a] * u[0];
            let turns = (a as f64 + u[1]) / self.reach.len() as f64;
            let (sin_phi, cos_phi) = sin_cos_turns(turns);
            let r = (1.0 - v).max(0.0).sqrt();
            DVec3::new(r * cos_phi, r * sin_phi, v.sqrt())
        } else {
            let u2 = (u[2] - TABLE_SHARE) / (1.0 - TABLE_SHARE);
            sample_grazing_cosine([u[0], u[1], u2]).w
        };
        DirectionSample {
            w,
            pdf: self.pdf(w),
        }
    }

    /// Density [1/sr] of [`Self::sample`] at local direction `w`.
    pub fn pdf(&self, w: DVec3) -> f64 {
        if w.z <= 0.0 {
            return 0.0;
        }
        let v = w.z * w.z;
        let turns = w.y.atan2(w.x) / std::f64::consts::TAU;
        let turns = if turns < 0.0 { turns + 1.0 } else { turns };
        let a = ((turns * self.reach.len() as f64) as usize).min(self.reach.len() - 1);
        let table = if v <= self.reach[a] {
            1.0 / self.mean
        } else {
            0.0
        };
        (TABLE_SHARE * table + (1.0 - TABLE_SHARE) * v_density(v)) * w.z * FRAC_1_PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;

    /// The density of `v = cos^2 theta` integrates to 1 over `(0, 1)` (it
    /// is piecewise constant between the band edges: an exact sum).
    #[test]
    fn density_of_v_integrates_to_one() {
        let mut edges = vec![0.0];
        edges.extend(BANDS.iter().rev());
        edges.push(1.0);
        let total: f64 = edges
            .windows(2)
            .map(|e| (e[1] - e[0]) * v_density(0.5 * (e[0] + e[1])))
            .sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
    }

    /// Sampled directions follow the density: the fraction with
    /// `cos^2 theta` below each band edge matches the integral of `p(v)`,
    /// and the weighted mean of `cos^2 theta` (as an importance-sampled
    /// integral against the cosine density) matches the exact 1/2.
    #[test]
    fn samples_follow_the_density() {
        let mut rng = Philox4x32::new(7, 0);
        let n = 400_000;
        let mut below = [0usize; 6];
        let mut mean = 0.0;
        let mut mean2 = 0.0;
        for _ in 0..n {
            let [a, b] = rng.next_2d();
            let s = sample_grazing_cosine([a, b, rng.next_f64()]);
            assert!((s.w.length() - 1.0).abs() < 1e-12 && s.w.z >= 0.0);
            assert!((s.pdf - grazing_cosine_pdf(s.w.z)).abs() <= 1e-12 * s.pdf);
            let v = s.w.z * s.w.z;
            for (k, &e) in BANDS.iter().enumerate() {
                if v <= e {
                    below[k] += 1;
                }
            }
            // E_cos[v] = 1/2, estimated with weight (cos / pi) / pdf.
            let x = v * (s.w.z * FRAC_1_PI) / s.pdf;
            mean += x;
            mean2 += x * x;
        }
        let nf = n as f64;
        let m = mean / nf;
        let se = ((mean2 / nf - m * m) / nf).sqrt();
        assert!((m - 0.5).abs() < 4.0 * se, "{m} +- {se}");
        for (k, &e) in BANDS.iter().enumerate() {
            // P(v <= e) = a0 e + sum over bands s of a_s min(e, s) / s.
            let p: f64 = COSINE_SHARE * e
                + BANDS
                    .iter()
                    .map(|&s| BAND_SHARE * e.min(s) / s)
                    .sum::<f64>();
            let got = below[k] as f64 / nf;
            let sd = (p * (1.0 - p) / nf).sqrt();
            assert!((got - p).abs() < 4.5 * sd, "edge {e}: {got} against {p}");
        }
    }
    /// The table's density integrates to 1 over the hemisphere and its
    /// samples follow it: the importance-sampled mean of `cos^2 theta`
    /// against the cosine density is the exact 1/2, and the share of
    /// samples inside the table's region matches the density's integral.
    #[test]
    fn table_samples_follow_the_density() {
        let reach: Vec<f64> = (0..32)
            .map(|a| {
                if a % 5 == 0 {
                    0.0
                } else {
                    1e-3 * (1.0 + a as f64)
                }
            })
            .collect();
        let t = GrazingTable::new(reach.clone()).unwrap();
        assert!(GrazingTable::new(vec![0.0; 8]).is_none());
        let mut rng = Philox4x32::new(11, 0);
        let n = 400_000;
        let (mut mean, mut mean2, mut inside) = (0.0, 0.0, 0usize);
        for _ in 0..n {
            let [a, b] = rng.next_2d();
            let s = t.sample([a, b, rng.next_f64()]);
            assert!((s.w.length() - 1.0).abs() < 1e-12 && s.w.z >= 0.0);
            let x = s.w.z * s.w.z * (s.w.z * FRAC_1_PI) / s.pdf;
            mean += x;
            mean2 += x * x;
            let turns = s.w.y.atan2(s.w.x) / std::f64::consts::TAU;
            let bin = ((turns.rem_euclid(1.0)) * 32.0) as usize % 32;
            if s.w.z * s.w.z <= reach[bin] {
                inside += 1;
            }
        }
        let nf = n as f64;
        let m = mean / nf;
        let se = ((mean2 / nf - m * m) / nf).sqrt();
        assert!((m - 0.5).abs() < 4.0 * se, "{m} +- {se}");
        // P(inside) = 0.8 + 0.2 * (the mixture's mass inside the region).
        let mass = |r: f64| {
            COSINE_SHARE * r
                + BANDS
                    .iter()
                    .map(|&s| BAND_SHARE * r.min(s) / s)
                    .sum::<f64>()
        };
        let p =
            TABLE_SHARE + (1.0 - TABLE_SHARE) * reach.iter().map(|&r| mass(r)).sum::<f64>() / 32.0;
        let got = inside as f64 / nf;
        let sd = (p * (1.0 - p) / nf).sqrt();
        assert!((got - p).abs() < 4.5 * sd, "{got} against {p}");
    }

    /// The table's density integrates to 1 over the hemisphere, by a
    /// deterministic sum (no sampling noise): per bin, `pdf pi / cos theta`
    /// is piecewise constant in `v = cos^2 theta` between the band edges
    /// and the bin's reach, and constant in azimuth within the bin, so a
    /// midpoint rule on those pieces is exact. Evaluated at azimuths in
    /// every bin (half of them with `atan2` negative), so a wrong bin
    /// mapping or a lost normalisation fails it.
    #[test]
    fn table_density_integrates_to_one_exactly() {
        let reach: Vec<f64> = (0..32i32)
            .map(|a| match a % 7 {
                0 => 0.0,
                1 => 1.5, // clamped to 1
                k => 10f64.powi(-k),
            })
            .collect();
        let t = GrazingTable::new(reach.clone()).unwrap();
        let mut total = 0.0;
        for (a, &r) in reach.iter().enumerate() {
            let r = r.clamp(0.0, 1.0);
            let mut edges = vec![0.0, 1.0, r];
            edges.extend(BANDS);
            edges.sort_by(f64::total_cmp);
            edges.dedup();
            for k in 0..4 {
                let turns = (a as f64 + (k as f64 + 0.5) / 4.0) / 32.0;
                let (sp, cp) = sin_cos_turns(turns);
                for e in edges.windows(2) {
                    let v = 0.5 * (e[0] + e[1]);
                    let (z, st) = (v.sqrt(), (1.0 - v).sqrt());
                    let w = DVec3::new(st * cp, st * sp, z);
                    // d omega = pi d(turns) dv / z.
                    total += t.pdf(w) * std::f64::consts::PI / z * (e[1] - e[0]) / 128.0;
                }
            }
        }
        assert!((total - 1.0).abs() < 1e-12, "{total}");
    }

    /// A direction drawn from the table's share in bin `a`, at either edge
    /// of the bin's azimuths and of its `v` range, is credited the table's
    /// density by [`GrazingTable::pdf`] (the bin mapping of `atan2` agrees
    /// with the sampling's at the bin edges, the wrap at turn 1 included).
    #[test]
    fn table_samples_are_credited_their_bin() {
        let reach: Vec<f64> = (0..32).map(|a| 1e-4 * (1.0 + a as f64)).collect();
        let t = GrazingTable::new(reach.clone()).unwrap();
        let total: f64 = reach.iter().sum();
        for a in 0..32 {
            // u[2] in the middle of bin a's share of the table's 0.8.
            let lo: f64 = reach[..a].iter().sum();
            let u2 = TABLE_SHARE * (lo + 0.5 * reach[a]) / total;
            for u1 in [1e-9, 0.5, 1.0 - 1e-9] {
                for u0 in [1e-6, 0.5, 1.0 - 1e-9] {
                    let s = t.sample([u0, u1, u2]);
                    let table = TABLE_SHARE / t.mean * s.w.z * FRAC_1_PI;
                    assert!(
                        s.pdf >= table,
                        "bin {a}, u1 {u1}, u0 {u0}: {} < {table}",
                        s.pdf
                    );
                }
            }
        }
    }
}
