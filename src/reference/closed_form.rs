//! Closed-form and quadrature references for finite geometry: the
//! integrating sphere, a point source over a square plate, the direct
//! illuminance of a point source.
//!
//! **Integrating sphere.** A point source of flux `Phi` \[lm\] anywhere inside
//! a sphere of radius `R` with a Lambertian inner wall of reflectance `rho`.
//! Between two wall points the kernel `cos cos / d^2` equals `1 / (4 R^2)`
//! (the chord makes equal angles `cos = d / 2R` with both normals), so light
//! reflected once or more is uniform over the wall. The first reflection
//! leaves `rho Phi` spread as exitance; each bounce onto the wall is uniform
//! irradiance `rho^k Phi / (4 pi R^2)`. Summing the orders:
//! `E_ind = rho Phi / (4 pi R^2 (1 - rho))` at every wall point, whatever the
//! source position. The direct term is `I cos / d^2` from the source.
//!
//! **Square plate.** A Lambertian plate of side `a` in `z = 0` (corner at the
//! origin, front side `+z`, reflectance `rho`) lit by an isotropic point
//! source `S` of intensity `I` above it; a receiver at `P` above the plate.
//! The plate is flat, so light reflects off it once only:
//! `E(P) = E_dir(P) + int_plate (rho / pi) E_plate(y) cos_y cos_P / d^2 dA`
//! with `E_plate(y) = I S_z / |S - y|^3`. The integrand is smooth (S and P lie
//! off the plate), so adaptive Gauss-Legendre reaches 1e-13. When the plate
//! is lit uniformly (`E_plate = E0`) and `P` is on the normal through a
//! corner, facing the plate, the integral is `rho E0 F` with the closed-form
//! corner form factor [`corner_form_factor`]; the tests check the quadrature
//! against it.

use gauss_quad::legendre::GaussLegendre;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Indirect illuminance \[lx\] on the wall of an integrating sphere of radius
/// `radius` \[m\], wall reflectance `rho` < 1, source flux `flux` \[lm\].
pub fn integrating_sphere_indirect(rho: f64, flux: f64, radius: f64) -> f64 {
    rho * flux / (4.0 * PI * radius * radius * (1.0 - rho))
}

/// Direct illuminance \[lx\] at `p` (unit normal `n`) from an isotropic point
/// source of intensity `i` \[cd\] at `s`, unoccluded: `I cos / d^2`, 0 from behind.
pub fn point_illuminance(i: f64, s: DVec3, p: DVec3, n: DVec3) -> f64 {
    let d = s - p;
    let c = n.dot(d);
    if c <= 0.0 {
        0.0
    } else {
        i * c / d.length_squared().powf(1.5)
    }
}

/// Form factor from a differential area at height `h` \[m\] on the normal
/// through a corner of an `a x b` rectangle, parallel to it and facing it.
pub fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

fn rule(n: usize) -> &'static [(f64, f64)] {
    static R10: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    static R21: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    let make = |n| {
        let n = std::num::NonZeroUsize::new(n).expect("non-zero");
        GaussLegendre::new(n).as_node_weight_pairs().to_vec()
    };
    match n {
        10 => R10.get_or_init(|| make(10)),
        _ => R21.get_or_init(|| make(21)),
    }
}

fn gl2(f: &dyn Fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64, n: usize) -> f64 {
    let (mx, hx, my, hy) = (
        0.5 * (x0 + x1),
        0.5 * (x1 - x0),
        0.5 * (y0 + y1),
        0.5 * (y1 - y0),
    );
    let r = rule(n);
    let mut s = 0.0;
    for &(u, wu) in r {
        let mut row = 0.0;
        for &(v, wv) in r {
            row += wv * f(mx + hx * u, my + hy * v);
        }
        s += wu * row;
    }
    s * hx * hy
}

/// Adaptive tensor Gauss-Legendre over a rectangle: a 21x21 rule on the
/// rectangle against the sum of the same rule on its four quarters; split
/// until they agree to `tol` (absolute), the tolerance shared by area.
/// Meant for smooth integrands (a kink needs the domain split at it).
pub fn adaptive_2d(
    f: &dyn Fn(f64, f64) -> f64,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    tol: f64,
) -> f64 {
    fn quarters(f: &dyn Fn(f64, f64) -> f64, r: [f64; 4]) -> [([f64; 4], f64); 4] {
        let (mx, my) = (0.5 * (r[0] + r[1]), 0.5 * (r[2] + r[3]));
        [
            [r[0], mx, r[2], my],
            [mx, r[1], r[2], my],
            [r[0], mx, my, r[3]],
            [mx, r[1], my, r[3]],
        ]
        .map(|q| (q, gl2(f, q[0], q[1], q[2], q[3], 21)))
    }
    fn go(f: &dyn Fn(f64, f64) -> f64, r: [f64; 4], whole: f64, tol: f64, depth: u32) -> f64 {
        let parts = quarters(f, r);
        let sum: f64 = parts.iter().map(|p| p.1).sum();
        if (sum - whole).abs() <= tol || depth >= 12 {
            return sum;
        }
        parts
            .iter()
            .map(|&(q, v)| go(f, q, v, tol / 4.0, depth + 1))
            .sum()
    }
    let whole = gl2(f, x0, x1, y0, y1, 21);
    go(f, [x0, x1, y0, y1], whole, tol, 0)
}

