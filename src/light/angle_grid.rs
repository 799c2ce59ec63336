//! An ascending grid of angles located from a direction's cosine and sine,
//! without inverse trigonometry: the cell and the fraction of the way
//! through it that bilinear interpolation of a photometric table needs.
//!
//! `acos` and `atan2` cost about as much as the whole direct term of a point
//! light, so the goniometric direct term finds its angle this way:
//!
//! - A *raw key* rises strictly with the angle and costs no inverse
//!   trigonometry, no division and no branch. A polar angle `gamma` in `[0,
//!   pi]` (sine `s >= 0`) has `k = 1 - c + s` up to a right angle and `k =
//!   3 - c - s` beyond, that is `2 - c - sign(c) (1 - s)`, in `[0, 4]`: its
//!   slope `|c| + s` lies in `[1, sqrt 2]`, so `|dgamma/dk| <= 1`. An
//!   azimuth in `[0, 2 pi)` (unit `(c, s)`, `s` of either sign) continues
//!   the pattern round the circle: `1 - c + s`, `3 - c - s`, `5 + c - s`,
//!   `7 + c + s` in the four quadrants, in `[0, 8]`, continuous at every
//!   quadrant edge (`4` at a half turn), the same slope bound. (The *key*
//!   of the tests is `sqrt(1/2)` times the raw key. Earlier keys: a
//!   pseudo-angle `s / (|c| + |s|)` per quadrant cost a division on the
//!   critical path; a three-piece key in `s`, `c` and `s` cost selects
//!   that LLVM turned into a branch, mispredicted on half the receivers.)
//! - Buckets of equal width in the raw key each keep a reference angle
//!   `g`, the angle of their lower edge, as `cos g`, `sin g` and, for the
//!   cell holding `g` and the next, the cell's lower node less `g` and its
//!   inverse width (the next cell's node is also its threshold). Then
//!   `theta = g + d` with `d = asin(s cos g - c sin g)`, its fraction
//!   through the cell is `(d - base) inv`, and the buckets are narrow enough
//!   ([`BUCKET_MAX_ANGLE`]) that the asin series to `x^5` is exact to
//!   rounding: the first term left out, `5 x^7 / 112`, is below 4e-18 for
//!   `|x| <= 0.005`. (The direct term is bound by its floating-point
//!   operations: buckets of 0.02 with the series to `x^7` measured 1 ns
//!   slower, and 0.06 with `x^11` slower still; the tables, 56 bytes a
//!   bucket and 200 buckets per radian of key, fit the L2 cache.) The
//!   bucket is the nearest to the key (one addition of [`ROUND_MAGIC`]
//!   rounds it).
//! - Buckets are also no wider than the narrowest cell, so one compare finds
//!   the cell (past [`MAX_BUCKETS`], a short scan).
//! - The grid is padded to the kind's whole range with *virtual* cells
//!   outside the measured angles, and the buckets cover every key: no range
//!   check and no `Option` on the direct term's path. Each cell carries an
//!   offset chosen by the caller, which points virtual cells at zero values.
//!
//! The angle agrees with `atan2(s, c)` to rounding, so the cell and fraction
//! are those of the inverse-trigonometric rule (a test compares them).

#[cfg(test)]
use std::f64::consts::FRAC_1_SQRT_2;
use std::f64::consts::PI;

/// Widest angle \[rad\] a bucket may span (the asin series' range).
pub const BUCKET_MAX_ANGLE: f64 = 0.005;

/// `1.5 * 2^52`: for `|x| < 2^51`, the sum `x + ROUND_MAGIC` holds `x`
/// rounded to the nearest integer in the low bits of its mantissa (two's
/// complement).
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

/// Most buckets of a grid's table.
const MAX_BUCKETS: usize = 1 << 14;

/// Which angle a grid holds, and so its key (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AngleKind {
    /// A polar angle in `[0, pi]` (the sine is never negative).
    Polar,
    /// An azimuth in `[0, 2 pi]`.
    Azimuth,
}

