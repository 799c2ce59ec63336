//! Randomised quasi-Monte Carlo: a digitally shifted Sobol' (0,2)-net.
//!
//! The first two Sobol' dimensions (van der Corput, and the Pascal-matrix
//! dimension) form a (0,2)-sequence in base 2: the first `2^m` points put
//! exactly one point in every elementary box of area `2^-m`. A random
//! digital shift (XOR with a uniform 32-bit word per dimension) plus uniform
//! low-order bits makes every point uniform on the unit square, so an
//! average over the net is unbiased, while the net stays stratified. Batches
//! with independent shifts are independent realisations, so batch statistics
//! stay honest (Owen 1997; L'Ecuyer & Lemieux 2002).

/// Direction numbers of Sobol' dimension 2: `v_0 = 2^31`, `v_k = v_{k-1} ^ (v_{k-1} >> 1)`.
const fn sobol2_directions() -> [u32; 32] {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut k = 1;
    while k < 32 {
        v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        k += 1;
    }
    v
}

const V2: [u32; 32] = sobol2_directions();

/// Point `i` of the first two Sobol' dimensions, as 32-bit words.
#[inline]
pub fn sobol_2d_bits(i: u32) -> [u32; 2] {
    let x = i.reverse_bits();
    let mut y = 0u32;
    let mut bits = i;
    let mut k = 0;
    while bits != 0 {
        if bits & 1 != 0 {
            y ^= V2[k];
        }
        bits >>= 1;
        k += 1;
    }
    [x, y]
}

/// A random digital shift for one net.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DigitalShift(pub [u32; 2]);

/// Point `i` of the shifted net, with `low` (uniforms in [0,1)) filling the
/// bits below 2^-32, so each coordinate is uniform on [0, 1).
#[inline]
pub fn shifted_sobol_2d(i: u32, shift: DigitalShift, low: [f64; 2]) -> [f64; 2] {
    let b = sobol_2d_bits(i);
    let s = 1.0 / 4_294_967_296.0;
    [
        (f64::from(b[0] ^ shift.0[0]) + low[0]) * s,
        (f64::from(b[1] ^ shift.0[1]) + low[1]) * s,
    ]
    .map(|u: f64| u.min(1.0 - f64::EPSILON / 2.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_points_match_sobol() {
        // First points of Sobol' dimensions 1 and 2.
        let want = [
            [0.0, 0.0],
            [0.5, 0.5],
            [0.25, 0.75],
            [0.75, 0.25],
            [0.125, 0.625],
        ];
        for (i, w) in want.iter().enumerate() {
            let b = sobol_2d_bits(i as u32);
            let u = [
                f64::from(b[0]) / 4294967296.0,
                f64::from(b[1]) / 4294967296.0,
            ];
            assert_eq!(u, *w, "point {i}");
        }
    }

    #[test]
    fn shifted_net_is_a_0m2_net() {
        // Every elementary box of area 2^-m holds exactly one of 2^m points.
        let m = 8u32;
        let n = 1u32 << m;
        let shift = DigitalShift([0x9e37_79b9, 0x7f4a_7c15]);
        let pts: Vec<[f64; 2]> = (0..n)
            .map(|i| shifted_sobol_2d(i, shift, [0.3, 0.7]))
            .collect();
        for a in 0..=m {
            let (nx, ny) = (1usize << a, 1usize << (m - a));
            let mut count = vec![0u32; nx * ny];
            for p in &pts {
                count[(p[0] * nx as f64) as usize * ny + (p[1] * ny as f64) as usize] += 1;
            }
            assert!(count.iter().all(|&c| c == 1), "boxes {nx}x{ny}");
        }
    }
}
