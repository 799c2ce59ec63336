//! The SH surface: construction, evaluation of `U` and its surface
//! gradient, the level function and the normal.
//!
//! With `P_k^m = s^m T_k^m` (see [`crate::math::sph_harm`]),
//! `dP_k^m/dtheta = s^(m-1) (m x T - s^2 T')` (for `m = 0`: `-s T'`) and
//! `(1/s) dP_k^m cos(m phi)/dphi = -m s^(m-1) T sin(m phi)`: the surface
//! gradient `grad_S U = U_theta theta_hat + (1/s) U_phi phi_hat` is
//! evaluated without dividing by `sin theta`, so it is exact at the poles
//! (there only `m = 1` contributes and the result does not depend on the
//! arbitrary `phi` chosen there). For `F(x) = rho - U(x/rho)`,
//! `grad F = r_hat - grad_S U / rho`, which gives the outward normal.

use super::{MAX_DEGREE, ShCoeff, ShError};
use crate::math::sph_harm::{Recurrence, offset, pair_count};
use glam::{DMat3, DVec3};

/// Tolerance of `R^T R = I` (largest entry of the difference).
const ROTATION_TOL: f64 = 1e-9;

/// A star-shaped surface `r = U(theta, phi)` given by an SH expansion,
/// placed in the world by a centre, a rotation and a scale.
#[derive(Clone, Debug)]
pub struct ShSurface {
    /// Degree `L` (highest degree with a non-zero coefficient).
    pub(super) degree: usize,
    /// Coefficients and recurrence constants of every `(k, m)`, m-major packed.
    pub(super) terms: Vec<Term>,
    /// `T_m^m`, the start of each order's recurrence.
    pub(super) diag: Vec<f64>,
    /// Centre \[m\].
    pub(super) center: DVec3,
    /// Local-to-world rotation `R`.
    pub(super) rot: DMat3,
    /// `R^T`.
    pub(super) rot_t: DMat3,
    /// World length per local length \[m\].
    pub(super) scale: f64,
    /// `a_00` \[local\].
    pub(super) a00: f64,
    /// `S = sum_{k>=1} S_k` \[local\].
    pub(super) s_sum: f64,
    /// `G = sum_k k S_k`, bound of `|grad_S U|` \[local\].
    pub(super) g_bound: f64,
    /// `H = sum_k k^2 S_k`, bound of the second arc derivative \[local\].
    pub(super) h_bound: f64,
    /// Lower bound of `U` \[local\], `> 0`.
    pub(super) r_min: f64,
    /// Upper bound of `U` \[local\].
    pub(super) r_max: f64,
}

/// One `(k, m)` entry of the evaluation table.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Term {
    /// `a_km` [local length].
    pub(super) a: f64,
    /// `b_km` [local length].
    pub(super) b: f64,
    /// Recurrence `alpha` at `(k, m)` (0 at `k = m`).
    pub(super) alpha: f64,
    /// Recurrence `beta` at `(k, m)` (0 at `k = m`).
    pub(super) beta: f64,
}

/// Sums over the degrees of one order `m`: `sum_k a_km T_k^m`,
/// `sum_k b_km T_k^m` and the same with `dT_k^m / dz`.
#[derive(Clone, Copy, Debug, Default)]
struct OrderSums {
    sa: f64,
    sb: f64,
    da: f64,
    db: f64,
}

/// Recurrence state of one order: `T_{k-1}, T_{k-2}` and their derivatives.
#[derive(Clone, Copy, Debug)]
struct Chain {
    t1: f64,
    t2: f64,
    d1: f64,
    d2: f64,
    sums: OrderSums,
}

impl Chain {
    /// Start at `T_m^m = diag` with the `(m, m)` term.
    #[inline(always)]
    fn new(diag: f64, first: &Term) -> Self {
        Self {
            t1: diag,
            t2: 0.0,
            d1: 0.0,
            d2: 0.0,
            sums: OrderSums {
                sa: first.a * diag,
                sb: first.b * diag,
                da: 0.0,
                db: 0.0,
            },
        }
    }

