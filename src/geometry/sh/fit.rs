//! Least-squares fit of an SH expansion to the radii of a point set (SVD).

use super::{MAX_DEGREE, ShCoeff, ShError};
use crate::math::sph_harm::{Recurrence, offset, pair_count};
use glam::DVec3;

/// Result of a least-squares SH fit (world units).
#[derive(Clone, Debug)]
pub struct ShFit {
    /// All pairs `0 <= m <= k <= degree`, k-major, in metres: use with
    /// `ShSurface::new(&coeffs, center, DMat3::IDENTITY, 1.0)`.
    pub coeffs: Vec<ShCoeff>,
    /// Root-mean-square radial residual `|p - c| - U(dir)` \[m\].
    pub rms_residual: f64,
    /// Largest absolute radial residual \[m\].
    pub max_residual: f64,
    /// Mean of `|p - c|` over the points \[m\].
    pub mean_radius: f64,
}

/// Largest condition number accepted by [`fit`].
const FIT_MAX_CONDITION: f64 = 1e12;

/// Least-squares fit of the radii `|p - center|` of `points` (world, \[m\])
/// as a function of direction by an SH expansion up to `degree` (world
/// frame, identity rotation, scale 1), by SVD (nalgebra).
///
/// Needs at least `(degree + 1)^2` points whose directions determine the
/// coefficients (condition number `<= 1e12`); rejects non-finite points and
/// points at the centre. The fitted expansion is not checked for `U > 0`;
/// [`ShSurface::new`](super::ShSurface::new) does that.
pub fn fit(points: &[DVec3], center: DVec3, degree: usize) -> Result<ShFit, ShError> {
    if !center.is_finite() {
        return Err(ShError::Center { center });
    }
    if degree > MAX_DEGREE {
        return Err(ShError::DegreeTooHigh {
            index: 0,
            k: degree,
            max: MAX_DEGREE,
        });
    }
    let needed = (degree + 1) * (degree + 1);
    if points.len() < needed {
        return Err(ShError::TooFewPoints {
            count: points.len(),
            degree,
            needed,
        });
    }
    let l = degree;
    let rec = Recurrence::new(l);
    let mut t = vec![0.0; pair_count(l)];
    let mut design = nalgebra::DMatrix::<f64>::zeros(points.len(), needed);
    let mut radii = nalgebra::DVector::<f64>::zeros(points.len());
    for (index, &p) in points.iter().enumerate() {
        if !p.is_finite() {
            return Err(ShError::PointNotFinite { index, point: p });
        }
        let v = p - center;
        let r = v.length();
        if r == 0.0 {
            return Err(ShError::PointAtCenter { index });
        }
        radii[index] = r;
        let y = v / r;
        let s = y.x.hypot(y.y);
        let (c1, s1) = if s > 0.0 {
            (y.x / s, y.y / s)
        } else {
            (1.0, 0.0)
        };
        rec.table(y.z, &mut t);
        let (mut cm, mut sm, mut spow) = (1.0, 0.0, 1.0);
        for m in 0..=l {
            let off = offset(l, m);
            for k in m..=l {
                let pkm = spow * t[off + k - m];
                let (ca, cb) = fit_columns(k, m);
                design[(index, ca)] = pkm * cm;
                if let Some(cb) = cb {
                    design[(index, cb)] = pkm * sm;
                }
            }
            spow *= s;
            (cm, sm) = (cm * c1 - sm * s1, sm * c1 + cm * s1);
        }
    }
    let svd = nalgebra::SVD::new(design.clone(), true, true);
    let sv = &svd.singular_values;
    let (smax, smin) = (sv.max(), sv.min());
    let condition = if smin > 0.0 {
        smax / smin
    } else {
        f64::INFINITY
    };
    if condition.is_nan() || condition > FIT_MAX_CONDITION {
        return Err(ShError::IllConditioned { degree, condition });
    }
    let x = svd
        .solve(&radii, 0.0)
        .expect("U and V were computed by the SVD");
    let residual = &radii - &design * &x;
    let n = points.len() as f64;
    let rms_residual = (residual.norm_squared() / n).sqrt();
    let max_residual = residual.amax();
    let mean_radius = radii.sum() / n;
    let mut coeffs = Vec::with_capacity(pair_count(l));
    for k in 0..=l {
        for m in 0..=k {
            let (ca, cb) = fit_columns(k, m);
            coeffs.push(ShCoeff {
                k,
                m,
                a: x[ca],
                b: cb.map_or(0.0, |c| x[c]),
            });
        }
    }
    Ok(ShFit {
        coeffs,
        rms_residual,
        max_residual,
        mean_radius,
    })
}

