//! Pearson chi-square goodness-of-fit tests of the direction samplers (and
//! of the raw uniforms) against their analytic densities, in the manner of
//! the chi-square tests of Mitsuba / pbrt-v4: histogram many samples on a
//! (θ, φ) grid, compare with the pdf integrated over each cell, pool cells
//! with expected count < 5, and reject at a Šidák-corrected level.
//!
//! All tests use fixed Philox4x32 seeds, so they are deterministic.

use core::f64::consts::{FRAC_PI_2, PI, TAU};
use glam::DVec3;

mod common;
use common::chi2_pvalue;
use lumest::sampling::Philox4x32;
use lumest::sampling::warp::{
    cardioid_sphere_pdf, cosine_hemisphere_pdf, sample_cardioid_sphere, sample_cosine_hemisphere,
    sample_uniform_sphere, uniform_sphere_pdf,
};

/// Family-wise significance level of all chi-square tests in this file.
const ALPHA_FAMILY: f64 = 0.01;
/// Number of chi-square tests in this file (for the Šidák correction).
const NUM_TESTS: i32 = 5;
/// Samples per test.
const N_SAMPLES: usize = 1_000_000;
/// Seed shared by all tests; each test uses its own stream.
const SEED: u64 = 0x5EED_C412_2024_0001;

/// Per-test level `1 - (1 - α)^(1/m)` (Šidák 1967).
fn sidak_alpha() -> f64 {
    1.0 - (1.0 - ALPHA_FAMILY).powf(1.0 / f64::from(NUM_TESTS))
}

