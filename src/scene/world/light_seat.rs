//! Where a point-like light stands on surfaces (its *seat*), and which of
//! its directions meet a surface at once.
//!
//! **Rule**: a light exactly on a surface belongs to the surface's
//! reflecting side, as if it stood just in front of it; the answer is the
//! limit as the light approaches from that side. Light it emits into the
//! surface meets the surface at once, at the light's position, and points
//! behind the surface do not see it. On a face of a box, a sphere or the
//! inside of a flat shape this darkens a half-space. Where several faces
//! pass through the light (an edge or a corner of a box, of a room built
//! of rectangles or of a mesh, a rug's rim on the floor) the limit is
//! taken along the bisector `b` of their reflecting normals: from `p + e b`
//! a direction meets the face whose plane it crosses first inside that
//! face (each face near the light is its plane cut by its edges through
//! the light: a half-plane at an edge, a wedge at a corner). So:
//!
//! - **a solid's edge or corner** (a box with outward normals: a lamp on a
//!   desk's front edge): a direction meets the solid only if it points into
//!   every face through the light (the solid's cone there), and then meets
//!   the face whose plane it crosses last (the least steep one);
//! - **a room's edge or corner** (a box with inward normals, or rectangles,
//!   or a mesh: a luminaire where a wall meets the ceiling): a direction
//!   leaves the room through any face it points out of, and meets the face
//!   it crosses first (the steepest);
//! - **the rim of a rectangle or disc**: a direction into the back of the
//!   shape meets it only where it crosses the plane inside the shape, that
//!   is, where it also points into the shape across every edge through the
//!   light; beyond the rim it meets what lies there (the floor under a rug).
//!
//! Seated on one face only (the rule before), a light in a corner of a
//! room of rectangles or of a mesh sent the light it aimed through the
//! other walls out of the room (7.2 lx against 16.2 at a ceiling point),
//! and a light on a mesh cabinet's top edge lit nothing below the top's
//! plane (a reviewer's find).
//!
//! A direction that meets a face at the light reflects there and is
//! tested against the seat again (a room's corner can send it into another
//! face at once).

use glam::DVec3;

/// One face through the light.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Face {
    surface: u32,
    /// The primitive (a mesh's triangle; 0 otherwise).
    prim: u32,
    /// Unit normal of the reflecting side the light stands on.
    n: DVec3,
    /// In-plane unit vectors into the face across its edges through the
    /// light (none: the whole plane near the light).
    edges: [DVec3; 2],
    n_edges: usize,
}

/// The faces a point-like light stands on ([`Self::new`]) and the
/// bisector its limit is taken along.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSeat {
    faces: Vec<Face>,
    /// Unit bisector of the faces' reflecting normals.
    b: DVec3,
}

/// One face offered to [`LightSeat::new`]: `(surface, primitive, unit
/// normal of its reflecting side (the geometric one where both sides
/// reflect), in-plane unit vectors into the face across its edges through
/// the light (at most two; none in its interior), whether both sides
/// reflect)`.
pub type SeatFace<'a> = (u32, u32, DVec3, &'a [DVec3], bool);

impl LightSeat {
    /// A seat on those of `faces` the light can stand in front of all at
    /// once; `None` without faces. One-sided faces come first, interiors
    /// before rims, then two-sided ones turned to the side of those; a face
    /// is kept where the bisector of the kept normals with its own stays in
    /// front of each of them. So a face lying against another and facing the
    /// other way (a cabinet's bottom on the floor, its back against a
    /// wall, a two-sided picture whose normal points into its wall) does
    /// not take the light to its side: summed with the other's normal it
    /// cancelled it, and the light lost what it sent into the floor or the
    /// wall (a reviewer's find).
    pub fn new(faces: &[SeatFace<'_>]) -> Option<Self> {
        let first = faces.first()?;
        // The order faces are offered in: one-sided before two-sided, and
        // a face's interior before its rims (the floor before a cabinet's
        // bottom edge on it, whatever the order of the scene file).
        let mut order: Vec<usize> = (0..faces.len()).collect();
        order.sort_by_key(|&k| (faces[k].4, faces[k].3.len()));
        // The side each face is kept with, if kept.
        let mut side: Vec<Option<DVec3>> = vec![None; faces.len()];
        let mut normals: Vec<DVec3> = Vec::new();
        for k in order {
            let (_, _, n, _, both) = faces[k];
            let n = match normals.iter().sum::<DVec3>().normalize_or_zero() {
                b if both && n.dot(b) < 0.0 => -n,
                _ => n,
            };
            let fresh = !normals.iter().any(|m| m.dot(n) > 1.0 - 1e-12);
            let b = (normals.iter().sum::<DVec3>() + if fresh { n } else { DVec3::ZERO })
                .normalize_or_zero();
            if normals.iter().chain([&n]).all(|m| m.dot(b) > 1e-9) {
                if fresh {
                    normals.push(n);
                }
                side[k] = Some(n);
            }
        }
        // Kept faces in the order given (a rug listed before the floor it
        // lies on is met first where both are).
        let kept = faces
            .iter()
            .zip(&side)
            .filter_map(|(&(surface, prim, _, edges, _), n)| {
                let k = edges.len().min(2);
                let mut e = [DVec3::ZERO; 2];
                e[..k].copy_from_slice(&edges[..k]);
                n.map(|n| Face {
                    surface,
                    prim,
                    n,
                    edges: e,
                    n_edges: k,
                })
            })
            .collect();
        let b = normals.iter().sum::<DVec3>().normalize_or(first.2);
        Some(Self { faces: kept, b })
    }

    /// The unit bisector of the faces' reflecting normals: the light stands
    /// just off its position along it.
    pub fn bisector(&self) -> DVec3 {
        self.b
    }

    /// Whether the light stands on one face only: a collision there hides
    /// nothing from a point that its own cosine does not (the face's back
    /// half-space), so [`Self::hides`] need not be asked of its scores.
    pub fn single_face(&self) -> bool {
        self.faces.len() == 1
    }

    /// The faces: `(surface, unit normal of the light's side)`.
    pub fn faces(&self) -> impl Iterator<Item = (u32, DVec3)> + '_ {
        self.faces.iter().map(|f| (f.surface, f.n))
    }

