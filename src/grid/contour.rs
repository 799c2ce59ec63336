//! Contour lines (isolines) of values on a rectilinear lattice, by
//! marching squares (Lorensen & Cline 1987, in two dimensions).
//!
//! The values `z[j nx + i]` sit at the lattice nodes `(xs[i], ys[j])`
//! (strictly increasing coordinates; for a grid, its cell centres). A node
//! is *above* a level when `z >= level`. In every lattice cell whose four
//! corners are finite, an edge whose two ends differ is crossed at the
//! linear interpolate `t = (level - z_a) / (z_b - z_a)`, which lies in
//! `[0, 1)` and never divides by zero (one end is below, the other not).
//! A cell with two crossed edges gives one segment; with four (a saddle:
//! opposite corners above), the mean of the corners decides which pair of
//! opposite corners is joined (the asymptotic decider's cheap form). A cell
//! with a NaN corner (a point missing from a disc's grid) gives nothing, so
//! lines end at its border.
//!
//! Segments are joined into polylines through the lattice edges they share:
//! an edge is crossed once, and touched by the segments of its (at most two)
//! cells, so joining by edge is exact, with no distance tolerance. Closed
//! lines repeat their first point at the end.

use std::collections::HashMap;

/// A lattice edge: horizontal from node `(i, j)` to `(i + 1, j)`, or
/// vertical from `(i, j)` to `(i, j + 1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Edge {
    H(usize, usize),
    V(usize, usize),
}

/// The contour lines of `z` at `level`: polylines of `(x, y)` points in
/// the lattice's coordinates. `z` has `xs.len() * ys.len()` values, row by
/// row (`x` fastest).
///
/// # Panics
/// If `z` does not have one value per node.
pub fn isolines(xs: &[f64], ys: &[f64], z: &[f64], level: f64) -> Vec<Vec<(f64, f64)>> {
    let (nx, ny) = (xs.len(), ys.len());
    assert_eq!(z.len(), nx * ny, "one value per lattice node");
    if nx < 2 || ny < 2 || !level.is_finite() {
        return Vec::new();
    }
    let at = |i: usize, j: usize| z[j * nx + i];
    let node = |i: usize, j: usize| (xs[i], ys[j]);
    // The point where `level` crosses an edge.
    let cross = |e: Edge| -> (f64, f64) {
        let ((i0, j0), (i1, j1)) = match e {
            Edge::H(i, j) => ((i, j), (i + 1, j)),
            Edge::V(i, j) => ((i, j), (i, j + 1)),
        };
        let (za, zb) = (at(i0, j0), at(i1, j1));
        let t = (level - za) / (zb - za);
        let (a, b) = (node(i0, j0), node(i1, j1));
        (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
    };
    let mut segments: Vec<[Edge; 2]> = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            // Corners counter-clockwise from the lower left, and the edges
            // between them: e[k] joins corner k and corner k + 1.
            let c = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            if c.iter().any(|v| !v.is_finite()) {
                continue;
            }
            let up = c.map(|v| v >= level);
            let e = [
                Edge::H(i, j),
                Edge::V(i + 1, j),
                Edge::H(i, j + 1),
                Edge::V(i, j),
            ];
            let crossed: Vec<usize> = (0..4).filter(|&k| up[k] != up[(k + 1) % 4]).collect();
            match crossed.len() {
                2 => segments.push([e[crossed[0]], e[crossed[1]]]),
                4 => {
                    let centre_up = c.iter().sum::<f64>() / 4.0 >= level;
                    if centre_up == up[0] {
                        // Corners 0 and 2 joined: cut off corners 1 and 3.
                        segments.push([e[0], e[1]]);
                        segments.push([e[2], e[3]]);
                    } else {
                        // Corners 1 and 3 joined: cut off corners 0 and 2.
                        segments.push([e[3], e[0]]);
                        segments.push([e[1], e[2]]);
                    }
                }
                _ => {}
            }
        }
    }
    join(&segments)
        .into_iter()
        .map(|edges| edges.into_iter().map(cross).collect())
        .collect()
}

