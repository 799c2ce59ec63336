//! Visibility cells (issue 15, fast rooms): one receiver list's region cut
//! into a grid of boxes, and per (cell, entry) which of the entry's
//! occluders can shadow a segment from the cell to it
//! ([`Scene::cell_visibility`]): most pairs then need no shadow test at all
//! (no occluder meets the hull of the cell and the receiver), and a cell
//! behind a cabinet from a wall point needs none either (a solid box
//! shadows all of it, [`crate::scene::world::CELL_DARK`]). The answers are
//! those of the entry's whole occluder list, pair by pair, so scores do not
//! depend on whether cells were built.

use crate::scene::Scene;
use crate::scene::world::Occluder;
use glam::DVec3;
use rayon::prelude::*;

/// One cell's split ([`VisibilityCells::split`]): the open responses, the
/// entries left to a test (their masks are the cell's), and the cell's masks.
pub(super) type CellSplit<'a> = (&'a [f64], &'a [u32], &'a [u64]);

/// Most cells along a region's longest side: for a flat region (a wall, a
/// floor, a desk top: one cell across) and for a solid one. Finer flat
/// cells leave fewer pairs to a shadow test (the office's 506 grid points,
/// one thread, 65,536 chains, `--near-radius 0`, least of 7 interleaved
/// runs: 12 a side 1.37 s, 24 a side 1.16 s, at about twice the masks);
/// a solid region (the curved shapes' list) gained nothing from 24 a side
/// (1.36 s), which takes eight times its masks.
const CELLS_PER_SIDE_FLAT: usize = 24;
const CELLS_PER_SIDE_SOLID: usize = 12;

/// One list's cells and their masks.
#[derive(Clone, Debug)]
pub(super) struct VisibilityCells {
    /// The region's low corner \[m\] and cells per metre along each axis.
    lo: DVec3,
    inv: DVec3,
    n: [usize; 3],
    /// Entries of the list.
    len: usize,
    /// Per cell (x fastest), per entry: the mask of
    /// [`Scene::cell_visibility`].
    vis: Vec<u64>,
    /// The constant-response entries' masks split for the two-pass kernel
    /// (flat lists only, else empty): per cell, the response `w` of each
    /// of the first `n_const` entries where no occluder can shadow it from
    /// the cell (mask 0) and 0 elsewhere, so that the open pairs score in
    /// straight-line code ...
    open_w: Vec<f64>,
    n_const: usize,
    /// ... and the entries left to a shadow test (their masks are in
    /// `vis`): `tests[test_start[c]..test_start[c + 1]]` for cell `c` (a
    /// dark entry is in neither).
    test_start: Vec<u32>,
    tests: Vec<u32>,
}

impl VisibilityCells {
    /// The cell counts along each axis for a region of extents `e` \[m\]
    /// with at most `per_side` cells along its longest side (1 along a
    /// side under a thousandth of a cell).
    fn counts(e: DVec3, per_side: usize) -> [usize; 3] {
        let side = e.max_element() / per_side as f64;
        std::array::from_fn(|a| {
            if side > 0.0 && e[a] > 1e-3 * side {
                ((e[a] / side).ceil() as usize).clamp(1, per_side)
            } else {
                1
            }
        })
    }

    /// Most 8-byte words the cells of a region can take for `len` entries
    /// (`split` of them also split for the two-pass kernel, see
    /// [`Self::build`]), at most `per_side` cells along the longest side:
    /// per cell a mask per entry, an open response per split entry and, at
    /// worst, every split entry on the cell's test list (4 bytes each).
    pub(super) fn size(region: (DVec3, DVec3), len: usize, split: usize, per_side: usize) -> usize {
        let n = Self::counts(region.1 - region.0, per_side);
        n[0] * n[1] * n[2] * (len + split + split.div_ceil(2))
    }