    /// Advance one degree.
    #[inline(always)]
    fn step(&mut self, z: f64, e: &Term) {
        // Grouped so that each new value is one multiply and one add away
        // from the previous one (the chains are latency-bound).
        let az = e.alpha * z;
        let t0 = az * self.t1 - e.beta * self.t2;
        let d0 = (e.alpha * self.t1 - e.beta * self.d2) + az * self.d1;
        self.sums.sa += e.a * t0;
        self.sums.sb += e.b * t0;
        self.sums.da += e.a * d0;
        self.sums.db += e.b * d0;
        self.t2 = self.t1;
        self.d2 = self.d1;
        self.t1 = t0;
        self.d1 = d0;
    }
}

impl ShSurface {
    /// Build and validate a surface.
    ///
    /// `coeffs` in local units (missing pairs are zero); `center` \[m\];
    /// `rotation` a proper rotation (local to world); `scale` > 0 world
    /// metres per local unit. Rejects: an empty list, `m > k`,
    /// `k > MAX_DEGREE`, non-finite values, `b != 0` at `m = 0`, repeated
    /// `(k, m)`, a non-finite centre, a bad scale or rotation, and
    /// expansions with `U <= 0` somewhere ([`ShError::NotStarShaped`]) or
    /// where `U > 0` cannot be proved ([`ShError::Unverified`]); see the
    /// module docs for the bound-then-grid check. Trailing degrees whose
    /// coefficients are all zero are dropped.
    pub fn new(
        coeffs: &[ShCoeff],
        center: DVec3,
        rotation: DMat3,
        scale: f64,
    ) -> Result<Self, ShError> {
        if coeffs.is_empty() {
            return Err(ShError::Empty);
        }
        for (index, c) in coeffs.iter().enumerate() {
            if c.k > MAX_DEGREE {
                return Err(ShError::DegreeTooHigh {
                    index,
                    k: c.k,
                    max: MAX_DEGREE,
                });
            }
            if c.m > c.k {
                return Err(ShError::OrderAboveDegree {
                    index,
                    k: c.k,
                    m: c.m,
                });
            }
            for (which, value) in [("a", c.a), ("b", c.b)] {
                if !value.is_finite() {
                    return Err(ShError::NotFinite {
                        index,
                        k: c.k,
                        m: c.m,
                        which,
                        value,
                    });
                }
            }
            if c.m == 0 && c.b != 0.0 {
                return Err(ShError::SineAtZeroOrder {
                    index,
                    k: c.k,
                    b: c.b,
                });
            }
        }
        let k_max = coeffs.iter().map(|c| c.k).max().unwrap_or(0);
        let mut seen: Vec<Option<usize>> = vec![None; pair_count(k_max)];
        for (index, c) in coeffs.iter().enumerate() {
            let slot = &mut seen[c.k * (c.k + 1) / 2 + c.m];
            if let Some(first) = *slot {
                return Err(ShError::Duplicate {
                    index,
                    first,
                    k: c.k,
                    m: c.m,
                });
            }
            *slot = Some(index);
        }
        if !center.is_finite() {
            return Err(ShError::Center { center });
        }
        if !(scale.is_finite() && scale > 0.0) {
            return Err(ShError::Scale { scale });
        }
        check_rotation(rotation)?;

        let degree = coeffs
            .iter()
            .filter(|c| c.a != 0.0 || c.b != 0.0)
            .map(|c| c.k)
            .max()
            .unwrap_or(0);
        let rec = Recurrence::new(degree);
        let mut terms: Vec<Term> = rec
            .alpha
            .iter()
            .zip(&rec.beta)
            .map(|(&alpha, &beta)| Term {
                alpha,
                beta,
                ..Term::default()
            })
            .collect();
        for c in coeffs.iter().filter(|c| c.k <= degree) {
            let e = &mut terms[offset(degree, c.m) + c.k - c.m];
            e.a = c.a;
            e.b = c.b;
        }
        let mut s_k = vec![0.0; degree + 1];
        for m in 0..=degree {
            let off = offset(degree, m);
            for k in m..=degree {
                s_k[k] += terms[off + k - m].a.hypot(terms[off + k - m].b);
            }
        }
        let a00 = terms[0].a;
        let s_sum: f64 = s_k[1..].iter().sum();
        let g_bound: f64 = s_k.iter().enumerate().map(|(k, s)| k as f64 * s).sum();
        let h_bound: f64 = s_k
            .iter()
            .enumerate()
            .map(|(k, s)| (k * k) as f64 * s)
            .sum();
        let mut surf = Self {
            degree,
            terms,
            diag: rec.diag,
            center,
            rot: rotation,
            rot_t: rotation.transpose(),
            scale,
            a00,
            s_sum,
            g_bound,
            h_bound,
            r_min: a00 - s_sum,
            r_max: a00 + s_sum,
        };
        surf.verify_star_shaped()?;
        Ok(surf)
    }

