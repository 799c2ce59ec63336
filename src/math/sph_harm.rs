//! Real spherical harmonics: Schmidt semi-normalised associated Legendre
//! functions and the coefficients of a real expansion.
//!
//! `P_k^m` are the Schmidt semi-normalised associated Legendre functions
//! without the Condon-Shortley phase:
//! `P_k^m = sqrt((2 - delta_m0) (k - m)! / (k + m)!) (1 - x^2)^(m/2) d^m P_k / dx^m`,
//! so `P_k^0 = P_k`, `sum_m P_k^m(x)^2 = 1` and `|P_k^m| <= 1`. A real
//! expansion of degree `L` is
//!
//! ```text
//! U(theta, phi) = sum_{k=0..L} sum_{m=0..k} P_k^m(cos theta) (a_km cos m phi + b_km sin m phi).
//! ```
//!
//! ## Evaluation
//!
//! Write `P_k^m(x) = s^m T_k^m(x)` with `s = sin theta` and `T_k^m` a
//! polynomial of degree `k - m` in `x = cos theta`:
//!
//! ```text
//! T_0^0 = T_1^1 = 1,  T_m^m = sqrt((2m - 1) / (2m)) T_{m-1}^{m-1}          (m >= 2)
//! T_k^m = [(2k - 1) x T_{k-1}^m - sqrt((k-1)^2 - m^2) T_{k-2}^m] / sqrt(k^2 - m^2)   (k > m)
//! ```
//!
//! and `T'` by differentiating the same recurrence. Keeping the factor `s^m`
//! apart makes every value finite and exact at the poles, where derivatives
//! in `theta` need `s^(m-1)` (see [`crate::geometry::sh`]).

/// One real SH coefficient pair of degree `k` and order `m` (local units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShCoeff {
    /// Degree `k >= 0`.
    pub k: usize,
    /// Order `0 <= m <= k`.
    pub m: usize,
    /// Cosine coefficient `a_km` [local length].
    pub a: f64,
    /// Sine coefficient `b_km` [local length]; must be 0 for `m = 0`.
    pub b: f64,
}

/// Start of order `m` in the m-major packed layout of degree `l`
/// (entries `(k, m)`, `k = m..=l`, at `offset + k - m`).
#[inline]
pub(crate) fn offset(l: usize, m: usize) -> usize {
    m * (l + 1) - m * m.saturating_sub(1) / 2
}

/// Number of `(k, m)` pairs with `0 <= m <= k <= l`.
#[inline]
pub(crate) fn pair_count(l: usize) -> usize {
    (l + 1) * (l + 2) / 2
}

/// Recurrence constants for `T_k^m` (m-major packed).
#[derive(Clone, Debug)]
pub(crate) struct Recurrence {
    /// Degree `L`.
    pub(crate) l: usize,
    /// `(2k - 1) / sqrt(k^2 - m^2)` at `(k, m)`, `k > m`.
    pub(crate) alpha: Vec<f64>,
    /// `sqrt((k - 1)^2 - m^2) / sqrt(k^2 - m^2)` at `(k, m)`, `k > m`.
    pub(crate) beta: Vec<f64>,
    /// `T_m^m`.
    pub(crate) diag: Vec<f64>,
}

impl Recurrence {
    /// Constants up to degree `l`.
    pub(crate) fn new(l: usize) -> Self {
        let n = pair_count(l);
        let mut alpha = vec![0.0; n];
        let mut beta = vec![0.0; n];
        let mut diag = vec![1.0; l + 1];
        for m in 2..=l {
            diag[m] = diag[m - 1] * ((2 * m - 1) as f64 / (2 * m) as f64).sqrt();
        }
        for m in 0..=l {
            let off = offset(l, m);
            for k in m + 1..=l {
                let den = ((k * k - m * m) as f64).sqrt();
                alpha[off + k - m] = (2 * k - 1) as f64 / den;
                beta[off + k - m] = (((k - 1) * (k - 1) - m * m) as f64).sqrt() / den;
            }
        }
        Self {
            l,
            alpha,
            beta,
            diag,
        }
    }

    /// `T_k^m(z)` for all pairs (m-major packed) into `t`.
    pub(crate) fn table(&self, z: f64, t: &mut [f64]) {
        for m in 0..=self.l {
            let (off, end) = (offset(self.l, m), offset(self.l, m + 1));
            let (mut p2, mut p1) = (0.0, self.diag[m]);
            t[off] = p1;
            let consts = self.alpha[off + 1..end]
                .iter()
                .zip(&self.beta[off + 1..end]);
            for (ti, (&al, &be)) in t[off + 1..end].iter_mut().zip(consts) {
                let p = al * z * p1 - be * p2;
                *ti = p;
                p2 = p1;
                p1 = p;
            }
        }
    }

