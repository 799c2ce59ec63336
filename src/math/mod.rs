//! Numerical building blocks that know nothing of scenes or light.

pub mod quadrature;
pub mod roots;
pub mod sph_harm;
