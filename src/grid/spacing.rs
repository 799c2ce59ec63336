//! The EN 12464-1 grid rule for calculation surfaces of workplaces.
//!
//! EN 12464-1 (2011, clause 4.4; the same rule in 2021) sizes the cells of
//! a calculation grid by the longest cell side allowed,
//!
//! `p = 0.2 x 5^log10(d)`  \[m\], at most 10 m,
//!
//! where `d` \[m\] is the longer side of the area, or the shorter one when the
//! longer is at least twice the shorter. The number of cells along `d` is
//! the smallest whole number `n >= d / p`; the cell side `d / n` found so is
//! then used to count the cells along the other side the same way (the next
//! whole number up), which keeps the cell aspect ratio within 0.5-2. The
//! points are the cell centres. Since `5^log10(d) = d^log10(5)`, `p` is
//! exact at the powers of ten: 0.2 m for 1 m, 1 m for 10 m, 5 m for 100 m.

/// Largest cell side allowed by EN 12464-1 for an area of relevant
/// dimension `d` \[m\]: `min(0.2 x 5^log10(d), 10)` \[m\].
pub fn max_cell_size(d: f64) -> f64 {
    (0.2 * 5f64.powf(d.log10())).min(10.0)
}

/// The relevant dimension `d` \[m\] of an `a` x `b` area: the longer side,
/// or the shorter when the longer is at least twice the shorter.
pub fn relevant_dimension(a: f64, b: f64) -> f64 {
    let (long, short) = if a >= b { (a, b) } else { (b, a) };
    if long >= 2.0 * short { short } else { long }
}

/// The smallest whole number of cells of side at most `p` along `len`
/// (at least 1). A quotient within 1e-12 of a whole number counts as that
/// number, so 10 m at 1 m is 10 cells despite rounding.
pub fn cells_along(len: f64, p: f64) -> usize {
    let q = len / p;
    let n = (q * (1.0 - 1e-12)).ceil();
    n.max(1.0) as usize
}

/// Cells along the two sides of an `a` x `b` area \[m\]: by the EN 12464-1
/// rule when `spacing` is `None`, else cells of side at most `spacing`
/// along each side.
pub fn cell_counts(a: f64, b: f64, spacing: Option<f64>) -> (usize, usize) {
    match spacing {
        Some(p) => (cells_along(a, p), cells_along(b, p)),
        None => {
            let d = relevant_dimension(a, b);
            let p = max_cell_size(d);
            let n = cells_along(d, p);
            let side = d / n as f64;
            // `d` is one of the sides; count the other with the cell side found.
            if d == a {
                (n, cells_along(b, side))
            } else {
                (cells_along(a, side), n)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule is exact at the powers of ten (`5^k` for `d = 10^k`).
    #[test]
    fn max_cell_size_at_powers_of_ten() {
        assert!((max_cell_size(1.0) - 0.2).abs() < 1e-15);
        assert!((max_cell_size(10.0) - 1.0).abs() < 1e-14);
        assert!((max_cell_size(100.0) - 5.0).abs() < 1e-13);
        // 1000 m would give 25 m: capped at 10 m.
        assert_eq!(max_cell_size(1000.0), 10.0);
    }

    /// Published examples (Fagerhult's EN 12464-1 knowledge hub, "Number of
    /// calculation points", table of maximum distances, given there to
    /// 0.1 m or rounder): 2 m -> 0.3 m, 5 m -> 0.6 m, 10 m -> 1.0 m,
    /// 50 m -> 3.0 m, 100 m -> 5.0 m (the formula gives 0.325, 0.616,
    /// 1.000, 3.080, 5.000 m).
    #[test]
    fn max_cell_size_matches_published_table() {
        assert!((max_cell_size(5.0) - 0.61601).abs() < 1e-5);
        assert!((max_cell_size(50.0) - 3.08006).abs() < 1e-5);
        for (d, table) in [
            (2.0, 0.3),
            (5.0, 0.6),
            (10.0, 1.0),
            (50.0, 3.0),
            (100.0, 5.0),
        ] {
            assert!((max_cell_size(d) - table).abs() < 0.1, "d = {d}");
        }
    }

    /// A 6 m x 4 m room: d = 6 m (aspect 1.5 < 2), p = 0.2 x 5^0.77815 =
    /// 0.6997 m, 9 cells of 0.667 m along 6 m, then 6 cells of 0.667 m
    /// along 4 m: 54 points.
    #[test]
    fn six_by_four_room() {
        let p = max_cell_size(6.0);
        assert!((p - 0.699736).abs() < 1e-6, "p = {p}");
        assert_eq!(cell_counts(6.0, 4.0, None), (9, 6));
        assert_eq!(cell_counts(4.0, 6.0, None), (6, 9));
    }

    /// A long corridor 20 m x 2 m (aspect 10): d is the shorter side, 2 m,
    /// p = 0.2 x 5^0.30103 = 0.3246 m: 7 cells of 0.2857 m across, then 70
    /// along 20 m (0.2857 m).
    #[test]
    fn long_area_uses_the_shorter_side() {
        assert_eq!(relevant_dimension(20.0, 2.0), 2.0);
        assert_eq!(relevant_dimension(3.9, 2.0), 3.9);
        assert!((max_cell_size(2.0) - 0.324669).abs() < 1e-6);
        assert_eq!(cell_counts(20.0, 2.0, None), (70, 7));
    }

    /// Every cell stays within the aspect range 0.5-2 and within p, over
    /// sides from 0.1 m to 300 m.
    #[test]
    fn cells_keep_their_aspect_and_size() {
        let sides: Vec<f64> = (0..60).map(|k| 0.1 * 1.15f64.powi(k)).collect();
        for &a in &sides {
            for &b in &sides {
                let (na, nb) = cell_counts(a, b, None);
                let (sa, sb) = (a / na as f64, b / nb as f64);
                let p = max_cell_size(relevant_dimension(a, b));
                let aspect = sa / sb;
                assert!((0.5..=2.0).contains(&aspect), "{a} x {b}: {na} x {nb}");
                assert!(
                    sa <= p * (1.0 + 1e-9) && sb <= p * (1.0 + 1e-9),
                    "{a} x {b}"
                );
            }
        }
    }

    /// A given spacing: cells of at most that side, whole quotients exact.
    #[test]
    fn given_spacing() {
        assert_eq!(cell_counts(5.0, 3.0, Some(0.5)), (10, 6));
        assert_eq!(cell_counts(5.1, 3.0, Some(0.5)), (11, 6));
        assert_eq!(cell_counts(0.1, 0.1, Some(0.5)), (1, 1));
    }
}
