//! A thin clear pane of glass: specular transmission straight through and
//! specular reflection, with the angle-dependent transmittance and
//! reflectance of a plane-parallel slab.
//!
//! Model (the classical thin-slab result, e.g. Rubin, "Optical properties
//! of soda lime silica glasses", Solar Energy Materials 12, 1985; Born and
//! Wolf, *Principles of Optics*, Sec. 1.5): unpolarised light meets the
//! pane at incidence cosine `c`; inside, it travels at the refraction angle
//! `cos t = sqrt(1 - (1 - c^2) / n^2)` and one pass through the pane keeps
//! the fraction `tau_t = tau^(1 / cos t)` of it (`tau`: one pass at normal
//! incidence, the internal transmittance). For each polarisation with
//! Fresnel reflectance `r` of one air-glass interface, summing the light
//! reflected back and forth inside the pane (a geometric series):
//!
//! `T = (1 - r)^2 tau_t / (1 - r^2 tau_t^2)`,
//! `R = r + (1 - r)^2 r tau_t^2 / (1 - r^2 tau_t^2)`,
//!
//! and the pane's `T`, `R` are the means over the `s` and `p`
//! polarisations, with `r_s = ((c - n cos t) / (c + n cos t))^2` and
//! `r_p = ((n c - cos t) / (n c + cos t))^2`. A thin pane does not displace
//! the rays that cross it (the offset is the thickness times a factor of
//! order one, millimetres).
//!
//! The user gives the normal (hemispherical-free, direct) transmittance
//! `T_n` of the pane, which glass makers list, and the refractive index
//! (1.52 for soda-lime float glass by default); `tau` follows from the
//! normal-incidence form of `T` (a quadratic in `tau`, see [`Glass::new`]).

/// A thin pane: normal transmittance, refractive index and the internal
/// transmittance derived from them (all dimensionless).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glass {
    /// Direct transmittance at normal incidence, `T(1)`.
    pub transmittance: f64,
    /// Refractive index of the glass (relative to air).
    pub index: f64,
    /// Internal transmittance of one pass at normal incidence (`tau`).
    tau: f64,
}

/// Default refractive index: soda-lime float glass.
pub const FLOAT_GLASS_INDEX: f64 = 1.52;

impl Glass {
    /// The pane whose normal transmittance is `transmittance`, of refractive
    /// index `index`. Inverts `T_n = (1 - r0)^2 tau / (1 - r0^2 tau^2)`
    /// (`r0 = ((n - 1)/(n + 1))^2`) for the internal transmittance:
    /// `tau = 2 T_n / ((1 - r0)^2 + sqrt((1 - r0)^4 + 4 r0^2 T_n^2))`, the
    /// positive root written without cancellation.
    ///
    /// # Errors
    /// `index` not in [1, 5] or not finite; `transmittance` not in
    /// `[0, T_max]` with `T_max = 2 n / (n^2 + 1)`, the transmittance of a
    /// pane that absorbs nothing (its two surfaces alone reflect the rest).
    pub fn new(transmittance: f64, index: f64) -> Result<Self, String> {
        if !(index.is_finite() && (1.0..=5.0).contains(&index)) {
            return Err(format!(
                "`index` must lie in [1, 5], got {}",
                crate::io::format_number(index)
            ));
        }
        let t_max = 2.0 * index / (index * index + 1.0);
        // (Rounding of a value computed as `T_max` itself is let through.)
        if !(transmittance.is_finite() && (0.0..=t_max * (1.0 + 1e-12)).contains(&transmittance)) {
            return Err(format!(
                "`transmittance` must lie in [0, {}] (a pane of index {} that absorbs nothing \
                 still reflects the rest at its two surfaces), got {}",
                crate::io::format_number(t_max),
                crate::io::format_number(index),
                crate::io::format_number(transmittance)
            ));
        }
        let r0 = ((index - 1.0) / (index + 1.0)).powi(2);
        let a = (1.0 - r0) * (1.0 - r0);
        let tn = transmittance;
        let tau = (2.0 * tn / (a + (a * a + 4.0 * r0 * r0 * tn * tn).sqrt())).min(1.0);
        Ok(Self {
            transmittance,
            index,
            tau,
        })
    }

