//! Bounds of the statistical checks (VOV, FOM stability, heavy tail) at a
//! false-alarm rate per *run*, not per receiver.
//!
//! A run of `m` receivers checks each of them. At a fixed level per
//! receiver the flags of a sound run grow with `m`: at 0.1 % per check,
//! 10,000 Sobolev points carried 1 to 125 flags in 7 of 10 runs (seeds
//! 1-10, `--rms-error 1e-3`), and the summary read "statistical checks
//! FAILED" on a textbook case. Here each bound is the quantile of its
//! statistic for normal batch means at the per-receiver level
//! `a = 1 - (1 - alpha)^(1/m)` (Sidak; conservative for receivers that
//! share chains), with `alpha` = [`FALSE_ALARM`] per check and run. A flag
//! then says that something is wrong with the receiver, not that it drew
//! the short straw among many.
//!
//! - **Heavy tail**: the largest `|x_b - m| / s` of `B` batch means is
//!   Grubbs' statistic `G`; its critical value at level `a` (two-sided) is
//!   `G_a = (B - 1) / sqrt(B) sqrt(t^2 / (B - 2 + t^2))` with `t` the upper
//!   `a / (2B)` quantile of Student's t with `B - 2` degrees of freedom
//!   (Grubbs 1969; exact to the Bonferroni step).
//! - **FOM stability**: with `s_h^2` from the first `B_h` batches and `s^2`
//!   from all `B`, `(B - 1) s^2 = sigma^2 (X_1 + X_2)` with `X_1 = (B_h - 1)
//!   s_h^2 / sigma^2 ~ chi^2(B_h - 1)` and `X_2 ~ chi^2(B - B_h)`
//!   independent (the later batches' spread and the shift of their mean), so
//!   the ratio `FOM(B_h) / FOM(B) = (R^2 B) / (R_h^2 B_h) = (s^2 / s_h^2)
//!   (m_h / m)^2`. Its variance part is `(B_h - 1) / ((B - 1) Y)` with `Y =
//!   X_1 / (X_1 + X_2) ~ Beta((B_h - 1) / 2, (B - B_h) / 2)`; its means'
//!   part has `ln (m_h / m)^2 ~ N(0, 4 R^2 (B / B_h - 1))`, independent.
//!   The logarithms of the two parts' two-sided quantiles at level `a` join
//!   in quadrature (as for two normal parts), and the range is widened to
//!   at least `[0.5, 2]` (a FOM that changed by less than a factor 2 is
//!   not worth a flag).
//! - **VOV**: `B VOV + 1` is the sample kurtosis `b_2` of the batch means;
//!   its upper quantile at level `a` by the normal approximation of
//!   Anscombe & Glynn (1983), inverted, and at least 0.1 (the transport
//!   codes' bound). Where the level lies beyond what `b_2` of `B` values
//!   can reach, no bound exists and the check is off: below 8 batches, and
//!   for many receivers at few batches (at 32 batches, beyond about 10^5
//!   receivers). The heavy-tail check still applies there, and a run of
//!   fewer than 32 batches is flagged `batches` whatever its VOV.

use statrs::distribution::{Beta, ContinuousCDF, Normal, StudentsT};
use std::cell::Cell;

/// False-alarm rate of each check per run (per tally of `m` receivers)
/// for normal batch means.
pub const FALSE_ALARM: f64 = 1e-3;

/// The bounds of the checks of one tally: `B` batches, the FOM snapshot at
/// `B_h` batches (if any), `m` receivers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckBounds {
    /// Largest trusted VOV (infinite: the check is off).
    pub vov: f64,
    /// Quantiles of the variance part of `FOM(B_h) / FOM(B)` at the level
    /// (`[0, inf]` without a snapshot); [`fom_bounds`] widens them by the
    /// means' part and to at least `[0.5, 2]`.
    pub fom: (f64, f64),
    /// The normal quantile of the means' part at the level (two-sided),
    /// for [`fom_bounds`].
    pub fom_mean_z: f64,
    /// Largest trusted `|x_b - m| / s`.
    pub deviation: f64,
}

