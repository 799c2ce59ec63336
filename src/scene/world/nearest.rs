//! Which surface a ray meets first, from the set of its hits: the tie rules
//! of the nearest-hit query, written so that the answer does not depend on
//! the order in which the shapes were tested (the linear loops and the
//! top-level BVH test them in different orders and must agree bit for bit).
//!
//! Hits fall in four classes: infinite *planes*, *flat* surfaces
//! (rectangles, discs) that do not emit, *emitters* (the rectangles and
//! discs of area sources), and *solids* (spheres, boxes, meshes). In each
//! class the nearest hit counts, ties in `t` going to the smaller key (the
//! shape's place in the fixed order planes, rectangles, discs, spheres,
//! boxes, meshes). Then, where two surfaces coincide, the one set onto the
//! other is met, whatever the rounding of their two hit distances (each
//! comparison with the relative tolerance [`COINCIDENT_TIE`]):
//!
//! - a rectangle or disc lying in a plane (a door in a wall given as a
//!   plane) wins over it: the nearest flat surface is met unless the
//!   nearest plane is nearer by more than the tolerance, `t_f < t_p (1 +
//!   COINCIDENT_TIE)`;
//! - an emitter set into a surface (a panel in the ceiling's plane) is met
//!   where the two coincide: the nearest emitter wins over the flat hit so
//!   far unless that one is nearer by more than the tolerance, `t_e < t_f
//!   (1 + COINCIDENT_TIE)`;
//! - a solid must beat the winning flat hit by more than the tolerance, `t_s
//!   < t_f (1 - COINCIDENT_TIE)`: a rectangle or disc lying on a box's or a
//!   mesh's face (a rug on the floor of a room box, a door in its wall) is
//!   met, not the face. (A solid used to win such ties by a few ulps about
//!   half the time: the rug read 12 % dark, the door 21 %, and a door in a
//!   wall plane lost every tie to the plane, 0 lx.)
//!
//! **Facing.** Two surfaces can coincide back to back (a thin panel given
//! as two one-sided rectangles, or as two triangles of opposite winding, as
//! exporters write "double-sided" faces): the ray must meet the one whose
//! reflecting side faces it, not its black back. So every hit records
//! whether the side the ray arrives at reflects ([`Cand::lit`],
//! [`super::Sides::lit`]): in a class, a lit hit within the tolerance of
//! the nearest one, when that shows its black side, is met instead. (The first listed of two such rectangles used
//! to win every tie: behind it, 0 lx of reflected light.) Within one mesh,
//! the triangle facing the ray wins near ties
//! ([`crate::geometry::mesh::Mesh::first_hit`]). Across classes the rules
//! above stand, black side or not: a surface set onto another covers it (a
//! panel luminaire facing into the ceiling hides the ceiling behind its
//! black back).
//!
//! (The loops this replaced applied the same thresholds in list order; they
//! agree except where two emitters, or an emitter and two other flat
//! surfaces, lie within 1e-9 of each other along the ray.) SH objects come
//! after all of this, in index order ([`super::Scene`]).
//!
//! **Pruning.** The answer's `t` lies within a factor `1 / (1 -
//! COINCIDENT_TIE)` of the nearest hit of any class, so a hit further than
//! [`PRUNE`] (relative) beyond the nearest one found so far can change
//! nothing: the queries test shapes only up to [`Nearest::bound`].

use super::COINCIDENT_TIE;

/// Relative margin beyond the nearest hit found so far within which hits
/// are still collected (ten times [`COINCIDENT_TIE`]: every hit further away
/// loses to the nearest one whatever its class).
const PRUNE: f64 = 1e-8;

/// One hit: ray parameter \[m\], the shape's key in the fixed order, its
/// surface and primitive.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cand {
    pub(super) t: f64,
    pub(super) key: u32,
    pub(super) surface: u32,
    pub(super) prim: u32,
    /// Whether the side of the surface the ray arrives at reflects (or
    /// emits): see the module docs, "Facing".
    pub(super) lit: bool,
}

const NONE: Cand = Cand {
    t: f64::INFINITY,
    key: u32::MAX,
    surface: u32::MAX,
    prim: 0,
    lit: false,
};

impl Cand {
    /// Whether `self` is nearer than `other`, ties to the smaller key (a
    /// total order: the answer does not depend on the order of the offers).
    #[inline(always)]
    fn before(&self, other: &Cand) -> bool {
        self.t < other.t || (self.t == other.t && self.key < other.key)
    }
}

/// One class's hits so far: the nearest, and the nearest of those whose
/// side facing the ray reflects. Both are minima of a total order, so the
/// class's answer ([`Slot::winner`]) does not depend on the order of the
/// offers.
#[derive(Clone, Copy, Debug)]
struct Slot {
    near: Cand,
    lit: Cand,
}

impl Slot {
    const EMPTY: Slot = Slot {
        near: NONE,
        lit: NONE,
    };

