//! The validation cases: each case is one file with one scene builder and
//! its reference (exact values, or data under `validation/cases/<name>/`);
//! [`report`] writes the convergence tables and plots that they share, and
//! [`stress`] is the matrix of hard cases built from them. The command
//! `lumest validate <case>` ([`crate::commands::validate`]) only dispatches here.

pub mod box_room;
pub mod case;
pub mod daylight;
pub mod flux_balance;
pub mod integrating_sphere;
pub mod luminaires;
pub mod plate;
pub mod report;
pub mod sobolev;
pub mod stress;
pub mod tiled_room;