    /// The face that direction `d` (any length) from the light meets at
    /// once: the first whose plane it crosses inside the face, seen from
    /// `p + e b`; ties go to the first listed.
    #[inline]
    fn met(&self, d: DVec3) -> Option<&Face> {
        let mut best: Option<(f64, &Face)> = None;
        for f in &self.faces {
            let dn = f.n.dot(d);
            let bn = f.n.dot(self.b);
            if dn >= 0.0 || bn <= 0.0 {
                continue;
            }
            // Where the ray from b crosses the face's plane, relative to
            // the light, in units of e.
            let s = bn / -dn;
            let x = self.b + s * d;
            if f.edges[..f.n_edges].iter().all(|e| e.dot(x) >= 0.0)
                && best.is_none_or(|(t, _)| s < t)
            {
                best = Some((s, f));
            }
        }
        best.map(|(_, f)| f)
    }

    /// The surface and the unit normal of the face that direction `d` (any
    /// length) from the light meets at once, at the light's position;
    /// `None` where `d` leaves the light freely.
    #[inline]
    pub fn meets(&self, d: DVec3) -> Option<(u32, DVec3)> {
        self.met(d).map(|f| (f.surface, f.n))
    }

    /// [`Self::meets`] with the face's primitive (a mesh's triangle; 0
    /// otherwise).
    #[inline]
    pub fn meets_prim(&self, d: DVec3) -> Option<(u32, DVec3, u32)> {
        self.met(d).map(|f| (f.surface, f.n, f.prim))
    }

    /// Whether point `x` lies where the light at `p` cannot reach it
    /// straight: behind the seat.
    #[inline]
    pub fn hides(&self, p: DVec3, x: DVec3) -> bool {
        self.met(x - p).is_some()
    }

