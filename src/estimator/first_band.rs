//! The first direction of an illuminance point's near paths drawn in
//! strata of its cosine lobe, graded in `cos^2 theta` from the grazing
//! directions up, each stratum holding a fixed number of the point's paths
//! in every batch.
//!
//! **Why.** A near path scores the light of the surfaces its first segment
//! meets within the split radius `R`; what lies farther comes from the
//! chains' collisions. For a point at a small distance `h` from a surface
//! it faces, the first segment leaves the radius only in the grazing
//! directions `cos^2 theta < (h / R)^2` (`h^2 / (h^2 + R^2)`, exactly, for a
//! plane): with `h = 1 mm` and `R = 0.1 m` one path in 10^4. Where the
//! surface is evenly lit (the sun on the ground) every other path brings
//! the same value, so a run that sees no escape reads the near part `1 /
//! (1 - p)` too high with an error bar of nearly nothing: reviewers
//! measured 95 % intervals covering 0-25 % of runs 1e-5-1e-3 m above a lit
//! floor (z up to 244, flagged `ok`), the excess the far part's share `p`.
//! Under a lamp the same holds for the floor's falloff over the distance
//! `h tan theta` a path reaches, spread over every decade of `cos^2 theta`
//! (0.1 mm above the floor under a lamp: 1e-7 high on most runs, mean z^2
//! 9).
//!
//! **How.** Stratified sampling. The grazing stratum is `cos^2 theta <
//! width`, `width` twice the escape share the probes suggest (so an
//! escape is about one of its paths in two, [`GRAZE`]), then one up to
//! eight times the share, then strata eight times wider each up to the top
//! one, which ends at 1 ([`edge_above`]); half the paths are shared
//! equally by the strata below the top (at least one each), the top keeps
//! the rest. Each path is drawn from the cosine restricted to its stratum
//! and weighted `cos / p(w)`, `p` the density of the directions of the
//! receiver's paths taken together ([`FirstBand::pdf`]: stratum `k` holds
//! `n_k` of the `n` paths and spans `[c_k, c_k+1)`, so `p = n_k cos / (n pi
//! (c_k+1 - c_k))` there), and every path weighs alike in the batch. The
//! light-guided connection at the receiver combines with that same density
//! (the balance heuristic over the batch's samples, Veach's multi-sample
//! model), so the sum stays unbiased whatever the strata; they decide the
//! variance only. Measured (40 seeds, 20,000 chains; points facing down
//! under a 1000 cd lamp 1 m up, over a floor of reflectance 0.5): coverage
//! 0.88-1.0 and mean z^2 0.9-1.3 at 0.1 mm-1 cm, against 0.15-0.55 and
//! 5-230 before; over a sunlit ground at 1e-5-3e-4 m 0.95-1.0 against
//! 0-0.2.
//!
//! **Where.** Only where the escapes matter: all 64 probes meet a surface
//! within the radius (escapes are rare), the escape share times [`RATIO`]
//! is at most [`MAX_WIDTH`], and the near paths' values are steady
//! ([`STEADY`]: the pilot's relative variance per path). Where they are
//! noisy anyway (multi-bounce light in a dark gap, or a room's
//! interreflections joined from the pool), the escapes' share is far
//! below an error bar that holds them, and the strata only cost variance:
//! points 1 mm off the cabinet's back in the 5 cm gap behind it read 4-7
//! times the variance (a reviewer's find). The office's 506 grid points
//! take none (same bytes).

use crate::sampling::warp::{Frame, sin_cos_turns};
use crate::scene::Scene;
use glam::DVec3;
use std::f64::consts::PI;

