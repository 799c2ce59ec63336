//! The normalised modified Phong material (Lafortune and Willems 1994):
//! reciprocity, energy conservation, albedo against an independent
//! integration, the sampling density (integral, consistency with `pdf`,
//! Pearson chi-square goodness of fit in the style of
//! `tests/sampling_chi2.rs`), and the scene-file syntax with its errors.
//!
//! All random tests use fixed Philox4x32 seeds, so they are deterministic.

use core::f64::consts::{FRAC_PI_2, PI, TAU};
use glam::DVec3;

mod common;
use common::chi2_pvalue;
use lumest::material::Material;
use lumest::math::quadrature::panel;
use lumest::sampling::warp::sample_uniform_sphere;
use lumest::sampling::{Frame, Philox4x32};
use std::path::Path;

/// Seed shared by all tests; each test uses its own stream.
const SEED: u64 = 0x5EED_F0E6_1994_0001;
/// Family-wise significance level of the chi-square tests in this file.
const ALPHA_FAMILY: f64 = 0.01;
/// Number of chi-square goodness-of-fit tests (cases of
/// [`chi2_sample_matches_pdf`]), for the Šidák correction.
const NUM_CHI2_TESTS: i32 = 5;
/// Samples per chi-square test.
const N_SAMPLES: usize = 500_000;

fn phong(kd: f64, ks: f64, n: f64) -> Material {
    Material::Phong { kd, ks, n }
}

