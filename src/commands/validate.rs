//! `lumest validate`: the validation cases of [`crate::cases`], by name.

use crate::cases::box_room::{BoxArgs, validate_box};
use crate::cases::daylight::{DaylightArgs, validate_daylight};
use crate::cases::integrating_sphere::{SphereArgs, validate_sphere};
use crate::cases::luminaires::{LuminairesArgs, validate_luminaires};
use crate::cases::plate::{PlateArgs, validate_plate};
use crate::cases::sobolev::{ValidateSobolevArgs, validate_sobolev};
use crate::cases::stress::{StressArgs, validate_stress};
use clap::Subcommand;

/// Validation cases.
#[derive(Subcommand, Clone, Debug)]
pub enum ValidateCase {
    /// Two infinite Lambertian planes and a point source, against the exact solution.
    Sobolev(ValidateSobolevArgs),
    /// Integrating sphere with an off-centre point source: uniform indirect illuminance.
    #[command(name = "integrating-sphere")]
    IntegratingSphere(SphereArgs),
    /// Point source above a square Lambertian plate, against 2-D quadrature
    /// (checked itself against the closed-form corner form factor).
    Plate(PlateArgs),
    /// Flux balance in a closed box room: absorbed flux equals emitted flux, no leaks.
    #[command(name = "box")]
    BoxFlux(BoxArgs),
    /// Stress matrix: extreme reflectances, distances, scales; points touching walls and sources.
    Stress(StressArgs),
    /// Every light kind against references: closed forms, sampled direct light (error against
    /// time), flux balance in a black box, and the variance of the direct-light strategies.
    Luminaires(LuminairesArgs),
    /// Daylight against references (issue 13): a uniform environment, the CIE overcast sky,
    /// a distant light, a window of a black room with and without a portal, and the probe
    /// `sky_sun.hdr` by importance sampling against median cut (error against time, z test).
    Daylight(DaylightArgs),
}

/// Run a validation case.
pub fn validate(case: &ValidateCase) -> anyhow::Result<()> {
    let report = match case {
        ValidateCase::Sobolev(a) => &a.case.report,
        ValidateCase::IntegratingSphere(a) => &a.case.report,
        ValidateCase::Plate(a) => &a.case.report,
        ValidateCase::BoxFlux(a) => &a.report,
        ValidateCase::Stress(a) => &a.report,
        ValidateCase::Luminaires(a) => &a.case.report,
        ValidateCase::Daylight(a) => &a.case.report,
    };
    // Before the run: a report "folder" that is a file was found only when
    // the tables were written, after the whole run.
    anyhow::ensure!(
        !report.exists() || report.is_dir(),
        "--report {}: is a file, not a folder; give a folder (it is created if missing)",
        report.display()
    );
    match case {
        ValidateCase::Sobolev(a) => validate_sobolev(a),
        ValidateCase::IntegratingSphere(a) => validate_sphere(a),
        ValidateCase::Plate(a) => validate_plate(a),
        ValidateCase::BoxFlux(a) => validate_box(a),
        ValidateCase::Stress(a) => validate_stress(a),
        ValidateCase::Luminaires(a) => validate_luminaires(a),
        ValidateCase::Daylight(a) => validate_daylight(a),
    }
}