/// Ratio of consecutive stratum edges in `cos^2 theta`.
const RATIO: f64 = 8.0;
/// The grazing stratum's width as a multiple of the escape share the
/// probes suggest: about every second of its paths escapes the radius, so
/// that even a short run sees many (at 8, one in eight: a run of 2000
/// chains, 32 grazing paths, saw none 1.4 % of the time and read the far
/// part's share twice with an error bar that missed it, z 11-22 flagged
/// `ok` over 40-80 seeds 1e-5-1e-3 m above a lit floor; at 2, mean z^2
/// 0.6-1.4 there at 2000 and 20,000 chains, the error bars 1.8-3.4 times
/// smaller under the lamp and the sun, within 11 % 1 m off the lamp's
/// axis). The stratum above it ends at [`RATIO`] times the share, where the
/// strata ended before: narrowing the grazing stratum alone widened the
/// strata above it, whose few paths then spanned a third of the lobe
/// (variance up 1.4-2 times, a `tail` flag 1 mm above a Sobolev floor).
const GRAZE: f64 = 2.0;
/// Share of the paths drawn in the strata below the top one, equally: the
/// light of a point facing an evenly lit surface varies alike in every
/// stratum (the surface's illuminance over the distance `h tan theta`
/// reached, escapes in the grazing one), and elsewhere the top stratum,
/// the bulk of the lobe, keeps half the paths.
const GRAZING_SHARE: f64 = 0.5;
/// Largest escape share times [`RATIO`] (in `cos^2 theta`): above it
/// escapes beyond the radius are common enough (`(h / R)^2` above 1/64) to
/// be seen by the plain cosine, and no strata are drawn. (At 1/512 a point
/// 2 cm above a sunlit ground, `(h / R)^2` about 0.003, kept the plain
/// cosine: z up to 35 over 30 runs of 4096 chains, mean z^2 101.)
const MAX_WIDTH: f64 = 0.125;
/// Largest variance of one near path's value relative to `E^2` (the
/// pilot's, [`crate::estimator::near_paths`]) at which the strata are
/// drawn. The rare escapes matter where the paths' values are steady (a
/// lit surface faced, its light direct: a lamp or the sun over a floor);
/// where they are noisy anyway (the dark gap behind the office's cabinet,
/// multi-bounce light), the escapes add little to an error bar that holds
/// them, and the strata cost 4-7 times the variance there (a reviewer's
/// find: one run 6 standard errors low, flagged `ok`).
pub const STEADY: f64 = 0.01;
/// Probes over the point's hemisphere.
const PROBES: usize = 64;

/// The strata of one path's first direction (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstBand {
    /// The grazing stratum's upper edge in `cos^2 theta`; the edges are `0,
    /// width, 8 width, 64 width, ...` up to 1.
    pub width: f64,
    /// Strata (at least 2), and the receiver's paths in the batch, path
    /// `s` drawn in stratum `s % strata`.
    pub strata: u32,
    pub paths: u64,
    /// This path's stratum.
    pub index: u32,
}

impl FirstBand {
    /// Strata for the grazing width `width` with `paths` paths in a batch
    /// (at least 2): up to the edge past which the next would pass 1, as
    /// many as leave the top stratum a path ([`Self::count`]).
    pub fn strata(width: f64, paths: u64) -> u32 {
        let mut k = 2u32;
        while edge_above(width, k) < 1.0 && k < 64 {
            let next = FirstBand {
                width,
                strata: k + 1,
                paths,
                index: 0,
            };
            if next.count(k) == 0 {
                break;
            }
            k += 1;
        }
        k
    }

    /// Lower and upper edge of stratum `k` in `cos^2 theta`.
    #[inline]
    fn edges(&self, k: u32) -> (f64, f64) {
        let edge = |i: u32| {
            if i == 0 {
                0.0
            } else if i >= self.strata {
                1.0
            } else {
                edge_above(self.width, i).min(1.0)
            }
        };
        (edge(k), edge(k + 1))
    }

    /// Paths of the batch drawn in stratum `k`: the strata below the top
    /// share [`GRAZING_SHARE`] of the paths equally (at least one each),
    /// the top stratum the rest (0 if none are left).
    #[inline]
    fn count(&self, k: u32) -> u64 {
        let lower =
            ((self.paths as f64 * GRAZING_SHARE) as u64 / u64::from(self.strata - 1)).max(1);
        if k + 1 < self.strata {
            lower
        } else {
            self.paths
                .saturating_sub(lower * u64::from(self.strata - 1))
        }
    }

    /// The stratum of the batch's path `s` (the first [`Self::count`]`(0)`
    /// paths in stratum 0, and so on).
    pub fn stratum_of_path(&self, s: u64) -> u32 {
        let mut first = 0;
        for k in 0..self.strata {
            first += self.count(k);
            if s < first {
                return k;
            }
        }
        self.strata - 1
    }

    /// The stratum holding `cos^2 theta = c2`.
    #[inline]
    fn stratum_of(&self, c2: f64) -> u32 {
        let mut k = 0;
        while k + 1 < self.strata && c2 >= self.edges(k).1 {
            k += 1;
        }
        k
    }

    /// The density [1/sr] of the first directions of the receiver's paths
    /// taken together at the local direction `w` (module docs); 0 below
    /// the hemisphere.
    #[inline]
    pub fn pdf(&self, w: DVec3) -> f64 {
        let c = w.z;
        if c <= 0.0 {
            return 0.0;
        }
        let k = self.stratum_of(c * c);
        let (lo, hi) = self.edges(k);
        self.count(k) as f64 / self.paths as f64 * c / (PI * (hi - lo))
    }

