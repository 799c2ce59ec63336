//! Tests of the SH surface: evaluation, bounds, construction and the ray march
//! (against the analytic sphere and a brute-force root search).

use super::*;
use crate::sampling::rng::Philox4x32;
use glam::DMat3;
use std::f64::consts::PI;

fn c(k: usize, m: usize, a: f64, b: f64) -> ShCoeff {
    ShCoeff { k, m, a, b }
}

fn unit(r: &mut Philox4x32) -> DVec3 {
    let z = 1.0 - 2.0 * r.next_f64();
    let s = (1.0 - z * z).max(0.0).sqrt();
    let (sp, cp) = (2.0 * PI * r.next_f64()).sin_cos();
    DVec3::new(s * cp, s * sp, z)
}

/// A unit vector orthogonal to `n`, random.
fn tangent(r: &mut Philox4x32, n: DVec3) -> DVec3 {
    loop {
        let v = unit(r);
        let t = v - n * n.dot(v);
        if t.length() > 0.1 {
            return t.normalize();
        }
    }
}

fn rotation() -> DMat3 {
    DMat3::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7)
}

#[test]
fn single_terms_match_closed_forms() {
    let mut r = Philox4x32::new(11, 0);
    let (a, b) = (0.3, -0.2);
    // (k, m, P_k^m(x) as a function of (x, s))
    type ClosedForm = fn(f64, f64) -> f64;
    let cases: [(usize, usize, ClosedForm); 4] = [
        (1, 1, |_, s| s),
        (2, 1, |x, s| 3f64.sqrt() * x * s),
        (3, 2, |x, s| 0.5 * 15f64.sqrt() * x * s * s),
        (3, 3, |_, s| (5.0f64 / 8.0).sqrt() * s * s * s),
    ];
    for (k, m, p) in cases {
        let surf = ShSurface::new(
            &[c(0, 0, 2.0, 0.0), c(k, m, a, b)],
            DVec3::ZERO,
            DMat3::IDENTITY,
            1.0,
        )
        .unwrap();
        assert_eq!(surf.degree(), k);
        let mut dirs: Vec<DVec3> = (0..200).map(|_| unit(&mut r)).collect();
        dirs.extend([
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.0, -1.0, 1.0).normalize(),
        ]);
        for y in dirs {
            let s = y.x.hypot(y.y);
            let phi = y.y.atan2(y.x);
            let mf = m as f64;
            let want = 2.0 + p(y.z, s) * (a * (mf * phi).cos() + b * (mf * phi).sin());
            let got = surf.radius(y);
            assert!(
                (got - want).abs() <= 1e-15,
                "k {k} m {m} dir {y}: {got} vs {want}"
            );
        }
    }
}

/// Pseudo-random bumpy coefficients: `a_00 = 1`, degree-k amplitudes `amp / k`.
pub(super) fn bumpy_coeffs(degree: usize, amp: f64, seed: u64) -> Vec<ShCoeff> {
    let mut r = Philox4x32::new(seed, 7);
    let mut v = vec![c(0, 0, 1.0, 0.0)];
    for k in 1..=degree {
        for m in 0..=k {
            let w = amp / k as f64;
            let a = w * (2.0 * r.next_f64() - 1.0);
            let b = if m == 0 {
                0.0
            } else {
                w * (2.0 * r.next_f64() - 1.0)
            };
            v.push(c(k, m, a, b));
        }
    }
    v
}

/// The degree-8 bumpy test shape at a given scale (centre scales too).
fn bumpy(scale: f64) -> ShSurface {
    ShSurface::new(
        &bumpy_coeffs(8, 0.2, 1),
        scale * DVec3::new(0.2, -0.1, 0.3),
        rotation(),
        scale * 1.7,
    )
    .unwrap()
}

#[test]
fn surface_gradient_matches_finite_differences() {
    let surf = bumpy(1.0);
    let mut r = Philox4x32::new(12, 0);
    let mut dirs: Vec<DVec3> = (0..300).map(|_| unit(&mut r)).collect();
    dirs.extend([DVec3::Z, -DVec3::Z]);
    let h: f64 = 1e-5;
    for y in dirs {
        let (_, g) = surf.radius_and_gradient(y);
        assert!(g.dot(y).abs() <= 1e-13, "gradient not tangent at {y}");
        for _ in 0..2 {
            let e = tangent(&mut r, y);
            // Along the great circle through y in direction e.
            let fd = (surf.radius(y * h.cos() + e * h.sin())
                - surf.radius(y * h.cos() - e * h.sin()))
                / (2.0 * h);
            assert!(
                (fd - g.dot(e)).abs() <= 1e-7,
                "dir {y}: fd {fd} vs {}",
                g.dot(e)
            );
        }
    }
}

