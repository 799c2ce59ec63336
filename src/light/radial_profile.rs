//! TEMPORARY (lead's placeholder until the profiles branch is merged): the uniform profile only.

/// Radial luminance profile of a disc.
#[derive(Clone, Debug, PartialEq)]
pub struct RadialProfile {
    radius: f64,
}

impl RadialProfile {
    /// The uniform profile on a disc of `radius`.
    pub fn uniform(radius: f64) -> Self {
        Self { radius }
    }
    /// Whether the profile is uniform.
    pub fn is_uniform(&self) -> bool {
        true
    }
    /// Relative luminance at `s`.
    pub fn shape(&self, _s: f64) -> f64 {
        1.0
    }
    /// `int_0^R shape 2 pi s ds`.
    pub fn flux_integral(&self) -> f64 {
        std::f64::consts::PI * self.radius * self.radius
    }
    /// Radius with density `shape 2 pi s / flux_integral`.
    pub fn sample_radius(&self, u: f64) -> f64 {
        self.radius * u.sqrt()
    }
}
impl RadialProfile {
    /// Placeholder parse: uniform only.
    pub fn parse(v: &toml::Value, radius: f64) -> Result<Self, String> {
        match v.as_str() {
            Some("uniform") => Ok(Self::uniform(radius)),
            _ => Err("only `uniform` until the profiles branch lands".into()),
        }
    }
}