impl AngleKind {
    /// The key of the angle with unit `(cos, sin) = (c, s)`: `h` times
    /// the raw key ([`Self::raw`]).
    #[inline(always)]
    #[cfg(test)]
    fn key(self, c: f64, s: f64) -> f64 {
        FRAC_1_SQRT_2 * self.raw(c, s)
    }

    /// The raw key of the angle with unit `(cos, sin) = (c, s)` (module
    /// docs).
    #[inline(always)]
    fn raw(self, c: f64, s: f64) -> f64 {
        match self {
            AngleKind::Polar => polar_raw(c, s),
            AngleKind::Azimuth => azimuth_raw(c, s),
        }
    }

    /// The angle \[rad\] of a key.
    #[cfg(test)]
    fn angle(self, k: f64) -> f64 {
        self.angle_of_raw(k * std::f64::consts::SQRT_2)
    }

    /// The angle \[rad\] of a raw key: `pi/4 + asin((k - 1) / sqrt 2)` up
    /// to a right angle, `3 pi/4 - asin((3 - k) / sqrt 2)` beyond
    /// (polar); an azimuth past the half turn mirrors it.
    fn angle_of_raw(self, k: f64) -> f64 {
        use std::f64::consts::{FRAC_PI_4, SQRT_2};
        match self {
            AngleKind::Polar => {
                if k <= 2.0 {
                    FRAC_PI_4 + ((k - 1.0) / SQRT_2).clamp(-1.0, 1.0).asin()
                } else {
                    3.0 * FRAC_PI_4 - ((3.0 - k) / SQRT_2).clamp(-1.0, 1.0).asin()
                }
            }
            AngleKind::Azimuth => {
                if k <= 4.0 {
                    AngleKind::Polar.angle_of_raw(k)
                } else {
                    2.0 * PI - AngleKind::Polar.angle_of_raw(8.0 - k)
                }
            }
        }
    }

    /// The key of an angle \[rad\], with right angles exact for an azimuth.
    #[cfg(test)]
    fn key_of(self, a: f64) -> f64 {
        FRAC_1_SQRT_2 * self.raw_of(a)
    }

    /// The raw key of an angle \[rad\], with right angles exact for an
    /// azimuth (`sin pi` is not quite 0, nor `cos pi/2`).
    fn raw_of(self, a: f64) -> f64 {
        match self {
            AngleKind::Polar => {
                let (s, c) = a.sin_cos();
                polar_raw(c, s.max(0.0))
            }
            AngleKind::Azimuth => {
                if a <= PI {
                    AngleKind::Polar.raw_of(a)
                } else if a >= 2.0 * PI {
                    8.0
                } else {
                    8.0 - AngleKind::Polar.raw_of(2.0 * PI - a)
                }
            }
        }
    }

    /// The range of angles \[rad\] the kind covers.
    fn range(self) -> f64 {
        match self {
            AngleKind::Polar => PI,
            AngleKind::Azimuth => 2.0 * PI,
        }
    }
}

/// The azimuth key of unit `(c, s)` (module docs), in `[0, 8h]`.
#[inline(always)]
#[cfg(test)]
fn azimuth_key(c: f64, s: f64) -> f64 {
    AngleKind::Azimuth.key(c, s)
}

/// The raw polar key `2 - c - sign(c) (1 - s)` of unit `(c, s)`, `s >= 0`
/// (module docs), in `[0, 4]`: `1 - c + s` up to a right angle, `3 - c -
/// s` beyond. `copysign` multiplies by the sign (`1 - s >= 0`), without a
/// branch: receivers lie on all sides of a luminaire, so a branch on `c`
/// would be mispredicted half the time (and LLVM turns `if`-selects into
/// branches at will). Rounding may leave a key an ulp outside its piece's
/// formula: it moves a direction at most into the neighbouring bucket,
/// which the lookup tolerates.
#[inline(always)]
fn polar_raw(c: f64, s: f64) -> f64 {
    (2.0 - c) - (1.0 - s).copysign(c)
}