#[test]
fn bounds_enclose_the_surface() {
    let surf = bumpy(2.5);
    let (lo, hi) = surf.bounds();
    let (a00, s) = (surf.a00, surf.s_sum);
    assert!(lo >= 2.5 * 1.7 * (a00 - s) && hi <= 2.5 * 1.7 * (a00 + s));
    assert!(lo > 0.0);
    let mut r = Philox4x32::new(13, 0);
    let (mut umin, mut umax) = (f64::INFINITY, 0.0f64);
    for _ in 0..50_000 {
        let u = surf.scale() * surf.radius(unit(&mut r));
        umin = umin.min(u);
        umax = umax.max(u);
    }
    assert!(
        lo <= umin && umax <= hi,
        "[{lo}, {hi}] vs sampled [{umin}, {umax}]"
    );
    // The grid bounds are tight (second-order slack).
    assert!(
        umin - lo <= 0.01 * umin && hi - umax <= 0.01 * umax,
        "[{lo}, {hi}] vs sampled [{umin}, {umax}]"
    );
    // The bounds are tight to the 5 % grid slack.
    eprintln!(
        "bumpy: a00 -/+ S = {} / {}, bounds [{lo}, {hi}], sampled [{umin}, {umax}], G = {}, H = {}",
        2.5 * 1.7 * (a00 - s),
        2.5 * 1.7 * (a00 + s),
        surf.g_bound,
        surf.h_bound
    );
}

#[test]
fn grid_proves_star_shape_when_the_coefficient_bound_cannot() {
    // U = 0.7 + 0.6 x + 0.9 x^2 (x = cos theta): min 0.6 at x = -1/3, but a00 - S = -0.2.
    let coeffs = [c(0, 0, 1.0, 0.0), c(1, 0, 0.6, 0.0), c(2, 0, 0.6, 0.0)];
    let surf = ShSurface::new(&coeffs, DVec3::ZERO, DMat3::IDENTITY, 1.0).unwrap();
    let (lo, hi) = surf.bounds();
    assert!(lo > 0.59 && lo <= 0.6, "r_min {lo}");
    assert!((2.2..2.25).contains(&hi), "r_max {hi}");
    // Positive everywhere but by 1e-12 only: cannot be proved.
    let coeffs = [
        c(0, 0, 0.4 + 1e-12, 0.0),
        c(1, 0, 0.6, 0.0),
        c(2, 0, 0.6, 0.0),
    ];
    let e = ShSurface::new(&coeffs, DVec3::ZERO, DMat3::IDENTITY, 1.0).unwrap_err();
    assert!(matches!(e, ShError::Unverified { .. }), "{e}");
    assert!(e.to_string().contains("could not verify"), "{e}");
    // Negative somewhere: U(theta = pi) = 1 - 2 = -1.
    let e = ShSurface::new(
        &[c(0, 0, 1.0, 0.0), c(1, 0, 2.0, 0.0)],
        DVec3::ZERO,
        DMat3::IDENTITY,
        1.0,
    )
    .unwrap_err();
    match e {
        ShError::NotStarShaped { radius, theta, .. } => {
            assert!(radius < 0.0 && (theta - PI).abs() < 0.1)
        }
        e => panic!("{e}"),
    }
}

