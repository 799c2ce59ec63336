//! Counter-based random numbers: Philox4x32-10 (Salmon et al., SC 2011).
//!
//! A chain's stream is a pure function of (seed, chain index): the key is
//! the seed and the counter holds the chain index and a draw counter, so
//! results never depend on which thread ran the chain.

/// Philox4x32-10 stream for one (seed, stream) pair.
#[derive(Clone, Debug)]
pub struct Philox4x32 {
    // TODO(helper): fields
}

impl Philox4x32 {
    /// Stream `stream` of the generator keyed by `seed`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let _ = (seed, stream);
        todo!()
    }
    /// Next uniform in [0, 1) with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        todo!()
    }
    /// Two uniforms in [0, 1).
    pub fn next_2d(&mut self) -> [f64; 2] {
        [self.next_f64(), self.next_f64()]
    }
}
