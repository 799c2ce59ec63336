//! Triangle meshes: Wavefront OBJ input and output, a BVH, ray queries.
//!
//! A [`Mesh`] is a set of triangles over shared vertices \[m\]. Each triangle's
//! front side is the side its counter-clockwise winding faces (right-hand
//! rule: `(v1 - v0) x (v2 - v0)`); the geometric normal returned by the ray
//! queries is that one, never flipped toward the ray. Triangles are opaque
//! from both sides and both sides are hit.
//!
//! # Acceleration: an own `f64` BVH, not `obvhs`
//!
//! The ray queries run on [`super::bvh::TriangleBvh`], a binned-SAH BVH written for
//! this crate in `f64`, with the watertight ray–triangle test of Woop,
//! Benthin and Wald (2013). `obvhs` (f32) was faster in a crate survey, but
//! an `f32` box around `f64` triangles and an `f32` slab test can cull a
//! triangle the `f64` test would hit (a millimetre at 10 km); guaranteeing
//! conservative boxes would mean patching its build and traversal. The own
//! BVH pads boxes by a relative margin far above all rounding, so its
//! answers are those of a brute-force loop over all triangles at every
//! scale (the tests check this).
//!
//! Measured (`bench_100k_triangles`, release, AMD EPYC VM with 2 cores
//! shared with other jobs, so per CPU second of one thread): a closed blob
//! of 99,904 triangles builds in 0.1 s and takes 15.9 MB (159 bytes per
//! triangle with the vertices); nearest hits run at about 1.0 M rays/s and
//! shadow rays at 1.2 to 1.4 M rays/s per thread, from inside (every ray
//! hits) or from outside (62 % hit). Queries take `&self`, so threads share
//! one mesh.
//!
//! # Watertightness
//!
//! A ray through a shared edge or vertex of a conforming mesh (neighbouring
//! triangles share vertices with bit-identical coordinates) hits at least
//! one of the triangles there: no light leaks through a closed mesh. Meshes
//! with T-junctions or cracks are not repaired.
//!
//! # Degenerate triangles
//!
//! Triangles of zero area (repeated or collinear vertices, up to rounding
//! of the cross product to zero) have no normal and are dropped when a mesh
//! is built; [`Mesh::dropped_triangles`] counts them. Triangle indices in
//! queries refer to the kept triangles, in input order.
//!
//! # Ray queries
//!
//! Rays are `o + t d` with unit `d` and `t` \[m\] in an open interval
//! `(t_min, t_max)`; `skip` names the triangle a ray leaves (so a ray
//! leaving a surface never re-hits it at `t ~ 0`).

use super::bvh::{Ends, RayQuery, TriangleBvh};
use glam::{DMat3, DVec3};
use std::fmt::Write as _;
use std::path::Path;

/// A bad mesh or mesh file, naming the file (and the line where known).
///
/// Meshes built in memory ([`Mesh::from_triangles`]) are named `<triangles>`.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A problem with the file or the mesh as a whole.
    #[error("{file}: {message}")]
    File {
        /// File name as given (or `<triangles>`).
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A problem on one line of an OBJ file.
    #[error("{file}:{line}: {message}")]
    Line {
        /// File name as given.
        file: String,
        /// Line number, 1-based.
        line: u64,
        /// What is wrong.
        message: String,
    },
}

/// Name used in errors for meshes built in memory.
const IN_MEMORY: &str = "<triangles>";

/// A vertex in messages: `(x, y, z)`, numbers as in the CSV output.
fn point(v: DVec3) -> String {
    let f = crate::io::format_number;
    format!("({}, {}, {})", f(v.x), f(v.y), f(v.z))
}

/// Largest coordinate of a vertex as the file gives it (file units, before
/// `translate`, `rotate` and `scale`): squares and products stay finite
/// for the tree and the welding. Where the mesh is placed its vertices must
/// lie within [`crate::scene::MAX_COORD`] (a file in millimetres with
/// georeferenced coordinates, re-centred by `translate`, is fine).
const MAX_FILE_COORD: f64 = 1e100;

/// The first vertex with a coordinate beyond `limit` (index, vertex).
fn beyond_limit(vertices: &[DVec3], limit: f64) -> Option<(usize, DVec3)> {
    vertices
        .iter()
        .enumerate()
        .find(|(_, v)| v.abs().max_element() > limit)
        .map(|(i, v)| (i, *v))
}

/// One vertex for each position: `o`/`g` groups (and files that repeat a
/// vertex per face) give each group its own copy of the vertices it shares
/// with the next, which would leave a closed surface open at the seams
/// (and a point inside it unflagged). Positions are compared bit for bit
/// (`-0` as `0`); the first copy keeps its place.
fn weld(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut first = std::collections::HashMap::with_capacity(vertices.len());
    let mut kept = Vec::with_capacity(vertices.len());
    let remap: Vec<u32> = vertices
        .iter()
        .map(|v| {
            let key = (v + DVec3::ZERO).to_array().map(f64::to_bits);
            *first.entry(key).or_insert_with(|| {
                kept.push(*v + DVec3::ZERO);
                kept.len() as u32 - 1
            })
        })
        .collect();
    let triangles = triangles
        .into_iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .collect();
    (kept, triangles)
}

/// An OBJ file's text with its continued lines joined: a backslash that
/// ends a line (before `\n` or `\r\n`) continues it on the next (the OBJ
/// format's rule, which `tobj` does not follow). The joined line keeps the
/// number of its first line, and the line breaks it swallowed follow it as
/// empty lines, so every later line keeps its number in messages.
fn join_continued_lines(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len());
    let mut swallowed = 0usize;
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        if b == b'\\' {
            let after = &bytes[i + 1..];
            let skip = if after.starts_with(b"\r\n") {
                2
            } else if after.starts_with(b"\n") {
                1
            } else {
                0
            };
            if skip > 0 {
                out.push(b' ');
                swallowed += 1;
                i += 1 + skip;
                continue;
            }
        }
        out.push(b);
        if b == b'\n' {
            out.extend(std::iter::repeat_n(b'\n', swallowed));
            swallowed = 0;
        }
        i += 1;
    }
    out.extend(std::iter::repeat_n(b'\n', swallowed));
    out
}

fn file_error(file: &str, message: impl Into<String>) -> MeshError {
    MeshError::File {
        file: file.to_string(),
        message: message.into(),
    }
}

/// A triangle mesh with a BVH for ray queries.
#[derive(Clone)]
pub struct Mesh {
    /// Vertices \[m\].
    vertices: Vec<DVec3>,
    /// Kept (non-degenerate) triangles, CCW, indices into `vertices`.
    triangles: Vec<[u32; 3]>,
    /// Bounds of the triangles' vertices \[m\].
    lo: DVec3,
    hi: DVec3,
    /// Zero-area triangles dropped when built.
    dropped: usize,
    /// Largest distance \[m\] of a kept triangle's corner from the centre of
    /// the bounds: the ball there of this radius holds every triangle.
    reach: f64,
    bvh: TriangleBvh,
    /// The box inside a closed mesh ([`super::mesh_core`]), found on first
    /// use.
    core: std::sync::OnceLock<Option<super::mesh_core::Core>>,
    /// Whether every edge joins two triangles, once each way, found on first use.
    closed: std::sync::OnceLock<bool>,
}

/// The mesh's summary, with a hash of every vertex and triangle: the
/// compiled scene's `Debug` text names a run in its state files (shards,
/// checkpoints), so two meshes that differ in one vertex must print apart.
impl std::fmt::Debug for Mesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut bytes = Vec::with_capacity(24 * self.vertices.len() + 12 * self.triangles.len());
        for v in &self.vertices {
            for c in v.to_array() {
                bytes.extend_from_slice(&c.to_bits().to_le_bytes());
            }
        }
        for t in &self.triangles {
            for i in t {
                bytes.extend_from_slice(&i.to_le_bytes());
            }
        }
        f.debug_struct("Mesh")
            .field(
                "content",
                &format_args!("{:016x}", crate::tally::shard::fnv1a(&bytes)),
            )
            .field("vertices", &self.vertices.len())
            .field("triangles", &self.triangles.len())
            .field("dropped", &self.dropped)
            .field("bounds", &(self.lo, self.hi))
            .field("bvh_nodes", &self.bvh.node_count())
            .finish()
    }
}

