//! Formats only: CSV point lists in, CSV results out, plots. No physics.

pub mod csvio;
pub mod envmap;
pub mod image;
pub mod interrupt;
pub mod isolux;
pub mod photometry;
pub mod plot;
pub mod sh_coeffs;
pub(crate) mod text;

pub use csvio::{
    InputError, PointTable, ViewTable, format_fixed, format_number, read_points, read_views,
    write_atomic,
};
