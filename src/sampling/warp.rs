//! Warps from the unit square to directions, each with pdf and inverse.
use glam::DVec3;

/// A sampled direction with its pdf [1/sr] (solid-angle measure).
#[derive(Clone, Copy, Debug)]
pub struct DirectionSample {
    /// Unit direction.
    pub w: DVec3,
    /// Density with respect to solid angle [1/sr].
    pub pdf: f64,
}

/// Orthonormal frame around a unit normal `n` (Duff et al. 2017).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub s: DVec3,
    pub t: DVec3,
    pub n: DVec3,
}

impl Frame {
    pub fn from_normal(n: DVec3) -> Self {
        let _ = n;
        todo!()
    }
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

/// Uniform direction on the unit sphere; pdf 1/(4 pi).
pub fn sample_uniform_sphere(u: [f64; 2]) -> DirectionSample {
    let _ = u;
    todo!()
}

/// Cosine-weighted direction on the hemisphere z > 0 (local frame); pdf cos/pi.
pub fn sample_cosine_hemisphere(u: [f64; 2]) -> DirectionSample {
    let _ = u;
    todo!()
}
