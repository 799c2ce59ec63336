//! The points of a flat grid as a rectilinear lattice in its plane, for
//! pictures: plane coordinates, the distinct coordinates along each axis,
//! and each point's node.
//!
//! A grid's points are read back from a points CSV (any grid, not only
//! those `lumest grid` writes), so the lattice is found from the points
//! themselves: they must share one normal and lie in one plane. When that
//! normal is a world axis the plane's axes are the other two world axes
//! (`x`, `y` for a floor; `x`, `z` or `y`, `z` for a wall), so a plan shows
//! room coordinates; otherwise (or when the points do not line up with the
//! world axes) the axes are `u`, from the first point towards its nearest
//! neighbour, and `v = n x u`, measured from the first point. Coordinates
//! closer than `1e-6` of the extent are one lattice line. Nodes without a
//! point (a disc's corners) are empty; at least half the nodes must have
//! one (a disc's grid fills about pi/4 of its square).

use glam::DVec3;

/// A grid's points as nodes of a rectilinear lattice in their plane.
#[derive(Clone, Debug, PartialEq)]
pub struct Lattice {
    /// Names of the two plane axes (`x`, `y`, `z`, or `u`, `v`).
    pub axes: [&'static str; 2],
    /// The plane point of coordinates (0, 0) \[m\].
    pub origin: DVec3,
    /// Unit first axis.
    pub u: DVec3,
    /// Unit second axis.
    pub v: DVec3,
    /// Distinct first coordinates, increasing \[m\].
    pub xs: Vec<f64>,
    /// Distinct second coordinates, increasing \[m\].
    pub ys: Vec<f64>,
    /// Node `(i, j)` of each point, in the input's order.
    pub nodes: Vec<(usize, usize)>,
    /// The cells around the nodes `(x0, x1, y0, y1)` \[m\]: half a spacing
    /// beyond the outer nodes (half the side of a point's own area when a
    /// lattice line is alone).
    pub bounds: (f64, f64, f64, f64),
}

impl Lattice {
    /// Plane coordinates of a point `p` \[m\] (projected along the normal).
    pub fn coords(&self, p: DVec3) -> (f64, f64) {
        let d = p - self.origin;
        (d.dot(self.u), d.dot(self.v))
    }

