//! Radius and derivative bounds of an SH surface (the ray march relies on
//! them never to miss the first hit), and the grid that proves `U > 0`.
//!
//! Let `Y_k` be the degree-`k` part of `U` and `S_k = sum_m sqrt(a_km^2 + b_km^2)`
//! (`|a_k0|` for `m = 0`). Since `|P_k^m| <= 1` and
//! `|a cos + b sin| <= sqrt(a^2 + b^2)`, `|Y_k| <= S_k`, so
//! `|U - a_00| <= S = sum_{k>=1} S_k`: the surface lies between the spheres
//! of radii `a_00 - S` and `a_00 + S`. When `a_00 - S <= 0` this bound proves
//! nothing, and a grid over the sphere decides (below); the grid also
//! tightens both radii.
//!
//! Bernstein's inequality for spherical polynomials: the restriction of
//! `Y_k` to any great circle, as a function of the arc angle `psi`, is a
//! trigonometric polynomial of degree `<= k` bounded by `S_k`, so (by the
//! trigonometric Bernstein inequality) `|dY_k/dpsi| <= k S_k` and
//! `|d^2 Y_k/dpsi^2| <= k^2 S_k`. Every tangent direction lies on a great
//! circle, hence
//!
//! ```text
//! |grad_S U| <= G = sum_k k S_k,      |d^2 U/dpsi^2| <= H = sum_k k^2 S_k   (local units).
//! ```
//!
//! Grid check: with nodes `theta_i = i pi / n`, `phi_j = 2 pi j / (2n)`,
//! any direction is joined to a node `q` by a path of length
//! `delta <= (pi/n + pi/n) / 2` (along a meridian, then along a parallel),
//! and so by a great-circle arc no longer than `delta`. Along that arc
//! `|U - U(q)| <= G delta` and `|U - U(q)| <= |grad_S U(q)| delta + H delta^2 / 2`
//! (Taylor with the bound `H` on the second derivative), so
//! `min U >= min_q [U(q) - min(G delta, |grad_S U(q)| delta + H delta^2 / 2)]`
//! and likewise for `max U`. The second form makes the bounds tight to
//! `O(delta^2)` near the extremes (where the gradient vanishes). A node with
//! `U <= 0` proves the expansion is not star-shaped; a positive lower bound
//! proves it is; in between the grid is refined (up to [`MAX_GRID`] polar
//! rows) before giving up with [`ShError::Unverified`]. The same grid gives
//! `r_min`, `r_max` (never looser than `a_00 -/+ S`).

use super::{ShError, ShSurface};
use crate::math::sph_harm::{Recurrence, offset, pair_count};
use std::f64::consts::PI;

/// Most polar rows of the star-shape verification grid (`2 MAX_GRID` azimuths).
pub const MAX_GRID: usize = 2048;

/// Rigorous range of `U` from a grid.
struct GridRange {
    /// Smallest node value and its `(theta, phi)`.
    min: f64,
    min_at: (f64, f64),
    /// Lower and upper bounds of `U` over the whole sphere.
    lower: f64,
    upper: f64,
    n_theta: usize,
    n_phi: usize,
}

impl ShSurface {
    /// Prove `U > 0` (bound, then grids) and tighten `r_min`, `r_max`.
    pub(super) fn verify_star_shaped(&mut self) -> Result<(), ShError> {
        let reference = self.a00.abs().max(self.s_sum).max(f64::MIN_POSITIVE);
        // Rounding of the node values: a few ulps of the largest possible sum.
        let margin = 1e-12 * (self.a00.abs() + self.s_sum);
        // Initial grid: G delta about 5 % of the radius.
        let rec = Recurrence::new(self.degree);
        let mut n = ((PI * self.g_bound / (0.05 * reference)).ceil() as usize).clamp(16, 256);
        loop {
            let g = self.grid_range(&rec, n, margin);
            if g.min <= 0.0 {
                return Err(ShError::NotStarShaped {
                    radius: g.min,
                    theta: g.min_at.0,
                    phi: g.min_at.1,
                });
            }
            if g.lower > 0.0 {
                self.r_min = (self.a00 - self.s_sum).max(g.lower);
                self.r_max = (self.a00 + self.s_sum).min(g.upper);
                return Ok(());
            }
            if n >= MAX_GRID {
                return Err(ShError::Unverified {
                    grid_min: g.min,
                    theta: g.min_at.0,
                    phi: g.min_at.1,
                    lower: g.lower,
                    n_theta: g.n_theta,
                    n_phi: g.n_phi,
                });
            }
            n = (2 * n).min(MAX_GRID);
        }
    }

