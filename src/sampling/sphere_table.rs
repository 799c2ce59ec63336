//! A piecewise-constant density over the sphere, tabulated on a
//! `(theta, phi)` grid: the exact importance sampler of an environment map.
//!
//! The table holds `nt x np` non-negative values `f_ij` (row `i` spans
//! `theta in [pi i / nt, pi (i + 1) / nt]`, column `j` spans `phi in [2 pi j
//! / np, 2 pi (j + 1) / np]`; `theta` from the map's pole). With the
//! `sin(theta)` measure each cell's solid angle is exact,
//! `Omega_ij = (cos theta_i - cos theta_{i+1}) 2 pi / np`, and the density
//! per solid angle is
//!
//! `p(w) = f_ij / F`, `F = sum_ij f_ij Omega_ij`,
//!
//! constant in each cell: proportional to the map's value itself (a map of
//! luminance is sampled in proportion to luminance, exactly). Sampling
//! (Pharr, Jakob, Humphreys, *PBRT* 4th ed., Sec. A.5.6, with the solid angle
//! folded into the marginal instead of a `sin` factor on the pixel): a row
//! from the marginal CDF of the rows' masses `sum_j f_ij Omega_ij`, a
//! column from the row's conditional CDF of `f_ij`, then a point uniform by
//! solid angle in the cell (`cos theta` uniform between the row's edges,
//! `phi` uniform). Each uniform is remapped within its CDF step, so the
//! map `u -> w` is continuous inside a cell and [`SphereTable::invert`]
//! recovers `u` exactly. Family: [`SphereTable::sample`],
//! [`SphereTable::pdf`], [`SphereTable::invert`], with explicit uniforms.

use core::f64::consts::PI;

/// Largest `f64` strictly below 1.
const ONE_MINUS_EPSILON: f64 = 1.0 - f64::EPSILON / 2.0;

/// Why a table was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TableError {
    /// The size does not match the values, or a dimension is zero.
    #[error("table of {rows} x {cols} cells needs {} values, got {got}", rows * cols)]
    Size {
        rows: usize,
        cols: usize,
        got: usize,
    },
    /// A value is negative or not finite.
    #[error("cell {index} is {value}: values must be finite and >= 0")]
    Value { index: usize, value: f64 },
    /// Every value is zero: nothing to sample.
    #[error("every cell is zero: nothing to sample")]
    Empty,
}

/// A sampled direction of a [`SphereTable`], in the table's own spherical
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereTableSample {
    /// `cos theta` (theta from the pole).
    pub cos_theta: f64,
    /// `phi` in `[0, 2 pi)` \[rad\].
    pub phi: f64,
    /// Density per solid angle [1/sr].
    pub pdf: f64,
    /// Row and column of the cell.
    pub cell: (usize, usize),
}

/// The tabulated density (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SphereTable {
    rows: usize,
    cols: usize,
    /// Values, row-major.
    f: Vec<f64>,
    /// `cos theta` at the row edges (`rows + 1`, from 1 down to -1).
    cos_edge: Vec<f64>,
    /// Marginal CDF over rows (`rows + 1`, from 0 to 1).
    row_cdf: Vec<f64>,
    /// Conditional CDFs over columns, `cols + 1` per row.
    col_cdf: Vec<f64>,
    /// `F = sum f Omega`.
    total: f64,
}

