//! Which side of a face of a closed two-sided mesh a point on it belongs
//! to: the side a receiver edge-on to the face is lifted to
//! ([`Scene::lift_to_its_side`]), and the side a light standing on it
//! stands on ([`Scene::light_surface`]).
//!
//! A closed mesh cuts space into regions, told apart by their winding
//! numbers ([`mesh_parity::winding`]: 0 outside, 1 inside one shell wound
//! outward, 2 inside a cabinet modelled in the same OBJ as its room), and
//! no light crosses it. Two-sided, it reflects into both regions at each
//! face, but where one of them holds no light it is dark. So:
//!
//! 1. where the scene's content (lights off the mesh, lights at
//!    infinity, other shapes, planes clear of the mesh's bounds) lies in
//!    the region on one side of the face only, that side (a lamp on a
//!    cabinet in a room; a floor point at a cabinet mesh's foot);
//! 2. else (content on both sides, or none) the side of the smaller
//!    nonzero winding number: inside the outermost shell (a luminaire on
//!    the ceiling of a room given as an OBJ, with or without a sun outside
//!    or a ground plane under it), outside an inner one (a lamp on a
//!    cabinet modelled in the room's OBJ).
//!
//! A point evaluated on the face saw past it on both sides, as past a
//! sheet, and so counted the dark side: a room mesh's wall foot read 7.84
//! against 10.33 lx a micrometre into the room. A light on the ceiling of
//! a two-sided room mesh wound outward (the usual OBJ convention) stood
//! outside, on the geometric normal's side, and the room read 0 lx
//! everywhere, with no error and no flag. Rule 2 takes a lamp on a lone
//! closed object with nothing else in the scene (or only a ground plane
//! touching it) as inside the object: give such a lamp a height.

use super::{Scene, on_mesh_tol};
use crate::geometry::mesh::Mesh;
use crate::geometry::mesh_parity;
use glam::DVec3;

/// Per mesh of a scene, found on first use and kept until the lights
/// change: the winding numbers of the regions that hold the scene's content
/// ([`Scene::content_windings`]).
#[derive(Clone, Default)]
pub(super) struct MeshLitSide(std::sync::OnceLock<Vec<std::sync::OnceLock<Vec<i64>>>>);

/// Found on demand, so it is left out of the scene's `Debug` text (which
/// names a run in its state files, and must not depend on what a run
/// asked first).
impl std::fmt::Debug for MeshLitSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("MeshLitSide")
    }
}

impl Scene {
    /// The unit normal of the side a point on a triangle (corners `v`,
    /// geometric normal `ng`) of the `i`-th mesh belongs to ([module
    /// docs](self)); `None` for an open mesh or where the sides' winding
    /// numbers cannot be found. A light standing on the mesh is no content
    /// of it (it lies on the surface), so a light's own seat is found with
    /// the same content as a receiver's side.
    pub(super) fn lit_side_of_face(&self, i: usize, v: &[DVec3; 3], ng: DVec3) -> Option<DVec3> {
        let m = &self.meshes[i].0;
        if !m.is_closed() {
            return None;
        }
        // Off the face's middle, a millionth of the mesh's size each way.
        let c = (v[0] + v[1] + v[2]) / 3.0;
        let h = 1e-6 * size(m);
        let (wp, wm) = (
            mesh_parity::winding(m, c + h * ng)?,
            mesh_parity::winding(m, c - h * ng)?,
        );
        let content = self.content_of(i);
        let plus = match (content.contains(&wp), content.contains(&wm)) {
            (true, false) => true,
            (false, true) => false,
            _ => match (wp.abs(), wm.abs()) {
                (0, _) => false,
                (_, 0) => true,
                (a, b) => a < b,
            },
        };
        Some(if plus { ng } else { -ng })
    }

