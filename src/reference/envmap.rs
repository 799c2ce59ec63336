//! The illuminance an environment map gives an unobstructed receiver, by
//! quadrature over its pixels: the reference for importance sampling and
//! median cut ([`crate::cases::daylight`], `tests/median_cut.rs`), sharing
//! no code with the light that samples the map.

use glam::DVec3;
use std::f64::consts::PI;

/// `sum_pixels L int_pixel max(0, n . w) dw` of an equirectangular map
/// (`y` row-major, row 0 the zenith, the left edge at `+x`, columns turning
/// clockwise seen from above, so column `j` spans the azimuths `phi` (from
/// `+x` towards `+y`) from `-2 pi (j + 1) / w` to `-2 pi j / w`, as the
/// README states), 8 x 8 midpoints per pixel uniform in `cos theta` and
/// `phi` (equal solid angles).
pub fn pixel_quadrature(y: &[f64], w: usize, h: usize, scale: f64, n: DVec3) -> f64 {
    let m = 8;
    let mut sum = 0.0;
    for i in 0..h {
        let (c0, c1) = (
            (PI * i as f64 / h as f64).cos(),
            (PI * (i + 1) as f64 / h as f64).cos(),
        );
        let omega = (c0 - c1) * 2.0 * PI / w as f64 / (m * m) as f64;
        for j in 0..w {
            let l = y[i * w + j] * scale;
            if l == 0.0 {
                continue;
            }
            let mut acc = 0.0;
            for a in 0..m {
                let ct = c0 + (c1 - c0) * (a as f64 + 0.5) / m as f64;
                let st = (1.0 - ct * ct).max(0.0).sqrt();
                for b in 0..m {
                    let phi = -2.0 * PI * (j as f64 + (b as f64 + 0.5) / m as f64) / w as f64;
                    acc += n
                        .dot(DVec3::new(st * phi.cos(), st * phi.sin(), ct))
                        .max(0.0);
                }
            }
            sum += l * acc * omega;
        }
    }
    sum
}
