//! # lumest: illumination by local estimation
//!
//! Conventions (units & frames) are documented here once; every public
//! physical quantity names its unit in its doc comment.
#![forbid(unsafe_code)]

pub mod reference;
pub mod sampling;
