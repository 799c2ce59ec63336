//! Exact direct illuminance from uniform Lambertian area sources, for the
//! estimator where nothing can hide a source ([`crate::estimator::exact_direct`]).
//!
//! For a planar source `A` of uniform luminance `L`, the illuminance at `x`
//! with unit normal `n` is `E = L int_A cos(theta_x) cos(theta_y) / d^2 dA`
//! over the part of `A` above `x`'s horizon. By Stokes' theorem (Lambert's
//! contour integral) `int_A cos_x cos_y / d^2 dA = (1/2) | oint_C (r x dr) . n / |r|^2 |`
//! over the boundary `C` of that part, `r = y - x`. A straight edge from
//! `a` to `b` (relative to `x`) contributes `gamma (a x b) . n / |a x b|`,
//! `gamma` the angle between `a` and `b`: for a polygon the sum over its
//! edges (clipped first by the horizon plane).
//!
//! A uniform disc wholly above the horizon has a closed form: its
//! irradiance vector (per unit luminance) has the axial component
//! `(pi/2) (1 - (h^2 + rho^2 - R^2) / S)` and the radial component (towards
//! the axis) `(pi h / (2 rho)) ((h^2 + rho^2 + R^2) / S - 1)` with
//! `S = sqrt((h^2 + rho^2 + R^2)^2 - 4 R^2 rho^2)`, `h` the height over the
//! disc's plane and `rho` the distance from its axis (the configuration
//! factors of a plane element parallel and perpendicular to a disc,
//! Howell's catalogue B-13 / B-15 type), and `E / L` is that vector dotted
//! with `n`. Where the horizon cuts the disc, the visible part is a
//! circular segment: its arc is integrated by Gauss-Legendre panels, its
//! chord exactly.

use crate::math::quadrature::{CompensatedSum, panel};
use crate::sampling::warp::Frame;
use glam::DVec3;
use std::f64::consts::PI;

/// The angle-weighted edge term `gamma (a x b) . n / |a x b|` (see the module docs).
#[inline]
fn edge(a: DVec3, b: DVec3, n: DVec3) -> f64 {
    let c = a.cross(b);
    let s = c.length();
    if s <= 0.0 {
        return 0.0;
    }
    let gamma = s.atan2(a.dot(b));
    gamma * c.dot(n) / s
}

/// `int cos_x cos_y / d^2 dA` \[sr\] over a planar convex polygon (`verts`
/// in order, either orientation) seen from `x` with unit normal `n`,
/// counting only what lies above `x`'s horizon; the polygon is taken as
/// emitting towards `x` whichever side `x` is on. Multiply by a luminance
/// [cd/m^2] for an illuminance \[lx\].
pub fn polygon_irradiance(verts: &[DVec3], x: DVec3, n: DVec3) -> f64 {
    // Sutherland-Hodgman against the half-space n . (y - x) > 0.
    let h = |y: DVec3| n.dot(y - x);
    let mut clipped: Vec<DVec3> = Vec::with_capacity(verts.len() + 2);
    for (i, &p) in verts.iter().enumerate() {
        let q = verts[(i + 1) % verts.len()];
        let (hp, hq) = (h(p), h(q));
        if hp > 0.0 {
            clipped.push(p);
        }
        if (hp > 0.0) != (hq > 0.0) && hp != hq {
            let t = hp / (hp - hq);
            clipped.push(p + (q - p) * t);
        }
    }
    if clipped.len() < 3 {
        return 0.0;
    }
    let mut sum = CompensatedSum::default();
    for (i, &p) in clipped.iter().enumerate() {
        let q = clipped[(i + 1) % clipped.len()];
        sum.add(edge(p - x, q - x, n));
    }
    0.5 * sum.total().abs()
}

/// Whether `x` is on the emitting side of a planar source through `p` with
/// front normal `m` (both sides when `two_sided`).
#[inline]
fn facing(p: DVec3, m: DVec3, x: DVec3, two_sided: bool) -> bool {
    let s = m.dot(x - p);
    s > 0.0 || (two_sided && s < 0.0)
}