impl CheckBounds {
    /// Bounds for `batches` batch means, a FOM snapshot at `half` batches,
    /// and `receivers` receivers checked in the run (at least 1), at
    /// [`FALSE_ALARM`] per check and run. Memoised for the last arguments
    /// (per thread): a run's receivers share them.
    pub fn new(batches: u64, half: Option<u64>, receivers: usize) -> Self {
        type Key = (u64, Option<u64>, usize);
        thread_local! {
            static LAST: Cell<Option<(Key, CheckBounds)>> = const { Cell::new(None) };
        }
        let key = (batches, half, receivers.max(1));
        if let Some((k, b)) = LAST.with(Cell::get)
            && k == key
        {
            return b;
        }
        let a = per_receiver_level(FALSE_ALARM, key.2);
        let b = Self {
            vov: vov_quantile(batches, a).max(0.1),
            fom: half.map_or((0.0, f64::INFINITY), |h| fom_quantiles(h, batches, a)),
            fom_mean_z: -Normal::standard().inverse_cdf(0.5 * a),
            deviation: grubbs_bound(batches, a),
        };
        LAST.with(|c| c.set(Some((key, b))));
        b
    }
}

/// Accepted range of the FOM ratio `(R^2 B) / (R_h^2 B_h)` of a receiver
/// whose relative error is `r` after `batches` batches, its snapshot at
/// `half` (module docs): the logarithms of the variance part's quantiles
/// `bounds.fom` joined in quadrature with the means' part's, `(m_h /
/// m)^2` with `ln (m_h / m)^2 ~ N(0, 4 r^2 (B / B_h - 1))` (the first
/// `B_h` batches' mean against all `B`, independent of the spreads for
/// normal batch means) at `bounds.fom_mean_z`: the quantile of a sum of
/// two independent normal parts; then widened to at least `[0.5, 2]`.
/// Without the means' part, receivers with `R` of 0.05 and 0.1 were
/// flagged 2.6 and 7.6 times as often as the level allows (simulated at
/// 2 %, 77 batches); with it, 0.9-1.1 times.
pub fn fom_bounds(bounds: &CheckBounds, r: f64, batches: u64, half: u64) -> (f64, f64) {
    let (lo, hi) = fom_range(bounds, r, batches, half);
    (lo.min(0.5), hi.max(2.0))
}

/// [`fom_bounds`] before the widening to `[0.5, 2]`: the quantiles of the
/// ratio at the bounds' level.
fn fom_range(bounds: &CheckBounds, r: f64, batches: u64, half: u64) -> (f64, f64) {
    let lever = (batches as f64 / half.max(1) as f64 - 1.0).max(0.0).sqrt();
    let means = bounds.fom_mean_z * 2.0 * r * lever;
    let (lo, hi) = bounds.fom;
    let join = |v: f64| (v * v + means * means).sqrt();
    ((-join(lo.ln())).exp(), join(hi.ln()).exp())
}

/// Level per receiver that keeps the rate `alpha` over `m` independent
/// receivers: `1 - (1 - alpha)^(1/m)` (Sidak).
pub fn per_receiver_level(alpha: f64, m: usize) -> f64 {
    -((-alpha).ln_1p() / m.max(1) as f64).exp_m1()
}

/// Critical value of Grubbs' statistic `max |x_b - m| / s` of `batches`
/// normal values at two-sided level `a` (module docs); infinite below 3
/// batches. Finite for any `batches >= 3` and `a > 0`, at most the largest
/// value the statistic can take, `(B - 1) / sqrt(B)`.
pub fn grubbs_bound(batches: u64, a: f64) -> f64 {
    if batches < 3 {
        return f64::INFINITY;
    }
    let n = batches as f64;
    let t = t_upper(n - 2.0, a / (2.0 * n));
    // (B - 1) / sqrt(B) sqrt(t^2 / (B - 2 + t^2)), written so that an
    // infinite t (a level below what f64 resolves) gives the limit.
    (n - 1.0) / n.sqrt() / (1.0 + (n - 2.0) / (t * t)).sqrt()
}

