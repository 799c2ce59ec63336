//! # lumest: illumination by local estimation
//!
//! Markov chains of rays are traced from the light sources; at every surface
//! collision the chain scores analytically into every requested point (the
//! local estimate of Marchuk and Mikhailov). Exact references (the Sobolev
//! problem) check the answers.
//!
//! ## Units and conventions
//!
//! - Lengths in metres \[m\]; luminous intensity in candela \[cd\]; flux in lumen
//!   \[lm\]; illuminance in lux [lx = lm/m^2]; luminance in [cd/m^2]. The scene
//!   file uses the same units; a light given by `flux` is converted to
//!   intensity once, when the scene is compiled.
//! - A surface's front side is the side its normal faces. Light arriving on
//!   the front side is reflected by the material; the back side absorbs.
//!   Every surface is opaque.
//! - A calculation point has a unit normal `n`; its illuminance is the flux
//!   per area arriving from the half-space `n` faces.
//! - Directions `wi`, `wo` are unit vectors pointing away from the surface.
//!   Pdfs state their measure: per solid angle [1/sr] or per area [1/m^2].
//! - `f64` throughout.
//!
//! ## Statistics
//!
//! Every estimate is a mean over independent batches of chains and carries its
//! standard error; see [`tally`] for the formulas (mean, standard error,
//! Student-t interval, relative error `R`, figure of merit `1/(R^2 T)`).
//!
//! ## Glossary
//!
//! `p` point, `n` normal, `u` uniforms, `pdf` density, `q` chain weight \[lm\],
//! `phi` flux \[lm\], `i` intensity \[cd\], `e` illuminance \[lx\], `l` luminance.
// No unsafe code, except the two calls that install the signal handler
// (`io::interrupt`, which allows it for itself): no signal crate is vendored;
// and the call of the AVX2 scoring kernel after the CPU check
// (`estimator/open_kernel.rs`).
#![deny(unsafe_code)]
// The docs are written for the crate's developers as much as its users: some
// public items point to the private code that does their work (build with
// `cargo doc --document-private-items` to follow them). Units in doc text
// are written `\[m\]`, escaped, so that rustdoc does not read them as links.
#![allow(rustdoc::private_intra_doc_links)]

pub mod cases;
pub mod chain;
pub mod commands;
pub mod estimator;
pub mod geometry;
pub mod glare;
pub mod grid;
pub mod io;
pub mod light;
pub mod material;
pub mod math;
pub mod reference;
pub mod report;
pub mod run;
pub mod sampling;
pub mod scene;
pub mod tally;

/// The backward estimator, at its historical path.
pub use estimator::backward;