/// The raw azimuth key of unit `(c, s)` (module docs), in `[0, 8]`, per
/// quadrant `1 - c + s`, `3 - c - s`, `5 + c - s`, `7 + c + s`: with the
/// signs `sc`, `ss` of `c` and `s`, `4 - ss (2 + sc + c) + sc s`, branch
/// free (`2 + sc + c >= 0`: `copysign` multiplies by `ss`). A negative-zero
/// `s` counts as the upper half (`atan2(-0, 1)` is `-0`, azimuth 0: `-0 +
/// 0` is `+0`).
#[inline(always)]
fn azimuth_raw(c: f64, s: f64) -> f64 {
    let sc = 1.0f64.copysign(c);
    (4.0 - ((c + sc) + 2.0).copysign(s + 0.0)) + s * sc
}

/// `asin x` for `|x| <= sin(BUCKET_MAX_ANGLE)` by its Maclaurin series.
#[inline(always)]
fn asin_small(x: f64) -> f64 {
    // Coefficients (2n)! / (4^n (n!)^2 (2n + 1)), n = 1, 2; plain products
    // (`mul_add` is a library call without FMA).
    let x2 = x * x;
    let p = 1.0 / 6.0 + x2 * (3.0 / 40.0);
    x + x * (x2 * p)
}

/// What the lookup needs of a bucket with reference angle `g`: `(cos g,
/// sin g)` and, for the cell holding `g` and the next, the fraction of the
/// angle `g + d` as `(d - base) inv` (56 bytes, one load, no dependent
/// one).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bucket {
    /// `cos g`, `sin g` of the reference angle `g` \[rad\].
    cos: f64,
    sin: f64,
    /// `[base, inv]` of the cell holding `g` and of the next: `base` the
    /// cell's lower node less `g` \[rad\], `inv` its inverse width [1/rad].
    /// The next cell's `base` is also its threshold less `g` (+inf past
    /// the last cell): `g + d` lies in it for `d` at or above it.
    frac: [[f64; 2]; 2],
    /// The two cells' offsets.
    off: [u32; 2],
}

/// A cell of the padded grid: its lower node, inverse width and the
/// caller's offset of its values.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cell {
    /// Lower node \[rad\].
    a: f64,
    /// `1 / width` [1/rad].
    inv: f64,
    /// The caller's offset ([`AngleGrid::with_offsets`]).
    off: usize,
}

/// An ascending grid of angles `a_0 < ... < a_n` \[rad\], padded to the
/// kind's whole range: a *virtual* cell `[0, a_0)` where `a_0 > 0` and
/// `(a_n, range]` where `a_n` is short of the range. The buckets cover
/// every key, so no range check comes before the lookup: the caller gives
/// virtual cells an offset of zero values (outside the measured angles).
#[derive(Clone, Debug, PartialEq)]
pub struct AngleGrid {
    kind: AngleKind,
    /// The padded cells, ascending.
    cells: Vec<Cell>,
    /// Thresholds of the padded cells: an angle `theta` lies in cell `j`
    /// for the largest `j` with `thr[j] <= theta`. `thr[0] = -inf`, a
    /// last entry `+inf`; a real node's angle, except the last real node
    /// before a virtual cell, whose threshold is the next float up (the
    /// node itself belongs to the measured range, as in `v > v_n` of the
    /// reference rule).
    thr: Vec<f64>,
    /// Virtual cells before `a_0` (0 or 1).
    lead: usize,
    /// Real cells (`n`).
    real: usize,
    /// Buckets of equal width over the kind's whole key range, plus one
    /// (a key at the very top of the range rounds to it).
    bucket: Vec<Bucket>,
    /// The buckets' reference angles `g` \[rad\] and the (padded) cells
    /// holding them (for the scan and [`Self::locate`]).
    refs: Vec<(f64, u32)>,
    /// Buckets per unit of the raw key.
    per_unit: f64,
    /// Every bucket holds at most one threshold: no scan.
    one_node: bool,
}

impl AngleGrid {
    /// The grid of ascending angles `a` \[rad\] (at least two, within
    /// `[0, pi]` for a polar angle and `[0, 2 pi]` for an azimuth); `None`
    /// otherwise. Offsets of real cells are their index, and of virtual
    /// cells the number of real cells plus one.
    pub fn new(kind: AngleKind, a: &[f64]) -> Option<Self> {
        Self::with_offsets(kind, a, 1, a.len())
    }