    /// The values of the points on the lattice, row by row (`x` fastest),
    /// NaN at nodes without a point.
    pub fn raster(&self, values: &[f64]) -> Vec<f64> {
        let nx = self.xs.len();
        let mut z = vec![f64::NAN; nx * self.ys.len()];
        for (&(i, j), &v) in self.nodes.iter().zip(values) {
            z[j * nx + i] = v;
        }
        z
    }
}

/// The unit normal of the plane through points `p` \[m\] (from the
/// farthest point from the first and the one farthest off that line), or
/// `None` when they lie on one line. Cylindrical and semicylindrical
/// receivers carry their axis or facing in the normal columns, not their
/// grid's normal.
pub fn plane_normal(p: &[DVec3]) -> Option<DVec3> {
    let p0 = *p.first()?;
    let far = |f: &dyn Fn(DVec3) -> f64| {
        p.iter()
            .copied()
            .max_by(|a, b| f(*a - p0).total_cmp(&f(*b - p0)))
    };
    let q1 = far(&|d| d.length_squared())?;
    let u = q1 - p0;
    let q2 = far(&|d| u.cross(d).length_squared())?;
    let n = u.cross(q2 - p0);
    // Off the line by more than rounding of the extent.
    (n.length() > 1e-9 * u.length_squared()).then(|| n.normalize())
}

/// The lattice of points `p` with normals `n` and cell areas `area` [m^2]
/// (used only for a lattice line that is alone); an error says why the
/// points are no flat rectilinear lattice.
pub fn lattice(p: &[DVec3], n: &[DVec3], area: &[f64]) -> Result<Lattice, String> {
    let Some((&p0, &n0)) = p.first().zip(n.first()) else {
        return Err("no points".into());
    };
    let n0 = n0.normalize();
    if !n0.is_finite() || n.iter().any(|m| m.normalize().dot(n0) < 1.0 - 1e-9) {
        return Err("the points do not share one normal".into());
    }
    let extent = p.iter().map(|q| (*q - p0).length()).fold(0.0, f64::max);
    let tol = 1e-6 * extent.max(1e-9);
    if p.iter().any(|q| (*q - p0).dot(n0).abs() > tol) {
        return Err("the points do not lie in one plane".into());
    }
    let half_side = |k: usize| 0.5 * area.get(k).map_or(1.0, |a| a.sqrt());
    let world = [DVec3::X, DVec3::Y, DVec3::Z];
    let names = ["x", "y", "z"];
    let mut frames = Vec::new();
    if let Some(k) = (0..3).find(|&k| n0[k].abs() > 1.0 - 1e-9) {
        let (a, b) = ((k + 1) % 3, (k + 2) % 3);
        let (a, b) = (a.min(b), a.max(b));
        frames.push(([names[a], names[b]], DVec3::ZERO, world[a], world[b]));
    }
    if let Some(q) = p
        .iter()
        .filter(|q| (**q - p0).length() > tol)
        .min_by(|a, b| (**a - p0).length().total_cmp(&(**b - p0).length()))
    {
        let d = *q - p0;
        let u = (d - d.dot(n0) * n0).normalize();
        frames.push((["u", "v"], p0, u, n0.cross(u)));
    }
    if frames.is_empty() {
        // A single point: any frame in its plane.
        let u = n0.any_orthonormal_vector();
        frames.push((["u", "v"], p0, u, n0.cross(u)));
    }
    let mut why = String::new();
    for (axes, origin, u, v) in frames {
        let c: Vec<(f64, f64)> = p
            .iter()
            .map(|q| ((*q - origin).dot(u), (*q - origin).dot(v)))
            .collect();
        let xs = distinct(c.iter().map(|c| c.0), tol);
        let ys = distinct(c.iter().map(|c| c.1), tol);
        if xs.len().saturating_mul(ys.len()) > 2 * p.len() {
            why = format!(
                "the points do not line up in rows and columns ({} x {} lines for {} points)",
                xs.len(),
                ys.len(),
                p.len()
            );
            continue;
        }
        let find = |lines: &[f64], x: f64| {
            lines
                .iter()
                .position(|&l| (l - x).abs() <= tol)
                .expect("every coordinate is on a line")
        };
        let nodes: Vec<(usize, usize)> = c
            .iter()
            .map(|&(x, y)| (find(&xs, x), find(&ys, y)))
            .collect();
        let mut seen = std::collections::HashSet::new();
        if !nodes.iter().all(|nd| seen.insert(*nd)) {
            why = "two points share a lattice node".into();
            continue;
        }
        let span = |l: &[f64]| match l.len() {
            1 => (l[0] - half_side(0), l[0] + half_side(0)),
            k => (
                l[0] - 0.5 * (l[1] - l[0]),
                l[k - 1] + 0.5 * (l[k - 1] - l[k - 2]),
            ),
        };
        let ((x0, x1), (y0, y1)) = (span(&xs), span(&ys));
        return Ok(Lattice {
            axes,
            origin,
            u,
            v,
            xs,
            ys,
            nodes,
            bounds: (x0, x1, y0, y1),
        });
    }
    Err(why)
}

/// The distinct values of `x` (closer than `tol`: one value, their first
/// in sorted order), increasing.
fn distinct(x: impl Iterator<Item = f64>, tol: f64) -> Vec<f64> {
    let mut v: Vec<f64> = x.collect();
    v.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::new();
    for x in v {
        if out.last().is_none_or(|&l| x - l > tol) {
            out.push(x);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plane through points, whatever their normal columns say; `None`
    /// on a line.
    #[test]
    fn plane_normal_of_points() {
        let p: Vec<DVec3> = (0..6)
            .map(|k| DVec3::new((k % 3) as f64, (k / 3) as f64, 1.5))
            .collect();
        assert_eq!(plane_normal(&p).map(|n| n.z.abs()), Some(1.0));
        let tilted: Vec<DVec3> = p.iter().map(|q| DVec3::new(q.x, q.y, q.x)).collect();
        let n = plane_normal(&tilted).unwrap();
        assert!((n.dot(DVec3::new(1.0, 0.0, -1.0).normalize()).abs() - 1.0).abs() < 1e-12);
        let line: Vec<DVec3> = (0..4).map(|k| DVec3::X * k as f64).collect();
        assert_eq!(plane_normal(&line), None);
    }

    /// A 3 x 2 floor grid at z = 0.75 (cells 0.5 m x 1 m): world axes x, y,
    /// nodes in file order, cell bounds half a spacing out.
    #[test]
    fn floor_grid_in_room_coordinates() {
        let mut p = Vec::new();
        for j in 0..2 {
            for i in 0..3 {
                p.push(DVec3::new(1.25 + 0.5 * i as f64, 2.5 + j as f64, 0.75));
            }
        }
        // A disc-like gap: the last node has no point.
        p.pop();
        let n = vec![DVec3::Z; p.len()];
        let l = lattice(&p, &n, &vec![0.5; p.len()]).unwrap();
        assert_eq!(l.axes, ["x", "y"]);
        assert_eq!(l.xs, vec![1.25, 1.75, 2.25]);
        assert_eq!(l.ys, vec![2.5, 3.5]);
        assert_eq!(l.nodes, vec![(0, 0), (1, 0), (2, 0), (0, 1), (1, 1)]);
        assert_eq!(l.bounds, (1.0, 2.5, 2.0, 4.0));
        let z = l.raster(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(&z[..5], &[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert!(z[5].is_nan());
    }

    /// A wall facing -x: axes y, z. A grid turned 30 degrees about z: the
    /// world axes fail, its own axes u, v succeed with unit spacing.
    #[test]
    fn walls_and_turned_grids() {
        let p: Vec<DVec3> = (0..4)
            .map(|k| DVec3::new(6.0, (k % 2) as f64, 1.0 + (k / 2) as f64))
            .collect();
        let l = lattice(&p, &[-DVec3::X; 4], &[1.0; 4]).unwrap();
        assert_eq!(l.axes, ["y", "z"]);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let (u, v) = (DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0));
        let p: Vec<DVec3> = (0..12)
            .map(|k| (k % 4) as f64 * u + (k / 4) as f64 * v)
            .collect();
        let l = lattice(&p, &vec![DVec3::Z; 12], &[1.0; 12]).unwrap();
        assert_eq!(l.axes, ["u", "v"]);
        assert_eq!(l.xs.len(), 4);
        assert_eq!(l.ys.len(), 3);
        for (x, k) in l.xs.iter().zip(0..) {
            assert!((x - k as f64).abs() < 1e-12);
        }
        // A single point: one cell of its own area.
        let l = lattice(&[DVec3::ONE], &[DVec3::Z], &[4.0]).unwrap();
        assert_eq!(l.bounds, (0.0, 2.0, 0.0, 2.0));
    }

    #[test]
    fn refuses_scattered_points() {
        let n = [DVec3::Z, DVec3::X];
        assert!(lattice(&[DVec3::ZERO, DVec3::X], &n, &[]).is_err());
        let p = [DVec3::ZERO, DVec3::new(1.0, 0.0, 0.5)];
        assert!(lattice(&p, &[DVec3::Z; 2], &[]).is_err());
        // Random points in a plane: no rows and columns.
        let p: Vec<DVec3> = (0..50)
            .map(|k| {
                let t = k as f64;
                DVec3::new((t * 0.618).fract() * 5.0, (t * 0.414).fract() * 3.0, 0.0)
            })
            .collect();
        let e = lattice(&p, &vec![DVec3::Z; 50], &[]).unwrap_err();
        assert!(e.contains("rows and columns"), "{e}");
    }
}
