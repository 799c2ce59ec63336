//! Where a point-like light stands on surfaces (its *seat*), and which of
//! its directions meet a surface at once.
//!
//! **Rule**: a light exactly on a surface belongs to the surface's
//! reflecting side, as if it stood just in front of it; the answer is the
//! limit as the light approaches from that side. Light it emits into the
//! surface meets the surface at once, at the light's position, and points
//! behind the surface do not see it. On a face of a box, a sphere or the
//! inside of a flat shape this darkens a half-space. On an edge the limit
//! is not a half-space; it is taken along the bisector of the faces
//! through the light (along the normal off a flat shape's rim):
//!
//! - **a solid's edge or corner** (a box with outward normals: a lamp on a
//!   desk's front edge): a direction meets the solid only if it points into
//!   every face through the light (the solid's cone there), and then meets
//!   the face whose plane it crosses last (the least steep one);
//! - **a room's edge or corner** (a box with inward normals: a luminaire
//!   where a wall meets the ceiling): a direction leaves the room through
//!   any face it points out of, and meets the face it crosses first (the
//!   steepest);
//! - **the rim of a rectangle or disc**: a direction into the back of the
//!   shape meets it only where it crosses the plane inside the shape, that
//!   is, where it also points into the shape across every edge through the
//!   light.
//!
//! A direction that meets a face at the light reflects there and is
//! tested against the seat again (a room's corner can send it into another
//! face at once).

use glam::DVec3;

/// How the faces of a seat combine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Joint {
    /// One surface (in front of a face, a sphere or a flat shape).
    One,
    /// A solid's edge or corner: dark only into every face.
    Solid,
    /// A room's edge or corner: dark into any face.
    Room,
}

/// The surfaces a point-like light stands on, with the unit normals of the
/// sides it belongs to, and for a light on a flat shape's rim, the
/// in-plane unit vectors into the shape across each edge through it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSeat {
    joint: Joint,
    /// The primitive of a one-surface seat (a mesh's triangle; 0 otherwise).
    prim: u32,
    faces: [(u32, DVec3); 3],
    n_faces: usize,
    rims: [DVec3; 2],
    n_rims: usize,
}

impl LightSeat {
    /// A light on one surface `s` with the unit normal `n` of its side,
    /// on the rim of a flat shape where `rims` (in-plane unit vectors into
    /// the shape, at most two) are given.
    pub fn flat(s: u32, n: DVec3, rims: &[DVec3]) -> Self {
        let mut r = [DVec3::ZERO; 2];
        let n_rims = rims.len().min(2);
        r[..n_rims].copy_from_slice(&rims[..n_rims]);
        Self {
            joint: Joint::One,
            prim: 0,
            faces: [(s, n); 3],
            n_faces: 1,
            rims: r,
            n_rims,
        }
    }

    /// A light on one to three faces of a box, each `(surface, unit normal
    /// of the reflecting side)`; `solid`: the box reflects outward (the
    /// light stands outside it), else inward (inside a room).
    pub fn box_faces(faces: &[(u32, DVec3)], solid: bool) -> Self {
        assert!(
            (1..=3).contains(&faces.len()),
            "a point lies on 1 to 3 faces of a box"
        );
        let mut f = [faces[0]; 3];
        f[..faces.len()].copy_from_slice(faces);
        Self {
            prim: 0,
            joint: match (faces.len(), solid) {
                (1, _) => Joint::One,
                (_, true) => Joint::Solid,
                (_, false) => Joint::Room,
            },
            faces: f,
            n_faces: faces.len(),
            rims: [DVec3::ZERO; 2],
            n_rims: 0,
        }
    }

    /// The seat on triangle `tri` of a mesh (see [`Self::flat`]).
    pub fn on_triangle(self, tri: u32) -> Self {
        Self { prim: tri, ..self }
    }

    /// The primitive a face met or left is: a mesh's triangle, else 0.
    pub fn prim(&self) -> u32 {
        self.prim
    }

    /// The faces: `(surface, unit normal of the light's side)`.
    pub fn faces(&self) -> &[(u32, DVec3)] {
        &self.faces[..self.n_faces]
    }

    /// The surface and the unit normal of the face that direction `d` (any
    /// length) from the light meets at once, at the light's position;
    /// `None` where `d` leaves the light freely.
    #[inline]
    pub fn meets(&self, d: DVec3) -> Option<(u32, DVec3)> {
        let faces = self.faces();
        match self.joint {
            Joint::One => {
                let (s, n) = faces[0];
                (n.dot(d) < 0.0 && self.rims[..self.n_rims].iter().all(|e| e.dot(d) > 0.0))
                    .then_some((s, n))
            }
            // Into the solid's cone: crossing every face's plane, it enters
            // through the one crossed last, the least steep.
            Joint::Solid => faces
                .iter()
                .all(|(_, n)| n.dot(d) < 0.0)
                .then(|| Self::steepest(faces, d, false)),
            // Out of any face: the first crossed, the steepest.
            Joint::Room => faces
                .iter()
                .any(|(_, n)| n.dot(d) < 0.0)
                .then(|| Self::steepest(faces, d, true)),
        }
    }