/// Degrees of freedom above which [`t_upper`] uses the Cornish-Fisher
/// expansion: statrs' `StudentsT::inverse_cdf` (AS 109 on the incomplete
/// beta ratio) never returns beyond about 1.4e7 (its start is clamped to
/// 0.9999 and the Newton step overflows), i.e. a run of 1.4e7 batches
/// (`--batch-size 1`) would hang in its checks.
const T_EXPANSION_DOF: f64 = 1e5;

/// Upper `p` quantile of Student's t with `dof` degrees of freedom, from
/// the lower tail (`1 - p` rounds to 1 below `p` = 1.1e-16, and loses
/// digits well before); above [`T_EXPANSION_DOF`] by the Cornish-Fisher
/// expansion in the normal quantile `z` (Abramowitz & Stegun 26.7.5, two
/// terms: the first one left out is below 1e-11 relative there for
/// `z < 10`; the test agrees with statrs to 2e-9 at 1e5 and 1e6).
fn t_upper(dof: f64, p: f64) -> f64 {
    if dof > T_EXPANSION_DOF {
        t_upper_expansion(dof, p)
    } else {
        -StudentsT::new(0.0, 1.0, dof)
            .expect("positive degrees of freedom")
            .inverse_cdf(p)
    }
}

/// The Cornish-Fisher expansion of [`t_upper`] for many degrees of freedom.
fn t_upper_expansion(dof: f64, p: f64) -> f64 {
    let z = -Normal::standard().inverse_cdf(p);
    let z2 = z * z;
    let g1 = (z2 + 1.0) * z / 4.0;
    let g2 = ((5.0 * z2 + 16.0) * z2 + 3.0) * z / 96.0;
    z + g1 / dof + g2 / (dof * dof)
}

/// The two-sided quantiles `(lower, upper)` at level `a` of `FOM(B_h) /
/// FOM(B)` for normal batch means, `B_h = half < B = batches` (module
/// docs); `(0, inf)` where no snapshot fits.
pub fn fom_quantiles(half: u64, batches: u64, a: f64) -> (f64, f64) {
    if half < 2 || batches <= half {
        return (0.0, f64::INFINITY);
    }
    let y =
        Beta::new(0.5 * (half - 1) as f64, 0.5 * (batches - half) as f64).expect("positive shapes");
    let scale = (half - 1) as f64 / (batches - 1) as f64;
    // The upper quantile of `Y` as 1 minus the lower one of `1 - Y ~
    // Beta(b, a)`, exact for tiny levels where `1 - a / 2` rounds to 1.
    let flipped =
        Beta::new(0.5 * (batches - half) as f64, 0.5 * (half - 1) as f64).expect("positive shapes");
    let y_lo = y.inverse_cdf(0.5 * a);
    let y_hi = 1.0 - flipped.inverse_cdf(0.5 * a);
    (scale / y_hi, scale / y_lo)
}