#[test]
fn constructor_rejects_bad_input() {
    let ok = [c(0, 0, 1.0, 0.0)];
    let i = DMat3::IDENTITY;
    let z = DVec3::ZERO;
    let err = |cs: &[ShCoeff], center: DVec3, rot: DMat3, scale: f64| {
        ShSurface::new(cs, center, rot, scale)
            .unwrap_err()
            .to_string()
    };
    assert!(err(&[], z, i, 1.0).contains("no spherical-harmonic coefficients"));
    assert!(
        err(&[c(0, 0, 1.0, 0.0), c(2, 3, 0.1, 0.0)], z, i, 1.0)
            .contains("order m = 3 exceeds degree k = 2")
    );
    assert!(
        err(&[c(0, 0, 1.0, 0.0), c(1, 1, f64::NAN, 0.0)], z, i, 1.0)
            .contains("a = NaN is not finite")
    );
    assert!(
        err(&[c(0, 0, 1.0, 0.0), c(1, 1, 0.0, f64::INFINITY)], z, i, 1.0)
            .contains("b = inf is not finite")
    );
    assert!(err(&[c(0, 0, 1.0, 0.5)], z, i, 1.0).contains("b = 0.5 must be 0"));
    assert!(
        err(
            &[c(0, 0, 1.0, 0.0), c(1, 1, 0.1, 0.0), c(1, 1, 0.2, 0.0)],
            z,
            i,
            1.0
        )
        .contains("coefficient 2 (k = 1, m = 1) repeats coefficient 1")
    );
    assert!(
        err(&[c(MAX_DEGREE + 1, 0, 1.0, 0.0)], z, i, 1.0).contains("exceeds the supported maximum")
    );
    assert!(err(&ok, DVec3::new(f64::NAN, 0.0, 0.0), i, 1.0).contains("centre"));
    assert!(err(&ok, z, i, 0.0).contains("scale 0 must be finite and > 0"));
    assert!(err(&ok, z, i, f64::INFINITY).contains("scale"));
    assert!(err(&ok, z, i * 1.01, 1.0).contains("R^T R differs"));
    assert!(
        err(
            &ok,
            z,
            DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0)),
            1.0
        )
        .contains("reflection")
    );
    assert!(err(&[c(0, 0, -1.0, 0.0)], z, i, 1.0).contains("not star-shaped"));
    // Trailing zero degrees are dropped; missing pairs are zero.
    let s = ShSurface::new(&[c(0, 0, 1.0, 0.0), c(5, 2, 0.0, 0.0)], z, i, 1.0).unwrap();
    assert_eq!(s.degree(), 0);
    assert_eq!(s.coefficient_count(), 1);
    let b = bumpy(1.0);
    assert_eq!(b.coefficient_count(), 81);
    assert!(b.storage_bytes() >= 81 * 8);
    assert_eq!(b.coefficients().len(), 45);
}

/// First `t` in `(t_min, t_max)` where the ray meets the sphere.
fn sphere_hit(center: DVec3, r: f64, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
    let p = o - center;
    let tc = -p.dot(d);
    let b = p.cross(d).length();
    if b >= r {
        return None;
    }
    let h = ((r - b) * (r + b)).sqrt();
    [tc - h, tc + h]
        .into_iter()
        .find(|&t| t > t_min && t < t_max)
}

