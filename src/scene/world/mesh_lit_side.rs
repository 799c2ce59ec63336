//! Which side of a closed mesh the light is on: the side a receiver
//! edge-on to one of its two-sided faces belongs to
//! ([`Scene::lift_to_its_side`]), and the side a light standing on one of
//! them belongs to ([`Scene::light_surface`]).
//!
//! A closed mesh cuts space in two, and no light crosses it: the region
//! without a light is dark on both of a two-sided face's sides. A point on
//! such a face that faces along it (a floor point at the foot of a room
//! mesh's wall, facing up; a point on a cabinet mesh's side, facing up)
//! is the limit from the lit region. Evaluated on the face it saw past it
//! on both sides, as past a sheet, and so counted the dark half: a room
//! mesh's wall foot read 7.84 against 10.33 lx a micrometre into the room,
//! a two-sided cabinet mesh's side 58.4 against 67.8 lx beside it.
//!
//! The lights that can be placed (off the mesh; lights at infinity lie
//! outside) decide; where none can (every light stands on the mesh: a
//! room mesh's ceiling luminaires), the mesh is taken as the enclosure of
//! the scene where nothing else lies outside its bounds (no plane, no
//! other shape), else as an object in it. A light on the ceiling of a
//! two-sided room mesh wound outward (the usual OBJ convention) stood
//! outside the room, on the geometric normal's side, and lit nothing in
//! it (0 lx everywhere, with no error and no flag).

use super::{MESH_REL, Scene};
use crate::geometry::mesh::Mesh;
use crate::geometry::mesh_parity::{self, Side};
use crate::light::Light;
use glam::DVec3;

/// Per mesh of a scene, found on first use and kept until the lights
/// change: [`Scene::lit_side_of_mesh`] over all the lights.
#[derive(Clone, Default)]
pub(super) struct MeshLitSide(std::sync::OnceLock<Vec<std::sync::OnceLock<Option<bool>>>>);

/// Found on demand, so it is left out of the scene's `Debug` text (which
/// names a run in its state files, and must not depend on what a run
/// asked first).
impl std::fmt::Debug for MeshLitSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("MeshLitSide")
    }
}

impl Scene {
    /// [`Self::lit_side_of_mesh`] of the `i`-th mesh over all the lights,
    /// kept.
    pub(super) fn lights_outside_mesh(&self, i: usize) -> Option<bool> {
        let all = self
            .mesh_lit_side
            .0
            .get_or_init(|| (0..self.meshes.len()).map(|_| Default::default()).collect());
        *all[i].get_or_init(|| self.lit_side_of_mesh(i, None))
    }

    /// Whether the light of the scene lies outside (`Some(true)`) or inside
    /// (`Some(false)`) its `i`-th mesh, leaving light `except` out
    /// ([module docs](self)); `None` for an open mesh or lights on both
    /// sides.
    pub(super) fn lit_side_of_mesh(&self, i: usize, except: Option<usize>) -> Option<bool> {
        let m = &self.meshes[i].0;
        if !m.is_closed() {
            return None;
        }
        let mut outside = None;
        for (k, l) in self.lights.iter().enumerate() {
            if Some(k) == except {
                continue;
            }
            let out = match light_side(m, l) {
                Side::Outside => true,
                Side::Inside => false,
                Side::Unknown => continue,
            };
            if outside.is_some_and(|o| o != out) {
                return None;
            }
            outside = Some(out);
        }
        Some(outside.unwrap_or_else(|| self.anything_outside_mesh(i)))
    }

    /// Whether a plane, or a finite shape other than the `i`-th mesh
    /// reaching beyond its bounds, lies in the scene.
    fn anything_outside_mesh(&self, i: usize) -> bool {
        if !self.planes.is_empty() {
            return true;
        }
        let (lo, hi) = self.meshes[i].0.bounds();
        let pad = DVec3::splat(MESH_REL * (hi - lo).length());
        self.finite_bounds_except_mesh(Some(i))
            .is_some_and(|(a, b)| {
                (a - (lo - pad)).min_element() < 0.0 || (hi + pad - b).min_element() < 0.0
            })
    }
}

/// The side of closed mesh `m` that light `l` lies on: outside for a light
/// at infinity; `Unknown` for one on the mesh.
fn light_side(m: &Mesh, l: &Light) -> Side {
    if l.is_directional() {
        return Side::Outside;
    }
    let p = l.position();
    match mesh_parity::side(m, p) {
        Side::Unknown => {
            let (lo, hi) = m.bounds();
            if m.triangle_at(p, MESH_REL * (hi - lo).length()).is_some() {
                Side::Unknown
            } else {
                mesh_parity::side_off_surface(m, p)
            }
        }
        s => s,
    }
}
