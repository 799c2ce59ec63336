//! Median cut (Debevec 2005, "A median cut algorithm for light probe
//! sampling"; seed 003): an environment map becomes `N = 2^k` distant
//! lights of equal energy, an approximation to the map (its bias is
//! reported, see `tests/median_cut.rs`).
//!
//! The "energy" of a cell of the equirectangular table is its luminance
//! times its solid angle, `e_ij = L_ij Omega_i` [cd/m^2 sr = lx at normal
//! incidence]; a summed-area table of `e` gives any rectangle's energy in
//! O(1). Starting from the whole map, every region is split, `k` times
//! over, across its longer angular extent (the height `dtheta` against the
//! width `dphi sin(theta)` at the region's middle latitude, so regions
//! near the poles are not cut into slivers) at the line that divides its
//! energy most nearly in half. Each final region becomes a collimated
//! distant light from the direction of its energy centroid (the
//! energy-weighted mean of its cells' centre directions, normalised) with
//! illuminance `E_n = sum e` normal to it: the region's light lumped into
//! one direction.

use super::environment::Environment;
use glam::DVec3;
use std::f64::consts::PI;

/// One light of the cut: the direction towards it (unit) and its normal
/// illuminance \[lx\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutLight {
    /// Unit world direction towards the light.
    pub wi: DVec3,
    /// Illuminance on a plane normal to `wi` \[lx\].
    pub e_n: f64,
}

/// A rectangle of cells: rows `i0..i1`, columns `j0..j1`.
#[derive(Clone, Copy, Debug)]
struct Region {
    i0: usize,
    i1: usize,
    j0: usize,
    j1: usize,
}

/// Summed-area table of cell energies.
struct Sat {
    cols: usize,
    s: Vec<f64>,
}

impl Sat {
    fn new(e: &[f64], rows: usize, cols: usize) -> Self {
        let mut s = vec![0.0; (rows + 1) * (cols + 1)];
        for i in 0..rows {
            let mut row = 0.0;
            for j in 0..cols {
                row += e[i * cols + j];
                s[(i + 1) * (cols + 1) + j + 1] = s[i * (cols + 1) + j + 1] + row;
            }
        }
        Self { cols, s }
    }

    /// Energy of rows `i0..i1`, columns `j0..j1`.
    fn sum(&self, r: Region) -> f64 {
        let w = self.cols + 1;
        (self.s[r.i1 * w + r.j1] - self.s[r.i0 * w + r.j1] - self.s[r.i1 * w + r.j0]
            + self.s[r.i0 * w + r.j0])
            .max(0.0)
    }
}

/// Split `env` into `n` lights (`n` a power of two, at most the number of
/// cells).
pub fn median_cut(env: &Environment, n: usize) -> Result<Vec<CutLight>, String> {
    if n == 0 || !n.is_power_of_two() {
        return Err(format!(
            "the number of lights must be a power of two, got {n}"
        ));
    }
    let (rows, cols) = env.table_size();
    if n > rows * cols {
        return Err(format!(
            "{n} lights from a map of {} cells: at most one light per cell",
            rows * cols
        ));
    }
    let e: Vec<f64> = (0..rows * cols)
        .map(|k| env.cell_value(k / cols, k % cols) * env.cell_solid_angle(k / cols))
        .collect();
    let sat = Sat::new(&e, rows, cols);
    let dtheta = PI / rows as f64;
    let dphi = 2.0 * PI / cols as f64;
    let mut regions = vec![Region {
        i0: 0,
        i1: rows,
        j0: 0,
        j1: cols,
    }];
    while regions.len() < n {
        let mut next = Vec::with_capacity(regions.len() * 2);
        for r in regions {
            let (h, w) = (r.i1 - r.i0, r.j1 - r.j0);
            let mid = 0.5 * (r.i0 + r.i1) as f64 * dtheta;
            let tall = h as f64 * dtheta;
            let wide = w as f64 * dphi * mid.sin();
            // Split across the longer extent; a region one cell long that
            // way is split the other way.
            let by_rows = (tall >= wide && h > 1) || w == 1;
            let total = sat.sum(r);
            let (a, b) = if by_rows {
                let k = best_split(r.i0, r.i1, |k| sat.sum(Region { i1: k, ..r }), total);
                (Region { i1: k, ..r }, Region { i0: k, ..r })
            } else {
                let k = best_split(r.j0, r.j1, |k| sat.sum(Region { j1: k, ..r }), total);
                (Region { j1: k, ..r }, Region { j0: k, ..r })
            };
            next.push(a);
            next.push(b);
        }
        regions = next;
    }
    Ok(regions
        .iter()
        .map(|r| {
            let mut c = DVec3::ZERO;
            let mut sum = 0.0;
            for i in r.i0..r.i1 {
                for j in r.j0..r.j1 {
                    let v = e[i * cols + j];
                    c += env.cell_direction(i, j) * v;
                    sum += v;
                }
            }
            let wi = if c.length() > 0.0 {
                c.normalize()
            } else {
                env.cell_direction((r.i0 + r.i1) / 2, (r.j0 + r.j1) / 2)
            };
            CutLight { wi, e_n: sum }
        })
        .collect())
}

/// The cut `k` in `(lo, hi)` whose first part's energy `first(k)` is
/// closest to half of `total` (`lo + 1` when the span is 1 cell... never:
/// callers split spans of 2 cells or more; a span of one cell gives `hi`).
fn best_split(lo: usize, hi: usize, first: impl Fn(usize) -> f64, total: f64) -> usize {
    if hi - lo < 2 {
        return hi;
    }
    // The first part's energy grows with k: bisect for half, then take the
    // nearer neighbour.
    let half = 0.5 * total;
    let (mut a, mut b) = (lo + 1, hi - 1);
    while a < b {
        let m = (a + b) / 2;
        if first(m) < half {
            a = m + 1;
        } else {
            b = m;
        }
    }
    let k = a;
    if k > lo + 1 && (first(k - 1) - half).abs() <= (first(k) - half).abs() {
        k - 1
    } else {
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::Mapping;

    #[test]
    fn energy_is_conserved_and_regions_are_equal_for_a_uniform_map() {
        let y = vec![2.0; 32 * 16];
        let env = Environment::new(&y, 32, 16, Mapping::Equirect, 1.0, 0.0).unwrap();
        for n in [1, 2, 16, 64] {
            let cut = median_cut(&env, n).unwrap();
            assert_eq!(cut.len(), n);
            let sum: f64 = cut.iter().map(|c| c.e_n).sum();
            assert!((sum - env.integral()).abs() < 1e-12 * sum, "{n}: {sum}");
            for c in &cut {
                assert!((c.wi.length() - 1.0).abs() < 1e-12);
            }
        }
        // One light of a uniform map: the centroid of the whole sphere is
        // undefined (zero vector); a single upper-hemisphere map points up.
        let y: Vec<f64> = (0..32 * 16)
            .map(|k| if k / 32 < 8 { 1.0 } else { 0.0 })
            .collect();
        let env = Environment::new(&y, 32, 16, Mapping::Equirect, 1.0, 0.0).unwrap();
        let cut = median_cut(&env, 1).unwrap();
        assert!((cut[0].wi - DVec3::Z).length() < 1e-12);
        assert!(median_cut(&env, 3).is_err() && median_cut(&env, 1024).is_err());
    }
}