/// Composite Simpson rule with `m` (even) subintervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, m: usize) -> f64 {
    let h = (b - a) / m as f64;
    let mut s = f(a) + f(b);
    for i in 1..m {
        s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// Probability of each (θ, φ) cell of a `nt x np` grid on θ ∈ [0, θ_max],
/// φ ∈ [0, 2π) under a solid-angle density `pdf(w)`, by 2D Simpson
/// quadrature of `pdf(w(θ, φ)) sin θ` over each cell. Index `it * np + ip`.
fn cell_probabilities(
    pdf: impl Fn(DVec3) -> f64,
    theta_max: f64,
    nt: usize,
    np: usize,
) -> Vec<f64> {
    let (dt, dp) = (theta_max / nt as f64, TAU / np as f64);
    let mut p = Vec::with_capacity(nt * np);
    for it in 0..nt {
        for ip in 0..np {
            let (t0, p0) = (it as f64 * dt, ip as f64 * dp);
            let inner = |theta: f64| {
                let (st, ct) = theta.sin_cos();
                simpson(
                    |phi| {
                        let (sp, cp) = phi.sin_cos();
                        pdf(DVec3::new(st * cp, st * sp, ct)) * st
                    },
                    p0,
                    p0 + dp,
                    16,
                )
            };
            p.push(simpson(inner, t0, t0 + dt, 64));
        }
    }
    p
}

/// Histogram of directions on the (θ, φ) grid of [`cell_probabilities`].
fn histogram(ws: impl Iterator<Item = DVec3>, theta_max: f64, nt: usize, np: usize) -> Vec<f64> {
    let mut h = vec![0.0; nt * np];
    for w in ws {
        let theta = w.z.clamp(-1.0, 1.0).acos();
        let mut phi = w.y.atan2(w.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let it = ((theta / theta_max * nt as f64) as usize).min(nt - 1);
        let ip = ((phi / TAU * np as f64) as usize).min(np - 1);
        assert!(
            theta <= theta_max * (1.0 + 1e-12),
            "direction {w:?} outside the domain"
        );
        h[it * np + ip] += 1.0;
    }
    h
}

fn assert_passes(name: &str, observed: &[f64], probs: &[f64]) {
    let total: f64 = probs.iter().sum();
    assert!(
        (total - 1.0).abs() < 1e-9,
        "{name}: cell probabilities sum to {total}"
    );
    let n: f64 = observed.iter().sum();
    let expected: Vec<f64> = probs.iter().map(|p| p * n).collect();
    let (p, stat, dof) = chi2_pvalue(observed, &expected);
    let alpha = sidak_alpha();
    eprintln!("{name}: chi2 = {stat:.2}, dof = {dof}, p = {p:.4} (reject below {alpha:.5})");
    assert!(
        p > alpha,
        "{name}: chi-square test rejected (stat {stat}, dof {dof}, p {p})"
    );
}

#[test]
fn chi2_uniform_sphere() {
    let (nt, np) = (10, 20);
    let probs = cell_probabilities(|_| uniform_sphere_pdf(), PI, nt, np);
    // Closed form: (cos θ_a - cos θ_b) / 2 / np.
    for it in 0..nt {
        let (a, b) = (it as f64 * PI / nt as f64, (it + 1) as f64 * PI / nt as f64);
        let exact = (a.cos() - b.cos()) / 2.0 / np as f64;
        assert!((probs[it * np] - exact).abs() < 1e-10);
    }
    let mut rng = Philox4x32::new(SEED, 1);
    let mut moments = [0.0; 4]; // x, y, z, z²
    let ws = (0..N_SAMPLES).map(|_| {
        let ds = sample_uniform_sphere(rng.next_2d());
        assert_eq!(ds.pdf, uniform_sphere_pdf());
        moments[0] += ds.w.x;
        moments[1] += ds.w.y;
        moments[2] += ds.w.z;
        moments[3] += ds.w.z * ds.w.z;
        ds.w
    });
    let h = histogram(ws, PI, nt, np);
    assert_passes("uniform sphere", &h, &probs);

    // Moments, 5-sigma: E[x] = E[y] = E[z] = 0 (Var 1/3), E[z²] = 1/3 (Var 4/45).
    let n = N_SAMPLES as f64;
    for (k, (mean, var)) in [
        (0.0, 1.0 / 3.0),
        (0.0, 1.0 / 3.0),
        (0.0, 1.0 / 3.0),
        (1.0 / 3.0, 4.0 / 45.0),
    ]
    .into_iter()
    .enumerate()
    {
        let m = moments[k] / n;
        assert!(
            (m - mean).abs() < 5.0 * (var / n).sqrt(),
            "moment {k}: {m} vs {mean}"
        );
    }
}

#[test]
fn chi2_cardioid_sphere() {
    let (nt, np) = (10, 20);
    let probs = cell_probabilities(|w| cardioid_sphere_pdf(w.z), PI, nt, np);
    // Closed form: the distribution of cos θ is ((1 + c) / 2)^2.
    for it in 0..nt {
        let (a, b) = (it as f64 * PI / nt as f64, (it + 1) as f64 * PI / nt as f64);
        let cdf = |c: f64| (0.5 * (1.0 + c)).powi(2);
        let exact = (cdf(a.cos()) - cdf(b.cos())) / np as f64;
        assert!((probs[it * np] - exact).abs() < 1e-10);
    }
    let mut rng = Philox4x32::new(SEED, 5);
    let mut mz = 0.0;
    let ws = (0..N_SAMPLES).map(|_| {
        let ds = sample_cardioid_sphere(rng.next_2d());
        assert!((ds.pdf - cardioid_sphere_pdf(ds.w.z)).abs() < 1e-15);
        mz += ds.w.z;
        ds.w
    });
    let h = histogram(ws, PI, nt, np);
    assert_passes("cardioid sphere", &h, &probs);
    // E[z] = 1/3, Var z = E[z^2] - 1/9 = 1/3 - 1/9 = 2/9; 5 sigma.
    let n = N_SAMPLES as f64;
    assert!(
        (mz / n - 1.0 / 3.0).abs() < 5.0 * (2.0 / 9.0 / n).sqrt(),
        "{}",
        mz / n
    );
}

#[test]
fn chi2_cosine_hemisphere() {
    let (nt, np) = (10, 20);
    let probs = cell_probabilities(|w| cosine_hemisphere_pdf(w.z), FRAC_PI_2, nt, np);
    // Closed form: (sin² θ_b - sin² θ_a) / np.
    for it in 0..nt {
        let (a, b) = (
            it as f64 * FRAC_PI_2 / nt as f64,
            (it + 1) as f64 * FRAC_PI_2 / nt as f64,
        );
        let exact = (b.sin().powi(2) - a.sin().powi(2)) / np as f64;
        assert!((probs[it * np] - exact).abs() < 1e-10);
    }
    let mut rng = Philox4x32::new(SEED, 2);
    let mut moments = [0.0; 4]; // x, y, z, z²
    let ws = (0..N_SAMPLES).map(|_| {
        let ds = sample_cosine_hemisphere(rng.next_2d());
        assert!(ds.w.z >= 0.0);
        assert!((ds.pdf - cosine_hemisphere_pdf(ds.w.z)).abs() < 1e-15);
        moments[0] += ds.w.x;
        moments[1] += ds.w.y;
        moments[2] += ds.w.z;
        moments[3] += ds.w.z * ds.w.z;
        ds.w
    });
    let h = histogram(ws, FRAC_PI_2, nt, np);
    assert_passes("cosine hemisphere", &h, &probs);

    // Moments, 5-sigma: E[x] = E[y] = 0 (Var 1/4), E[z] = 2/3 (Var 1/18),
    // E[z²] = 1/2 (Var 1/12).
    let n = N_SAMPLES as f64;
    for (k, (mean, var)) in [
        (0.0, 0.25),
        (0.0, 0.25),
        (2.0 / 3.0, 1.0 / 18.0),
        (0.5, 1.0 / 12.0),
    ]
    .into_iter()
    .enumerate()
    {
        let m = moments[k] / n;
        assert!(
            (m - mean).abs() < 5.0 * (var / n).sqrt(),
            "moment {k}: {m} vs {mean}"
        );
    }
}

#[test]
fn chi2_next_f64_uniform() {
    let bins = 200;
    let mut rng = Philox4x32::new(SEED, 3);
    let mut h = vec![0.0; bins];
    for _ in 0..N_SAMPLES {
        h[(rng.next_f64() * bins as f64) as usize] += 1.0;
    }
    assert_passes("next_f64", &h, &vec![1.0 / bins as f64; bins]);
}

#[test]
fn chi2_next_2d_pairs_uniform() {
    // Successive pairs (as consumed by the warps) on a 20 x 20 grid: catches
    // correlation between consecutive draws within and across blocks.
    let k = 20;
    let mut rng = Philox4x32::new(SEED, 4);
    let mut h = vec![0.0; k * k];
    for _ in 0..N_SAMPLES {
        let [a, b] = rng.next_2d();
        h[(a * k as f64) as usize * k + (b * k as f64) as usize] += 1.0;
    }
    assert_passes("next_2d pairs", &h, &vec![1.0 / (k * k) as f64; k * k]);
}

#[test]
fn pooling_and_pvalue_sanity() {
    // A perfect fit has p = 1; a grossly wrong one has p ~ 0.
    let e = [100.0, 100.0, 1.0, 2.0, 3.0];
    let (p, stat, dof) = chi2_pvalue(&e, &e);
    assert_eq!((stat, dof), (0.0, 2)); // the three small cells pooled into one
    assert!((p - 1.0).abs() < 1e-12);
    let (p, _, _) = chi2_pvalue(&[150.0, 50.0, 6.0], &[100.0, 100.0, 6.0]);
    assert!(p < 1e-10);
}

#[test]
fn chi2_has_power_against_a_nearby_density() {
    // Harness sanity: cosine-hemisphere samples tested against the slightly
    // different lobe (n + 1)/(2π) cos^n θ with n = 1.05 must be rejected.
    let (nt, np, n_exp) = (10, 20, 1.05_f64);
    let probs = cell_probabilities(
        |w| (n_exp + 1.0) / TAU * w.z.max(0.0).powf(n_exp),
        FRAC_PI_2,
        nt,
        np,
    );
    let mut rng = Philox4x32::new(SEED, 5);
    let ws = (0..N_SAMPLES).map(|_| sample_cosine_hemisphere(rng.next_2d()).w);
    let h = histogram(ws, FRAC_PI_2, nt, np);
    let n: f64 = h.iter().sum();
    let expected: Vec<f64> = probs.iter().map(|p| p * n).collect();
    let (p, stat, dof) = chi2_pvalue(&h, &expected);
    eprintln!("power check: chi2 = {stat:.2}, dof = {dof}, p = {p:.3e}");
    assert!(p < 1e-6, "failed to reject a wrong density (p = {p})");
}