/// Columns of `a_km` and `b_km` (none at `m = 0`) in the fit's design
/// matrix: degree `k` occupies columns `k^2 .. (k+1)^2`, as
/// `a_k0, a_k1, b_k1, a_k2, b_k2, ...`.
fn fit_columns(k: usize, m: usize) -> (usize, Option<usize>) {
    if m == 0 {
        (k * k, None)
    } else {
        (k * k + 2 * m - 1, Some(k * k + 2 * m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sh::ShSurface;
    use crate::geometry::sh::tests::bumpy_coeffs;
    use glam::DMat3;
    use std::f64::consts::PI;

    fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
        let golden = PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let s = (1.0 - z * z).sqrt();
                let (sp, cp) = (golden * i as f64).sin_cos();
                DVec3::new(s * cp, s * sp, z)
            })
            .collect()
    }

    #[test]
    fn fit_recovers_exact_coefficients() {
        let truth = bumpy_coeffs(4, 0.1, 5);
        let center = DVec3::new(1.0, -2.0, 0.5);
        let s = ShSurface::new(&truth, center, DMat3::IDENTITY, 1.0).unwrap();
        let pts: Vec<DVec3> = fibonacci_sphere(800)
            .into_iter()
            .map(|y| center + s.radius(y) * y)
            .collect();
        let f = fit(&pts, center, 4).unwrap();
        assert_eq!(f.coeffs.len(), 15);
        for (t, g) in truth.iter().zip(&f.coeffs) {
            assert_eq!((t.k, t.m), (g.k, g.m));
            assert!(
                (t.a - g.a).abs() <= 1e-10 && (t.b - g.b).abs() <= 1e-10,
                "{t:?} vs {g:?}"
            );
        }
        assert!(f.rms_residual <= 1e-12 && f.max_residual <= 1e-11, "{f:?}");
        let mean = pts.iter().map(|p| (*p - center).length()).sum::<f64>() / pts.len() as f64;
        assert!((f.mean_radius - mean).abs() <= 1e-14);
        // Higher degree: the extra coefficients vanish.
        let f6 = fit(&pts, center, 6).unwrap();
        assert!(
            f6.coeffs
                .iter()
                .filter(|c| c.k > 4)
                .all(|c| c.a.abs() < 1e-10 && c.b.abs() < 1e-10)
        );
        // Lower degree: a positive residual.
        let f3 = fit(&pts, center, 3).unwrap();
        assert!(
            f3.rms_residual > 1e-4 && f3.max_residual >= f3.rms_residual,
            "{f3:?}"
        );
        // The fitted coefficients make a surface.
        let back = ShSurface::new(&f.coeffs, center, DMat3::IDENTITY, 1.0).unwrap();
        let y = DVec3::new(0.3, -0.4, 0.5).normalize();
        assert!((back.radius(y) - s.radius(y)).abs() <= 1e-11);
    }

    #[test]
    fn fit_rejects_bad_input() {
        let c0 = DVec3::ZERO;
        let pts = fibonacci_sphere(10);
        assert!(matches!(
            fit(&pts, c0, 3),
            Err(ShError::TooFewPoints { needed: 16, .. })
        ));
        let mut bad = fibonacci_sphere(50);
        bad[7] = c0;
        assert!(matches!(
            fit(&bad, c0, 2),
            Err(ShError::PointAtCenter { index: 7 })
        ));
        bad[7] = DVec3::new(f64::NAN, 0.0, 0.0);
        assert!(matches!(
            fit(&bad, c0, 2),
            Err(ShError::PointNotFinite { index: 7, .. })
        ));
        // All points on the equator: P_1^0 = 0 there, so a_10 is undetermined.
        let ring: Vec<DVec3> = (0..100)
            .map(|i| {
                let (s, c) = (2.0 * PI * i as f64 / 100.0).sin_cos();
                DVec3::new(c, s, 0.0)
            })
            .collect();
        let e = fit(&ring, c0, 2).unwrap_err();
        assert!(matches!(e, ShError::IllConditioned { .. }), "{e}");
    }
}