    /// `U` and `|grad_S U|` on the grid `theta_i = i pi / n` (`i = 0..=n`),
    /// `phi_j = pi j / n` (`j < 2n`): the smallest node value and rigorous
    /// bounds over the sphere. Every direction lies within the path length
    /// `delta = (pi/n + pi/n) / 2` of a node, so near node `q`
    /// `|U - U(q)| <= min(G delta, |grad_S U(q)| delta + H delta^2 / 2)`
    /// (first- and second-order Bernstein bounds along the great circle
    /// from `q`); `margin` covers rounding.
    fn grid_range(&self, rec: &Recurrence, n_theta: usize, margin: f64) -> GridRange {
        let l = self.degree;
        let n_phi = 2 * n_theta;
        let delta = 0.5 * (PI / n_theta as f64 + 2.0 * PI / n_phi as f64);
        let slack1 = self.g_bound * delta;
        let half_h = 0.5 * self.h_bound * delta * delta;
        let mut cos_tab = vec![0.0; n_phi * (l + 1)];
        let mut sin_tab = vec![0.0; n_phi * (l + 1)];
        for j in 0..n_phi {
            let phi = 2.0 * PI * j as f64 / n_phi as f64;
            for m in 0..=l {
                let (s, c) = (m as f64 * phi).sin_cos();
                cos_tab[j * (l + 1) + m] = c;
                sin_tab[j * (l + 1) + m] = s;
            }
        }
        let mut t = vec![0.0; pair_count(l)];
        let mut dt = vec![0.0; pair_count(l)];
        // Per order m: coefficients of cos(m phi) and sin(m phi) in U,
        // U_theta and (1/sin theta) U_phi along the current row.
        let mut cu = vec![[0.0; 6]; l + 1];
        let mut out = GridRange {
            min: f64::INFINITY,
            min_at: (0.0, 0.0),
            lower: f64::INFINITY,
            upper: f64::NEG_INFINITY,
            n_theta,
            n_phi,
        };
        for i in 0..=n_theta {
            let theta = PI * i as f64 / n_theta as f64;
            let (s, z) = if i == 0 {
                (0.0, 1.0)
            } else if i == n_theta {
                (0.0, -1.0)
            } else {
                theta.sin_cos()
            };
            rec.table_with_derivative(z, &mut t, &mut dt);
            let (mut spow, mut spow1) = (1.0, 0.0);
            for (m, cm) in cu.iter_mut().enumerate() {
                let off = offset(l, m);
                let (mut sa, mut sb, mut da, mut db) = (0.0, 0.0, 0.0, 0.0);
                for i in off..=off + l - m {
                    let e = &self.terms[i];
                    sa += e.a * t[i];
                    sb += e.b * t[i];
                    da += e.a * dt[i];
                    db += e.b * dt[i];
                }
                let mf = m as f64;
                *cm = if m == 0 {
                    [sa, sb, -s * da, -s * db, 0.0, 0.0]
                } else {
                    [
                        spow * sa,
                        spow * sb,
                        spow1 * (mf * z * sa - s * s * da),
                        spow1 * (mf * z * sb - s * s * db),
                        mf * spow1 * sb,
                        -mf * spow1 * sa,
                    ]
                };
                spow1 = spow;
                spow *= s;
            }
            // At the poles every azimuth gives the same value and gradient.
            let j_end = if s == 0.0 { 1 } else { n_phi };
            for j in 0..j_end {
                let row = j * (l + 1);
                let (mut u, mut ut, mut up) = (0.0, 0.0, 0.0);
                for (m, cm) in cu.iter().enumerate() {
                    let (c, sn) = (cos_tab[row + m], sin_tab[row + m]);
                    u += cm[0] * c + cm[1] * sn;
                    ut += cm[2] * c + cm[3] * sn;
                    up += cm[4] * c + cm[5] * sn;
                }
                if u < out.min {
                    out.min = u;
                    out.min_at = (theta, 2.0 * PI * j as f64 / n_phi as f64);
                }
                let slack = slack1.min((ut * ut + up * up).sqrt() * delta + half_h) + margin;
                out.lower = out.lower.min(u - slack);
                out.upper = out.upper.max(u + slack);
            }
        }
        out
    }
}
