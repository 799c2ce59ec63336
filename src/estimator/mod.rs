//! Estimators: scores of collisions at requested points. No accumulation
//! across batches and no I/O here; the caller owns the buffers.
//!
//! **Local estimate** (Marchuk et al. 1980, ch. 5): the illuminance at a point
//! `p` with unit normal `n_p` due to light reflected at least once is
//!
//! `E_ind(p) = E[ sum_n Q_n f_r(wi_n, wo_n) cos(theta_n) cos(theta_p) / d_n^2 V(x_n, p) ]`
//!
//! where `x_n` are the collisions of a light-tracing chain with weights `Q_n`
//! [lm], `wo_n` the unit direction from `x_n` to `p`, `theta_n` the angle
//! between `wo_n` and the surface normal at `x_n`, `theta_p` the angle between
//! `-wo_n` and `n_p`, `d_n = |p - x_n|`, and `V` the visibility. Every
//! collision scores into every point at once. The first-order (direct) part
//! is computed exactly and separately ([`Receivers::direct`]).

use crate::chain::Collision;
use crate::geometry::SideMask;
use crate::scene::Scene;
use glam::DVec3;

/// The geometric kernel `cos(theta_x) cos(theta_p) / d^2` [1/m^2] between a
/// surface point `x` with front normal `n_x` and a receiver `p` with normal
/// `n_p`; zero when either cosine is not positive.
#[inline]
pub fn local_kernel(x: DVec3, n_x: DVec3, p: DVec3, n_p: DVec3) -> f64 {
    let d = p - x;
    let d2 = d.length_squared();
    let cx = n_x.dot(d);
    let cp = -n_p.dot(d);
    if cx <= 0.0 || cp <= 0.0 {
        0.0
    } else {
        cx * cp / (d2 * d2)
    }
}

/// Error building receivers from a point list.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("point {index}: {message}")]
pub struct ReceiverError {
    /// 0-based index of the point in the list.
    pub index: usize,
    /// What is wrong.
    pub message: String,
}

/// Points that can receive light reflected at one surface, stored as
/// structure of arrays so the scoring loop vectorises.
#[derive(Clone, Debug, Default)]
struct ReceiverList {
    /// Index of each entry in the user's point list.
    idx: Vec<u32>,
    px: Vec<f64>,
    py: Vec<f64>,
    pz: Vec<f64>,
    nx: Vec<f64>,
    ny: Vec<f64>,
    nz: Vec<f64>,
    masks: Vec<SideMask>,
    /// Planes (bits) that could separate a collision on this surface from some entry.
    blockers: u64,
    /// Offset of this list in a flat accumulator.
    offset: usize,
}

/// Illuminance receivers (points with normals), compiled against a scene.
#[derive(Clone, Debug)]
pub struct Receivers {
    n_points: usize,
    lists: Vec<ReceiverList>,
    total_len: usize,
    direct: Vec<f64>,
}