/// Unit vector with polar angle `theta` from +z and azimuth `phi`.
fn dir(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

fn mirror(wi: DVec3) -> DVec3 {
    DVec3::new(-wi.x, -wi.y, wi.z)
}

// ---------------------------------------------------------------- BRDF ----

#[test]
fn reciprocity_on_random_pairs() {
    let params = [
        (0.3, 0.2, 20.0),
        (0.0, 1.0, 0.0),
        (0.5, 0.5, 1.0),
        (0.1, 0.9, 1000.0),
        (0.2, 0.7, 3.7),
    ];
    let mut rng = Philox4x32::new(SEED, 1);
    for (kd, ks, n) in params {
        let m = phong(kd, ks, n);
        for k in 0..20_000 {
            let wi = sample_uniform_sphere(rng.next_2d()).w;
            // Half the pairs near the mirror direction, so sharp lobes are hit.
            let wo = if k % 2 == 0 {
                sample_uniform_sphere(rng.next_2d()).w
            } else {
                let jitter = sample_uniform_sphere(rng.next_2d()).w * 0.05;
                (mirror(wi) + jitter).normalize()
            };
            let (a, b) = (m.eval(wi, wo), m.eval(wo, wi));
            assert_eq!(a, b, "{kd} {ks} {n}: {wi:?} {wo:?}");
            assert!(a.is_finite() && a >= 0.0);
            if wi.z <= 0.0 || wo.z <= 0.0 {
                assert_eq!(a, 0.0);
            } else {
                assert!(a >= kd / PI);
            }
        }
    }
}

#[test]
fn brdf_formula_at_known_directions() {
    let (kd, ks, n) = (0.3, 0.2, 20.0);
    let m = phong(kd, ks, n);
    let wi = dir(0.5, 0.2);
    // Exactly in the mirror direction: cos alpha = 1.
    let f = m.eval(wi, mirror(wi));
    assert!((f - (kd / PI + ks * (n + 2.0) / TAU)).abs() < 1e-14);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-15;
    // 0.1 rad away from it, in the plane of incidence.
    let wo = dir(0.6, 0.2 + PI);
    let expect = kd / PI + ks * (n + 2.0) / TAU * 0.1_f64.cos().powf(n);
    assert!((m.eval(wi, wo) - expect).abs() < 1e-14);
    // More than 90 degrees from the mirror direction: diffuse only.
    assert!(close(m.eval(dir(1.2, 0.0), dir(1.2, 0.0)), kd / PI));
    assert_eq!(m.constant_brdf(), None);
}

// -------------------------------------------------------------- albedo ----

#[test]
fn albedo_at_most_one_over_a_grid_of_angles() {
    let mut thetas: Vec<f64> = (0..=180).map(|k| k as f64 * 0.5_f64.to_radians()).collect();
    thetas.extend([89.9, 89.999, 90.0 - 1e-9].map(f64::to_radians));
    for n in [0.0, 1.0, 20.0, 1000.0] {
        for (kd, ks) in [(0.0, 1.0), (0.5, 0.5), (0.9, 0.1), (1.0, 0.0), (0.3, 0.2)] {
            let m = phong(kd, ks, n);
            for &t in &thetas {
                let a = m.albedo(dir(t, 0.7));
                assert!(a <= 1.0, "kd {kd} ks {ks} n {n} theta {t}: albedo {a}");
                assert!(a <= kd + ks + 1e-15 && a >= kd, "{kd} {ks} {n} {t}: {a}");
            }
            // Normal incidence: the whole lobe is above the surface.
            assert!((m.albedo(DVec3::Z) - (kd + ks)).abs() < 1e-15);
            // Grazing and below: nothing (f = 0 for wi.z <= 0).
            assert_eq!(m.albedo(dir(FRAC_PI_2 + 0.1, 0.0)), 0.0);
        }
    }
}

/// Midpoint rule for `int_{S^2} g(w) dw` in polar coordinates `(alpha,
/// phi)` around the mirror direction `r` of `wi` (frame
/// [`Frame::from_normal`]`(r)`): `nt` cells in alpha on [0, pi], `2 nt` in
/// phi. The end of the specular lobe, `alpha = pi/2`, is a cell edge for
/// even `nt`, so the integrands below (BRDF times clamped cosine, or pdf)
/// are continuous inside every cell up to kinks (the horizon, and the lobe
/// end for n = 1), and the rule is second order.
fn midpoint_around_mirror(wi: DVec3, nt: usize, g: impl Fn(DVec3) -> f64) -> f64 {
    let frame = Frame::from_normal(mirror(wi));
    let (da, dp) = (PI / nt as f64, PI / nt as f64);
    let phis: Vec<(f64, f64)> = (0..2 * nt)
        .map(|j| ((j as f64 + 0.5) * dp).sin_cos())
        .collect();
    let mut sum = 0.0;
    for i in 0..nt {
        let (sa, ca) = ((i as f64 + 0.5) * da).sin_cos();
        let mut row = 0.0;
        for &(sp, cp) in &phis {
            row += g(frame.to_world(DVec3::new(sa * cp, sa * sp, ca)));
        }
        sum += row * sa;
    }
    sum * da * dp
}

/// Richardson extrapolation of a second-order rule from `coarse = M(2h)`
/// and `fine = M(h)`: with `M(h) = I + C h^2 + o(h^2)`, the extrapolated
/// value `R = fine + (fine - coarse)/3 = I + o(h^2)` and
/// `est = |fine - coarse|/3 ~ |C| h^2` is the size of the error of `fine`.
/// Returns `(R, est)`.
fn richardson(coarse: f64, fine: f64) -> (f64, f64) {
    (fine + (fine - coarse) / 3.0, (fine - coarse).abs() / 3.0)
}

/// [`richardson`] of [`midpoint_around_mirror`] on `nt/2` and `nt` grids.
fn midpoint_extrapolated(wi: DVec3, nt: usize, g: impl Fn(DVec3) -> f64) -> (f64, f64) {
    let coarse = midpoint_around_mirror(wi, nt / 2, &g);
    let fine = midpoint_around_mirror(wi, nt, &g);
    richardson(coarse, fine)
}

/// `Material::albedo` against an independent integration of
/// `int f(wi, wo) max(wo.z, 0) dwo`: the midpoint rule on 200 x 400 and
/// 400 x 800 grids around the mirror direction (second order, see
/// [`midpoint_around_mirror`]; h = 7.9e-3 rad, ~4 cells per width of the
/// n = 1000 lobe), extrapolated by [`richardson`]. Tolerance:
/// `|albedo - R| <= est + 1e-10`, i.e. the albedo must be closer to the
/// extrapolated limit than the finer grid's own error (`R` is accurate to
/// o(h^2), far below `est` for these integrands; observed
/// `|albedo - R| / est <= 0.25`, largest where the horizon kink crosses a
/// sharp lobe). For n = 0 the closed form `kd + ks (1 + cos theta)/2`
/// (derived in `phong_specular_albedo`) is checked too, to 1e-14.
#[test]
fn albedo_matches_independent_midpoint_integration() {
    let params = [
        (0.0, 1.0, 1.0),
        (0.0, 1.0, 20.0),
        (0.0, 1.0, 1000.0),
        (0.3, 0.2, 20.0),
        (0.5, 0.5, 0.0),
        (0.2, 0.8, 3.5),
    ];
    let mut worst_ratio: f64 = 0.0;
    for (kd, ks, n) in params {
        let m = phong(kd, ks, n);
        for deg in [0.0, 30.0, 60.0, 80.0, 89.0_f64] {
            let wi = dir(deg.to_radians(), 0.3);
            let a = m.albedo(wi);
            let (r, est) = midpoint_extrapolated(wi, 400, |w| m.eval(wi, w) * w.z.max(0.0));
            let err = (a - r).abs();
            eprintln!(
                "kd {kd} ks {ks} n {n} theta {deg}: albedo {a:.12} extrapolated midpoint \
                 {r:.12} |diff| {err:.2e}, error estimate of the fine grid {est:.2e}"
            );
            assert!(
                err <= est + 1e-10,
                "kd {kd} ks {ks} n {n} theta {deg}: {a} vs {r} (estimate {est:e})"
            );
            worst_ratio = worst_ratio.max(err / (est + 1e-300));
            if n == 0.0 {
                let exact = kd + ks * 0.5 * (1.0 + wi.z);
                assert!((a - exact).abs() < 1e-14, "{a} vs closed form {exact}");
            }
        }
    }
    eprintln!("worst |albedo - R| / est: {worst_ratio:.3}");
}

// ------------------------------------------------------------ sampling ----

/// Midpoint rule for `int_{theta < pi/2} pdf(wi, w) dw` on an
/// `nt x 2 nt` grid in the local (theta, phi), with `wi` in the xz-plane,
/// where the integrand is even in phi (half range, doubled).
fn above_horizon_midpoint(m: &Material, wi: DVec3, nt: usize) -> f64 {
    assert_eq!(wi.y, 0.0);
    let (dt, dp) = (FRAC_PI_2 / nt as f64, PI / (2 * nt) as f64);
    let phis: Vec<(f64, f64)> = (0..2 * nt)
        .map(|j| ((j as f64 + 0.5) * dp).sin_cos())
        .collect();
    let mut sum = 0.0;
    for i in 0..nt {
        let (st, ct) = ((i as f64 + 0.5) * dt).sin_cos();
        let mut row = 0.0;
        for &(sp, cp) in &phis {
            row += m.pdf(wi, DVec3::new(st * cp, st * sp, ct));
        }
        sum += row * st;
    }
    2.0 * sum * dt * dp
}

/// The pdf integrates to 1 over the sphere and to the probability of
/// landing above the horizon (<= 1) over `w.z > 0`; that probability
/// matches the fraction of `sample()` outputs with `w.z > 0` (binomial, 5
/// sigma); every sample carries `pdf == pdf(wi, w)`.
///
/// Integrals: the sphere by [`midpoint_extrapolated`] on 200 and 400
/// rings; the upper hemisphere by the midpoint rule in (theta, phi) on 200
/// and 400 rings, second order for n >= 1 (the integrand is smooth up to
/// kinks inside the hemisphere), extrapolated by [`richardson`]; tolerance
/// `est + 1e-10` as in the albedo test. For n = 0 the lobe is uniform on the
/// hemisphere around `r` and ends with a jump, so instead the exact value:
/// that hemisphere meets the upper one in a lune of area `2 (pi - theta_i)`,
/// so `P = P_d + (1 - P_d)(1 - theta_i / pi)`.
#[test]
fn pdf_integrates_to_above_horizon_probability_and_matches_samples() {
    let n_samples = 100_000;
    let mut rng = Philox4x32::new(SEED, 2);
    for (kd, ks, n) in [
        (0.3, 0.2, 20.0),
        (0.0, 1.0, 200.0),
        (0.5, 0.5, 0.0),
        (0.1, 0.9, 1.0),
    ] {
        let m = phong(kd, ks, n);
        for deg in [0.0, 45.0, 75.0, 88.0_f64] {
            let theta = deg.to_radians();
            let wi = dir(theta, 0.0);
            let (sphere, est) = midpoint_extrapolated(wi, 400, |w| m.pdf(wi, w));
            assert!(
                (sphere - 1.0).abs() <= est + 1e-10,
                "{kd} {ks} {n} {deg}: int_S2 pdf = {sphere} (estimate {est:e})"
            );
            let (above, tol) = if n == 0.0 {
                let pd = kd / (kd + ks);
                (pd + (1.0 - pd) * (1.0 - theta / PI), 1e-15)
            } else {
                let (r, est) = richardson(
                    above_horizon_midpoint(&m, wi, 200),
                    above_horizon_midpoint(&m, wi, 400),
                );
                (r, est + 1e-10)
            };
            assert!(above <= 1.0 + tol, "{kd} {ks} {n} {deg}: {above}");
            let mut hits = 0usize;
            // A direction in a general azimuth, to exercise the frame too.
            let wi_rot = dir(theta, 1.1);
            for _ in 0..n_samples {
                let s = m.sample(wi_rot, rng.next_2d());
                assert!((s.w.length() - 1.0).abs() < 1e-14);
                assert!(s.pdf.is_finite() && s.pdf >= 0.0);
                assert_eq!(s.pdf, m.pdf(wi_rot, s.w));
                if s.w.z > 0.0 {
                    hits += 1;
                }
            }
            let frac = hits as f64 / n_samples as f64;
            let p = above.clamp(0.0, 1.0);
            let sigma = (p * (1.0 - p) / n_samples as f64).sqrt();
            eprintln!(
                "kd {kd} ks {ks} n {n} theta {deg}: int_S2 pdf {sphere:.8}, \
                 int_H+ pdf {above:.8} (tol {tol:.1e}), sampled fraction above {frac:.6}"
            );
            assert!(
                (frac - above).abs() <= 5.0 * sigma + tol,
                "{kd} {ks} {n} {deg}: fraction {frac} vs {above}"
            );
        }
    }
}

/// Per-test level `1 - (1 - alpha)^(1/m)` (Šidák 1967).
fn sidak_alpha() -> f64 {
    1.0 - (1.0 - ALPHA_FAMILY).powf(1.0 / f64::from(NUM_CHI2_TESTS))
}

/// Cells in polar coordinates `(alpha, phi)` around the mirror direction
/// `r` of `wi` (frame [`Frame::from_normal`]`(r)`), covering the whole
/// sphere: alpha edges `(pi/2) (k/20)^2` on [0, pi/2] (graded so that a
/// sharp lobe spans several rings; `alpha = pi/2`, where the n = 0 lobe
/// ends, is an edge) and 8 equal rings on [pi/2, pi]; 16 phi sectors.
struct LobeGrid {
    frame: Frame,
    edges: Vec<f64>,
    np: usize,
}

impl LobeGrid {
    fn new(wi: DVec3) -> Self {
        let mut edges: Vec<f64> = (0..=20)
            .map(|k| FRAC_PI_2 * (k as f64 / 20.0).powi(2))
            .collect();
        edges.extend((1..=8).map(|k| FRAC_PI_2 + FRAC_PI_2 * k as f64 / 8.0));
        Self {
            frame: Frame::from_normal(mirror(wi)),
            edges,
            np: 16,
        }
    }

    fn cells(&self) -> usize {
        (self.edges.len() - 1) * self.np
    }

    /// Probability of each cell under `pdf(w)`, by a 20 x 20-point
    /// Gauss-Legendre product rule of `pdf sin(alpha)` per cell (an open
    /// rule: the n = 0 lobe's jump at the cell edge `alpha = pi/2` is never
    /// evaluated).
    fn probabilities(&self, pdf: impl Fn(DVec3) -> f64) -> Vec<f64> {
        let dp = TAU / self.np as f64;
        let mut p = Vec::with_capacity(self.cells());
        for ring in self.edges.windows(2) {
            for ip in 0..self.np {
                let p0 = ip as f64 * dp;
                let inner = |a: f64| {
                    panel(
                        &|phi| pdf(self.frame.to_world(dir(a, phi))) * a.sin(),
                        p0,
                        p0 + dp,
                    )
                };
                p.push(panel(&inner, ring[0], ring[1]));
            }
        }
        p
    }

    fn histogram(&self, ws: impl Iterator<Item = DVec3>) -> Vec<f64> {
        let mut h = vec![0.0; self.cells()];
        for w in ws {
            let l = self.frame.to_local(w);
            let a = l.z.clamp(-1.0, 1.0).acos();
            let mut phi = l.y.atan2(l.x);
            if phi < 0.0 {
                phi += TAU;
            }
            let ia = (self.edges.partition_point(|&e| e <= a) - 1).min(self.edges.len() - 2);
            let ip = ((phi / TAU * self.np as f64) as usize).min(self.np - 1);
            h[ia * self.np + ip] += 1.0;
        }
        h
    }
}

/// Chi-square test of `m.sample(wi, .)` against `pdf` on the lobe grid;
/// returns `(p, stat, dof)`.
fn chi2_of_sampler(
    m: &Material,
    wi: DVec3,
    pdf: impl Fn(DVec3) -> f64,
    stream: u64,
) -> (f64, f64, usize) {
    let grid = LobeGrid::new(wi);
    let probs = grid.probabilities(pdf);
    let total: f64 = probs.iter().sum();
    // Simpson on cells where the pdf has a kink (the horizon) is accurate
    // to ~1e-6 of the total here.
    assert!(
        (total - 1.0).abs() < 1e-5,
        "cell probabilities sum to {total}"
    );
    let mut rng = Philox4x32::new(SEED, stream);
    let h = grid.histogram((0..N_SAMPLES).map(|_| m.sample(wi, rng.next_2d()).w));
    let expected: Vec<f64> = probs.iter().map(|p| p * N_SAMPLES as f64).collect();
    chi2_pvalue(&h, &expected)
}

#[test]
fn chi2_sample_matches_pdf() {
    let cases = [
        // (kd, ks, n, theta_i [deg], phi_i [rad])
        (0.3, 0.2, 20.0, 30.0, 0.4),
        (0.0, 1.0, 200.0, 45.0, 2.0),
        (0.2, 0.8, 200.0, 80.0, -1.0),
        (0.5, 0.5, 1.0, 60.0, 3.0),
        (0.6, 0.4, 0.0, 20.0, 5.0),
    ];
    assert_eq!(cases.len(), NUM_CHI2_TESTS as usize);
    let alpha = sidak_alpha();
    for (k, (kd, ks, n, deg, phi)) in cases.into_iter().enumerate() {
        let m = phong(kd, ks, n);
        let wi = dir(f64::to_radians(deg), phi);
        let (p, stat, dof) = chi2_of_sampler(&m, wi, |w| m.pdf(wi, w), 10 + k as u64);
        eprintln!(
            "phong kd {kd} ks {ks} n {n} theta {deg}: chi2 = {stat:.2}, dof = {dof}, \
             p = {p:.4} (reject below {alpha:.5})"
        );
        assert!(
            p > alpha,
            "kd {kd} ks {ks} n {n} theta {deg}: chi-square rejected (stat {stat}, dof {dof}, p {p})"
        );
    }
}

#[test]
fn chi2_has_power_against_a_nearby_exponent() {
    // Harness sanity: samples of the n = 200 lobe tested against the pdf of
    // the n = 210 lobe must be rejected.
    let m = phong(0.0, 1.0, 200.0);
    let wrong = phong(0.0, 1.0, 210.0);
    let wi = dir(0.8, 2.0);
    let (p, stat, dof) = chi2_of_sampler(&m, wi, |w| wrong.pdf(wi, w), 20);
    eprintln!("power check: chi2 = {stat:.2}, dof = {dof}, p = {p:.3e}");
    assert!(p < 1e-6, "failed to reject a wrong density (p = {p})");
}

// --------------------------------------------------------- scene file ----

const SCENE: &str = r#"[[surface]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = { type = "phong", diffuse = 0.3, specular = 0.2, exponent = 20 }

[[surface]]
type = "plane"
point = [0.0, 0.0, 1.0]
normal = [0.0, 0.0, -1.0]
material = { type = "lambertian", reflectance = 0.5 }

[[light]]
type = "point"
position = [0.0, 0.0, 0.5]
intensity = 1.0
"#;

#[test]
fn phong_material_parses() {
    let scene = lumest::scene::parse(SCENE, Path::new("x.toml")).expect("valid scene");
    assert_eq!(
        scene.surfaces[0].material,
        Material::Phong {
            kd: 0.3,
            ks: 0.2,
            n: 20.0
        }
    );
    assert_eq!(
        scene.surfaces[1].material,
        Material::Lambertian { rho: 0.5 }
    );
    // Boundary values are accepted: kd + ks = 1, n = 0, a float exponent.
    let edge = SCENE.replace(
        "diffuse = 0.3, specular = 0.2, exponent = 20",
        "diffuse = 0.7, specular = 0.3, exponent = 0.0",
    );
    let scene = lumest::scene::parse(&edge, Path::new("x.toml")).expect("valid scene");
    assert_eq!(
        scene.surfaces[0].material,
        Material::Phong {
            kd: 0.7,
            ks: 0.3,
            n: 0.0
        }
    );
}

#[test]
fn bad_phong_inputs_name_line_and_field() {
    let phong_line = "{ type = \"phong\", diffuse = 0.3, specular = 0.2, exponent = 20 }";
    let lamb_line = "{ type = \"lambertian\", reflectance = 0.5 }";
    // (from, to, "file:line:", field, message fragment)
    let cases = [
        (
            phong_line,
            "{ type = \"phong\", diffuse = 0.3, specular = 0.2 }",
            "x.toml:5:",
            "field `exponent`",
            "missing field",
        ),
        (
            phong_line,
            "{ type = \"phong\", specular = 0.2, exponent = 20 }",
            "x.toml:5:",
            "field `diffuse`",
            "missing field",
        ),
        (
            phong_line,
            "{ type = \"phong\", diffuse = 0.3, exponent = 20 }",
            "x.toml:5:",
            "field `specular`",
            "missing field",
        ),
        (
            phong_line,
            "{ type = \"phong\", diffuse = -0.1, specular = 0.2, exponent = 20 }",
            "x.toml:5:",
            "field `diffuse`",
            "must be finite and >= 0, got -0.1",
        ),
        (
            phong_line,
            "{ type = \"phong\", diffuse = 0.3, specular = nan, exponent = 20 }",
            "x.toml:5:",
            "field `specular`",
            "must be finite and >= 0",
        ),
        (
            phong_line,
            "{ type = \"phong\", diffuse = 0.3, specular = 0.2, exponent = -1 }",
            "x.toml:5:",
            "field `exponent`",
            "must be finite and >= 0, got -1",
        ),
        (
            phong_line,
            "{ type = \"phong\", diffuse = 0.3, specular = 0.2, exponent = inf }",
            "x.toml:5:",
            "field `exponent`",
            "must be finite",
        ),
        (
            phong_line,
            "{ type = \"phong\", diffuse = 0.7, specular = 0.4, exponent = 20 }",
            "x.toml:5:",
            "field `specular`",
            "`diffuse` + `specular` must be <= 1",
        ),
        (
            phong_line,
            "{ type = \"phong\", diffuse = 0.3, specular = 0.2, exponent = 20, reflectance = 0.5 }",
            "x.toml:5:",
            "field `reflectance`",
            "not allowed for material type `phong`",
        ),
        (
            lamb_line,
            "{ type = \"lambertian\", reflectance = 0.5, exponent = 20 }",
            "x.toml:11:",
            "field `exponent`",
            "not allowed for material type `lambertian`",
        ),
        (
            lamb_line,
            "{ type = \"lambertian\", diffuse = 0.5 }",
            "x.toml:11:",
            "field `diffuse`",
            "not allowed for material type `lambertian`",
        ),
        (
            phong_line,
            "{ type = \"phong\", diffuse = 0.3, specular = 0.2, shininess = 20 }",
            "x.toml:5:",
            "shininess",
            "unknown field",
        ),
        (
            phong_line,
            "{ type = \"blinn\", diffuse = 0.3, specular = 0.2, exponent = 20 }",
            "x.toml:5:",
            "field `type`",
            "lambertian, phong",
        ),
    ];
    for (from, to, at, field, fragment) in cases {
        let text = SCENE.replacen(from, to, 1);
        assert_ne!(text, SCENE);
        let err = lumest::scene::parse(&text, Path::new("x.toml"))
            .expect_err(&format!("accepted a bad scene ({to})"))
            .to_string();
        assert!(
            err.starts_with(at) && err.contains(field) && err.contains(fragment),
            "for {to}: expected {at} {field} {fragment}, got: {err}"
        );
    }
    // The value's column is reported, not just the line.
    let text = SCENE.replace("specular = 0.2", "specular = 0.9");
    let err = lumest::scene::parse(&text, Path::new("x.toml"))
        .unwrap_err()
        .to_string();
    let col = SCENE.lines().nth(4).unwrap().find("0.2").unwrap() + 1;
    assert!(
        err.starts_with(&format!("x.toml:5:{col}: field `specular`")),
        "{err}"
    );
}