    /// [`Self::new`] with the offset [`Self::locate_cell`] returns: `k *
    /// scale` for the real cell `k`, `virtual_off` for a virtual cell.
    pub fn with_offsets(
        kind: AngleKind,
        a: &[f64],
        scale: usize,
        virtual_off: usize,
    ) -> Option<Self> {
        let n = a.len();
        if n < 2 || a[0] < 0.0 || a[n - 1] > kind.range() || a.windows(2).any(|w| w[1] <= w[0]) {
            return None;
        }
        let keys: Vec<f64> = a.iter().map(|&x| kind.raw_of(x)).collect();
        if keys.windows(2).any(|w| w[1] <= w[0]) {
            return None;
        }
        // Padded nodes and thresholds.
        let lead = usize::from(a[0] > 0.0);
        let trail = a[n - 1] < kind.range();
        let mut nodes = Vec::with_capacity(n + 2);
        let mut cells = Vec::with_capacity(n + 1);
        let mut thr = vec![f64::NEG_INFINITY];
        if lead == 1 {
            nodes.push(0.0);
            cells.push(virtual_off);
            thr.push(a[0]);
        }
        nodes.extend_from_slice(a);
        cells.extend((0..n - 1).map(|k| k * scale));
        thr.extend_from_slice(&a[1..n - 1]);
        if trail {
            nodes.push(kind.range());
            cells.push(virtual_off);
            thr.push(a[n - 1].next_up());
        }
        thr.push(f64::INFINITY);
        let cells: Vec<Cell> = cells
            .iter()
            .enumerate()
            .map(|(j, &off)| Cell {
                a: nodes[j],
                inv: 1.0 / (nodes[j + 1] - nodes[j]),
                off,
            })
            .collect();
        let span = kind.raw_of(kind.range());
        let narrowest = nodes
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        // A bucket spans no more angle than raw key (|dangle/draw| <= 1).
        let width = BUCKET_MAX_ANGLE.min(narrowest);
        let buckets = ((span / width).ceil() as usize + 1).clamp(16, MAX_BUCKETS);
        let per_unit = buckets as f64 / span;
        // Bucket b spans the raw keys within half a bucket of b / per_unit
        // (the lookup rounds to the nearest).
        let edge = |b: usize| {
            kind.angle_of_raw((b as f64 - 0.5) / per_unit)
                .clamp(0.0, kind.range())
        };
        let mut bucket = Vec::with_capacity(buckets + 1);
        let mut refs = Vec::with_capacity(buckets + 1);
        let mut k = 0;
        for b in 0..=buckets {
            // The reference angle: the bucket's lower edge.
            let g = edge(b);
            while thr[k + 1] <= g {
                k += 1;
            }
            let (sin, cos) = g.sin_cos();
            let k1 = (k + 1).min(cells.len() - 1);
            bucket.push(Bucket {
                cos,
                sin,
                frac: [
                    [cells[k].a - g, cells[k].inv],
                    [thr[k + 1] - g, cells[k1].inv],
                ],
                off: [cells[k].off as u32, cells[k1].off as u32],
            });
            refs.push((g, k as u32));
        }
        let one_node = (0..=buckets).all(|b| {
            let (lo, hi) = (edge(b), edge(b + 1));
            thr.iter().filter(|&&x| x > lo && x <= hi).count() <= 1
        });
        Some(Self {
            kind,
            cells,
            thr,
            lead,
            real: n - 1,
            bucket,
            refs,
            per_unit,
            one_node,
        })
    }

    /// Cell `k` and fraction `t` in `[0, 1]` of the angle whose unit
    /// `(cos, sin)` is `(c, s)`; `None` outside `[a_0, a_n]`.
    pub fn locate(&self, c: f64, s: f64) -> Option<(usize, f64)> {
        let (j, _, t) = self.padded(self.kind.raw(c, s), c, s);
        let k = j.checked_sub(self.lead)?;
        (k < self.real).then_some((k, t.clamp(0.0, 1.0)))
    }