    /// Internal transmittance of one pass at normal incidence.
    pub fn internal_transmittance(&self) -> f64 {
        self.tau
    }

    /// `(R, T)`: the pane's specular reflectance and transmittance for
    /// unpolarised light at incidence cosine `c` (either side; `|c|` is
    /// used). Grazing incidence (`c = 0`) reflects everything.
    #[inline]
    pub fn reflect_transmit(&self, c: f64) -> (f64, f64) {
        let c = c.abs().min(1.0);
        if c.is_nan() || c <= 0.0 {
            return (1.0, 0.0);
        }
        let n = self.index;
        let ct = (1.0 - (1.0 - c * c) / (n * n)).max(0.0).sqrt();
        let tau_t = if self.tau >= 1.0 {
            1.0
        } else if self.tau <= 0.0 {
            0.0
        } else {
            (self.tau.ln() / ct).exp()
        };
        let rs = ((c - n * ct) / (c + n * ct)).powi(2);
        let rp = ((n * c - ct) / (n * c + ct)).powi(2);
        let slab = |r: f64| {
            let d = 1.0 - r * r * tau_t * tau_t;
            if d <= 0.0 {
                // r = 1 and tau_t = 1: everything is reflected.
                return (1.0, 0.0);
            }
            let g = (1.0 - r) * (1.0 - r) / d;
            (r + g * r * tau_t * tau_t, g * tau_t)
        };
        let (r1, t1) = slab(rs);
        let (r2, t2) = slab(rp);
        (0.5 * (r1 + r2), 0.5 * (t1 + t2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fresnel reflectance of one interface for one polarisation, from
    /// Snell's law with angles (a second route: `sin`/`cos` of the angles,
    /// not the cosine algebra above).
    fn fresnel_angles(theta_i: f64, n: f64) -> (f64, f64) {
        if theta_i == 0.0 {
            let r = ((n - 1.0) / (n + 1.0)).powi(2);
            return (r, r);
        }
        let theta_t = (theta_i.sin() / n).asin();
        let rs = ((theta_i - theta_t).sin() / (theta_i + theta_t).sin()).powi(2);
        let rp = ((theta_i - theta_t).tan() / (theta_i + theta_t).tan()).powi(2);
        (rs, rp)
    }

    /// The slab by explicit ray bookkeeping: each internal bounce pair
    /// multiplies by `(r tau_t)^2`, summed until negligible.
    fn slab_series(r: f64, tau_t: f64) -> (f64, f64) {
        let (mut t, mut rr) = (0.0, r);
        let mut amp = (1.0 - r) * tau_t; // entering, one pass
        for _ in 0..10_000 {
            t += amp * (1.0 - r);
            rr += amp * r * tau_t * (1.0 - r);
            amp *= r * tau_t * r * tau_t;
            if amp < 1e-18 {
                break;
            }
        }
        (rr, t)
    }

    fn reference(g: &Glass, theta_i: f64) -> (f64, f64) {
        let n = g.index;
        let (rs, rp) = fresnel_angles(theta_i, n);
        let theta_t = (theta_i.sin() / n).asin();
        let tau_t = g.internal_transmittance().powf(1.0 / theta_t.cos());
        let (r1, t1) = slab_series(rs, tau_t);
        let (r2, t2) = slab_series(rp, tau_t);
        ((r1 + r2) / 2.0, (t1 + t2) / 2.0)
    }

    #[test]
    fn textbook_fresnel_values() {
        // n = 1.5 at 45 degrees: R_s = 0.0920, R_p = 0.0085 (one interface).
        let (rs, rp) = fresnel_angles(45f64.to_radians(), 1.5);
        assert!((rs - 0.0920).abs() < 5e-5, "{rs}");
        assert!((rp - 0.00847).abs() < 5e-5, "{rp}");
        // A lossless pane of n = 1.5 at normal incidence: T = 2n/(n^2+1).
        let g = Glass::new(2.0 * 1.5 / (1.5 * 1.5 + 1.0), 1.5).unwrap();
        let (r, t) = g.reflect_transmit(1.0);
        assert!((t - 12.0 / 13.0).abs() < 1e-12 && (r - 1.0 / 13.0).abs() < 1e-12);
        // Brewster's angle: the p wave passes a lossless pane whole.
        let tb = 1.5f64.atan();
        let (_, rp) = fresnel_angles(tb, 1.5);
        assert!(rp < 1e-20);
    }

    #[test]
    fn normal_transmittance_round_trips() {
        for &n in &[1.0, 1.33, 1.52, 2.4] {
            let t_max = 2.0 * n / (n * n + 1.0);
            for k in 0..=20 {
                let tn = t_max * k as f64 / 20.0;
                let g = Glass::new(tn, n).unwrap();
                let (r, t) = g.reflect_transmit(1.0);
                assert!((t - tn).abs() < 1e-13, "n {n} T_n {tn}: T(1) = {t}");
                assert!(r >= 0.0 && r + t <= 1.0 + 1e-15);
            }
        }
    }

    #[test]
    fn matches_the_series_at_every_angle() {
        for &(tn, n) in &[
            (0.88, 1.52),
            (0.5, 1.52),
            (0.9, 1.5),
            (0.0, 1.52),
            (0.91, 1.52),
        ] {
            let g = Glass::new(tn, n).unwrap();
            for k in 0..=89 {
                let th = (k as f64).to_radians();
                let (r, t) = g.reflect_transmit(th.cos());
                let (rr, tr) = reference(&g, th);
                assert!(
                    (r - rr).abs() < 1e-12 && (t - tr).abs() < 1e-12,
                    "T_n {tn} n {n} at {k} deg: ({r}, {t}) vs ({rr}, {tr})"
                );
                // Energy: nothing is created; absorption >= 0.
                assert!(r + t <= 1.0 + 1e-14 && r >= 0.0 && t >= 0.0);
            }
        }
    }

    #[test]
    fn angular_fall_off_of_clear_float_glass() {
        // Clear 4 mm float: T_n = 0.88 (n = 1.52). T falls slowly to 50
        // degrees, then steeply; R rises from about 8 %.
        let g = Glass::new(0.88, FLOAT_GLASS_INDEX).unwrap();
        let t = |deg: f64| g.reflect_transmit(deg.to_radians().cos()).1;
        let r = |deg: f64| g.reflect_transmit(deg.to_radians().cos()).0;
        assert!((r(0.0) - 0.0792).abs() < 2e-3, "{}", r(0.0));
        assert!(t(30.0) < 0.88 && t(30.0) > 0.86, "{}", t(30.0));
        assert!(t(60.0) > 0.74 && t(60.0) < 0.80, "{}", t(60.0));
        assert!(t(80.0) < 0.45, "{}", t(80.0));
        for k in 1..90 {
            assert!(t(k as f64) <= t(k as f64 - 1.0) + 1e-15);
        }
        assert_eq!(g.reflect_transmit(0.0), (1.0, 0.0));
        assert_eq!(g.reflect_transmit(-1.0), g.reflect_transmit(1.0));
    }

    #[test]
    fn refuses_what_no_pane_can_do() {
        assert!(Glass::new(0.95, 1.52).is_err());
        assert!(Glass::new(-0.1, 1.52).is_err());
        assert!(Glass::new(0.8, 0.9).is_err());
        assert!(Glass::new(f64::NAN, 1.52).is_err());
        assert!(Glass::new(0.8, f64::INFINITY).is_err());
    }
}