/// All sphere checks at one scale; returns the hit distances divided by the scale.
fn sphere_checks(scale: f64) -> Vec<Option<f64>> {
    let r0 = 1.3;
    let rw = scale * r0;
    let center = scale * DVec3::new(0.3, -0.2, 0.5);
    let rot = rotation();
    let s = ShSurface::new(&[c(0, 0, r0, 0.0)], center, rot, scale).unwrap();
    assert_eq!(s.bounds(), (rw, rw));
    let mut r = Philox4x32::new(21, 0);
    let mut out = Vec::new();
    let check = |o: DVec3, d: DVec3, t_min: f64, t_max: f64, out: &mut Vec<Option<f64>>| {
        let want = sphere_hit(center, rw, o, d, t_min, t_max);
        let got = s.first_hit(o, d, t_min, t_max);
        match (want, got) {
            (None, None) => {}
            (Some(tw), Some((t, n))) => {
                assert!(
                    (t - tw).abs() <= 1e-12 * rw,
                    "scale {scale}: t {t} vs {tw} (o {o}, d {d})"
                );
                let nw = (o + tw * d - center) / rw;
                assert!((n - nw).length() <= 1e-12, "normal {n} vs {nw}");
                assert!((s.normal(o + tw * d) - nw).length() <= 1e-12);
            }
            (w, g) => panic!("scale {scale}: analytic {w:?}, got {g:?} (o {o}, d {d})"),
        }
        assert_eq!(s.crosses(o, d, t_min, t_max), want.is_some());
        out.push(got.map(|(t, _)| t / scale));
    };
    // From outside, aimed near the sphere (hits and misses).
    for _ in 0..400 {
        let o = center + rw * (1.2 + 2.0 * r.next_f64()) * unit(&mut r);
        let target = center + rw * 1.3 * r.next_f64() * unit(&mut r);
        check(o, (target - o).normalize(), 0.0, f64::INFINITY, &mut out);
    }
    // From inside (random, and from the centre).
    for _ in 0..200 {
        let o = center + rw * 0.99 * r.next_f64().cbrt() * unit(&mut r);
        check(o, unit(&mut r), 0.0, f64::INFINITY, &mut out);
    }
    let d = unit(&mut r);
    check(center, d, 0.0, f64::INFINITY, &mut out);
    // Through the centre, and through the poles (local +-z) from outside and inside.
    check(center - 3.0 * rw * d, d, 0.0, f64::INFINITY, &mut out);
    let w = rot * DVec3::Z;
    for pole in [w, -w] {
        check(
            center + 3.0 * rw * pole,
            -pole,
            0.0,
            f64::INFINITY,
            &mut out,
        );
        check(center + 0.5 * rw * pole, pole, 0.0, f64::INFINITY, &mut out);
        check(center - 0.5 * rw * pole, pole, 0.0, f64::INFINITY, &mut out);
        let (t, n) = s
            .first_hit(center + 3.0 * rw * pole, -pole, 0.0, f64::INFINITY)
            .unwrap();
        assert!((t - 2.0 * rw).abs() <= 1e-12 * rw && (n - pole).length() <= 1e-12);
    }
    // Grazing: passing 1e-6 R inside / outside the sphere; exactly tangent.
    for _ in 0..50 {
        let d = unit(&mut r);
        let e = tangent(&mut r, d);
        for b in [1.0 - 1e-6, 1.0 + 1e-6, 1.0 - 1e-3] {
            check(
                center + rw * b * e - 3.0 * rw * d,
                d,
                0.0,
                f64::INFINITY,
                &mut out,
            );
        }
        // 1e-12 R inside: still a chord of 1.4e-6 R, found; t ill-conditioned.
        let o = center + rw * (1.0 - 1e-12) * e - 3.0 * rw * d;
        let (t, _) = s
            .first_hit(o, d, 0.0, f64::INFINITY)
            .expect("near-tangent hit");
        assert!((t - 3.0 * rw).abs() <= 2e-6 * rw);
        // Tangent: either answer, finite and near the tangent point.
        if let Some((t, n)) = s.first_hit(center + rw * e - 3.0 * rw * d, d, 0.0, f64::INFINITY) {
            assert!((t - 3.0 * rw).abs() <= 1e-5 * rw && n.is_finite());
        }
    }
    // Segment limits: stops before the sphere; starts between entry and exit.
    let o = center - 3.0 * rw * d;
    check(o, d, 0.0, 1.5 * rw, &mut out);
    check(o, d, 2.5 * rw, f64::INFINITY, &mut out);
    check(o, d, 3.5 * rw, 4.5 * rw, &mut out);
    // Starting on the surface: leaving outward nothing; inward the far side.
    for _ in 0..100 {
        let n = unit(&mut r);
        let x = center + rw * n;
        let e = tangent(&mut r, n);
        let out_dir = (n + e * (2.0 * r.next_f64() - 1.0) * 3.0).normalize();
        let out_dir = if out_dir.dot(n) > 0.0 {
            out_dir
        } else {
            -out_dir
        };
        assert!(s.first_hit(x, out_dir, 0.0, f64::INFINITY).is_none());
        let (t, nn) = s
            .first_hit(x, -out_dir, 0.0, f64::INFINITY)
            .expect("far side");
        let tw = 2.0 * rw * out_dir.dot(n);
        assert!(
            (t - tw).abs() <= 1e-12 * rw
                && (nn - (x - out_dir * tw - center) / rw).length() <= 1e-12
        );
        // Shadow segment between two surface points: no crossing inside it.
        assert!(!s.crosses(x, -out_dir, 0.0, t));
        assert!(!s.crosses(x, -out_dir, 0.0, tw));
        // Through the surface and beyond: crossing.
        assert!(s.crosses(x, -out_dir, 0.0, 1.5 * tw));
    }
    out
}

#[test]
fn degree_zero_is_the_analytic_sphere_at_every_scale() {
    let base = sphere_checks(1.0);
    for scale in [1e-3, 1e4] {
        let other = sphere_checks(scale);
        assert_eq!(base.len(), other.len());
        for (a, b) in base.iter().zip(&other) {
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-12 * 1.3, "{a} vs {b}"),
                _ => panic!("scale {scale}: {a:?} vs {b:?}"),
            }
        }
    }
}

/// Brute force: sample `f` on `n` uniform steps over the part of
/// `(t_min, t_max)` inside a ball of radius `1.001 r_max`, bisect the
/// first sign change. Returns the first crossing and the grid spacing.
fn brute_first(
    s: &ShSurface,
    o: DVec3,
    d: DVec3,
    t_min: f64,
    t_max: f64,
    n: usize,
) -> (Option<f64>, f64) {
    let rb = 1.001 * s.bounds().1;
    let p = o - s.center();
    let tc = -p.dot(d);
    let b = p.cross(d).length();
    if b >= rb {
        return (None, 0.0);
    }
    let h = ((rb - b) * (rb + b)).sqrt();
    let (t0, t1) = (t_min.max(tc - h), t_max.min(tc + h));
    if t0 >= t1 {
        return (None, 0.0);
    }
    let f = |t: f64| s.level(o + t * d);
    let sign = f(t0).signum();
    let dt = (t1 - t0) / n as f64;
    let mut prev = t0;
    for i in 1..=n {
        let t = if i == n { t1 } else { t0 + dt * i as f64 };
        if f(t) * sign <= 0.0 {
            if i == n && t == t_max {
                break;
            }
            let (mut lo, mut hi) = (prev, t);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if f(mid) * sign > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return (Some(hi), dt);
        }
        prev = t;
    }
    (None, dt)
}

