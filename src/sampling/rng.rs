//! Counter-based random numbers: Philox4x32-10 (Salmon et al., SC 2011).
//!
//! A chain's stream is a pure function of (seed, chain index): the key is
//! the seed and the counter holds the chain index and a draw counter, so
//! results never depend on which thread ran the chain.
//!
//! Reference: J. K. Salmon, M. A. Moraes, R. O. Dror, D. E. Shaw,
//! "Parallel random numbers: as easy as 1, 2, 3", Proc. SC'11 (2011),
//! doi:10.1145/2063384.2063405. Constants and round structure as in the
//! Random123 library (D. E. Shaw Research).

use core::convert::Infallible;

/// Philox4x32 multiplier applied to counter word 0 (Salmon et al. 2011, Table 2).
const PHILOX_M0: u32 = 0xD251_1F53;
/// Philox4x32 multiplier applied to counter word 2.
const PHILOX_M1: u32 = 0xCD9E_8D57;
/// Weyl key increment for key word 0 (golden ratio, 32 bits).
const PHILOX_W0: u32 = 0x9E37_79B9;
/// Weyl key increment for key word 1 (sqrt(3) - 1, 32 bits).
const PHILOX_W1: u32 = 0xBB67_AE85;

/// Words buffered per refill: one 4-word block.
const BUF_WORDS: usize = 4;

/// 2^-53: turns the top 53 bits of a `u64` into a float in [0, 1).
const INV_2_POW_53: f64 = 1.0 / (1u64 << 53) as f64;

/// One Philox4x32 round: two 32x32 -> 64-bit multiplies, then the
/// (hi ^ ctr ^ key, lo) Feistel-like permutation of Salmon et al. (2011).
#[inline(always)]
fn round(c: [u32; 4], k: [u32; 2]) -> [u32; 4] {
    let p0 = u64::from(PHILOX_M0) * u64::from(c[0]);
    let p1 = u64::from(PHILOX_M1) * u64::from(c[2]);
    let (hi0, lo0) = ((p0 >> 32) as u32, p0 as u32);
    let (hi1, lo1) = ((p1 >> 32) as u32, p1 as u32);
    [hi1 ^ c[1] ^ k[0], lo1, hi0 ^ c[3] ^ k[1], lo0]
}

/// The Philox4x32-10 bijection: 10 Philox rounds applied to the
/// 128-bit counter `ctr` under the 64-bit key `key`, the key being bumped
/// by the Weyl constants (0x9E3779B9, 0xBB67AE85) between rounds.
///
/// This is the keyed counter-based PRF `b_k(c)` of Salmon et al. (SC'11,
/// Sec. 3.3 / 4); words are in Random123 order (`ctr[0]` is the low word,
/// `key[0]` is `k0`), so the known-answer vectors of Random123's
/// `kat_vectors` apply verbatim.
#[inline(always)]
pub fn philox4x32_10(ctr: [u32; 4], key: [u32; 2]) -> [u32; 4] {
    let mut c = ctr;
    let mut k = key;
    c = round(c, k);
    for _ in 1..10 {
        k = [k[0].wrapping_add(PHILOX_W0), k[1].wrapping_add(PHILOX_W1)];
        c = round(c, k);
    }
    c
}

/// Philox4x32-10 stream for one (seed, stream) pair.
///
/// * key `k = (seed as u32, (seed >> 32) as u32)`;
/// * block `i` of the stream is `philox4x32_10([i_lo, i_hi, stream_lo, stream_hi], k)`,
///   i = 0, 1, 2, ... (the draw counter);
/// * the four 32-bit words of a block are handed out in order `0, 1, 2, 3`;
///   a `u64` is two consecutive words, little-endian (first word = low half),
///   which is `rand_core`'s convention (`utils::next_u64_via_u32`).
///
/// Hence every stream is a pure function of (seed, stream) and has period
/// 2^64 blocks = 2^66 32-bit words; distinct `stream` values give disjoint
/// counter sets, i.e. non-overlapping sequences under the same key.
///
/// Implements [`rand_core::TryRng`] with `Error = Infallible`, hence
/// [`rand_core::Rng`] through rand_core's blanket impl. Not a
/// cryptographic generator (no `TryCryptoRng`).
#[derive(Clone, Debug)]
pub struct Philox4x32 {
    /// Key words (k0, k1) = seed's (low, high) halves.
    key: [u32; 2],
    /// Counter words 2, 3 = stream's (low, high) halves.
    stream: [u32; 2],
    /// Index of the next block to generate (counter words 0, 1).
    block: u64,
    /// Output words of the current block.
    buf: [u32; BUF_WORDS],
    /// Next unused word in `buf`; `BUF_WORDS` means the buffer is exhausted.
    idx: usize,
}

impl Philox4x32 {
    /// Stream `stream` of the generator keyed by `seed`.
    ///
    /// Construction is O(1) and draws nothing; the first block is
    /// computed on the first draw.
    #[inline]
    pub fn new(seed: u64, stream: u64) -> Self {
        Self {
            key: [seed as u32, (seed >> 32) as u32],
            stream: [stream as u32, (stream >> 32) as u32],
            block: 0,
            buf: [0; BUF_WORDS],
            idx: BUF_WORDS,
        }
    }