/// Join segments sharing an edge into chains of edges: open chains first
/// (from an end touched by one segment), then closed ones (first edge
/// repeated at the end).
fn join(segments: &[[Edge; 2]]) -> Vec<Vec<Edge>> {
    let mut touching: HashMap<Edge, Vec<usize>> = HashMap::new();
    for (s, seg) in segments.iter().enumerate() {
        for &e in seg {
            touching.entry(e).or_default().push(s);
        }
    }
    let mut used = vec![false; segments.len()];
    let mut lines = Vec::new();
    let walk = |start: usize, from: Edge, used: &mut Vec<bool>| -> Vec<Edge> {
        let mut line = vec![from];
        let (mut s, mut at) = (start, from);
        loop {
            used[s] = true;
            let next = if segments[s][0] == at {
                segments[s][1]
            } else {
                segments[s][0]
            };
            line.push(next);
            match touching[&next].iter().find(|&&t| !used[t]) {
                Some(&t) => (s, at) = (t, next),
                None => return line,
            }
        }
    };
    // Open lines start at an edge touched by one segment only.
    for s in 0..segments.len() {
        if used[s] {
            continue;
        }
        if let Some(&end) = segments[s].iter().find(|e| touching[e].len() == 1) {
            lines.push(walk(s, end, &mut used));
        }
    }
    for s in 0..segments.len() {
        if !used[s] {
            lines.push(walk(s, segments[s][0], &mut used));
        }
    }
    lines
}

/// About `n` round contour levels strictly inside `(lo, hi)`: multiples of
/// a step of 1, 2 or 5 times a power of ten. Empty when the range is empty
/// or not finite.
pub fn levels(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) || n == 0 {
        return Vec::new();
    }
    let step = nice_step((hi - lo) / n as f64);
    let k0 = (lo / step).floor() as i64 + 1;
    let k1 = (hi / step).ceil() as i64 - 1;
    (k0..=k1)
        .map(|k| k as f64 * step)
        .filter(|&v| v > lo && v < hi)
        .collect()
}

