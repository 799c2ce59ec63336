//! The Sobolev problem: two infinite parallel Lambertian planes and an
//! isotropic point source between them, solved exactly by Hankel transform.
//!
//! ## Derivation
//!
//! Source of intensity `I` [cd]; plane `i` (1 or 2) at distance `h_i` [m] from
//! it, reflectance `rho_i`; `j` is the other plane, `H = h1 + h2`, `r` the
//! horizontal distance from the foot of the source.
//!
//! - Direct illuminance: `E0_i(r) = I h_i / (r^2 + h_i^2)^(3/2)`.
//! - A Lambertian plane of exitance `M` gives the other plane the illuminance
//!   `K * M`, with the kernel `K(s) = H^2 / (pi (s^2 + H^2)^2)` (unit integral).
//! - So `E_i = E0_i + rho_j K * E_j`. Under the 2-D Fourier (Hankel) transform
//!   `f^(k) = 2 pi int f(r) J0(k r) r dr`: `E0_i^ = 2 pi I e^(-k h_i)` and
//!   `K^ = kappa(k) = H k K1(H k)` (`kappa(0) = 1`, decreasing), hence
//!
//!   `E_i(r) = I int_0^inf [e^(-k h_i) + rho_j kappa e^(-k h_j)] / (1 - rho1 rho2 kappa^2) J0(k r) k dk`.
//!
//! - The direct term is subtracted analytically; the reflected part is
//!   `I int G_i(k) J0(k r) k dk` with
//!   `G_i = [rho1 rho2 kappa^2 e^(-k h_i) + rho_j kappa e^(-k h_j)] / (1 - rho1 rho2 kappa^2)`.
//! - Reflection order `n` (Neumann series) has the transform
//!   `rho_j^((n+1)/2) rho_i^((n-1)/2) kappa^n e^(-k h_j)` for odd `n` and
//!   `(rho_i rho_j)^(n/2) kappa^n e^(-k h_i)` for even `n`; they sum to `G_i`.
//! - Checks of the derivation (tests): flux on plane `i`,
//!   `int E_i dA = 2 pi I (1 + rho_j) / (1 - rho1 rho2)`, so absorbed flux is `4 pi I`;
//!   far field `r^3 E_i -> I (h_i + rho_j h_j) / (1 - rho1 rho2)`.
//!
//! ## Numerics
//!
//! Near `k = 0`, `G_i = g0 - g1 k + O(k^2 ln k)` with
//! `g0 = (rho1 rho2 + rho_j)/(1 - rho1 rho2)` and
//! `g1 = (rho1 rho2 h_i + rho_j h_j)/(1 - rho1 rho2)`. The linear term is what
//! makes `E ~ 1/r^3` at large `r`, and integrating it numerically against
//! `J0(k r)` would cancel most digits. So `S(k) = (g0 + (H g0 - g1) k) e^(-H k)`,
//! which matches `G_i` to first order and has the closed-form transform
//! `g0 H / (r^2+H^2)^(3/2) + (H g0 - g1) (2 H^2 - r^2) / (r^2+H^2)^(5/2)`, is
//! subtracted, and only `G_i - S` (of order `k^2 ln k` at 0) is integrated, by
//! [`super::quadrature::hankel0`]. The tail is cut where the bound
//! `|G_i| <= g0 kappa`, `int_K^inf kappa k dk = (H K)^2 K2(H K) / H^2`, falls
//! below `1e-16` of the answer's scale. Bessel functions: `pxfm` (correctly
//! rounded J0, K0, K1).
//!
//! Accuracy (tests): against independent 30-digit values (h = 0.5, rho = 0.5)
//! the relative error is below 1e-15 for r <= 3 and 3e-12 at r = 100; halving
//! the panels changes E by less than 1e-10 for r <= 100, rho1 rho2 <= 0.99 and
//! h_i >= 0.01. Beyond r ~ 300 the rounding of the Bessel argument `k r`
//! limits the result (about 1e-7 relative at r = 1000). Cost: about 1 ms per
//! value for r <= 3 and H = 1, 25 ms at r = 100, 15 ms for H = 0.02.

use super::quadrature::hankel0;

/// Error for invalid Sobolev parameters.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SobolevError {
    #[error("{0}")]
    Invalid(String),
}

/// The Sobolev configuration. Plane 1 lies at distance `h1` [m] from the
/// source, plane 2 at `h2` [m] on the other side; reflectances `rho1`, `rho2`;
/// source intensity `intensity` [cd].
#[derive(Clone, Debug)]
pub struct Sobolev {
    pub h1: f64,
    pub h2: f64,
    pub rho1: f64,
    pub rho2: f64,
    pub intensity: f64,
    /// Panel refinement of the quadrature (1; larger only for convergence studies).
    refine: u32,
}

/// Illuminance at a point of one plane [lx].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SobolevValue {
    /// Total illuminance [lx].
    pub e: f64,
    /// Direct illuminance from the source [lx].
    pub e_direct: f64,
    /// Illuminance by reflected light, all orders [lx].
    pub e_reflected: f64,
}

/// `kappa(k) = H k K1(H k)`, the Hankel transform of the plane-to-plane kernel.
#[inline]
fn kappa(x: f64) -> f64 {
    if x < 1e-300 { 1.0 } else { x * pxfm::f_k1(x) }
}

/// `int_X^inf x^2 K1(x) dx = X^2 K2(X)`, with `K2(x) = K0(x) + 2 K1(x) / x`.
fn kappa_tail(x: f64) -> f64 {
    if x < 1e-300 {
        2.0
    } else {
        x * x * pxfm::f_k0(x) + 2.0 * x * pxfm::f_k1(x)
    }
}