    /// Whether `q` lies in a region of a closed mesh that holds no light
    /// (its winding number is none of the lights': a cabinet mesh's
    /// inside, the outside of a room mesh with every light inside and no
    /// sky). No light crosses a closed mesh, whichever sides reflect.
    /// A light standing on surfaces counts from just off its seat, in the
    /// region it lights ([`Scene::light_shadow_origin`]: a downlight on a
    /// room mesh's ceiling is inside), a sphere light by its centre where
    /// its ball keeps clear of the mesh. `false` where that cannot be
    /// told: an open mesh, an area light, a sphere light touching the
    /// mesh, a winding number not found.
    pub(super) fn in_dark_mesh_region(&self, q: DVec3) -> bool {
        use crate::light::Light;
        self.meshes.iter().any(|(m, _)| {
            if !m.is_closed() {
                return false;
            }
            let tol = on_mesh_tol(m);
            let mut lit = Vec::new();
            for (k, l) in self.lights.iter().enumerate() {
                let at = match l {
                    _ if l.is_directional() => {
                        lit.push(0);
                        continue;
                    }
                    Light::Sphere { c, r, .. } => {
                        if !m.triangles_through(*c, *r + tol).is_empty() {
                            return false;
                        }
                        *c
                    }
                    _ if l.is_point_like() => match self.light_surface(k) {
                        Some(_) => self.light_shadow_origin(k),
                        None => l.position(),
                    },
                    _ => return false,
                };
                if !m.triangles_through(at, tol).is_empty() {
                    return false;
                }
                match mesh_parity::winding(m, at) {
                    Some(w) => lit.push(w),
                    None => return false,
                }
            }
            mesh_parity::winding(m, q).is_some_and(|w| !lit.contains(&w))
        })
    }

    /// The `i`-th mesh's content windings ([`Self::content_windings`]),
    /// found once.
    fn content_of(&self, i: usize) -> &[i64] {
        let all = self
            .mesh_lit_side
            .0
            .get_or_init(|| (0..self.meshes.len()).map(|_| Default::default()).collect());
        all[i].get_or_init(|| self.content_windings(i))
    }

    /// The winding numbers of the `i`-th mesh (closed) at the scene's
    /// content: each light off the mesh at its
    /// position, lights at infinity and planes clear of the mesh's bounds
    /// outside (0), each other finite shape at its bounds' centre, or
    /// outside where its bounds reach beyond the mesh's. Sorted, each once.
    fn content_windings(&self, i: usize) -> Vec<i64> {
        let m = &self.meshes[i].0;
        let (lo, hi) = m.bounds();
        let tol = on_mesh_tol(m);
        let (lo, hi) = (lo - DVec3::splat(tol), hi + DVec3::splat(tol));
        let mut w = Vec::new();
        for l in &self.lights {
            if l.is_directional() {
                w.push(0);
            } else if m.triangles_through(l.position(), tol).is_empty() {
                w.extend(mesh_parity::winding(m, l.position()));
            }
        }
        // A plane that meets the bounds (a ground plane under a room mesh)
        // is not counted: it may be the mesh's own floor.
        let corners = (0..8).map(|k| {
            DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            )
        });
        for pl in &self.planes {
            let sides: Vec<f64> = corners.clone().map(|q| pl.n.dot(q - pl.p)).collect();
            if sides.iter().all(|&d| d > 0.0) || sides.iter().all(|&d| d < 0.0) {
                w.push(0);
            }
        }
        for (a, b) in self.shape_bounds_except_mesh(i) {
            if (a - lo).min_element() < 0.0 || (hi - b).min_element() < 0.0 {
                w.push(0);
            } else {
                w.extend(mesh_parity::winding(m, 0.5 * (a + b)));
            }
        }
        w.sort_unstable();
        w.dedup();
        w
    }
}

/// The length of a mesh's bounds' diagonal \[m\].
fn size(m: &Mesh) -> f64 {
    let (lo, hi) = m.bounds();
    (hi - lo).length()
}