impl Mesh {
    /// Load a Wavefront OBJ file with `tobj`: all objects and groups merged
    /// into one mesh, polygons triangulated by ear clipping in their plane
    /// ([`super::polygon`]: exact for concave polygons too, the winding
    /// kept), points and lines ignored, materials,
    /// normals and texture coordinates ignored. Coordinates are read as
    /// `f64` and taken as metres. Zero-area triangles are dropped.
    ///
    /// Errors name the file, and the line for parse errors, non-finite
    /// vertices and vertex indices out of range.
    pub fn load_obj(path: &Path) -> Result<Self, MeshError> {
        let file = path.display().to_string();
        let bytes =
            std::fs::read(path).map_err(|e| file_error(&file, format!("cannot read: {e}")))?;
        let bytes = join_continued_lines(&bytes);
        let mut rest: &[u8] = &bytes;
        let options = tobj::LoadOptions {
            triangulate: false,
            single_index: false,
            ignore_points: true,
            ignore_lines: true,
        };
        let loaded = tobj::load_obj_buf(&mut rest, &options, |_| Ok(Default::default()));
        // For locating errors only.
        let text = || String::from_utf8_lossy(&bytes);
        let models = match loaded {
            Ok((models, _materials)) => models,
            Err(e) => {
                return Err(match e {
                    // Raised when an object ends, not on the offending
                    // line: found again by a scan of the text.
                    tobj::LoadError::FaceVertexOutOfBounds
                    | tobj::LoadError::FaceTexCoordOutOfBounds
                    | tobj::LoadError::FaceNormalOutOfBounds => {
                        let (slot, key, what) = match e {
                            tobj::LoadError::FaceVertexOutOfBounds => {
                                (0, "v", ("vertex", "vertices"))
                            }
                            tobj::LoadError::FaceTexCoordOutOfBounds => {
                                (1, "vt", ("texture coordinate", "texture coordinates"))
                            }
                            _ => (2, "vn", ("normal", "normals")),
                        };
                        match bad_face_ref(&text(), slot, key, what) {
                            Some((line, message)) => MeshError::Line {
                                file,
                                line,
                                message,
                            },
                            None => file_error(&file, e.to_string()),
                        }
                    }
                    tobj::LoadError::FaceColorOutOfBounds | tobj::LoadError::InvalidPolygon => {
                        file_error(&file, e.to_string())
                    }
                    // Raised while parsing the last line read.
                    _ => {
                        let consumed = &bytes[..bytes.len() - rest.len()];
                        let newlines = consumed.iter().filter(|&&b| b == b'\n').count() as u64;
                        let line = if consumed.last() == Some(&b'\n') {
                            newlines
                        } else {
                            newlines + 1
                        };
                        MeshError::Line {
                            file,
                            line,
                            message: e.to_string(),
                        }
                    }
                });
            }
        };
        // tobj takes a face of fewer than 3 vertices for a line, which it
        // drops here unchecked: one that refers to a missing vertex is
        // refused all the same.
        if let Some((line, message)) = bad_face_ref(&text(), 0, "v", ("vertex", "vertices")) {
            return Err(MeshError::Line {
                file,
                line,
                message,
            });
        }
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for m in &models {
            let base = vertices.len() as u32;
            vertices.extend(
                m.mesh
                    .positions
                    .chunks_exact(3)
                    .map(|p| DVec3::new(p[0], p[1], p[2])),
            );
            // Faces of any arity (none listed: all triangles).
            let idx = &m.mesh.indices;
            let arities = &m.mesh.face_arities;
            let mut at = 0usize;
            let faces = if arities.is_empty() {
                idx.len() / 3
            } else {
                arities.len()
            };
            for f in 0..faces {
                let k = arities.get(f).map_or(3, |&a| a as usize);
                let face = &idx[at..at + k];
                at += k;
                if k == 3 {
                    triangles.push([base + face[0], base + face[1], base + face[2]]);
                } else if k > 3 {
                    let pts: Vec<DVec3> = face
                        .iter()
                        .map(|&i| {
                            let p = &m.mesh.positions[3 * i as usize..3 * i as usize + 3];
                            DVec3::new(p[0], p[1], p[2])
                        })
                        .collect();
                    triangles.extend(
                        super::polygon::triangulate(&pts)
                            .into_iter()
                            .map(|t| [base + face[t[0]], base + face[t[1]], base + face[t[2]]]),
                    );
                }
            }
        }
        if let Some(v) = vertices.iter().find(|v| !v.is_finite()) {
            return Err(match non_finite_vertex(&text()) {
                Some(line) => MeshError::Line {
                    file,
                    line,
                    message: "vertex coordinates are not finite".into(),
                },
                None => file_error(&file, format!("vertex {} is not finite", point(*v))),
            });
        }
        if let Some((i, v)) = beyond_limit(&vertices, MAX_FILE_COORD) {
            return Err(file_error(
                &file,
                format!(
                    "vertex {} = {} lies beyond +-{MAX_FILE_COORD:e} (file units)",
                    i + 1,
                    point(v),
                ),
            ));
        }
        let (vertices, triangles) = weld(vertices, triangles);
        Self::build(&file, vertices, triangles)
    }

    /// Mesh from vertices \[m\] and counter-clockwise triangles (indices into
    /// `vertices`). Rejects non-finite vertices and out-of-range indices;
    /// drops zero-area triangles (see [`Mesh::dropped_triangles`]); an error
    /// if no triangle is left.
    pub fn from_triangles(
        vertices: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, MeshError> {
        Self::build(IN_MEMORY, vertices, triangles)
    }

    fn build(
        file: &str,
        vertices: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, MeshError> {
        if let Some((i, v)) = vertices.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(file_error(
                file,
                format!("vertex {i} = {} is not finite", point(*v)),
            ));
        }
        let nv = vertices.len();
        let mut kept = Vec::with_capacity(triangles.len());
        let mut corners = Vec::with_capacity(triangles.len());
        let mut dropped = 0;
        for (k, t) in triangles.iter().enumerate() {
            if let Some(&i) = t.iter().find(|&&i| i as usize >= nv) {
                return Err(file_error(
                    file,
                    format!("triangle {k}: vertex index {i} out of range ({nv} vertices)"),
                ));
            }
            let p = t.map(|i| vertices[i as usize]);
            let area2 = (p[1] - p[0]).cross(p[2] - p[0]).length();
            if area2 > 0.0 && area2.is_finite() {
                kept.push(*t);
                corners.push(p);
            } else {
                dropped += 1;
            }
        }
        if kept.is_empty() {
            return Err(file_error(
                file,
                if dropped > 0 {
                    format!("no triangles ({dropped} of zero area dropped)")
                } else {
                    "no triangles".to_string()
                },
            ));
        }
        if kept.len() >= u32::MAX as usize {
            return Err(file_error(file, "too many triangles"));
        }
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for p in corners.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let centre = 0.5 * (lo + hi);
        // (Vertices are finite, checked above: the fold drops no NaN.)
        let reach = corners
            .iter()
            .flatten()
            .map(|p| (*p - centre).length())
            .fold(0.0, f64::max);
        let bvh = TriangleBvh::build(&corners);
        Ok(Self {
            vertices,
            triangles: kept,
            lo,
            hi,
            dropped,
            reach,
            bvh,
            core: std::sync::OnceLock::new(),
            closed: std::sync::OnceLock::new(),
        })
    }

    /// Whether the mesh is a closed, consistently wound surface: every edge
    /// joins exactly two triangles, once in each direction (so it bounds a
    /// solid; [`super::mesh_parity`] tells its inside).
    pub fn is_closed(&self) -> bool {
        *self
            .closed
            .get_or_init(|| super::mesh_core::closed(&self.triangles))
    }

    /// Whether the mesh is closed as a surface (every edge joins exactly
    /// two triangles) but not consistently wound: some neighbours run
    /// their shared edge the same way, so it has no inside
    /// ([`Self::is_closed`] is false) and one of the two faces' sides is
    /// wrong.
    pub fn is_closed_but_unevenly_wound(&self) -> bool {
        !self.is_closed() && super::mesh_core::closed_unoriented(&self.triangles)
    }

    /// The core of a closed mesh: a box inside the solid, whose crossing by
    /// a shadow segment proves it blocked ([`super::mesh_core`]); `None`
    /// for an open mesh. Found on the first call (a few passes over the
    /// triangles).
    pub fn core(&self) -> Option<&super::mesh_core::Core> {
        self.core
            .get_or_init(|| {
                let corners: Vec<[DVec3; 3]> = (0..self.triangles.len() as u32)
                    .map(|k| self.corners(k))
                    .collect();
                super::mesh_core::Core::find(&corners, &self.triangles, (self.lo, self.hi))
            })
            .as_ref()
    }

    /// The mesh moved by `x -> translate + scale * rotation * x`, BVH rebuilt.
    ///
    /// # Panics
    /// If `scale` is not positive and finite, `rotation` is not a rotation
    /// (orthonormal with determinant +1, to 1e-9), or the result is not
    /// finite; see [`Mesh::try_transformed`] for the checked form.
    pub fn transformed(self, translate: DVec3, rotation: DMat3, scale: f64) -> Self {
        match self.try_transformed(translate, rotation, scale) {
            Ok(m) => m,
            Err(e) => panic!("{e}"),
        }
    }

    /// [`Mesh::transformed`], with bad arguments reported as errors.
    pub fn try_transformed(
        self,
        translate: DVec3,
        rotation: DMat3,
        scale: f64,
    ) -> Result<Self, MeshError> {
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(file_error(
                IN_MEMORY,
                format!(
                    "transform: scale {} is not positive and finite",
                    crate::io::format_number(scale)
                ),
            ));
        }
        let off = (rotation.transpose() * rotation - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let det = rotation.determinant();
        if !(off <= 1e-9 && (det - 1.0).abs() <= 1e-9 && translate.is_finite()) {
            return Err(file_error(
                IN_MEMORY,
                format!(
                    "transform: not a rotation (|R^T R - I| = {off:e}, det = {det}) \
                     or translation {} not finite",
                    point(translate)
                ),
            ));
        }
        let vertices = self
            .vertices
            .iter()
            .map(|&v| translate + scale * (rotation * v))
            .collect::<Vec<_>>();
        if let Some((i, v)) = beyond_limit(&vertices, crate::scene::MAX_COORD) {
            return Err(file_error(
                IN_MEMORY,
                format!(
                    "transform: vertex {} moves to {}, beyond +-{:e} m (translate, rotate, scale)",
                    i + 1,
                    point(v),
                    crate::scene::MAX_COORD
                ),
            ));
        }
        Self::build(IN_MEMORY, vertices, self.triangles)
    }

    /// Number of (kept) triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Vertices \[m\].
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// Triangles (CCW vertex indices), in input order without the dropped ones.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Zero-area triangles dropped when the mesh was built.
    pub fn dropped_triangles(&self) -> usize {
        self.dropped
    }

    /// Corners \[m\] of triangle `tri`.
    pub fn corners(&self, tri: u32) -> [DVec3; 3] {
        self.triangles[tri as usize].map(|i| self.vertices[i as usize])
    }

    /// Unit geometric normal of triangle `tri` (CCW winding, right-hand rule).
    pub fn normal(&self, tri: u32) -> DVec3 {
        let p = self.corners(tri);
        (p[1] - p[0]).cross(p[2] - p[0]).normalize()
    }

    /// Area of triangle `tri` [m^2].
    pub fn area(&self, tri: u32) -> f64 {
        let p = self.corners(tri);
        0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
    }

    /// Bytes of geometry (vertices, triangles) and BVH storage (nodes,
    /// leaf-ordered triangle corners, ids).
    pub fn storage_bytes(&self) -> usize {
        size_of::<Self>()
            + self.vertices.len() * size_of::<DVec3>()
            + self.triangles.len() * size_of::<[u32; 3]>()
            + self.bvh.storage_bytes()
    }

    /// Axis-aligned bounds `(lower, upper)` of the triangles \[m\].
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (self.lo, self.hi)
    }