impl Sobolev {
    /// Validate the parameters: `h1, h2 > 0` finite [m], reflectances in
    /// [0, 1] with `rho1 rho2 < 1`, intensity finite and `>= 0` [cd].
    pub fn new(
        h1: f64,
        h2: f64,
        rho1: f64,
        rho2: f64,
        intensity: f64,
    ) -> Result<Self, SobolevError> {
        let bad = |m: String| Err(SobolevError::Invalid(m));
        for (name, h) in [("h1", h1), ("h2", h2)] {
            if !(h.is_finite() && h > 0.0) {
                return bad(format!("{name} must be a positive distance [m], got {h}"));
            }
        }
        for (name, r) in [("rho1", rho1), ("rho2", rho2)] {
            if !(r.is_finite() && (0.0..=1.0).contains(&r)) {
                return bad(format!("{name} must lie in [0, 1], got {r}"));
            }
        }
        if rho1 * rho2 >= 1.0 {
            return bad("rho1 * rho2 must be below 1 (otherwise no finite solution exists)".into());
        }
        if !(intensity.is_finite() && intensity >= 0.0) {
            return bad(format!(
                "intensity must be finite and >= 0 [cd], got {intensity}"
            ));
        }
        Ok(Self {
            h1,
            h2,
            rho1,
            rho2,
            intensity,
            refine: 1,
        })
    }

    /// The same problem with quadrature panels `refine` times narrower (for
    /// convergence studies; the answer must not change).
    pub fn refined(&self, refine: u32) -> Self {
        Self {
            refine: refine.max(1),
            ..self.clone()
        }
    }

    /// `(h_i, h_j, rho_i, rho_j)` for plane `i`.
    fn sides(&self, plane: u8) -> (f64, f64, f64, f64) {
        match plane {
            1 => (self.h1, self.h2, self.rho1, self.rho2),
            2 => (self.h2, self.h1, self.rho2, self.rho1),
            _ => panic!("plane must be 1 or 2, got {plane}"),
        }
    }

    /// `I int f(k) J0(k r) k dk` for a transform `f` with `f = g0 - g1 k + O(k^2 ln k)`
    /// at 0 and `|f| <= g0 kappa` (see the module docs).
    fn transform<F: Fn(f64) -> f64>(&self, f: F, g0: f64, g1: f64, r: f64) -> f64 {
        assert!(
            r.is_finite() && r >= 0.0,
            "r must be finite and >= 0, got {r}"
        );
        let hh = self.h1 + self.h2;
        let (c0, c1) = (g0, hh * g0 - g1);
        let q2 = r * r + hh * hh;
        let s_exact =
            c0 * hh / (q2 * q2.sqrt()) + c1 * (2.0 * hh * hh - r * r) / (q2 * q2 * q2.sqrt());
        let resid = |k: f64| {
            let e = (-hh * k).exp();
            f(k) - (c0 + c1 * k) * e
        };
        let tail = |k: f64| {
            let e = (-hh * k).exp();
            let t_g = g0 * kappa_tail(hh * k) / (hh * hh);
            let t_s = c0.abs() * e * (k / hh + 1.0 / (hh * hh))
                + c1.abs() * e * (k * k / hh + 2.0 * k / (hh * hh) + 2.0 / (hh * hh * hh));
            t_g + t_s
        };
        let h_min = self.h1.min(self.h2);
        let tol = 1e-16 * g0 * h_min / (q2 * q2.sqrt());
        self.intensity * (s_exact + hankel0(resid, r, 1.0 / hh, tail, tol, self.refine))
    }

    /// Illuminance on plane `plane` (1 or 2) at horizontal distance `r` [m].
    /// Panics on a plane other than 1 or 2, or a negative or non-finite `r`.
    pub fn illuminance(&self, plane: u8, r: f64) -> SobolevValue {
        let (hi, hj, ri, rj) = self.sides(plane);
        let hh = self.h1 + self.h2;
        let q = ri * rj;
        let g0 = (q + rj) / (1.0 - q);
        let g1 = (q * hi + rj * hj) / (1.0 - q);
        let g = |k: f64| {
            let kp = kappa(hh * k);
            (q * kp * kp * (-k * hi).exp() + rj * kp * (-k * hj).exp()) / (1.0 - q * kp * kp)
        };
        let e_reflected = self.transform(g, g0, g1, r);
        let e_direct = self.intensity * hi / (r * r + hi * hi).powf(1.5);
        SobolevValue {
            e: e_direct + e_reflected,
            e_direct,
            e_reflected,
        }
    }

    /// Illuminance [lx] of reflection order `n >= 1` on plane `plane` at `r` [m].
    pub fn order(&self, plane: u8, r: f64, n: u32) -> f64 {
        assert!(n >= 1, "reflection orders start at 1");
        let (hi, hj, ri, rj) = self.sides(plane);
        let hh = self.h1 + self.h2;
        let (p, h) = if n % 2 == 1 {
            (rj.powi(n.div_ceil(2) as i32) * ri.powi((n / 2) as i32), hj)
        } else {
            ((ri * rj).powi((n / 2) as i32), hi)
        };
        if p == 0.0 {
            return 0.0;
        }
        let c = |k: f64| p * kappa(hh * k).powi(n as i32) * (-k * h).exp();
        self.transform(c, p, p * h, r)
    }

    /// Far-field coefficient `lim r^3 E_i = I (h_i + rho_j h_j) / (1 - rho1 rho2)` [cd m].
    pub fn far_field_coefficient(&self, plane: u8) -> f64 {
        let (hi, hj, ri, rj) = self.sides(plane);
        self.intensity * (hi + rj * hj) / (1.0 - ri * rj)
    }
}