    /// Whether point `x` lies where the light at `p` cannot reach it
    /// straight: behind the seat.
    #[inline]
    pub fn hides(&self, p: DVec3, x: DVec3) -> bool {
        self.meets(x - p).is_some()
    }

    /// The surface that a direction `d` which leaves freely ([`Self::meets`]
    /// is `None`) leaves (for [`crate::scene::Scene::intersect`]'s `from`):
    /// the face it points out of most (a box's face it leaves is never met
    /// again at the light; one it enters it meets at its exit).
    #[inline]
    pub fn leaves(&self, d: DVec3) -> u32 {
        let faces = self.faces();
        let mut best = faces[0];
        for &f in &faces[1..] {
            if f.1.dot(d) > best.1.dot(d) {
                best = f;
            }
        }
        best.0
    }

    /// Of the faces, the one with the most negative (`most`) or least
    /// negative `n . d`, first in order on ties.
    fn steepest(faces: &[(u32, DVec3)], d: DVec3, most: bool) -> (u32, DVec3) {
        let mut best = faces[0];
        for &f in &faces[1..] {
            let (a, b) = (f.1.dot(d), best.1.dot(d));
            if (most && a < b) || (!most && a > b) {
                best = f;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_seat_darkens_its_back_half_space() {
        let s = LightSeat::flat(3, DVec3::Z, &[]);
        assert_eq!(s.meets(DVec3::new(0.3, 0.1, -0.2)), Some((3, DVec3::Z)));
        assert_eq!(s.meets(DVec3::new(0.3, 0.1, 0.2)), None);
        assert_eq!(s.leaves(DVec3::new(0.3, 0.1, 0.2)), 3);
    }

    #[test]
    fn a_rim_darkens_only_directions_through_the_shape() {
        // On the edge u = 0 of a rectangle in z = 0 lying at x > 0.
        let s = LightSeat::flat(1, DVec3::Z, &[DVec3::X]);
        assert!(s.hides(DVec3::ZERO, DVec3::new(0.5, 0.0, -1.0)));
        assert!(!s.hides(DVec3::ZERO, DVec3::new(-0.5, 0.0, -1.0)));
        assert!(!s.hides(DVec3::ZERO, DVec3::new(0.5, 0.0, 1.0)));
        // A corner: both edges.
        let c = LightSeat::flat(1, DVec3::Z, &[DVec3::X, DVec3::Y]);
        assert!(c.hides(DVec3::ZERO, DVec3::new(0.5, 0.5, -1.0)));
        assert!(!c.hides(DVec3::ZERO, DVec3::new(0.5, -0.5, -1.0)));
    }

    #[test]
    fn a_solid_edge_darkens_its_wedge_and_a_room_edge_all_but_its_wedge() {
        // A desk's top (normal +z) and front (normal -y) faces.
        let top = (10, DVec3::Z);
        let front = (11, -DVec3::Y);
        let desk = LightSeat::box_faces(&[top, front], true);
        // Up over the desk, down in front of it: free.
        assert_eq!(desk.meets(DVec3::new(0.0, 1.0, 1.0)), None);
        assert_eq!(desk.meets(DVec3::new(0.0, -1.0, -1.0)), None);
        // Into the desk, mostly horizontal: it crosses the front plane
        // first, above the top, and enters through the top.
        assert_eq!(desk.meets(DVec3::new(0.0, 1.0, -0.1)), Some(top));
        assert_eq!(desk.meets(DVec3::new(0.0, 0.1, -1.0)), Some(front));
        assert_eq!(desk.leaves(DVec3::new(0.0, 1.0, 1.0)), 10);
        assert_eq!(desk.leaves(DVec3::new(0.0, -1.0, -1.0)), 11);
        // A room's ceiling (normal -z) and wall x = 0 (normal +x).
        let ceiling = (20, -DVec3::Z);
        let wall = (21, DVec3::X);
        let room = LightSeat::box_faces(&[wall, ceiling], false);
        assert_eq!(room.meets(DVec3::new(1.0, 0.0, -1.0)), None);
        // Out through the wall only, or first through the wall.
        assert_eq!(room.meets(DVec3::new(-1.0, 0.0, -1.0)), Some(wall));
        assert_eq!(room.meets(DVec3::new(-1.0, 0.0, 0.1)), Some(wall));
        assert_eq!(room.meets(DVec3::new(-0.1, 0.0, 1.0)), Some(ceiling));
    }
}
