//! Illuminance from a Lambertian disc with a radial luminance profile, by
//! 2-D quadrature in polar coordinates on the disc. Independent of the
//! estimators and of [`crate::light::radial_profile`]: the profiles are
//! written here again from their definitions (seed 000, with the
//! hyperbolic ones made finite as documented there).

use crate::math::quadrature::panel;
use glam::DVec3;
use std::f64::consts::PI;

/// Relative luminance of the named profile at radius `s` on a disc of
/// radius `r` (peak 1; `R/s` for `hyperbolic-decreasing`, 1 at the rim),
/// with `t` the turning radius of `v` and `tent` or the offset of
/// `hyperbolic-increasing`. `None` for an unknown name.
pub fn profile_luminance(name: &str, r: f64, t: f64, s: f64) -> Option<f64> {
    Some(match name {
        "uniform" => 1.0,
        "linear-decreasing" => 1.0 - s / r,
        "linear-increasing" => s / r,
        "v" => (s - t).abs() / t.max(r - t),
        "tent" => {
            if s <= t {
                s / t
            } else {
                (r - s) / (r - t)
            }
        }
        "hyperbolic-decreasing" => r / s,
        "hyperbolic-increasing" => t / (r + t - s),
        _ => return None,
    })
}

/// Illuminance \[lx\] at `x` (unit normal `n`) from a disc (centre `c`, unit
/// emitting normal `m`, radius `r`) of luminance `l(s)` [cd/m^2] at radius
/// `s`, emitting from its front only:
/// `E = int_0^r int_0^2pi l(s) max(0, cos_x) max(0, cos_y) / d^2 s dphi ds`,
/// with 20-point Gauss-Legendre panels in `s` (split at `kinks`, 64
/// panels) and in `phi` (64 panels; the horizon cut is smooth enough at
/// this resolution for the tests' 1e-6). A `1/s` profile is integrable
/// here because the area element carries `s`.
pub fn disc_illuminance(
    c: DVec3,
    m: DVec3,
    r: f64,
    l: &dyn Fn(f64) -> f64,
    kinks: &[f64],
    x: DVec3,
    n: DVec3,
) -> f64 {
    // An orthonormal pair in the disc's plane (written here, not shared).
    let a = if m.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = (a - m * a.dot(m)).normalize();
    let v = m.cross(u);
    let ring = |s: f64| {
        let g = |phi: f64| {
            let (sp, cp) = phi.sin_cos();
            let y = c + (u * cp + v * sp) * s;
            let d = y - x;
            let d2 = d.length_squared();
            let cx = n.dot(d);
            let cy = -m.dot(d);
            if cx <= 0.0 || cy <= 0.0 {
                0.0
            } else {
                cx * cy / (d2 * d2)
            }
        };
        let panels = 64;
        let h = 2.0 * PI / panels as f64;
        let around: f64 = (0..panels)
            .map(|k| panel(&g, h * k as f64, h * (k + 1) as f64))
            .sum();
        l(s) * s * around
    };
    let mut edges: Vec<f64> = std::iter::once(0.0)
        .chain(kinks.iter().copied().filter(|&k| k > 0.0 && k < r))
        .chain(std::iter::once(r))
        .collect();
    edges.sort_by(f64::total_cmp);
    let mut sum = 0.0;
    for w in edges.windows(2) {
        let panels = 64;
        let h = (w[1] - w[0]) / panels as f64;
        for k in 0..panels {
            let lo = w[0] + h * k as f64;
            sum += panel(&ring, lo, lo + h);
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_disc_on_axis_and_linear_profiles_in_one_dimension() {
        let (c, m, r) = (DVec3::new(0.0, 0.0, 2.0), -DVec3::Z, 0.5);
        for h in [0.1, 0.7, 2.0] {
            let x = DVec3::new(0.0, 0.0, 2.0 - h);
            // Uniform: pi L R^2 / (R^2 + h^2).
            let e = disc_illuminance(c, m, r, &|_| 1.0, &[], x, DVec3::Z);
            let exact = PI * r * r / (r * r + h * h);
            assert!((e / exact - 1.0).abs() < 1e-10, "h {h}: {e} vs {exact}");
            // Linear-increasing on axis: 2 pi int (s/R) h^2 s / (s^2 + h^2)^2 ds
            // = (2 pi h^2 / R) [ atan(R/h)/(2h) - R / (2 (R^2 + h^2)) ].
            let e = disc_illuminance(c, m, r, &|s| s / r, &[], x, DVec3::Z);
            let exact =
                2.0 * PI * h * h / r * ((r / h).atan() / (2.0 * h) - r / (2.0 * (r * r + h * h)));
            assert!((e / exact - 1.0).abs() < 1e-10, "h {h}: {e} vs {exact}");
        }
    }
}