/// A point source above a square Lambertian plate (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct PlateCase {
    /// Side of the plate \[m\]; the plate is `[0, a] x [0, a]` in `z = 0`.
    pub a: f64,
    /// Reflectance of the plate's upper side.
    pub rho: f64,
    /// Source position \[m\], `z > 0`.
    pub source: DVec3,
    /// Source intensity \[cd\].
    pub intensity: f64,
}

impl PlateCase {
    /// Illuminance \[lx\] on the plate at `(x, y, 0)` (direct only).
    pub fn plate_illuminance(&self, x: f64, y: f64) -> f64 {
        point_illuminance(self.intensity, self.source, DVec3::new(x, y, 0.0), DVec3::Z)
    }

    /// Illuminance \[lx\] at `p` (`z > 0`, unit normal `n`): direct plus light
    /// reflected once by the plate, to about 1e-13 relative.
    pub fn illuminance(&self, p: DVec3, n: DVec3) -> (f64, f64) {
        let direct = point_illuminance(self.intensity, self.source, p, n);
        let reflected =
            reflected_from_plate(self.a, self.rho, p, n, &|x, y| self.plate_illuminance(x, y));
        (direct, reflected)
    }
}

/// Illuminance \[lx\] at `p` (`z > 0`, unit normal `n`) from a Lambertian
/// plate `[0, a]^2` in `z = 0` of reflectance `rho` whose own illuminance is
/// `e_plate(x, y)` \[lx\].
pub fn reflected_from_plate(
    a: f64,
    rho: f64,
    p: DVec3,
    n: DVec3,
    e_plate: &dyn Fn(f64, f64) -> f64,
) -> f64 {
    let f = |x: f64, y: f64| {
        let d = p - DVec3::new(x, y, 0.0);
        let d2 = d.length_squared();
        let cy = d.z; // times d
        let cp = -n.dot(d); // times d
        if cp <= 0.0 || cy <= 0.0 {
            return 0.0;
        }
        rho / PI * e_plate(x, y) * cy * cp / (d2 * d2)
    };
    // Scale of the total for the absolute tolerance: a coarse pass.
    let rough = gl2(&f, 0.0, a, 0.0, a, 21).abs().max(f64::MIN_POSITIVE);
    adaptive_2d(&f, 0.0, a, 0.0, a, 1e-14 * rough)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_form_factor_limits() {
        // An infinite quadrant seen from any height: 1/4.
        assert!((corner_form_factor(1e9, 1e9, 1.0) - 0.25).abs() < 1e-8);
        // Four corner rectangles make a centred one: compare with the
        // centred square form factor by 2-D integration of cos^2/(pi d^2).
        let h = 0.7;
        let f = |x: f64, y: f64| h * h / (PI * (x * x + y * y + h * h).powi(2));
        let quad = adaptive_2d(&f, -1.0, 1.0, -1.5, 1.5, 1e-16);
        assert!((4.0 * corner_form_factor(1.0, 1.5, h) - quad).abs() < 1e-13);
    }

    #[test]
    fn uniform_plate_matches_the_closed_form_form_factor() {
        for (a, h, rho, e0) in [
            (1.0, 0.3, 0.8, 2.5),
            (2.0, 2.0, 0.5, 1.0),
            (0.01, 1e-4, 0.9, 7.0),
        ] {
            let p = DVec3::new(0.0, 0.0, h);
            let q = reflected_from_plate(a, rho, p, -DVec3::Z, &|_, _| e0);
            let exact = rho * e0 * corner_form_factor(a, a, h);
            assert!(((q - exact) / exact).abs() < 1e-12, "{q} {exact}");
        }
    }

    #[test]
    fn integrating_sphere_flux_balance() {
        // Absorbed flux: (1 - rho) * (direct + indirect flux onto the wall) = Phi.
        let (rho, phi, r) = (0.9, 1000.0, 1.5);
        let e = integrating_sphere_indirect(rho, phi, r);
        let onto_wall = phi + e * 4.0 * PI * r * r;
        assert!(((1.0 - rho) * onto_wall - phi).abs() < 1e-9 * phi);
    }
}
