//! Radial luminance profiles of disc sources (seed 000), with exact radial
//! sampling.
//!
//! On a disc of radius `R` the luminance at distance `s` from the centre is
//! `L(s) = L0 g(s)` with the *shape* `g` (peak 1) and `L0` the peak
//! luminance (the scene's `luminance`). The profiles:
//!
//! | profile | `g(s)` | `G(s) = int_0^s g(t) t dt` |
//! |---|---|---|
//! | uniform | `1` | `s^2/2` |
//! | linear-decreasing | `(R - s)/R` | `(R s^2/2 - s^3/3)/R` |
//! | linear-increasing | `s/R` | `s^3/(3R)` |
//! | v, turning `T` | `abs(s - T)/P`, `P = max(T, R - T)` | `(T s^2/2 - s^3/3)/P` for `s <= T`, `(s^3/3 - T s^2/2 + T^3/3)/P` beyond |
//! | tent, turning `T` | `s/T` up to `T`, `(R - s)/(R - T)` beyond | `s^3/(3T)`; `T^2/3 + (R (s^2 - T^2)/2 - (s^3 - T^3)/3)/(R - T)` |
//! | hyperbolic-decreasing | `R/s` (1 at the rim) | `R s` |
//! | hyperbolic-increasing | `a/(R + a - s)` (1 at the rim) | `a (c ln(c/(c - s)) - s)`, `c = R + a` |
//! | tabulated | piecewise linear through the user's points, scaled to peak 1 | exact per piece |
//!
//! **The seed's hyperbolic profiles.** `1/s` diverges at the centre, but
//! the flux `int g 2 pi s ds` is finite: it is kept, with `luminance`
//! meaning the luminance at the rim (its peak is infinite). `1/(R - s)`
//! diverges at the rim and so does its flux (`int s/(R - s) ds` grows like
//! `-R ln(R - s)`): not a luminaire. It is made integrable by an offset,
//! `1/(R + a - s)`, with `a = offset` (default `R/10`): the luminance rises
//! towards the rim to `(R + a)/a` times its centre value and is finite
//! everywhere; `luminance` is its value at the rim.
//!
//! The flux of one side is `pi L0 K` with `K = 2 pi G(R)`
//! ([`RadialProfile::flux_integral`]). Points are drawn with density
//! proportional to the luminance: `s` with density `g(s) s / G(R)`,
//! by inverting `G(s) = u G(R)` with Newton steps kept inside a bracket
//! (bisection whenever a step leaves it), and the angle uniformly.

use std::f64::consts::PI;

/// The kind of a radial profile (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub enum ProfileKind {
    /// Constant.
    Uniform,
    /// `(R - s)/R`.
    LinearDecreasing,
    /// `s/R`.
    LinearIncreasing,
    /// `abs(s - T)/max(T, R - T)`.
    V {
        /// Turning radius `T` \[m\], in `[0, R]`.
        turning: f64,
    },
    /// `s/T` up to `T`, then `(R - s)/(R - T)`; `0 < T < R`.
    Tent {
        /// Turning radius `T` \[m\].
        turning: f64,
    },
    /// `R/s`.
    HyperbolicDecreasing,
    /// `a/(R + a - s)`.
    HyperbolicIncreasing {
        /// Offset `a > 0` \[m\].
        offset: f64,
    },
    /// Piecewise linear through `(s[i], g[i])`, `s` from 0 to `R`,
    /// `max g = 1`, with `cum[i] = G(s[i])`.
    Tabulated {
        /// Radii \[m\], from 0 to `R`, increasing.
        s: Vec<f64>,
        /// Shape values, peak 1.
        g: Vec<f64>,
        /// `G` at each radius.
        cum: Vec<f64>,
    },
}

/// A radial luminance profile on a disc of radius `radius` \[m\].
#[derive(Clone, Debug, PartialEq)]
pub struct RadialProfile {
    radius: f64,
    kind: ProfileKind,
    /// `G(R)`.
    total: f64,
}

