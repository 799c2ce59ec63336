//! Closed forms for uniform Lambertian area sources and a cosine luminaire,
//! from the configuration-factor catalogue (Howell, "A Catalog of
//! Radiation Heat Transfer Configuration Factors", plane element to a
//! rectangle), derived here and combined by superposition. Independent of
//! the estimators and of [`crate::light::lambert`].

use std::f64::consts::PI;

/// Configuration factor from a plane element to a parallel rectangle
/// `[0, a] x [0, b]` at height `c` above it, one corner over the element:
/// `F = (1 / 2 pi) [A / sqrt(1 + A^2) atan(B / sqrt(1 + A^2)) + B / sqrt(1 + B^2) atan(A / sqrt(1 + B^2))]`,
/// `A = a / c`, `B = b / c`; odd in `a` and in `b` (for superposition).
pub fn parallel_corner(a: f64, b: f64, c: f64) -> f64 {
    let (sa, sb) = (a.signum(), b.signum());
    let (x, y) = (a.abs() / c, b.abs() / c);
    if x == 0.0 || y == 0.0 {
        return 0.0;
    }
    let (rx, ry) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    sa * sb * (x / rx * (y / rx).atan() + y / ry * (x / ry).atan()) / (2.0 * PI)
}

/// Configuration factor from a plane element to a rectangle in a
/// perpendicular plane at distance `c`, spanning `[0, a]` along the line
/// where the planes meet (measured from the element's foot) and `[0, b]`
/// away from the element's plane: with `y` along the line and `z` up,
/// `F = (c / pi) int int z / (c^2 + y^2 + z^2)^2 dz dy
///    = (1 / 2 pi) [atan(a / c) - c / sqrt(c^2 + b^2) atan(a / sqrt(c^2 + b^2))]`;
/// odd in `a`.
pub fn perpendicular_corner(a: f64, b: f64, c: f64) -> f64 {
    let s = a.signum();
    let a = a.abs();
    let q = (c * c + b * b).sqrt();
    s * ((a / c).atan() - c / q * (a / q).atan()) / (2.0 * PI)
}

/// Illuminance \[lx\] at a point facing a parallel rectangle of luminance
/// `l` [cd/m^2] at height `c` \[m\], the rectangle spanning `[x0, x1] x
/// [y0, y1]` \[m\] relative to the point's foot: `pi L F` by superposition of
/// four corner rectangles.
pub fn parallel_rectangle(l: f64, x0: f64, x1: f64, y0: f64, y1: f64, c: f64) -> f64 {
    let g = |x: f64, y: f64| parallel_corner(x, y, c);
    PI * l * (g(x1, y1) - g(x0, y1) - g(x1, y0) + g(x0, y0))
}

/// Illuminance \[lx\] at a point from a rectangle of luminance `l` in a plane
/// perpendicular to the point's, at distance `c` \[m\], spanning `[y0, y1]`
/// along the planes' common direction (relative to the point's foot) and
/// `[z0, z1]` (`0 <= z0 < z1`) above the point's plane.
pub fn perpendicular_rectangle(l: f64, y0: f64, y1: f64, z0: f64, z1: f64, c: f64) -> f64 {
    let g = |y: f64, z: f64| perpendicular_corner(y, z, c);
    PI * l * (g(y1, z1) - g(y0, z1) - g(y1, z0) + g(y0, z0))
}

/// Illuminance \[lx\] on a plane a height `h` \[m\] below a luminaire of
/// intensity `I0 cos(theta)` \[cd\] (`theta` from the downward vertical), at
/// distance `d` \[m\] from it: `I(theta) cos(theta) / d^2 = I0 h^2 / d^4`.
pub fn cosine_intensity_plane(i0: f64, h: f64, d: f64) -> f64 {
    i0 * h * h / (d * d * d * d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Midpoint rule of the defining integral.
    fn brute_parallel(x0: f64, x1: f64, y0: f64, y1: f64, c: f64, m: usize) -> f64 {
        let (dx, dy) = ((x1 - x0) / m as f64, (y1 - y0) / m as f64);
        let mut s = 0.0;
        for i in 0..m {
            for j in 0..m {
                let (x, y) = (x0 + (i as f64 + 0.5) * dx, y0 + (j as f64 + 0.5) * dy);
                let r2 = x * x + y * y + c * c;
                s += c * c / (r2 * r2);
            }
        }
        s * dx * dy
    }

    fn brute_perpendicular(y0: f64, y1: f64, z0: f64, z1: f64, c: f64, m: usize) -> f64 {
        let (dy, dz) = ((y1 - y0) / m as f64, (z1 - z0) / m as f64);
        let mut s = 0.0;
        for i in 0..m {
            for j in 0..m {
                let (y, z) = (y0 + (i as f64 + 0.5) * dy, z0 + (j as f64 + 0.5) * dz);
                let r2 = y * y + z * z + c * c;
                s += z * c / (r2 * r2);
            }
        }
        s * dy * dz
    }

    #[test]
    fn superposed_corners_match_the_defining_integrals() {
        for (x0, x1, y0, y1, c) in [
            (-0.3, 0.3, -0.6, 0.6, 3.0),
            (0.5, 1.2, -0.2, 0.9, 0.7),
            (-2.0, -0.5, 0.1, 0.4, 1.5),
        ] {
            let e = parallel_rectangle(1.0, x0, x1, y0, y1, c);
            let b = brute_parallel(x0, x1, y0, y1, c, 2000);
            assert!((e / b - 1.0).abs() < 1e-6, "{e} vs {b}");
        }
        for (y0, y1, z0, z1, c) in [
            (-0.5, 0.5, 0.0, 1.0, 0.8),
            (0.2, 1.4, 0.3, 2.0, 1.1),
            (-1.0, -0.1, 1.0, 1.5, 0.4),
        ] {
            let e = perpendicular_rectangle(1.0, y0, y1, z0, z1, c);
            let b = brute_perpendicular(y0, y1, z0, z1, c, 2000);
            assert!((e / b - 1.0).abs() < 1e-6, "{e} vs {b}");
        }
        // A large parallel rectangle approaches the infinite plane: pi L.
        let e = parallel_rectangle(1.0, -1e6, 1e6, -1e6, 1e6, 1.0);
        assert!((e / PI - 1.0).abs() < 1e-5);
    }
}