/// A random surface point (world) and its outward normal.
fn surface_point(s: &ShSurface, r: &mut Philox4x32) -> (DVec3, DVec3) {
    let y = unit(r);
    let x = s.center() + s.scale() * s.radius(y) * (s.rotation() * y);
    (x, s.normal(x))
}

#[derive(Default, Debug)]
struct Stats {
    rays: usize,
    hits: usize,
    thin: usize,
    touch: usize,
    steps: usize,
    max_steps: usize,
}

/// Compare `first_hit` with brute force on one ray; updates stats.
fn compare(s: &ShSurface, o: DVec3, d: DVec3, t_min: f64, t_max: f64, n: usize, st: &mut Stats) {
    let rw = s.bounds().1;
    let (got, steps) = s.first_hit_counted(o, d, t_min, t_max);
    st.rays += 1;
    st.steps += steps;
    st.max_steps = st.max_steps.max(steps);
    let (want, dt) = brute_first(s, o, d, t_min, t_max, n);
    assert_eq!(
        s.crosses(o, d, t_min, t_max),
        got.is_some(),
        "crosses vs first_hit (o {o}, d {d})"
    );
    if let Some((t, nrm)) = got {
        st.hits += 1;
        assert!(t > t_min && t < t_max);
        let x = o + t * d;
        assert!(
            s.level(x).abs() <= 1e-11 * rw,
            "not on the surface: {}",
            s.level(x)
        );
        assert!((nrm - s.normal(x)).length() <= 1e-12 && (nrm.length() - 1.0).abs() < 1e-14);
    }
    // Root tolerance: 1e-9 of the radius, wider where the ray is nearly
    // tangent (a level error of ~1e-16 R moves the root by ~1e-16 R / |n.d|).
    let tol = |t: f64| {
        let slope = s.normal(o + t * d).dot(d).abs();
        1e-9 * rw + 1e-14 * rw / slope.max(1e-300)
    };
    match (want, got) {
        (None, None) => {}
        (Some(tb), None) => {
            panic!("missed a hit: brute {tb} (o {o}, d {d}, t in ({t_min}, {t_max}))")
        }
        (Some(tb), Some((t, _))) if (t - tb).abs() <= tol(t) => {}
        (Some(tb), Some((t, _))) if tb < t => {
            panic!("brute force found an earlier hit: {tb} < {t} (o {o}, d {d})")
        }
        (_, Some((t, _))) => {
            // An earlier crossing pair thinner than the brute-force grid:
            // confirm a sign change near t on a grid 1000 times finer.
            st.thin += 1;
            let (w, _) = brute_first(s, o, d, (t - 2.0 * dt).max(t_min), t + 2.0 * dt, 4000);
            let slope = s.normal(o + t * d).dot(d);
            let level = s.level(o + t * d);
            match w {
                Some(w) => assert!((w - t).abs() <= tol(t), "thin crossing at {w} vs {t}"),
                // A tangent touch: the level dips below zero by rounding only.
                None if slope.abs() <= 1e-6 && level.abs() <= 1e-14 * rw => st.touch += 1,
                None => {
                    panic!("thin crossing not confirmed: t {t}, slope {slope}, level {level}")
                }
            }
        }
    }
}