    /// `T_k^m(z)` into `t` and `dT_k^m/dz` into `dt`.
    pub(crate) fn table_with_derivative(&self, z: f64, t: &mut [f64], dt: &mut [f64]) {
        for m in 0..=self.l {
            let (off, end) = (offset(self.l, m), offset(self.l, m + 1));
            let (mut p2, mut p1) = (0.0, self.diag[m]);
            let (mut d2, mut d1) = (0.0, 0.0);
            t[off] = p1;
            dt[off] = 0.0;
            let consts = self.alpha[off + 1..end]
                .iter()
                .zip(&self.beta[off + 1..end]);
            let outs = t[off + 1..end].iter_mut().zip(&mut dt[off + 1..end]);
            for ((ti, di), (&al, &be)) in outs.zip(consts) {
                let p = al * z * p1 - be * p2;
                let d = al * (p1 + z * d1) - be * d2;
                *ti = p;
                *di = d;
                p2 = p1;
                p1 = p;
                d2 = d1;
                d1 = d;
            }
        }
    }
}

/// Schmidt semi-normalised associated Legendre functions `P_k^m(cos theta)`
/// (no Condon-Shortley phase) for all `0 <= m <= k <= l`, at index
/// `k (k + 1) / 2 + m`.
///
/// Pass `cos theta` and `sin theta >= 0` separately (computing one from the
/// other loses accuracy near the poles or the equator).
pub fn schmidt_legendre(l: usize, cos_theta: f64, sin_theta: f64) -> Vec<f64> {
    let rec = Recurrence::new(l);
    let mut t = vec![0.0; pair_count(l)];
    rec.table(cos_theta, &mut t);
    let mut out = vec![0.0; pair_count(l)];
    let mut sm = 1.0;
    for m in 0..=l {
        let off = offset(l, m);
        for k in m..=l {
            out[k * (k + 1) / 2 + m] = sm * t[off + k - m];
        }
        sm *= sin_theta;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binom(n: usize, k: usize) -> f64 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
    }

    /// Schmidt `P_k^m` from the explicit sum for `P_k` and exact polynomial
    /// differentiation (independent of the recurrences).
    fn schmidt_explicit(k: usize, m: usize, x: f64) -> f64 {
        let mut dm = 0.0;
        for j in 0..=k / 2 {
            let n = k - 2 * j;
            if n < m {
                continue;
            }
            let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
            let coef = sign * binom(k, j) * binom(2 * k - 2 * j, k) / 2f64.powi(k as i32);
            let fall: f64 = (0..m).map(|i| (n - i) as f64).product();
            dm += coef * fall * x.powi((n - m) as i32);
        }
        let fact = |n: usize| (1..=n).fold(1.0, |a, i| a * i as f64);
        let norm = if m == 0 {
            1.0
        } else {
            (2.0 * fact(k - m) / fact(k + m)).sqrt()
        };
        let s = ((1.0 - x) * (1.0 + x)).sqrt();
        norm * s.powi(m as i32) * dm
    }

    fn xs() -> Vec<f64> {
        let mut v: Vec<f64> = (0..=40).map(|i| -1.0 + i as f64 / 20.0).collect();
        v.extend([0.123_456_789, -0.987_654_321, 1.0 - 1e-9, -1.0 + 1e-12]);
        v
    }

    #[test]
    fn legendre_matches_closed_forms() {
        let r3 = 3f64.sqrt();
        for x in xs() {
            let s = ((1.0 - x) * (1.0 + x)).sqrt();
            let p = schmidt_legendre(12, x, s);
            let at = |k: usize, m: usize| p[k * (k + 1) / 2 + m];
            let closed = [
                (0, 0, 1.0),
                (1, 0, x),
                (1, 1, s),
                (2, 0, 0.5 * (3.0 * x * x - 1.0)),
                (2, 1, r3 * x * s),
                (2, 2, 0.5 * r3 * s * s),
                (3, 0, 0.5 * (5.0 * x * x * x - 3.0 * x)),
                (3, 1, (3.0f64 / 8.0).sqrt() * s * (5.0 * x * x - 1.0)),
                (3, 2, 0.5 * 15f64.sqrt() * x * s * s),
                (3, 3, (5.0f64 / 8.0).sqrt() * s * s * s),
                (4, 4, (35.0f64 / 64.0).sqrt() * s.powi(4)),
            ];
            for (k, m, want) in closed {
                let got = at(k, m);
                assert!(
                    (got - want).abs() <= 2e-15,
                    "P_{k}^{m}({x}) = {got}, closed form {want}"
                );
            }
            for k in 0..=12 {
                for m in 0..=k {
                    let want = schmidt_explicit(k, m, x);
                    let got = at(k, m);
                    assert!(
                        (got - want).abs() <= 1e-12,
                        "P_{k}^{m}({x}) = {got}, explicit {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn schmidt_addition_theorem() {
        let l = 60;
        for x in xs() {
            let s = ((1.0 - x) * (1.0 + x)).sqrt();
            let p = schmidt_legendre(l, x, s);
            for k in 0..=l {
                let row = &p[k * (k + 1) / 2..=k * (k + 1) / 2 + k];
                let sum: f64 = row.iter().map(|v| v * v).sum();
                assert!((sum - 1.0).abs() <= 1e-13, "k = {k}, x = {x}: sum {sum}");
                assert!(row.iter().all(|v| v.abs() <= 1.0 + 1e-15));
            }
        }
    }
}