impl RadialProfile {
    /// A profile of `kind` on a disc of `radius` \[m\] (checked by
    /// [`Self::parse`]; a tent with `T = 0` or `T = R` becomes the linear
    /// profile it equals).
    pub fn new(radius: f64, kind: ProfileKind) -> Self {
        let kind = match kind {
            ProfileKind::Tent { turning } if turning <= 0.0 => ProfileKind::LinearDecreasing,
            ProfileKind::Tent { turning } if turning >= radius => ProfileKind::LinearIncreasing,
            k => k,
        };
        let mut p = Self {
            radius,
            kind,
            total: 0.0,
        };
        p.total = p.g_int(radius);
        p
    }

    /// The uniform profile on a disc of `radius` \[m\].
    pub fn uniform(radius: f64) -> Self {
        Self::new(radius, ProfileKind::Uniform)
    }

    /// Whether the profile is uniform.
    pub fn is_uniform(&self) -> bool {
        matches!(self.kind, ProfileKind::Uniform)
    }

    /// The profile's kind.
    pub fn kind(&self) -> &ProfileKind {
        &self.kind
    }

    /// Relative luminance `g(s)` at distance `s` \[m\] from the centre (peak
    /// 1; see the module docs), 0 beyond the rim.
    pub fn shape(&self, s: f64) -> f64 {
        let r = self.radius;
        if !(0.0..=r).contains(&s) {
            return 0.0;
        }
        match &self.kind {
            ProfileKind::Uniform => 1.0,
            ProfileKind::LinearDecreasing => (r - s) / r,
            ProfileKind::LinearIncreasing => s / r,
            ProfileKind::V { turning: t } => (s - t).abs() / t.max(r - t),
            ProfileKind::Tent { turning: t } => {
                if s <= *t {
                    s / t
                } else {
                    (r - s) / (r - t)
                }
            }
            ProfileKind::HyperbolicDecreasing => r / s,
            ProfileKind::HyperbolicIncreasing { offset: a } => a / (r + a - s),
            ProfileKind::Tabulated { s: xs, g, .. } => {
                let i = xs.partition_point(|&x| x <= s).clamp(1, xs.len() - 1);
                let (x0, x1) = (xs[i - 1], xs[i]);
                let w = if x1 > x0 { (s - x0) / (x1 - x0) } else { 0.0 };
                g[i - 1] + (g[i] - g[i - 1]) * w
            }
        }
    }

    /// `G(s) = int_0^s g(t) t dt` [m^2] in closed form.
    fn g_int(&self, s: f64) -> f64 {
        let r = self.radius;
        let s = s.clamp(0.0, r);
        match &self.kind {
            ProfileKind::Uniform => s * s / 2.0,
            ProfileKind::LinearDecreasing => (r * s * s / 2.0 - s * s * s / 3.0) / r,
            ProfileKind::LinearIncreasing => s * s * s / (3.0 * r),
            ProfileKind::V { turning: t } => {
                let p = t.max(r - t);
                let v = if s <= *t {
                    t * s * s / 2.0 - s * s * s / 3.0
                } else {
                    s * s * s / 3.0 - t * s * s / 2.0 + t * t * t / 3.0
                };
                v / p
            }
            ProfileKind::Tent { turning: t } => {
                if s <= *t {
                    s * s * s / (3.0 * t)
                } else {
                    t * t / 3.0
                        + (r * (s * s - t * t) / 2.0 - (s * s * s - t * t * t) / 3.0) / (r - t)
                }
            }
            ProfileKind::HyperbolicDecreasing => r * s,
            ProfileKind::HyperbolicIncreasing { offset: a } => {
                let c = r + a;
                // c ln(c / (c - s)) - s, with ln_1p for small s.
                a * (-c * (-s / c).ln_1p() - s)
            }
            ProfileKind::Tabulated { s: xs, g, cum } => {
                let i = xs.partition_point(|&x| x <= s).clamp(1, xs.len() - 1);
                let (x0, x1) = (xs[i - 1], xs[i]);
                if x1 <= x0 {
                    return cum[i - 1];
                }
                let k = (g[i] - g[i - 1]) / (x1 - x0);
                cum[i - 1] + piece(g[i - 1], k, x0, s)
            }
        }
    }

    /// `int g dA = 2 pi G(R)` [m^2] over the disc: a one-sided disc of peak
    /// luminance `L0` emits `pi L0` times this \[lm\].
    pub fn flux_integral(&self) -> f64 {
        2.0 * PI * self.total
    }

    /// Cumulative distribution of the sampled radius, `G(s) / G(R)`.
    pub fn cdf(&self, s: f64) -> f64 {
        self.g_int(s) / self.total
    }

