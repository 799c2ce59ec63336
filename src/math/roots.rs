//! Root finding for inverting monotone CDFs.

/// The root of an increasing function on `[lo, hi]` by Newton steps kept
/// inside a shrinking bracket: `fd(x)` gives `(f(x), f'(x))`; a step that
/// would leave the bracket (or a zero derivative) is replaced by bisection,
/// so the iteration always converges; it stops when the bracket or the
/// step falls below a few ulps of `scale` (the interval's size) or `f` is
/// exactly 0. Starts at `x0` (clamped into the bracket).
pub fn bracketed_newton(fd: impl Fn(f64) -> (f64, f64), mut lo: f64, mut hi: f64, x0: f64) -> f64 {
    let scale = (hi - lo).abs().max(f64::MIN_POSITIVE);
    let mut x = x0.clamp(lo, hi);
    for _ in 0..200 {
        let (f, d) = fd(x);
        if f == 0.0 {
            break;
        }
        if f > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        if hi - lo <= 4.0 * f64::EPSILON * scale {
            break;
        }
        let next = if d > 0.0 { x - f / d } else { f64::NAN };
        let step = if next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
        if (step - x).abs() <= 2.0 * f64::EPSILON * scale {
            x = step;
            break;
        }
        x = step;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_roots_of_steep_flat_and_kinked_functions() {
        // x^3 on [0, 1] (zero slope at the start), u = 1e-12 .. 1.
        for u in [0.0, 1e-12, 0.3, 0.999, 1.0] {
            let x = bracketed_newton(|x| (x * x * x - u, 3.0 * x * x), 0.0, 1.0, 0.5);
            assert!((x * x * x - u).abs() < 1e-14, "{u}: {x}");
        }
        // A kink: slope 1 then 100.
        let f = |x: f64| {
            if x < 0.5 {
                (x - 0.7, 1.0)
            } else {
                (0.5 - 0.7 + 100.0 * (x - 0.5), 100.0)
            }
        };
        let x = bracketed_newton(f, 0.0, 1.0, 0.0);
        assert!((x - 0.502).abs() < 1e-14, "{x}");
    }
}