    /// The surface and primitive that a direction `d` which leaves freely
    /// ([`Self::meets`] is `None`) leaves (for
    /// [`crate::scene::Scene::intersect`]'s `from`): the face it points out
    /// of most (a box's face it leaves is never met again at the light; one
    /// it enters it meets at its exit).
    #[inline]
    pub fn leaves(&self, d: DVec3) -> (u32, u32) {
        let faces = &self.faces;
        let mut best = &faces[0];
        for f in &faces[1..] {
            if f.n.dot(d) > best.n.dot(d) {
                best = f;
            }
        }
        (best.surface, best.prim)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light on one surface `s` with the unit normal `n` of its side,
    /// on the rim of a flat shape where `rims` are given.
    fn flat(s: u32, n: DVec3, rims: &[DVec3]) -> LightSeat {
        LightSeat::new(&[(s, 0, n, rims, false)]).unwrap()
    }

    #[test]
    fn a_flat_seat_darkens_its_back_half_space() {
        let s = flat(3, DVec3::Z, &[]);
        assert_eq!(s.meets(DVec3::new(0.3, 0.1, -0.2)), Some((3, DVec3::Z)));
        assert_eq!(s.meets(DVec3::new(0.3, 0.1, 0.2)), None);
        assert_eq!(s.leaves(DVec3::new(0.3, 0.1, 0.2)), (3, 0));
    }

    #[test]
    fn a_rim_darkens_only_directions_through_the_shape() {
        // On the edge u = 0 of a rectangle in z = 0 lying at x > 0.
        let s = flat(1, DVec3::Z, &[DVec3::X]);
        assert!(s.hides(DVec3::ZERO, DVec3::new(0.5, 0.0, -1.0)));
        assert!(!s.hides(DVec3::ZERO, DVec3::new(-0.5, 0.0, -1.0)));
        assert!(!s.hides(DVec3::ZERO, DVec3::new(0.5, 0.0, 1.0)));
        // A corner: both edges.
        let c = flat(1, DVec3::Z, &[DVec3::X, DVec3::Y]);
        assert!(c.hides(DVec3::ZERO, DVec3::new(0.5, 0.5, -1.0)));
        assert!(!c.hides(DVec3::ZERO, DVec3::new(0.5, -0.5, -1.0)));
    }

    #[test]
    fn a_solid_edge_darkens_its_wedge_and_a_room_edge_all_but_its_wedge() {
        // A desk's top (normal +z) and front (normal -y) faces.
        let top = (10, DVec3::Z);
        let front = (11, -DVec3::Y);
        // Each face extends into the desk across the other's edge.
        let desk = LightSeat::new(&[
            (10, 0, DVec3::Z, &[DVec3::Y], false),
            (11, 0, -DVec3::Y, &[-DVec3::Z], false),
        ])
        .unwrap();
        // Up over the desk, down in front of it: free.
        assert_eq!(desk.meets(DVec3::new(0.0, 1.0, 1.0)), None);
        assert_eq!(desk.meets(DVec3::new(0.0, -1.0, -1.0)), None);
        // Into the desk, mostly horizontal: it crosses the front plane
        // first, above the top, and enters through the top.
        assert_eq!(desk.meets(DVec3::new(0.0, 1.0, -0.1)), Some(top));
        assert_eq!(desk.meets(DVec3::new(0.0, 0.1, -1.0)), Some(front));
        assert_eq!(desk.leaves(DVec3::new(0.0, 1.0, 1.0)), (10, 0));
        assert_eq!(desk.leaves(DVec3::new(0.0, -1.0, -1.0)), (11, 0));
        // A room's ceiling (normal -z) and wall x = 0 (normal +x).
        let ceiling = (20, -DVec3::Z);
        let wall = (21, DVec3::X);
        let room = LightSeat::new(&[
            (21, 0, DVec3::X, &[-DVec3::Z], false),
            (20, 0, -DVec3::Z, &[DVec3::X], false),
        ])
        .unwrap();
        assert_eq!(room.meets(DVec3::new(1.0, 0.0, -1.0)), None);
        // Out through the wall only, or first through the wall.
        assert_eq!(room.meets(DVec3::new(-1.0, 0.0, -1.0)), Some(wall));
        assert_eq!(room.meets(DVec3::new(-1.0, 0.0, 0.1)), Some(wall));
        assert_eq!(room.meets(DVec3::new(-0.1, 0.0, 1.0)), Some(ceiling));
    }

    #[test]
    fn a_room_corner_of_three_faces_and_a_rug_rim_on_the_floor() {
        // The corner x = y = z = 0 of a room: each wall extends along the
        // other two axes.
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        let corner = LightSeat::new(&[
            (0, 0, x, &[y, z], false),
            (1, 0, y, &[x, z], false),
            (2, 0, z, &[x, y], false),
        ])
        .unwrap();
        assert_eq!(corner.meets(DVec3::new(1.0, 2.0, 3.0)), None);
        assert_eq!(corner.meets(DVec3::new(-1.0, 2.0, 3.0)), Some((0, x)));
        // Out through two walls: the first crossed, the steeper.
        assert_eq!(corner.meets(DVec3::new(-2.0, -1.0, 3.0)), Some((0, x)));
        assert_eq!(corner.meets(DVec3::new(-1.0, -2.0, 3.0)), Some((1, y)));
        // A rug (x > 0) on the floor, the light on its rim: down over the
        // rug it meets the rug (listed first), down beyond it the floor.
        let rug = LightSeat::new(&[(5, 0, z, &[x], false), (6, 0, z, &[], false)]).unwrap();
        assert_eq!(rug.meets(DVec3::new(0.5, 0.0, -1.0)), Some((5, z)));
        assert_eq!(rug.meets(DVec3::new(-0.5, 0.0, -1.0)), Some((6, z)));
        assert_eq!(rug.meets(DVec3::new(-0.5, 0.0, 1.0)), None);
    }

    #[test]
    fn a_face_against_another_facing_away_does_not_take_the_light() {
        let (y, z) = (DVec3::Y, DVec3::Z);
        // The floor (+z), a cabinet's bottom on it (-z) and its front (-y),
        // the light on the front's foot: down in front of the cabinet it
        // meets the floor.
        let foot = LightSeat::new(&[
            (0, 0, z, &[], false),
            (1, 0, -z, &[y], false),
            (2, 0, -y, &[z], false),
        ])
        .unwrap();
        assert_eq!(foot.faces().count(), 2);
        assert_eq!(foot.meets(DVec3::new(0.0, -1.0, -1.0)), Some((0, z)));
        assert_eq!(foot.meets(DVec3::new(0.0, 1.0, 0.5)), Some((2, -y)));
        assert_eq!(foot.meets(DVec3::new(0.0, -1.0, 1.0)), None);
        // A two-sided rug whose normal points down into the floor, listed
        // first: turned up, to the floor's side.
        let rug = LightSeat::new(&[(5, 0, -z, &[], true), (6, 0, z, &[], false)]).unwrap();
        assert_eq!(rug.meets(DVec3::new(0.3, 0.0, 1.0)), None);
        assert!(rug.meets(DVec3::new(0.3, 0.0, -1.0)).is_some());
    }
}