    /// Density of the sampled radius per unit radius [1/m], `g(s) s / G(R)`.
    pub fn pdf_radius(&self, s: f64) -> f64 {
        self.shape(s) * s / self.total
    }

    /// A radius \[m\] with density [`Self::pdf_radius`], for `u` in `[0, 1)`:
    /// the root of `G(s) = u G(R)` by Newton steps inside a shrinking
    /// bracket (bisection when a step would leave it). Singular profiles
    /// (`R/s`) are kept at least `1e-9 R` from the centre, where their
    /// luminance stays finite (a shift of probability 1e-9 by 1e-9 R).
    pub fn sample_radius(&self, u: f64) -> f64 {
        let r = self.radius;
        let target = u.clamp(0.0, 1.0) * self.total;
        let floor = match self.kind {
            ProfileKind::HyperbolicDecreasing => 1e-9 * r,
            _ => 0.0,
        };
        // A start from the uniform profile's inverse.
        let s = crate::math::roots::bracketed_newton(
            |s| (self.g_int(s) - target, self.shape(s) * s),
            0.0,
            r,
            r * u.clamp(0.0, 1.0).sqrt(),
        );
        s.clamp(floor, r)
    }

    /// Read a profile from the scene's `profile` value for a disc of
    /// `radius` \[m\]: a name (`"uniform"`, `"linear-decreasing"`,
    /// `"linear-increasing"`, `"hyperbolic-decreasing"`,
    /// `"hyperbolic-increasing"`) or a table `{ type = "v", turning = T }`,
    /// `{ type = "tent", turning = T }` (`T` \[m\]),
    /// `{ type = "hyperbolic-increasing", offset = a }` or
    /// `{ type = "tabulated", s = [...], l = [...] }` (radii from 0 to the
    /// radius, increasing; luminances `>= 0`, any scale: the peak becomes
    /// the scene's `luminance`).
    pub fn parse(value: &toml::Value, radius: f64) -> Result<Self, String> {
        let kinds = "`uniform`, `linear-decreasing`, `linear-increasing`, `v`, `tent`, \
                     `hyperbolic-decreasing`, `hyperbolic-increasing`, `tabulated`";
        let (name, table) = match value {
            toml::Value::String(s) => (s.as_str(), None),
            toml::Value::Table(t) => match t.get("type") {
                Some(toml::Value::String(s)) => (s.as_str(), Some(t)),
                _ => return Err(format!("a profile table needs `type` (one of {kinds})")),
            },
            _ => return Err(format!("must be a name or a table (one of {kinds})")),
        };
        let allowed: &[&str] = match name {
            "v" | "tent" => &["type", "turning"],
            "hyperbolic-increasing" => &["type", "offset"],
            "tabulated" => &["type", "s", "l"],
            _ => &["type"],
        };
        if let Some(t) = table
            && let Some(k) = t.keys().find(|k| !allowed.contains(&k.as_str()))
        {
            return Err(format!("`{k}` is not a field of a `{name}` profile"));
        }
        let number = |key: &str| -> Result<f64, String> {
            let v = table
                .and_then(|t| t.get(key))
                .ok_or_else(|| format!("a `{name}` profile needs `{key}` [m]"))?;
            let x = v
                .as_float()
                .or_else(|| v.as_integer().map(|i| i as f64))
                .ok_or_else(|| format!("`{key}` must be a number"))?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(format!(
                    "`{key}` must be finite, got {}",
                    crate::io::format_number(x)
                ))
            }
        };
        let list = |key: &str| -> Result<Vec<f64>, String> {
            let v = table
                .and_then(|t| t.get(key))
                .and_then(|v| v.as_array())
                .ok_or_else(|| format!("a `tabulated` profile needs the list `{key}`"))?;
            v.iter()
                .map(|x| {
                    x.as_float()
                        .or_else(|| x.as_integer().map(|i| i as f64))
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| format!("`{key}` must hold finite numbers"))
                })
                .collect()
        };
        let kind = match name {
            "uniform" => ProfileKind::Uniform,
            "linear-decreasing" => ProfileKind::LinearDecreasing,
            "linear-increasing" => ProfileKind::LinearIncreasing,
            "hyperbolic-decreasing" => ProfileKind::HyperbolicDecreasing,
            "hyperbolic-increasing" => {
                let a = if table.is_some_and(|t| t.contains_key("offset")) {
                    number("offset")?
                } else {
                    radius / 10.0
                };
                if a <= 0.0 {
                    return Err(format!(
                        "`offset` must be > 0 [m] (1/(R - s) is not integrable), got {}",
                        crate::io::format_number(a)
                    ));
                }
                ProfileKind::HyperbolicIncreasing { offset: a }
            }
            "v" | "tent" => {
                let t = number("turning")?;
                if !(0.0..=radius).contains(&t) {
                    return Err(format!(
                        "`turning` must lie in [0, {radius}] (the radius), got {}",
                        crate::io::format_number(t)
                    ));
                }
                if name == "v" {
                    ProfileKind::V { turning: t }
                } else {
                    ProfileKind::Tent { turning: t }
                }
            }
            "tabulated" => {
                let (s, l) = (list("s")?, list("l")?);
                if s.len() < 2 || s.len() != l.len() {
                    return Err(format!(
                        "`s` and `l` need the same length, at least 2 (got {} and {})",
                        s.len(),
                        l.len()
                    ));
                }
                if s[0] != 0.0 || (s[s.len() - 1] - radius).abs() > 1e-9 * radius {
                    return Err(format!(
                        "`s` must run from 0 to the radius {radius}, got {} .. {}",
                        s[0],
                        s[s.len() - 1]
                    ));
                }
                if s.windows(2).any(|w| w[1] <= w[0]) {
                    return Err("`s` must increase strictly".into());
                }
                let peak = l.iter().copied().fold(0.0, f64::max);
                if l.iter().any(|&x| x < 0.0) || peak <= 0.0 {
                    return Err("`l` must be >= 0 and not all 0".into());
                }
                let mut s = s;
                let last = s.len() - 1;
                s[last] = radius;
                let g: Vec<f64> = l.iter().map(|x| x / peak).collect();
                let mut cum = vec![0.0; s.len()];
                for i in 1..s.len() {
                    let k = (g[i] - g[i - 1]) / (s[i] - s[i - 1]);
                    cum[i] = cum[i - 1] + piece(g[i - 1], k, s[i - 1], s[i]);
                }
                ProfileKind::Tabulated { s, g, cum }
            }
            other => {
                return Err(format!(
                    "unknown profile `{other}` (this version knows {kinds})"
                ));
            }
        };
        Ok(Self::new(radius, kind))
    }
}