impl SphereTable {
    /// A table of `rows x cols` values `f` (row-major; row 0 at the pole
    /// `theta = 0`, column 0 at `phi = 0`).
    pub fn new(f: Vec<f64>, rows: usize, cols: usize) -> Result<Self, TableError> {
        if rows == 0 || cols == 0 || f.len() != rows * cols {
            return Err(TableError::Size {
                rows,
                cols,
                got: f.len(),
            });
        }
        if let Some((index, &value)) = f
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(TableError::Value { index, value });
        }
        let cos_edge: Vec<f64> = (0..=rows)
            .map(|i| {
                if i == rows {
                    -1.0
                } else if 2 * i == rows {
                    // The horizon, exactly (`cos(pi / 2)` rounds to 6e-17:
                    // a row below it would reach above the horizon).
                    0.0
                } else {
                    (PI * i as f64 / rows as f64).cos()
                }
            })
            .collect();
        let dphi = 2.0 * PI / cols as f64;
        let mut row_mass = Vec::with_capacity(rows);
        let mut col_cdf = Vec::with_capacity(rows * (cols + 1));
        for i in 0..rows {
            let row = &f[i * cols..(i + 1) * cols];
            let mut acc = 0.0;
            col_cdf.push(0.0);
            for &v in row {
                acc += v;
                col_cdf.push(acc);
            }
            let last = col_cdf.len() - 1;
            let base = last - cols;
            for (k, c) in col_cdf[base..=last].iter_mut().enumerate() {
                // A dark row is never picked; its CDF stays uniform.
                *c = if acc > 0.0 {
                    *c / acc
                } else {
                    k as f64 / cols as f64
                };
            }
            col_cdf[last] = 1.0;
            row_mass.push(acc * (cos_edge[i] - cos_edge[i + 1]) * dphi);
        }
        let total: f64 = row_mass.iter().sum();
        if total <= 0.0 {
            return Err(TableError::Empty);
        }
        let mut row_cdf = Vec::with_capacity(rows + 1);
        let mut acc = 0.0;
        row_cdf.push(0.0);
        for m in &row_mass {
            acc += m;
            row_cdf.push(acc / total);
        }
        row_cdf[rows] = 1.0;
        Ok(Self {
            rows,
            cols,
            f,
            cos_edge,
            row_cdf,
            col_cdf,
            total,
        })
    }

    /// Rows and columns.
    pub fn size(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }

    /// `F = sum f_ij Omega_ij` (for a luminance map: the integral of the
    /// luminance over the sphere, [cd/m^2 sr]).
    pub fn integral(&self) -> f64 {
        self.total
    }

    /// Value of cell `(i, j)`.
    pub fn value(&self, i: usize, j: usize) -> f64 {
        self.f[i * self.cols + j]
    }

    /// Solid angle \[sr\] of a cell of row `i`.
    pub fn cell_solid_angle(&self, i: usize) -> f64 {
        (self.cos_edge[i] - self.cos_edge[i + 1]) * 2.0 * PI / self.cols as f64
    }

    /// `cos theta` at the upper and lower edges of row `i`.
    pub fn row_edges(&self, i: usize) -> (f64, f64) {
        (self.cos_edge[i], self.cos_edge[i + 1])
    }

    /// Index `k` with `cdf[k] <= u < cdf[k + 1]` skipping empty steps.
    #[inline]
    fn find(cdf: &[f64], u: f64) -> usize {
        // partition_point: first index whose value is > u; the step before it.
        let k = cdf.partition_point(|&c| c <= u);
        k.clamp(1, cdf.len() - 1) - 1
    }

    /// A direction drawn with density [`Self::pdf`] from `u in [0, 1)^2`.
    #[inline]
    pub fn sample(&self, u: [f64; 2]) -> SphereTableSample {
        let i = Self::find(&self.row_cdf, u[0]);
        let (c0, c1) = (self.row_cdf[i], self.row_cdf[i + 1]);
        let v0 = ((u[0] - c0) / (c1 - c0)).clamp(0.0, ONE_MINUS_EPSILON);
        let cdf = &self.col_cdf[i * (self.cols + 1)..(i + 1) * (self.cols + 1)];
        let j = Self::find(cdf, u[1]);
        let (d0, d1) = (cdf[j], cdf[j + 1]);
        let v1 = ((u[1] - d0) / (d1 - d0)).clamp(0.0, ONE_MINUS_EPSILON);
        let (ct0, ct1) = (self.cos_edge[i], self.cos_edge[i + 1]);
        let cos_theta = ct0 + v0 * (ct1 - ct0);
        let phi = 2.0 * PI * (j as f64 + v1) / self.cols as f64;
        SphereTableSample {
            cos_theta,
            phi,
            pdf: self.value(i, j) / self.total,
            cell: (i, j),
        }
    }

    /// The cell holding `(cos theta, phi)`.
    #[inline]
    pub fn cell_of(&self, cos_theta: f64, phi: f64) -> (usize, usize) {
        let theta = cos_theta.clamp(-1.0, 1.0).acos();
        let mut i = ((theta / PI) * self.rows as f64) as usize;
        // The edges are cosines of i pi / rows: settle rounding at an edge.
        i = i.min(self.rows - 1);
        while i > 0 && cos_theta > self.cos_edge[i] {
            i -= 1;
        }
        while i + 1 < self.rows && cos_theta < self.cos_edge[i + 1] {
            i += 1;
        }
        let p = phi.rem_euclid(2.0 * PI) / (2.0 * PI);
        let j = ((p * self.cols as f64) as usize).min(self.cols - 1);
        (i, j)
    }

    /// Density per solid angle [1/sr] at `(cos theta, phi)`.
    #[inline]
    pub fn pdf(&self, cos_theta: f64, phi: f64) -> f64 {
        let (i, j) = self.cell_of(cos_theta, phi);
        self.value(i, j) / self.total
    }

    /// The uniforms that [`Self::sample`] maps to `(cos theta, phi)` (a
    /// direction of non-zero density).
    pub fn invert(&self, cos_theta: f64, phi: f64) -> [f64; 2] {
        let (i, j) = self.cell_of(cos_theta, phi);
        let (ct0, ct1) = (self.cos_edge[i], self.cos_edge[i + 1]);
        let v0 = ((cos_theta - ct0) / (ct1 - ct0)).clamp(0.0, 1.0);
        let (c0, c1) = (self.row_cdf[i], self.row_cdf[i + 1]);
        let cdf = &self.col_cdf[i * (self.cols + 1)..(i + 1) * (self.cols + 1)];
        let (d0, d1) = (cdf[j], cdf[j + 1]);
        let p = phi.rem_euclid(2.0 * PI) / (2.0 * PI) * self.cols as f64 - j as f64;
        [
            (c0 + v0 * (c1 - c0)).clamp(0.0, ONE_MINUS_EPSILON),
            (d0 + p.clamp(0.0, 1.0) * (d1 - d0)).clamp(0.0, ONE_MINUS_EPSILON),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> SphereTable {
        let (rows, cols) = (8, 16);
        let f = (0..rows * cols)
            .map(|k| {
                let (i, j) = (k / cols, k % cols);
                if i == 5 {
                    0.0
                } else {
                    1.0 + ((i * 7 + j * 3) % 5) as f64
                }
            })
            .collect();
        SphereTable::new(f, rows, cols).unwrap()
    }

    #[test]
    fn sample_invert_and_pdf_agree() {
        let t = table();
        for k in 0..2000 {
            let u = [(k as f64 + 0.5) / 2000.0, (k as f64 * 0.618_034).fract()];
            let s = t.sample(u);
            assert!(s.pdf > 0.0, "a zero cell was sampled");
            assert_eq!(t.cell_of(s.cos_theta, s.phi), s.cell);
            assert_eq!(t.pdf(s.cos_theta, s.phi), s.pdf);
            let back = t.invert(s.cos_theta, s.phi);
            assert!(
                (back[0] - u[0]).abs() < 1e-9 && (back[1] - u[1]).abs() < 1e-9,
                "{u:?} -> {back:?}"
            );
        }
    }

    #[test]
    fn density_integrates_to_one_and_bad_tables_are_refused() {
        let t = table();
        let (rows, cols) = t.size();
        let sum: f64 = (0..rows)
            .flat_map(|i| (0..cols).map(move |j| (i, j)))
            .map(|(i, j)| t.value(i, j) / t.integral() * t.cell_solid_angle(i))
            .sum();
        assert!((sum - 1.0).abs() < 1e-13);
        let omega: f64 = (0..rows).map(|i| t.cell_solid_angle(i) * cols as f64).sum();
        assert!((omega - 4.0 * PI).abs() < 1e-13);
        assert!(matches!(
            SphereTable::new(vec![0.0; 4], 2, 2),
            Err(TableError::Empty)
        ));
        assert!(matches!(
            SphereTable::new(vec![1.0, -1.0, 1.0, 1.0], 2, 2),
            Err(TableError::Value { index: 1, .. })
        ));
        assert!(matches!(
            SphereTable::new(vec![1.0; 3], 2, 2),
            Err(TableError::Size { .. })
        ));
        assert!(SphereTable::new(vec![1.0, f64::NAN], 1, 2).is_err());
    }
}
