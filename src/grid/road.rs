//! The EN 13201-3 field of calculation of a road.
//!
//! The field runs along the road between two successive luminaires of a
//! row (length `S` \[m\]) and across the carriageway. EN 13201-3 (2015,
//! clause 7.3) spaces the transverse rows of points `D = S / N` apart,
//! with `N = 10` for `S <= 30 m` and otherwise the smallest whole `N` with
//! `D <= 3 m`; the first row lies `D / 2` beyond the first luminaire, so
//! the rows are at the centres of `N` equal cells. Across each lane of width
//! `W_L` there are 3 points, `d = W_L / 3` apart and `d / 2` from the lane's
//! edges: the centres of 3 equal cells.
//!
//! For illuminance over a whole relevant area (rather than per lane) the
//! standard asks for the fewest points across, at least 3, with `d <= 1.5
//! m` over the whole width: 3 points per lane (the luminance rule, kept
//! here) keep `d <= 1.5 m` for lanes up to 4.5 m wide (the usual 3-3.75
//! m), with as many or more points; wider lanes are warned of.

/// Transverse rows along a field of length `s` \[m\] (the spacing of the
/// luminaires): `N = 10` up to 30 m, else the smallest `N` with `s / N <= 3 m`.
pub fn rows_along(s: f64) -> usize {
    if s <= 30.0 {
        10
    } else {
        super::spacing::cells_along(s, 3.0)
    }
}

/// Points across each lane.
pub const POINTS_PER_LANE: usize = 3;

/// Largest transverse spacing `d` \[m\] EN 13201-3 allows across an
/// illuminance field.
pub const MAX_ACROSS: f64 = 1.5;

#[cfg(test)]
mod tests {
    use super::*;

    /// `N = 10` up to 30 m; beyond, `D <= 3 m` with the fewest rows:
    /// 30.1 m -> 11 (2.74 m), 33 m -> 11 (3.0 m exactly), 33.1 m -> 12,
    /// 45 m -> 15 (EN 13201-3 examples: S = 30 m gives D = 3 m, S = 36 m
    /// gives N = 12, D = 3 m).
    #[test]
    fn rows_by_spacing() {
        assert_eq!(rows_along(10.0), 10);
        assert_eq!(rows_along(30.0), 10);
        assert_eq!(rows_along(30.1), 11);
        assert_eq!(rows_along(33.0), 11);
        assert_eq!(rows_along(33.1), 12);
        assert_eq!(rows_along(36.0), 12);
        assert_eq!(rows_along(45.0), 15);
        for k in 1..2000 {
            let s = 0.05 * k as f64;
            let n = rows_along(s);
            let d = s / n as f64;
            if s > 30.0 {
                assert!(d <= 3.0 + 1e-12 && s / (n - 1) as f64 > 3.0, "S = {s}");
            } else {
                assert_eq!(n, 10);
            }
        }
    }
}