/// Upper quantile at level `a` of `VOV = (b_2 - 1) / B` for `batches`
/// normal values, by the Anscombe-Glynn approximation of the kurtosis
/// `b_2` (module docs); infinite (the check off) where the approximation
/// has no quantile that far out or puts it beyond the largest VOV of
/// `batches` values, or below 8 batches.
pub fn vov_quantile(batches: u64, a: f64) -> f64 {
    if batches < 8 {
        return f64::INFINITY;
    }
    let n = batches as f64;
    let mean = 3.0 * (n - 1.0) / (n + 1.0);
    let var = 24.0 * n * (n - 2.0) * (n - 3.0) / ((n + 1.0).powi(2) * (n + 3.0) * (n + 5.0));
    let beta1 = 6.0 * (n * n - 5.0 * n + 2.0) / ((n + 7.0) * (n + 9.0))
        * (6.0 * (n + 3.0) * (n + 5.0) / (n * (n - 2.0) * (n - 3.0))).sqrt();
    let big_a = 6.0 + 8.0 / beta1 * (2.0 / beta1 + (1.0 + 4.0 / (beta1 * beta1)).sqrt());
    // From the lower tail: `1 - a` loses digits for tiny `a`.
    let z = -Normal::standard().inverse_cdf(a);
    // Z = (1 - 2/(9A) - cbrt((1 - 2/A) / (1 + x sqrt(2/(A-4))))) / sqrt(2/(9A)).
    let t = 1.0 - 2.0 / (9.0 * big_a) - z * (2.0 / (9.0 * big_a)).sqrt();
    if t <= 0.0 {
        return f64::INFINITY;
    }
    let x = ((1.0 - 2.0 / big_a) / t.powi(3) - 1.0) / (2.0 / (big_a - 4.0)).sqrt();
    let b2 = mean + x * var.sqrt();
    // No VOV of `B` values exceeds one outlier's, `b_2 = (B^2 - 3B + 3) /
    // (B - 1)`: a quantile beyond it (the approximation's far tail, many
    // receivers and few batches) means the check cannot discriminate there.
    let b2_max = (n * n - 3.0 * n + 3.0) / (n - 1.0);
    if b2 >= b2_max {
        return f64::INFINITY;
    }
    (b2 - 1.0) / n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tally::Welford;

    fn normals(rng: &mut crate::sampling::Philox4x32, out: &mut [f64]) {
        for pair in out.chunks_mut(2) {
            let [u, v] = rng.next_2d();
            let r = (-2.0 * (1.0 - u).ln()).sqrt();
            let (s, c) = (std::f64::consts::TAU * v).sin_cos();
            pair[0] = r * c;
            if pair.len() > 1 {
                pair[1] = r * s;
            }
        }
    }

    /// Each quantile against simulated normal batch means at levels where
    /// a simulation resolves it: the fraction beyond it is the level.
    #[test]
    fn quantiles_match_simulated_normal_batch_means() {
        let mut rng = crate::sampling::Philox4x32::new(23, 0);
        let runs = 40_000;
        let (h, b) = (32u64, 77u64);
        let a = 0.02;
        let (lo, hi) = fom_quantiles(h, b, a);
        let g = grubbs_bound(b, a);
        let v = vov_quantile(b, a);
        let (mut fom_out, mut tail, mut vov) = (0, 0, 0);
        let mut x = vec![0.0; b as usize];
        for _ in 0..runs {
            normals(&mut rng, &mut x);
            let (mut first, mut all) = (Welford::new(), Welford::new());
            for (i, &xi) in x.iter().enumerate() {
                if i < h as usize {
                    first.push(xi);
                }
                all.push(xi);
            }
            let ratio = all.variance() / first.variance();
            fom_out += usize::from(!(lo..=hi).contains(&ratio));
            tail += usize::from(all.max_deviation() > g);
            vov += usize::from(all.vov() > v);
        }
        // 2 % of 40,000 = 800 +- 28 (Grubbs' Bonferroni step is exact to
        // within 0.01 % here); the Anscombe-Glynn approximation is close.
        let expect = a * runs as f64;
        eprintln!("FOM {fom_out} tail {tail} VOV {vov} of {expect}");
        assert!(
            (fom_out as f64 - expect).abs() < 4.0 * expect.sqrt(),
            "FOM {fom_out}"
        );
        assert!(
            (tail as f64 - expect).abs() < 4.0 * expect.sqrt(),
            "tail {tail}"
        );
        assert!(
            (vov as f64 - expect).abs() < 4.0 * expect.sqrt(),
            "VOV {vov}"
        );
    }

    /// The FOM ratio of receivers with a large relative error (R about
    /// 0.05 and 0.1 at 77 batches, snapshot at 32) and a small one: the
    /// means' part of the range keeps the flags at the level (2 % here),
    /// where the variance part alone flagged several times that (2.6 and
    /// 7.6 times).
    #[test]
    fn fom_range_holds_its_level_at_large_relative_errors() {
        let mut rng = crate::sampling::Philox4x32::new(37, 0);
        let a = 0.02;
        let bounds = CheckBounds {
            vov: f64::INFINITY,
            fom: fom_quantiles(32, 77, a),
            fom_mean_z: -Normal::standard().inverse_cdf(0.5 * a),
            deviation: f64::INFINITY,
        };
        let plain = fom_quantiles(32, 77, a);
        let runs = 40_000;
        let mut x = vec![0.0; 77];
        for r in [0.001, 0.05, 0.1] {
            let (mut flagged, mut flagged_plain) = (0, 0);
            for _ in 0..runs {
                normals(&mut rng, &mut x);
                let (mut first, mut all) = (Welford::new(), Welford::new());
                for (i, v) in x.iter_mut().enumerate() {
                    *v = 1.0 + r * 77f64.sqrt() * *v;
                    if i < 32 {
                        first.push(*v);
                    }
                    all.push(*v);
                }
                let rel = |w: &Welford| w.std_error() / w.mean();
                let ratio = (rel(&all).powi(2) * 77.0) / (rel(&first).powi(2) * 32.0);
                let (lo, hi) = fom_range(&bounds, rel(&all), 77, 32);
                flagged += usize::from(!(lo..=hi).contains(&ratio));
                flagged_plain += usize::from(!(plain.0..=plain.1).contains(&ratio));
            }
            let level = a * runs as f64;
            eprintln!("R {r}: {flagged} vs {flagged_plain} of level {level}");
            assert!(
                (flagged as f64 - level).abs() < 4.0 * level.sqrt(),
                "R {r}: {flagged} flagged, level {level}"
            );
            if r > 0.01 {
                assert!(
                    flagged_plain as f64 > 1.5 * level,
                    "R {r}: the variance part alone flagged only {flagged_plain}"
                );
            }
        }
    }

    /// The bounds a single receiver had before: 6 / 32 for the VOV at 32
    /// batches (the simulated 0.999 quantile), the Sidak normal bound for
    /// the deviation; and they grow with the receivers.
    #[test]
    fn bounds_grow_with_the_receivers() {
        let one = CheckBounds::new(32, None, 1);
        assert!((one.vov - 6.0 / 32.0).abs() < 0.02, "{}", one.vov);
        let many = CheckBounds::new(32, None, 10_000);
        assert!(many.vov > one.vov && many.deviation > one.deviation);
        let fom1 = fom_bounds(&CheckBounds::new(77, Some(32), 1), 0.0, 77, 32);
        let fom_m = fom_bounds(&CheckBounds::new(77, Some(32), 10_000), 0.0, 77, 32);
        assert!(fom_m.1 > fom1.1 && fom_m.0 == 0.5, "{fom_m:?}");
        // The means' part widens the range with the relative error.
        let c = CheckBounds::new(77, Some(32), 10_000);
        let wide = fom_bounds(&c, 0.05, 77, 32);
        assert!(wide.1 > fom_m.1 && wide.0 < 0.5, "{wide:?}");
        assert_eq!(fom_bounds(&c, 1e-300, 77, 32), fom_m);
        assert!((per_receiver_level(1e-3, 1) - 1e-3).abs() < 1e-15);
        assert!((per_receiver_level(1e-3, 1000) - 1.0005e-6).abs() < 1e-9);
        // Tiny levels (10^12 receivers) and long runs: finite bounds that
        // grow with the receivers, below what the statistics can reach
        // (`1 - p` would round to 1 there: infinite quantiles, NaN bounds).
        for b in [32u64, 500, 1003, 5000, 100_000] {
            let mut last = CheckBounds::new(b, Some(b / 2), 1);
            for m in [1e3, 1e6, 1e9, 1e12] {
                let c = CheckBounds::new(b, Some(b / 2), m as usize);
                let (n, max_g) = (b as f64, (b as f64 - 1.0) / (b as f64).sqrt());
                assert!(
                    c.deviation.is_finite() && c.deviation < max_g,
                    "{b} {m}: {c:?}"
                );
                assert!(c.deviation > last.deviation, "{b} {m}: {c:?}");
                assert!(c.fom.0 > 0.0 && c.fom.1.is_finite(), "{b} {m}: {c:?}");
                assert!(
                    c.fom.1 >= last.fom.1 && c.fom.0 <= last.fom.0,
                    "{b} {m}: {c:?}"
                );
                assert!(!c.vov.is_nan() && c.vov >= last.vov, "{b} {m}: {c:?}");
                // The largest VOV of B values is (b2_max - 1) / B.
                let vov_max = ((n * n - 3.0 * n + 3.0) / (n - 1.0) - 1.0) / n;
                assert!(c.vov < vov_max || c.vov.is_infinite(), "{b} {m}: {c:?}");
                last = c;
            }
        }
    }

    /// The FOM quantiles against the closed forms of their Beta law where it
    /// has one: `B_h = 3` makes the first shape 1, `Y ~ Beta(1, b)` with
    /// quantile `1 - (1 - p)^(1/b)` (`B = 5`: uniform). A swapped shape, a
    /// scale `B_h / B` or a one-sided level miss them (the simulation test
    /// cannot resolve a 2 % shift of the scale).
    #[test]
    fn fom_quantiles_match_closed_forms() {
        for (h, b) in [(3u64, 5u64), (3, 9), (3, 40)] {
            let shape_b = 0.5 * (b - h) as f64;
            let scale = 2.0 / (b - 1) as f64;
            for a in [0.02, 1e-6] {
                let q = |p: f64| 1.0 - (1.0 - p).powf(1.0 / shape_b);
                let want = (scale / q(1.0 - 0.5 * a), scale / q(0.5 * a));
                let got = fom_quantiles(h, b, a);
                let close = |x: f64, y: f64| (x - y).abs() < 1e-6 * y;
                assert!(
                    close(got.0, want.0) && close(got.1, want.1),
                    "B_h {h} B {b} a {a}: {got:?} against {want:?}"
                );
            }
        }
    }

    /// Grubbs' critical values against the published two-sided 5 % table
    /// (n = 10: 2.290, 20: 2.709, 30: 2.908, 100: 3.384): wrong degrees of
    /// freedom (`B` or `B - 1`) or a one-sided level miss them by 0.5 % and
    /// more.
    #[test]
    fn grubbs_bound_matches_the_table() {
        for (n, g) in [(10, 2.290), (20, 2.709), (30, 2.908), (100, 3.384)] {
            let v = grubbs_bound(n, 0.05);
            assert!((v - g).abs() < 1.5e-3, "n {n}: {v} against {g}");
        }
    }

    /// Runs of many batches and many receivers: every bound is a number (a
    /// NaN bound passed every tail), at most the largest deviation `B`
    /// values allow, growing with the receivers, and computed at all: at
    /// 1.4e7 batches and more statrs' t quantile never returned, so each
    /// size runs on its own thread with a deadline. The t quantile's
    /// expansion above 1e5 degrees of freedom agrees with statrs' below.
    #[test]
    fn bounds_of_huge_runs_are_finite_and_computed() {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for b in [
                3u64,
                8,
                32,
                77,
                1000,
                100_001,
                1_000_000,
                14_000_000,
                30_000_000,
                1 << 40,
            ] {
                let mut last = 0.0;
                for m in [1usize, 10_000, 10_000_000, 1 << 40] {
                    let c = CheckBounds::new(b, (b >= 64).then_some(b / 4), m);
                    tx.send(Some((b, m, c, last))).unwrap();
                    last = c.deviation;
                }
            }
            tx.send(None).unwrap();
        });
        while let Some((b, m, c, last)) = rx
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("a bound took more than 20 s")
        {
            let n = b as f64;
            let most = (n - 1.0) / n.sqrt();
            assert!(
                c.deviation >= last && c.deviation <= most,
                "B {b} m {m}: {c:?} (before {last})"
            );
            assert!(
                !c.vov.is_nan() && c.vov >= 0.1 || b < 8,
                "B {b} m {m}: {c:?}"
            );
            assert!(!c.fom.0.is_nan() && !c.fom.1.is_nan(), "B {b} m {m}: {c:?}");
        }
        for p in [1e-3, 1e-9, 1e-14] {
            for dof in [T_EXPANSION_DOF, 1e6] {
                let s = -StudentsT::new(0.0, 1.0, dof).unwrap().inverse_cdf(p);
                let e = t_upper_expansion(dof, p);
                assert!((e - s).abs() < 2e-9 * s, "dof {dof} p {p}: {e} {s}");
            }
        }
    }

    /// Checks of one receiver from its batch means, the FOM snapshot at 32.
    fn flags(x: &[f64], receivers: usize) -> String {
        let (mut first, mut all) = (Welford::new(), Welford::new());
        for (i, &xi) in x.iter().enumerate() {
            if i < 32 {
                first.push(xi);
            }
            all.push(xi);
        }
        let r2b_h = (first.std_error() / first.mean()).powi(2) * 32.0;
        crate::tally::Diagnostics::of(&all, 0.0, Some((32, r2b_h)), receivers).flag()
    }

    /// Sound runs of 500 independent receivers with 77 normal batch means
    /// each: at most 0.3 % of runs carry a flag (three checks at 0.1 %).
    #[test]
    fn sound_runs_of_many_receivers_are_rarely_flagged() {
        let mut rng = crate::sampling::Philox4x32::new(29, 0);
        let (runs, m) = (200, 500);
        let mut x = vec![0.0; 77];
        let mut flagged_runs = 0;
        let mut flagged_points = 0;
        for _ in 0..runs {
            let mut any = false;
            for _ in 0..m {
                normals(&mut rng, &mut x);
                x.iter_mut().for_each(|v| *v += 100.0);
                if flags(&x, m) != "ok" {
                    any = true;
                    flagged_points += 1;
                }
            }
            flagged_runs += usize::from(any);
        }
        assert!(flagged_runs <= 3, "{flagged_runs} of {runs} runs flagged");
        // The per-receiver rate the bounds replaced (about 0.1 %, 11 of
        // 10,000 here) would have flagged about 40 % of these runs: the
        // test tells the two apart.
        let mut per_point = 0;
        for _ in 0..runs * m / 10 {
            normals(&mut rng, &mut x);
            x.iter_mut().for_each(|v| *v += 100.0);
            per_point += usize::from(flags(&x, 1) != "ok");
        }
        let p = per_point as f64 / (runs * m / 10) as f64;
        let old_runs = runs as f64 * (1.0 - (1.0 - p).powi(m as i32));
        eprintln!(
            "{flagged_points} points in {flagged_runs} runs; {per_point} alone: {old_runs:.0} runs"
        );
        assert!(old_runs >= 30.0, "{per_point} alone: {old_runs} runs");
    }

    /// Receivers whose batch means are means of 256 draws of an infinite-
    /// variance Pareto law (tail exponent 1.2), the heavy tail the checks
    /// exist for: most are still flagged among 10,000 receivers.
    #[test]
    fn heavy_tails_are_flagged_among_many_receivers() {
        let mut rng = crate::sampling::Philox4x32::new(31, 0);
        let tallies = 200;
        let mut x = vec![0.0; 77];
        let (mut one, mut many) = (0, 0);
        for _ in 0..tallies {
            for xb in x.iter_mut() {
                *xb = (0..128)
                    .map(|_| {
                        let [u, v] = rng.next_2d();
                        (1.0 - u).powf(-1.0 / 1.2) + (1.0 - v).powf(-1.0 / 1.2)
                    })
                    .sum::<f64>()
                    / 256.0;
            }
            one += usize::from(flags(&x, 1) != "ok");
            many += usize::from(flags(&x, 10_000) != "ok");
        }
        eprintln!("heavy tail flagged: {one} of {tallies} alone, {many} among 10,000");
        assert!(many >= tallies / 2, "{many} of {tallies}");
    }
}
