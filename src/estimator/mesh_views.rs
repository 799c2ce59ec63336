//! Maps of the large meshes from the receivers that test them
//! ([`MeshView`]): each receiver list's mesh occluders get the map of their
//! mesh from the entry's receiver, built once per (receiver, mesh) and
//! shared by every list the receiver is in. A map answers most of the
//! shadow tests from collisions to that receiver without the mesh's BVH,
//! with the exact test's answer (so the scores keep their bits).
//!
//! Measured (2 cores, the build before interleaved, the same output bytes):
//! in the office (`lumest bench --scene data/office.toml --case-time 6`,
//! its 506 planar grid points, the sculpture of 25,280 triangles) scores/s
//! rose 1-3 % (9.3e7-9.7e7 to 9.6e7-9.8e7), set-up by 0.03 s, peak memory by
//! 4 MB: most of the office's time is elsewhere. In a 10 x 8 x 3 m room
//! with a bumpy ball of 101,760 triangles (radius 0.6 m) and 500
//! work-plane points, one thread, 60,000 chains: 8.1e3-8.9e3 chains/s
//! became 1.21e4-1.23e4 (x 1.4). The office at 20,000 points 0.8 m above
//! the floor, 8192 chains, 2 threads: 12.0 s wall became 8.9 s (the run
//! 11.3 s became 7.0 s, the maps' set-up took about 1 s of the rest), peak
//! memory 189 MB became 260 MB (16,384 maps, the budget). Tried and dropped: 128 cells a side
//! (edge cells 11 % of the mesh tests instead of 20 % in that room, no
//! faster: the larger maps miss the cache), and per-cell bounds on the
//! distance of the triangles a ray can meet there (a pass over every
//! triangle per map, 0.35 s more set-up in the office, no fewer tests:
//! the segments left over end on the mesh or within its ball).

use super::ReceiverList;
use crate::estimator::Receiver;
use crate::geometry::mesh_view::{MAP_BYTES, MeshEdges, MeshView};
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::Arc;

/// Fewest triangles a mesh needs for maps: a small mesh's BVH test is
/// cheaper than a map's set-up.
const MIN_TRIANGLES: usize = 256;

/// Most bytes of maps over all lists (past it the rest test their BVH).
const MAX_BYTES: usize = 64 << 20;

/// Most triangles summed over the maps built: a map's set-up costs a pass
/// over its mesh's triangles and edges (about 0.1 ms for 25,000).
const MAX_TRIANGLE_PASSES: usize = 1 << 30;

/// Give the mesh occluders of `lists` their maps from the entries'
/// receivers (`receivers`, indexed by the lists' `idx`), within the
/// budgets, in (receiver, mesh) order.
pub(super) fn attach(scene: &Scene, receivers: &[Receiver], lists: &mut [ReceiverList]) {
    let mut want: Vec<(u32, u32)> = Vec::new();
    for list in lists.iter() {
        if list.occ_start.is_empty() {
            continue;
        }
        for (k, &j) in list.idx.iter().enumerate() {
            let occ = &list.occ[list.occ_start[k] as usize..list.occ_start[k + 1] as usize];
            for i in occ.iter().filter_map(|o| o.mesh()) {
                if scene.mesh(i).triangle_count() >= MIN_TRIANGLES {
                    want.push((j, i));
                }
            }
        }
    }
    if want.is_empty() {
        return;
    }
    want.sort_unstable();
    want.dedup();
    let (mut bytes, mut passes) = (0usize, 0usize);
    want.retain(|&(_, i)| {
        let t = scene.mesh(i).triangle_count();
        let keep = bytes + MAP_BYTES <= MAX_BYTES && passes + t <= MAX_TRIANGLE_PASSES;
        if keep {
            bytes += MAP_BYTES;
            passes += t;
        }
        keep
    });
    let mut meshes: Vec<u32> = want.iter().map(|w| w.1).collect();
    meshes.sort_unstable();
    meshes.dedup();
    let edges: Vec<MeshEdges> = meshes
        .par_iter()
        .map(|&i| MeshEdges::new(scene.mesh(i)))
        .collect();
    let views: Vec<Option<Arc<MeshView>>> = want
        .par_iter()
        .map(|&(j, i)| {
            let e = &edges[meshes.binary_search(&i).expect("listed")];
            MeshView::build(scene.mesh(i), e, receivers[j as usize].p).map(Arc::new)
        })
        .collect();
    for list in lists.iter_mut() {
        if list.occ_start.is_empty() {
            continue;
        }
        for (k, &j) in list.idx.iter().enumerate() {
            let occ = &mut list.occ[list.occ_start[k] as usize..list.occ_start[k + 1] as usize];
            for o in occ.iter_mut() {
                if let Some(i) = o.mesh()
                    && let Ok(w) = want.binary_search(&(j, i))
                    && let Some(v) = &views[w]
                {
                    o.set_view(v.clone());
                }
            }
        }
    }
}