    /// Degree `L`: the highest degree with a non-zero coefficient.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Centre \[m\].
    pub fn center(&self) -> DVec3 {
        self.center
    }

    /// Local-to-world rotation `R`.
    pub fn rotation(&self) -> DMat3 {
        self.rot
    }

    /// World metres per local unit.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// World radius bounds \[m\]: the surface lies between the spheres of
    /// these radii around the centre (`a_00 -/+ S`, tightened by the
    /// verification grid; see the module docs). Both are `> 0`.
    pub fn bounds(&self) -> (f64, f64) {
        (self.scale * self.r_min, self.scale * self.r_max)
    }

    /// Bounds `(G, H)` of the first and second arc derivatives of `U` on the
    /// unit sphere (Bernstein; local units): `|grad_S U| <= G = sum_k k S_k`,
    /// `|d^2 U / dpsi^2| <= H = sum_k k^2 S_k` along any great circle.
    pub fn derivative_bounds(&self) -> (f64, f64) {
        (self.g_bound, self.h_bound)
    }

    /// The coefficients of all pairs `0 <= m <= k <= degree()` (zeros
    /// included), in k-major order.
    pub fn coefficients(&self) -> Vec<ShCoeff> {
        let l = self.degree;
        let mut out = Vec::with_capacity(pair_count(l));
        for k in 0..=l {
            for m in 0..=k {
                let i = offset(l, m) + k - m;
                out.push(ShCoeff {
                    k,
                    m,
                    a: self.terms[i].a,
                    b: self.terms[i].b,
                });
            }
        }
        out
    }

    /// Sums of the `N` orders `m .. m + N` (`m + N <= L + 1`), their
    /// independent recurrences interleaved so the CPU can overlap them
    /// (each is a serial dependency chain).
    #[inline(always)]
    fn order_block<const N: usize>(&self, m: usize, z: f64) -> [OrderSums; N] {
        let l = self.degree;
        let rows: [&[Term]; N] =
            std::array::from_fn(|j| &self.terms[offset(l, m + j)..offset(l, m + j + 1)]);
        let mut ch: [Chain; N] = std::array::from_fn(|j| Chain::new(self.diag[m + j], &rows[j][0]));
        // Order m + j has L - m - j + 1 degrees: the last order sets the
        // common length, the others then finish N - 1 - j more steps.
        let common = rows[N - 1].len();
        for i in 1..common {
            for (c, row) in ch.iter_mut().zip(&rows) {
                c.step(z, &row[i]);
            }
        }
        for (c, row) in ch.iter_mut().zip(&rows) {
            for e in &row[common..] {
                c.step(z, e);
            }
        }
        ch.map(|c| c.sums)
    }