/// `int_{x0}^{x} (g0 + k (t - x0)) t dt` for one linear piece.
fn piece(g0: f64, k: f64, x0: f64, x: f64) -> f64 {
    let c = g0 - k * x0;
    c * (x * x - x0 * x0) / 2.0 + k * (x * x * x - x0 * x0 * x0) / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;

    fn profiles() -> Vec<(&'static str, RadialProfile)> {
        let r = 0.4;
        let t = |s: &str| toml::from_str::<toml::Table>(&format!("p = {s}")).unwrap()["p"].clone();
        [
            ("uniform", "\"uniform\""),
            ("linear-decreasing", "\"linear-decreasing\""),
            ("linear-increasing", "\"linear-increasing\""),
            ("v", "{ type = \"v\", turning = 0.15 }"),
            ("tent", "{ type = \"tent\", turning = 0.1 }"),
            ("hyperbolic-decreasing", "\"hyperbolic-decreasing\""),
            ("hyperbolic-increasing", "\"hyperbolic-increasing\""),
            (
                "tabulated",
                "{ type = \"tabulated\", s = [0.0, 0.1, 0.25, 0.4], l = [2.0, 5.0, 1.0, 0.0] }",
            ),
        ]
        .into_iter()
        .map(|(n, v)| (n, RadialProfile::parse(&t(v), r).unwrap()))
        .collect()
    }

    /// `int_0^R g(s) s ds` by 20-point Gauss-Legendre on 400 panels (split
    /// at the kinks by their fineness; the 1/s profile's integrand is 1).
    fn quad(p: &RadialProfile, a: f64, b: f64) -> f64 {
        let n = 400;
        let h = (b - a) / n as f64;
        (0..n)
            .map(|k| {
                let lo = a + h * k as f64;
                crate::math::quadrature::panel(&|s: f64| p.shape(s) * s, lo, lo + h)
            })
            .sum()
    }

    #[test]
    fn closed_forms_match_quadrature_and_the_peak_is_one() {
        for (name, p) in profiles() {
            for s in [0.05, 0.1, 0.15, 0.2, 0.33, 0.4] {
                let q = quad(&p, 0.0, s);
                assert!(
                    (p.g_int(s) - q).abs() <= 1e-6 * q.max(1e-12),
                    "{name} at {s}: {} vs {q}",
                    p.g_int(s)
                );
            }
            assert!(
                (p.flux_integral() - 2.0 * PI * quad(&p, 0.0, 0.4)).abs()
                    < 1e-6 * p.flux_integral()
            );
            let peak = (1..=4000)
                .map(|k| p.shape(0.4 * k as f64 / 4000.0))
                .fold(0.0, f64::max);
            if name != "hyperbolic-decreasing" {
                assert!((peak - 1.0).abs() < 1e-3, "{name}: peak {peak}");
            } else {
                assert!((p.shape(0.4) - 1.0).abs() < 1e-15, "1 at the rim");
            }
        }
    }

    #[test]
    fn sampling_inverts_the_cdf() {
        for (name, p) in profiles() {
            for k in 0..=200 {
                let u = k as f64 / 200.0;
                let s = p.sample_radius(u);
                assert!((0.0..=0.4).contains(&s));
                let tol = if name == "hyperbolic-decreasing" {
                    1e-8
                } else {
                    1e-12
                };
                assert!(
                    (p.cdf(s) - u).abs() < tol,
                    "{name}: u {u} -> s {s}, cdf {}",
                    p.cdf(s)
                );
            }
        }
    }

    /// Kolmogorov-Smirnov statistic `sqrt(n) D` of samples against `cdf`.
    fn ks(samples: &mut [f64], cdf: &dyn Fn(f64) -> f64) -> f64 {
        samples.sort_by(f64::total_cmp);
        let n = samples.len() as f64;
        let d = samples
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                let f = cdf(x);
                (f - i as f64 / n)
                    .abs()
                    .max((((i + 1) as f64) / n - f).abs())
            })
            .fold(0.0, f64::max);
        n.sqrt() * d
    }

    #[test]
    fn kolmogorov_smirnov_per_profile_and_a_wrong_cdf_fails() {
        // Eight tests at family-wise 1e-3: the asymptotic Kolmogorov
        // quantile for 1.25e-4 is about 2.16.
        let bound = 2.16;
        for (name, p) in profiles() {
            let mut rng = Philox4x32::new(42, 0);
            let mut xs: Vec<f64> = (0..20_000)
                .map(|_| p.sample_radius(rng.next_f64()))
                .collect();
            let d = ks(&mut xs, &|s| p.cdf(s));
            assert!(d < bound, "{name}: sqrt(n) D = {d}");
            if name != "uniform" {
                // The uniform disc's CDF (s/R)^2 is rejected.
                let wrong = ks(&mut xs, &|s| (s / 0.4).powi(2));
                assert!(
                    wrong > 3.0 * bound,
                    "{name}: the wrong CDF gives only {wrong}"
                );
            }
        }
    }

    #[test]
    fn bad_profiles_are_refused_with_the_field() {
        let t = |s: &str| toml::from_str::<toml::Table>(&format!("p = {s}")).unwrap()["p"].clone();
        for (v, what) in [
            ("{ type = \"v\" }", "turning"),
            ("{ type = \"tent\", turning = 0.5 }", "turning"),
            ("{ type = \"hyperbolic-increasing\", offset = 0 }", "offset"),
            (
                "{ type = \"tabulated\", s = [0, 0.4], l = [1] }",
                "same length",
            ),
            (
                "{ type = \"tabulated\", s = [0.1, 0.4], l = [1, 1] }",
                "from 0",
            ),
            (
                "{ type = \"tabulated\", s = [0, 0.4], l = [0, 0] }",
                "not all 0",
            ),
            ("\"cosine\"", "unknown profile"),
            ("{ type = \"v\", turning = 0.1, slope = 2 }", "slope"),
            ("3", "name or a table"),
        ] {
            let e = RadialProfile::parse(&t(v), 0.4).unwrap_err();
            assert!(e.contains(what), "{v}: {e}");
        }
    }
}