    /// This path's first direction (local frame) from `u`, its weight `cos
    /// / pdf` and [`Self::pdf`] there.
    #[inline]
    pub fn sample(&self, u: [f64; 2]) -> (DVec3, f64, f64) {
        let (lo, hi) = self.edges(self.index);
        let c2 = (lo + (hi - lo) * u[0]).min(hi);
        let (sp, cp) = sin_cos_turns(u[1]);
        let s = (1.0 - c2).max(0.0).sqrt();
        let w = DVec3::new(s * cp, s * sp, c2.sqrt());
        let beta = PI * (hi - lo) * self.paths as f64 / self.count(self.index) as f64;
        (w, beta, self.pdf(w))
    }
}

/// Edge `i >= 1` of the strata in `cos^2 theta` for a grazing stratum
/// `width` wide: `width`, then [`RATIO`] times the escape share (`width
/// RATIO / GRAZE`), then [`RATIO`] times wider each.
#[inline]
fn edge_above(width: f64, i: u32) -> f64 {
    if i <= 1 {
        width
    } else {
        width * (RATIO / GRAZE) * RATIO.powi(i as i32 - 2)
    }
}

/// The grazing stratum's width for an illuminance point at `p` (normal
/// frame `frame`) whose near paths reach `radius` \[m\]: where all of 64
/// probes over its hemisphere (a cosine-distributed Fibonacci spiral) meet
/// a surface within the radius, escapes are rare, and the width is
/// [`GRAZE`] times `(h / radius)^2`, `h` the nearest probe hit (the escape
/// share of a point facing a plane); 0 (no strata) where some probe leaves
/// the radius, or [`RATIO`] times the share is above [`MAX_WIDTH`]
/// (escapes are common enough to be seen), or no width results.
pub fn band_width(scene: &Scene, p: DVec3, frame: &Frame, radius: f64) -> f64 {
    let mut nearest = f64::INFINITY;
    for k in 0..PROBES {
        let w = frame.to_world(super::probe_local(k, PROBES, false));
        match scene.first_hit_from(p, w) {
            Some(h) if h.t < radius => nearest = nearest.min(h.t),
            _ => return 0.0,
        }
    }
    let share = (nearest / radius).powi(2);
    let width = GRAZE * share;
    if width.is_finite() && width > 0.0 && RATIO * share <= MAX_WIDTH {
        width
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The strata's paths together draw the directions with
    /// [`FirstBand::pdf`], which integrates to 1; each path's weight is
    /// `cos / pdf`; the strata cover `[0, 1]` in `cos^2 theta`.
    #[test]
    fn strata_and_density_agree() {
        for (width, paths) in [
            (1e-6, 39),
            (0.01, 16),
            (0.125, 5),
            (1e-9, 3),
            (1e-9, 2),
            (1e-7, 1000),
        ] {
            let strata = FirstBand::strata(width, paths);
            assert!(strata >= 2 && u64::from(strata) <= paths.max(2));
            let band = |index| FirstBand {
                width,
                strata,
                paths,
                index,
            };
            assert_eq!(band(0).edges(0).0, 0.0);
            assert_eq!(band(0).edges(strata - 1).1, 1.0);
            let counts: u64 = (0..strata).map(|k| band(0).count(k)).sum();
            assert_eq!(counts, paths);
            assert!((0..strata).all(|k| band(0).count(k) >= 1));
            // int pdf dw over the hemisphere, by the midpoint rule in
            // cos^2 within each stratum (dw = pi d(cos^2) / cos).
            let m = 20_000;
            let mut total = 0.0;
            for k in 0..strata {
                let (lo, hi) = band(0).edges(k);
                for i in 0..m {
                    let c2 = lo + (hi - lo) * (i as f64 + 0.5) / m as f64;
                    let c = c2.sqrt();
                    let w = DVec3::new((1.0 - c2).sqrt(), 0.0, c);
                    total += band(0).pdf(w) * PI / c * (hi - lo) / m as f64;
                }
            }
            assert!((total - 1.0).abs() < 1e-9, "{width} {paths}: {total}");
            let mut rng = crate::sampling::Philox4x32::new(3, 0);
            // Each path's weight: beta = cos / pdf, its direction in its
            // stratum; over a batch's paths the weights sum to pi paths
            // (the cosine lobe's integral, pi, per path).
            let mut sum = 0.0;
            for s in 0..paths {
                let b = band(band(0).stratum_of_path(s));
                let (w, beta, pdf) = b.sample(rng.next_2d());
                assert!((w.length() - 1.0).abs() < 1e-12);
                assert_eq!(b.stratum_of(w.z * w.z), b.index);
                assert!(
                    (beta - w.z / pdf).abs() <= 1e-9 * beta,
                    "{beta} {}",
                    w.z / pdf
                );
                sum += beta;
            }
            assert!(
                (sum / paths as f64 - PI).abs() < 1e-9,
                "{}",
                sum / paths as f64
            );
        }
    }
}