#[test]
fn bumpy_random_rays_agree_with_brute_force() {
    let s = bumpy(1.0);
    let (_, rmax) = s.bounds();
    let c0 = s.center();
    let mut r = Philox4x32::new(31, 0);
    let mut st = Stats::default();
    for i in 0..3000 {
        let (o, d, t_max) = match i % 4 {
            0 | 1 => {
                // From outside, aimed into the bounding ball.
                let o = c0 + rmax * (1.1 + 2.0 * r.next_f64()) * unit(&mut r);
                let target = c0 + rmax * 1.05 * r.next_f64() * unit(&mut r);
                let t_max = if i % 8 == 1 {
                    3.0 * rmax * r.next_f64()
                } else {
                    f64::INFINITY
                };
                (o, (target - o).normalize(), t_max)
            }
            2 => {
                // From inside the solid.
                let y = unit(&mut r);
                let o = c0 + s.scale() * s.radius(y) * 0.99 * r.next_f64() * (s.rotation() * y);
                (o, unit(&mut r), f64::INFINITY)
            }
            _ => {
                // Skimming: near-tangent to the surface at a random point.
                let (x, n) = surface_point(&s, &mut r);
                let e = tangent(&mut r, n);
                let d = (e + n * 0.02 * (2.0 * r.next_f64() - 1.0)).normalize();
                let o = x + n * rmax * 1e-3 * (2.0 * r.next_f64() - 1.0) - 2.0 * rmax * d;
                (o, d, f64::INFINITY)
            }
        };
        compare(&s, o, d, 0.0, t_max, 4000, &mut st);
    }
    eprintln!(
        "bumpy random rays: {st:?}, mean evaluations per ray {:.1}",
        st.steps as f64 / st.rays as f64
    );
    assert!(st.hits > st.rays / 3, "too few hits to be a test: {st:?}");
    assert!(st.thin <= st.rays / 100, "{st:?}");
    assert!(st.max_steps < 5000, "{st:?}");
}

#[test]
fn bumpy_grazing_inside_centre_and_pole_rays() {
    let s = bumpy(1.0);
    let (_, rmax) = s.bounds();
    let c0 = s.center();
    let rot = s.rotation();
    let mut r = Philox4x32::new(41, 0);
    let mut st = Stats::default();
    // Grazing at 1e-7 and 1e-4 of the radius above / below the tangent plane, and on it.
    for _ in 0..30 {
        let (x, n) = surface_point(&s, &mut r);
        let e = tangent(&mut r, n);
        for eps in [1e-7, -1e-7, 1e-4, -1e-4, 0.0] {
            let o = x + n * rmax * eps - 2.0 * rmax * e;
            compare(&s, o, e, 0.0, f64::INFINITY, 30_000, &mut st);
        }
    }
    // Rays starting on the surface: leaving outward / inward (no hit at the start).
    for _ in 0..100 {
        let (x, n) = surface_point(&s, &mut r);
        let e = tangent(&mut r, n);
        for sign in [1.0, -1.0] {
            let d = (n * sign + e * 2.0 * r.next_f64()).normalize();
            let got = s.first_hit(x, d, 0.0, f64::INFINITY);
            if let Some((t, _)) = got {
                assert!(t > 1e-6 * rmax, "self-hit at t = {t}");
            }
            let (want, _) = brute_first(&s, x, d, 1e-6 * rmax, f64::INFINITY, 10_000);
            match (want, got) {
                (None, None) => {}
                (Some(tb), Some((t, _))) => {
                    assert!((t - tb).abs() <= 1e-9 * rmax, "{t} vs {tb}")
                }
                (w, g) => panic!("on-surface start: brute {w:?}, got {g:?}"),
            }
        }
    }
    // Radial rays: from the centre, through the centre, through the poles.
    for i in 0..200 {
        let y = match i {
            0 => DVec3::Z,
            1 => -DVec3::Z,
            _ => unit(&mut r),
        };
        let w = rot * y;
        let u = s.scale() * s.radius(y);
        let (t, n) = s.first_hit(c0, w, 0.0, f64::INFINITY).unwrap();
        assert!((t - u).abs() <= 1e-12 * rmax, "from the centre: {t} vs {u}");
        assert!(n.dot(w) > 0.0 && (n - s.normal(c0 + u * w)).length() <= 1e-12);
        let (t, _) = s
            .first_hit(c0 + 3.0 * rmax * w, -w, 0.0, f64::INFINITY)
            .unwrap();
        assert!(
            (t - (3.0 * rmax - u)).abs() <= 1e-12 * rmax,
            "radial from outside: {t}"
        );
        // Through the centre from the other side.
        let u_back = s.scale() * s.radius(-y);
        let (t, _) = s
            .first_hit(c0 + 0.5 * u_back * -w, w, 0.0, f64::INFINITY)
            .unwrap();
        assert!(
            (t - (0.5 * u_back + u)).abs() <= 1e-12 * rmax,
            "through the centre: {t}"
        );
        compare(
            &s,
            c0 - 3.0 * rmax * w,
            w,
            0.0,
            f64::INFINITY,
            4000,
            &mut st,
        );
    }
    // Shadow segments between surface points: crosses iff brute force finds
    // a sign change strictly inside (ends excluded by 1e-6 of the radius).
    for _ in 0..200 {
        let (x1, _) = surface_point(&s, &mut r);
        let (x2, _) = surface_point(&s, &mut r);
        let len = (x2 - x1).length();
        let d = (x2 - x1) / len;
        let (want, _) = brute_first(&s, x1, d, 1e-6 * rmax, len - 1e-6 * rmax, 10_000);
        assert_eq!(
            s.crosses(x1, d, 0.0, len),
            want.is_some(),
            "segment {x1} -> {x2}"
        );
    }
    eprintln!("bumpy special rays: {st:?}");
    assert!(st.max_steps < 5000, "{st:?}");
}

