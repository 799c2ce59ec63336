//! Which side of a closed mesh the lights are on: the side a receiver
//! edge-on to one of its two-sided faces belongs to
//! ([`Scene::lift_to_its_side`]).
//!
//! A closed mesh cuts space in two, and no light crosses it: the region
//! without a light is dark on both of a two-sided face's sides. A point on
//! such a face that faces along it (a floor point at the foot of a room
//! mesh's wall, facing up; a point on a cabinet mesh's side, facing up)
//! is the limit from the lit region. Evaluated on the face it saw past it
//! on both sides, as past a sheet, and so counted the dark half: a room
//! mesh's wall foot read 7.84 against 10.33 lx a micrometre into the room,
//! a two-sided cabinet mesh's side 58.4 against 67.8 lx beside it.

use super::Scene;
use crate::geometry::mesh_parity::{self, Side};

/// Per mesh of a scene, found on first use and kept until the lights
/// change: `Some(true)` where every light that can be placed lies outside
/// the closed mesh (lights at infinity do), `Some(false)` where every one
/// lies inside, `None` for an open mesh, lights on both sides, or none
/// placed (a light on the mesh itself is not placed).
#[derive(Clone, Default)]
pub(super) struct MeshLitSide(std::sync::OnceLock<Vec<Option<bool>>>);

/// Found on demand, so it is left out of the scene's `Debug` text (which
/// names a run in its state files, and must not depend on what a run
/// asked first).
impl std::fmt::Debug for MeshLitSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("MeshLitSide")
    }
}

impl Scene {
    /// Whether the lights of the scene lie outside (`Some(true)`) or inside
    /// (`Some(false)`) its `i`-th mesh ([module docs](self)).
    pub(super) fn lights_outside_mesh(&self, i: usize) -> Option<bool> {
        self.mesh_lit_side.0.get_or_init(|| {
            self.meshes
                .iter()
                .map(|(m, _)| {
                    if !m.is_closed() {
                        return None;
                    }
                    let mut outside = None;
                    for l in &self.lights {
                        let here = if l.is_directional() {
                            Side::Outside
                        } else {
                            mesh_parity::side(m, l.position())
                        };
                        let out = match here {
                            Side::Outside => true,
                            Side::Inside => false,
                            Side::Unknown => continue,
                        };
                        if outside.is_some_and(|o| o != out) {
                            return None;
                        }
                        outside = Some(out);
                    }
                    outside
                })
                .collect()
        })[i]
    }
}