    /// Compute block `self.block` into the buffer and advance the draw counter.
    #[inline(always)]
    fn refill(&mut self) {
        let ctr = [
            self.block as u32,
            (self.block >> 32) as u32,
            self.stream[0],
            self.stream[1],
        ];
        self.buf = philox4x32_10(ctr, self.key);
        self.block = self.block.wrapping_add(1);
        self.idx = 0;
    }

    /// Next uniformly distributed 32-bit word.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        if self.idx >= BUF_WORDS {
            self.refill();
        }
        let x = self.buf[self.idx];
        self.idx += 1;
        x
    }

    /// Next uniformly distributed 64-bit word: `lo | hi << 32` where `lo`,
    /// `hi` are the next two 32-bit words (in that order).
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        if self.idx + 2 <= BUF_WORDS {
            // Fast path: both words in the buffer.
            let lo = u64::from(self.buf[self.idx]);
            let hi = u64::from(self.buf[self.idx + 1]);
            self.idx += 2;
            lo | (hi << 32)
        } else {
            let lo = u64::from(self.next_u32());
            let hi = u64::from(self.next_u32());
            lo | (hi << 32)
        }
    }

    /// Next uniform in [0, 1) with 53 random bits: `(x >> 11) * 2^-53` for
    /// one 64-bit draw `x`. Takes values `j 2^-53`, j = 0 .. 2^53 - 1, each
    /// with probability 2^-53, so the result is never 1.0.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * INV_2_POW_53
    }

    /// Two uniforms in [0, 1) (two successive [`next_f64`](Self::next_f64) draws).
    #[inline]
    pub fn next_2d(&mut self) -> [f64; 2] {
        [self.next_f64(), self.next_f64()]
    }
}

impl rand_core::TryRng for Philox4x32 {
    type Error = Infallible;