    /// The offset ([`Self::with_offsets`]) of the cell holding the angle
    /// whose unit `(cos, sin)` is `(c, s)`, and the fraction `t` of the way
    /// through it: in `[0, 1]` but for rounding at a node, which may leave
    /// it an ulp outside (not clamped: an interpolant between non-negative
    /// values can then come out a rounding error below zero, so the caller
    /// clamps its result at zero, one operation where two clamps cost
    /// four). `polar` is the caller's promise of the kind (debug builds
    /// check it): the key needs no dispatch.
    #[inline(always)]
    pub fn locate_cell(&self, polar: bool, c: f64, s: f64) -> (usize, f64) {
        debug_assert_eq!(polar, self.kind == AngleKind::Polar);
        let key = if polar {
            polar_raw(c, s)
        } else {
            azimuth_raw(c, s)
        };
        let (_, off, t) = self.padded(key, c, s);
        (off, t)
    }

    /// Padded cell, its offset and the fraction of the angle with raw
    /// key `key` and unit `(c, s)`.
    #[inline(always)]
    fn padded(&self, key: f64, c: f64, s: f64) -> (usize, usize, f64) {
        // The nearest bucket centre by one addition: the low bits of `pos
        // + ROUND_MAGIC` hold `pos` rounded (a saturating `as` conversion
        // costs two more floating-point operations). A key within the
        // range gives at most the extra last bucket; the bound only guards
        // against a NaN.
        let pos = key * self.per_unit + ROUND_MAGIC;
        let b = ((pos.to_bits() as u32) as usize).min(self.bucket.len() - 1);
        let r = &self.bucket[b];
        let d = asin_small(s * r.cos - c * r.sin);
        // theta = g + d is at least g (to rounding), and one threshold at
        // most lies between them (branch-free); a scan where a bucket holds
        // more (the last threshold is +inf: the scan stops).
        if !self.one_node {
            return self.scan(b, d);
        }
        let sel = usize::from(d >= r.frac[1][0]);
        let [base, inv] = r.frac[sel];
        // (Only `locate` reads the cell index: the fast path loads nothing
        // more. Rounding may put theta a hair below g at a node: t = -ulp.)
        let k = self.refs.get(b).map_or(0, |&(_, k)| k as usize) + sel;
        (k, r.off[sel] as usize, (d - base) * inv)
    }