#[test]
fn bumpy_is_scale_invariant() {
    let base = bumpy(1.0);
    let mut r = Philox4x32::new(51, 0);
    let rays: Vec<(DVec3, DVec3)> = (0..500)
        .map(|_| {
            let o = base.center() + 3.0 * unit(&mut r);
            let target = base.center() + 1.7 * r.next_f64() * unit(&mut r);
            (o, (target - o).normalize())
        })
        .collect();
    for scale in [1e-3, 1e4] {
        let s = bumpy(scale);
        for &(o, d) in &rays {
            let a = base.first_hit(o, d, 0.0, f64::INFINITY);
            let b = s.first_hit(o * scale, d, 0.0, f64::INFINITY);
            match (a, b) {
                (None, None) => {}
                (Some((ta, na)), Some((tb, nb))) => {
                    assert!((ta - tb / scale).abs() <= 1e-10, "{ta} vs {}", tb / scale);
                    assert!((na - nb).length() <= 1e-9);
                }
                _ => panic!("scale {scale}: {a:?} vs {b:?}"),
            }
        }
    }
}

#[test]
fn normals_match_finite_differences_and_pole_limits() {
    let s = bumpy(1.0);
    let (_, rmax) = s.bounds();
    let mut r = Philox4x32::new(61, 0);
    let fd_normal = |x: DVec3| {
        let h = 1e-5 * rmax;
        let g = DVec3::new(
            s.level(x + DVec3::X * h) - s.level(x - DVec3::X * h),
            s.level(x + DVec3::Y * h) - s.level(x - DVec3::Y * h),
            s.level(x + DVec3::Z * h) - s.level(x - DVec3::Z * h),
        );
        g.normalize()
    };
    let rot = s.rotation();
    let on = |y: DVec3| s.center() + s.scale() * s.radius(y) * (rot * y.normalize());
    for _ in 0..300 {
        let x = on(unit(&mut r));
        let n = s.normal(x);
        assert!(
            (n - fd_normal(x)).length() <= 1e-7,
            "normal {n} vs fd {}",
            fd_normal(x)
        );
    }
    for pole in [DVec3::Z, -DVec3::Z] {
        let xp = on(pole);
        let np = s.normal(xp);
        assert!(
            (np - fd_normal(xp)).length() <= 1e-7,
            "pole {pole}: {np} vs fd {}",
            fd_normal(xp)
        );
        // Nearby points on all sides converge to the pole normal.
        for eps in [1e-4, 1e-6, 1e-8] {
            for j in 0..12 {
                let phi = 2.0 * PI * j as f64 / 12.0;
                let y = DVec3::new(eps * phi.cos(), eps * phi.sin(), pole.z);
                let dn = (s.normal(on(y)) - np).length();
                assert!(dn <= 100.0 * eps, "pole {pole}, eps {eps}, phi {phi}: {dn}");
            }
        }
    }
}

/// Cost of one `first_hit` on the bumpy shape:
/// `cargo test --release -p lumest --lib geometry::sh::tests::bench_first_hit -- --ignored --nocapture`.
#[test]
#[ignore]
fn bench_first_hit() {
    let s = bumpy(1.0);
    let (_, rmax) = s.bounds();
    let mut r = Philox4x32::new(71, 0);
    let rays: Vec<(DVec3, DVec3)> = (0..200_000)
        .map(|_| {
            let o = s.center() + 3.0 * rmax * unit(&mut r);
            let target = s.center() + rmax * r.next_f64() * unit(&mut r);
            (o, (target - o).normalize())
        })
        .collect();
    let (mut best, mut best_level) = (f64::INFINITY, f64::INFINITY);
    let (mut hits, mut evals, mut sum) = (0usize, 0usize, 0.0);
    for _ in 0..5 {
        let t0 = std::time::Instant::now();
        (hits, evals) = (0, 0);
        for &(o, d) in &rays {
            let (h, n) = s.first_hit_counted(o, d, 0.0, f64::INFINITY);
            hits += usize::from(h.is_some());
            evals += n;
        }
        best = best.min(t0.elapsed().as_secs_f64());
        let t1 = std::time::Instant::now();
        for &(o, _) in &rays {
            sum += s.level(o);
        }
        best_level = best_level.min(t1.elapsed().as_secs_f64());
    }
    let n = rays.len() as f64;
    eprintln!(
        "first_hit: {:.0} ns/ray ({hits} hits of {n}), {:.1} level evaluations/ray; level: {:.0} ns ({sum:.1}); best of 5",
        best / n * 1e9,
        evals as f64 / n,
        best_level / n * 1e9
    );
}