    #[inline(always)]
    fn offer(&mut self, c: Cand) {
        if c.before(&self.near) {
            self.near = c;
        }
        if c.lit && c.before(&self.lit) {
            self.lit = c;
        }
    }

    /// The nearest hit, unless it shows its black side and a lit one
    /// coincides with it within [`COINCIDENT_TIE`] (two one-sided surfaces
    /// back to back, whose hit distances differ by rounding).
    #[inline(always)]
    fn winner(&self) -> Cand {
        if !self.near.lit && self.lit.t <= self.near.t * (1.0 + COINCIDENT_TIE) {
            self.lit
        } else {
            self.near
        }
    }
}

/// The hits of each class so far.
#[derive(Clone, Copy, Debug)]
pub(super) struct Nearest {
    plane: Slot,
    flat: Slot,
    emitter: Slot,
    solid: Slot,
    /// Hits at or beyond this `t` \[m\] cannot change the answer.
    pub(super) bound: f64,
}

impl Nearest {
    /// No hit yet.
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self {
            plane: Slot::EMPTY,
            flat: Slot::EMPTY,
            emitter: Slot::EMPTY,
            solid: Slot::EMPTY,
            bound: f64::INFINITY,
        }
    }

    #[inline(always)]
    fn lower_bound(&mut self, t: f64) {
        self.bound = self.bound.min(t * (1.0 + PRUNE));
    }

    /// A hit on an infinite plane.
    #[inline(always)]
    pub(super) fn plane(&mut self, c: Cand) {
        self.plane.offer(c);
        self.lower_bound(c.t);
    }

    /// A hit on a rectangle or disc (an area source's when `emitter`).
    #[inline(always)]
    pub(super) fn flat(&mut self, c: Cand, emitter: bool) {
        if emitter {
            self.emitter.offer(c);
        } else {
            self.flat.offer(c);
        }
        self.lower_bound(c.t);
    }

    /// A hit on a sphere, box or mesh.
    #[inline(always)]
    pub(super) fn solid(&mut self, c: Cand) {
        self.solid.offer(c);
        self.lower_bound(c.t);
    }

    /// The winning hit and whether it is an emitter's; `None` without hits.
    #[inline]
    pub(super) fn resolve(&self) -> Option<(Cand, bool)> {
        let (plane, flat, emitter, solid) = (
            self.plane.winner(),
            self.flat.winner(),
            self.emitter.winner(),
            self.solid.winner(),
        );
        let flat = if flat.t < plane.t * (1.0 + COINCIDENT_TIE) {
            flat
        } else {
            plane
        };
        let (f, emitter) = if emitter.t < flat.t * (1.0 + COINCIDENT_TIE) {
            (emitter, true)
        } else {
            (flat, false)
        };
        let threshold = f.t * (1.0 - COINCIDENT_TIE);
        if solid.t < threshold {
            Some((solid, false))
        } else if f.t < f64::INFINITY {
            Some((f, emitter))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(t: f64, key: u32) -> Cand {
        Cand {
            t,
            key,
            surface: key,
            prim: 0,
            lit: true,
        }
    }

    /// Every ordering of `0..n`.
    fn permutations(n: usize) -> Vec<Vec<usize>> {
        if n == 0 {
            return vec![vec![]];
        }
        let mut out = vec![];
        for p in permutations(n - 1) {
            for k in 0..=p.len() {
                let mut q = p.clone();
                q.insert(k, n - 1);
                out.push(q);
            }
        }
        out
    }

    /// Every order of the same hits gives the same answer, and the rules
    /// pick what the module docs say.
    #[test]
    fn answer_is_independent_of_the_order_and_follows_the_rules() {
        // (t, key, class: 0 flat, 1 emitter, 2 solid, 3 plane), expected
        // winner key.
        let tie = 0.5 * COINCIDENT_TIE;
        type Hits = Vec<(f64, u32, u8)>;
        let cases: Vec<(Hits, Option<u32>)> = vec![
            (vec![], None),
            (vec![(2.0, 3, 0), (1.0, 5, 0)], Some(5)),
            // Equal t: the smaller key.
            (vec![(1.0, 7, 0), (1.0, 4, 0), (1.0, 9, 0)], Some(4)),
            // Emitter just behind a flat surface (within the tie): emitter.
            (vec![(1.0, 1, 0), (1.0 + tie, 9, 1)], Some(9)),
            (vec![(1.0, 1, 0), (1.0 + 3.0 * tie, 9, 1)], Some(1)),
            // Flat surface just in front of an emitter: still the emitter.
            (vec![(1.0, 9, 1), (1.0 - tie, 1, 0)], Some(9)),
            // A solid must beat an emitter or a flat surface clearly.
            (vec![(1.0, 9, 1), (1.0 - tie, 20, 2)], Some(9)),
            (vec![(1.0, 9, 1), (1.0 - 3.0 * tie, 20, 2)], Some(20)),
            (vec![(1.0, 2, 0), (1.0, 20, 2)], Some(2)),
            (vec![(1.0, 2, 0), (1.0 - tie, 20, 2)], Some(2)),
            (vec![(1.0, 2, 0), (1.0 - 3.0 * tie, 20, 2)], Some(20)),
            (vec![(1.0, 2, 0), (0.999, 20, 2)], Some(20)),
            // A rectangle in a plane wins over it, within the tie; a plane
            // clearly nearer wins, and loses to a solid as a flat does.
            (vec![(1.0, 0, 3), (1.0 + tie, 5, 0)], Some(5)),
            (vec![(1.0 + tie, 0, 3), (1.0, 5, 0)], Some(5)),
            (vec![(1.0, 0, 3), (1.0 + 3.0 * tie, 5, 0)], Some(0)),
            (vec![(1.0, 0, 3), (1.0 - tie, 20, 2)], Some(0)),
            (
                vec![(1.0, 0, 3), (1.0 + tie, 5, 0), (1.0 + 2.0 * tie, 9, 1)],
                Some(9),
            ),
            (vec![(1.0, 1, 3), (1.0, 0, 3)], Some(0)),
            (vec![(1.0, 20, 2), (1.0, 21, 2)], Some(20)),
            // Two emitters: the nearer.
            (vec![(1.0 + tie, 9, 1), (1.0, 8, 1), (1.0, 1, 0)], Some(8)),
        ];
        for (hits, want) in cases {
            for p in permutations(hits.len()) {
                let mut acc = Nearest::new();
                for &i in &p {
                    let (t, key, class) = hits[i];
                    match class {
                        0 => acc.flat(c(t, key), false),
                        1 => acc.flat(c(t, key), true),
                        2 => acc.solid(c(t, key)),
                        _ => acc.plane(c(t, key)),
                    }
                }
                let got = acc.resolve().map(|(h, _)| h.key);
                assert_eq!(got, want, "{hits:?} in order {p:?}");
            }
        }
    }

    /// Of coincident hits in a class (within the tolerance), the one whose
    /// reflecting side faces the ray; across classes the rules above; in
    /// every order.
    #[test]
    fn a_lit_side_wins_a_tie_in_its_class() {
        let tie = 0.5 * COINCIDENT_TIE;
        // (t, key, class as above, lit), expected winner key.
        type Hits = Vec<(f64, u32, u8, bool)>;
        let cases: Vec<(Hits, Option<u32>)> = vec![
            // Equal t in a class: the lit one, whatever the keys.
            (vec![(1.0, 4, 0, false), (1.0, 7, 0, true)], Some(7)),
            (vec![(1.0, 20, 2, false), (1.0, 21, 2, true)], Some(21)),
            (vec![(1.0, 1, 3, false), (1.0, 0, 3, true)], Some(0)),
            // Within the tolerance in a class: the lit one too (rounding
            // of two back-to-back tilted rectangles' distances) ...
            (vec![(1.0, 4, 0, false), (1.0 + tie, 7, 0, true)], Some(7)),
            (vec![(1.0 + tie, 4, 2, true), (1.0, 7, 2, false)], Some(4)),
            (
                vec![
                    (1.0, 4, 0, false),
                    (1.0 + tie, 7, 0, true),
                    (1.0 + 0.5 * tie, 8, 0, true),
                ],
                Some(8),
            ),
            // ... but not beyond it: the nearer, lit or not.
            (
                vec![(1.0, 4, 0, false), (1.0 + 3.0 * tie, 7, 0, true)],
                Some(4),
            ),
            (vec![(1.0, 4, 0, true), (1.0 + tie, 7, 0, false)], Some(4)),
            // Across classes the rules stand: the surface set onto the
            // other covers it, black side or not.
            (vec![(1.0, 0, 3, true), (1.0 + tie, 5, 0, false)], Some(5)),
            (vec![(1.0, 2, 0, false), (1.0 - tie, 20, 2, true)], Some(2)),
            (vec![(1.0, 2, 0, true), (1.0, 9, 1, false)], Some(9)),
            // Both black: the rules as before.
            (vec![(1.0, 0, 3, false), (1.0 + tie, 5, 0, false)], Some(5)),
        ];
        for (hits, want) in cases {
            for p in permutations(hits.len()) {
                let mut acc = Nearest::new();
                for &i in &p {
                    let (t, key, class, lit) = hits[i];
                    let h = Cand { lit, ..c(t, key) };
                    match class {
                        0 => acc.flat(h, false),
                        1 => acc.flat(h, true),
                        2 => acc.solid(h),
                        _ => acc.plane(h),
                    }
                }
                let got = acc.resolve().map(|(h, _)| h.key);
                assert_eq!(got, want, "{hits:?} in order {p:?}");
            }
        }
    }
}