impl Receivers {
    /// Compile points `p` [m] with unit normals `n` against `scene`.
    ///
    /// A point enters the list of a surface only if it lies strictly in front
    /// of it (a collision there can score into it); the exact direct
    /// illuminance is computed here once.
    pub fn new(scene: &Scene, points: &[(DVec3, DVec3)]) -> Result<Self, ReceiverError> {
        let masks: Vec<SideMask> = points.iter().map(|(p, _)| scene.side_mask(*p)).collect();
        let mut direct = vec![0.0; points.len()];
        for (j, (p, n)) in points.iter().enumerate() {
            if !(p.is_finite() && n.is_finite() && (n.length() - 1.0).abs() < 1e-9) {
                return Err(ReceiverError {
                    index: j,
                    message: "position and unit normal must be finite".into(),
                });
            }
            for l in &scene.lights {
                let lp = l.position();
                if (lp - *p).length() <= 1e-12 * lp.abs().max_element().max(p.abs().max_element()) {
                    return Err(ReceiverError {
                        index: j,
                        message: format!(
                            "point coincides with a point light at {lp:?}: illuminance is infinite"
                        ),
                    });
                }
                if scene.side_mask(lp).sees(masks[j]) {
                    direct[j] += l.direct_illuminance(*p, *n);
                }
            }
        }
        let mut lists = Vec::with_capacity(scene.planes.len());
        let mut offset = 0;
        for (s, _) in scene.planes.iter().enumerate() {
            let mut list = ReceiverList {
                offset,
                ..Default::default()
            };
            for (j, (p, n)) in points.iter().enumerate() {
                if masks[j].front & (1 << s) == 0 {
                    continue;
                }
                list.idx.push(j as u32);
                list.px.push(p.x);
                list.py.push(p.y);
                list.pz.push(p.z);
                list.nx.push(n.x);
                list.ny.push(n.y);
                list.nz.push(n.z);
                list.masks.push(masks[j]);
                list.blockers |= (masks[j].front | masks[j].back) & !(1 << s);
            }
            offset += list.idx.len();
            lists.push(list);
        }
        Ok(Self {
            n_points: points.len(),
            lists,
            total_len: offset,
            direct,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.n_points
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.n_points == 0
    }

    /// Exact direct illuminance at each point [lx].
    pub fn direct(&self) -> &[f64] {
        &self.direct
    }

    /// Length of the flat per-bucket accumulator used by [`Self::score`].
    pub fn accumulator_len(&self) -> usize {
        self.total_len
    }

    /// Add the local-estimate scores [lx] of collision `c` into `acc` (one
    /// bucket of length [`Self::accumulator_len`]); returns the number of
    /// point scores evaluated.
    #[inline]
    pub fn score(&self, scene: &Scene, c: &Collision, acc: &mut [f64]) -> usize {
        let list = &self.lists[c.surface as usize];
        let len = list.idx.len();
        if len == 0 {
            return 0;
        }
        let material = &scene.surfaces[c.surface as usize].material;
        let f = material
            .constant_brdf()
            .expect("only Lambertian materials exist");
        let qf = c.q * f;
        let acc = &mut acc[list.offset..list.offset + len];
        let (x, n) = (c.p, c.n);
        let xm = if list.blockers != 0 {
            scene.side_mask(x)
        } else {
            SideMask::default()
        };
        if (xm.front | xm.back) & list.blockers == 0 {
            score_open(list, x, n, qf, acc);
        } else {
            score_masked(list, x, n, qf, xm, acc);
        }
        len
    }

    /// Add a flat accumulator bucket (see [`Self::score`]) into per-point sums.
    pub fn reduce(&self, acc: &[f64], per_point: &mut [f64]) {
        for list in &self.lists {
            for (k, &j) in list.idx.iter().enumerate() {
                per_point[j as usize] += acc[list.offset + k];
            }
        }
    }
}

/// Score a collision at `x` (front normal `n`, weight times BRDF `qf`) into
/// every entry of `list`, no plane in the way. Written over zipped slices so
/// the compiler drops bounds checks and vectorises.
#[inline]
fn score_open(list: &ReceiverList, x: DVec3, n: DVec3, qf: f64, acc: &mut [f64]) {
    let it = acc
        .iter_mut()
        .zip(list.px.iter().zip(&list.py).zip(&list.pz))
        .zip(list.nx.iter().zip(&list.ny).zip(&list.nz));
    for (a, ((px, py), pz), ((nx, ny), nz)) in it.map(|((a, p), q)| (a, p, q)) {
        let (dx, dy, dz) = (px - x.x, py - x.y, pz - x.z);
        let cx = (n.x * dx + n.y * dy + n.z * dz).max(0.0);
        let cp = (-(nx * dx + ny * dy + nz * dz)).max(0.0);
        let d2 = dx * dx + dy * dy + dz * dz;
        *a += qf * cx * cp / (d2 * d2);
    }
}

/// As [`score_open`], with entries hidden from `x` by a plane scoring zero.
#[inline]
fn score_masked(list: &ReceiverList, x: DVec3, n: DVec3, qf: f64, xm: SideMask, acc: &mut [f64]) {
    for (k, a) in acc.iter_mut().enumerate() {
        if xm.sees(list.masks[k]) {
            let p = DVec3::new(list.px[k], list.py[k], list.pz[k]);
            let np = DVec3::new(list.nx[k], list.ny[k], list.nz[k]);
            *a += qf * local_kernel(x, n, p, np);
        }
    }
}