/// A deep dimple: `U = 1 + (1 - 1e-5) cos theta` comes within `1e-5` of the
/// centre at the south pole, so the Lipschitz bounds there (`r_min = 1e-5`)
/// force steps of about `2e-5` on rays aimed at it from outside. Such a ray
/// needs more level evaluations than the march's first budget; the old march
/// reported a miss there (`MAX_STEPS` level evaluations, then `None`). Every
/// ray must give the first crossing that a dense brute-force root search
/// finds (`1e6` samples along the chord, then bisection).
#[test]
fn rays_beyond_the_step_budget_still_hit() {
    let s = ShSurface::new(
        &[c(0, 0, 1.0, 0.0), c(1, 0, 1.0 - 1e-5, 0.0)],
        DVec3::ZERO,
        DMat3::IDENTITY,
        1.0,
    )
    .unwrap();
    let (rmin, rmax) = s.bounds();
    assert!((rmin - 1e-5).abs() <= 1e-15, "r_min {rmin}");
    let rays = [
        (DVec3::new(1e-6, 0.0, -3.0), DVec3::Z),
        (
            DVec3::new(0.0, 2e-5, -2.5),
            DVec3::new(0.0, -1e-6, 1.0).normalize(),
        ),
        (
            DVec3::new(0.4, -0.3, -2.0),
            DVec3::new(-0.4, 0.3, 2.0).normalize(),
        ),
    ];
    let mut beyond = 0;
    for (o, d) in rays {
        let (got, steps) = s.first_hit_counted(o, d, 0.0, f64::INFINITY);
        beyond += usize::from(steps > super::march::STEP_BUDGET);
        let (want, dt) = brute_first(&s, o, d, 0.0, f64::INFINITY, 1_000_000);
        let want = want.expect("the ray crosses the dimple");
        let (t, n) = got.unwrap_or_else(|| panic!("miss after {steps} evaluations: o {o}, d {d}"));
        assert!(
            (t - want).abs() <= dt,
            "t {t} vs brute force {want} (+- {dt}), {steps} evaluations"
        );
        let x = o + t * d;
        assert!(
            s.level(x).abs() <= 1e-12 * rmax,
            "level {} at the hit",
            s.level(x)
        );
        assert!((n - s.normal(x)).length() <= 1e-9);
    }
    // The case is the one it is meant to be: rays past the old cap.
    assert!(
        beyond >= 1,
        "no ray needed more than {} evaluations",
        super::march::STEP_BUDGET
    );
}

/// Rays from very far away (up to `1e11` radii, where an ulp of `t` exceeds
/// the floor step and the rounding of `o + t d` the clip margin) find the
/// analytic sphere's entry point to the precision of `t`. Without moving
/// the origin (`ShSurface::rebase`), the ray from `1e8` radii reported the
/// exit point and the one from `1e9` radii a miss.
#[test]
fn far_origins_still_hit() {
    let r0 = 1.3;
    let center = DVec3::new(0.3, -0.2, 0.5);
    let s = ShSurface::new(&[c(0, 0, r0, 0.0)], center, rotation(), 1.0).unwrap();
    let mut r = Philox4x32::new(31, 0);
    for far in [1e6, 1e8, 1e11] {
        for _ in 0..50 {
            let d = unit(&mut r);
            let aim = center + 0.9 * r0 * tangent(&mut r, d) * r.next_f64();
            let o = aim - far * d;
            let want = sphere_hit(center, r0, o, d, 0.0, f64::INFINITY).unwrap();
            let (got, steps) = s.first_hit_counted(o, d, 0.0, f64::INFINITY);
            let (t, _) = got.unwrap_or_else(|| panic!("miss from {far}: {steps} evaluations"));
            assert!(
                (t - want).abs() <= 1e-12 * r0 + 8.0 * f64::EPSILON * far,
                "from {far}: t {t} vs {want}"
            );
        }
    }
}