    /// A ball holding every triangle: the centre of [`Self::bounds`] and
    /// the largest distance of a corner from it \[m\] (for a round mesh
    /// tighter than the ball round its box, by up to `sqrt 3`).
    pub fn bounding_ball(&self) -> (DVec3, f64) {
        (0.5 * (self.lo + self.hi), self.reach)
    }

    /// Nearest hit of the ray `o + t d` (unit `d`) with `t` \[m\] in
    /// `(t_min, t_max)`, skipping triangle `skip`: `(t, unit geometric
    /// normal by CCW winding, not flipped toward the ray, triangle index)`.
    /// With `front = Some(f)`, a triangle whose winding side `f` (`true`:
    /// the front) faces the ray wins a near tie with one that shows the
    /// other side ([`super::bvh::TriangleBvh::first_hit`]): a one-sided
    /// mesh's "double-sided" faces, written as two coincident triangles of
    /// opposite winding, reflect from both sides.
    pub fn first_hit(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        skip: Option<u32>,
        front: Option<bool>,
    ) -> Option<(f64, DVec3, u32)> {
        self.first_hit_leaving(o, d, t_min, t_max, Ends::skip(skip), front)
    }

    /// [`Self::first_hit`] for a ray leaving a point that may lie on
    /// triangles ([`Ends`]: the triangles through `o` met within
    /// `ends.near` are skipped).
    pub fn first_hit_leaving(
        &self,
        o: DVec3,
        d: DVec3,
        t_min: f64,
        t_max: f64,
        ends: Ends,
        front: Option<bool>,
    ) -> Option<(f64, DVec3, u32)> {
        let q = RayQuery::new(o, d);
        let (t, tri, p) = self
            .bvh
            .first_hit(&q, t_min, t_max, ends, front.map(|f| (d, f)))?;
        Some((t, (p[1] - p[0]).cross(p[2] - p[0]).normalize(), tri))
    }

    /// How far a point `p` may lie from a triangle's plane and be on it
    /// \[m\]: the rounding of coordinates of `p`'s and the mesh's size
    /// (1e-12 of the mesh's size, and 64 ulp of the largest coordinate).
    pub fn on_tolerance(&self, p: DVec3) -> f64 {
        let scale = p.abs().max(self.lo.abs()).max(self.hi.abs()).max_element();
        1e-12 * (self.hi - self.lo).length() + 64.0 * f64::EPSILON * scale
    }

    /// A triangle that point `p` lies on, within `tol` \[m\] of its plane
    /// and inside its edges (widened by `tol`); the first in order. A
    /// linear search after a bounds test: for set-up (a light or an eye on
    /// the mesh), not for paths.
    pub fn triangle_at(&self, p: DVec3, tol: f64) -> Option<u32> {
        let pad = DVec3::splat(tol);
        if (self.lo - pad).cmpgt(p).any() || p.cmpgt(self.hi + pad).any() {
            return None;
        }
        (0..self.triangles.len() as u32).find(|&k| on_triangle(p, &self.corners(k), tol))
    }

    /// The triangles that point `p` lies on, within `tol` \[m\] of their
    /// planes and inside their edges widened by `tol`, in index order,
    /// each once, with their corners: the triangles of the leaves met by
    /// segments through `p` along the three axes (one crosses any plane),
    /// so a point on an edge or a corner finds every triangle there. (The
    /// segments' own hits were taken before: a point on the diagonal two
    /// triangles of a wall share, off it by rounding, met one of them only,
    /// and a light there lost the light it sent into the other's half; a
    /// reviewer's find.)
    pub fn triangles_through(&self, p: DVec3, tol: f64) -> Vec<(u32, [DVec3; 3])> {
        let reach = 4.0 * tol.max(f64::MIN_POSITIVE);
        let mut out: Vec<(u32, [DVec3; 3])> = Vec::new();
        for d in [DVec3::X, DVec3::Y, DVec3::Z] {
            let q = RayQuery::new(p - reach * d, d);
            self.bvh.for_each_candidate(&q, 0.0, 2.0 * reach, |id, v| {
                if out.iter().all(|x| x.0 != id) && on_triangle(p, v, tol) {
                    out.push((id, *v));
                }
            });
        }
        out.sort_by_key(|x| x.0);
        out
    }

    /// The signed crossings of the ray `o + t d` (unit `d`), `t > t_min`,
    /// with the mesh: +1 for each triangle it leaves through the front of
    /// (the side the counter-clockwise winding faces), -1 for each it
    /// enters through the front; every triangle met counts, also two met
    /// at the same distance.
    pub fn signed_crossings(&self, o: DVec3, d: DVec3, t_min: f64) -> i64 {
        let q = RayQuery::new(o, d);
        let mut n = 0i64;
        self.bvh.for_each_hit(&q, t_min, f64::INFINITY, |_, _, p| {
            let facing = (p[1] - p[0]).cross(p[2] - p[0]).dot(d);
            n += match facing.partial_cmp(&0.0) {
                Some(std::cmp::Ordering::Greater) => 1,
                Some(std::cmp::Ordering::Less) => -1,
                _ => 0,
            };
        });
        n
    }

