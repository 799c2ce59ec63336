//! Random streams and warps from uniforms `u in [0,1)^k` to directions.
//!
//! Nothing here mentions lights or scenes: a warp takes explicit uniforms
//! (so tests can drive it) and returns a named record with its pdf.

pub mod alias;
pub mod cone;
pub mod grazing;
pub mod owen;
pub mod qmc;
pub mod rng;
pub mod sphere_table;
pub mod warp;

pub use rng::Philox4x32;
pub use warp::{DirectionSample, Frame};