/// Illuminance per unit luminance [lx per cd/m^2] at `x` (unit normal `n`)
/// from the parallelogram `corner + a e1 + b e2` emitting towards
/// `e1 x e2` (and away from it too when `two_sided`).
pub fn rect_irradiance(
    corner: DVec3,
    e1: DVec3,
    e2: DVec3,
    x: DVec3,
    n: DVec3,
    two_sided: bool,
) -> f64 {
    let m = e1.cross(e2);
    if !facing(corner, m, x, two_sided) {
        return 0.0;
    }
    polygon_irradiance(&[corner, corner + e1, corner + e1 + e2, corner + e2], x, n)
}

/// Illuminance per unit luminance [lx per cd/m^2] at `x` (unit normal `n`)
/// from the disc of `radius` about `center` emitting towards unit
/// `normal` (and away from it too when `two_sided`); see the module docs.
pub fn disc_irradiance(
    center: DVec3,
    normal: DVec3,
    radius: f64,
    x: DVec3,
    n: DVec3,
    two_sided: bool,
) -> f64 {
    if !facing(center, normal, x, two_sided) {
        return 0.0;
    }
    // Frame of the disc, its normal towards x.
    let side = normal.dot(x - center).signum();
    let m = normal * side;
    let frame = Frame::from_normal(m);
    // The horizon: n . (y - x) = a + b cos(phi - phi0) on the rim.
    let (nu, nv) = (n.dot(frame.s), n.dot(frame.t));
    let a = n.dot(center - x);
    let b = radius * nu.hypot(nv);
    if a <= -b {
        return 0.0;
    }
    let rel = x - center;
    let h = rel.dot(m);
    let radial = rel - m * h;
    let rho = radial.length();
    if a >= b {
        // Wholly above the horizon: the irradiance vector in closed form.
        let r2 = radius * radius;
        let q = h * h + rho * rho + r2;
        // s = sqrt(q^2 - 4 R^2 rho^2) as a product (no cancellation).
        let s = (h * h + (rho - radius).powi(2)).sqrt() * (h * h + (rho + radius).powi(2)).sqrt();
        // 1 - b/s = (s - b)/s, with s - b = 4 R^2 h^2 / (s + b) when b > 0
        // (no cancellation far away or next to the rim).
        let b = h * h + rho * rho - r2;
        let s_minus_b = if b > 0.0 {
            4.0 * r2 * h * h / (s + b)
        } else {
            s - b
        };
        let axial = 0.5 * PI * s_minus_b / s;
        // (q / s - 1) / rho, written without cancellation for small rho:
        // q / s - 1 = (q^2 - s^2) / (s (q + s)) = 4 R^2 rho^2 / (s (q + s)).
        let radial_mag = 0.5 * PI * h * 4.0 * r2 * rho / (s * (q + s));
        let towards_axis = if rho > 0.0 {
            -radial / rho
        } else {
            DVec3::ZERO
        };
        // Directions to the disc point down its normal (-m) and in towards its axis.
        let e = (-m * axial + towards_axis * radial_mag).dot(n);
        return e.max(0.0);
    }
    // Cut by the horizon: the circular segment where n . (y - x) > 0.
    let phi0 = nv.atan2(nu);
    let alpha = (-a / b).clamp(-1.0, 1.0).acos();
    let rim = |phi: f64| {
        let (sp, cp) = phi.sin_cos();
        center + (frame.s * cp + frame.t * sp) * radius
    };
    let arc = |phi: f64| {
        let (sp, cp) = phi.sin_cos();
        let y = center + (frame.s * cp + frame.t * sp) * radius;
        let dy = (frame.t * cp - frame.s * sp) * radius;
        let r = y - x;
        r.cross(dy).dot(n) / r.length_squared()
    };
    let (lo, hi) = (phi0 - alpha, phi0 + alpha);
    // 32 Gauss-Legendre panels, each halved until its halves agree with it
    // to 1e-13 of the whole arc's size (at most 24 halvings): next to the
    // rim the integrand has a sharp peak (a receiver 1e-4 R from the rim
    // was 9 % off with the fixed panels; found by an mpmath check).
    fn adapt(
        f: &dyn Fn(f64) -> f64,
        (a, b): (f64, f64),
        whole: f64,
        tol: f64,
        depth: u32,
        sum: &mut CompensatedSum,
    ) {
        let g = |t: f64| f(t);
        let m = 0.5 * (a + b);
        let (l, r) = (panel(&g, a, m), panel(&g, m, b));
        if depth >= 24 || (l + r - whole).abs() <= tol {
            sum.add(l);
            sum.add(r);
        } else {
            adapt(f, (a, m), l, tol, depth + 1, sum);
            adapt(f, (m, b), r, tol, depth + 1, sum);
        }
    }
    let panels = 32;
    let step = (hi - lo) / panels as f64;
    let coarse: Vec<f64> = (0..panels)
        .map(|k| {
            let p0 = lo + step * k as f64;
            panel(&arc, p0, p0 + step)
        })
        .collect();
    let tol = 1e-13 * coarse.iter().map(|v| v.abs()).sum::<f64>().max(1e-300);
    let mut sum = CompensatedSum::default();
    for (k, &c) in coarse.iter().enumerate() {
        let p0 = lo + step * k as f64;
        adapt(&arc, (p0, p0 + step), c, tol, 0, &mut sum);
    }
    sum.add(edge(rim(hi) - x, rim(lo) - x, n));
    0.5 * sum.total().abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;

    /// Brute force: midpoint rule in polar coordinates over a disc, or in
    /// the two edge parameters of a parallelogram.
    fn brute(
        y_of: &dyn Fn(f64, f64) -> (DVec3, f64),
        m: DVec3,
        x: DVec3,
        n: DVec3,
        k: usize,
    ) -> f64 {
        let mut sum = 0.0;
        for i in 0..k {
            for j in 0..k {
                let (y, da) = y_of((i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64);
                let r = y - x;
                let d2 = r.length_squared();
                let cx = n.dot(r);
                let cy = m.dot(r).abs();
                if cx > 0.0 {
                    sum += cx * cy / (d2 * d2) * da;
                }
            }
        }
        sum / (k * k) as f64
    }

    fn rel_close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1e-12)
    }

    #[test]
    fn disc_closed_form_and_clipped_segments_against_brute_force() {
        let mut rng = Philox4x32::new(11, 0);
        let (c, m, r) = (
            DVec3::new(0.2, -0.1, 2.0),
            DVec3::new(0.3, 0.0, -1.0).normalize(),
            0.5,
        );
        let f = Frame::from_normal(m);
        let disc = |u: f64, v: f64| {
            let s = r * u.sqrt();
            let (sp, cp) = (2.0 * PI * v).sin_cos();
            (c + (f.s * cp + f.t * sp) * s, PI * r * r)
        };
        let (mut cut, mut whole) = (0, 0);
        for _ in 0..60 {
            let u = rng.next_2d();
            let w = rng.next_2d();
            let x = DVec3::new(2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0, 1.5 * w[0]);
            let n = crate::sampling::warp::sample_uniform_sphere(rng.next_2d()).w;
            let e = disc_irradiance(c, m, r, x, n, true);
            let b1 = brute(&disc, m, x, n, 500);
            let b2 = brute(&disc, m, x, n, 1000);
            // Midpoint error falls like 1/k^2: Richardson bound, plus a floor.
            let tol = 3.0 * (b2 - b1).abs() + 1e-9;
            assert!((e - b2).abs() <= tol, "x {x} n {n}: {e} vs {b2} ({b1})");
            let a = n.dot(c - x);
            let bb = r * (1.0 - n.dot(m).powi(2)).sqrt();
            if a.abs() < bb {
                cut += 1
            } else if a > 0.0 {
                whole += 1
            }
        }
        assert!(cut >= 10 && whole >= 10, "cut {cut}, whole {whole}");
        // On the axis: pi R^2 / (R^2 + h^2).
        let x = c + m * 1.3;
        let e = disc_irradiance(c, m, r, x, -m, false);
        assert!(rel_close(e, PI * r * r / (r * r + 1.3 * 1.3), 1e-14), "{e}");
        // One-sided: nothing behind.
        assert_eq!(disc_irradiance(c, m, r, c - m * 0.5, m, false), 0.0);
        // Far on the axis, no cancellation: pi R^2 / (R^2 + h^2) to rounding.
        for h in [1e3, 1e4] {
            let e = disc_irradiance(DVec3::ZERO, DVec3::Z, 1.0, DVec3::Z * h, -DVec3::Z, false);
            assert!(rel_close(e, PI / (1.0 + h * h), 1e-13), "h {h}: {e}");
        }
    }

    /// Next to the rim with the horizon cutting the disc, the disc lies
    /// between its inscribed and circumscribed 65536-gons, and every part of
    /// it above the horizon adds light: the exact value is bracketed.
    #[test]
    fn horizon_cut_disc_next_to_its_rim_is_bracketed_by_polygons() {
        let n = DVec3::new(0.0, 1.0, -0.2).normalize();
        let k = 65536;
        let poly = |rad: f64| -> Vec<DVec3> {
            (0..k)
                .map(|i| {
                    let t = 2.0 * PI * i as f64 / k as f64;
                    DVec3::new(rad * t.cos(), rad * t.sin(), 0.0)
                })
                .collect()
        };
        let (inner, outer) = (poly(1.0), poly(1.0 / (PI / k as f64).cos()));
        for d in [1e-2, 1e-3, 1e-4] {
            let x = DVec3::new(1.0 + d, 0.0, d);
            let e = disc_irradiance(DVec3::ZERO, DVec3::Z, 1.0, x, n, false);
            let (lo, hi) = (
                polygon_irradiance(&inner, x, n),
                polygon_irradiance(&outer, x, n),
            );
            assert!(
                lo <= e * (1.0 + 1e-12) && e <= hi * (1.0 + 1e-12),
                "delta {d}: {lo} <= {e} <= {hi}"
            );
            assert!((hi - lo) < 1e-3 * e, "delta {d}: bracket too wide");
        }
    }

    #[test]
    fn rectangle_against_brute_force_and_the_corner_form_factor() {
        let (o, e1, e2) = (
            DVec3::new(-0.3, 0.6, 3.0),
            DVec3::new(0.6, 0.0, 0.0),
            DVec3::new(0.0, -1.2, 0.0),
        );
        let m = e1.cross(e2).normalize();
        let rect = |u: f64, v: f64| (o + e1 * u + e2 * v, 0.72);
        let mut rng = Philox4x32::new(3, 0);
        for _ in 0..40 {
            let u = rng.next_2d();
            let x = DVec3::new(3.0 * u[0] - 1.5, 3.0 * u[1] - 1.5, 2.9 * rng.next_f64());
            let n = crate::sampling::warp::sample_uniform_sphere(rng.next_2d()).w;
            let e = rect_irradiance(o, e1, e2, x, n, false);
            let b1 = brute(&rect, m, x, n, 500);
            let b2 = brute(&rect, m, x, n, 1000);
            let tol = 3.0 * (b2 - b1).abs() + 1e-9;
            assert!((e - b2).abs() <= tol, "x {x} n {n}: {e} vs {b2}");
        }
        // Corner of a parallel rectangle a x b at height c (Howell B-3):
        // F = (1/2pi) [A atan(B/sqrt) ...]; here pi F with A = a/sqrt(a^2+c^2) etc.
        let (a, b, c): (f64, f64, f64) = (0.6, 1.2, 3.0);
        let (xa, yb) = (a / c, b / c);
        let f = (xa / (1.0 + xa * xa).sqrt() * (yb / (1.0 + xa * xa).sqrt()).atan()
            + yb / (1.0 + yb * yb).sqrt() * (xa / (1.0 + yb * yb).sqrt()).atan())
            / (2.0 * PI);
        let x = DVec3::new(-0.3, 0.6, 0.0);
        let e = rect_irradiance(o, e1, e2, x, DVec3::Z, false);
        assert!(rel_close(e, PI * f, 1e-13), "{e} vs {}", PI * f);
        assert_eq!(
            rect_irradiance(o, e1, e2, DVec3::new(0.0, 0.0, 3.5), -DVec3::Z, false),
            0.0
        );
    }
}