    #[inline]
    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        Ok(Philox4x32::next_u32(self))
    }

    #[inline]
    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        Ok(Philox4x32::next_u64(self))
    }

    #[inline]
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        rand_core::utils::fill_bytes_via_next_word(dst, || {
            Ok::<u32, Infallible>(Philox4x32::next_u32(self))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Known-answer vectors for Philox4x32 with 10 rounds, from the
    // `kat_vectors` file of the Random123 distribution (D. E. Shaw Research),
    // as pasted into DEShawResearch/Random123-Boost,
    // libs/random/test/test_philox.cpp (commit 916db91ae4c6fd8324ef054a518851321ab41f91),
    // test case `test_kat_philox4x32`. Format: counter[4] key[2] -> output[4].
    //   philox4x32 10 00000000 00000000 00000000 00000000 00000000 00000000   6627e8d5 e169c58d bc57ac4c 9b00dbd8
    //   philox4x32 10 ffffffff ffffffff ffffffff ffffffff ffffffff ffffffff   408f276d 41c83b0e a20bc7c6 6d5451fd
    //   philox4x32 10 243f6a88 85a308d3 13198a2e 03707344 a4093822 299f31d0   d16cfe09 94fdcceb 5001e420 24126ea1
    const KAT: [([u32; 4], [u32; 2], [u32; 4]); 3] = [
        (
            [0, 0, 0, 0],
            [0, 0],
            [0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8],
        ),
        (
            [u32::MAX; 4],
            [u32::MAX; 2],
            [0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd],
        ),
        (
            [0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344],
            [0xa4093822, 0x299f31d0],
            [0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1],
        ),
    ];

    #[test]
    fn known_answers_block_function() {
        for (ctr, key, want) in KAT {
            assert_eq!(
                philox4x32_10(ctr, key),
                want,
                "ctr {ctr:08x?} key {key:08x?}"
            );
        }
    }

    #[test]
    fn known_answers_through_stream_layout() {
        // All-zero KAT = block 0 of (seed 0, stream 0).
        let mut g = Philox4x32::new(0, 0);
        let got: Vec<u32> = (0..4).map(|_| g.next_u32()).collect();
        assert_eq!(got, KAT[0].2);

        // Pi-digits KAT: seed = k1:k0, stream = c3:c2, draw counter = c1:c0.
        let (ctr, key, want) = KAT[2];
        let seed = u64::from(key[0]) | (u64::from(key[1]) << 32);
        let stream = u64::from(ctr[2]) | (u64::from(ctr[3]) << 32);
        let block = u64::from(ctr[0]) | (u64::from(ctr[1]) << 32);
        let mut g = Philox4x32::new(seed, stream);
        g.block = block; // jump straight to that draw counter
        let got: Vec<u32> = (0..4).map(|_| g.next_u32()).collect();
        assert_eq!(got, want);

        // All-ones KAT: last block of the last stream of seed u64::MAX; the
        // draw counter then wraps to 0.
        let mut g = Philox4x32::new(u64::MAX, u64::MAX);
        g.block = u64::MAX;
        let got: Vec<u32> = (0..4).map(|_| g.next_u32()).collect();
        assert_eq!(got, KAT[1].2);
        // The draw counter wraps to 0.
        assert_eq!(g.block, 0);
    }

    #[test]
    fn stream_is_the_sequence_of_single_blocks() {
        // Word 4 i + j of stream (seed, s) is word j of
        // philox4x32_10([i_lo, i_hi, s_lo, s_hi], (seed_lo, seed_hi)).
        let (seed, s) = (0x0123_4567_89ab_cdef_u64, 0xfedc_ba98_7654_3210_u64);
        let mut g = Philox4x32::new(seed, s);
        let key = [seed as u32, (seed >> 32) as u32];
        for i in 0..11u64 {
            let want = philox4x32_10(
                [i as u32, (i >> 32) as u32, s as u32, (s >> 32) as u32],
                key,
            );
            for w in want {
                assert_eq!(g.next_u32(), w, "block {i}");
            }
        }
        // Same across the 32-bit carry of the draw counter.
        let mut g = Philox4x32::new(seed, s);
        g.block = u64::from(u32::MAX);
        for i in [u64::from(u32::MAX), 1 << 32] {
            let want = philox4x32_10(
                [i as u32, (i >> 32) as u32, s as u32, (s >> 32) as u32],
                key,
            );
            for w in want {
                assert_eq!(g.next_u32(), w, "block {i}");
            }
        }
    }

    #[test]
    fn u64_is_two_u32_little_endian_across_blocks() {
        let mut a = Philox4x32::new(7, 3);
        let mut b = Philox4x32::new(7, 3);
        // Misalign by one word so next_u64 straddles block boundaries.
        assert_eq!(a.next_u32(), b.next_u32());
        for _ in 0..100 {
            let lo = u64::from(b.next_u32());
            let hi = u64::from(b.next_u32());
            assert_eq!(a.next_u64(), lo | (hi << 32));
        }
    }

    #[test]
    fn rand_core_traits_agree_with_inherent_methods() {
        use rand_core::Rng;
        fn take<R: Rng>(r: &mut R) -> (u32, u64) {
            (r.next_u32(), r.next_u64())
        }
        let mut a = Philox4x32::new(11, 5);
        let mut b = a.clone();
        let (x, y) = take(&mut a);
        assert_eq!(x, b.next_u32());
        assert_eq!(y, b.next_u64());

        let mut bytes = [0u8; 10];
        let mut c = Philox4x32::new(11, 5);
        Rng::fill_bytes(&mut c, &mut bytes);
        let mut d = Philox4x32::new(11, 5);
        let w: Vec<u8> = (0..3).flat_map(|_| d.next_u32().to_le_bytes()).collect();
        assert_eq!(bytes[..], w[..10]);
    }

    #[test]
    fn same_seed_and_stream_reproduce() {
        let mut a = Philox4x32::new(0x0123_4567_89ab_cdef, 42);
        let mut b = Philox4x32::new(0x0123_4567_89ab_cdef, 42);
        for _ in 0..1000 {
            assert_eq!(a.next_f64().to_bits(), b.next_f64().to_bits());
        }
    }

    #[test]
    fn different_streams_and_seeds_differ() {
        let draw = |seed, stream| {
            let mut g = Philox4x32::new(seed, stream);
            (0..16).map(|_| g.next_u64()).collect::<Vec<_>>()
        };
        let base = draw(1, 0);
        // Neighbouring streams, a stream differing only in its high word,
        // and neighbouring seeds (each key half) all give different output.
        for (seed, stream) in [
            (1, 1),
            (1, 2),
            (1, 1 << 32),
            (0, 0),
            (2, 0),
            (1 << 32 | 1, 0),
        ] {
            let other = draw(seed, stream);
            assert_ne!(base, other, "seed {seed} stream {stream}");
            // Not merely shifted: no common 64-bit word at all.
            assert!(base.iter().all(|x| !other.contains(x)));
        }
    }

    #[test]
    fn next_f64_moments_and_range() {
        let mut g = Philox4x32::new(2024, 0);
        let n = 1_000_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let u = g.next_f64();
            assert!((0.0..1.0).contains(&u));
            s1 += u;
            s2 += u * u;
        }
        let mean = s1 / n as f64;
        let var = s2 / n as f64 - mean * mean;
        // 5-sigma bands. Std. error of the mean: sqrt(1/(12 n)); of the
        // sample variance: sqrt(Var[(u - 1/2)^2] / n) = sqrt(1/(180 n)).
        assert!(
            (mean - 0.5).abs() < 5.0 * (1.0 / 12.0 / n as f64).sqrt(),
            "mean {mean}"
        );
        assert!(
            (var - 1.0 / 12.0).abs() < 5.0 * (1.0 / 180.0 / n as f64).sqrt(),
            "var {var}"
        );
    }

    #[test]
    fn next_f64_extremes() {
        // The largest 53-bit value maps strictly below 1.
        assert!(((u64::MAX >> 11) as f64 * INV_2_POW_53) < 1.0);
        assert_eq!(
            (u64::MAX >> 11) as f64 * INV_2_POW_53,
            1.0 - f64::EPSILON / 2.0
        );
        assert_eq!(0.0 * INV_2_POW_53, 0.0);
    }
}