    /// Whether the ray `o + t d` (unit `d`) hits any triangle but `skip`
    /// with `t` \[m\] in `(t_min, t_max)` (shadow ray; stops at the first hit
    /// found).
    pub fn occluded(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64, skip: Option<u32>) -> bool {
        self.segment_blocked(o, d, t_min, t_max, Ends::skip(skip))
    }

    /// Whether the segment from `o` to `o + t_max d` (unit `d`) meets a
    /// triangle with `t` \[m\] in `(t_min, t_max)` that [`Ends`] lets
    /// count at either end.
    pub fn segment_blocked(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64, ends: Ends) -> bool {
        let q = RayQuery::new(o, d);
        self.bvh.any_hit(&q, t_min, t_max, ends)
    }

    /// The mesh as Wavefront OBJ text: a comment, `v x y z` lines (shortest
    /// decimal that reads back to the same `f64`), `f a b c` lines (1-based).
    pub fn to_obj_string(&self) -> String {
        let mut s = String::with_capacity(40 * self.vertices.len() + 24 * self.triangles.len());
        let _ = writeln!(
            s,
            "# lumest mesh: {} vertices, {} triangles, metres",
            self.vertices.len(),
            self.triangles.len()
        );
        for v in &self.vertices {
            let _ = writeln!(s, "v {} {} {}", v.x, v.y, v.z);
        }
        for t in &self.triangles {
            let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }

    /// Write the mesh as an OBJ file ([`Mesh::to_obj_string`]), atomically
    /// (temporary file, then rename).
    pub fn write_obj(&self, path: &Path) -> Result<(), MeshError> {
        let file = path.display().to_string();
        let Some(p) = path.to_str() else {
            return Err(file_error(&file, "path is not valid UTF-8"));
        };
        crate::io::csvio::write_atomic(p, self.to_obj_string().as_bytes())
            .map_err(|e| file_error(&file, format!("cannot write: {e}")))
    }
}

/// A closed star-shaped mesh: a UV sphere whose vertex at polar angle
/// `theta` (from `+z`) and azimuth `phi` (from `+x` toward `+y`) lies at
/// distance `radius(theta, phi)` \[m\] from the origin.
///
/// `n_theta >= 2` bands in `theta`, `n_phi >= 3` sectors in `phi`. Vertices:
/// the north pole (index 0, at `radius(0, 0)`), rings `i = 1..n_theta` of
/// `n_phi` vertices at `theta = pi i / n_theta`, `phi = 2 pi j / n_phi`
/// (index `1 + (i-1) n_phi + j`), the south pole last (`radius(pi, 0)`).
/// Triangles, counter-clockwise seen from outside: the north fan
/// (`n_phi`), two per quad of each band between rings, then the south fan
/// (`n_phi`); `2 n_phi (n_theta - 1)` in all.
///
/// Errors when the counts are too small or a radius is not positive and
/// finite. The mesh is star-shaped about the origin, so it is closed and
/// has no self-intersections.
pub fn star_blob(
    n_theta: usize,
    n_phi: usize,
    radius: impl Fn(f64, f64) -> f64,
) -> Result<Mesh, MeshError> {
    if n_theta < 2 || n_phi < 3 {
        return Err(file_error(
            IN_MEMORY,
            format!("star_blob: need n_theta >= 2 and n_phi >= 3, got {n_theta}, {n_phi}"),
        ));
    }
    let nv = 2 + (n_theta - 1) * n_phi;
    if nv > u32::MAX as usize / 2 {
        return Err(file_error(IN_MEMORY, "star_blob: too many vertices"));
    }
    let point = |theta: f64, phi: f64| -> Result<DVec3, MeshError> {
        let r = radius(theta, phi);
        if !(r > 0.0 && r.is_finite()) {
            return Err(file_error(
                IN_MEMORY,
                format!("star_blob: radius({theta}, {phi}) = {r} is not positive and finite"),
            ));
        }
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        Ok(r * DVec3::new(st * cp, st * sp, ct))
    };
    let pi = std::f64::consts::PI;
    let mut vertices = Vec::with_capacity(nv);
    vertices.push(point(0.0, 0.0)?);
    for i in 1..n_theta {
        let theta = pi * i as f64 / n_theta as f64;
        for j in 0..n_phi {
            vertices.push(point(theta, 2.0 * pi * j as f64 / n_phi as f64)?);
        }
    }
    let south = vertices.len() as u32;
    vertices.push(point(pi, 0.0)?);
    let ring = |i: usize, j: usize| (1 + (i - 1) * n_phi + j % n_phi) as u32;
    let mut triangles = Vec::with_capacity(2 * n_phi * (n_theta - 1));
    for j in 0..n_phi {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for i in 1..n_theta - 1 {
        for j in 0..n_phi {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    for j in 0..n_phi {
        triangles.push([south, ring(n_theta - 1, j + 1), ring(n_theta - 1, j)]);
    }
    Mesh::from_triangles(vertices, triangles)
}

/// Line (1-based) of the first `v` line whose position is not finite.
fn non_finite_vertex(text: &str) -> Option<u64> {
    text.lines().enumerate().find_map(|(n, line)| {
        let mut w = line.split_whitespace();
        if w.next() != Some("v") {
            return None;
        }
        let vals: Vec<f64> = w.take(4).map_while(|s| s.parse().ok()).collect();
        let bad = vals.iter().take(3).any(|x| !x.is_finite())
            || (vals.len() == 4 && vals[..3].iter().any(|x| !(x / vals[3]).is_finite()));
        bad.then_some(n as u64 + 1)
    })
}

/// The first face line of `text` with a reference out of range: its
/// `slot`-th index (0: vertex, 1: texture coordinate, 2: normal) beyond the
/// `key` lines (`v`, `vt`, `vn`) of the file (1-based, or negative from the
/// last read), with a message naming what it refers to (singular, plural).
fn bad_face_ref(
    text: &str,
    slot: usize,
    key: &str,
    (what, plural): (&str, &str),
) -> Option<(u64, String)> {
    let total = text
        .lines()
        .filter(|l| l.split_whitespace().next() == Some(key))
        .count() as i64;
    let mut seen = 0i64;
    for (n, line) in text.lines().enumerate() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some(k) if k == key => seen += 1,
            Some("f") => {
                for r in w {
                    let Ok(x) = r.split('/').nth(slot).unwrap_or("").parse::<i64>() else {
                        continue;
                    };
                    let bad = if x < 0 {
                        seen + x < 0
                    } else {
                        x == 0 || x > total
                    };
                    if bad {
                        return Some((
                            n as u64 + 1,
                            format!(
                                "face {what} index {x} out of range \
                                 ({total} {plural} in the file, {seen} before this line)"
                            ),
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// Whether `p` lies on triangle `[a, b, c]`: within `tol` \[m\] of its plane
/// and inside each of its edges widened by `tol` (never on a degenerate
/// triangle).
fn on_triangle(p: DVec3, [a, b, c]: &[DVec3; 3], tol: f64) -> bool {
    let n = (*b - *a).cross(*c - *a);
    let len = n.length();
    if len <= 0.0 || (p - *a).dot(n).abs() > tol * len {
        return false;
    }
    [(*a, *b), (*b, *c), (*c, *a)]
        .iter()
        .all(|&(u, v)| n.cross(v - u).dot(p - u) >= -tol * len * (v - u).length())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Philox4x32;
    use std::collections::HashMap;
    use std::f64::consts::PI;

    fn unit(rng: &mut Philox4x32) -> DVec3 {
        let z = 2.0 * rng.next_f64() - 1.0;
        let phi = 2.0 * PI * rng.next_f64();
        let s = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }

    fn in_box(rng: &mut Philox4x32, h: f64) -> DVec3 {
        DVec3::new(
            h * (2.0 * rng.next_f64() - 1.0),
            h * (2.0 * rng.next_f64() - 1.0),
            h * (2.0 * rng.next_f64() - 1.0),
        )
    }

    /// Nearest hit over all triangles, the same triangle test as the BVH.
    fn brute_first(
        m: &Mesh,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        skip: Option<u32>,
    ) -> Option<(f64, u32)> {
        let q = RayQuery::new(o, d);
        let mut best: Option<(f64, u32)> = None;
        for k in 0..m.triangle_count() as u32 {
            if Some(k) == skip {
                continue;
            }
            if let Some(t) = q.triangle(&m.corners(k))
                && t > t0
                && t < t1
                && best.is_none_or(|b| t < b.0)
            {
                best = Some((t, k));
            }
        }
        best
    }

    /// An arbitrary rotation (no axis-aligned coordinates survive it).
    fn rotation() -> DMat3 {
        DMat3::from_axis_angle(DVec3::new(0.3, -0.7, 0.5).normalize(), 0.917)
    }

    /// Unit icosphere: icosahedron subdivided `levels` times, shared vertices.
    fn icosphere(levels: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let g = (1.0 + 5f64.sqrt()) / 2.0;
        let mut v: Vec<DVec3> = [
            (-1.0, g, 0.0),
            (1.0, g, 0.0),
            (-1.0, -g, 0.0),
            (1.0, -g, 0.0),
            (0.0, -1.0, g),
            (0.0, 1.0, g),
            (0.0, -1.0, -g),
            (0.0, 1.0, -g),
            (g, 0.0, -1.0),
            (g, 0.0, 1.0),
            (-g, 0.0, -1.0),
            (-g, 0.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
        .collect();
        let mut f: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..levels {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
            let mut midpoint = |a: u32, b: u32, v: &mut Vec<DVec3>| {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    v.push((v[a as usize] + v[b as usize]).normalize());
                    v.len() as u32 - 1
                })
            };
            let mut g = Vec::with_capacity(4 * f.len());
            for &[a, b, c] in &f {
                let ab = midpoint(a, b, &mut v);
                let bc = midpoint(b, c, &mut v);
                let ca = midpoint(c, a, &mut v);
                g.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            f = g;
        }
        (v, f)
    }

    /// Cube [-1, 1]^3, two triangles per face, CCW outward.
    fn cube() -> Mesh {
        let v = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                )
            })
            .collect();
        let quads = [
            [0, 2, 3, 1], // z = -1
            [4, 5, 7, 6], // z = +1
            [0, 1, 5, 4], // y = -1
            [2, 6, 7, 3], // y = +1
            [0, 4, 6, 2], // x = -1
            [1, 3, 7, 5], // x = +1
        ];
        let t = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        Mesh::from_triangles(v, t).unwrap()
    }

    fn bumpy(theta: f64, phi: f64) -> f64 {
        1.0 + 0.25 * (3.0 * phi).cos() * theta.sin().powi(2) + 0.1 * (5.0 * theta).cos()
    }

    /// Edges (vertex pairs) of a mesh, each once.
    fn edges(m: &Mesh) -> Vec<(u32, u32)> {
        let mut e: Vec<(u32, u32)> = m
            .triangles()
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        e.sort_unstable();
        e.dedup();
        e
    }

    fn check_against_brute_force(m: &Mesh, rays: usize, spread: f64, seed: u64) {
        let mut rng = Philox4x32::new(seed, 0);
        let (lo, hi) = m.bounds();
        let c = 0.5 * (lo + hi);
        let h = spread * 0.5 * (hi - lo).max_element();
        let mut hits = 0;
        for i in 0..rays {
            let o = c + in_box(&mut rng, h);
            let d = unit(&mut rng);
            let t0 = match i % 3 {
                0 => 0.0,
                1 => 1e-9 * h,
                _ => h * rng.next_f64(),
            };
            let t1 = if i % 4 == 0 {
                f64::INFINITY
            } else {
                t0 + 3.0 * h * rng.next_f64()
            };
            let skip = (i % 5 == 0).then(|| (rng.next_u32() as usize % m.triangle_count()) as u32);
            let brute = brute_first(m, o, d, t0, t1, skip);
            let bvh = m.first_hit(o, d, t0, t1, skip, None);
            assert_eq!(brute.map(|b| b.0), bvh.map(|b| b.0), "ray {i}: o {o} d {d}");
            if let (Some(b), Some(h)) = (brute, bvh) {
                // Equal distances from two triangles happen only at shared edges.
                if b.1 != h.2 {
                    assert_eq!(b.0, h.0);
                }
                assert!((h.1 - m.normal(h.2)).length() < 1e-15);
                hits += 1;
            }
            assert_eq!(m.occluded(o, d, t0, t1, skip), brute.is_some(), "ray {i}");
        }
        assert!(
            hits > rays / 10 && hits < rays,
            "{hits} hits of {rays}: a weak test"
        );
    }

    #[test]
    fn bvh_matches_brute_force_on_triangle_soup() {
        let mut rng = Philox4x32::new(1, 0);
        let mut v = Vec::new();
        let mut t = Vec::new();
        for k in 0..3000u32 {
            let c = in_box(&mut rng, 1.0);
            // Mostly small triangles, some long slivers.
            let s = if k % 10 == 0 { 0.8 } else { 0.05 };
            for _ in 0..3 {
                v.push(c + s * in_box(&mut rng, 1.0));
            }
            t.push([3 * k, 3 * k + 1, 3 * k + 2]);
        }
        let m = Mesh::from_triangles(v, t).unwrap();
        assert_eq!(m.triangle_count(), 3000);
        check_against_brute_force(&m, 4000, 1.5, 2);
    }

    #[test]
    fn bvh_matches_brute_force_on_closed_meshes() {
        let (v, f) = icosphere(3);
        let ico = Mesh::from_triangles(v, f).unwrap().transformed(
            DVec3::new(0.31, -2.7, 1.1),
            rotation(),
            1.7,
        );
        assert_eq!(ico.triangle_count(), 1280);
        check_against_brute_force(&ico, 3000, 1.6, 3);
        let blob = star_blob(30, 50, bumpy).unwrap();
        check_against_brute_force(&blob, 3000, 1.6, 4);
    }

    #[test]
    fn degenerate_and_coincident_triangles_build() {
        // 2000 triangles through one centre (no binned split exists).
        let mut rng = Philox4x32::new(5, 0);
        let mut v = Vec::new();
        let mut t = Vec::new();
        for k in 0..2000u32 {
            let a = unit(&mut rng);
            let b = unit(&mut rng);
            v.extend([a, b, -a - b]);
            t.push([3 * k, 3 * k + 1, 3 * k + 2]);
        }
        t.push([0, 0, 1]); // repeated vertex: dropped
        v.extend([DVec3::ZERO, DVec3::X, 2.0 * DVec3::X]);
        t.push([6000, 6001, 6002]); // collinear: dropped
        let m = Mesh::from_triangles(v, t).unwrap();
        assert_eq!(m.triangle_count(), 2000);
        assert_eq!(m.dropped_triangles(), 2);
        check_against_brute_force(&m, 1000, 0.5, 6);
    }

    #[test]
    fn ends_skip_the_triangles_through_an_end_only() {
        // A 2 x 2 square as two triangles at z = 0, a third coincident with
        // the first (a rug on the floor), and a wall at x = 1.
        let v = vec![
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
            DVec3::new(1.0, -1.0, 1.0),
            DVec3::new(1.0, 1.0, 1.0),
        ];
        let t = vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [1, 2, 5], [1, 5, 4]];
        let m = Mesh::from_triangles(v, t).unwrap();
        let near = 1e-9;
        let ends = |skip, p: DVec3| Ends {
            skip,
            near,
            tol: m.on_tolerance(p),
        };
        // From a point on the floor (triangle 0, and the rug 2 through it)
        // 1e-10 m from the wall, towards the wall: the wall, at 1.4e-10.
        let o = DVec3::new(1.0 - 1e-10, 0.2, 0.0);
        let d = DVec3::new(1.0, 0.0, 1.0).normalize();
        let (t, _, tri) = m
            .first_hit_leaving(o, d, 0.0, f64::INFINITY, ends(Some(0), o), None)
            .unwrap();
        assert!(
            tri >= 3 && (t / (1e-10 * 2f64.sqrt()) - 1.0).abs() < 1e-5,
            "{tri} at {t}"
        );
        // Skipping every triangle within `near` (the rule before) passes
        // through the wall.
        assert!(
            m.first_hit(o, d, near, f64::INFINITY, Some(0), None)
                .is_none()
        );
        // Along the floor, away from the wall: neither the floor nor the
        // rug it lies on.
        let away = DVec3::new(-1.0, 0.0, 0.1).normalize();
        assert!(
            m.first_hit_leaving(o, away, 0.0, f64::INFINITY, ends(Some(0), o), None)
                .is_none()
        );
        // A segment from above to that point is not blocked by the floor it
        // ends on; to a point 1e-10 m below the floor, it is; to a point
        // 1e-10 m beyond the wall, the wall blocks it (the rule before let
        // both through), not to one 1e-10 m before it.
        let above = DVec3::new(0.5, 0.2, 0.7);
        let blocked = |a: DVec3, b: DVec3| {
            let (d, len) = ((b - a).normalize(), (b - a).length());
            let e = Ends {
                skip: None,
                near: near * len,
                tol: m.on_tolerance(a).max(m.on_tolerance(b)),
            };
            m.segment_blocked(a, d, 0.0, len, e)
        };
        assert!(!blocked(above, o));
        assert!(blocked(above, o - 1e-10 * DVec3::Z));
        assert!(blocked(above, DVec3::new(1.0 + 1e-10, 0.2, 0.5)));
        assert!(!blocked(above, DVec3::new(1.0 - 1e-10, 0.2, 0.5)));
    }

    #[test]
    fn skip_and_ray_interval() {
        let m = star_blob(20, 40, bumpy).unwrap();
        let mut rng = Philox4x32::new(7, 0);
        for _ in 0..500 {
            let k = (rng.next_u32() as usize % m.triangle_count()) as u32;
            let p = m.corners(k);
            let (a, b) = (rng.next_f64(), rng.next_f64());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let x = p[0] + a * (p[1] - p[0]) + b * (p[2] - p[0]);
            let n = m.normal(k);
            // Leaving inward from a point on triangle k: the next hit is
            // elsewhere, never k itself.
            let (t, nn, j) = m
                .first_hit(x, -n, 0.0, f64::INFINITY, Some(k), None)
                .unwrap();
            assert_ne!(j, k);
            assert!(t > 1e-3, "t = {t}");
            assert_eq!(nn, m.normal(j));
            // Leaving outward from a star-shaped closed surface: nothing.
            assert!(
                m.first_hit(x, n, 0.0, f64::INFINITY, Some(k), None)
                    .is_none()
            );
            assert!(!m.occluded(x, n, 0.0, f64::INFINITY, Some(k)));
            // t_max just before / after the hit.
            assert!(m.first_hit(x, -n, 0.0, t * 0.999, Some(k), None).is_none());
            assert!(!m.occluded(x, -n, 0.0, t * 0.999, Some(k)));
            assert!(m.occluded(x, -n, 0.0, t * 1.001, Some(k)));
            assert_eq!(
                m.first_hit(x, -n, 0.0, t * 1.001, Some(k), None).unwrap().2,
                j
            );
            // t_min beyond the first hit: the next one (or none), never an earlier one.
            if let Some((t2, _, j2)) = m.first_hit(x, -n, t * 1.001, f64::INFINITY, Some(k), None) {
                assert!(t2 > t * 1.001 && j2 != j);
            }
            // From the far side, the hit on k is found unless skipped.
            let y = x - 0.5 * t * n;
            let (s, _, i) = m.first_hit(y, n, 0.0, f64::INFINITY, None, None).unwrap();
            if i == k {
                assert!((s - 0.5 * t).abs() < 1e-9);
                assert!(
                    m.first_hit(y, n, 0.0, f64::INFINITY, Some(k), None)
                        .is_none_or(|h| h.2 != k)
                );
            }
        }
    }

    /// Whether `q` is strictly inside a convex closed mesh, by `eps` \[m\].
    fn inside_convex(m: &Mesh, q: DVec3, eps: f64) -> bool {
        (0..m.triangle_count() as u32).all(|k| m.normal(k).dot(q - m.corners(k)[0]) < -eps)
    }

    /// Rays from `origins` aimed exactly at every vertex and at points along
    /// every edge must all hit (BVH nearest, BVH any-hit and brute force).
    /// Origins outside the mesh need a convex mesh; targets a ray only
    /// grazes there (silhouette) or reaches after crossing it are left out.
    fn assert_watertight(m: &Mesh, origins: &[DVec3], fractions: &[f64]) -> usize {
        let v = m.vertices();
        let mut targets: Vec<DVec3> = v.to_vec();
        for (a, b) in edges(m) {
            let (a, b) = (v[a as usize], v[b as usize]);
            targets.extend(fractions.iter().map(|f| a + f * (b - a)));
        }
        let mut n = 0;
        for &o in origins {
            let outside = !inside_convex(m, o, 0.0);
            for &p in &targets {
                let d = (p - o).normalize();
                let eps = 1e-6 * (p - o).length();
                if outside && !inside_convex(m, p + 1e3 * eps * d, eps) {
                    continue; // grazing the silhouette or reaching the far side
                }
                let dist = (p - o).length();
                let hit = m.first_hit(o, d, 0.0, f64::INFINITY, None, None);
                assert!(hit.is_some(), "leak: o {o} towards {p}");
                let (t, _, _) = hit.unwrap();
                assert!(
                    t <= dist * (1.0 + 1e-9),
                    "o {o} towards {p}: t {t} beyond {dist}"
                );
                assert!(
                    m.occluded(o, d, 0.0, f64::INFINITY, None),
                    "leak (any-hit): o {o} towards {p}"
                );
                if n % 4 == 0 {
                    assert_eq!(
                        brute_first(m, o, d, 0.0, f64::INFINITY, None).map(|b| b.0),
                        Some(t)
                    );
                }
                n += 1;
            }
        }
        n
    }

    #[test]
    fn watertight_at_shared_edges_and_vertices() {
        let fractions = [0.5, 1.0 / 3.0, 0.1, 0.9, 0.7123];
        // Cube: exact ties (rays along diagonals, axes, through face diagonals).
        let c = cube();
        let mut n = assert_watertight(
            &c,
            &[
                DVec3::ZERO,
                DVec3::new(0.25, -0.5, 0.125),
                DVec3::new(0.0, 0.0, 5.0),
                DVec3::new(3.1, -2.3, 4.7),
            ],
            &fractions,
        );
        for d in [
            DVec3::X,
            -DVec3::Y,
            DVec3::Z,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 0.0, 1.0),
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(0.0, 1.0, -0.5),
        ] {
            let (t, _, _) = c
                .first_hit(DVec3::ZERO, d.normalize(), 0.0, f64::INFINITY, None, None)
                .unwrap();
            assert!((t - d.length() / d.abs().max_element()).abs() < 1e-15);
            n += 1;
        }
        // Icosphere, moved off the axes, from inside and from outside.
        let (v, f) = icosphere(3);
        let ico = Mesh::from_triangles(v, f).unwrap().transformed(
            DVec3::new(0.31, -2.7, 1.1),
            rotation(),
            1.7,
        );
        let ctr = DVec3::new(0.31, -2.7, 1.1);
        n += assert_watertight(
            &ico,
            &[
                ctr,
                ctr + DVec3::new(0.4, 0.3, -0.2),
                ctr + DVec3::new(-5.0, 7.0, 3.0),
            ],
            &fractions,
        );
        // Star blob: high-valence poles, long thin triangles near them.
        let blob = star_blob(24, 48, bumpy).unwrap();
        n += assert_watertight(
            &blob,
            &[DVec3::ZERO, DVec3::new(0.1, -0.2, 0.3)],
            &fractions,
        );
        assert!(n > 60_000, "{n} rays");
    }

    #[test]
    fn same_hits_at_all_scales() {
        let base = star_blob(30, 60, bumpy).unwrap();
        let mut rng = Philox4x32::new(9, 0);
        let rays: Vec<(DVec3, DVec3)> = (0..3000)
            .map(|_| (in_box(&mut rng, 1.5), unit(&mut rng)))
            .collect();
        let reference: Vec<_> = rays
            .iter()
            .map(|&(o, d)| base.first_hit(o, d, 0.0, f64::INFINITY, None, None))
            .collect();
        let r = rotation();
        for scale in [1e-3, 1.0, 1e4] {
            // Placed away from the origin, as an object in a large scene would be.
            let shift = DVec3::new(3.0, -2.0, 0.5) * scale * 10.0;
            let m = base.clone().transformed(shift, r, scale);
            let (lo, hi) = m.bounds();
            assert!((hi - lo).max_element() < 3.0 * scale);
            for (i, (&(o, d), &want)) in rays.iter().zip(&reference).enumerate() {
                let (o2, d2) = (shift + scale * (r * o), r * d);
                let got = m.first_hit(o2, d2, 0.0, f64::INFINITY, None, None);
                match (want, got) {
                    (None, None) => {}
                    (Some((t, n, k)), Some((t2, n2, k2))) => {
                        assert_eq!(k, k2, "scale {scale} ray {i}");
                        assert!(
                            (t2 / scale - t).abs() <= 1e-9 * t.max(1.0),
                            "scale {scale} ray {i}: {t2} vs {t}"
                        );
                        assert!((n2 - r * n).length() < 1e-9);
                    }
                    _ => panic!("scale {scale} ray {i}: {want:?} vs {got:?}"),
                }
                assert_eq!(m.occluded(o2, d2, 0.0, f64::INFINITY, None), want.is_some());
            }
        }
    }

    #[test]
    fn star_blob_is_closed_and_outward() {
        let (nt, np) = (12, 20);
        let m = star_blob(nt, np, bumpy).unwrap();
        assert_eq!(m.triangle_count(), 2 * np * (nt - 1));
        assert_eq!(m.vertices().len(), 2 + (nt - 1) * np);
        // Every directed edge once, its reverse once: closed and consistently wound.
        let mut directed = HashMap::new();
        for t in m.triangles() {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *directed.entry((a, b)).or_insert(0) += 1;
            }
        }
        for (&(a, b), &c) in &directed {
            assert_eq!(c, 1);
            assert_eq!(directed.get(&(b, a)), Some(&1));
        }
        for k in 0..m.triangle_count() as u32 {
            let p = m.corners(k);
            assert!(
                m.normal(k).dot(p[0] + p[1] + p[2]) > 0.0,
                "triangle {k} faces inward"
            );
        }
        // Sphere: enclosed volume (divergence theorem) close to 4/3 pi r^3.
        let s = star_blob(64, 128, |_, _| 2.0).unwrap();
        let vol: f64 = (0..s.triangle_count() as u32)
            .map(|k| {
                let p = s.corners(k);
                p[0].dot(p[1].cross(p[2])) / 6.0
            })
            .sum();
        let exact = 4.0 / 3.0 * PI * 8.0;
        assert!((vol / exact - 1.0).abs() < 2e-3, "{vol} vs {exact}");
        assert!(star_blob(1, 10, bumpy).is_err());
        let e = star_blob(4, 8, |t, _| 1.0 - t).unwrap_err().to_string();
        assert!(e.contains("not positive"), "{e}");
    }

    /// A closed blob, the same with one triangle turned, and with one
    /// left out (open).
    #[test]
    fn uneven_winding_is_told_from_an_open_mesh() {
        let m = star_blob(6, 8, bumpy).unwrap();
        assert!(m.is_closed() && !m.is_closed_but_unevenly_wound());
        let mut t = m.triangles().to_vec();
        t[3] = [t[3][0], t[3][2], t[3][1]];
        let turned = Mesh::from_triangles(m.vertices().to_vec(), t.clone()).unwrap();
        assert!(!turned.is_closed() && turned.is_closed_but_unevenly_wound());
        t.remove(3);
        let open = Mesh::from_triangles(m.vertices().to_vec(), t).unwrap();
        assert!(!open.is_closed() && !open.is_closed_but_unevenly_wound());
    }

    #[test]
    fn from_triangles_checks() {
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let m = Mesh::from_triangles(v.clone(), vec![[0, 1, 2]]).unwrap();
        assert_eq!(m.normal(0), DVec3::Z);
        assert_eq!(m.bounds(), (DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0)));
        assert_eq!(m.area(0), 0.5);
        assert!(m.storage_bytes() > 3 * 24 + 12);
        let e = Mesh::from_triangles(v.clone(), vec![[0, 1, 3]])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "<triangles>: triangle 0: vertex index 3 out of range (3 vertices)"
        );
        let mut w = v.clone();
        w[1].y = f64::NAN;
        let e = Mesh::from_triangles(w, vec![[0, 1, 2]])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("<triangles>: vertex 1 = ") && e.ends_with("is not finite"),
            "{e}"
        );
        let e = Mesh::from_triangles(v.clone(), vec![[0, 1, 1]])
            .unwrap_err()
            .to_string();
        assert_eq!(e, "<triangles>: no triangles (1 of zero area dropped)");
        let e = Mesh::from_triangles(v.clone(), vec![])
            .unwrap_err()
            .to_string();
        assert_eq!(e, "<triangles>: no triangles");
        assert!(
            m.clone()
                .try_transformed(DVec3::ZERO, DMat3::IDENTITY, 0.0)
                .is_err()
        );
        assert!(
            m.clone()
                .try_transformed(
                    DVec3::ZERO,
                    DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0)),
                    1.0
                )
                .is_err()
        );
        let t = m.transformed(
            DVec3::new(0.0, 0.0, 5.0),
            DMat3::from_rotation_x(PI / 2.0),
            2.0,
        );
        assert!((t.normal(0) - -DVec3::Y).length() < 1e-15);
        assert!((t.bounds().1 - DVec3::new(2.0, 0.0, 7.0)).length() < 1e-15);
    }

    fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    /// A closed cube split into `g` groups and `o` objects, and one that
    /// repeats its vertices for every face, loads closed: tobj numbers each
    /// group's vertices apart, and without welding the seams left the mesh
    /// open (a point inside it was not flagged; a reviewer's case).
    #[test]
    fn groups_and_repeated_vertices_are_welded_closed() {
        let dir = tempfile::tempdir().unwrap();
        let v = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n";
        let faces = [
            "f 1 3 2", "f 2 3 4", "f 5 6 7", "f 6 8 7", "f 1 2 5", "f 2 6 5", "f 3 7 4", "f 4 7 8",
            "f 1 5 3", "f 3 5 7", "f 2 4 6", "f 4 8 6",
        ];
        let plain = format!("{v}{}\n", faces.join("\n"));
        let groups = format!(
            "{v}g top\n{}\ng rest\n{}\n",
            faces[..2].join("\n"),
            faces[2..].join("\n")
        );
        let objects = format!(
            "{v}o a\n{}\no b\n{}\n",
            faces[..5].join("\n"),
            faces[5..].join("\n")
        );
        // Every face with its own three vertices (and -0 for 0 in one).
        let corners: Vec<[f64; 3]> = v
            .lines()
            .map(|l| {
                let c: Vec<f64> = l[2..].split(' ').map(|x| x.parse().unwrap()).collect();
                [c[0], c[1], c[2]]
            })
            .collect();
        let mut unwelded = String::new();
        for (k, f) in faces.iter().enumerate() {
            for i in f[2..].split(' ') {
                let c = corners[i.parse::<usize>().unwrap() - 1];
                let x = if k == 0 && c[0] == 0.0 {
                    "-0".to_string()
                } else {
                    c[0].to_string()
                };
                unwelded.push_str(&format!("v {x} {} {}\n", c[1], c[2]));
            }
            unwelded.push_str(&format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3));
        }
        for (name, text) in [
            ("plain", plain),
            ("groups", groups),
            ("objects", objects),
            ("unwelded", unwelded),
        ] {
            let m = Mesh::load_obj(&write(&dir, &format!("{name}.obj"), &text)).unwrap();
            assert_eq!(m.vertices().len(), 8, "{name}");
            assert_eq!(m.triangle_count(), 12, "{name}");
            assert!(m.is_closed(), "{name} is not closed");
        }
    }

    /// A concave face (an L of area 3 at z = 1): ear clipping covers it
    /// exactly, facing +z; a fan from its first vertex would also cover
    /// (0.8, 1.2), outside the L (a reviewer's case: a point there read 0
    /// lx under a light above).
    #[test]
    fn a_concave_face_is_covered_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let text = "v 0 0 1\nv 2 0 1\nv 2 2 1\nv 1 2 1\nv 1 1 1\nv 0 1 1\nf 1 2 3 4 5 6\n";
        let m = Mesh::load_obj(&write(&dir, "l.obj", text)).unwrap();
        assert_eq!(m.triangle_count(), 4);
        let area: f64 = (0..4).map(|k| m.area(k)).sum();
        assert!((area - 3.0).abs() < 1e-12, "{area}");
        assert!((0..4).all(|k| m.normal(k) == DVec3::Z));
        let down = -DVec3::Z;
        for (x, y, hit) in [
            (0.8, 1.2, false),
            (1.9, 1.9, true),
            (0.5, 0.5, true),
            (0.5, 1.5, false),
        ] {
            let o = DVec3::new(x, y, 2.0);
            assert_eq!(m.occluded(o, down, 1e-9, 5.0, None), hit, "({x}, {y})");
        }
    }

    #[test]
    fn obj_loading_merges_objects_and_triangulates() {
        let dir = tempfile::tempdir().unwrap();
        let text = "\
# two objects: a unit cube of quads and a pentagon
mtllib missing.mtl
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vn 0 0 1
usemtl nothing
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 4 8 7 3
f 1 5 8 4
f 2//1 3//1 7//1 6//1
l 1 7
o pentagon
g part
v 3 0 0
v 4 0 0
v 4.5 1 0
v 3.5 2 0
v 2.5 1 0
f -5 -4 -3 -2 -1
f 9
";
        let p = write(&dir, "two.obj", text);
        let m = Mesh::load_obj(&p).unwrap();
        assert_eq!(m.triangle_count(), 12 + 3);
        assert_eq!(m.vertices().len(), 8 + 5);
        assert_eq!(m.dropped_triangles(), 0);
        assert_eq!(m.bounds(), (DVec3::ZERO, DVec3::new(4.5, 2.0, 1.0)));
        // Cube normals point out of the cube; the pentagon faces +z.
        for k in 0..12 {
            let p = m.corners(k);
            let c = (p[0] + p[1] + p[2]) / 3.0 - DVec3::splat(0.5);
            assert!(m.normal(k).dot(c) > 0.0, "cube triangle {k}");
        }
        for k in 12..15 {
            assert_eq!(m.normal(k), DVec3::Z);
        }
        let area: f64 = (0..15).map(|k| m.area(k)).sum();
        assert!((area - (6.0 + 2.5)).abs() < 1e-12, "{area}");
        // A ray into the cube from below hits the bottom face from outside.
        let (t, n, _) = m
            .first_hit(
                DVec3::new(0.3, 0.6, -1.0),
                DVec3::Z,
                0.0,
                f64::INFINITY,
                None,
                None,
            )
            .unwrap();
        assert_eq!((t, n), (1.0, -DVec3::Z));
    }

    #[test]
    fn obj_round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let m = star_blob(16, 24, bumpy).unwrap().transformed(
            DVec3::new(1e3 / 3.0, -0.1, 7e-5),
            rotation(),
            1e-3 * PI,
        );
        let p = dir.path().join("blob.obj");
        m.write_obj(&p).unwrap();
        let back = Mesh::load_obj(&p).unwrap();
        assert_eq!(back.triangle_count(), m.triangle_count());
        for k in 0..m.triangle_count() as u32 {
            assert_eq!(back.corners(k), m.corners(k));
        }
        let bad = dir.path().join("no/such/dir/x.obj");
        let e = m.write_obj(&bad).unwrap_err().to_string();
        assert!(e.contains("x.obj: cannot write"), "{e}");
    }

    /// A backslash ending a line continues it on the next (the OBJ rule; a
    /// reviewer's cube with one face split over two lines was refused).
    #[test]
    fn obj_continued_lines_are_joined() {
        let dir = tempfile::tempdir().unwrap();
        let verts = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
        let one = dir.path().join("one.obj");
        let split = dir.path().join("split.obj");
        std::fs::write(&one, format!("{verts}f 1 2 3 4\n")).unwrap();
        std::fs::write(
            &split,
            "v 0 0 \\\r\n0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 \\\n 3 4\n",
        )
        .unwrap();
        let (a, b) = (
            Mesh::load_obj(&one).unwrap(),
            Mesh::load_obj(&split).unwrap(),
        );
        assert_eq!(a.triangle_count(), 2);
        assert_eq!((a.vertices(), a.triangles()), (b.vertices(), b.triangles()));
        assert_eq!(join_continued_lines(b"a \\\nb\nc\\"), b"a  b\n\nc\\");
    }

    #[test]
    fn obj_errors_name_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("office_chair.obj");
        let e = Mesh::load_obj(&missing).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("{}: cannot read", missing.display())),
            "{e}"
        );
        let cases = [
            (
                "nan.obj",
                "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n",
                ":3: vertex coordinates are not finite",
            ),
            (
                "inf.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n",
                ":3: vertex coordinates are not finite",
            ),
            (
                "range.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\nf 1 2 9\n",
                ":6: face vertex index 9 out of range (3 vertices in the file, 3 before this line)",
            ),
            (
                "zero.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
                ":4: face vertex index 0 out of range",
            ),
            (
                "rel.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\nv 1 1 1\n",
                ":4: face vertex index -4 out of range (4 vertices in the file, 3 before this line)",
            ),
            (
                "parse.obj",
                "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n",
                ":2: position parse error",
            ),
            (
                "face.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
                ":4: face parse error",
            ),
            (
                "vt.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1/1 2/5 3/1\n",
                ":6: face texture coordinate index 5 out of range (1 texture coordinates in the file, 1 before this line)",
            ),
            (
                "vn.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//4\n",
                ":5: face normal index 4 out of range (1 normals in the file, 1 before this line)",
            ),
            (
                // Continued lines (a backslash ending a line) keep the
                // numbers of the lines after them.
                "continued.obj",
                "v 0 0 \\\n0\nv 1 0 0\nv 0 1 0\nf 1 \\\r\n2 3\nf 1 2 x\n",
                ":7: face parse error",
            ),
            (
                "short.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 9\n",
                ":5: face vertex index 9 out of range (3 vertices in the file, 3 before this line)",
            ),
            ("empty.obj", "# nothing\n", ": no triangles"),
            (
                "flat.obj",
                "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
                ": no triangles (1 of zero area dropped)",
            ),
        ];
        for (name, text, want) in cases {
            let p = write(&dir, name, text);
            let e = Mesh::load_obj(&p).expect_err(name).to_string();
            let file = p.display().to_string();
            assert!(e.starts_with(&file), "{name}: {e}");
            assert!(e[file.len()..].starts_with(want), "{name}: {e}");
        }
    }

    /// CPU time of the calling thread \[s\] (Linux; wall-clock time elsewhere),
    /// so that timings are not skewed by other processes sharing the cores.
    fn thread_cpu_seconds(wall: std::time::Instant) -> f64 {
        std::fs::read_to_string("/proc/thread-self/schedstat")
            .ok()
            .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
            .map_or_else(|| wall.elapsed().as_secs_f64(), |ns| ns * 1e-9)
    }

    /// Timing on a ~100k-triangle closed blob: build time, rays per second of
    /// CPU time on one thread, and wall-clock rays/s on all rayon threads. Run
    /// with `cargo test --release --lib geometry::mesh::tests::bench -- --ignored --nocapture`
    /// (`LUMEST_BENCH_RAYS` sets the number of rays, default 1e6).
    #[test]
    #[ignore]
    fn bench_100k_triangles() {
        use rayon::prelude::*;
        let base = star_blob(224, 224, bumpy).unwrap();
        let (v, f) = (base.vertices().to_vec(), base.triangles().to_vec());
        let w = std::time::Instant::now();
        let c0 = thread_cpu_seconds(w);
        let m = Mesh::from_triangles(v, f).unwrap();
        let build = thread_cpu_seconds(w) - c0;
        println!(
            "{} triangles: built in {build:.3} s CPU, {:.1} MB ({} B/triangle), {} BVH nodes",
            m.triangle_count(),
            m.storage_bytes() as f64 / 1e6,
            m.storage_bytes() / m.triangle_count(),
            m.bvh.node_count()
        );
        let n: usize = std::env::var("LUMEST_BENCH_RAYS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1_000_000);
        let mut rng = Philox4x32::new(11, 0);
        // Rays from inside (every ray hits) and from a shell outside aimed
        // roughly at the blob (about 60 % hit).
        let inside: Vec<(DVec3, DVec3)> = (0..n)
            .map(|_| (0.6 * in_box(&mut rng, 0.5), unit(&mut rng)))
            .collect();
        let outside: Vec<(DVec3, DVec3)> = (0..n)
            .map(|_| {
                let o = 3.0 * unit(&mut rng);
                (o, (-o.normalize() + 0.4 * unit(&mut rng)).normalize())
            })
            .collect();
        let first =
            |&(o, d): &(DVec3, DVec3)| m.first_hit(o, d, 0.0, f64::INFINITY, None, None).is_some();
        let any = |&(o, d): &(DVec3, DVec3)| m.occluded(o, d, 0.0, f64::INFINITY, None);
        for (name, rays) in [("inside", &inside), ("outside", &outside)] {
            let w = std::time::Instant::now();
            let c0 = thread_cpu_seconds(w);
            let hits = rays.iter().filter(|r| first(r)).count();
            let c1 = thread_cpu_seconds(w);
            let occ = rays.iter().filter(|r| any(r)).count();
            let c2 = thread_cpu_seconds(w);
            let w = std::time::Instant::now();
            let par = rays.par_iter().filter(|r| first(r)).count();
            let wall = w.elapsed().as_secs_f64();
            assert_eq!((hits, occ), (par, par));
            println!(
                "{name}: {hits} of {n} hit; 1 thread: first_hit {:.2} M rays/s, occluded {:.2} M rays/s (per CPU second); \
                 {} threads: first_hit {:.2} M rays/s (wall clock)",
                n as f64 / (c1 - c0) / 1e6,
                n as f64 / (c2 - c1) / 1e6,
                rayon::current_num_threads(),
                n as f64 / wall / 1e6,
            );
        }
    }
}
