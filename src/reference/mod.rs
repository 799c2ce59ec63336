//! Analytic solutions used as ground truth.
//!
//! This module never calls the chain or the estimators, so a check against it
//! stays independent of the Monte Carlo code.

pub mod area_source;
pub mod closed_form;
pub mod disc_profile;
pub mod envmap;
pub mod quadrature;
pub mod sobolev;

pub use quadrature::QuadOptions;
pub use sobolev::{Path, Settings, Sobolev, SobolevError, SobolevValue};