    /// The cells of `region` \[m\] for entries at `points` whose occluders
    /// are `occ[start[k]..start[k + 1]]`, at most `per_side` cells along
    /// the longest side (default through
    /// [`Self::per_side`]); with `split = Some(w)`, the first `w.len()`
    /// entries (of constant response `w`) are also split into open and
    /// tested pairs per cell ([`Self::split`]).
    pub(super) fn build(
        scene: &Scene,
        region: (DVec3, DVec3),
        points: &[DVec3],
        start: &[u32],
        occ: &[Occluder],
        per_side: usize,
        split: Option<&[f64]>,
    ) -> Self {
        let (lo, hi) = region;
        let e = hi - lo;
        let n = Self::counts(e, per_side);
        let step = e / DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        let inv = DVec3::new(
            if e.x > 0.0 { n[0] as f64 / e.x } else { 0.0 },
            if e.y > 0.0 { n[1] as f64 / e.y } else { 0.0 },
            if e.z > 0.0 { n[2] as f64 / e.z } else { 0.0 },
        );
        let len = points.len();
        // The cells in parallel, each filling its own row (x fastest, as
        // `cell` indexes them): the same masks whatever the threads. A
        // list's cells can be most of a run's set-up, and the lists
        // themselves are built in parallel but unevenly (the walls' lists
        // hold most points).
        let mut vis = vec![0u64; n[0] * n[1] * n[2] * len];
        if len > 0 {
            vis.par_chunks_mut(len).enumerate().for_each(|(c, row)| {
                let idx = [c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])];
                // The cell's box; the last along an axis ends at the
                // region's own bound.
                let c0 =
                    DVec3::from_array(std::array::from_fn(|a| lo[a] + step[a] * idx[a] as f64));
                let c1 = DVec3::from_array(std::array::from_fn(|a| {
                    if idx[a] + 1 == n[a] {
                        hi[a]
                    } else {
                        lo[a] + step[a] * (idx[a] + 1) as f64
                    }
                }));
                for ((e, p), m) in points.iter().enumerate().zip(row.iter_mut()) {
                    let o = &occ[start[e] as usize..start[e + 1] as usize];
                    if !o.is_empty() {
                        *m = scene.cell_visibility(*p, o, (c0, c1));
                    }
                }
            });
        }
        let (mut open_w, mut test_start, mut tests) = (Vec::new(), Vec::new(), Vec::new());
        if let Some(w) = split {
            test_start.push(0);
            for row in vis.chunks_exact(len.max(1)).take(n[0] * n[1] * n[2]) {
                for (k, (&m, &w)) in row.iter().zip(w).enumerate() {
                    open_w.push(if m == 0 { w } else { 0.0 });
                    if m != 0 && m != crate::scene::world::CELL_DARK {
                        tests.push(k as u32);
                    }
                }
                test_start.push(tests.len() as u32);
            }
        }
        Self {
            lo,
            inv,
            n,
            len,
            vis,
            open_w,
            n_const: split.map_or(0, <[f64]>::len),
            test_start,
            tests,
        }
    }

    /// For a collision at `x` \[m\] (as [`Self::row`]): the open responses of
    /// the constant-response entries, the pairs left to a shadow test
    /// (entry, mask) and the cell's masks ([`Self::row`]); `None` unless
    /// the cells were built split.
    #[inline(always)]
    pub(super) fn split(&self, x: DVec3) -> Option<CellSplit<'_>> {
        if self.test_start.is_empty() {
            return None;
        }
        let c = self.cell(x);
        let t = self.test_start[c] as usize..self.test_start[c + 1] as usize;
        Some((
            &self.open_w[c * self.n_const..(c + 1) * self.n_const],
            &self.tests[t],
            &self.vis[c * self.len..(c + 1) * self.len],
        ))
    }

    /// The default most cells along the longest side of `region` \[m\]:
    /// [`CELLS_PER_SIDE_FLAT`] where it takes one cell across (an extent
    /// under a thousandth of the longest, as [`Self::counts`] has it),
    /// else [`CELLS_PER_SIDE_SOLID`].
    pub(super) fn per_side(region: (DVec3, DVec3)) -> usize {
        let flat = Self::counts(region.1 - region.0, CELLS_PER_SIDE_FLAT).contains(&1);
        if flat {
            CELLS_PER_SIDE_FLAT
        } else {
            CELLS_PER_SIDE_SOLID
        }
    }

    /// The masks of the cell holding `x` \[m\] (a point of the region; one
    /// outside by rounding is taken to the nearest cell, whose box the
    /// masks were made for grown by the occluder lists' margin).
    #[inline(always)]
    pub(super) fn row(&self, x: DVec3) -> &[u64] {
        let c = self.cell(x);
        &self.vis[c * self.len..(c + 1) * self.len]
    }

    /// The index of the cell holding `x` (see [`Self::row`]).
    #[inline(always)]
    fn cell(&self, x: DVec3) -> usize {
        let r = (x - self.lo) * self.inv;
        // `as` saturates: negative (and NaN) to 0.
        let i = (r.x as usize).min(self.n[0] - 1);
        let j = (r.y as usize).min(self.n[1] - 1);
        let k = (r.z as usize).min(self.n[2] - 1);
        (k * self.n[1] + j) * self.n[0] + i
    }
}