    /// `U` and the surface gradient `grad_S U` (a local vector tangent to
    /// the unit sphere) at the local direction `y` (any non-zero length;
    /// normalised here), and the unit direction used.
    #[inline]
    pub(super) fn eval(&self, y: DVec3) -> (f64, DVec3, DVec3) {
        let y = y / y.length();
        let z = y.z;
        let s = (y.x * y.x + y.y * y.y).sqrt();
        let (c1, s1) = if s > 0.0 {
            (y.x / s, y.y / s)
        } else {
            (1.0, 0.0)
        };
        let l = self.degree;
        let mut acc = [0.0; 3]; // U, U_theta, U_phi / sin theta
        // cos(m phi), sin(m phi), s^m, s^(m-1)
        let mut rot = (1.0, 0.0);
        let mut pow = (1.0, 0.0);
        let mut add = |m: usize, o: OrderSums| {
            let (cm, sm) = rot;
            let (spow, spow1) = pow;
            let c = o.sa * cm + o.sb * sm;
            let d = o.da * cm + o.db * sm;
            acc[0] += spow * c;
            if m == 0 {
                acc[1] -= s * d;
            } else {
                let mf = m as f64;
                acc[1] += spow1 * (mf * z * c - s * s * d);
                acc[2] += mf * spow1 * (o.sb * cm - o.sa * sm);
            }
            pow = (spow * s, spow);
            rot = (cm * c1 - sm * s1, sm * c1 + cm * s1);
        };
        let mut m = 0;
        while m + 2 <= l + 1 {
            for (j, o) in self.order_block::<2>(m, z).into_iter().enumerate() {
                add(m + j, o);
            }
            m += 2;
        }
        if m == l {
            add(m, self.order_block::<1>(m, z)[0]);
        }
        let theta_hat = DVec3::new(z * c1, z * s1, -s);
        let phi_hat = DVec3::new(-s1, c1, 0.0);
        (acc[0], acc[1] * theta_hat + acc[2] * phi_hat, y)
    }

    /// Radius `U` [local units] in the local direction `dir_local` (any
    /// non-zero length; normalised here).
    pub fn radius(&self, dir_local: DVec3) -> f64 {
        self.eval(dir_local).0
    }

    /// Radius `U` [local units] and its surface gradient `grad_S U`
    /// [local units per radian], a local vector tangent to the unit sphere at
    /// `dir_local` (normalised here). Exact at the poles.
    pub fn radius_and_gradient(&self, dir_local: DVec3) -> (f64, DVec3) {
        let (u, g, _) = self.eval(dir_local);
        (u, g)
    }

    /// "Level" `f(x) = |x - c| - scale U(dir)` \[m\]: `< 0` inside, `> 0`
    /// outside (at the centre, `-scale U(+z)`).
    pub fn level(&self, x: DVec3) -> f64 {
        self.probe(x - self.center, DVec3::Z).f
    }

    /// Outward unit normal at a surface point `x` (world), from the analytic
    /// gradient of the level (exact at the poles). Off the surface, the
    /// normalised gradient of the level; `+z` of the local frame at the centre.
    pub fn normal(&self, x: DVec3) -> DVec3 {
        let p = self.probe(x - self.center, DVec3::Z);
        if p.rho > 0.0 {
            p.grad.normalize()
        } else {
            self.rot * DVec3::Z
        }
    }

    /// Number of real coefficients defining the shape: `(L + 1)^2` (`a_km`
    /// for `0 <= m <= k <= L`, `b_km` for `m >= 1`); `8` bytes each in the
    /// most compact storage.
    pub fn coefficient_count(&self) -> usize {
        (self.degree + 1) * (self.degree + 1)
    }

    /// Bytes this surface occupies in memory: the struct plus its arrays
    /// (per `(k, m)`: `a`, `b` and two recurrence constants; per order: `T_m^m`).
    pub fn storage_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.terms.capacity() * std::mem::size_of::<Term>()
            + self.diag.capacity() * std::mem::size_of::<f64>()
    }
}

/// Check that `r` is a proper rotation (orthonormal within `ROTATION_TOL`, determinant +1).
fn check_rotation(r: DMat3) -> Result<(), ShError> {
    if !r.is_finite() {
        return Err(ShError::Rotation {
            reason: "entries are not finite".into(),
        });
    }
    let e = (r.transpose() * r - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |acc, x| acc.max(x.abs()));
    if e.is_nan() || e > ROTATION_TOL {
        return Err(ShError::Rotation {
            reason: format!(
                "R^T R differs from the identity by {e:e} (tolerance {ROTATION_TOL:e})"
            ),
        });
    }
    let det = r.determinant();
    if det < 0.0 {
        return Err(ShError::Rotation {
            reason: format!("determinant {det} < 0 (a reflection)"),
        });
    }
    Ok(())
}