    /// [`Self::padded`] where a bucket may hold several thresholds: the
    /// angle `g + d` of bucket `b` by a scan from the cell holding `g`.
    #[cold]
    #[inline(never)]
    fn scan(&self, b: usize, d: f64) -> (usize, usize, f64) {
        let (g, k) = self.refs[b];
        let (theta, mut k) = (g + d, k as usize);
        while theta >= self.thr[k + 1] {
            k += 1;
        }
        let cell = self.cells[k];
        (k, cell.off, (theta - cell.a) * cell.inv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_rise_with_the_angle_and_invert() {
        for kind in [AngleKind::Polar, AngleKind::Azimuth] {
            let m = 100_000;
            let mut last = -1.0;
            for j in 0..m {
                let a = kind.range() * j as f64 / m as f64;
                let (s, c) = a.sin_cos();
                let k = kind.key(c, s.max(if kind == AngleKind::Polar { 0.0 } else { -1.0 }));
                assert!(k > last, "{kind:?} {a}: {k} <= {last}");
                assert!((k - kind.key_of(a)).abs() < 1e-12, "{kind:?} {a}");
                assert!((kind.angle(k) - a).abs() < 1e-7, "{kind:?} {a}");
                last = k;
            }
        }
        let h = FRAC_1_SQRT_2;
        assert_eq!(azimuth_key(1.0, 0.0), 0.0);
        assert_eq!(azimuth_key(1.0, -0.0), 0.0);
        assert_eq!(azimuth_key(0.0, 1.0), 2.0 * h);
        assert_eq!(azimuth_key(-1.0, 0.0), 4.0 * h);
        assert_eq!(azimuth_key(0.0, -1.0), 6.0 * h);
        assert_eq!(AngleKind::Azimuth.key_of(PI), 4.0 * h);
        assert_eq!(AngleKind::Azimuth.key_of(2.0 * PI), 8.0 * h);
        assert!((AngleKind::Azimuth.key_of(1.5 * PI) - 6.0 * h).abs() < 1e-15);
        // Continuous across the half and the full turn.
        let e = 1e-9;
        assert!((azimuth_key(-1.0, e) - azimuth_key(-1.0, -e)).abs() < 3.0 * e);
        assert!((8.0 * h - azimuth_key(1.0, -e)).abs() < 2.0 * e);
    }

    #[test]
    fn asin_series_is_exact_to_rounding_on_its_range() {
        let xmax = BUCKET_MAX_ANGLE.sin();
        for k in 0..=10_000 {
            let x = -xmax + 2.0 * xmax * k as f64 / 10_000.0;
            assert!((asin_small(x) - x.asin()).abs() <= 3e-17, "{x}");
        }
    }

    /// Cell and fraction against `atan2` and a search, on even and uneven
    /// grids, cells wider than pi, and cells so narrow that the buckets
    /// hold several nodes (the scan).
    #[test]
    fn cells_and_fractions_match_the_inverse_trigonometric_rule() {
        let deg = |v: &[f64]| v.iter().map(|x| x.to_radians()).collect::<Vec<f64>>();
        let step = |d: f64, n: usize| (0..=n).map(|k| d * k as f64).collect::<Vec<f64>>();
        let grids = [
            (AngleKind::Polar, deg(&step(2.5, 72))),
            (AngleKind::Polar, deg(&step(5.0, 18))),
            (
                AngleKind::Polar,
                deg(&[10.0, 11.0, 15.0, 40.0, 41.0, 42.0, 43.0, 120.0]),
            ),
            (
                AngleKind::Polar,
                deg(&[0.0, 1e-4, 2e-4, 3e-4, 90.0, 90.0001, 180.0]),
            ),
            (AngleKind::Polar, deg(&[0.0, 180.0])),
            (AngleKind::Azimuth, deg(&step(5.0, 72))),
            (
                AngleKind::Azimuth,
                deg(&[0.0, 30.0, 45.0, 90.0, 180.0, 270.0, 360.0]),
            ),
            (AngleKind::Azimuth, deg(&[0.0, 200.0, 360.0])),
            (
                AngleKind::Azimuth,
                deg(&[0.0, 1e-4, 2e-4, 3e-4, 90.0, 90.0001, 360.0]),
            ),
        ];
        for (kind, a) in &grids {
            let g = AngleGrid::new(*kind, a).unwrap();
            assert_eq!(g.one_node, a[1] > 1e-3, "{a:?}");
            let n = a.len();
            for j in 0..200_000 {
                let th = kind.range() * (j as f64 + 0.37) / 200_000.0;
                let (s, c) = th.sin_cos();
                let got = g.locate(c, s);
                if th < a[0] || th > a[n - 1] {
                    assert!(got.is_none(), "{th} outside {:?}", (a[0], a[n - 1]));
                    continue;
                }
                let (k, t) = got.unwrap();
                let kk = a.partition_point(|&x| x <= th).clamp(1, n - 1) - 1;
                let tt = (th - a[kk]) / (a[kk + 1] - a[kk]);
                // The same point of the piecewise-linear interpolant.
                let (x, y) = (k as f64 + t, kk as f64 + tt);
                assert!(
                    (x - y).abs() < 1e-12,
                    "{kind:?} {th}: ({k}, {t}) vs ({kk}, {tt})"
                );
            }
        }
    }

    #[test]
    fn bad_grids_are_refused() {
        assert!(AngleGrid::new(AngleKind::Azimuth, &[0.0]).is_none());
        assert!(AngleGrid::new(AngleKind::Azimuth, &[0.0, 0.0]).is_none());
        assert!(AngleGrid::new(AngleKind::Azimuth, &[-0.1, 1.0]).is_none());
        assert!(AngleGrid::new(AngleKind::Azimuth, &[0.0, 7.0]).is_none());
        assert!(AngleGrid::new(AngleKind::Polar, &[0.0, 3.5]).is_none());
    }
}
