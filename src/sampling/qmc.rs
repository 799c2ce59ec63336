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

/// How the chains of a batch stratify their leading uniforms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Qmc {
    /// Independent uniforms from each chain's stream.
    Off,
    /// A digitally shifted Sobol' net over the emitted direction and the
    /// first reflection (this module).
    Shift,
    /// An Owen-scrambled Sobol' net over the light pick, emission position
    /// and direction and the first three reflections ([`super::owen`]).
    /// The default: at least as good as `Shift` in every case measured
    /// with batches of 256 chains or more (`validation/qmc/README.md`).
    #[default]
    Owen,
}

/// Direction numbers `v_k = m_k 2^(31-k)` of a Sobol' dimension with primitive
/// polynomial of degree `s`, inner coefficients `a` (bits, highest first) and
/// initial `m` (Joe & Kuo 2008 notation):
/// `m_k = 2 a_1 m_{k-1} ^ 4 a_2 m_{k-2} ^ ... ^ 2^s m_{k-s} ^ m_{k-s}`.
const fn directions(s: usize, a: u32, m_init: [u32; 3]) -> [u32; 32] {
    let mut m = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        if k < s {
            m[k] = m_init[k];
        } else {
            let mut x = m[k - s] ^ (m[k - s] << s);
            let mut i = 1;
            while i < s {
                if (a >> (s - 1 - i)) & 1 == 1 {
                    x ^= m[k - i] << i;
                }
                i += 1;
            }
            m[k] = x;
        }
        k += 1;
    }
    let mut v = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        v[k] = m[k] << (31 - k);
        k += 1;
    }
    v
}

/// Dimension 2 (`x + 1`), 3 (`x^2 + x + 1`, m = 1, 3) and 4 (`x^3 + x + 1`, m = 1, 3, 1).
const V2: [u32; 32] = directions(1, 0, [1, 0, 0]);
const V3: [u32; 32] = directions(2, 1, [1, 3, 0]);
const V4: [u32; 32] = directions(3, 1, [1, 3, 1]);

/// Gray-code-free Sobol' word: XOR of the direction numbers of the set bits of `i`.
#[inline]
fn sobol_word(i: u32, v: &[u32; 32]) -> u32 {
    let mut y = 0u32;
    let mut bits = i;
    let mut k = 0;
    while bits != 0 {
        if bits & 1 != 0 {
            y ^= v[k];
        }
        bits >>= 1;
        k += 1;
    }
    y
}

/// Point `i` of Sobol' dimensions 3 and 4, as 32-bit words.
#[inline]
pub fn sobol_34_bits(i: u32) -> [u32; 2] {
    [sobol_word(i, &V3), sobol_word(i, &V4)]
}

/// Point `i` of Sobol' dimensions 3 and 4, digitally shifted (as [`shifted_sobol_2d`]).
#[inline]
pub fn shifted_sobol_34(i: u32, shift: DigitalShift, low: [f64; 2]) -> [f64; 2] {
    words_to_unit(sobol_34_bits(i), shift, low)
}

#[inline]
fn words_to_unit(b: [u32; 2], shift: DigitalShift, low: [f64; 2]) -> [f64; 2] {
    let s = 1.0 / 4_294_967_296.0;
    [
        (f64::from(b[0] ^ shift.0[0]) + low[0]) * s,
        (f64::from(b[1] ^ shift.0[1]) + low[1]) * s,
    ]
    .map(|u: f64| u.min(1.0 - f64::EPSILON / 2.0))
}

/// Point `i` of the first two Sobol' dimensions, as 32-bit words.
#[inline]
pub fn sobol_2d_bits(i: u32) -> [u32; 2] {
    [i.reverse_bits(), sobol_word(i, &V2)]
}

/// A random digital shift for one net.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DigitalShift(pub [u32; 2]);

/// Point `i` of the shifted net, with `low` (uniforms in [0,1)) filling the
/// bits below 2^-32, so each coordinate is uniform on [0, 1).
#[inline]
pub fn shifted_sobol_2d(i: u32, shift: DigitalShift, low: [f64; 2]) -> [f64; 2] {
    words_to_unit(sobol_2d_bits(i), shift, low)
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
    fn dimension_two_matches_its_closed_form_and_all_dimensions_stratify() {
        // v_k = v_{k-1} ^ (v_{k-1} >> 1) for dimension 2.
        for k in 1..32 {
            assert_eq!(V2[k], V2[k - 1] ^ (V2[k - 1] >> 1));
        }
        // First points of dimensions 3 and 4 (m_1 = 1, m_2 = 3), and the
        // Bratley-Fox worked example for x^3 + x + 1: m_4 = 4 m_2 ^ 8 m_1 ^ m_1 = 5.
        let f = |w: u32| f64::from(w) / 4294967296.0;
        let d3: Vec<f64> = (0..4).map(|i| f(sobol_34_bits(i)[0])).collect();
        let d4: Vec<f64> = (0..4).map(|i| f(sobol_34_bits(i)[1])).collect();
        assert_eq!(d3, [0.0, 0.5, 0.75, 0.25]);
        assert_eq!(d4, [0.0, 0.5, 0.75, 0.25]);
        assert_eq!(V4[3] >> (31 - 3), 5);
        // Each one-dimensional projection of 2^m points is a (0,m,1)-net.
        let m = 10;
        for dim in 0..2 {
            let mut seen = vec![false; 1 << m];
            for i in 0..(1u32 << m) {
                let w = sobol_34_bits(i)[dim] >> (32 - m);
                assert!(!seen[w as usize]);
                seen[w as usize] = true;
            }
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