/// The smallest of 1, 2, 5 times a power of ten that is at least `raw`.
pub fn nice_step(raw: f64) -> f64 {
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|&s| s >= raw * (1.0 - 1e-12))
        .unwrap_or(10.0 * mag)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lattice(n: usize, a: f64, b: f64) -> Vec<f64> {
        (0..n)
            .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
            .collect()
    }

    /// A plane `z = x` is cut at `x = level` along the whole height, one
    /// open line joined across every row of cells.
    #[test]
    fn linear_field_gives_one_straight_line() {
        let xs = [0.0, 1.0, 2.0, 4.0];
        let ys = lattice(6, -1.0, 1.5);
        let z: Vec<f64> = ys.iter().flat_map(|_| xs.iter().copied()).collect();
        let lines = isolines(&xs, &ys, &z, 3.1);
        assert_eq!(lines.len(), 1);
        let line = &lines[0];
        assert_eq!(line.len(), ys.len());
        for p in line {
            assert!((p.0 - 3.1).abs() < 1e-12, "{p:?}");
        }
        let mut yv: Vec<f64> = line.iter().map(|p| p.1).collect();
        yv.sort_by(f64::total_cmp);
        assert_eq!(yv, ys);
        // Outside the range: nothing.
        assert!(isolines(&xs, &ys, &z, 4.5).is_empty());
        assert!(isolines(&xs, &ys, &z, -0.5).is_empty());
    }

    /// `z = x^2 + y^2` on a fine lattice: the level-1 line is one closed
    /// ring on the unit circle (within the linear interpolation's error
    /// `h^2 / 4`), enclosing the area pi within 0.2 %.
    #[test]
    fn paraboloid_gives_the_unit_circle() {
        let xs = lattice(61, -1.5, 1.5);
        let ys = lattice(41, -1.4, 1.6);
        let z: Vec<f64> = ys
            .iter()
            .flat_map(|&y| xs.iter().map(move |&x| x * x + y * y))
            .collect();
        let lines = isolines(&xs, &ys, &z, 1.0);
        assert_eq!(lines.len(), 1);
        let ring = &lines[0];
        assert_eq!(ring.first(), ring.last(), "closed");
        for p in ring {
            let r2 = p.0 * p.0 + p.1 * p.1;
            assert!((r2 - 1.0).abs() < 0.0026, "{p:?}: r^2 = {r2}");
        }
        let area = 0.5
            * ring
                .windows(2)
                .map(|w| w[0].0 * w[1].1 - w[1].0 * w[0].1)
                .sum::<f64>()
                .abs();
        assert!(
            (area / std::f64::consts::PI - 1.0).abs() < 2e-3,
            "area {area}"
        );
    }

    /// A NaN node removes its four cells: the ring around it opens and
    /// ends at the hole's border.
    #[test]
    fn nan_nodes_cut_lines() {
        let xs = lattice(21, -1.0, 1.0);
        let ys = xs.clone();
        let mut z: Vec<f64> = ys
            .iter()
            .flat_map(|&y| xs.iter().map(move |&x| x * x + y * y))
            .collect();
        // The node nearest (0.5, 0) is missing.
        z[10 * 21 + 15] = f64::NAN;
        let lines = isolines(&xs, &ys, &z, 0.25);
        assert_eq!(lines.len(), 1);
        let line = &lines[0];
        assert_ne!(line.first(), line.last(), "open");
        for p in [line[0], *line.last().unwrap()] {
            assert!(
                (p.0 - 0.5).abs() <= 0.1 + 1e-12 && p.1.abs() <= 0.1 + 1e-12,
                "{p:?}"
            );
        }
    }

    /// A saddle cell: the centre (mean 0.5 >= 0.5) is above, so the two
    /// high corners are joined and the two segments cut off the low ones.
    #[test]
    fn saddle_joins_by_the_centre() {
        let (xs, ys) = ([0.0, 1.0], [0.0, 1.0]);
        // Corners: (0,0) = 1, (1,0) = 0, (0,1) = 0, (1,1) = 1.
        let z = [1.0, 0.0, 0.0, 1.0];
        let mut lines = isolines(&xs, &ys, &z, 0.5);
        assert_eq!(lines.len(), 2);
        for l in &mut lines {
            l.sort_by(|a, b| a.partial_cmp(b).unwrap());
        }
        lines.sort_by(|a, b| a.partial_cmp(b).unwrap());
        // Around the low corner (1, 0) and the low corner (0, 1).
        assert_eq!(lines[0], vec![(0.0, 0.5), (0.5, 1.0)]);
        assert_eq!(lines[1], vec![(0.5, 0.0), (1.0, 0.5)]);
        // Below the centre: the low corners are joined instead.
        let lines = isolines(&xs, &ys, &z, 0.6);
        let mut ends: Vec<(f64, f64)> = lines.concat();
        ends.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(ends, vec![(0.0, 0.4), (0.4, 0.0), (0.6, 1.0), (1.0, 0.6)]);
        let around_origin = lines.iter().find(|l| l.contains(&(0.0, 0.4))).unwrap();
        assert!(around_origin.contains(&(0.4, 0.0)));
    }

    #[test]
    fn round_levels() {
        assert_eq!(levels(238.6, 442.8, 6), vec![250.0, 300.0, 350.0, 400.0]);
        assert_eq!(levels(0.0, 1.0, 5), vec![0.2, 0.4, 0.6000000000000001, 0.8]);
        assert!(levels(1.0, 1.0, 5).is_empty());
        assert!(levels(f64::NAN, 1.0, 5).is_empty());
        assert_eq!(nice_step(0.3), 0.5);
        assert_eq!(nice_step(7.0), 10.0);
        assert_eq!(nice_step(20.0), 20.0);
    }
}
