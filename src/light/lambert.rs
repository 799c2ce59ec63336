//! TEMPORARY placeholder until the contour branch is merged.
use glam::DVec3;
/// Placeholder.
pub fn rect_irradiance(_c: DVec3, _e1: DVec3, _e2: DVec3, _x: DVec3, _n: DVec3, _two: bool) -> f64 {
    unimplemented!("lambert contour pending merge")
}
/// Placeholder.
pub fn disc_irradiance(_c: DVec3, _m: DVec3, _r: f64, _x: DVec3, _n: DVec3, _two: bool) -> f64 {
    unimplemented!("lambert contour pending merge")
}
