//! The modelling ratio `E_z / E_h` (EN 12464-1:2021: the ratio of the
//! cylindrical to the horizontal illuminance at a point; 0.3 to 0.6 for a
//! good modelling of faces) at points listed twice in the points CSV, once
//! `planar` facing up and once `cylindrical` with a vertical axis.
//!
//! Both estimates come from the same chains, so their errors are
//! correlated. The ratio's standard error is the delta method's with the
//! covariance of the two totals taken over the batches:
//! `se(R)^2 = (var(E_z) - 2 R cov(E_z, E_h) + R^2 var(E_h)) / E_h^2`, the
//! (co)variances those of the means (the batch means' sample (co)variances
//! over `B`), the exact direct parts adding none.

use crate::estimator::{Receiver, Response, Solid};
use crate::tally::BatchMeans;
use std::collections::HashMap;

/// A pair of receivers at one position: `h` planar facing `+z`, `z`
/// cylindrical with a vertical axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pair {
    /// Index of the planar receiver.
    pub h: usize,
    /// Index of the cylindrical receiver.
    pub z: usize,
}

/// The pairs among the first `n` receivers: each vertical cylinder with a
/// planar point facing straight up at exactly the same position (the first
/// such point in the list).
pub fn pairs(receivers: &[Receiver], n: usize) -> Vec<Pair> {
    let vertical = |r: &Receiver| (r.n.z.abs() - 1.0).abs() < 1e-12;
    let key = |r: &Receiver| [r.p.x, r.p.y, r.p.z].map(|c| (c + 0.0).to_bits());
    let mut up: HashMap<[u64; 3], usize> = HashMap::new();
    for (j, r) in receivers.iter().enumerate().take(n) {
        if r.response == Response::Illuminance && vertical(r) && r.n.z > 0.0 {
            up.entry(key(r)).or_insert(j);
        }
    }
    receivers
        .iter()
        .enumerate()
        .take(n)
        .filter(|(_, r)| r.response == Response::Solid(Solid::Cylindrical) && vertical(r))
        .filter_map(|(z, r)| up.get(&key(r)).map(|&h| Pair { h, z }))
        .collect()
}

/// The ratio `E_z / E_h` of a pair and its standard error from the batch
/// means `bm` of the receivers (totals but for the exact direct parts
/// `direct` \[lx\]); `None` when `E_h` is not positive or fewer than 2
/// batches are kept.
pub fn ratio(bm: &BatchMeans, direct: &[f64], pair: Pair) -> Option<(f64, f64)> {
    let b = bm.batches();
    if b < 2 || pair.h >= bm.receivers() || pair.z >= bm.receivers() {
        return None;
    }
    let (mut mh, mut mz) = (0.0, 0.0);
    for k in 0..b {
        mh += bm.batch(k)[pair.h];
        mz += bm.batch(k)[pair.z];
    }
    let bf = b as f64;
    let (mh, mz) = (mh / bf, mz / bf);
    let (mut vhh, mut vzz, mut vhz) = (0.0, 0.0, 0.0);
    for k in 0..b {
        let (dh, dz) = (bm.batch(k)[pair.h] - mh, bm.batch(k)[pair.z] - mz);
        vhh += dh * dh;
        vzz += dz * dz;
        vhz += dh * dz;
    }
    // Variances of the means.
    let s = 1.0 / ((bf - 1.0) * bf);
    let (vhh, vzz, vhz) = (vhh * s, vzz * s, vhz * s);
    let (eh, ez) = (direct[pair.h] + mh, direct[pair.z] + mz);
    if !(eh > 0.0 && eh.is_finite() && ez.is_finite()) {
        return None;
    }
    let r = ez / eh;
    let var = ((vzz - 2.0 * r * vhz + r * r * vhh) / (eh * eh)).max(0.0);
    Some((r, var.sqrt()))
}

/// The output columns of the points CSV that hold the ratio and its
/// standard error, written where some points pair up: on each pair's
/// cylindrical row, empty on the others (`NaN` where the ratio is
/// undefined: `E_h` not positive).
pub const COLUMNS: [&str; 2] = ["modelling_ratio", "modelling_ratio_stderr"];

/// The [`COLUMNS`] cells of the first `n` rows: each pair's ratio and
/// standard error ([`ratio`]) on its cylindrical row `z`.
pub fn cells(bm: &BatchMeans, direct: &[f64], pairs: &[Pair], n: usize) -> Vec<[String; 2]> {
    let mut c = vec![[String::new(), String::new()]; n];
    for &p in pairs {
        let (r, se) = ratio(bm, direct, p).unwrap_or((f64::NAN, f64::NAN));
        c[p.z] = [r, se].map(crate::io::format_number);
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn pairs_need_the_same_position_and_vertical_normals() {
        let p = DVec3::new(1.0, 2.0, 1.2);
        let rec = [
            Receiver::illuminance(p, DVec3::Z),
            Receiver::solid(p, DVec3::Z, Solid::Cylindrical),
            Receiver::solid(p + DVec3::X, DVec3::Z, Solid::Cylindrical),
            Receiver::illuminance(p + DVec3::Y, -DVec3::Z),
            Receiver::solid(p + DVec3::Y, DVec3::Z, Solid::Cylindrical),
            Receiver::solid(p, DVec3::X, Solid::Cylindrical),
        ];
        assert_eq!(pairs(&rec, rec.len()), vec![Pair { h: 0, z: 1 }]);
        assert!(pairs(&rec, 1).is_empty());
    }

    #[test]
    fn ratio_error_is_the_delta_method_with_the_covariance() {
        // Batch means of two receivers, the second half of the first
        // plus independent noise.
        let (b, mut bm) = (4000, BatchMeans::new(2));
        let mut rng = crate::sampling::Philox4x32::new(1, 2);
        for _ in 0..b {
            let h = 100.0 + 10.0 * (rng.next_f64() - 0.5);
            let z = 0.5 * h + 2.0 * (rng.next_f64() - 0.5);
            bm.record(0, h);
            bm.record(1, z);
        }
        let (r, se) = ratio(&bm, &[20.0, 5.0], Pair { h: 0, z: 1 }).unwrap();
        // E_h = 120, E_z = 55: R = 0.4583. With the direct parts the ratio
        // moves; var(E_z) = 0.25 var(h) + var(noise), cov = 0.5 var(h).
        assert!((r - 55.0 / 120.0).abs() < 0.01, "{r}");
        let (vh, vn) = (100.0 / 12.0, 4.0 / 12.0);
        let want = ((0.25 * vh + vn - 2.0 * r * 0.5 * vh + r * r * vh) / b as f64).sqrt() / 120.0;
        assert!((se / want - 1.0).abs() < 0.1, "{se} vs {want}");
        // Ignoring the covariance would give a visibly different error.
        let indep = ((0.25 * vh + vn + r * r * vh) / b as f64).sqrt() / 120.0;
        assert!((indep / want - 1.0).abs() > 0.3);
        assert!(ratio(&bm, &[-100.0, 0.0], Pair { h: 0, z: 1 }).is_none());
    }
}
