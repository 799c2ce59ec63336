//! The room's outline on a grid's plane: the scene's finite surfaces, as
//! the scene file writes them, projected along the plane's normal (a plan
//! for a floor grid, an elevation for a wall grid), and the luminaires'
//! positions.
//!
//! Boxes give the convex hull of their eight projected corners (the room
//! itself, a box with inward normals, drawn heavy), rectangles the hull of
//! their four corners (a vertical partition on a floor plan: a line),
//! discs 48 points of their rim. Infinite planes, meshes and SH objects
//! are left out (a plane has no outline; a mesh's is not worth its load).

use crate::grid::lattice::Lattice;
use crate::io::isolux::Outline;
use crate::scene::desc::SceneDesc;
use glam::DVec3;

/// The outlines of `desc`'s finite surfaces in `lattice`'s plane coordinates \[m\].
pub fn outlines(desc: &SceneDesc, lattice: &Lattice) -> Vec<Outline> {
    let v3 = |v: &Option<toml::Spanned<crate::scene::desc::Vec3>>| {
        v.as_ref().map(|v| DVec3::from(v.get_ref().0))
    };
    let mut out = Vec::new();
    for s in &desc.surface {
        let s = s.get_ref();
        let corners: Vec<DVec3> = match s.kind.get_ref().as_str() {
            "box" => match (v3(&s.min), v3(&s.max)) {
                (Some(a), Some(b)) => (0..8)
                    .map(|k| {
                        DVec3::new(
                            if k & 1 == 0 { a.x } else { b.x },
                            if k & 2 == 0 { a.y } else { b.y },
                            if k & 4 == 0 { a.z } else { b.z },
                        )
                    })
                    .collect(),
                _ => continue,
            },
            "rectangle" => match (v3(&s.corner), v3(&s.edge1), v3(&s.edge2)) {
                (Some(c), Some(e1), Some(e2)) => vec![c, c + e1, c + e1 + e2, c + e2],
                _ => continue,
            },
            "disc" => match (v3(&s.center), v3(&s.normal), s.radius.as_ref()) {
                (Some(c), Some(n), Some(r)) if n.length() > 0.0 => {
                    let n = n.normalize();
                    let a = n.any_orthonormal_vector();
                    let b = n.cross(a);
                    let r = *r.get_ref();
                    (0..48)
                        .map(|k| {
                            let t = k as f64 * std::f64::consts::TAU / 48.0;
                            c + r * (t.cos() * a + t.sin() * b)
                        })
                        .collect()
                }
                _ => continue,
            },
            _ => continue,
        };
        let pts: Vec<(f64, f64)> = corners.iter().map(|&p| lattice.coords(p)).collect();
        if pts.iter().any(|p| !(p.0.is_finite() && p.1.is_finite())) {
            continue;
        }
        let hull = convex_hull(&pts);
        // (A box's normals are inward unless it says otherwise.)
        let inward = s.normals.as_ref().is_none_or(|n| n.get_ref() == "inward");
        out.push(Outline {
            closed: hull.len() > 2,
            heavy: s.kind.get_ref() == "box" && inward,
            points: hull,
        });
    }
    out
}

/// The luminaires' positions (`position`, `center`, or a rectangle's
/// centre: `corner` plus half of each edge) in `lattice`'s plane
/// coordinates \[m\].
pub fn luminaires(desc: &SceneDesc, lattice: &Lattice) -> Vec<(f64, f64)> {
    let v = |p: &Option<toml::Spanned<crate::scene::desc::Vec3>>| {
        p.as_ref().map(|p| DVec3::from(p.get_ref().0))
    };
    desc.light
        .iter()
        .filter_map(|l| {
            let l = l.get_ref();
            let rect = || {
                let half =
                    0.5 * (v(&l.edge1).unwrap_or_default() + v(&l.edge2).unwrap_or_default());
                v(&l.corner).map(|c| c + half)
            };
            v(&l.position)
                .or(v(&l.center))
                .or_else(rect)
                .map(|p| lattice.coords(p))
        })
        .collect()
}

/// The convex hull of `p`, counter-clockwise (Andrew's monotone chain);
/// collinear points give the two ends of their segment.
pub fn convex_hull(p: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut pts = p.to_vec();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let scale = pts
        .iter()
        .map(|q| q.0.abs().max(q.1.abs()))
        .fold(0.0, f64::max)
        .max(1e-300);
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    // Turns smaller than rounding count as straight.
    let eps = 1e-12 * scale * scale;
    let mut hull: Vec<(f64, f64)> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= eps
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_projected_box_and_a_vertical_rectangle() {
        // A box's corners seen from above: its rectangle.
        let p = [
            (0.0, 0.0),
            (6.0, 0.0),
            (0.0, 4.0),
            (6.0, 4.0),
            (0.0, 0.0),
            (6.0, 0.0),
            (3.0, 2.0),
        ];
        assert_eq!(
            convex_hull(&p),
            vec![(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)]
        );
        // A vertical rectangle seen from above: a segment.
        let p = [(3.0, 2.4), (3.0, 3.9), (3.0, 3.9), (3.0, 2.4)];
        assert_eq!(convex_hull(&p), vec![(3.0, 2.4), (3.0, 3.9)]);
    }

    /// The office scene on its work-plane lattice: the room is the heavy
    /// 6 x 4 m rectangle, the table a 48-point ring, the partition a line,
    /// and the six luminaires are placed.
    #[test]
    fn office_plan() {
        let src = std::fs::read_to_string("data/office.toml").unwrap();
        let desc: SceneDesc = toml::from_str(&src).unwrap();
        let p: Vec<DVec3> = (0..4)
            .map(|k| DVec3::new((k % 2) as f64, (k / 2) as f64, 0.75))
            .collect();
        let lat = crate::grid::lattice::lattice(&p, &[DVec3::Z; 4], &[1.0; 4]).unwrap();
        let o = outlines(&desc, &lat);
        let room = o.iter().find(|o| o.heavy).unwrap();
        assert_eq!(
            room.points,
            vec![(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)]
        );
        assert!(o.iter().any(|o| o.points.len() == 48));
        assert!(o.iter().any(|o| o.points == vec![(3.0, 2.4), (3.0, 3.9)]));
        assert_eq!(luminaires(&desc, &lat).len(), 6);
    }

    /// A rectangle light is marked at its centre (it was at its corner),
    /// and a box without `normals` (inward by default) is drawn heavy.
    #[test]
    fn rectangle_lights_at_their_centre_and_default_rooms_heavy() {
        let desc: SceneDesc = toml::from_str(
            "[[surface]]\ntype = \"box\"\nmin = [0, 0, 0]\nmax = [4, 3, 2.5]\n\
             material = { type = \"lambertian\", reflectance = 0.5 }\n\
             [[light]]\ntype = \"rectangle\"\ncorner = [1.7, 2.1, 2.5]\nedge1 = [0.6, 0, 0]\n\
             edge2 = [0, -1.2, 0]\nluminance = 1000\n",
        )
        .unwrap();
        let p: Vec<DVec3> = (0..4)
            .map(|k| DVec3::new((k % 2) as f64, (k / 2) as f64, 0.8))
            .collect();
        let lat = crate::grid::lattice::lattice(&p, &[DVec3::Z; 4], &[1.0; 4]).unwrap();
        let (x, y) = luminaires(&desc, &lat)[0];
        assert!(
            (x - 2.0).abs() < 1e-12 && (y - 1.5).abs() < 1e-12,
            "({x}, {y})"
        );
        assert!(outlines(&desc, &lat).iter().any(|o| o.heavy));
    }
}
