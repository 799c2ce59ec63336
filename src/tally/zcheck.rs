//! z scores against references, and their largest `|z|`, with no bad
//! receiver dropped.
//!
//! An estimate `x` with standard error `s` checked against a reference
//! value `r` has the z score
//!
//! ```text
//! z = (x - r) / s            for 0 < s < inf,
//! z = 0                      for s = 0 and x = r exactly,
//! z = +-inf                  for s = 0 and x != r,
//! z = NaN                    for x, r or s not finite, or s < 0.
//! ```
//!
//! A zero standard error is a claim of exactness (nothing random was
//! scored): it passes only when the value is the reference to the last bit;
//! otherwise the z score is infinite. A receiver that never scores thus
//! fails instead of being left out of the test. Where rounding of a closed
//! form is expected, the caller adds a stated rounding allowance to `s` in
//! quadrature (`s = sqrt(s_mc^2 + a^2)`); the allowance is then part of the
//! error, never an exception to the test.
//!
//! A z score *passes* a two-sided bound `k` when it is finite and
//! `|z| <= k` ([`within`]); so a NaN or an infinite z fails. The largest
//! `|z|` over many receivers ([`max_abs_z`], [`max_abs`]) propagates NaN,
//! unlike `f64::max`, which returns the other operand and so drops a NaN
//! silently; the comparison `max <= k` is then false, and the fold fails.

/// z score of `estimate` against `reference` with standard error
/// `std_error` (same unit), by the rules of the module doc: NaN when any
/// input is not finite or the error is negative; with zero error, 0 when
/// the estimate equals the reference exactly and `+-inf` otherwise.
pub fn z_score(estimate: f64, std_error: f64, reference: f64) -> f64 {
    if !(estimate.is_finite() && reference.is_finite()) {
        return f64::NAN;
    }
    z_of_difference(estimate - reference, std_error)
}

/// z score of a difference `diff = estimate - reference` taken by the
/// caller (for example part by part), with standard error `std_error`;
/// the rules of [`z_score`].
pub fn z_of_difference(diff: f64, std_error: f64) -> f64 {
    if !(diff.is_finite() && std_error.is_finite()) || std_error < 0.0 {
        f64::NAN
    } else if std_error > 0.0 {
        diff / std_error
    } else if diff == 0.0 {
        0.0
    } else {
        diff.signum() * f64::INFINITY
    }
}

/// Rounding allowance for the difference of two closed forms `a` and `b`
/// of a few floating-point operations each (each good to a few `eps/2`):
/// `3 eps (|a| + |b|)`, same unit. Add it to the standard error in
/// quadrature, `sqrt(s^2 + allowance^2)`, where an exact part (a direct
/// illuminance) is computed twice by different code; it is the only
/// tolerance a zero-error comparison gets.
pub fn rounding_allowance(a: f64, b: f64) -> f64 {
    3.0 * f64::EPSILON * (a.abs() + b.abs())
}

/// Whether `z` passes the two-sided bound `bound`: finite and `|z| <= bound`.
pub fn within(z: f64, bound: f64) -> bool {
    z.is_finite() && z.abs() <= bound
}

/// The larger of `acc` and `|x|`, NaN when either is NaN: the step of a
/// fold of `|z|` that keeps a NaN (`f64::max` drops it).
pub fn max_abs(acc: f64, x: f64) -> f64 {
    if acc.is_nan() || x.is_nan() {
        f64::NAN
    } else {
        acc.max(x.abs())
    }
}

/// Largest `|z|` over `zs`: NaN if any is NaN, `inf` if any is infinite, 0
/// for none. Compare it with [`within`] (or `<=`, which is false for NaN).
pub fn max_abs_z(zs: impl IntoIterator<Item = f64>) -> f64 {
    zs.into_iter().fold(0.0, max_abs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordinary_z() {
        assert_eq!(z_score(11.0, 2.0, 10.0), 0.5);
        assert_eq!(z_score(9.0, 2.0, 10.0), -0.5);
        assert!(within(z_score(11.0, 2.0, 10.0), 1.0));
        assert!(!within(z_score(13.0, 2.0, 10.0), 1.0));
    }

    #[test]
    fn non_finite_inputs_fail() {
        for (x, s, r) in [
            (f64::NAN, 1.0, 0.0),
            (0.0, f64::NAN, 0.0),
            (0.0, 1.0, f64::NAN),
            (f64::INFINITY, 1.0, 0.0),
            (0.0, 1.0, f64::NEG_INFINITY),
            (0.0, f64::INFINITY, 0.0),
            (1.0, -1.0, 0.0),
        ] {
            let z = z_score(x, s, r);
            assert!(z.is_nan(), "({x}, {s}, {r}) -> {z}");
            assert!(!within(z, 1e300), "({x}, {s}, {r}) passes");
        }
    }

    #[test]
    fn zero_error_passes_only_when_exact() {
        assert_eq!(z_score(0.7207, 0.0, 0.7207), 0.0);
        assert!(within(z_score(0.7207, 0.0, 0.7207), 0.0));
        assert_eq!(z_score(0.0, 0.0, 0.0), 0.0);
        // One ulp off with a zero error: infinite z, fails any bound.
        let next = f64::from_bits(0.7207f64.to_bits() + 1);
        assert_eq!(z_score(next, 0.0, 0.7207), f64::INFINITY);
        assert_eq!(z_score(0.7207, 0.0, next), f64::NEG_INFINITY);
        assert!(!within(z_score(next, 0.0, 0.7207), 1e300));
        // A receiver that never scored where light was expected.
        assert!(!within(z_score(0.0, 0.0, 1.0), 1e300));
        // One ulp of a closed form, with the rounding allowance: passes;
        // 1e-12 off does not.
        let a = rounding_allowance(next, 0.7207);
        assert!(within(z_score(next, a, 0.7207), 1.0));
        assert!(!within(z_score(0.7207 * (1.0 + 1e-12), a, 0.7207), 3.0));
    }

    #[test]
    fn fold_keeps_nan_and_inf() {
        assert_eq!(max_abs_z([0.5, -2.0, 1.0]), 2.0);
        assert_eq!(max_abs_z(std::iter::empty()), 0.0);
        // `f64::max` would give 2 here, in either order.
        assert!(max_abs_z([f64::NAN, -2.0, 1.0]).is_nan());
        assert!(max_abs_z([1.0, -2.0, f64::NAN]).is_nan());
        assert_eq!(max_abs_z([1.0, f64::NEG_INFINITY]), f64::INFINITY);
        assert!(!within(max_abs_z([0.1, f64::NAN]), 3.0));
        let passes = max_abs_z([0.1, f64::NAN]) <= 3.0;
        assert!(!passes);
        assert!(max_abs(f64::NAN, 1.0).is_nan());
        assert!(max_abs(1.0, f64::NAN).is_nan());
    }
}
